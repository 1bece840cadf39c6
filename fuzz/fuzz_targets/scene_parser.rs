//! Any bytes as a scene file: parsing must end in a scene or a typed
//! error, never a panic; a scene that parses is built in its number type
//! and stepped over its first 64 steps by the one stepping pipeline of
//! `run` and `validate`.
#![no_main]

use bushing_sim::Scene;
use bushing_sim::model;
use bushing_sim::run::{self, RunError, Sink, Step};
use bushing_sim::scene::NumberType;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scene) = Scene::parse("fuzz.toml", text) else {
        return;
    };
    match scene.number {
        NumberType::F32 => step::<f32>(&scene),
        NumberType::F64 => step::<f64>(&scene),
    }
});

/// Counts the steps the pipeline hands over.
struct Count(u64);

impl<T: bushing::Real> Sink<T> for Count {
    fn step(&mut self, s: &Step<'_, T>) -> Result<(), RunError> {
        self.0 += 1;
        assert_eq!(s.index, self.0, "steps in order from 1");
        Ok(())
    }
}

fn step<T: bushing::Real + 'static>(scene: &Scene) {
    let Ok(mut bushing) = model::compile::<T>(scene) else {
        return;
    };
    let steps = scene.steps().min(64);
    let mut count = Count(0);
    let stepped = run::drive_steps(scene, bushing.as_mut(), steps, &mut [&mut count]);
    assert!(stepped.is_ok(), "a counting sink never fails");
    assert_eq!(count.0, steps, "one row per step");
}
