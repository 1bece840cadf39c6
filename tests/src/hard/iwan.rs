//! Hard cases of Iwan banks: chatter at a turning point, forces within the
//! slip limits, drift under tiny oscillations, steps exactly at the
//! threshold.

use core::f64::consts::TAU;

use bushing::{Bushing, Effect, EffectOutput, IwanBank, IwanCellSpec, IwanSliders, Polynomial};

use super::{Measure, effect_force, worst};
use crate::check::{Failure, param};
use bushing_kernels::Noise;

type Iwan16 = Bushing<f32, Polynomial<f32, 2>, (IwanBank<f32, 16>,)>;

/// 16 Jenkins cells on 150 N/mm, slip distances 0.02 to 1.5 mm (log),
/// total fraction 0.4; returns the bushing and the sum of slip forces.
fn iwan16() -> Result<(Iwan16, f64), Failure> {
    let (_, limits, cells) = jenkins16();
    let bank = IwanBank::new(&cells).map_err(param)?;
    let b = Bushing::new(Polynomial::linear(150.0).map_err(param)?, (bank,)).map_err(param)?;
    Ok((b, limits))
}

/// The cells of [`iwan16`]: (count, sum of slip forces, cells).
fn jenkins16() -> (usize, f64, [IwanCellSpec; 16]) {
    let mut cells = [IwanCellSpec::new(0.1, 1.0); 16];
    let ratio = libm::pow(75.0, 1.0 / 15.0);
    let mut x_f = 0.02;
    let mut limits = 0.0;
    for c in &mut cells {
        *c = IwanCellSpec::from_slip_distance(0.4 / 16.0, 150.0, x_f);
        limits += c.slip_force;
        x_f *= ratio;
    }
    (cells.len(), limits, cells)
}

pub(super) fn iwan_chatter_at_turning_point() -> Measure {
    let (b, _) = iwan16()?;
    let (mut clean, mut noisy) = (b.state_at(0.0), b.state_at(0.0));
    let mut rng = Noise::new(3);
    let per = 400usize;
    let x = |n: usize| 2.0 * libm::sin(TAU * n as f64 / per as f64);
    let (mut w, mut amplitude) = (0.0f64, 0.0f64);
    // Up to the crest (n = per/4), 100 steps of noise below it (up to
    // 0.5 x_f,min: the crest stays the highest turning point), then on
    // along the sine for one and a half periods. Each noisy step may round
    // each sticking cell's force by half an ulp: 100 steps and 16 cells
    // stay below 1e-5 of the amplitude.
    for n in 1..=per / 4 {
        effect_force(&b, &mut clean, x(n) as f32);
        effect_force(&b, &mut noisy, x(n) as f32);
    }
    let crest = x(per / 4);
    for _ in 0..100 {
        let jitter = -0.01 * rng.uniform();
        effect_force(&b, &mut noisy, (crest + jitter) as f32);
    }
    for n in per / 4 + 1..=2 * per {
        let fc = effect_force(&b, &mut clean, x(n) as f32) as f64;
        let fnoisy = effect_force(&b, &mut noisy, x(n) as f32) as f64;
        amplitude = amplitude.max(libm::fabs(fc));
        // Once the path is more than the noise band below the crest, the
        // inner loops are wiped out.
        if x(n) < crest - 0.02 || n > per / 2 {
            w = worst(w, libm::fabs(fc - fnoisy));
        }
    }
    Ok(w / amplitude)
}

pub(super) fn iwan_force_within_slip_limits() -> Measure {
    let (b, limits) = iwan16()?;
    let mut s = b.state_at(0.0);
    let mut rng = Noise::new(7);
    let mut w = 0.0f64;
    for n in 0..4000 {
        let x = 3.0 * libm::sin(TAU * n as f64 / 500.0) + 0.05 * rng.gauss();
        let f = effect_force(&b, &mut s, x as f32) as f64;
        w = worst(w, libm::fabs(f) / limits);
    }
    Ok(w)
}

pub(super) fn iwan_clamp_drift_within_rounding() -> Measure {
    let (b, limits) = iwan16()?;
    let (drift, start, steps) = tiny_oscillation_drift(&b)?;
    // A sticking cell's force is rounded once per step, by at most half an
    // ulp of a value below its slip force: 2^-24 F_f,i per cell and step.
    let rounding = steps as f64 * limits * libm::pow(2.0, -24.0);
    Ok(drift * libm::fabs(start) / rounding)
}

/// Relative force drift of `b` preloaded to 1 mm then oscillating by
/// 2e-6 mm for 100 000 steps; also the preload force and the step count.
fn tiny_oscillation_drift<E: Effect<f32, Report = EffectOutput<f32>>>(
    b: &Bushing<f32, Polynomial<f32, 2>, (E,)>,
) -> Result<(f64, f64, usize), Failure> {
    let mut s = b.state_at(0.0);
    // Preload to 1 mm (some cells slip), then oscillate by 2e-6 mm.
    for n in 1..=100 {
        effect_force(b, &mut s, 0.01 * n as f32);
    }
    // The first move up lets the cells at their slip force slide by the
    // step once (Masing): measure from after that cycle.
    effect_force(b, &mut s, 1.000_002);
    let start = effect_force(b, &mut s, 1.0) as f64;
    let steps = 100_000;
    let mut end = start;
    for n in 0..steps {
        let x = if n % 2 == 0 { 1.000_002f32 } else { 1.0 };
        end = effect_force(b, &mut s, x) as f64;
    }
    if !end.is_nan() {
        end = effect_force(b, &mut s, 1.0) as f64;
    }
    Ok((libm::fabs(end - start) / libm::fabs(start), start, steps))
}

pub(super) fn iwan_sliders_tiny_oscillations_do_not_drift() -> Measure {
    let (_, _, cells) = jenkins16();
    let bank = IwanSliders::<f32, 16>::new(&cells, 150.0).map_err(param)?;
    let b = Bushing::new(Polynomial::linear(150.0).map_err(param)?, (bank,)).map_err(param)?;
    Ok(tiny_oscillation_drift(&b)?.0)
}

pub(super) fn iwan_steps_exactly_at_threshold() -> Measure {
    // One cell, g = 0.5 on 100 N/mm, slip distance 0.25 mm: slip force
    // 12.5 N is reached by a step of exactly 0.25 mm.
    let spec = IwanCellSpec::from_slip_distance(0.5, 100.0, 0.25);
    let bank = IwanBank::<f32, 1>::new(&[spec]).map_err(param)?;
    let b = Bushing::new(Polynomial::<f32, 2>::linear(100.0).map_err(param)?, (bank,))
        .map_err(param)?;
    let limit = spec.slip_force;
    let mut s = b.state_at(0.0);
    let mut w = 0.0f64;
    let mut x = 0.0f32;
    for k in 0..40 {
        // Up and down by exactly twice the slip distance, then hold and
        // step by the slip distance.
        x += if k % 4 < 2 { 0.25 } else { -0.25 };
        let f = effect_force(&b, &mut s, x) as f64;
        if k % 4 == 1 || k % 4 == 3 {
            w = worst(w, libm::fabs(libm::fabs(f) - limit) / limit);
        }
        w = worst(w, (libm::fabs(f) - limit).max(0.0) / limit);
    }
    Ok(w)
}
