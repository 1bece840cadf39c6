//! Banks of nonlinear viscous x_f cells (seed 000 eq 1.52, eq 2.41):
//! `type = "xf"`.
//!
//! ```toml
//! [[effects]]
//! type = "xf"
//! form = "midpoint"          # midpoint (eq 2.41) or exact-ramp
//! cells = [{ f_hz = 0.0, g = 0.1, x_f = 0.05 }]
//! ```
//!
//! The table is read straight into the core's `XfForm` and `XfSpec`.

use bushing::xf::{self, XfCell};
use bushing::{ParamError, Real, XfForm, XfSpec};
use serde::Deserialize;

use super::{DynBank, check_count};
use crate::reference::{Drive, Line, Measured, compared, no};

/// `[[effects]] type = "xf"`, as written and as checked.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Xf {
    /// Discrete form.
    pub form: XfForm,
    /// The cells: relaxation frequency `f_hz` (0: rate independent), load
    /// fraction `g`, hysteretic relaxation distance `x_f` in mm.
    pub cells: Vec<XfSpec>,
}

/// x_f bank sized at run time (the core's slice kernel).
pub type DynXf<T> = DynBank<T, XfCell<T>>;

impl Xf {
    /// The number of cells.
    pub(super) fn check(self) -> Result<Self, String> {
        check_count(self.cells.len())?;
        Ok(self)
    }

    /// The bank in `T` at time step `dt`.
    pub fn build<T: Real>(&self, dt: f64) -> Result<DynXf<T>, ParamError> {
        Ok(DynBank {
            cells: self
                .cells
                .iter()
                .enumerate()
                .map(|(i, s)| XfCell::new(*s, dt, i))
                .collect::<Result<_, _>>()?,
            kernel: match self.form {
                XfForm::Midpoint => |c, s, d| xf::step_xf(XfForm::Midpoint, c, s, d),
                XfForm::ExactRamp => |c, s, d| xf::step_xf(XfForm::ExactRamp, c, s, d),
            },
            rest_at_x0: false,
            fraction: self.cells.iter().map(|s| s.g).sum(),
            dt: Some(dt),
        })
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        format!("xf {} x{}", self.form.name(), self.cells.len())
    }

    /// On a linear backbone K, under a triangle or a sine with every ω = 0:
    /// each cell is Dahl's law of exponent 1 in x with `λ = ω/v + 1/x_f`,
    /// so the loop tip is `Σ g K tanh(λ A) / λ`.
    pub(super) fn references(&self, m: &Measured) -> Vec<Line> {
        let Some(k) = m.k_lin else {
            return no("the x_f saturation g K x_f needs a linear backbone");
        };
        let speed = match m.drive {
            Drive::Triangle(v) => Some(v),
            Drive::Sine(_) => None,
        };
        if speed.is_none() && self.cells.iter().any(|c| c.omega > 0.0) {
            return no("x_f cells with omega > 0 relax at a varying rate under a sine");
        }
        let mut tip = 0.0;
        let mut saturation = 0.0;
        for c in &self.cells {
            let lambda = speed.map_or(0.0, |v| c.omega / v) + 1.0 / c.x_f;
            saturation += c.g * k / lambda;
            tip += c.g * k / lambda * (lambda * m.amplitude).tanh();
        }
        vec![compared(
            format!(
                "half peak-to-peak force; saturation sum g K x_f v/(v + omega x_f) = {saturation:.6e} N, loop tip sum g K tanh(lambda A)/lambda"
            ),
            "N",
            tip,
            m.swing,
        )]
    }
}
