// Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
// the parameters of `model.toml` as constructor calls of the `bushing`
// crate. Units: mm, N, s; corners in Hz.

use bushing::{Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline, ParamError, Real};

/// Backbone knots, mm.
pub const BACKBONE_X_MM: [f64; 9] = [-4.5, -3.3125, -2.125, -0.9375, 0.25, 1.4375, 2.625, 3.8125, 5.0];
/// F^inf at the knots, N.
pub const BACKBONE_F_N: [f64; 9] = [-1012.8352780053801, -700.5943869411498, -404.94520349131136, -177.59262078838378, 47.50636666785073, 274.7942853052464, 530.0561887716597, 828.8556007557175, 1179.48835524978];
/// Maxwell cells: (corner Hz, fraction g).
pub const MAXWELL_HZ_G: [(f64, f64); 3] = [(0.48824973972737973, 0.09644881736588207), (4.783789148367207, 0.12004500443457215), (47.30135124273672, 0.08253330228893181)];

/// The Maxwell cells as the core's specs.
pub fn maxwell_cells() -> [MaxwellSpec; 3] {
    MAXWELL_HZ_G.map(|(f, g)| MaxwellSpec::hz(f, g))
}

/// Jenkins cells: (fraction g, slip force N).
pub const IWAN_G_SLIP_N: [(f64, f64); 4] = [(0.05057473717174214, 0.669644854515071), (0.05041804875112943, 2.8196107751159953), (0.06201441797611442, 9.315280727334654), (0.059105681919097076, 23.067571621931357)];

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
