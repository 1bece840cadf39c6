//! Any bytes as a scene file: parsing must end in a scene or a typed
//! error, never a panic; a scene that parses is built in its number type
//! and stepped over its first 64 steps.
#![no_main]

use bushing_sim::Scene;
use bushing_sim::scene::NumberType;
use bushing_sim::{model, profile};
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

fn step<T: bushing::Real + 'static>(scene: &Scene) {
    let Ok(mut bushing) = model::compile::<T>(scene) else {
        return;
    };
    let inputs: Vec<T> = (1..=scene.steps().min(64))
        .map(|n| T::from_f64(profile::displacement(&scene.profile, n as f64 * scene.dt)))
        .collect();
    let (mut rows, mut parts) = (Vec::new(), Vec::new());
    bushing.step_into(&inputs, &mut rows, &mut parts);
    assert_eq!(rows.len(), inputs.len(), "one row per step");
}
