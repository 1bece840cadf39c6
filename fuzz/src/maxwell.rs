//! Maxwell banks: every form, each state storage, one to eight cells;
//! each cell's own constructor; the bank re-tuned while it runs, exactly
//! (`shifted`, f64) or on line (`retune`, libm or micromath), to a shift
//! factor given or taken from a WLF or Arrhenius law at a temperature
//! (`ShiftFactor::at` in f64, `at_in` in the working type).

use arbitrary::{Result, Unstructured};
use bushing::{
    Accumulator, Bushing, Compensated, MaxwellBank, MaxwellCell, MaxwellForm, MaxwellSpec,
    Multiplied, Plain, ShiftFactor,
};

use crate::contract::{built, steps};
use crate::draw::{Path, backbone, decades, fraction, param, time_step};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    match u.int_in_range(0u8..=2)? {
        0 => storage::<T, Plain<T>>(u),
        1 => storage::<T, Compensated<T>>(u),
        _ => storage::<T, Multiplied<T>>(u),
    }
}

fn storage<T: Num, A: Accumulator<T>>(u: &mut Unstructured<'_>) -> Result<()> {
    match u.int_in_range(0u8..=2)? {
        0 => cells::<T, A, 1>(u),
        1 => cells::<T, A, 3>(u),
        _ => cells::<T, A, 8>(u),
    }
}

/// `N` cells of the same form.
pub fn specs<const N: usize>(u: &mut Unstructured<'_>) -> Result<[MaxwellSpec; N]> {
    let mut specs = [MaxwellSpec::new(0.0, 0.0); N];
    for s in &mut specs {
        *s = if u.arbitrary()? {
            MaxwellSpec::hz(decades(u, 1e-3, 1e3)?, fraction(u, N)?)
        } else {
            MaxwellSpec::new(decades(u, 1e-3, 1e4)?, fraction(u, N)?)
        };
    }
    Ok(specs)
}

fn cells<T: Num, A: Accumulator<T>, const N: usize>(u: &mut Unstructured<'_>) -> Result<()> {
    let dt = time_step(u)?;
    let form = *u.choose(&MaxwellForm::ALL)?;
    let specs = specs::<N>(u)?;
    for (i, spec) in specs.iter().enumerate() {
        let _ = built(MaxwellCell::<T>::new(form, *spec, dt, i));
    }
    let Some(mut bank) = built(MaxwellBank::<T, N, A>::new(form, &specs, dt)) else {
        return Ok(());
    };
    let _ = bank.branch_response(decades(u, 1e-2, 1e4)?);
    let law = shift_factor(u)?;
    let backbone = backbone(u)?;
    let mut path = Path::new(10.0);
    let Some(b) = built(Bushing::new(backbone, (bank.clone(),))) else {
        return Ok(());
    };
    let mut s = b.state_at(path.next(u)?);
    steps(u, &b, &mut s, &mut path)?;
    // The state carries over a re-tune unchanged.
    for _ in 0..u.int_in_range(0u8..=3)? {
        retune(u, &mut bank, law)?;
        let Some(b) = built(Bushing::new(backbone, (bank.clone(),))) else {
            return Ok(());
        };
        steps(u, &b, &mut s, &mut path)?;
    }
    Ok(())
}

/// A WLF law and a temperature in °C, an Arrhenius law and one in
/// kelvin, or none.
fn shift_factor(u: &mut Unstructured<'_>) -> Result<Option<(ShiftFactor, f64, f64)>> {
    Ok(match u.int_in_range(0u8..=2)? {
        0 => built(ShiftFactor::wlf(
            param(u, 0.0, 40.0)?,
            param(u, 1.0, 200.0)?,
            param(u, -50.0, 100.0)?,
        ))
        .map(|law| (law, -80.0, 200.0)),
        1 => built(ShiftFactor::arrhenius(
            param(u, 1e3, 3e4)?,
            param(u, 200.0, 400.0)?,
        ))
        .map(|law| (law, 150.0, 500.0)),
        _ => None,
    })
}

/// Re-tunes `bank`, exactly or on line, to a shift factor from `law` or
/// drawn directly. A refused on-line re-tune leaves the bank as it was.
fn retune<T: Num, A: Accumulator<T>, const N: usize>(
    u: &mut Unstructured<'_>,
    bank: &mut MaxwellBank<T, N, A>,
    law: Option<(ShiftFactor, f64, f64)>,
) -> Result<()> {
    let alt = u.arbitrary()?;
    if u.arbitrary()? {
        let a_t = match law {
            Some((law, lo, hi)) => match built(law.at(param(u, lo, hi)?)) {
                Some(a_t) => {
                    assert!(a_t.is_finite() && a_t > 0.0, "shift factor {a_t}");
                    a_t
                }
                None => return Ok(()),
            },
            None => decades(u, 1e-3, 1e3)?,
        };
        if let Some(shifted) = built(bank.shifted(a_t)) {
            *bank = shifted;
        }
    } else {
        let a_t = match law {
            Some((law, lo, hi)) => {
                match built(T::shift_at(&law, T::from_f64(param(u, lo, hi)?), alt)) {
                    Some(a_t) => {
                        assert!(a_t.is_finite() && a_t > T::ZERO, "shift factor {a_t:?}");
                        a_t
                    }
                    None => return Ok(()),
                }
            }
            None if u.arbitrary()? => T::any(u)?,
            None => T::from_f64(decades(u, 1e-3, 1e3)?),
        };
        let before = bank.clone();
        if built(T::retune(bank, a_t, alt)).is_none() {
            assert!(*bank == before, "a refused re-tune changed the bank");
        }
    }
    Ok(())
}
