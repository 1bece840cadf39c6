//! The viscous dashpot F = c ẋ (seed 000 §5.2.2 (a), the "viscous" mount),
//! backward difference of the step: `type = "dashpot"`.
//!
//! ```toml
//! [[effects]]
//! type = "dashpot"
//! c = 0.5        # N·s/mm
//! ```

use std::f64::consts::{PI, TAU};

use bushing::{Dashpot, ParamError, Real};
use serde::Deserialize;

use crate::reference::{Drive, Line, Measured, compared, no};

/// `[[effects]] type = "dashpot"`, as written and as checked.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DashpotTable {
    /// Coefficient c in N·s/mm.
    pub c: f64,
}

impl DashpotTable {
    /// The dashpot in `T` at time step `dt` (the core's checks of c and
    /// of c/dt in `T`).
    pub fn build<T: Real>(&self, dt: f64) -> Result<Dashpot<T>, ParamError> {
        Dashpot::new(self.c, dt)
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        format!("dashpot c={}", self.c)
    }

    /// Under a sine: the first harmonic against the discrete response
    /// `(c/Δt)(1 - e^{-iθ})`, θ = ω Δt (storage `(c/Δt)(1 - cos θ)` on top of
    /// the linear backbone K, loss `(c/Δt) sin θ`), the loss against the
    /// continuous `c ω`, and the energy per cycle against the discrete
    /// `(4π/θ)(c/Δt) X² sin²(θ/2)`. Under a triangle of speed v: the
    /// force `c v` and the energy per cycle `4 c v A`.
    pub(super) fn references(&self, m: &Measured) -> Vec<Line> {
        let gain = self.c / m.dt;
        match m.drive {
            Drive::Triangle(v) => vec![
                compared("half peak-to-peak force, c v", "N", self.c * v, m.swing),
                compared(
                    "energy per steady cycle, 4 c v A",
                    "mJ",
                    4.0 * self.c * v * m.amplitude,
                    m.per_cycle,
                ),
            ],
            Drive::Sine(f) => {
                let Some(k) = m.k_lin else {
                    return no("the complex modulus needs a sine on a linear backbone");
                };
                let Some((storage, loss)) = m.modulus else {
                    return no("the least-squares fit is singular");
                };
                let theta = TAU * f * m.dt;
                let x = m.x_amplitude;
                let half = (0.5 * theta).sin();
                vec![
                    compared(
                        "storage K' of g0 K x + dashpot force vs the backward difference's exact response",
                        "N/mm",
                        k * m.g0 + gain * (1.0 - theta.cos()),
                        storage,
                    ),
                    compared(
                        "loss K'' vs the backward difference's exact response",
                        "N/mm",
                        gain * theta.sin(),
                        loss,
                    ),
                    compared(
                        "loss K'' vs c omega (continuous)",
                        "N/mm",
                        self.c * TAU * f,
                        loss,
                    ),
                    compared(
                        "energy per steady cycle vs the backward difference's (4 pi / theta)(c/dt) X^2 sin^2(theta/2)",
                        "mJ",
                        4.0 * PI / theta * gain * x * x * half * half,
                        m.per_cycle,
                    ),
                ]
            }
        }
    }
}
