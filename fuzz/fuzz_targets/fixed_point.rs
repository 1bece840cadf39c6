//! The `FixedPoint` family of `bushing_fuzz` alone.
#![no_main]

use bushing_fuzz::Family;
libfuzzer_sys::fuzz_target!(|data: &[u8]| bushing_fuzz::run(Family::FixedPoint, data));
