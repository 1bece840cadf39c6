//! Backbones alone: `Polynomial::new` of two to six coefficients,
//! `Polynomial::linear` and `MonotoneSpline::new`, each on a bushing with
//! no effect.

use arbitrary::{Result, Unstructured};
use bushing::Polynomial;

use crate::contract::{built, drive};
use crate::draw::{decades, polynomial, spline};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    match u.int_in_range(0u8..=4)? {
        0 => {
            if let Some(p) = built(Polynomial::<T, 2>::linear(decades(u, 1e-3, 1e6)?)) {
                drive(u, p, ())?;
            }
        }
        1 => {
            if let Some(p) = polynomial::<T, 2>(u)? {
                drive(u, p, ())?;
            }
        }
        2 => {
            if let Some(p) = polynomial::<T, 6>(u)? {
                drive(u, p, ())?;
            }
        }
        3 => {
            if let Some(s) = spline::<T, 3>(u)? {
                drive(u, s, ())?;
            }
        }
        _ => {
            if let Some(s) = spline::<T, 8>(u)? {
                drive(u, s, ())?;
            }
        }
    }
    Ok(())
}
