//! x_f cells in steady sliding: the exact ramp saturates, the midpoint form
//! follows its own law.

use bushing::{Bushing, Polynomial, Real, XfBank, XfForm, XfSpec};

use crate::check::{CaseResult, Failure, at_most, param};

/// Steady sliding at a = |dx| / x_f per step, omega = 0: force over g K x_f.
pub(crate) fn xf_saturation<T: Real>(form: XfForm, a: f64) -> Result<f64, Failure> {
    let (g, k, x_f) = (0.5, 10.0, 0.2);
    let bank = XfBank::<T, 1>::new(form, &[XfSpec { omega: 0.0, g, x_f }], 1e-3).map_err(param)?;
    let b = Bushing::new(Polynomial::<T, 2>::linear(k).map_err(param)?, (bank,)).map_err(param)?;
    let mut s = b.state_at(T::ZERO);
    let steps = (libm::ceil(40.0 / a) as usize).max(40);
    let mut f = 0.0;
    // Back and forth around zero keeps x small in f32: slide up, then the
    // last 40/a steps measure.
    for n in 1..=steps {
        let x = T::from_f64(n as f64 * a * x_f);
        f = b
            .step(&mut s, x)
            .effects
            .map_or(f64::NAN, |r| r.0.force.to_f64());
    }
    Ok(f / (g * k * x_f))
}

pub(crate) fn xf_exact_ramp_saturates_f32() -> CaseResult {
    for a in [0.01, 0.1, 1.0, 10.0, 1e3] {
        let r = xf_saturation::<f32>(XfForm::ExactRamp, a)?;
        at_most(
            "exact-ramp saturation error, relative",
            libm::fabs(r - 1.0),
            1e-6,
        )?;
    }
    Ok(())
}

pub(crate) fn xf_midpoint_under_saturation_f32() -> CaseResult {
    for a in [0.5, 1.0, 2.0, 5.0] {
        let r = xf_saturation::<f32>(XfForm::Midpoint, a)?;
        let expected = bushing::xf::midpoint_saturation_ratio(a);
        at_most(
            "midpoint saturation vs a/(2 sinh(a/2))",
            libm::fabs(r - expected),
            1e-5,
        )?;
    }
    Ok(())
}
