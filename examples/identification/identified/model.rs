// Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
// the parameters of `model.toml` as constructor calls of the `bushing`
// crate. Units: mm, N, s; corners in Hz.

use bushing::{Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline, ParamError, Real};

/// Backbone knots, mm.
pub const BACKBONE_X_MM: [f64; 9] = [-4.5, -3.3125, -2.125, -0.9375, 0.25, 1.4375, 2.625, 3.8125, 5.0];
/// F^inf at the knots, N.
pub const BACKBONE_F_N: [f64; 9] = [-1006.773655176911, -701.7911213910143, -404.7655542698291, -177.5833827437563, 47.49387367344312, 274.78319429248506, 530.0356097904846, 828.8310634608772, 1179.4569027788057];
/// Maxwell cells: (corner Hz, fraction g).
pub const MAXWELL_HZ_G: [(f64, f64); 3] = [(0.4882560704996233, 0.09644869125893366), (4.783858292669776, 0.12004384348298437), (47.30147829613322, 0.08253231298430493)];

/// The Maxwell cells as the core's specs.
pub fn maxwell_cells() -> [MaxwellSpec; 3] {
    MAXWELL_HZ_G.map(|(f, g)| MaxwellSpec::hz(f, g))
}

/// Jenkins cells: (fraction g, slip force N).
pub const IWAN_G_SLIP_N: [(f64, f64); 4] = [(0.05057404944023454, 0.6696540762488987), (0.05043852078728055, 2.822915470755744), (0.06196501487759307, 9.306494386522843), (0.05912524098482845, 23.068790657992075)];

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
