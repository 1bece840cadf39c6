//! The nonlinear viscous x_f cell: the transition between viscoelasticity
//! and rate-independent hysteresis (seed 000 §1.5.2).
//!
//! A Maxwell cell whose relaxation frequency grows with the speed,
//! `ω̂ = ω + |ẋ| / x_f`, eq 1.52 in force-rate form (eq 1.49 and the 3D
//! eq 2.39 drive it with Ḟ^∞, which a nonlinear backbone needs):
//!
//! ```text
//! Ḟ^i + (ω_i + |ẋ| / x_f^i) F^i = g_i Ḟ^∞
//! ```
//!
//! At low speed and amplitude it is a Maxwell cell; in steady sliding
//! (ω → 0) its force saturates at the friction level `F_s = g_i K^∞ x_f^i`
//! (eq 1.50-1.51), so it is also the Dahl cell of exponent 1 and a Bouc-Wen
//! cell with n = 1. Over a step the exponent is `y = ω dt + |Δx| / x_f`,
//! which depends on the motion, so the decay is formed at run time
//! (`expm1`, about 40 guest instructions per cell on a Cortex-M4F).
//!
//! Two forms:
//!
//! - [`XfForm::Midpoint`], the thesis's recursion (eq 2.41 in 0D):
//!   `F_n = e^-y F_{n-1} + g e^(-y/2) ΔF^∞`. Under repeated equal steps with
//!   ω = 0 it settles on `F_s a / (2 sinh(a/2))`, a = |Δx| / x_f: it
//!   under-saturates, by 4 % at a = 1 and 59 % at a = 5
//!   (`docs/xf-saturation.md`). Steps must stay much smaller than x_f.
//! - [`XfForm::ExactRamp`], the exponential integrator exact when F^∞ and
//!   |x| are linear in time over the step:
//!   `F_n = e^-y F_{n-1} + g (1 - e^-y)/y ΔF^∞`. In steady sliding on a
//!   linear backbone it saturates at `g K^∞ x_f` exactly, whatever the
//!   step. It divides by y once per cell per step (y > 0 guarded: at y = 0
//!   the factor is its limit 1), the one division by data of the core.
//!
//! - **States**: one force per cell; the bushing keeps x_{n-1} and F^∞_{n-1}.
//! - **Stability**: both forms have the pole e^-y in (0, 1] for every step
//!   and speed; the force stays within the high-pass bound
//!   2 g max|F^∞| for any input.
//! - **Dissipation**: `ω̂ F² / (g K^∞)`, trapezoid over the step
//!   (`y (F_{n-1}² + F_n²) / (2 g K^∞)`), never negative.
//! - **Cost**: per cell one `expm1` plus about 8 multiply-adds (exact ramp
//!   adds one division); the energy adds 3 and one division per bank.

use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, positive, scaled};
use crate::real::Real;

/// Discrete form of an x_f cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize, serde::Serialize),
    serde(rename_all = "kebab-case")
)]
pub enum XfForm {
    /// Eq 2.41: e^(-y/2) on the increment.
    Midpoint,
    /// Exact for a ramp: (1 - e^-y)/y on the increment.
    ExactRamp,
}

impl XfForm {
    /// Both forms.
    pub const ALL: [Self; 2] = [Self::Midpoint, Self::ExactRamp];

    /// Name used in scene files and reports.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Midpoint => "midpoint",
            Self::ExactRamp => "exact-ramp",
        }
    }

    /// Parses a name written by [`XfForm::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// Parameters of one x_f cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XfSpec {
    /// Viscous relaxation frequency ω_i in rad/s (0 for a rate-independent
    /// cell).
    pub omega: f64,
    /// Load fraction g_i.
    pub g: f64,
    /// Hysteretic relaxation distance x_f^i, mm (the unit of x).
    pub x_f: f64,
}

impl XfSpec {
    /// A cell of relaxation frequency `f_hz` (Hz), fraction `g` and
    /// distance `x_f`.
    pub fn hz(f_hz: f64, g: f64, x_f: f64) -> Self {
        Self {
            omega: core::f64::consts::TAU * f_hz,
            g,
            x_f,
        }
    }
}

