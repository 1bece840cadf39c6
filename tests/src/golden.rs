//! The golden traces: f32 runs whose hash must be bit-identical on the host
//! and on every Cortex-M target.

use bushing::stack::{FirstLoading, Sts, TurningPoints};
use bushing::{
    Berg, BoucWen, Bushing, Compensated, Dahl, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm,
    MaxwellSpec, MonotoneSpline, Oscillator, Polynomial, Real, XfBank, XfForm, XfSpec,
};

use crate::check::{CaseResult, Failure, holds, param};
use crate::iwan::reference_iwan;

/// FNV-1a over the bit patterns of a trace.
#[derive(Debug, Clone, Copy)]
pub struct TraceHash(u64);

impl TraceHash {
    /// Empty hash.
    pub const fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    /// Mixes one value.
    pub fn push<T: Real>(&mut self, v: T) {
        for byte in v.bits().to_le_bytes() {
            self.0 ^= byte as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    /// The hash.
    pub const fn value(self) -> u64 {
        self.0
    }
}

impl Default for TraceHash {
    fn default() -> Self {
        Self::new()
    }
}

/// Steps of the golden trace.
pub const GOLDEN_STEPS: usize = 12_000;

/// Hash of the golden trace, as computed on the host and required on every
/// target. Regenerate with `cargo test -p bushing-tests --test golden -- --nocapture`
/// after a deliberate change of a kernel, and say why in the commit.
pub const GOLDEN_HASH: u64 = 0x45d3_8d76_7be4_a98a;

/// The golden trace: two f32 bushings (polynomial + 4 compensated exact-ramp
/// cells; spline + 3 midpoint cells) under a two-tone input with a NaN and
/// an out-of-range sample inside; hashes force, tangent and energy.
pub fn golden_trace() -> Result<u64, Failure> {
    let specs4 = [
        MaxwellSpec::hz(0.02, 0.08),
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(5.0, 0.12),
        MaxwellSpec::hz(80.0, 0.1),
    ];
    let dt = 2e-4;
    let bank4 =
        MaxwellBank::<f32, 4, Compensated<f32>>::new(MaxwellForm::RateExactRamp, &specs4, dt)
            .map_err(param)?;
    let poly = Polynomial::<f32, 4>::new(&[0.0, 200.0, 5.0, 8.0], (-5.0, 5.0)).map_err(param)?;
    let a = Bushing::new(poly, (bank4,)).map_err(param)?;
    let specs3 = [
        MaxwellSpec::hz(1.0, 0.1),
        MaxwellSpec::hz(10.0, 0.1),
        MaxwellSpec::hz(900.0, 0.1),
    ];
    let bank3 =
        MaxwellBank::<f32, 3>::new(MaxwellForm::RateMidpoint, &specs3, dt).map_err(param)?;
    let xs = [-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0];
    let fs = [-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0];
    let spline = MonotoneSpline::<f32, 8>::new(&xs, &fs).map_err(param)?;
    let b = Bushing::new(spline, (bank3,)).map_err(param)?;
    let (mut sa, mut sb) = (a.state_at(0.0), b.state_at(0.0));
    let mut hash = TraceHash::new();
    let w1 = (core::f64::consts::TAU * 3.0 * dt) as f32;
    let w2 = (core::f64::consts::TAU * 47.0 * dt) as f32;
    for n in 0..GOLDEN_STEPS {
        let t = n as f32;
        let mut x = 3.0 * libm::sinf(w1 * t) + 0.2 * libm::sinf(w2 * t);
        if n == 5000 {
            x = f32::NAN;
        }
        if n == 7000 {
            x = 1e25;
        }
        for out in
            [a.step(&mut sa, x), b.step(&mut sb, x)].map(|o| (o.force, o.tangent, o.dissipated))
        {
            hash.push(out.0);
            hash.push(out.1);
            hash.push(out.2);
        }
    }
    holds(
        "golden trace saw its two faults",
        sa.rejected() == 2 && sb.rejected() == 2,
    )?;
    Ok(hash.value())
}

pub(crate) fn golden_trace_f32() -> CaseResult {
    let h = golden_trace()?;
    if h == GOLDEN_HASH {
        Ok(())
    } else {
        Err(Failure {
            what: "golden trace hash differs from the host's",
            got: 0.0,
            bound: 0.0,
            bits: Some((h, GOLDEN_HASH)),
        })
    }
}

/// Hash of the hysteresis golden trace (see [`GOLDEN_HASH`]).
pub const GOLDEN_HYSTERESIS_HASH: u64 = 0x3857_ad1d_890b_1d11;

/// A composite f32 bushing: hardening backbone, 3 Maxwell cells (exact
/// ramp), 3 Jenkins cells (clamp) and 2 x_f cells (exact ramp), under a
/// two-tone input with a NaN inside; hashes force, tangent and energy.
pub fn golden_trace_hysteresis() -> Result<u64, Failure> {
    let dt = 5e-4;
    let maxwell = MaxwellBank::<f32, 3>::new(
        MaxwellForm::RateExactRamp,
        &[
            MaxwellSpec::hz(0.5, 0.1),
            MaxwellSpec::hz(5.0, 0.1),
            MaxwellSpec::hz(50.0, 0.05),
        ],
        dt,
    )
    .map_err(param)?;
    let iwan = IwanBank::<f32, 3>::new(&[
        IwanCellSpec::from_slip_distance(0.1, 150.0, 0.05),
        IwanCellSpec::from_slip_distance(0.1, 150.0, 0.2),
        IwanCellSpec::from_slip_distance(0.1, 150.0, 0.8),
    ])
    .map_err(param)?;
    let xf = XfBank::<f32, 2>::new(
        XfForm::ExactRamp,
        &[XfSpec::hz(0.005, 0.15, 0.02), XfSpec::hz(5.0, 0.1, 0.002)],
        dt,
    )
    .map_err(param)?;
    let bb = Polynomial::<f32, 4>::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).map_err(param)?;
    let b = Bushing::new(bb, (maxwell, iwan, xf)).map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut hash = TraceHash::new();
    let w1 = (core::f64::consts::TAU * 2.0 * dt) as f32;
    let w2 = (core::f64::consts::TAU * 31.0 * dt) as f32;
    for n in 0..GOLDEN_STEPS {
        let t = n as f32;
        let mut x = 2.0 * libm::sinf(w1 * t) + 0.1 * libm::sinf(w2 * t);
        if n == 4000 {
            x = f32::NAN;
        }
        let out = b.step(&mut s, x);
        hash.push(out.force);
        hash.push(out.tangent);
        hash.push(out.dissipated);
        if let Some((m, i, f)) = out.effects {
            for e in [m, i, f] {
                holds(
                    "no branch reports negative dissipation",
                    e.dissipated >= 0.0,
                )?;
            }
        }
    }
    holds("hysteresis golden trace saw its fault", s.rejected() == 1)?;
    Ok(hash.value())
}

pub(crate) fn golden_trace_hysteresis_f32() -> CaseResult {
    let h = golden_trace_hysteresis()?;
    if h == GOLDEN_HYSTERESIS_HASH {
        Ok(())
    } else {
        Err(Failure {
            what: "hysteresis golden trace hash differs from the host's",
            got: 0.0,
            bound: 0.0,
            bits: Some((h, GOLDEN_HYSTERESIS_HASH)),
        })
    }
}

/// Hash of the friction golden trace (see [`GOLDEN_HASH`]). It changed
/// when the turning-point stack's energy became the exact work along each
/// branch travelled (the forces and tangents did not change), and when the
/// Bouc-Wen solver took Newton's converged step instead of bisecting
/// again, with `|w|^(n-1)` as products for a whole n (the root moved
/// within rounding).
pub const GOLDEN_FRICTION_HASH: u64 = 0x05d0_56ac_9e3f_3f95;

/// The cells that call libm per step, in f32: the STS law on an 8-deep
/// turning-point stack (so that it overflows), Dahl (α = 0.7), Bouc-Wen
/// (n = 3) and Berg on one linear backbone under a sine of falling
/// amplitude with a NaN inside; then the reference Iwan oscillator under a forced sine.
/// Hashes force, tangent and energy of the bushing, and p, v and the
/// restoring force of the oscillator.
pub fn golden_trace_friction() -> Result<u64, Failure> {
    let stack = TurningPoints::<_, 8>::new(
        Sts::<f32>::new(400.0, 300.0).map_err(param)?,
        FirstLoading::Masing,
    );
    let dahl = Dahl::<f32>::new(200.0, 10.0, 0.7).map_err(param)?;
    let bouc_wen = BoucWen::<f32>::new(20.0, 10.0, 60.0, 20.0, 3.0).map_err(param)?;
    let berg = Berg::<f32>::new(12.0, 0.05).map_err(param)?;
    let b = Bushing::new(
        Polynomial::<f32, 2>::linear(100.0).map_err(param)?,
        (stack, dahl, bouc_wen, berg),
    )
    .map_err(param)?;
    let mut s = b.state_at(0.0);
    let mut hash = TraceHash::new();
    let dt = 5e-4;
    // A 23 Hz sine whose amplitude falls from 1.5 to 0.15 mm: every
    // reversal lies inside the last one, so the turning points pile up.
    let w = (core::f64::consts::TAU * 23.0 * dt) as f32;
    let fall = 0.9 / GOLDEN_STEPS as f32;
    for n in 0..GOLDEN_STEPS {
        let t = n as f32;
        let mut x = 1.5 * (1.0 - fall * t) * libm::sinf(w * t);
        if n == 3000 {
            x = f32::NAN;
        }
        let out = b.step(&mut s, x);
        hash.push(out.force);
        hash.push(out.tangent);
        hash.push(out.dissipated);
        if let Some((k, d, w, g)) = out.effects {
            for e in [k, d, w, g] {
                holds(
                    "no friction cell reports negative dissipation",
                    e.dissipated >= 0.0,
                )?;
            }
        }
    }
    holds("friction golden trace saw its fault", s.rejected() == 1)?;
    holds("the 8-deep stack overflowed", s.effects().0.overflows() > 0)?;
    let osc = Oscillator::new(reference_iwan::<f32>()?, 0.01).map_err(param)?;
    let mut so = osc.state_at(0.0, 0.0, 0.0);
    let w = (2.3 * 0.01) as f32;
    for n in 1..=4000 {
        let out = osc.step(&mut so, 1.2 * libm::sinf(w * n as f32));
        holds("oscillator converged", out.converged)?;
        hash.push(out.p);
        hash.push(out.v);
        hash.push(out.force);
    }
    Ok(hash.value())
}

pub(crate) fn golden_trace_friction_f32() -> CaseResult {
    let h = golden_trace_friction()?;
    if h == GOLDEN_FRICTION_HASH {
        Ok(())
    } else {
        Err(Failure {
            what: "friction golden trace hash differs from the host's",
            got: 0.0,
            bound: 0.0,
            bits: Some((h, GOLDEN_FRICTION_HASH)),
        })
    }
}
