//! The stepping pass every cost figure times: a bushing stepped from rest
//! through precomputed inputs, reading what a control loop reads.

use std::time::Duration;

use bushing::{Backbone, Bushing, Effect, Real};

/// Steps `bushing` from rest at `x0` through `inputs`, reading force,
/// tangent and dissipated energy as a control loop does, and returns the
/// wall-clock time of the steps. Never inlined, so that an instruction
/// counter can select it by name (`cost --instructions`).
#[inline(never)]
pub fn stepping_pass<T: Real, B: Backbone<T>, E: Effect<T>>(
    bushing: &Bushing<T, B, E>,
    inputs: &[T],
    x0: T,
) -> Duration {
    let mut state = bushing.state_at(x0);
    let start = std::time::Instant::now();
    for &x in inputs {
        let o = bushing.step(&mut state, x);
        std::hint::black_box((o.force, o.tangent, o.dissipated));
    }
    start.elapsed()
}

/// Name of [`stepping_pass`], for callgrind's `--toggle-collect`.
pub const STEPPING: &str = "stepping_pass";

/// Nanoseconds per input.
pub fn per_step<T>(elapsed: Duration, inputs: &[T]) -> f64 {
    elapsed.as_secs_f64() * 1e9 / inputs.len().max(1) as f64
}

/// Something timed per step on `(inputs, x0)`: nanoseconds per input.
pub type Timer<T> = Box<dyn Fn(&[T], T) -> f64>;

/// The timer of one bushing.
pub fn timer<T: Real + 'static, B: Backbone<T> + 'static, E: Effect<T> + 'static>(
    b: Bushing<T, B, E>,
) -> Timer<T> {
    Box::new(move |inputs, x0| per_step(stepping_pass(&b, inputs, x0), inputs))
}
