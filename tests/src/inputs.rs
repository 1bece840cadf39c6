//! Non-finite and huge inputs on a Maxwell bushing: refused, the state
//! kept, the fault raised.

use bushing::{Bushing, Faults, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};

use crate::check::{CaseResult, Failure, holds, param};

pub(crate) type Demo32 = Bushing<f32, Polynomial<f32, 4>, (MaxwellBank<f32, 3>,)>;

/// A hardening backbone with three exact-ramp Maxwell cells, f32, 1 kHz.
pub(crate) fn demo32() -> Result<Demo32, Failure> {
    let specs = [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(5.0, 0.1),
        MaxwellSpec::hz(50.0, 0.1),
    ];
    let bank = MaxwellBank::new(MaxwellForm::RateExactRamp, &specs, 1e-3).map_err(param)?;
    let bb = Polynomial::new(&[0.0, 200.0, 0.0, 8.0], (-5.0, 5.0)).map_err(param)?;
    Bushing::new(bb, (bank,)).map_err(param)
}

pub(crate) fn non_finite_input_keeps_state() -> CaseResult {
    let b = demo32()?;
    let mut s = b.state_at(0.0);
    for n in 0..100 {
        b.step(&mut s, n as f32 * 0.01);
    }
    let before = s.clone();
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let out = b.step(&mut s, bad);
        holds(
            "refused step returns the last force",
            out.force == before.force(),
        )?;
        holds("refused step dissipates nothing", out.dissipated == 0.0)?;
    }
    holds(
        "fault flag raised",
        s.faults().contains(Faults::NON_FINITE_INPUT),
    )?;
    holds("three steps counted as refused", s.rejected() == 3)?;
    holds("effects' state untouched", s.effects() == before.effects())?;
    s.clear_faults();
    let out = b.step(&mut s, 1.01);
    holds(
        "next finite step runs",
        out.force.is_finite() && out.effects.is_some() && s.faults().is_empty(),
    )
}

pub(crate) fn huge_input_refused() -> CaseResult {
    let b = demo32()?;
    let mut s = b.state_at(0.5);
    let f = s.force();
    // 1e30 mm on a linear extension of slope ~800 N/mm: above the guard.
    let out = b.step(&mut s, 1e30);
    holds(
        "out-of-range flag",
        s.faults().contains(Faults::OUT_OF_RANGE),
    )?;
    holds("force kept", out.force == f)?;
    // Large but representable: accepted and finite.
    let out = b.step(&mut s, 1e12);
    holds(
        "1e12 accepted, finite",
        out.effects.is_some() && out.force.is_finite() && out.dissipated.is_finite(),
    )
}
