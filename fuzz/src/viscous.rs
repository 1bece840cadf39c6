//! The dashpot, alone, beside a Maxwell bank (built for the same time step
//! or another: `TimeStepMismatch`) and, present or not, beside an Iwan
//! bank.

use arbitrary::{Result, Unstructured};
use bushing::{Dashpot, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm};

use crate::contract::{built, drive};
use crate::draw::{backbone, decades, fraction, time_step};
use crate::maxwell::specs;
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let dt = time_step(u)?;
    let Some(dashpot) = built(Dashpot::<T>::new(decades(u, 1e-6, 1e3)?, dt)) else {
        return Ok(());
    };
    let _ = dashpot.c();
    let backbone = backbone::<T>(u)?;
    match u.int_in_range(0u8..=2)? {
        0 => drive(u, backbone, (dashpot,)),
        1 => {
            let bank_dt = if u.ratio(1u8, 4)? { time_step(u)? } else { dt };
            let form = *u.choose(&MaxwellForm::ALL)?;
            match built(MaxwellBank::<T, 2>::new(form, &specs::<2>(u)?, bank_dt)) {
                Some(bank) => drive(u, backbone, (dashpot, bank)),
                None => Ok(()),
            }
        }
        _ => {
            let cells = [
                IwanCellSpec::new(fraction(u, 2)?, decades(u, 1e-2, 1e2)?),
                IwanCellSpec::new(fraction(u, 2)?, decades(u, 1e-2, 1e2)?),
            ];
            let dashpot = u.arbitrary::<bool>()?.then_some(dashpot);
            match built(IwanBank::<T, 2>::new(&cells)) {
                Some(bank) => drive(u, backbone, (dashpot, bank)),
                None => Ok(()),
            }
        }
    }
}
