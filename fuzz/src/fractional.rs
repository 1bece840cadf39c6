//! The fractional cell: `FractionalSpec` (`new`, `hz`, `validate`, its
//! modulus) and `Grunwald` with 0 (refused), 1, 4, 16 or 64 taps.

use arbitrary::{Result, Unstructured};
use bushing::{FractionalSpec, Grunwald};

use crate::contract::{built, drive};
use crate::draw::{backbone, decades, param, time_step};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    match u.int_in_range(0u8..=4)? {
        0 => taps::<T, 0>(u),
        1 => taps::<T, 1>(u),
        2 => taps::<T, 4>(u),
        3 => taps::<T, 16>(u),
        _ => taps::<T, 64>(u),
    }
}

fn taps<T: Num, const N: usize>(u: &mut Unstructured<'_>) -> Result<()> {
    let (alpha, g) = (param(u, 0.0, 1.0)?, param(u, 0.0, 1.0)?);
    let spec = if u.arbitrary()? {
        FractionalSpec::hz(decades(u, 1e-2, 1e2)?, alpha, g)
    } else {
        FractionalSpec::new(decades(u, 1e-1, 1e3)?, alpha, g)
    };
    if built(spec.validate()).is_some() {
        let _ = spec.branch_modulus(decades(u, 1e-2, 1e4)?);
    }
    let Some(cell) = built(Grunwald::<T, N>::new(spec, time_step(u)?)) else {
        return Ok(());
    };
    let _ = (cell.dc_leak(), cell.branch_response(decades(u, 1e-2, 1e4)?));
    let backbone = backbone(u)?;
    drive(u, backbone, (cell,))
}
