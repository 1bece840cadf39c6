//! The turning-point stack: `Sts` and `KfTable` laws on `TurningPoints` of
//! capacity 2, 3, 8 or 64, with Masing's first loading or without.

use arbitrary::{Result, Unstructured};
use bushing::stack::Relaxation;
use bushing::{FirstLoading, KfTable, Sts, TurningPoints};

use crate::contract::{built, drive};
use crate::draw::{backbone, decades, param};
use crate::num::Num;

pub fn fuzz<T: Num>(u: &mut Unstructured<'_>) -> Result<()> {
    let first = if u.arbitrary()? {
        FirstLoading::Masing
    } else {
        FirstLoading::Ignored
    };
    if u.arbitrary()? {
        match sts::<T>(u)? {
            Some(law) => capacity(u, law, first),
            None => Ok(()),
        }
    } else {
        match kf_table::<T, 8>(u)? {
            Some(law) => capacity(u, law, first),
            None => Ok(()),
        }
    }
}

/// An STS law of C and K_1.
pub fn sts<T: Num>(u: &mut Unstructured<'_>) -> Result<Option<Sts<T>>> {
    Ok(built(Sts::new(
        decades(u, 1.0, 1e4)?,
        decades(u, 1.0, 1e3)?,
    )))
}

/// A K_f(d) table of up to `M` points (sometimes one more, or lengths
/// that differ), mostly increasing in d and non-increasing in K_f.
pub fn kf_table<T: Num, const M: usize>(u: &mut Unstructured<'_>) -> Result<Option<KfTable<T, M>>> {
    let (mut d, mut k) = ([0.0; 16], [0.0; 16]);
    let n = u.int_in_range(0..=(M + 1).min(d.len()))?;
    let (mut di, mut ki) = (param(u, 0.0, 1.0)?, decades(u, 1.0, 1e3)?);
    for (dj, kj) in d.iter_mut().zip(k.iter_mut()).take(n) {
        (*dj, *kj) = (di, ki);
        di += decades(u, 1e-3, 5.0)?;
        ki *= param(u, 0.0, 1.0)?;
    }
    let m = if u.ratio(1u8, 16)? {
        n.saturating_sub(1)
    } else {
        n
    };
    Ok(built(KfTable::new(&d[..n], &k[..m])))
}

fn capacity<T: Num, R: Relaxation<T>>(
    u: &mut Unstructured<'_>,
    law: R,
    first: FirstLoading,
) -> Result<()> {
    let backbone = backbone::<T>(u)?;
    match u.int_in_range(0u8..=3)? {
        0 => drive(u, backbone, (TurningPoints::<R, 2>::new(law, first),)),
        1 => drive(u, backbone, (TurningPoints::<R, 3>::new(law, first),)),
        2 => drive(u, backbone, (TurningPoints::<R, 8>::new(law, first),)),
        _ => drive(u, backbone, (TurningPoints::<R, 64>::new(law, first),)),
    }
}
