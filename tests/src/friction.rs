//! Dahl, Bouc-Wen and Berg cells bounded under huge steps.

use bushing::{Berg, BoucWen, Bushing, Dahl, Effect, EffectOutput, Polynomial};

use crate::check::{CaseResult, Failure, at_most, holds, param};

/// Steps `b` through jumps of `h` (0, h, -h, ...): finite, within `bound`,
/// never negative dissipation.
fn bounded_under_jumps<E: Effect<f32, Report = EffectOutput<f32>>>(
    e: E,
    h: f32,
    bound: f32,
) -> CaseResult {
    let b = Bushing::new(Polynomial::<f32, 2>::linear(1.0).map_err(param)?, (e,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    for k in 0..300 {
        let x = match k % 3 {
            0 => 0.0,
            1 => h,
            _ => -h,
        };
        let o = b.step(&mut s, x).effects.map(|r| r.0);
        let o = o.ok_or(Failure {
            what: "step refused",
            got: x as f64,
            bound: 0.0,
            bits: None,
        })?;
        holds(
            "finite force and energy",
            o.force.is_finite() && o.dissipated.is_finite(),
        )?;
        holds("dissipation never negative", o.dissipated >= 0.0)?;
        at_most(
            "|F| over its bound",
            (o.force.abs() / bound) as f64,
            1.0 + 1e-5,
        )?;
    }
    Ok(())
}

pub(crate) fn friction_cells_bounded_f32() -> CaseResult {
    // Steps from 1e-2 to 100 times the characteristic displacement.
    for alpha in [0.3, 1.0, 2.0, 5.0] {
        let d = Dahl::<f32>::new(100.0, 2.0, alpha).map_err(param)?;
        for h in [0.01f32, 1.0, 100.0] {
            bounded_under_jumps(d, h * 0.02, 2.0)?;
        }
    }
    for n in [0.5, 1.0, 2.0, 5.0, 20.0] {
        let bw = BoucWen::<f32>::new(100.0, 1.0, 30.0, 10.0, n).map_err(param)?;
        let f_u = bw.ultimate_force();
        for h in [0.01f32, 1.0, 100.0] {
            bounded_under_jumps(bw, h * f_u / 100.0, f_u)?;
        }
    }
    let berg = Berg::<f32>::new(3.0, 0.1).map_err(param)?;
    for h in [0.001f32, 0.1, 10.0] {
        bounded_under_jumps(berg, h, 3.0)?;
    }
    Ok(())
}
