//! Hard cases of the Grünwald memory near α = 0 and α = 1.

use core::f64::consts::TAU;

use bushing::{Bushing, FractionalSpec, Grunwald, Polynomial};

use super::{Measure, effect_force, worst};
use crate::check::param;

/// Storage and loss of a 256-tap cell (f_c = 2 Hz, g = 0.6) at 1 kHz under
/// a 5 Hz sine, against the discrete model's own response (f64).
fn grunwald_against_response(alpha: f64) -> Measure {
    let k = 100.0f64;
    let cell =
        Grunwald::<f32, 256>::new(FractionalSpec::hz(2.0, alpha, 0.6), 1e-3).map_err(param)?;
    let (re, im) = cell.branch_response(TAU * 5.0);
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(k).map_err(param)?, (cell,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let (per, cycles) = (200usize, 8usize);
    let (mut a_sin, mut a_cos) = (0.0f64, 0.0f64);
    for n in 1..=cycles * per {
        let phase = TAU * (n % per) as f64 / per as f64;
        let f = effect_force(&b, &mut s, libm::sin(phase) as f32) as f64;
        if n > (cycles - 1) * per {
            a_sin += 2.0 * f * libm::sin(phase) / per as f64;
            a_cos += 2.0 * f * libm::cos(phase) / per as f64;
        }
    }
    // The loss share is small near α = 0: measure both against the
    // modulus, |K*| of the branch.
    let modulus = k * libm::hypot(re, im);
    Ok(worst(
        libm::fabs(a_sin - k * re) / modulus,
        libm::fabs(a_cos - k * im) / modulus,
    ))
}

pub(super) fn grunwald_alpha_near_zero() -> Measure {
    grunwald_against_response(0.02)
}

pub(super) fn grunwald_alpha_near_one() -> Measure {
    grunwald_against_response(0.98)
}
