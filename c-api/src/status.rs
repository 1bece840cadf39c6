//! What a C call returns: a status code, and on a refused construction
//! the parameter and the bound it breaks.

use core::ffi::c_char;

use bushing::{Param, ParamError};

/// The result of a call, as the `BUSHING_STATUS_*` codes below give it to
/// C (`bushing_status_t`).
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BushingStatus {
    /// Success.
    Ok = 0,
    /// The step was refused: its input was not finite or beyond the guard,
    /// or a force would have left it. The state is kept and a fault flag
    /// raised; the output holds the last force.
    Refused = 1,
    /// A pointer argument was null.
    NullPointer = -1,
    /// The model or state was not initialised by its `init` (or belongs to
    /// another kind of model).
    NotInitialised = -2,
    /// A kind field (a form, a backbone, a filter, a sensor) holds a value
    /// that names no kind.
    UnknownKind = -3,
    /// A parameter is NaN or infinite, or a coefficient made from it
    /// overflows the working type.
    NotFinite = -10,
    /// A parameter must be strictly positive.
    NotPositive = -11,
    /// The load fractions of all branches add up to more than one.
    FractionsAboveOne = -12,
    /// One cell's load fraction is above one.
    CellFractionAboveOne = -13,
    /// An explicit Maxwell form was asked for a cell with ω dt >= 1.
    ExplicitUnstable = -14,
    /// A list is shorter than its minimum.
    TooFew = -15,
    /// A list is longer than its capacity.
    TooMany = -16,
    /// Two lists that must have the same length do not.
    LengthMismatch = -17,
    /// A sequence must increase strictly.
    NotIncreasing = -18,
    /// A sequence must not increase.
    Increasing = -19,
    /// A polynomial backbone's tangent is not positive on its range.
    TangentNotPositive = -20,
    /// A range is empty (its low end not below its high end).
    EmptyRange = -21,
    /// A parameter is outside its range.
    OutOfRange = -22,
    /// Two parts were built for different time steps.
    TimeStepMismatch = -23,
}

/// The result of a call: `BUSHING_STATUS_OK` (0) is success; a step that
/// the model refused is `BUSHING_STATUS_REFUSED` (1); every other value is
/// negative and names the rule a call or a parameter broke. The codes from
/// -10 on are the rules of the core's `ParamError`, one each.
pub type BushingStatusCode = i32;

/// Success.
pub const BUSHING_STATUS_OK: BushingStatusCode = 0;

/// The step was refused: its input was not finite or beyond the guard,
/// or a force would have left it. The state is kept and a fault flag
/// raised; the output holds the last force.
pub const BUSHING_STATUS_REFUSED: BushingStatusCode = 1;

/// A pointer argument was null.
pub const BUSHING_STATUS_NULL_POINTER: BushingStatusCode = -1;

/// The model or state was not initialised by its `init` (or belongs to
/// another kind of model).
pub const BUSHING_STATUS_NOT_INITIALISED: BushingStatusCode = -2;

/// A kind field (a form, a backbone, a filter, a sensor) holds a value
/// that names no kind.
pub const BUSHING_STATUS_UNKNOWN_KIND: BushingStatusCode = -3;

/// A parameter is NaN or infinite, or a coefficient made from it
/// overflows the working type.
pub const BUSHING_STATUS_NOT_FINITE: BushingStatusCode = -10;

/// A parameter must be strictly positive.
pub const BUSHING_STATUS_NOT_POSITIVE: BushingStatusCode = -11;

/// The load fractions of all branches add up to more than one.
pub const BUSHING_STATUS_FRACTIONS_ABOVE_ONE: BushingStatusCode = -12;

/// One cell's load fraction is above one.
pub const BUSHING_STATUS_CELL_FRACTION_ABOVE_ONE: BushingStatusCode = -13;

/// An explicit Maxwell form was asked for a cell with ω dt >= 1.
pub const BUSHING_STATUS_EXPLICIT_UNSTABLE: BushingStatusCode = -14;

/// A list is shorter than its minimum.
pub const BUSHING_STATUS_TOO_FEW: BushingStatusCode = -15;

/// A list is longer than its capacity.
pub const BUSHING_STATUS_TOO_MANY: BushingStatusCode = -16;

/// Two lists that must have the same length do not.
pub const BUSHING_STATUS_LENGTH_MISMATCH: BushingStatusCode = -17;

/// A sequence must increase strictly.
pub const BUSHING_STATUS_NOT_INCREASING: BushingStatusCode = -18;

/// A sequence must not increase.
pub const BUSHING_STATUS_INCREASING: BushingStatusCode = -19;

/// A polynomial backbone's tangent is not positive on its range.
pub const BUSHING_STATUS_TANGENT_NOT_POSITIVE: BushingStatusCode = -20;

/// A range is empty (its low end not below its high end).
pub const BUSHING_STATUS_EMPTY_RANGE: BushingStatusCode = -21;

