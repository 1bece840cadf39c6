//! The modal oscillator: `Oscillator::new` (and `with_max_iterations`) on
//! the Iwan restoring force of the joint thesis, a Maxwell one (built for
//! the oscillator's step or another) or a friction cell, from an
//! arbitrary state, under arbitrary forces or a `Sweep`.
//!
//! Contract: a step never panics; a refused one (no iteration) keeps the
//! state and returns the last restoring force; an accepted one gives a
//! restoring force within the guard, a finite dissipated energy and a
//! finite state.

use arbitrary::{Result, Unstructured};
use bushing::excitation::{Spacing, Sweep};
use bushing::{
    Backbone, Berg, Bushing, Dahl, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, Oscillator,
    Polynomial,
};

use crate::contract::{Members, built, guarded};
use crate::draw::{Path, backbone, decades, fraction, param, time_step};
use crate::maxwell::specs;
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let dt = time_step(u)?;
    let backbone = backbone::<T>(u)?;
    match u.int_in_range(0u8..=3)? {
        0 => {
            let Some(linear) = built(Polynomial::<T, 2>::linear(decades(u, 1.0, 1e6)?)) else {
                return Ok(());
            };
            let mut cells = [IwanCellSpec::new(0.0, 0.0); 4];
            for c in &mut cells {
                *c = IwanCellSpec::new(fraction(u, 4)?, decades(u, 1e-2, 1e2)?);
            }
            match built(IwanBank::<T, 4>::new(&cells)) {
                Some(bank) => run(u, linear, (bank,), dt),
                None => Ok(()),
            }
        }
        1 => {
            let bank_dt = if u.ratio(1u8, 4)? { time_step(u)? } else { dt };
            let form = *u.choose(&MaxwellForm::ALL)?;
            match built(MaxwellBank::<T, 2>::new(form, &specs::<2>(u)?, bank_dt)) {
                Some(bank) => run(u, backbone, (bank,), dt),
                None => Ok(()),
            }
        }
        2 => match built(Berg::<T>::new(param(u, 0.0, 50.0)?, param(u, 0.0, 1.0)?)) {
            Some(cell) => run(u, backbone, (cell,), dt),
            None => Ok(()),
        },
        _ => match built(Dahl::<T>::new(
            decades(u, 1.0, 1e4)?,
            decades(u, 1e-2, 50.0)?,
            param(u, 0.0, 3.0)?,
        )) {
            Some(cell) => run(u, backbone, (cell,), dt),
            None => Ok(()),
        },
    }
}

fn run<T: Num, B: Backbone<T>, E: Members<T>>(
    u: &mut Unstructured<'_>,
    backbone: B,
    effects: E,
    dt: f64,
) -> Result<()> {
    let Some(restoring) = built(Bushing::new(backbone, effects)) else {
        return Ok(());
    };
    let Some(mut osc) = built(Oscillator::new(restoring, dt)) else {
        return Ok(());
    };
    if u.ratio(1u8, 4)? {
        osc = osc.with_max_iterations(u.int_in_range(0u32..=64)?);
    }
    let _ = (osc.dt(), osc.reference_stiffness(), osc.restoring().g0());
    let mut path = Path::<T>::new(decades(u, 1e-2, 1e4)?);
    let mut s = osc.state_at(path.next(u)?, path.next(u)?, path.next(u)?);
    // A sweep's amplitude, start and end frequencies and duration.
    let sweep = if u.arbitrary()? {
        let spacing = if u.arbitrary()? {
            Spacing::Log
        } else {
            Spacing::Linear
        };
        let amplitude = param(u, 0.0, 1e3)?;
        built(Sweep::new(
            decades(u, 0.1, 1e3)?,
            decades(u, 0.1, 1e3)?,
            decades(u, 1e-3, 10.0)?,
            spacing,
        ))
        .map(|sweep| (amplitude, sweep))
    } else {
        None
    };
    for n in 0..u.int_in_range(1u32..=256)? {
        let f = match &sweep {
            Some((amplitude, sweep)) if !u.ratio(1u8, 16)? => {
                let _ = sweep.frequency(n as f64 * dt);
                T::from_f64(amplitude * sweep.unit(n as f64 * dt))
            }
            _ => path.next(u)?,
        };
        let (p, v, a, r) = (s.p(), s.v(), s.a(), s.restoring().force());
        let out = osc.step(&mut s, f);
        if out.iterations == 0 {
            assert!(!out.converged, "a refused step reports convergence");
            let kept = [
                (p, s.p()),
                (v, s.v()),
                (a, s.a()),
                (r, s.restoring().force()),
            ];
            assert!(
                kept.iter().all(|(x, y)| x.bits() == y.bits()) && out.force.bits() == r.bits(),
                "a refused step changed the state: {out:?}"
            );
        } else {
            assert!(
                guarded(out.force) && out.dissipated.is_finite(),
                "an accepted step out of the contract: {out:?}"
            );
            assert!(
                s.p().is_finite() && s.v().is_finite() && s.a().is_finite(),
                "an accepted step left a non-finite state: {out:?}"
            );
        }
    }
    Ok(())
}
