//! Typed construction errors and run-time fault flags.

use core::fmt;

/// Names one parameter, with its position when it belongs to a list
/// (a cell of a bank, a knot of a spline, a coefficient of a polynomial).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Param {
    /// Parameter name as written in the docs and in scene files.
    pub name: &'static str,
    /// Position in its list, if any.
    pub index: Option<usize>,
}

impl Param {
    /// A scalar parameter.
    pub const fn scalar(name: &'static str) -> Self {
        Self { name, index: None }
    }
    /// Entry `index` of a list parameter.
    pub const fn item(name: &'static str, index: usize) -> Self {
        Self {
            name,
            index: Some(index),
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.index {
            Some(i) => write!(f, "{}[{}]", self.name, i),
            None => f.write_str(self.name),
        }
    }
}

/// Why a set of parameters was refused. One variant per broken rule; each
/// names the parameter and the bound it breaks.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamError {
    /// The value is NaN or infinite, or a coefficient derived from it
    /// overflows the working type (a Maxwell cell whose ω·dt is too large
    /// for its energy coefficient ω·dt/g).
    NotFinite {
        /// Offending parameter.
        param: Param,
    },
    /// The value must be strictly positive.
    NotPositive {
        /// Offending parameter.
        param: Param,
        /// Value given.
        value: f64,
    },
    /// The load fractions g^i of all dissipative branches add up to more
    /// than one, which would leave a negative long-term gain g^0 (seed 000
    /// §2.4.1: the fractions are relative to the high-frequency gain K^∞).
    FractionsAboveOne {
        /// Sum of the fractions.
        sum: f64,
    },
    /// The load fraction g of one cell is above one: a single cell would
    /// take more than the whole backbone (g must be in (0, 1]; a g that is
    /// not positive is [`ParamError::NotPositive`]).
    CellFractionAboveOne {
        /// Cell index in its bank; `None` for a cell that is not part of a
        /// bank (the fractional cell).
        cell: Option<usize>,
        /// The fraction given.
        g: f64,
    },
    /// An explicit scheme (eqs 1.13, 1.16) was asked for a cell with
    /// `omega * dt >= 1`, where its pole `1 - omega*dt` is no longer in (0, 1).
    ExplicitUnstable {
        /// Cell index in its bank.
        cell: usize,
        /// The product omega * dt of that cell.
        omega_dt: f64,
    },
    /// Not enough points or coefficients.
    TooFew {
        /// Offending list.
        param: Param,
        /// Smallest accepted length.
        min: usize,
        /// Length given.
        got: usize,
    },
    /// More points or coefficients than the fixed capacity.
    TooMany {
        /// Offending list.
        param: Param,
        /// Capacity of the type.
        capacity: usize,
        /// Length given.
        got: usize,
    },
    /// Two lists that must have the same length do not.
    LengthMismatch {
        /// The second list.
        param: Param,
        /// Length of the first list.
        expected: usize,
        /// Length of the second.
        got: usize,
    },
    /// A sequence must increase strictly; `param.index` is the first entry
    /// that does not exceed its predecessor.
    NotIncreasing {
        /// Offending entry.
        param: Param,
    },
    /// A sequence must not increase (a hysteretic relaxation stiffness
    /// K_f(d) relaxes with the distance d); `param.index` is the first entry
    /// above its predecessor.
    Increasing {
        /// Offending entry.
        param: Param,
    },
    /// The backbone tangent is not positive everywhere on its range, so the
    /// elastic potential would not be convex (seed 000 §2.3.1). `x` is a
    /// point where positivity fails or cannot be proven.
    TangentNotPositive {
        /// Abscissa where the check failed.
        x: f64,
    },
    /// A range with `lo >= hi`.
    EmptyRange {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// The value must lie in `[min, max]` (`min` itself excluded when
    /// `min_open`).
    OutOfRange {
        /// Offending parameter.
        param: Param,
        /// Value given.
        value: f64,
        /// Lower bound.
        min: f64,
        /// Whether the lower bound itself is refused.
        min_open: bool,
        /// Upper bound (included).
        max: f64,
    },
    /// Effects built for different time steps were put in one bushing.
    TimeStepMismatch {
        /// Time step of the first effect.
        first: f64,
        /// A different time step found later.
        other: f64,
    },
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NotFinite { param } => write!(f, "{param} must be finite"),
            Self::NotPositive { param, value } => {
                write!(f, "{param} must be > 0 (got {value})")
            }
            Self::FractionsAboveOne { sum } => write!(
                f,
                "load fractions g add up to {sum}, above 1: the long-term gain g0 = 1 - sum(g) would be negative"
            ),
            Self::CellFractionAboveOne { cell, g } => {
                if let Some(i) = cell {
                    write!(f, "cells[{i}].")?;
                }
                write!(
                    f,
                    "g = {g} must be in (0, 1]: a single cell cannot take more than the whole backbone"
                )
            }
            Self::ExplicitUnstable { cell, omega_dt } => write!(
                f,
                "cell {cell}: omega*dt = {omega_dt} >= 1, outside the range of an explicit scheme; use an exponential form or a smaller dt"
            ),
            Self::TooFew { param, min, got } => {
                write!(f, "{param}: at least {min} entries needed, got {got}")
            }
            Self::TooMany {
                param,
                capacity,
                got,
            } => write!(f, "{param}: capacity is {capacity} entries, got {got}"),
            Self::LengthMismatch {
                param,
                expected,
                got,
            } => write!(f, "{param}: expected {expected} entries, got {got}"),
            Self::NotIncreasing { param } => {
                write!(f, "{param} must be larger than the entry before it")
            }
            Self::Increasing { param } => {
                write!(f, "{param} must not exceed the entry before it")
            }
            Self::TangentNotPositive { x } => {
                write!(f, "backbone tangent is not provably positive near x = {x}")
            }
            Self::EmptyRange { lo, hi } => write!(f, "range [{lo}, {hi}] is empty"),
            Self::OutOfRange {
                param,
                value,
                min,
                min_open,
                max,
            } => {
                let open = if min_open { "(" } else { "[" };
                let (value, min, max) = (Num(value), Num(min), Num(max));
                write!(f, "{param} = {value} is outside {open}{min}, {max}]")
            }
            Self::TimeStepMismatch { first, other } => write!(
                f,
                "effects built for different time steps: {first} s and {other} s"
            ),
        }
    }
}

