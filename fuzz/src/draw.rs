//! Parameters, inputs and backbones drawn from the fuzzer's bytes.

use arbitrary::{Result, Unstructured};
use bushing::{Backbone, MonotoneSpline, ParamError, Polynomial};

use crate::num::Num;

/// The model, or `None` after forming the error's text (the construction
/// half of the contract of [`crate::contract`]).
pub fn built<M>(r: core::result::Result<M, ParamError>) -> Option<M> {
    match r {
        Ok(m) => Some(m),
        Err(e) => {
            let _ = e.to_string();
            None
        }
    }
}

/// A parameter: mostly in `[lo, hi]`, sometimes a special value or any
/// bit pattern.
pub fn param(u: &mut Unstructured<'_>, lo: f64, hi: f64) -> Result<f64> {
    Ok(match u.int_in_range(0u8..=7)? {
        0 => f64::from_bits(u.arbitrary()?),
        1 => *u.choose(&[0.0, -0.0, f64::NAN, f64::INFINITY, -1.0, 1e308, 1e-308])?,
        _ => lo + (hi - lo) * (u.int_in_range(0u32..=1 << 20)? as f64 / (1 << 20) as f64),
    })
}

/// A parameter spread over decades: mostly log-uniform in `[lo, hi]`
/// (both positive), sometimes what [`param`] gives.
pub fn decades(u: &mut Unstructured<'_>, lo: f64, hi: f64) -> Result<f64> {
    if u.ratio(1u8, 4)? {
        return param(u, lo, hi);
    }
    let t = u.int_in_range(0u32..=1 << 20)? as f64 / (1 << 20) as f64;
    Ok(lo * (hi / lo).powf(t))
}

/// A time step in seconds, 10 µs to 10 ms.
pub fn time_step(u: &mut Unstructured<'_>) -> Result<f64> {
    decades(u, 1e-5, 1e-2)
}

/// A sequence of inputs (displacements, forces, node coordinates): each
/// one any bit pattern of the working type, a special value, a small move
/// from the last one (turning points, sticking cells) or a jump within
/// `±scale`.
#[derive(Debug, Clone, Copy)]
pub struct Path<T> {
    last: T,
    scale: f64,
}

impl<T: Num> Path<T> {
    /// Inputs within `±scale`, starting at 0.
    pub fn new(scale: f64) -> Self {
        Self {
            last: T::ZERO,
            scale,
        }
    }

    /// The next input.
    pub fn next(&mut self, u: &mut Unstructured<'_>) -> Result<T> {
        let guard = T::GUARD.to_f64();
        let x = match u.int_in_range(0u8..=15)? {
            0 => T::any(u)?,
            1 => T::from_f64(*u.choose(&[
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
                1e30,
                -1e30,
                0.0,
                guard,
                -guard,
                2.0 * guard,
                0.5 * guard,
            ])?),
            2..=6 => {
                self.last + T::from_f64(self.scale * 1e-4 * u.int_in_range(-1000i32..=1000)? as f64)
            }
            _ => T::from_f64(self.scale * 1e-4 * u.int_in_range(-10_000i32..=10_000)? as f64),
        };
        self.last = x;
        Ok(x)
    }
}

/// Either backbone of the core, so that every family can run on both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnyBackbone<T> {
    /// A cubic on a range, extended linearly.
    Polynomial(Polynomial<T, 4>),
    /// A monotone spline through up to 8 points.
    Spline(MonotoneSpline<T, 8>),
}

impl<T: Num> Backbone<T> for AnyBackbone<T> {
    fn eval(&self, x: T) -> (T, T) {
        match self {
            Self::Polynomial(p) => p.eval(x),
            Self::Spline(s) => s.eval(x),
        }
    }
}

/// `k x + a x^2 + b x^3` on `[lo, hi]`, with up to `N` coefficients (one
/// more, or one only, now and then: `TooMany`, `TooFew`).
pub fn polynomial<T: Num, const N: usize>(
    u: &mut Unstructured<'_>,
) -> Result<Option<Polynomial<T, N>>> {
    let mut c = [0.0; 8];
    let n = u.int_in_range(1..=(N + 1).min(c.len()))?;
    for (k, ck) in c.iter_mut().enumerate().take(n) {
        *ck = match k {
            0 => param(u, -10.0, 10.0)?,
            1 => decades(u, 1.0, 1e3)?,
            _ => param(u, -10.0, 10.0)? / (k * k) as f64,
        };
    }
    let range = (param(u, -20.0, -1.0)?, param(u, 1.0, 20.0)?);
    Ok(built(Polynomial::new(&c[..n], range)))
}

/// A monotone spline through up to `N` points (sometimes more, or
/// mismatched lengths), mostly increasing in x and in force.
pub fn spline<T: Num, const N: usize>(
    u: &mut Unstructured<'_>,
) -> Result<Option<MonotoneSpline<T, N>>> {
    let (mut xs, mut fs) = ([0.0; 10], [0.0; 10]);
    let n = u.int_in_range(0..=(N + 1).min(xs.len()))?;
    let (mut x, mut f) = (param(u, -10.0, -1.0)?, param(u, -1e3, 0.0)?);
    for (xi, fi) in xs.iter_mut().zip(fs.iter_mut()).take(n) {
        (*xi, *fi) = (x, f);
        x += param(u, 0.0, 5.0)?;
        f += param(u, 0.0, 500.0)?;
    }
    let m = if u.ratio(1u8, 16)? {
        n.saturating_sub(1)
    } else {
        n
    };
    Ok(built(MonotoneSpline::new(&xs[..n], &fs[..m])))
}

/// A backbone for a model under test: mostly a cubic, sometimes a spline,
/// and a plausible cubic when the drawn one is refused.
pub fn backbone<T: Num>(u: &mut Unstructured<'_>) -> Result<AnyBackbone<T>> {
    if u.ratio(1u8, 4)?
        && let Some(s) = spline::<T, 8>(u)?
    {
        return Ok(AnyBackbone::Spline(s));
    }
    Ok(AnyBackbone::Polynomial(match polynomial::<T, 4>(u)? {
        Some(p) => p,
        None => fallback(),
    }))
}

/// The cubic of the examples, 150 N/mm hardening, on ±6 mm.
pub fn fallback<T: Num>() -> Polynomial<T, 4> {
    Polynomial::new(&[0.0, 150.0, 0.0, 4.0], (-6.0, 6.0)).expect("the fallback backbone")
}

/// The load fraction of one of `n` cells: mostly a share of one.
pub fn fraction(u: &mut Unstructured<'_>, n: usize) -> Result<f64> {
    param(u, 0.0, 1.0 / n.max(1) as f64)
}
