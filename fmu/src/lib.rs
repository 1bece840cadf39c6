//! The FMI 2.0 co-simulation entry points of the bushing FMU.
//!
//! `bushing-sim fmu` packs this crate's shared library as
//! `binaries/linux64/bushing.so` beside the model (`resources/model.toml`)
//! and its `modelDescription.xml`. Everything the FMU does is
//! [`bushing_sim::fmu::Slave`], safe Rust; this crate only turns C
//! arguments into its calls and its answers into `fmi2Status` codes and
//! log messages (see `docs/fmu.md`).
//!
//! Every `unsafe` is here, at the boundary: reading the master's
//! pointers, and the instance and FMU-state handles that are `Box`es
//! handed out as raw pointers. Each entry point checks its pointers for
//! null and runs inside [`std::panic::catch_unwind`], so that a failure
//! inside the FMU is `fmi2Fatal` and a logged message, never a crash of
//! the master.
// Every `unsafe` block says why it holds.
#![deny(clippy::undocumented_unsafe_blocks)]

mod boundary;
mod entry;

pub use boundary::{
    CallbackFunctions, FMI2_COSIMULATION, FMI2_DISCARD, FMI2_ERROR, FMI2_FATAL, FMI2_OK,
    FMI2_WARNING, Fmi2Status, Instance, Logger,
};
pub use entry::*;
