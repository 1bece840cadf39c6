//! Temperature: the time-temperature shift of the viscoelastic cells
//! (seed 000 §1.5.1, eqs 1.46-1.48).
//!
//! A thermorheologically simple rubber at temperature T behaves as at the
//! reference T_0 at a reduced frequency: `E(ω, T) = E(a_T ω, T_0)`
//! (eq 1.46). This crate uses the usual shift factor a_T: **a_T > 1 below
//! T_0** (the cold rubber is slower and stiffer), a_T(T_0) = 1, and the
//! relaxation frequencies move as
//!
//! ```text
//! ω_i(T) = ω_i(T_0) / a_T
//! ```
//!
//! so that `K(iω, T) = K(i a_T ω, T_0)` exactly for a Maxwell bank (eq 1.8).
//! The thesis writes eq 1.47 as `ω_i(T) = α(T) ω_i(T_0)`: its α(T) is the
//! reciprocal of the a_T of eq 1.46 (the two equations disagree; this crate
//! follows eq 1.46). Only the viscoelastic corners move (eq 1.48): the
//! backbone, the Iwan cells and the x_f distances are left as they are.
//!
//! The thesis gives no shift-factor law; the two classical ones are here:
//! Williams-Landel-Ferry, `log10 a_T = -C_1 (T - T_0) / (C_2 + T - T_0)`, and
//! Arrhenius, `ln a_T = (E_a / R) (1/T - 1/T_0)` (T in kelvin). A running
//! bank is re-tuned with [`crate::MaxwellBank::shifted`] (f64, exact) or
//! on line with [`crate::MaxwellBank::retune`] and [`ShiftFactor::at_in`]
//! (in the working type, with libm's or micromath's exponentials).

use crate::error::{Param, ParamError, finite, positive};
use crate::real::{Exponentials, LibmExp, Real};

/// A shift-factor law a_T (see the module docs for the direction).
///
/// ```
/// use bushing::temperature::ShiftFactor;
/// use bushing::{LibmExp, ParamError};
///
/// // WLF with the universal constants, referred to 20 °C.
/// let law = ShiftFactor::wlf(8.86, 101.6, 293.15)?;
/// assert_eq!(law.at(293.15)?, 1.0);
/// let warm = law.at(313.15)?; // 40 °C: faster relaxation
/// assert!(warm < 1.0);
/// // On line, in f32, with one exponential.
/// let a_t = law.at_in::<f32, LibmExp>(313.15)?;
/// assert!((f64::from(a_t) - warm).abs() < 1e-5 * warm);
/// // C_2 must be positive.
/// assert!(ShiftFactor::wlf(8.86, 0.0, 293.15).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShiftFactor {
    /// Williams-Landel-Ferry.
    Wlf {
        /// C_1 (dimensionless; 17.44 for the "universal" constants).
        c1: f64,
        /// C_2 in kelvin (51.6 for the "universal" constants).
        c2: f64,
        /// Reference temperature T_0 (°C or K, as T).
        t_ref: f64,
    },
    /// Arrhenius.
    Arrhenius {
        /// Activation energy over the gas constant, E_a / R, in kelvin.
        activation: f64,
        /// Reference temperature T_0 in kelvin.
        t_ref: f64,
    },
}

impl ShiftFactor {
    /// WLF law; refuses non-finite constants and C_2 <= 0.
    pub fn wlf(c1: f64, c2: f64, t_ref: f64) -> Result<Self, ParamError> {
        Ok(Self::Wlf {
            c1: finite(Param::scalar("c1"), c1)?,
            c2: positive(Param::scalar("c2"), c2)?,
            t_ref: finite(Param::scalar("t_ref"), t_ref)?,
        })
    }

    /// Arrhenius law; refuses a non-positive reference temperature (kelvin)
    /// and a non-finite activation.
    pub fn arrhenius(activation: f64, t_ref: f64) -> Result<Self, ParamError> {
        Ok(Self::Arrhenius {
            activation: finite(Param::scalar("activation"), activation)?,
            t_ref: positive(Param::scalar("t_ref"), t_ref)?,
        })
    }

    /// a_T at temperature `t`, in f64 with libm. Refuses temperatures where
    /// the law has no meaning (WLF at T - T_0 <= -C_2, Arrhenius at
    /// T <= 0 K) and shift factors that are not finite and positive in f64.
    pub fn at(&self, t: f64) -> Result<f64, ParamError> {
        self.at_in::<f64, LibmExp>(t)
    }