impl core::error::Error for ParamError {}

/// A number as a person reads it: plain from 1e-4 to 1e9, in exponent form
/// beyond (a guard of 2^500 is `3.273390607896142e150`, not 151 digits).
struct Num(f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-4..1e9).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn positive(param: Param, value: f64) -> Result<f64, ParamError> {
    if !value.is_finite() {
        Err(ParamError::NotFinite { param })
    } else if value > 0.0 {
        Ok(value)
    } else {
        Err(ParamError::NotPositive { param, value })
    }
}

/// Checks that `value` is positive and that it and its reciprocal fit the
/// working type: `value` in `[1/GUARD, GUARD]` (8.7e-19 to 1.2e18 in f32).
/// For parameters whose reciprocal is stored, so that neither rounds to
/// zero nor overflows in `T`.
pub(crate) fn scaled<T: crate::Real>(param: Param, value: f64) -> Result<f64, ParamError> {
    let value = positive(param, value)?;
    let max = T::GUARD.to_f64();
    let min = 1.0 / max;
    if value < min || value > max {
        Err(ParamError::OutOfRange {
            param,
            value,
            min,
            min_open: false,
            max,
        })
    } else {
        Ok(value)
    }
}

/// Checks that a finite `value` is within [`crate::Real::GUARD`] of the
/// working type in magnitude (`[-GUARD, GUARD]`): a value a law stores and
/// multiplies by distances or forces.
pub(crate) fn guarded<T: crate::Real>(param: Param, value: f64) -> Result<f64, ParamError> {
    let max = T::GUARD.to_f64();
    if value.abs() <= max {
        Ok(value)
    } else {
        Err(ParamError::OutOfRange {
            param,
            value,
            min: -max,
            min_open: false,
            max,
        })
    }
}