/// A parameter is outside its range.
pub const BUSHING_STATUS_OUT_OF_RANGE: BushingStatusCode = -22;

/// Two parts were built for different time steps.
pub const BUSHING_STATUS_TIME_STEP_MISMATCH: BushingStatusCode = -23;

impl BushingStatus {
    /// The code C sees.
    pub(crate) fn code(self) -> BushingStatusCode {
        self as BushingStatusCode
    }
}

/// A core parameter name, the C spec field it comes from, and the index
/// of the parameter in that field when the field is an array of
/// different parameters (`friction_params`).
pub(crate) type Field = (&'static str, &'static str, Option<usize>);

/// Bytes of [`BushingError::param`], its final NUL included.
pub const BUSHING_PARAM_NAME_BYTES: usize = 32;

/// What a refused construction broke: the status, the parameter (its
/// name as in the docs and its position in its list), the value given and
/// the bound. Fields that do not apply are -1 (`index`) or NaN.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct BushingError {
    /// The status the call returned (`BUSHING_STATUS_*`).
    pub status: BushingStatusCode,
    /// Position of the parameter in its list, or -1.
    pub index: i32,
    /// The value given, or NaN.
    pub value: f64,
    /// The bound it breaks (a minimum, maximum or capacity), or NaN.
    pub bound: f64,
    /// The parameter's name, NUL-terminated (empty when the rule names
    /// none).
    pub param: [c_char; BUSHING_PARAM_NAME_BYTES],
}

impl BushingError {
    /// The detail of `status` alone.
    pub(crate) fn of(status: BushingStatus) -> Self {
        Self {
            status: status.code(),
            index: -1,
            value: f64::NAN,
            bound: f64::NAN,
            param: [0; BUSHING_PARAM_NAME_BYTES],
        }
    }

    /// An unknown kind in the field `name`, holding `value`.
    pub(crate) fn unknown_kind(name: &'static str, value: u32) -> Self {
        let mut e = Self::of(BushingStatus::UnknownKind).named(Param::scalar(name));
        e.value = f64::from(value);
        e
    }

    /// The same refusal in the C spec's words: a core parameter name
    /// found in `fields` becomes the spec field it came from (and that
    /// field's index, for an array of different parameters).
    pub(crate) fn in_fields(self, fields: &[Field]) -> Self {
        let len = self.param.iter().position(|&c| c == 0).unwrap_or(0);
        let given = self.param.get(..len).unwrap_or(&[]);
        let same = |name: &str| {
            name.len() == given.len() && name.bytes().zip(given).all(|(a, &b)| a as c_char == b)
        };
        let Some(&(_, field, index)) = fields.iter().find(|(core, ..)| same(core)) else {
            return self;
        };
        let index = index.or(usize::try_from(self.index).ok());
        let mut out = self;
        out.param = [0; BUSHING_PARAM_NAME_BYTES];
        out.named(Param { name: field, index })
    }

    fn named(mut self, param: Param) -> Self {
        self.index = param
            .index
            .and_then(|i| i32::try_from(i).ok())
            .unwrap_or(-1);
        // The name truncated to leave room for the NUL.
        for (dst, &b) in self
            .param
            .iter_mut()
            .zip(param.name.as_bytes())
            .take(BUSHING_PARAM_NAME_BYTES - 1)
        {
            *dst = b as c_char;
        }
        self
    }
}

/// Lengths and indices as the C side reads them.
fn count(n: usize) -> f64 {
    n as f64
}

