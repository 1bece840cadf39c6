//! The model class an identification fits, a model of that class
//! ([`Candidate`]) and the parameter vector the refinement moves.
//!
//! The force is seed 000 eq 1.9, `F = g⁰ F^∞(x) + Σ F^e`, with
//! `g⁰ = 1 - Σ g` over every cell:
//!
//! - **backbone** F^∞: a monotone spline on fixed knots (the parameters
//!   are the force at one knot, the *anchor*, and the logarithms of the
//!   rises between knots, each rise moving the knots beyond it away from
//!   the anchor, so every candidate increases) or a polynomial (its
//!   coefficients, scaled by the force and displacement ranges);
//! - **Maxwell cells** (eq 1.8, rate-exact-ramp form): ln ω and ln g each;
//! - **hysteresis**: an Iwan bank of Jenkins cells in clamp form (eq 1.32:
//!   ln g and ln of the slip force each), or the continuous STS law on a
//!   turning-point stack (eq 1.42: ln C and ln K_1), or none;
//! - **x_f cells** (eq 1.36, exact-ramp form), any number (the seed's
//!   materials have two with g > 0, Table 3.1): ln ω, ln g and ln x_f
//!   each.
//!
//! Logarithms keep every frequency, fraction, force and distance positive
//! whatever step the optimiser takes; a candidate whose fractions sum
//! past 1 is refused by the core's constructors and scored as a failure.

use std::f64::consts::TAU;

use bushing::{FirstLoading, IwanCellSpec, MaxwellForm, MaxwellSpec, XfForm, XfSpec};

use super::replay::Model;
use crate::family::Effect;
use crate::family::backbone::BackboneSpec;
use crate::family::iwan::{Iwan, IwanForm};
use crate::family::maxwell::{Maxwell, Storage};
use crate::family::turning_points::{Law, Stack};
use crate::family::xf::Xf;

/// The backbone's form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BackboneForm {
    /// A monotone cubic spline through knots.
    Spline,
    /// A polynomial, linear outside its range.
    Polynomial,
}

/// The hysteretic part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum HysteresisForm {
    /// An Iwan bank of Jenkins cells (clamp form, eq 1.32).
    Iwan,
    /// The continuous STS law on a turning-point stack (eq 1.42).
    Sts,
    /// No hysteresis.
    None,
}

/// What to identify.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModelClass {
    /// Backbone form.
    pub backbone: BackboneForm,
    /// Spline knots, or the polynomial's degree.
    pub backbone_size: usize,
    /// Maxwell cells (0: none).
    pub maxwell_cells: usize,
    /// Hysteresis form.
    pub hysteresis: HysteresisForm,
    /// Jenkins cells of the Iwan bank.
    pub jenkins_cells: usize,
    /// x_f cells (0: none).
    pub xf_cells: usize,
}

impl Default for ModelClass {
    /// A 9-knot spline, 3 Maxwell cells and 4 Jenkins cells, no x_f cell.
    fn default() -> Self {
        Self {
            backbone: BackboneForm::Spline,
            backbone_size: 9,
            maxwell_cells: 3,
            hysteresis: HysteresisForm::Iwan,
            jenkins_cells: 4,
            xf_cells: 0,
        }
    }
}

/// A model of the class.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// F^∞ (a spline or a polynomial).
    pub backbone: BackboneSpec,
    /// Maxwell cells.
    pub maxwell: Vec<MaxwellSpec>,
    /// Jenkins cells (slip forces in N).
    pub jenkins: Vec<IwanCellSpec>,
    /// STS law `(C N²/mm, K_1 N/mm)`.
    pub sts: Option<(f64, f64)>,
    /// The x_f cells.
    pub xf: Vec<XfSpec>,
    /// The spline knot whose force is a parameter of the vector; the
    /// rises are taken outward from it (unused for a polynomial).
    pub anchor: usize,
}

/// What a parameter is, for the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Its name, e.g. `maxwell[1].f_hz`.
    pub name: String,
    /// Its unit.
    pub unit: &'static str,
    /// Its value in that unit.
    pub value: f64,
    /// Whether the vector holds its logarithm (else a scaled value).
    pub log: bool,
}

