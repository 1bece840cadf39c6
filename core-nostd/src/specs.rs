//! The parameter specs as a configuration file writes them (feature
//! `serde`): each spec is read through its checked constructor, so a value
//! out of its range is refused while the file is read, with the
//! parameter's name and bound ([`ParamError`]'s message).
//!
//! | type | written as | checks |
//! |---|---|---|
//! | [`MaxwellSpec`] | `{ f_hz, g }`, corner frequency in Hz | f_hz finite and > 0, g in (0, 1] |
//! | [`XfSpec`] | `{ f_hz, g, x_f }`, x_f in mm | f_hz finite and >= 0, g in (0, 1], x_f finite and > 0 |
//! | [`IwanCellSpec`] | `{ g, slip_force }`, slip force in N | g in (0, 1], slip_force finite and > 0 |
//! | [`FractionalSpec`] | `{ f_c_hz, alpha, g }` | [`FractionalSpec::validate`] |
//! | [`MaxwellForm`](crate::MaxwellForm), [`XfForm`](crate::XfForm), [`FirstLoading`](crate::FirstLoading) | their names: `"rate-midpoint"`, `"exact-ramp"`, `"masing"` | |
//!
//! What depends on the time step or on the whole bank (ω·dt of an explicit
//! form, the sum of the fractions) is checked by the model's constructor.
//! The specs are read, not written: a corner in rad/s written back in Hz
//! would not give the same bits when read again.

use core::fmt;
use core::marker::PhantomData;

use serde::Deserialize;
use serde::de::value::MapAccessDeserializer;
use serde::de::{Deserializer, Error, MapAccess, Visitor};

use crate::error::{Param, ParamError, positive};
use crate::fractional::FractionalSpec;
use crate::iwan::IwanCellSpec;
use crate::maxwell::MaxwellSpec;
use crate::xf::XfSpec;

/// Reads a spec `S` from a table written as `R`, and checks it with `S`'s
/// `TryFrom<R>`: the check runs while the table is being read, so a file
/// format that tracks positions reports a refused value at its table.
struct Checked<R, S>(PhantomData<(R, S)>);

impl<'de, R: Deserialize<'de>, S: TryFrom<R, Error = ParamError>> Visitor<'de> for Checked<R, S> {
    type Value = S;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a table of parameters")
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<S, A::Error> {
        let raw = R::deserialize(MapAccessDeserializer::new(map))?;
        S::try_from(raw).map_err(A::Error::custom)
    }
}

/// `Deserialize` for each spec, through its written form.
macro_rules! read_through {
    ($($spec:ty => $raw:ty),+ $(,)?) => {
        $(
            impl<'de> Deserialize<'de> for $spec {
                fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                    d.deserialize_map(Checked::<$raw, $spec>(PhantomData))
                }
            }
        )+
    };
}

read_through!(
    MaxwellSpec => MaxwellHz,
    XfSpec => XfHz,
    IwanCellSpec => IwanForce,
    FractionalSpec => FractionalHz,
);

/// A load fraction of one cell: in (0, 1].
fn fraction(g: f64) -> Result<f64, ParamError> {
    let g = positive(Param::scalar("g"), g)?;
    if g > 1.0 {
        return Err(ParamError::CellFractionAboveOne { cell: None, g });
    }
    Ok(g)
}

/// [`MaxwellSpec`] as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaxwellHz {
    f_hz: f64,
    g: f64,
}

impl TryFrom<MaxwellHz> for MaxwellSpec {
    type Error = ParamError;
    fn try_from(w: MaxwellHz) -> Result<Self, ParamError> {
        positive(Param::scalar("f_hz"), w.f_hz)?;
        Ok(Self::hz(w.f_hz, fraction(w.g)?))
    }
}

/// [`XfSpec`] as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct XfHz {
    f_hz: f64,
    g: f64,
    x_f: f64,
}

impl TryFrom<XfHz> for XfSpec {
    type Error = ParamError;
    fn try_from(w: XfHz) -> Result<Self, ParamError> {
        let param = Param::scalar("f_hz");
        if !w.f_hz.is_finite() {
            return Err(ParamError::NotFinite { param });
        }
        if w.f_hz < 0.0 {
            return Err(ParamError::OutOfRange {
                param,
                value: w.f_hz,
                min: 0.0,
                min_open: false,
                max: f64::INFINITY,
            });
        }
        let g = fraction(w.g)?;
        let x_f = positive(Param::scalar("x_f"), w.x_f)?;
        Ok(Self::hz(w.f_hz, g, x_f))
    }
}

/// [`IwanCellSpec`] as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct IwanForce {
    g: f64,
    slip_force: f64,
}