    /// a_T at temperature `t`, computed in the working type with the
    /// exponentials `E` (one exponential, two divisions): the on-line path
    /// beside [`crate::MaxwellBank::retune`]. WLF is evaluated as
    /// `exp(-ln 10 C_1 ΔT / (C_2 + ΔT))`, Arrhenius as
    /// `exp(E_a/R (T_0 - T) / (T T_0))` (no difference of reciprocals, which
    /// would cancel in f32). Same refusals as [`Self::at`], in the range of
    /// `T`.
    pub fn at_in<T: Real, E: Exponentials<T>>(&self, t: T) -> Result<T, ParamError> {
        let param = Param::scalar("temperature");
        if !t.is_finite() {
            return Err(ParamError::NotFinite { param });
        }
        let exponent = match *self {
            Self::Wlf { c1, c2, t_ref } => {
                let (c2_t, dt) = (T::from_f64(c2), t - T::from_f64(t_ref));
                if dt <= -c2_t {
                    return Err(ParamError::OutOfRange {
                        param,
                        value: t.to_f64(),
                        min: t_ref - c2,
                        min_open: true,
                        max: f64::INFINITY,
                    });
                }
                T::from_f64(-core::f64::consts::LN_10 * c1) * dt / (c2_t + dt)
            }
            Self::Arrhenius { activation, t_ref } => {
                if t <= T::ZERO {
                    return Err(ParamError::NotPositive {
                        param,
                        value: t.to_f64(),
                    });
                }
                let t_ref = T::from_f64(t_ref);
                T::from_f64(activation) * (t_ref - t) / (t * t_ref)
            }
        };
        let a = E::exp(exponent);
        if a.is_finite() && a > T::ZERO {
            Ok(a)
        } else {
            Err(ParamError::NotFinite {
                param: Param::scalar("a_t"),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accumulator::Plain;
    use crate::backbone::Polynomial;
    use crate::bushing::Bushing;
    use crate::maxwell::{MaxwellBank, MaxwellForm, MaxwellSpec};
    use core::f64::consts::TAU;

    #[test]
    fn wlf_and_arrhenius_values_and_direction() {
        let wlf = ShiftFactor::wlf(17.44, 51.6, 20.0).unwrap();
        assert_eq!(wlf.at(20.0).unwrap(), 1.0);
        let hot = wlf.at(30.0).unwrap();
        assert!((hot.log10() + 17.44 * 10.0 / 61.6).abs() < 1e-12);
        assert!(
            hot < 1.0 && wlf.at(0.0).unwrap() > 1.0,
            "cold is slow: a_T > 1"
        );
        let arr = ShiftFactor::arrhenius(8000.0, 293.15).unwrap();
        assert_eq!(arr.at(293.15).unwrap(), 1.0);
        let cold = arr.at(273.15).unwrap();
        assert!((cold.ln() - 8000.0 * (1.0 / 273.15 - 1.0 / 293.15)).abs() < 1e-12);
        assert!(cold > 1.0);
    }

    #[test]
    fn out_of_domain_temperatures_are_refused() {
        let wlf = ShiftFactor::wlf(17.44, 51.6, 20.0).unwrap();
        assert!(matches!(
            wlf.at(20.0 - 51.6),
            Err(ParamError::OutOfRange { min, .. }) if (min - (20.0 - 51.6)).abs() < 1e-12
        ));
        assert!(matches!(
            wlf.at(f64::NAN),
            Err(ParamError::NotFinite { .. })
        ));
        let arr = ShiftFactor::arrhenius(8000.0, 293.15).unwrap();
        assert!(matches!(arr.at(-5.0), Err(ParamError::NotPositive { .. })));
        // a_T overflowing f64 is refused, not returned as infinity.
        assert!(matches!(arr.at(1e-3), Err(ParamError::NotFinite { .. })));
        assert!(ShiftFactor::wlf(17.44, 0.0, 20.0).is_err());
        assert!(ShiftFactor::arrhenius(8000.0, 0.0).is_err());
    }

    #[test]
    fn working_type_shift_factors_follow_the_f64_law() {
        let wlf = ShiftFactor::wlf(17.44, 51.6, 20.0).unwrap();
        let arr = ShiftFactor::arrhenius(8000.0, 293.15).unwrap();
        for (law, temps) in [
            (wlf, [-10.0, 0.0, 15.0, 20.0, 35.0, 80.0]),
            (arr, [243.15, 273.15, 288.15, 293.15, 308.15, 353.15]),
        ] {
            for t in temps {
                let exact = law.at(t).unwrap();
                let f = law.at_in::<f32, LibmExp>(t as f32).unwrap() as f64;
                // The exponent ln a_T carries a few f32 roundings.
                let bound = 8.0 * f32::EPSILON as f64 * (1.0 + exact.ln().abs());
                assert!((f / exact - 1.0).abs() < bound, "libm {t}: {f} vs {exact}");
                #[cfg(feature = "micromath")]
                {
                    let m = law.at_in::<f32, crate::MicromathExp>(t as f32).unwrap() as f64;
                    assert!((m / exact - 1.0).abs() < 2.4e-3 + bound, "micromath {t}");
                }
            }
        }
        assert_eq!(arr.at_in::<f32, LibmExp>(293.15), Ok(1.0));
        assert!(matches!(
            wlf.at_in::<f32, LibmExp>(-40.0),
            Err(ParamError::OutOfRange { .. })
        ));
        assert!(matches!(
            arr.at_in::<f32, LibmExp>(0.0),
            Err(ParamError::NotPositive { .. })
        ));
        // e^(8000 (293 - 20) / (20 293)) overflows f32 but not f64.
        assert!(arr.at(20.0).is_ok());
        assert!(matches!(
            arr.at_in::<f32, LibmExp>(20.0),
            Err(ParamError::NotFinite { .. })
        ));
    }

    type Bank = MaxwellBank<f64, 4, Plain<f64>>;

    #[test]
    fn retuned_bank_is_continuous_and_settles_on_the_reduced_frequency_modulus() {
        let (dt, per) = (1e-3, 200usize);
        let omega = TAU / (dt * per as f64); // 5 Hz
        let specs = [
            MaxwellSpec::hz(0.5, 0.1),
            MaxwellSpec::hz(2.0, 0.15),
            MaxwellSpec::hz(8.0, 0.15),
            MaxwellSpec::hz(40.0, 0.1),
        ];
        let warm = Bank::new(MaxwellForm::RateExactRamp, &specs, dt).unwrap();
        let wlf = ShiftFactor::wlf(17.44, 51.6, 20.0).unwrap();
        let a_t = wlf.at(15.0).unwrap(); // 5 K colder: slower
        assert!(a_t > 1.0);
        let cold = warm.shifted(a_t).unwrap();
        let k = Polynomial::<f64, 2>::linear(1.0).unwrap();
        let (bw, bc) = (
            Bushing::new(k, (warm,)).unwrap(),
            Bushing::new(k, (cold,)).unwrap(),
        );
        let mut s = bw.state_at(0.0);
        let x = |n: usize| (TAU * (n % per) as f64 / per as f64).sin();
        let mut largest_change = 0.0f64;
        let mut last = 0.0;
        for n in 1..=20 * per + per / 3 {
            let f = bw.step(&mut s, x(n)).force;
            largest_change = largest_change.max((f - last).abs());
            last = f;
        }
        // The switch, between two steps, mid-period.
        let n0 = 20 * per + per / 3;
        let f = bc.step(&mut s, x(n0 + 1)).force;
        assert!(
            (f - last).abs() <= largest_change,
            "jump {} > largest step change {largest_change}",
            (f - last).abs()
        );
        let (mut fr, mut fi) = (0.0, 0.0);
        let periods = 60; // the slowest cold pole is 0.5 Hz / a_T
        for n in n0 + 2..=n0 + 1 + periods * per {
            let out = bc.step(&mut s, x(n));
            if n > n0 + 1 + (periods - 1) * per {
                let phase = TAU * (n % per) as f64 / per as f64;
                fr += 2.0 * out.force * phase.sin() / per as f64;
                fi += 2.0 * out.force * phase.cos() / per as f64;
            }
        }
        // eq 1.8 at the reference temperature and the reduced frequency.
        let w = a_t * omega;
        let g0 = 1.0 - specs.iter().map(|c| c.g).sum::<f64>();
        let (s_ref, l_ref) = specs.iter().fold((g0, 0.0), |(s, l), c| {
            let d = w * w + c.omega * c.omega;
            (s + c.g * w * w / d, l + c.g * w * c.omega / d)
        });
        assert!((fr / s_ref - 1.0).abs() < 5e-3, "storage {fr} vs {s_ref}");
        assert!((fi / l_ref - 1.0).abs() < 5e-3, "loss {fi} vs {l_ref}");
    }
}
