//! The viscous dashpot: F = c ẋ in parallel with the backbone, the
//! "viscous" mount model of seed 000 §5.2.2 (a), F = f(u) + c u̇.
//!
//! Discretised with the backward difference of the step, ẋ ≈ Δx/Δt:
//! F_n = (c/Δt)(x_n - x_{n-1}). The step dissipates F_n Δx = (c/Δt) Δx²
//! (eq 5.1 with P = c ẋ², ≥ 0 in every step, zero when the bushing stops:
//! the dissipated power of a Kelvin-Voigt model vanishes at zero velocity,
//! unlike a bank of Maxwell cells, §5.2.3). The force does not depend on
//! the history before the last step, so the effect has no state.
//!
//! **Stability**: unconditional (it is the backward-Euler damper); in an
//! explicit multibody integration the damper adds c to the damping of the
//! mode, whose explicit limit is the integrator's.
//!
//! **Cost**: two multiplications (three with the energy).

use crate::bushing::{Drive, Effect, EffectOutput};
use crate::error::{Param, ParamError, positive};
use crate::real::Real;

/// A dashpot of coefficient c (force per velocity), at time step Δt.
///
/// ```
/// use bushing::viscous::Dashpot;
/// use bushing::{Bushing, ParamError, Polynomial};
///
/// // c = 2 N·s/mm at 1 kHz.
/// let backbone = Polynomial::<f32, 2>::new(&[0.0, 100.0], (-5.0, 5.0))?;
/// let bushing = Bushing::new(backbone, (Dashpot::new(2.0, 1e-3)?,))?;
/// let mut state = bushing.state_at(0.0);
/// // 0.01 mm in 1 ms: 10 mm/s, so 20 N of damping over 1 N of spring.
/// let out = bushing.step(&mut state, 0.01);
/// assert!((out.force - 21.0).abs() < 1e-3);
/// assert!(Dashpot::<f32>::new(-2.0, 1e-3).is_err());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dashpot<T> {
    /// c/Δt.
    gain: T,
    c: f64,
    dt: f64,
}

impl<T: Real> Dashpot<T> {
    /// A dashpot of coefficient `c` (N·s/mm with mm and N) at step `dt` s.
    /// Refuses `c` or `dt` not finite and positive (`c`, `dt`), and a
    /// c/Δt that does not fit the working type (`c`, [`ParamError::NotFinite`]).
    pub fn new(c: f64, dt: f64) -> Result<Self, ParamError> {
        let c = positive(Param::scalar("c"), c)?;
        let dt = positive(Param::scalar("dt"), dt)?;
        let gain = T::from_f64(c / dt);
        if !gain.is_finite() || gain.abs() > T::GUARD {
            return Err(ParamError::NotFinite {
                param: Param::scalar("c"),
            });
        }
        Ok(Self { gain, c, dt })
    }

    /// The coefficient c.
    pub fn c(&self) -> f64 {
        self.c
    }
}

impl<T: Real> Effect<T> for Dashpot<T> {
    type State = ();
    type Report = EffectOutput<T>;

    fn fraction(&self) -> f64 {
        0.0
    }
    fn dt(&self) -> Option<f64> {
        Some(self.dt)
    }
    fn rest(&self, _: T) {}
    #[inline(always)]
    fn step(&self, _: &mut (), drive: &Drive<T>) -> EffectOutput<T> {
        let force = self.gain * drive.dx;
        EffectOutput {
            force,
            tangent: self.gain,
            dissipated: force * drive.dx,
        }
    }
    #[inline(always)]
    fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
        *report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Bushing, Polynomial};

    #[test]
    fn force_is_c_times_the_velocity_and_energy_is_c_v_squared() {
        let (c, dt, v) = (0.6, 1e-3, 25.0); // N·s/mm, s, mm/s
        let b = Bushing::new(
            Polynomial::<f64, 2>::linear(100.0).unwrap(),
            (Dashpot::new(c, dt).unwrap(),),
        )
        .unwrap();
        let mut s = b.state_at(0.0);
        let mut energy = 0.0;
        for n in 1..=100 {
            let x = v * dt * n as f64;
            let o = b.step(&mut s, x);
            let damper = o.force - 100.0 * x;
            assert!((damper - c * v).abs() < 1e-9, "{damper}");
            assert!((o.tangent - (100.0 + c / dt)).abs() < 1e-6);
            energy += o.dissipated;
        }
        // c v² over 0.1 s.
        assert!((energy - c * v * v * 0.1).abs() < 1e-9 * energy, "{energy}");
        // At rest again: no force, no dissipation.
        let x = s.x();
        let o = b.step(&mut s, x);
        assert_eq!((o.force - 100.0 * x, o.dissipated), (0.0, 0.0));
    }

    #[test]
    fn bad_coefficients_are_refused_by_name() {
        assert_eq!(
            Dashpot::<f64>::new(-1.0, 1e-3),
            Err(ParamError::NotPositive {
                param: Param::scalar("c"),
                value: -1.0
            })
        );
        assert_eq!(
            Dashpot::<f64>::new(1.0, 0.0).map(|_| ()),
            Err(ParamError::NotPositive {
                param: Param::scalar("dt"),
                value: 0.0
            })
        );
        assert_eq!(
            Dashpot::<f32>::new(1e30, 1e-9).map(|_| ()),
            Err(ParamError::NotFinite {
                param: Param::scalar("c")
            })
        );
    }
}