/// Coefficients of one x_f cell.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct XfCell<T> {
    h: T,
    inv_xf: T,
    g: T,
    inv_g: T,
}

impl<T: Real> XfCell<T> {
    /// Coefficients of cell `index` at time step `dt`.
    pub fn new(spec: XfSpec, dt: f64, index: usize) -> Result<Self, ParamError> {
        let dt = positive(Param::scalar("dt"), dt)?;
        if !(spec.omega.is_finite() && spec.omega >= 0.0) {
            return Err(ParamError::NotPositive {
                param: Param::item("omega", index),
                value: spec.omega,
            });
        }
        let g = scaled::<T>(Param::item("g", index), spec.g)?;
        if g > 1.0 {
            return Err(ParamError::CellFractionAboveOne {
                cell: Some(index),
                g,
            });
        }
        let x_f = scaled::<T>(Param::item("x_f", index), spec.x_f)?;
        // ω·dt must fit the working type (below its guard).
        let h = spec.omega * dt;
        let max = T::GUARD.to_f64();
        if h > max {
            return Err(ParamError::OutOfRange {
                param: Param::item("omega dt", index),
                value: h,
                min: 0.0,
                min_open: false,
                max,
            });
        }
        Ok(Self {
            h: T::from_f64(h),
            inv_xf: T::from_f64(1.0 / x_f),
            g: T::from_f64(g),
            inv_g: T::from_f64(1.0 / g),
        })
    }
}

/// Advances x_f cells by one step (the one implementation, used by
/// [`XfBank`] and by run-time sized banks).
#[inline(always)]
pub fn step_xf<T: Real>(
    form: XfForm,
    cells: &[XfCell<T>],
    forces: &mut [T],
    drive: &Drive<T>,
) -> EffectOutput<T> {
    let adx = drive.dx.abs();
    let s = if drive.dx > T::ZERO {
        T::ONE
    } else if drive.dx < T::ZERO {
        -T::ONE
    } else {
        T::ZERO
    };
    let df = drive.df_inf;
    let mut force = T::ZERO;
    let mut dforce = T::ZERO;
    let mut squares = T::ZERO;
    for (c, f) in cells.iter().zip(forces.iter_mut()) {
        let old = *f;
        let y = c.h + adx * c.inv_xf;
        // new = old - d old + gain ΔF^inf; ∂new/∂y for the tangent.
        let (d, gain, dnew_dy) = match form {
            XfForm::Midpoint => {
                let m = (-T::HALF * y).exp_m1(); // e^(-y/2) - 1
                let half = T::ONE + m;
                let d = -m * (T::ONE + half); // 1 - e^-y
                let gain = c.g * half;
                (d, gain, -(half * half) * old - T::HALF * gain * df)
            }
            XfForm::ExactRamp => {
                let d = -(-y).exp_m1(); // 1 - e^-y
                let e = T::ONE - d;
                let (phi, dphi) = if y > T::ZERO {
                    let phi = d / y;
                    (phi, (e - phi) / y)
                } else {
                    (T::ONE, -T::HALF)
                };
                let gain = c.g * phi;
                (d, gain, -e * old + c.g * df * dphi)
            }
        };
        let new = old - d * old + gain * df;
        *f = new;
        force += new;
        dforce += gain * drive.k_inf + s * c.inv_xf * dnew_dy;
        squares += y * c.inv_g * (old * old + new * new);
    }
    EffectOutput {
        force,
        tangent: dforce,
        dissipated: T::HALF * squares / drive.k_inf,
    }
}

/// A bank of `N` x_f cells in one form (see the module docs for equations,
/// limits and cost).
///
/// ```
/// use bushing::{Bushing, ParamError, Polynomial, XfBank, XfForm, XfSpec};
///
/// // One x_f cell: 1 Hz viscous relaxation, 20 %, x_f = 0.5 mm, at 1 kHz.
/// let cells = [XfSpec::hz(1.0, 0.2, 0.5)];
/// let bank = XfBank::<f32, 1>::new(XfForm::ExactRamp, &cells, 1e-3)?;
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (bank,))?;
/// let mut state = bushing.state_at(0.0);
/// let out = bushing.step(&mut state, 0.2);
/// assert!(out.force > 16.0 && out.force < 20.0 && out.dissipated >= 0.0);
/// // x_f must be positive.
/// let r = XfBank::<f32, 1>::new(XfForm::ExactRamp, &[XfSpec::hz(1.0, 0.2, 0.0)], 1e-3);
/// assert!(r.is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct XfBank<T, const N: usize> {
    form: XfForm,
    cells: [XfCell<T>; N],
    fraction: f64,
    dt: f64,
}

