//! Shared pieces of the firmware examples: the kernels whose cost is
//! measured, built the way a rig firmware builds them.
#![no_std]
#![forbid(unsafe_code)]

use core::f64::consts::PI;

use bushing::{
    Backbone, Bushing, Compensated, Effect, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline,
    ParamError, Polynomial,
};

/// Control period of the probes: 2 kHz.
pub const DT: f64 = 5e-4;

/// Four cells from 0.05 Hz to 50 Hz, one per decade.
pub const CELLS: [MaxwellSpec; 4] = [
    MaxwellSpec::new(0.1 * PI, 0.1),
    MaxwellSpec::new(PI, 0.1),
    MaxwellSpec::new(10.0 * PI, 0.15),
    MaxwellSpec::new(100.0 * PI, 0.1),
];

/// Polynomial backbone with a 4-cell bank of plain states.
pub type Maxwell4 = Bushing<f32, Polynomial<f32, 4>, (MaxwellBank<f32, 4>,)>;
/// Polynomial backbone with a 4-cell bank of compensated states.
pub type Maxwell4Compensated =
    Bushing<f32, Polynomial<f32, 4>, (MaxwellBank<f32, 4, Compensated<f32>>,)>;

/// Cubic hardening backbone, N and mm.
pub fn polynomial() -> Result<Polynomial<f32, 4>, ParamError> {
    Polynomial::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0))
}

/// Eight measured points, N and mm.
pub fn spline() -> Result<MonotoneSpline<f32, 8>, ParamError> {
    MonotoneSpline::new(
        &[-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0],
        &[-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0],
    )
}

/// A polynomial backbone with a 4-cell bank in `form`.
pub fn maxwell4(form: MaxwellForm) -> Result<Maxwell4, ParamError> {
    Bushing::new(polynomial()?, (MaxwellBank::new(form, &CELLS, DT)?,))
}

/// The same with compensated cell states.
pub fn maxwell4_compensated() -> Result<Maxwell4Compensated, ParamError> {
    Bushing::new(
        polynomial()?,
        (MaxwellBank::new(MaxwellForm::RateExactRamp, &CELLS, DT)?,),
    )
}

/// Triangle input of `N` samples between -2 and 2 mm.
pub fn triangle<const N: usize>() -> [f32; N] {
    let mut x = [0.0f32; N];
    for (i, v) in x.iter_mut().enumerate() {
        let u = (i % 200) as f32 / 200.0;
        *v = if u < 0.5 {
            -2.0 + 8.0 * u
        } else {
            6.0 - 8.0 * u
        };
    }
    x
}

/// Steps `b` over `xs`, feeding every output to `sink`.
#[inline(never)]
pub fn run<B: Backbone<f32>, E: Effect<f32>>(
    b: &Bushing<f32, B, E>,
    xs: &[f32],
    mut sink: impl FnMut(f32, f32, f32),
) {
    let mut s = b.state_at(0.0);
    for &x in xs {
        let o = b.step(&mut s, core::hint::black_box(x));
        sink(o.force, o.tangent, o.dissipated);
    }
}
