//! Shared pieces of the firmware examples: the rig loop, and on the
//! Cortex-M targets the cost probe, the memory report and the defmt
//! logger. The kernels the firmware measures are built by
//! `bushing-kernels`, which the host reports, benchmarks and tests use as
//! well.
#![no_std]
// Only `memory` (linker symbols and stack painting) and `log` (the defmt
// logger's shared state) need `unsafe`.
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
pub mod log;
#[cfg(target_os = "none")]
pub mod memory;
#[cfg(target_os = "none")]
pub mod probe;
pub mod rig;
