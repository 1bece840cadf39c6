//! Grünwald fractional cells (seed 000 eqs 1.20-1.25): `type =
//! "fractional"`.
//!
//! ```toml
//! [[effects]]
//! type = "fractional"
//! f_c_hz = 2.0     # transition frequency, Hz
//! alpha = 0.5      # order, 0 < alpha <= 1
//! g = 0.6          # load fraction
//! taps = 256       # memory length N, one of FRACTIONAL_TAPS
//! ```
//!
//! The core's `Grunwald<T, N>` is sized at compile time; [`DynGrunwald`]
//! picks one of a menu of lengths at run time.

use std::f64::consts::TAU;
use std::sync::Arc;

use bushing::fractional::{FractionalSpec, Grunwald, GrunwaldState};
use bushing::{Drive, Effect, EffectOutput, Param, ParamError, Real};
use serde::Deserialize;

use crate::reference::{Drive as Profile, Line, Measured, compared, no};

/// Memory lengths N a scene's fractional cell may have: the core's
/// `Grunwald<T, N>` is sized at compile time, so a scene picks one of
/// these (each a cell of its own, see [`DynGrunwald`]).
pub const FRACTIONAL_TAPS: [usize; 5] = [16, 64, 256, 1024, 4096];

/// `[[effects]] type = "fractional"`, as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractionalTable {
    /// Transition frequency f_c in Hz (ω_c = 2π f_c).
    pub f_c_hz: f64,
    /// Order α of the derivative, 0 < α <= 1.
    pub alpha: f64,
    /// Load fraction g.
    pub g: f64,
    /// Memory length N in steps: one of [`FRACTIONAL_TAPS`].
    pub taps: i64,
}

/// A checked fractional cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fractional {
    /// ω_c (rad/s), α and g.
    pub spec: FractionalSpec,
    /// Memory length N, one of [`FRACTIONAL_TAPS`].
    pub taps: usize,
}

impl FractionalTable {
    /// The memory length on the menu and the transition frequency.
    pub(super) fn check(self) -> Result<Fractional, String> {
        let taps = usize::try_from(self.taps)
            .ok()
            .filter(|n| FRACTIONAL_TAPS.contains(n))
            .ok_or_else(|| {
                let menu: Vec<_> = FRACTIONAL_TAPS.iter().map(|n| n.to_string()).collect();
                format!(
                    "taps = {} is not one of {} (the memory lengths a scene's fractional cell is built with)",
                    self.taps,
                    menu.join(", ")
                )
            })?;
        if !(self.f_c_hz.is_finite() && self.f_c_hz > 0.0) {
            return Err(format!(
                "f_c_hz must be finite and > 0 Hz, got {}",
                self.f_c_hz
            ));
        }
        Ok(Fractional {
            spec: FractionalSpec::hz(self.f_c_hz, self.alpha, self.g),
            taps,
        })
    }
}

impl Fractional {
    /// The cell in `T` at time step `dt` (the core's checks of the spec
    /// and of `dt`).
    pub fn build<T: Real>(&self, dt: f64) -> Result<DynGrunwald<T>, ParamError> {
        DynGrunwald::new(self.spec, self.taps, dt)
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        format!("fractional alpha {} x{}", self.spec.alpha, self.taps)
    }
}

/// Under a sine on a linear backbone K: the first harmonic against the
/// discrete cell's exact steady response (its weights as stored in `T`);
/// the memory of N steps is what the scheme computes, so the reference is
/// the truncated sum, not eq 1.21.
pub(super) fn references<T: Real>(cell: &DynGrunwald<T>, m: &Measured) -> Vec<Line> {
    let (Profile::Sine(f), Some(k)) = (m.drive, m.k_lin) else {
        return no("the complex modulus needs a sine on a linear backbone");
    };
    let (s, l) = cell.branch_response(TAU * f);
    let Some((storage, loss)) = m.modulus else {
        return no("the least-squares fit is singular");
    };
    vec![
        compared(
            "storage K' of g0 K x + cell force, first harmonic vs the discrete cell's exact response",
            "N/mm",
            k * (m.g0 + s),
            storage,
        ),
        compared(
            "loss K'' vs the discrete cell's exact response",
            "N/mm",
            k * l,
            loss,
        ),
    ]
}

