//! Backbones in f32: the polynomial against f64, the monotone spline's
//! force and tangent.

use bushing::{Backbone, MonotoneSpline, Polynomial};

use crate::check::{CaseResult, at_most, holds, param};

pub(crate) fn polynomial_f32_matches_f64() -> CaseResult {
    let c = [0.0, 200.0, 0.0, 8.0];
    let p32 = Polynomial::<f32, 4>::new(&c, (-5.0, 5.0)).map_err(param)?;
    let p64 = Polynomial::<f64, 4>::new(&c, (-5.0, 5.0)).map_err(param)?;
    let mut worst = 0.0f64;
    for i in -700..=700 {
        let x = i as f64 * 0.01;
        let (f32v, k32) = p32.eval(x as f32);
        let (f64v, k64) = p64.eval(x);
        worst = worst.max((f32v as f64 - f64v).abs() / (1.0 + f64v.abs()));
        worst = worst.max((k32 as f64 - k64).abs() / k64);
    }
    at_most("relative f32 error of force and tangent", worst, 1e-6)
}

pub(crate) fn spline_f32_monotone_positive_tangent() -> CaseResult {
    let xs = [-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0];
    let fs = [-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0];
    let s = MonotoneSpline::<f32, 8>::new(&xs, &fs).map_err(param)?;
    let mut prev = f32::NEG_INFINITY;
    let mut min_k = f32::INFINITY;
    for i in 0..=4000 {
        let x = -5.0 + 10.0 * i as f32 / 4000.0;
        let (f, k) = s.eval(x);
        holds("spline force increases", f >= prev)?;
        prev = f;
        min_k = min_k.min(k);
    }
    holds("spline tangent positive", min_k > 0.0)
}
