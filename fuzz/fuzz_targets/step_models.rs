//! Any model family of the core, picked by the first byte (see
//! `bushing_fuzz::Family`): construction ends in a model or a typed error,
//! a step never panics, a refused step keeps the force and an accepted one
//! stays finite and within the guard.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| bushing_fuzz::run_any(data));