/// Declares [`DynGrunwald`] and its state over a menu of memory lengths.
macro_rules! grunwald_menu {
    ($($variant:ident = $n:literal),+ $(,)?) => {
        /// A Grünwald fractional cell (the core's [`Grunwald`]) whose memory
        /// length N, a const generic of the core, is picked at run time from
        /// [`FRACTIONAL_TAPS`]: one
        /// monomorphised cell per length. The parameters (N weights) are
        /// shared, so cloning a built model does not copy them.
        #[derive(Debug, Clone)]
        pub enum DynGrunwald<T> {
            $(
                #[doc = concat!("N = ", stringify!($n), ".")]
                $variant(Arc<Grunwald<T, $n>>),
            )+
        }

        /// State of a [`DynGrunwald`]: the core's ring of N values, boxed.
        #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(bound(
            serialize = "T: serde::Serialize",
            deserialize = "T: serde::Deserialize<'de> + Copy + Default"
        ))]
        pub enum DynGrunwaldState<T> {
            $(
                #[doc = concat!("N = ", stringify!($n), ".")]
                $variant(Box<GrunwaldState<T, $n>>),
            )+
        }

        impl<T: Real> Clone for DynGrunwaldState<T> {
            fn clone(&self) -> Self {
                match self {
                    $(Self::$variant(s) => Self::$variant(s.clone()),)+
                }
            }
            /// Copies into the same box when both are of one length: an
            /// effect list keeps a copy of every state before each step.
            fn clone_from(&mut self, source: &Self) {
                match (self, source) {
                    $((Self::$variant(d), Self::$variant(s)) => (**d).clone_from(s),)+
                    (d, s) => *d = s.clone(),
                }
            }
        }

        impl<T: Real> DynGrunwald<T> {
            /// Builds the cell with `taps` history taps (one of the menu)
            /// for time step `dt`; the core's checks of `spec` and `dt`.
            pub fn new(spec: FractionalSpec, taps: usize, dt: f64) -> Result<Self, ParamError> {
                match taps {
                    $($n => Ok(Self::$variant(Arc::new(Grunwald::new(spec, dt)?))),)+
                    // The scene reader names the menu; this is its ends.
                    _ => Err(ParamError::OutOfRange {
                        param: Param::scalar("taps"),
                        value: taps as f64,
                        min: FRACTIONAL_TAPS[0] as f64,
                        min_open: false,
                        max: FRACTIONAL_TAPS[FRACTIONAL_TAPS.len() - 1] as f64,
                    }),
                }
            }

            /// Memory length N.
            pub fn taps(&self) -> usize {
                match self {
                    $(Self::$variant(_) => $n,)+
                }
            }

            /// Branch share of the complex stiffness over K^∞ at ω (rad/s),
            /// as (storage, loss): the discrete cell's exact steady state
            /// ([`Grunwald::branch_response`]).
            pub fn branch_response(&self, omega: f64) -> (f64, f64) {
                match self {
                    $(Self::$variant(c) => c.branch_response(omega),)+
                }
            }
        }

        impl<T: Real> Effect<T> for DynGrunwald<T> {
            type State = DynGrunwaldState<T>;
            type Report = EffectOutput<T>;

            fn fraction(&self) -> f64 {
                match self {
                    $(Self::$variant(c) => c.fraction(),)+
                }
            }
            fn dt(&self) -> Option<f64> {
                match self {
                    $(Self::$variant(c) => c.dt(),)+
                }
            }
            fn rest(&self, x0: T) -> Self::State {
                match self {
                    $(Self::$variant(c) => DynGrunwaldState::$variant(Box::new(c.rest(x0))),)+
                }
            }
            #[inline]
            fn step(&self, state: &mut Self::State, drive: &Drive<T>) -> EffectOutput<T> {
                match (self, state) {
                    $((Self::$variant(c), DynGrunwaldState::$variant(s)) => c.step(s, drive),)+
                    // A state always comes from its own cell's `rest`.
                    _ => EffectOutput::zero(),
                }
            }
            fn total(report: &EffectOutput<T>) -> EffectOutput<T> {
                *report
            }
            /// The core's refusal, which keeps only what a step writes.
            #[inline]
            fn step_if(
                &self,
                state: &mut Self::State,
                drive: &Drive<T>,
                accept: impl FnOnce(&EffectOutput<T>) -> bool,
            ) -> Option<EffectOutput<T>> {
                match (self, state) {
                    $((Self::$variant(c), DynGrunwaldState::$variant(s)) => {
                        c.step_if(s, drive, accept)
                    })+
                    _ => None,
                }
            }
        }
    };
}

grunwald_menu!(X16 = 16, X64 = 64, X256 = 256, X1024 = 1024, X4096 = 4096);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fractional_menu_builds_every_listed_length_and_no_other() {
        let spec = FractionalSpec::hz(5.0, 0.5, 0.6);
        for n in 0..=2 * FRACTIONAL_TAPS[FRACTIONAL_TAPS.len() - 1] {
            match DynGrunwald::<f32>::new(spec, n, 1e-3) {
                Ok(cell) => {
                    assert!(FRACTIONAL_TAPS.contains(&n), "{n} is not listed");
                    assert_eq!(cell.taps(), n);
                    assert_eq!(cell.fraction(), 0.6);
                    assert_eq!(cell.dt(), Some(1e-3));
                }
                Err(e) => {
                    assert!(!FRACTIONAL_TAPS.contains(&n), "{n}: {e}");
                    assert!(matches!(e, ParamError::OutOfRange { .. }), "{e}");
                }
            }
        }
    }

    #[test]
    fn a_fractional_state_is_copied_into_its_own_box() {
        let cell = DynGrunwald::<f64>::new(FractionalSpec::hz(5.0, 0.5, 0.6), 256, 1e-3).unwrap();
        let drive = Drive {
            x: 1.0,
            dx: 1.0,
            f_inf: 100.0,
            df_inf: 100.0,
            k_inf: 100.0,
        };
        let mut stepped = cell.rest(0.0);
        cell.step(&mut stepped, &drive);
        let mut copy = cell.rest(0.0);
        let DynGrunwaldState::X256(boxed) = &copy else {
            panic!("256 taps");
        };
        let before = std::ptr::from_ref(&**boxed);
        copy.clone_from(&stepped);
        assert_eq!(copy, stepped);
        let DynGrunwaldState::X256(boxed) = &copy else {
            panic!("256 taps");
        };
        assert_eq!(std::ptr::from_ref(&**boxed), before, "no new allocation");
    }
}
