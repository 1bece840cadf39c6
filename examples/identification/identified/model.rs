// Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
// the parameters of `model.toml` as constructor calls of the `bushing`
// crate. Units: mm, N, s; corners in Hz.

use bushing::{Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline, ParamError, Real};

/// Backbone knots, mm.
pub const BACKBONE_X_MM: [f64; 9] = [-4.5, -3.3125, -2.125, -0.9375, 0.25, 1.4375, 2.625, 3.8125, 5.0];
/// F^inf at the knots, N.
pub const BACKBONE_F_N: [f64; 9] = [-1029.2511086132772, -700.2375212162698, -415.5770527240492, -178.9189536628228, 47.62741152599385, 276.13114948765696, 532.2686197082826, 832.3879174128308, 1184.392255397598];
/// Maxwell cells: (corner Hz, fraction g).
pub const MAXWELL_HZ_G: [(f64, f64); 3] = [(0.4785375600856795, 0.09577533535552477), (4.761841342116405, 0.11951036819240136), (46.45072074048186, 0.08099981832813533)];

/// The Maxwell cells as the core's specs.
pub fn maxwell_cells() -> [MaxwellSpec; 3] {
    MAXWELL_HZ_G.map(|(f, g)| MaxwellSpec::hz(f, g))
}

/// Jenkins cells: (fraction g, slip force N).
pub const IWAN_G_SLIP_N: [(f64, f64); 4] = [(0.04315693148789261, 0.40460127583454525), (0.058245663588469956, 2.5718913660869736), (0.06618313473542073, 9.747547971288865), (0.05919732841830042, 23.068846406179773)];

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
