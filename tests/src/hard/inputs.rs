//! Hard cases of non-finite and huge inputs: refused with the state kept,
//! then recovery.

use bushing::Faults;

use super::{Measure, miss};
use crate::inputs::demo32;

pub(super) fn non_finite_inputs_keep_state() -> Measure {
    let b = demo32()?;
    let mut s = b.state_at(0.0);
    for n in 0..100 {
        b.step(&mut s, n as f32 * 0.01);
    }
    let mut wrong = 0.0;
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let before = s.clone();
        let out = b.step(&mut s, bad);
        wrong += miss(out.force == before.force() && out.dissipated == 0.0);
        wrong += miss(s.effects() == before.effects() && s.force() == before.force());
        wrong += miss(s.faults().contains(Faults::NON_FINITE_INPUT));
        s.clear_faults();
    }
    Ok(wrong)
}

pub(super) fn huge_inputs_refused_then_recover() -> Measure {
    let b = demo32()?;
    let mut s = b.state_at(0.5);
    let mut wrong = 0.0;
    for huge in [1e30f32, -1e30] {
        let before = s.clone();
        let out = b.step(&mut s, huge);
        wrong += miss(s.faults().contains(Faults::OUT_OF_RANGE));
        wrong += miss(out.force == before.force() && s.effects() == before.effects());
        s.clear_faults();
    }
    for large in [1e12f32, -1e12, 0.5] {
        let out = b.step(&mut s, large);
        wrong += miss(out.effects.is_some() && out.force.is_finite() && out.dissipated.is_finite());
    }
    Ok(wrong)
}