impl<T: Real, const N: usize> XfBank<T, N> {
    /// Builds the bank for time step `dt`.
    pub fn new(form: XfForm, specs: &[XfSpec; N], dt: f64) -> Result<Self, ParamError> {
        let mut cells = [XfCell::default(); N];
        let mut fraction = 0.0;
        for (i, (c, s)) in cells.iter_mut().zip(specs).enumerate() {
            *c = XfCell::new(*s, dt, i)?;
            fraction += s.g;
        }
        if fraction > 1.0 + 1e-12 {
            return Err(ParamError::FractionsAboveOne { sum: fraction });
        }
        Ok(Self {
            form,
            cells,
            fraction,
            dt,
        })
    }
}

impl<T: Real, const N: usize> Effect<T> for XfBank<T, N> {
    type State = [T; N];
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        self.fraction
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self, _: T) -> [T; N] {
        [T::ZERO; N]
    }
    #[inline(always)]
    fn step(&self, state: &mut [T; N], drive: &Drive<T>) -> EffectOutput<T> {
        step_xf(self.form, &self.cells, state, drive)
    }
    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

/// Force the midpoint form settles on, relative to `g K^∞ x_f`, under
/// repeated equal steps a = |Δx| / x_f with ω = 0: `a / (2 sinh(a/2))`.
pub fn midpoint_saturation_ratio(a: f64) -> f64 {
    if a == 0.0 {
        1.0
    } else {
        0.5 * a / libm::sinh(0.5 * a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backbone::Polynomial;
    use crate::bushing::Bushing;

    /// Steady sliding with equal steps a x_f on K^inf = 10, g = 0.5, x_f = 0.2.
    fn settle(form: XfForm, a: f64, omega: f64) -> f64 {
        let (g, k, x_f) = (0.5, 10.0, 0.2);
        let bank = XfBank::<f64, 1>::new(form, &[XfSpec { omega, g, x_f }], 1e-3).unwrap();
        let b = Bushing::new(Polynomial::<f64, 2>::linear(k).unwrap(), (bank,)).unwrap();
        let mut s = b.state_at(0.0);
        let steps = ((40.0 / a).ceil() as usize).max(40);
        let mut f = 0.0;
        for n in 1..=steps {
            f = b.step(&mut s, n as f64 * a * x_f).effects.unwrap().0.force;
        }
        f / (g * k * x_f)
    }

    #[test]
    fn exact_ramp_saturates_at_g_k_x_f_for_any_step() {
        for a in [1e-3, 0.01, 0.1, 1.0, 3.7, 10.0, 100.0, 1e4] {
            let r = settle(XfForm::ExactRamp, a, 0.0);
            assert!((r - 1.0).abs() < 1e-6, "a = {a}: {r}");
        }
    }

    #[test]
    fn midpoint_under_saturates_by_a_over_2_sinh_half_a() {
        for a in [0.01, 0.5, 1.0, 2.0, 3.7, 5.0] {
            let r = settle(XfForm::Midpoint, a, 0.0);
            assert!(
                (r - midpoint_saturation_ratio(a)).abs() < 1e-9,
                "a = {a}: {r}"
            );
        }
        assert!((midpoint_saturation_ratio(1.0) - 0.9595).abs() < 1e-4);
        assert!((midpoint_saturation_ratio(5.0) - 0.4132).abs() < 1e-4);
    }

    #[test]
    fn with_viscosity_steady_sliding_settles_on_g_k_dx_over_y() {
        // y = omega dt + a: F* = g K dx / y exactly in the exact-ramp form.
        let omega = 200.0;
        let a = 0.05;
        let r = settle(XfForm::ExactRamp, a, omega);
        let y = omega * 1e-3 + a;
        assert!((r - a / y).abs() < 1e-9, "{r} vs {}", a / y);
    }

    #[test]
    fn steady_loop_matches_the_closed_form_of_the_exact_update() {
        // omega = 0, g K = 1 N/mm, triangle of amplitude 1 mm: peak force
        // F_s tanh(1/x_f) and loop energy 4 F_s - 2 (F_s + F_p) x_f (1 - e^(-2/x_f)).
        for (x_f, f_p, w) in [
            (0.5, 0.48201, 1.03597),
            (1.0, 0.76159, 0.95362),
            (3.0, 0.96454, 0.42554),
        ] {
            let bank = XfBank::<f64, 1>::new(
                XfForm::ExactRamp,
                &[XfSpec {
                    omega: 0.0,
                    g: 0.5,
                    x_f,
                }],
                1e-3,
            )
            .unwrap();
            let b = Bushing::new(Polynomial::<f64, 2>::linear(2.0).unwrap(), (bank,)).unwrap();
            let mut s = b.state_at(0.0);
            let n = 4000;
            let (mut peak, mut energy) = (0.0f64, 0.0);
            for k in 0..20 * n {
                let u = (k % n) as f64 / n as f64;
                let x = if u < 0.25 {
                    4.0 * u
                } else if u < 0.75 {
                    2.0 - 4.0 * u
                } else {
                    4.0 * u - 4.0
                };
                let out = b.step(&mut s, x);
                assert!(out.dissipated >= 0.0);
                if k >= 19 * n {
                    peak = peak.max(out.effects.unwrap().0.force);
                    energy += out.dissipated;
                }
            }
            assert!((peak - f_p).abs() < 1e-4, "x_f = {x_f}: peak {peak}");
            assert!(
                (energy - w).abs() < 1e-4 * w.max(1.0),
                "x_f = {x_f}: energy {energy}"
            );
        }
    }

    #[test]
    fn tangent_matches_central_difference() {
        let specs = [
            XfSpec::hz(0.005, 0.3, 0.02),
            XfSpec::hz(5.0, 0.2, 0.002),
            XfSpec::hz(50.0, 0.1, 0.5),
        ];
        for form in XfForm::ALL {
            let bank = XfBank::<f64, 3>::new(form, &specs, 1e-3).unwrap();
            let bb = Polynomial::<f64, 4>::new(&[0.0, 100.0, 2.0, 5.0], (-5.0, 5.0)).unwrap();
            let b = Bushing::new(bb, (bank,)).unwrap();
            let mut s = b.state_at(0.0);
            let mut worst = 0.0f64;
            for n in 1..600 {
                let x = 0.8 * libm::sin(n as f64 * 0.03) + 0.1;
                let (out, _) = b.trial(&s, x);
                let e = 1e-7;
                let fd = (b.trial(&s, x + e).0.force - b.trial(&s, x - e).0.force) / (2.0 * e);
                worst = worst.max((out.tangent - fd).abs() / out.tangent.abs());
                b.step(&mut s, x);
            }
            assert!(worst < 1e-6, "{form:?}: {worst}");
        }
    }

    #[test]
    fn parameter_errors() {
        let ok = XfSpec {
            omega: 0.0,
            g: 0.1,
            x_f: 0.1,
        };
        assert!(XfBank::<f64, 1>::new(XfForm::ExactRamp, &[ok], 1e-3).is_ok());
        assert_eq!(
            XfBank::<f64, 1>::new(XfForm::ExactRamp, &[XfSpec { x_f: 0.0, ..ok }], 1e-3),
            Err(ParamError::NotPositive {
                param: Param::item("x_f", 0),
                value: 0.0
            })
        );
        assert!(matches!(
            XfBank::<f64, 1>::new(XfForm::Midpoint, &[XfSpec { omega: -1.0, ..ok }], 1e-3),
            Err(ParamError::NotPositive { .. })
        ));
        assert_eq!(
            XfBank::<f64, 2>::new(XfForm::Midpoint, &[ok, XfSpec { g: 1.2, ..ok }], 1e-3),
            Err(ParamError::CellFractionAboveOne {
                cell: Some(1),
                g: 1.2
            })
        );
    }
}
