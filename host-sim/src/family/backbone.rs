//! The backbone family: its `[backbone]` table and its build, for the
//! scene reader, the run, the references and the cost cases alike.

use bushing::{Backbone, Bushing, MonotoneSpline, ParamError, Polynomial, Real};
use serde::Deserialize;

tagged_table! {
    /// `[backbone]`: F^∞(x) in N for x in mm.
    #[derive(Debug, Clone, PartialEq, Deserialize)]
    pub enum BackboneSpec, read by tag as BackboneByTag("BackboneSpec") {
        /// F = c0 + c1 x + c2 x^2 + ... on `range`, linear outside.
        Polynomial {
            /// Coefficients c0, c1, ... (N/mm^k), at most 8.
            coefficients: Vec<f64>,
            /// Validity range [lo, hi] in mm.
            range: [f64; 2],
        },
        /// Monotone cubic spline through measured points, linear outside.
        Spline {
            /// Displacements in mm, increasing.
            x: Vec<f64>,
            /// Forces in N, increasing.
            force: Vec<f64>,
        },
    }
}

/// Most polynomial coefficients a scene may give.
pub const MAX_COEFFICIENTS: usize = 8;
/// Most spline points a scene may give.
pub const MAX_POINTS: usize = 256;

/// A backbone chosen at run time.
#[derive(Debug, Clone)]
pub enum AnyBackbone<T> {
    /// Polynomial.
    Polynomial(Polynomial<T, MAX_COEFFICIENTS>),
    /// Monotone spline.
    Spline(Box<MonotoneSpline<T, MAX_POINTS>>),
}

impl<T: Real> Backbone<T> for AnyBackbone<T> {
    #[inline]
    fn eval(&self, x: T) -> (T, T) {
        match self {
            Self::Polynomial(p) => p.eval(x),
            Self::Spline(s) => s.eval(x),
        }
    }
}

/// Builds the backbone of a scene.
pub fn backbone<T: Real>(spec: &BackboneSpec) -> Result<AnyBackbone<T>, ParamError> {
    let b = match spec {
        BackboneSpec::Polynomial {
            coefficients,
            range,
        } => AnyBackbone::Polynomial(Polynomial::new(coefficients, (range[0], range[1]))?),
        BackboneSpec::Spline { x, force } => {
            AnyBackbone::Spline(Box::new(MonotoneSpline::new(x, force)?))
        }
    };
    // What a bushing asks of its backbone (its rest point within the
    // guard), checked where the scene is read rather than when it is built.
    Bushing::new(b.clone(), ())?;
    Ok(b)
}