impl From<ParamError> for BushingError {
    fn from(e: ParamError) -> Self {
        use BushingStatus as S;
        use ParamError as E;
        let with = |status, param, value: f64, bound: f64| {
            let mut out = Self::of(status).named(param);
            (out.value, out.bound) = (value, bound);
            out
        };
        let none = Param::scalar("");
        match e {
            E::NotFinite { param } => with(S::NotFinite, param, f64::NAN, f64::NAN),
            E::NotPositive { param, value } => with(S::NotPositive, param, value, 0.0),
            E::FractionsAboveOne { sum } => {
                with(S::FractionsAboveOne, Param::scalar("g"), sum, 1.0)
            }
            E::CellFractionAboveOne { cell, g } => {
                let param = cell.map_or(Param::scalar("g"), |i| Param::item("g", i));
                with(S::CellFractionAboveOne, param, g, 1.0)
            }
            E::ExplicitUnstable { cell, omega_dt } => with(
                S::ExplicitUnstable,
                Param::item("omega", cell),
                omega_dt,
                1.0,
            ),
            E::TooFew { param, min, got } => with(S::TooFew, param, count(got), count(min)),
            E::TooMany {
                param,
                capacity,
                got,
            } => with(S::TooMany, param, count(got), count(capacity)),
            E::LengthMismatch {
                param,
                expected,
                got,
            } => with(S::LengthMismatch, param, count(got), count(expected)),
            E::NotIncreasing { param } => with(S::NotIncreasing, param, f64::NAN, f64::NAN),
            E::Increasing { param } => with(S::Increasing, param, f64::NAN, f64::NAN),
            E::TangentNotPositive { x } => with(S::TangentNotPositive, none, x, 0.0),
            E::EmptyRange { lo, hi } => with(S::EmptyRange, none, lo, hi),
            E::OutOfRange {
                param,
                value,
                min,
                max,
                ..
            } => {
                // The bound broken: the nearer end.
                let bound = if value < min || value.is_nan() {
                    min
                } else {
                    max
                };
                with(S::OutOfRange, param, value, bound)
            }
            E::TimeStepMismatch { first, other } => {
                with(S::TimeStepMismatch, Param::scalar("dt"), other, first)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name(e: &BushingError) -> String {
        let bytes: Vec<u8> = e
            .param
            .iter()
            .take_while(|&&c| c != 0)
            .map(|&c| c as u8)
            .collect();
        String::from_utf8(bytes).unwrap()
    }

    #[test]
    fn a_refusal_names_its_parameter_index_value_and_bound() {
        let e = BushingError::from(ParamError::TooMany {
            param: Param::item("x", 3),
            capacity: 16,
            got: 20,
        });
        assert_eq!(e.status, BUSHING_STATUS_TOO_MANY);
        assert_eq!(
            (name(&e).as_str(), e.index, e.value, e.bound),
            ("x", 3, 20.0, 16.0)
        );
        let e = BushingError::from(ParamError::NotPositive {
            param: Param::scalar("dt"),
            value: -1.0,
        });
        assert_eq!((name(&e).as_str(), e.index, e.value), ("dt", -1, -1.0));
    }

    #[test]
    fn a_core_name_becomes_the_spec_field() {
        let fields: [Field; 2] = [("g", "maxwell_g", None), ("x2", "friction_params", Some(1))];
        let e = BushingError::from(ParamError::CellFractionAboveOne {
            cell: Some(3),
            g: 1.5,
        })
        .in_fields(&fields);
        assert_eq!((name(&e).as_str(), e.index), ("maxwell_g", 3));
        let e = BushingError::from(ParamError::NotFinite {
            param: Param::scalar("x2"),
        })
        .in_fields(&fields);
        assert_eq!((name(&e).as_str(), e.index), ("friction_params", 1));
        let e = BushingError::from(ParamError::NotFinite {
            param: Param::scalar("gamma"),
        })
        .in_fields(&fields);
        assert_eq!((name(&e).as_str(), e.index), ("gamma", -1));
    }

    #[test]
    fn a_long_name_is_cut_and_still_ends_with_nul() {
        let long = "a_parameter_name_of_far_more_than_thirty_two_bytes";
        let e = BushingError::from(ParamError::NotFinite {
            param: Param::scalar(long),
        });
        assert_eq!(e.param[BUSHING_PARAM_NAME_BYTES - 1], 0);
        assert_eq!(name(&e), long[..BUSHING_PARAM_NAME_BYTES - 1]);
    }

    #[test]
    fn each_code_is_its_rules() {
        use BushingStatus as S;
        let pairs = [
            (S::Ok, BUSHING_STATUS_OK),
            (S::Refused, BUSHING_STATUS_REFUSED),
            (S::NullPointer, BUSHING_STATUS_NULL_POINTER),
            (S::NotInitialised, BUSHING_STATUS_NOT_INITIALISED),
            (S::UnknownKind, BUSHING_STATUS_UNKNOWN_KIND),
            (S::NotFinite, BUSHING_STATUS_NOT_FINITE),
            (S::NotPositive, BUSHING_STATUS_NOT_POSITIVE),
            (S::FractionsAboveOne, BUSHING_STATUS_FRACTIONS_ABOVE_ONE),
            (
                S::CellFractionAboveOne,
                BUSHING_STATUS_CELL_FRACTION_ABOVE_ONE,
            ),
            (S::ExplicitUnstable, BUSHING_STATUS_EXPLICIT_UNSTABLE),
            (S::TooFew, BUSHING_STATUS_TOO_FEW),
            (S::TooMany, BUSHING_STATUS_TOO_MANY),
            (S::LengthMismatch, BUSHING_STATUS_LENGTH_MISMATCH),
            (S::NotIncreasing, BUSHING_STATUS_NOT_INCREASING),
            (S::Increasing, BUSHING_STATUS_INCREASING),
            (S::TangentNotPositive, BUSHING_STATUS_TANGENT_NOT_POSITIVE),
            (S::EmptyRange, BUSHING_STATUS_EMPTY_RANGE),
            (S::OutOfRange, BUSHING_STATUS_OUT_OF_RANGE),
            (S::TimeStepMismatch, BUSHING_STATUS_TIME_STEP_MISMATCH),
        ];
        for (status, code) in pairs {
            assert_eq!(status.code(), code, "{status:?}");
        }
        let mut codes: Vec<_> = pairs.iter().map(|p| p.1).collect();
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), pairs.len(), "two rules share a code");
    }
}
