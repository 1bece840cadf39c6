//! Hard cases of turning-point stacks: overflow, and Masing's factor on
//! first loading.

use bushing::stack::{Relaxation, Sts};

use super::{Measure, effect_force, failure, worst};
use crate::check::param;
use crate::stack::sts_bushing;

pub(super) fn turning_point_stack_overflow() -> Measure {
    let small = sts_bushing::<4>()?;
    let big = sts_bushing::<32>()?;
    let (mut ss, mut sb) = (small.state_at(0.0), big.state_at(0.0));
    let law = Sts::<f32>::new(400.0, 300.0).map_err(param)?;
    let mut x = 0.0f32;
    let mut w = 0.0f64;
    let mut turns = [0.0f32; 21];
    for (i, t) in turns.iter_mut().enumerate().take(11) {
        let a = 3.0 - 0.25 * i as f32;
        *t = if i % 2 == 0 { a } else { -a };
    }
    for i in 11..21 {
        let back = turns.get(20 - i).copied().unwrap_or(0.0);
        if let Some(t) = turns.get_mut(i) {
            *t = back;
        }
    }
    for &p in &turns {
        for k in 1..=50 {
            let v = if k == 50 {
                p
            } else {
                x + (p - x) * k as f32 / 50.0
            };
            let fs = effect_force(&small, &mut ss, v);
            let fb = effect_force(&big, &mut sb, v);
            let bound = law.branch(ss.effects().0.dropped_span()).0;
            w = worst(w, ((fs - fb).abs() - bound) as f64);
        }
        x = p;
    }
    if ss.effects().0.overflows() == 0 {
        return Err(failure("the small stack never overflowed", 0.0));
    }
    Ok(w)
}

pub(super) fn first_loading_masing_factor() -> Measure {
    let b = sts_bushing::<8>()?;
    let mut s = b.state_at(0.0);
    let mut virgin = [0.0f32; 201];
    for (k, v) in virgin.iter_mut().enumerate().skip(1) {
        *v = effect_force(&b, &mut s, 0.01 * k as f32);
    }
    let ft = virgin.last().copied().unwrap_or(f32::NAN);
    let mut w = 0.0f64;
    for (k, v) in virgin.iter().enumerate().skip(1) {
        let f = effect_force(&b, &mut s, 2.0 - 0.02 * k as f32);
        let twice = 2.0 * v;
        w = worst(w, ((ft - f - twice).abs() / twice) as f64);
    }
    Ok(w)
}
