//! Friction cells: `Dahl`, `BoucWen` and `Berg`.

use arbitrary::{Result, Unstructured};
use bushing::{Berg, BoucWen, Dahl};

use crate::contract::{built, drive};
use crate::draw::{backbone, decades, param};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let backbone = backbone::<T>(u)?;
    match u.int_in_range(0u8..=2)? {
        0 => {
            let alpha = if u.arbitrary()? {
                1.0
            } else {
                param(u, 0.0, 5.0)?
            };
            if let Some(d) = built(Dahl::<T>::new(
                decades(u, 1.0, 1e4)?,
                decades(u, 1e-2, 50.0)?,
                alpha,
            )) {
                drive(u, backbone, (d,))?;
            }
        }
        1 => {
            let beta = param(u, 0.0, 50.0)?;
            if let Some(bw) = built(BoucWen::<T>::new(
                decades(u, 1.0, 1e3)?,
                param(u, 0.0, 2.0)?,
                beta,
                param(u, -beta, beta)?,
                param(u, 0.0, 60.0)?,
            )) {
                let _ = bw.ultimate_force();
                drive(u, backbone, (bw,))?;
            }
        }
        _ => {
            if let Some(b) = built(Berg::<T>::new(param(u, 0.0, 50.0)?, param(u, 0.0, 1.0)?)) {
                drive(u, backbone, (b,))?;
            }
        }
    }
    Ok(())
}
