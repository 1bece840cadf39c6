//! Turning-point stacks: Masing's factor two and Madelung's rule with an
//! overflowing stack.

use bushing::stack::{FirstLoading, Relaxation, Sts, TurningPoints};
use bushing::{Bushing, Polynomial};

use crate::check::{CaseResult, Failure, at_most, holds, param};

type StsBushing<const M: usize> = Bushing<f32, Polynomial<f32, 2>, (TurningPoints<Sts<f32>, M>,)>;

pub(crate) fn sts_bushing<const M: usize>() -> Result<StsBushing<M>, Failure> {
    let law = Sts::new(400.0, 300.0).map_err(param)?;
    Bushing::new(
        Polynomial::linear(100.0).map_err(param)?,
        (TurningPoints::new(law, FirstLoading::Masing),),
    )
    .map_err(param)
}

pub(crate) fn stack_masing_f32() -> CaseResult {
    // Virgin loading to 2, then a reversal: F_T - F(2 - d) = 2 F_v(d / 2).
    let b = sts_bushing::<8>()?;
    let mut s = b.state_at(0.0);
    let mut virgin = [0.0f32; 201];
    for (k, v) in virgin.iter_mut().enumerate().skip(1) {
        *v = b
            .step(&mut s, 0.01 * k as f32)
            .effects
            .map_or(f32::NAN, |r| r.0.force);
    }
    let ft = virgin[200];
    let mut worst = 0.0f64;
    for (k, v) in virgin.iter().enumerate().skip(1) {
        let d = 0.02 * k as f32;
        let f = b
            .step(&mut s, 2.0 - d)
            .effects
            .map_or(f32::NAN, |r| r.0.force);
        let twice = 2.0 * v;
        worst = worst.max(((ft - f - twice).abs() / twice) as f64);
    }
    at_most(
        "reversal over twice the virgin curve at d/2, relative",
        worst,
        1e-5,
    )
}

pub(crate) fn stack_madelung_overflow_f32() -> CaseResult {
    let small = sts_bushing::<4>()?;
    let big = sts_bushing::<32>()?;
    let (mut ss, mut sb) = (small.state_at(0.0), big.state_at(0.0));
    // Nested loops ten deep, then back out through every turning point.
    let mut turns = [0.0f32; 21];
    for (i, t) in turns.iter_mut().enumerate().take(11) {
        let a = 3.0 - 0.25 * i as f32;
        *t = if i % 2 == 0 { a } else { -a };
    }
    for i in 11..21 {
        turns[i] = turns[20 - i];
    }
    let law = Sts::<f32>::new(400.0, 300.0).map_err(param)?;
    let mut x = 0.0f32;
    let mut at_turn = [0.0f32; 21];
    for (i, &p) in turns.iter().enumerate() {
        for k in 1..=50 {
            let v = if k == 50 {
                p
            } else {
                x + (p - x) * k as f32 / 50.0
            };
            let fs = small
                .step(&mut ss, v)
                .effects
                .map_or(f32::NAN, |r| r.0.force);
            let fb = big.step(&mut sb, v).effects.map_or(f32::NAN, |r| r.0.force);
            let bound = law.branch(ss.effects().0.dropped_span()).0;
            at_most(
                "overflow error over H(dropped span)",
                ((fs - fb).abs() - bound) as f64,
                1e-3,
            )?;
            if k == 50 {
                at_turn[i] = fb;
            }
        }
        x = p;
    }
    holds("the small stack overflowed", ss.effects().0.overflows() > 0)?;
    // Coming back out, every turning point's force is found again.
    let mut worst = 0.0f64;
    for i in 11..21 {
        worst =
            worst.max(((at_turn[i] - at_turn[20 - i]).abs() / at_turn[i].abs().max(1.0)) as f64);
    }
    at_most("Madelung return, relative", worst, 1e-5)
}