/// Checks that `value` is finite and in `[min, max]` (`min` excluded when
/// `min_open`).
pub(crate) fn in_range(
    param: Param,
    value: f64,
    min: f64,
    min_open: bool,
    max: f64,
) -> Result<f64, ParamError> {
    let value = finite(param, value)?;
    let above = if min_open { value > min } else { value >= min };
    if above && value <= max {
        Ok(value)
    } else {
        Err(ParamError::OutOfRange {
            param,
            value,
            min,
            min_open,
            max,
        })
    }
}

/// Checks that a value in the working type (an on-line input such as a
/// shift factor) is finite and strictly positive.
pub(crate) fn positive_in<T: crate::Real>(param: Param, value: T) -> Result<T, ParamError> {
    if !value.is_finite() {
        return Err(ParamError::NotFinite { param });
    }
    if value <= T::ZERO {
        return Err(ParamError::NotPositive {
            param,
            value: value.to_f64(),
        });
    }
    Ok(value)
}

/// Checks that `value` is finite.
pub(crate) fn finite(param: Param, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::NotFinite { param })
    }
}

/// Sticky fault flags of a running model. A step that raises one keeps the
/// last finite state; the caller reads and clears the flags when it likes.
///
/// `Display` (and `Debug`, and `defmt::Format` with the `defmt` feature)
/// name the raised flags, as the constants are named:
///
/// ```
/// use bushing::Faults;
///
/// let mut f = Faults::NONE;
/// assert_eq!(f.to_string(), "NONE");
/// f.raise(Faults::OUT_OF_RANGE);
/// f.raise(Faults::NON_FINITE_INPUT);
/// assert_eq!(f.to_string(), "NON_FINITE_INPUT | OUT_OF_RANGE");
/// assert_eq!(format!("{f:?}"), "Faults(NON_FINITE_INPUT | OUT_OF_RANGE)");
/// assert_eq!(f.names().count(), 2);
/// ```
#[derive(Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Faults(u8);

impl Faults {
    /// No fault.
    pub const NONE: Self = Self(0);
    /// An input was NaN or infinite.
    pub const NON_FINITE_INPUT: Self = Self(1);
    /// The input displacement, or the backbone force or tangent there,
    /// exceeded [`crate::Real::GUARD`], or the tangent was not positive in
    /// the working type (a stiffness that underflows there).
    pub const OUT_OF_RANGE: Self = Self(2);
    /// The dissipated energy of a step was not finite in the working type
    /// (a very stiff cell under a force near the guard, or a tangent near
    /// zero): the step was taken, its force and tangent are valid, and it
    /// reports no dissipated energy.
    pub const ENERGY_OVERFLOW: Self = Self(4);
    /// A step would have given an effect a force or tangent, or the
    /// bushing a total force or tangent, that is not finite or exceeds
    /// [`crate::Real::GUARD`] (a law driven far beyond its data): the step
    /// was refused and the state kept.
    pub const FORCE_OUT_OF_RANGE: Self = Self(8);

    /// True if no flag is raised.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }
    /// True if every flag of `other` is raised.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
    /// Raises the flags of `other`.
    pub fn raise(&mut self, other: Self) {
        self.0 |= other.0;
    }
    /// The raw bits (for logging).
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Every flag with its name, in the order of its bit.
    pub const FLAGS: [(Self, &'static str); 4] = [
        (Self::NON_FINITE_INPUT, "NON_FINITE_INPUT"),
        (Self::OUT_OF_RANGE, "OUT_OF_RANGE"),
        (Self::ENERGY_OVERFLOW, "ENERGY_OVERFLOW"),
        (Self::FORCE_OUT_OF_RANGE, "FORCE_OUT_OF_RANGE"),
    ];

    /// The names of the raised flags, in the order of their bits.
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        Self::FLAGS
            .into_iter()
            .filter(move |&(flag, _)| self.contains(flag))
            .map(|(_, name)| name)
    }

