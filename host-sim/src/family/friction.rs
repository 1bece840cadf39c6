//! Single friction cells (seed 000 eqs 1.43-1.45): `type = "dahl"`,
//! `"bouc-wen"` and `"berg"`.
//!
//! ```toml
//! [[effects]]
//! type = "dahl"
//! k_d = 200.0    # N/mm
//! f_f = 10.0     # N
//! alpha = 1.0    # default 1
//! ```
//!
//! References: the tip of the steady symmetric loop of the continuous law
//! at the profile's amplitude (the laws never reach their saturation force
//! in a finite travel, except Dahl with α < 1), the saturation printed
//! beside it.

use bushing::{Berg, BoucWen, Dahl, ParamError, Real};
use serde::Deserialize;

use super::AnyEffect;
use crate::reference::{Line, Measured, bisect, compared, simpson};

/// Parameters of a Dahl cell.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DahlParams {
    /// Initial stiffness in N/mm.
    pub k_d: f64,
    /// Friction force in N.
    pub f_f: f64,
    /// Exponent (default 1).
    #[serde(default = "one")]
    pub alpha: f64,
}

fn one() -> f64 {
    1.0
}

/// Parameters of a Bouc-Wen cell.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoucWenParams {
    /// Force scale in N/mm.
    pub alpha: f64,
    /// A.
    pub a: f64,
    /// β.
    pub beta: f64,
    /// γ, with |γ| < β.
    pub gamma: f64,
    /// Exponent n.
    pub n: f64,
}

/// Parameters of a Berg cell.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BergParams {
    /// Largest friction force in N.
    pub f_max: f64,
    /// Displacement in mm at which half of it is reached from rest.
    pub x2: f64,
}

/// A single friction cell (parameters in f64; the model is built in the
/// run's number type).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Friction {
    /// Dahl (eq 1.43).
    Dahl(DahlParams),
    /// Bouc-Wen (eq 1.44).
    BoucWen(BoucWenParams),
    /// Berg (eq 1.45).
    Berg(BergParams),
}

impl Friction {
    /// The cell in `T`.
    pub fn build<T: Real>(&self) -> Result<AnyEffect<T>, ParamError> {
        Ok(match *self {
            Self::Dahl(p) => AnyEffect::Dahl(Dahl::new(p.k_d, p.f_f, p.alpha)?),
            Self::BoucWen(p) => {
                AnyEffect::BoucWen(BoucWen::new(p.alpha, p.a, p.beta, p.gamma, p.n)?)
            }
            Self::Berg(p) => AnyEffect::Berg(Berg::new(p.f_max, p.x2)?),
        })
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        match self {
            Self::Dahl(p) => format!("dahl alpha={}", p.alpha),
            Self::BoucWen(p) => format!("bouc-wen n={}", p.n),
            Self::Berg(_) => "berg".into(),
        }
    }

    /// The half peak-to-peak force against the tip of the steady loop.
    pub(super) fn references(&self, m: &Measured) -> Vec<Line> {
        let a = m.amplitude;
        let (what, tip) = match *self {
            Self::Dahl(d) => (
                format!(
                    "half peak-to-peak force; saturation f_f = {} N, loop tip of eq 1.43 over 2A",
                    d.f_f
                ),
                dahl_tip(d.k_d, d.f_f, d.alpha, a),
            ),
            Self::BoucWen(b) => {
                let ultimate = BoucWen::<f64>::new(b.alpha, b.a, b.beta, b.gamma, b.n)
                    .map(|c| c.ultimate_force())
                    .unwrap_or(f64::NAN);
                (
                    format!(
                        "half peak-to-peak force; ultimate force alpha w_u = {ultimate:.6e} N, loop tip of eq 1.44 over 2A"
                    ),
                    bouc_wen_tip(b.alpha, b.a, b.beta, b.gamma, b.n, a),
                )
            }
            Self::Berg(b) => {
                let (x2, fm) = (b.x2, b.f_max);
                (
                    format!(
                        "half peak-to-peak force; f_max = {fm} N, loop tip (x2/f_max) r^2 + (x2 + A) r = A f_max"
                    ),
                    (-(x2 + a) + ((x2 + a).powi(2) + 4.0 * x2 * a).sqrt()) / (2.0 * x2 / fm),
                )
            }
        };
        vec![compared(what, "N", tip, m.swing)]
    }
}

