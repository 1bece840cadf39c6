//! x_f cells: `XfSpec` (literal and `hz`), each `XfCell`, and `XfBank` of
//! one or three cells in both forms.

use arbitrary::{Result, Unstructured};
use bushing::xf::XfCell;
use bushing::{XfBank, XfForm, XfSpec};

use crate::contract::{built, drive};
use crate::draw::{backbone, decades, fraction, param, time_step};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    if u.arbitrary()? {
        cells::<T, 1>(u)
    } else {
        cells::<T, 3>(u)
    }
}

fn cells<T: Num, const N: usize>(u: &mut Unstructured<'_>) -> Result<()> {
    let dt = time_step(u)?;
    let form = *u.choose(&XfForm::ALL)?;
    let mut specs = [XfSpec::hz(0.0, 0.0, 0.0); N];
    for (i, s) in specs.iter_mut().enumerate() {
        let (g, x_f) = (fraction(u, N)?, decades(u, 1e-4, 1.0)?);
        *s = if u.arbitrary()? {
            XfSpec::hz(param(u, 0.0, 200.0)?, g, x_f)
        } else {
            XfSpec {
                omega: param(u, 0.0, 1e3)?,
                g,
                x_f,
            }
        };
        let _ = built(XfCell::<T>::new(*s, dt, i));
    }
    if let Some(bank) = built(XfBank::<T, N>::new(form, &specs, dt)) {
        let backbone = backbone(u)?;
        drive(u, backbone, (bank,))?;
    }
    Ok(())
}