    /// The text of `Display`, in four pieces: per flag of [`Self::FLAGS`],
    /// its name (after `" | "` when an earlier flag is raised) or `""`.
    /// One shape for `Display` and `defmt::Format`, which writes each
    /// formatted value in one call.
    fn pieces(self) -> [&'static str; 4] {
        const JOINED: [&str; 4] = [
            " | NON_FINITE_INPUT",
            " | OUT_OF_RANGE",
            " | ENERGY_OVERFLOW",
            " | FORCE_OUT_OF_RANGE",
        ];
        let mut out = [""; 4];
        let mut first = true;
        for ((piece, (flag, name)), joined) in out.iter_mut().zip(Self::FLAGS).zip(JOINED) {
            if self.contains(flag) {
                *piece = if first { name } else { joined };
                first = false;
            }
        }
        out
    }
}

/// The names of the raised flags joined by `" | "`, or `NONE`.
impl fmt::Display for Faults {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("NONE");
        }
        self.pieces().iter().try_for_each(|p| f.write_str(p))
    }
}

/// `Faults(` the `Display` text `)`.
impl fmt::Debug for Faults {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Faults({self})")
    }
}

/// The `Display` text, decoded on the host.
#[cfg(feature = "defmt")]
impl defmt::Format for Faults {
    fn format(&self, f: defmt::Formatter<'_>) {
        if self.is_empty() {
            defmt::write!(f, "NONE");
        } else {
            let [a, b, c, d] = self.pieces();
            defmt::write!(f, "{=str}{=str}{=str}{=str}", a, b, c, d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positive_rejects_each_bad_value_with_its_variant() {
        let p = Param::item("omega", 3);
        assert_eq!(positive(p, 2.0), Ok(2.0));
        assert_eq!(
            positive(p, 0.0),
            Err(ParamError::NotPositive {
                param: p,
                value: 0.0
            })
        );
        assert_eq!(
            positive(p, f64::NAN),
            Err(ParamError::NotFinite { param: p })
        );
        assert_eq!(
            positive(p, f64::INFINITY),
            Err(ParamError::NotFinite { param: p })
        );
        assert_eq!(finite(p, -1.0), Ok(-1.0));
    }

    #[test]
    fn a_cell_fraction_above_one_names_the_cell_and_the_bound() {
        let e = ParamError::CellFractionAboveOne {
            cell: Some(1),
            g: 1.2,
        };
        let text = alloc::format!("{e}");
        assert!(
            text.starts_with("cells[1].g = 1.2 must be in (0, 1]"),
            "{text}"
        );
        let e = ParamError::CellFractionAboveOne { cell: None, g: 1.5 };
        let text = alloc::format!("{e}");
        assert!(text.starts_with("g = 1.5 must be in (0, 1]"), "{text}");
    }

    #[test]
    fn faults_are_sticky_bits() {
        let mut f = Faults::NONE;
        assert!(f.is_empty());
        f.raise(Faults::OUT_OF_RANGE);
        f.raise(Faults::NON_FINITE_INPUT);
        assert!(f.contains(Faults::OUT_OF_RANGE) && f.contains(Faults::NON_FINITE_INPUT));
        assert_eq!(f.bits(), 3);
    }

    #[test]
    fn faults_print_the_names_of_their_flags() {
        assert_eq!(alloc::format!("{}", Faults::NONE), "NONE");
        assert_eq!(alloc::format!("{:?}", Faults::NONE), "Faults(NONE)");
        // Every subset of the four flags: the raised names in bit order.
        for bits in 0u8..16 {
            let mut f = Faults::NONE;
            let mut expected = alloc::vec::Vec::new();
            for (k, (flag, name)) in Faults::FLAGS.into_iter().enumerate() {
                if bits & (1 << k) != 0 {
                    f.raise(flag);
                    expected.push(name);
                }
            }
            assert_eq!(f.bits(), bits);
            assert_eq!(f.names().collect::<alloc::vec::Vec<_>>(), expected);
            let text = if expected.is_empty() {
                alloc::string::String::from("NONE")
            } else {
                expected.join(" | ")
            };
            assert_eq!(alloc::format!("{f}"), text);
        }
    }
}
