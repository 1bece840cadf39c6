//! The reference Iwan oscillator in free decay.

use bushing::Oscillator;

use crate::check::{CaseResult, at_most, holds, param};
use crate::iwan::reference_iwan;

pub(crate) fn iwan_oscillator_free_decay_f32() -> CaseResult {
    // The reference oscillator of seed 004 §4.1 released from 1.5 m: the
    // log decrement over the first cycles against the secant damping, to
    // the 0.2 points of damping within which seed 004 reports agreement.
    let osc = Oscillator::new(reference_iwan::<f32>()?, 0.005).map_err(param)?;
    let mut s = osc.state_at(1.5, 0.0, 0.0);
    let (mut p1, mut p2) = (1.5f32, 1.5f32);
    let mut peaks = [0.0f32; 6];
    let mut found = 0;
    for _ in 0..100_000 {
        let out = osc.step(&mut s, 0.0);
        holds("Newton converged", out.converged)?;
        if p2 > p1 && p2 >= out.p && p2 > 0.0 {
            if let Some(slot) = peaks.get_mut(found) {
                *slot = p2;
            }
            found += 1;
            if found == peaks.len() {
                break;
            }
        }
        (p1, p2) = (p2, out.p);
    }
    holds("six peaks found", found == peaks.len())?;
    for w in peaks.windows(2) {
        let (a, b) = (w[0] as f64, w[1] as f64);
        let pm = libm::sqrt(a * b);
        let xi = libm::log(a / b) / core::f64::consts::TAU;
        let phis = (0..20).map(|i| 0.2 + 1.8 * i as f64 / 19.0);
        let d: f64 = phis
            .clone()
            .filter(|&f| f < pm)
            .map(|f| 0.2 * f * (pm - f))
            .sum();
        let f_r = 5.0 * pm + phis.map(|f| 0.05 * pm.min(f)).sum::<f64>();
        let reference = d / (core::f64::consts::TAU * f_r * pm);
        at_most(
            "|xi - xi_secant| (damping ratio)",
            libm::fabs(xi - reference),
            2e-3,
        )?;
    }
    Ok(())
}