impl Candidate {
    /// The model to replay and to write.
    pub fn model(&self) -> Model {
        let mut effects = Vec::new();
        if !self.maxwell.is_empty() {
            effects.push(Effect::Maxwell(Maxwell {
                form: MaxwellForm::RateExactRamp,
                state: Storage::Plain,
                cells: self.maxwell.clone(),
            }));
        }
        if !self.jenkins.is_empty() {
            effects.push(Effect::Iwan(Iwan {
                form: IwanForm::Clamp,
                k_ref: self.k_at_rest(),
                cells: self.jenkins.clone(),
            }));
        }
        if let Some((c, k1)) = self.sts {
            effects.push(Effect::TurningPoints(Stack {
                law: Law::Sts { c, k1 },
                first_loading: FirstLoading::Masing,
            }));
        }
        if !self.xf.is_empty() {
            effects.push(Effect::Xf(Xf {
                form: XfForm::ExactRamp,
                cells: self.xf.clone(),
            }));
        }
        Model {
            backbone: self.backbone.clone(),
            effects,
        }
    }

    /// The tangent of F^∞ at 0, N/mm (the reference of slip distances).
    pub fn k_at_rest(&self) -> f64 {
        crate::family::backbone::backbone::<f64>(&self.backbone)
            .map(|b| bushing::Backbone::eval(&b, 0.0).1)
            .unwrap_or(f64::NAN)
    }

    /// The long-term fraction g⁰ = 1 - Σ g.
    pub fn g0(&self) -> f64 {
        1.0 - self.maxwell.iter().map(|c| c.g).sum::<f64>()
            - self.jenkins.iter().map(|c| c.g).sum::<f64>()
            - self.xf.iter().map(|c| c.g).sum::<f64>()
    }

    /// The parameters, in the order of [`Candidate::vector`].
    pub fn params(&self) -> Vec<Param> {
        let mut out = Vec::new();
        let mut p = |name: String, unit, value, log| {
            out.push(Param {
                name,
                unit,
                value,
                log,
            })
        };
        match &self.backbone {
            BackboneSpec::Spline { x, force } => {
                let a = self.anchor.min(x.len().saturating_sub(1));
                p(format!("backbone F at {} mm", x[a]), "N", force[a], false);
                for k in 1..x.len() {
                    p(
                        format!("backbone rise {} to {} mm", x[k - 1], x[k]),
                        "N",
                        force[k] - force[k - 1],
                        true,
                    );
                }
            }
            BackboneSpec::Polynomial { coefficients, .. } => {
                for (k, &c) in coefficients.iter().enumerate() {
                    p(format!("backbone c{k}"), "N/mm^k", c, false);
                }
            }
        }
        for (i, c) in self.maxwell.iter().enumerate() {
            p(format!("maxwell[{i}].f_hz"), "Hz", c.omega / TAU, true);
            p(format!("maxwell[{i}].g"), "", c.g, true);
        }
        for (j, c) in self.jenkins.iter().enumerate() {
            p(format!("iwan[{j}].g"), "", c.g, true);
            p(format!("iwan[{j}].slip_force"), "N", c.slip_force, true);
        }
        if let Some((c, k1)) = self.sts {
            p("sts.c".into(), "N²/mm", c, true);
            p("sts.k1".into(), "N/mm", k1, true);
        }
        for (i, c) in self.xf.iter().enumerate() {
            p(format!("xf[{i}].f_hz"), "Hz", c.omega / TAU, true);
            p(format!("xf[{i}].g"), "", c.g, true);
            p(format!("xf[{i}].x_f"), "mm", c.x_f, true);
        }
        out
    }

    /// The parameter vector: logarithms, and the linear values over their
    /// scale ([`Candidate::scales`]).
    pub fn vector(&self) -> Vec<f64> {
        let scales = self.scales();
        self.params()
            .iter()
            .zip(&scales)
            .map(|(p, s)| if p.log { p.value.ln() } else { p.value / s })
            .collect()
    }

    /// The scale each linear parameter is divided by in the vector (1 for
    /// the logarithms): the force range for the spline's anchor, and
    /// `F / X^k` for a polynomial's c_k.
    pub fn scales(&self) -> Vec<f64> {
        let params = self.params();
        let mut s = vec![1.0; params.len()];
        match &self.backbone {
            BackboneSpec::Spline { force, .. } => {
                s[0] = (force[force.len() - 1] - force[0]).abs().max(1e-9);
            }
            BackboneSpec::Polynomial {
                coefficients,
                range,
            } => {
                let x = range[0].abs().max(range[1].abs()).max(1e-9);
                let f = coefficients
                    .iter()
                    .enumerate()
                    .map(|(k, c)| (c * x.powi(k as i32)).abs())
                    .fold(1e-9, f64::max);
                for (k, v) in s.iter_mut().take(coefficients.len()).enumerate() {
                    *v = f / x.powi(k as i32);
                }
            }
        }
        s
    }

