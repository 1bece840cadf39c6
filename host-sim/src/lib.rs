//! # bushing-sim: scenes, traces, plots and accuracy reports
//!
//! The host side of the `bushing` library. A *scene* (TOML, see
//! `docs/scenes.md`) names a backbone, the effects to simulate with their
//! parameters, the rate, the number type and a displacement profile;
//! [`run::run`] builds only those effects, steps them and writes a CSV
//! trace and SVG plots. [`modulus`] measures the steady-state complex
//! modulus of the Maxwell forms against the closed form.
#![forbid(unsafe_code)]

#[macro_use]
mod tagged;

pub mod accuracy_cost;
pub mod cli;
pub mod compare;
pub mod cost;
pub mod csv_text;
pub mod family;
pub mod fit;
pub mod fmu;
pub mod fractional_report;
pub mod harmonic;
pub mod identify;
pub mod iwan_report;
pub mod markdown;
pub mod model;
pub mod modulus;
pub mod output;
pub mod plot;
pub mod powertrain;
pub mod probe;
pub mod profile;
pub mod records;
pub mod reference;
pub mod run;
pub mod scene;
pub mod validate;
pub mod xf_report;

pub use scene::{Scene, SceneError};
