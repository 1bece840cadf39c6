//! Hard cases of friction cells under huge steps: Bouc-Wen with large
//! exponents, Dahl and Berg.

use bushing::{Berg, BoucWen, Bushing, Dahl, Effect, EffectOutput, Polynomial};

use super::{Measure, worst};
use crate::check::param;

/// Largest |F| / `bound` of `e` on a unit linear backbone through jumps of
/// `h` (0, h, -h, ...); NaN on a refused step, a non-finite output or a
/// negative dissipation.
fn jumps<E: Effect<f32, Report = EffectOutput<f32>>>(e: E, h: f32, bound: f32) -> Measure {
    let b = Bushing::new(Polynomial::<f32, 2>::linear(1.0).map_err(param)?, (e,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut w = 0.0f64;
    for k in 0..300 {
        let x = match k % 3 {
            0 => 0.0,
            1 => h,
            _ => -h,
        };
        let Some(o) = b.step(&mut s, x).effects.map(|r| r.0) else {
            return Ok(f64::NAN);
        };
        if !(o.force.is_finite() && o.dissipated >= 0.0) {
            return Ok(f64::NAN);
        }
        w = w.max((o.force.abs() / bound) as f64);
    }
    Ok(w)
}

pub(super) fn bouc_wen_large_exponents() -> Measure {
    let mut w = 0.0f64;
    for n in [5.0, 20.0, 50.0] {
        let bw = BoucWen::<f32>::new(100.0, 1.0, 30.0, 10.0, n).map_err(param)?;
        let f_u = bw.ultimate_force();
        for h in [0.01f32, 1.0, 100.0] {
            w = worst(w, jumps(bw, h * f_u / 100.0, f_u)?);
        }
    }
    Ok(w)
}

pub(super) fn dahl_huge_steps() -> Measure {
    let mut w = 0.0f64;
    for alpha in [0.3, 1.0, 2.0, 5.0] {
        let d = Dahl::<f32>::new(100.0, 2.0, alpha).map_err(param)?;
        for h in [0.01f32, 1.0, 100.0] {
            w = worst(w, jumps(d, h * 0.02, 2.0)?);
        }
    }
    Ok(w)
}

pub(super) fn berg_huge_steps() -> Measure {
    let berg = Berg::<f32>::new(3.0, 0.1).map_err(param)?;
    let mut w = 0.0f64;
    for h in [0.001f32, 0.1, 10.0] {
        w = worst(w, jumps(berg, h, 3.0)?);
    }
    Ok(w)
}