    /// The candidate of the same class and scales with the vector `v`
    /// (the scales are those of `self`).
    pub fn with_vector(&self, v: &[f64]) -> Self {
        let scales = self.scales();
        let params = self.params();
        let value = |i: usize| {
            let raw = v.get(i).copied().unwrap_or(f64::NAN);
            if params.get(i).is_some_and(|p| p.log) {
                raw.exp()
            } else {
                raw * scales.get(i).copied().unwrap_or(1.0)
            }
        };
        let mut i = 0;
        let mut next = || {
            i += 1;
            value(i - 1)
        };
        let backbone = match &self.backbone {
            BackboneSpec::Spline { x, .. } => {
                let a = self.anchor.min(x.len().saturating_sub(1));
                let mut force = vec![next(); x.len()];
                let rises: Vec<f64> = (1..x.len()).map(|_| next()).collect();
                for k in (0..a).rev() {
                    force[k] = force[k + 1] - rises[k];
                }
                for k in a + 1..x.len() {
                    force[k] = force[k - 1] + rises[k - 1];
                }
                BackboneSpec::Spline {
                    x: x.clone(),
                    force,
                }
            }
            BackboneSpec::Polynomial {
                coefficients,
                range,
            } => BackboneSpec::Polynomial {
                coefficients: coefficients.iter().map(|_| next()).collect(),
                range: *range,
            },
        };
        let maxwell = (0..self.maxwell.len())
            .map(|_| {
                let f = next();
                MaxwellSpec::hz(f, next())
            })
            .collect();
        let jenkins = (0..self.jenkins.len())
            .map(|_| {
                let g = next();
                IwanCellSpec::new(g, next())
            })
            .collect();
        let sts = self.sts.map(|_| {
            let c = next();
            (c, next())
        });
        let xf = (0..self.xf.len())
            .map(|_| {
                let f = next();
                let g = next();
                XfSpec::hz(f, g, next())
            })
            .collect();
        Self {
            backbone,
            maxwell,
            jenkins,
            sts,
            xf,
            anchor: self.anchor,
        }
    }

    /// The same model with the spline's level given at the knot nearest
    /// 0 mm, where the records about rest pin it.
    pub fn anchored_at_rest(&self) -> Self {
        let anchor = match &self.backbone {
            BackboneSpec::Spline { x, .. } => x
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                .map_or(0, |(k, _)| k),
            BackboneSpec::Polynomial { .. } => 0,
        };
        Self {
            anchor,
            ..self.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spline() -> Candidate {
        Candidate {
            backbone: BackboneSpec::Spline {
                x: vec![-2.0, -1.0, 0.25, 1.0, 2.0],
                force: vec![-300.0, -120.0, 30.0, 110.0, 260.0],
            },
            maxwell: vec![MaxwellSpec::hz(1.0, 0.2)],
            jenkins: Vec::new(),
            sts: None,
            xf: Vec::new(),
            anchor: 0,
        }
    }

    /// Either anchor reads the same model back from its vector, names its
    /// level at its own knot, and moves only the knots beyond a rise.
    #[test]
    fn a_spline_reads_back_from_either_anchor() {
        let first = spline();
        let rest = first.anchored_at_rest();
        assert_eq!(rest.anchor, 2);
        assert_eq!(first.params()[0].name, "backbone F at -2 mm");
        assert_eq!(rest.params()[0].name, "backbone F at 0.25 mm");
        for c in [&first, &rest] {
            let back = c.with_vector(&c.vector());
            let (BackboneSpec::Spline { force: a, .. }, BackboneSpec::Spline { force: b, .. }) =
                (&c.backbone, &back.backbone)
            else {
                panic!("not a spline");
            };
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() < 1e-9, "{x} read back as {y}");
            }
        }
        // The first rise (-2 to -1 mm) raised: with the level at rest only
        // the first knot moves, with the level at the first knot all the
        // others do.
        let mut v = rest.vector();
        v[1] += 0.1;
        let BackboneSpec::Spline { force, .. } = rest.with_vector(&v).backbone else {
            panic!("not a spline");
        };
        assert!((force[0] + 120.0 + 180.0 * 0.1f64.exp()).abs() < 1e-9);
        assert!(
            force[1..]
                .iter()
                .zip([-120.0, 30.0, 110.0, 260.0])
                .all(|(a, b)| (a - b).abs() < 1e-9)
        );
        let mut v = first.vector();
        v[1] += 0.1;
        let BackboneSpec::Spline { force, .. } = first.with_vector(&v).backbone else {
            panic!("not a spline");
        };
        assert!((force[0] + 300.0).abs() < 1e-9);
        assert!((force[4] - 260.0 - 180.0 * (0.1f64.exp() - 1.0)).abs() < 1e-9);
    }
}