/// Tip r of the steady symmetric loop of Dahl's law (eq 1.43) between
/// ±A: the up stroke from -r travels 2A in u = 1 - F/f_f, exactly as the
/// law integrates (`u^(1-α)` linear in travel, `u e^{k_d ξ / f_f}` at α = 1).
fn dahl_tip(k_d: f64, f_f: f64, alpha: f64, a: f64) -> f64 {
    let travel = k_d * 2.0 * a / f_f;
    if alpha == 1.0 {
        return f_f * (0.5 * travel).tanh();
    }
    let end = |r: f64| {
        let u0 = 1.0 + r / f_f;
        let p = u0.powf(1.0 - alpha) - (1.0 - alpha) * travel;
        let u1 = if p <= 0.0 {
            0.0
        } else {
            p.powf(1.0 / (1.0 - alpha))
        };
        f_f * (1.0 - u1)
    };
    bisect(|r| end(r) - r, 0.0, f_f)
}

/// Tip of the steady symmetric loop of the Bouc-Wen law (eq 1.44): w = F/α
/// goes from -r to r over a travel 2A with `dw/dξ = A_bw - (γ + β sgn w)
/// |w|^n`. The travel is integrated by Simpson's rule, on `w = w_u (1 -
/// e^{-s})` above 0 where the rate vanishes at w_u.
fn bouc_wen_tip(alpha: f64, a_bw: f64, beta: f64, gamma: f64, n: f64, a: f64) -> f64 {
    let w_u = (a_bw / (beta + gamma)).powf(1.0 / n);
    let below = |r: f64| {
        simpson(
            |w: f64| 1.0 / (a_bw + (beta - gamma) * w.abs().powf(n)),
            -r,
            0.0,
            2000,
        )
    };
    // Above 0 in s: dw = w_u e^{-s} ds, A - (β+γ) w^n = A (1 - (1 - e^{-s})^n).
    let above = |s_end: f64| {
        simpson(
            |s: f64| {
                let e = (-s).exp();
                let gap = -(n * (-e).ln_1p()).exp_m1();
                if gap > 0.0 {
                    w_u * e / (a_bw * gap)
                } else {
                    w_u / (a_bw * n)
                }
            },
            0.0,
            s_end,
            4000,
        )
    };
    let r_of = |s: f64| w_u * -(-s).exp_m1();
    let travel = |s: f64| below(r_of(s)) + above(s);
    const S_MAX: f64 = 40.0;
    let s = if travel(S_MAX) < 2.0 * a {
        S_MAX
    } else {
        bisect(|s| 2.0 * a - travel(s), 0.0, S_MAX)
    };
    alpha * r_of(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loop_tips_of_the_friction_laws() {
        // Dahl α = 1 against its closed form; α = 1 through the general
        // branch (α slightly off) agrees.
        let t1 = dahl_tip(200.0, 10.0, 1.0, 0.03);
        assert!((t1 - 10.0 * (0.6f64).tanh()).abs() < 1e-12);
        let near = dahl_tip(200.0, 10.0, 1.0 + 1e-7, 0.03);
        assert!((near / t1 - 1.0).abs() < 1e-5, "{near} {t1}");
        // α < 1 saturates in a finite travel.
        assert!((dahl_tip(200.0, 10.0, 0.5, 1.0) / 10.0 - 1.0).abs() < 1e-12);
        // Bouc-Wen with n = 1 and γ = 0 is Dahl α = 1 in w: dw/dξ = A - β
        // |w| on both sides, tip w_u tanh(β A_amp).
        let tip = bouc_wen_tip(20.0, 10.0, 60.0, 0.0, 1.0, 0.01);
        let w_u = 10.0 / 60.0;
        let expect = 20.0 * w_u * (60.0f64 * 0.01).tanh();
        assert!((tip / expect - 1.0).abs() < 1e-6, "{tip} {expect}");
        // Far into saturation: the ultimate force.
        let u = bouc_wen_tip(20.0, 10.0, 60.0, 20.0, 8.0, 1.0);
        assert!((u / (20.0 * (0.125f64).powf(0.125)) - 1.0).abs() < 1e-12);
    }
}
