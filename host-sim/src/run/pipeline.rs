//! The one stepping loop of the scenes: the profile is read through the
//! scene's ADC, the model steps a chunk at a time (timed, with no I/O
//! inside), and every step is then handed to each [`Sink`] in turn: for
//! `run` the trace, the plots, the modulus probe and the progress bar; for
//! `validate` its steady-cycle window.

use std::time::Instant;

use bushing::{EffectOutput, Real};

use crate::model::{SceneModel, StepRow};
use crate::scene::Scene;

/// Steps per timed chunk.
pub const CHUNK: usize = 4096;

/// One step as the sinks see it.
#[derive(Debug, Clone, Copy)]
pub struct Step<'a, T: Real> {
    /// Step number, from 1.
    pub index: u64,
    /// Time at the end of the step, s.
    pub time: f64,
    /// The profile's value at `time`, read through the scene's ADC, in
    /// f64 (before the conversion to the working type).
    pub demand: f64,
    /// The input the model read (displacement, or force for an
    /// oscillator scene).
    pub input: T,
    /// The model's outputs.
    pub row: &'a StepRow<T>,
    /// Each effect's output, in the scene's order (empty when refused).
    pub parts: &'a [EffectOutput<T>],
}

/// Something that takes every step of a run.
pub trait Sink<T: Real> {
    /// One step.
    fn step(&mut self, step: &Step<'_, T>) -> Result<(), super::RunError>;
    /// The end of a chunk of steps, `done` of them so far.
    fn chunk_done(&mut self, _done: u64) {}
}

/// Steps `model` over the scene's whole profile, handing every step to
/// `sinks`, and returns the seconds spent stepping alone.
pub fn drive<T: Real>(
    scene: &Scene,
    model: &mut dyn SceneModel<T>,
    sinks: &mut [&mut dyn Sink<T>],
) -> Result<f64, super::RunError> {
    drive_steps(scene, model, scene.steps(), sinks)
}

/// [`drive`] over the first `steps` steps only.
pub fn drive_steps<T: Real>(
    scene: &Scene,
    model: &mut dyn SceneModel<T>,
    steps: u64,
    sinks: &mut [&mut dyn Sink<T>],
) -> Result<f64, super::RunError> {
    let count = model.effect_count();
    let mut demands = Vec::with_capacity(CHUNK);
    let mut inputs = Vec::with_capacity(CHUNK);
    let mut rows: Vec<StepRow<T>> = Vec::with_capacity(CHUNK);
    let mut parts = Vec::with_capacity(CHUNK * count);
    let mut busy = 0.0f64;
    let mut n = 0u64;
    while n < steps {
        let len = (steps - n).min(CHUNK as u64) as usize;
        inputs.clear();
        demands.clear();
        for k in 0..len as u64 {
            let t = (n + 1 + k) as f64 * scene.dt;
            let demand = scene.input(t);
            demands.push(demand);
            inputs.push(T::from_f64(demand));
        }
        rows.clear();
        parts.clear();
        let start = Instant::now();
        crate::model::step_scene(scene, model, n, &inputs, &mut rows, &mut parts)?;
        busy += start.elapsed().as_secs_f64();
        for (k, ((input, demand), row)) in inputs.iter().zip(&demands).zip(&rows).enumerate() {
            let index = n + 1 + k as u64;
            let step = Step {
                index,
                time: index as f64 * scene.dt,
                demand: *demand,
                input: *input,
                row,
                parts: if row.refused {
                    &[]
                } else {
                    parts.get(k * count..(k + 1) * count).unwrap_or_default()
                },
            };
            for sink in sinks.iter_mut() {
                sink.step(&step)?;
            }
        }
        n += len as u64;
        for sink in sinks.iter_mut() {
            sink.chunk_done(n);
        }
    }
    Ok(busy)
}
