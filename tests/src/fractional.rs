//! The Grünwald fractional cell's steady modulus.

use bushing::{Bushing, FractionalSpec, Grunwald, Polynomial};

use crate::check::{CaseResult, at_most, param};

pub(crate) fn grunwald_modulus_f32() -> CaseResult {
    // A 256-tap fractional cell (α = 0.5, f_c = 2 Hz, g = 0.6) at 1 kHz
    // under a 5 Hz sine: the steady branch force matches the discrete
    // model's own response (computed in f64) to 2e-3, and the energy per
    // cycle its loss, π K'' x².
    let k = 100.0f64;
    let spec = FractionalSpec::hz(2.0, 0.5, 0.6);
    let cell = Grunwald::<f32, 256>::new(spec, 1e-3).map_err(param)?;
    let (re, im) = cell.branch_response(core::f64::consts::TAU * 5.0);
    let b =
        Bushing::new(Polynomial::<f32, 2>::linear(k).map_err(param)?, (cell,)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let per = 200usize;
    let cycles = 8usize;
    let (mut a_sin, mut a_cos, mut energy) = (0.0f64, 0.0f64, 0.0f64);
    for n in 1..=cycles * per {
        let phase = core::f64::consts::TAU * (n % per) as f64 / per as f64;
        let out = b.step(&mut s, libm::sin(phase) as f32);
        if n > (cycles - 1) * per {
            let f = out.effects.map_or(f64::NAN, |r| r.0.force as f64);
            a_sin += 2.0 * f * libm::sin(phase) / per as f64;
            a_cos += 2.0 * f * libm::cos(phase) / per as f64;
            energy += out.dissipated as f64;
        }
    }
    at_most(
        "storage share vs discrete response",
        libm::fabs(a_sin / (k * re) - 1.0),
        2e-3,
    )?;
    at_most(
        "loss share vs discrete response",
        libm::fabs(a_cos / (k * im) - 1.0),
        2e-3,
    )?;
    at_most(
        "energy per cycle vs pi K'' x^2",
        libm::fabs(energy / (core::f64::consts::PI * k * im) - 1.0),
        5e-3,
    )
}
