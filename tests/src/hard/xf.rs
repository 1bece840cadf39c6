//! Hard cases of x_f cells with steps far larger than x_f.

use bushing::XfForm;

use super::{Measure, worst};
use crate::xf::xf_saturation;

pub(super) fn xf_exact_ramp_steps_far_above_xf() -> Measure {
    let mut w = 0.0f64;
    for a in [1e2, 1e3, 1e4] {
        let r = xf_saturation::<f32>(XfForm::ExactRamp, a)?;
        w = worst(w, libm::fabs(r - 1.0));
    }
    Ok(w)
}

pub(super) fn xf_midpoint_steps_far_above_xf() -> Measure {
    let mut w = 0.0f64;
    for a in [10.0, 30.0, 100.0] {
        let r = xf_saturation::<f32>(XfForm::Midpoint, a)?;
        w = worst(w, libm::fabs(r - bushing::xf::midpoint_saturation_ratio(a)));
    }
    Ok(w)
}
