// Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
// the parameters of `model.toml` as constructor calls of the `bushing`
// crate. Units: mm, N, s; corners in Hz.

use bushing::{Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline, ParamError, Real};

/// Backbone knots, mm.
pub const BACKBONE_X_MM: [f64; 9] = [-4.5, -3.3125, -2.125, -0.9375, 0.25, 1.4375, 2.625, 3.8125, 5.0];
/// F^inf at the knots, N.
pub const BACKBONE_F_N: [f64; 9] = [-1013.0318788722275, -700.2903171733587, -405.1527105533265, -177.64154621396148, 47.48425363605597, 274.5818759568949, 529.773535401116, 828.7341821351097, 1179.4088979474718];
/// Maxwell cells: (corner Hz, fraction g).
pub const MAXWELL_HZ_G: [(f64, f64); 3] = [(0.48827319833613614, 0.09646025665398217), (4.784177420837615, 0.12005029860139267), (47.300902074317925, 0.08253854075028377)];

/// The Maxwell cells as the core's specs.
pub fn maxwell_cells() -> [MaxwellSpec; 3] {
    MAXWELL_HZ_G.map(|(f, g)| MaxwellSpec::hz(f, g))
}

/// Jenkins cells: (fraction g, slip force N).
pub const IWAN_G_SLIP_N: [(f64, f64); 4] = [(0.05058122924952603, 0.6696778896980692), (0.05046158742116023, 2.82558750466968), (0.062119616903167425, 9.337279306122223), (0.059194736013548785, 23.370808297568743)];

/// The Jenkins cells as the core's specs.
pub fn iwan_cells() -> [IwanCellSpec; 4] {
    IWAN_G_SLIP_N.map(|(g, f)| IwanCellSpec::new(g, f))
}

/// The identified bushing in the number type `T`.
pub type Model<T> = Bushing<T, MonotoneSpline<T, 9>, (MaxwellBank<T, 3>, IwanBank<T, 4>,)>;

/// The identified bushing at time step `dt` (s).
pub fn model<T: Real>(dt: f64) -> Result<Model<T>, ParamError> {
    Bushing::new(MonotoneSpline::new(&BACKBONE_X_MM, &BACKBONE_F_N)?, (MaxwellBank::new(MaxwellForm::RateExactRamp, &maxwell_cells(), dt)?, IwanBank::new(&iwan_cells())?,))
}