impl TryFrom<IwanForce> for IwanCellSpec {
    type Error = ParamError;
    fn try_from(w: IwanForce) -> Result<Self, ParamError> {
        let g = fraction(w.g)?;
        let f = positive(Param::scalar("slip_force"), w.slip_force)?;
        Ok(Self::new(g, f))
    }
}

/// [`FractionalSpec`] as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FractionalHz {
    f_c_hz: f64,
    alpha: f64,
    g: f64,
}

impl TryFrom<FractionalHz> for FractionalSpec {
    type Error = ParamError;
    fn try_from(w: FractionalHz) -> Result<Self, ParamError> {
        positive(Param::scalar("f_c_hz"), w.f_c_hz)?;
        let spec = Self::hz(w.f_c_hz, w.alpha, w.g);
        spec.validate()?;
        Ok(spec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::maxwell::MaxwellForm;
    use crate::stack::FirstLoading;
    use crate::xf::XfForm;
    use alloc::string::ToString;
    use serde::de::IntoDeserializer;
    use serde::de::value::{Error, MapDeserializer};

    /// Reads `T` from (key, value) pairs, as a file's table would give them.
    fn read<T: for<'de> Deserialize<'de>>(pairs: &[(&'static str, f64)]) -> Result<T, Error> {
        T::deserialize(MapDeserializer::<_, Error>::new(pairs.iter().copied()))
    }

    fn named<T: for<'de> Deserialize<'de>>(name: &'static str) -> Result<T, Error> {
        T::deserialize(IntoDeserializer::<Error>::into_deserializer(name))
    }

    #[test]
    fn specs_are_read_through_their_checks() {
        let m: MaxwellSpec = read(&[("f_hz", 2.0), ("g", 0.25)]).unwrap();
        assert_eq!(m, MaxwellSpec::hz(2.0, 0.25));
        let x: XfSpec = read(&[("f_hz", 0.0), ("g", 0.1), ("x_f", 0.02)]).unwrap();
        assert_eq!(x, XfSpec::hz(0.0, 0.1, 0.02));
        let i: IwanCellSpec = read(&[("g", 0.1), ("slip_force", 3.0)]).unwrap();
        assert_eq!(i, IwanCellSpec::new(0.1, 3.0));
        let f: FractionalSpec = read(&[("f_c_hz", 5.0), ("alpha", 0.5), ("g", 0.3)]).unwrap();
        assert_eq!(f, FractionalSpec::hz(5.0, 0.5, 0.3));
    }

    #[test]
    fn out_of_range_values_name_the_parameter_and_bound() {
        let cases = [
            (
                read::<MaxwellSpec>(&[("f_hz", f64::NAN), ("g", 0.2)]).map(|_| ()),
                "f_hz must be finite",
            ),
            (
                read::<MaxwellSpec>(&[("f_hz", 1.0), ("g", 1.5)]).map(|_| ()),
                "g = 1.5 must be in (0, 1]",
            ),
            (
                read::<XfSpec>(&[("f_hz", -1.0), ("g", 0.1), ("x_f", 0.1)]).map(|_| ()),
                "f_hz = -1 is outside [0, inf]",
            ),
            (
                read::<XfSpec>(&[("f_hz", 1.0), ("g", 0.1), ("x_f", 0.0)]).map(|_| ()),
                "x_f must be > 0 (got 0)",
            ),
            (
                read::<IwanCellSpec>(&[("g", 0.1), ("slip_force", -2.0)]).map(|_| ()),
                "slip_force must be > 0 (got -2)",
            ),
            (
                read::<FractionalSpec>(&[("f_c_hz", 1.0), ("alpha", 1.5), ("g", 0.1)]).map(|_| ()),
                "alpha = 1.5 is outside (0, 1]",
            ),
            (
                read::<MaxwellSpec>(&[("f_hz", 1.0), ("g", 0.1), ("omega", 6.0)]).map(|_| ()),
                "unknown field `omega`",
            ),
        ];
        for (got, expect) in cases {
            let text = got.unwrap_err().to_string();
            assert!(
                text.starts_with(expect),
                "{text:?} should start with {expect:?}"
            );
        }
    }

    #[test]
    fn forms_are_read_by_name() {
        for form in MaxwellForm::ALL {
            assert_eq!(named::<MaxwellForm>(form.name()).unwrap(), form);
        }
        for form in XfForm::ALL {
            assert_eq!(named::<XfForm>(form.name()).unwrap(), form);
        }
        assert_eq!(
            named::<FirstLoading>("masing").unwrap(),
            FirstLoading::Masing
        );
        assert_eq!(
            named::<FirstLoading>("ignored").unwrap(),
            FirstLoading::Ignored
        );
        let e = named::<MaxwellForm>("rate-exponential")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown variant `rate-exponential`"), "{e}");
    }
}
