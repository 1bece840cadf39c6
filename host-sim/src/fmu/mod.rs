//! The bushing as an FMI 2.0 co-simulation FMU (`bushing-sim fmu`,
//! `docs/fmu.md`).
//!
//! - [`resource`]: the model the FMU carries in `resources/model.toml`
//!   (a scene's model part) and the GUID that ties it to the description;
//! - [`description`]: the variables and `modelDescription.xml`;
//! - [`package`]: the `.fmu` archive;
//! - [`slave`]: what the FMU's library runs, FMI's state machine in safe
//!   Rust (the C entry points are the crate `bushing-fmu`).

pub mod description;
pub mod package;
pub mod resource;
pub mod slave;

pub use description::{MODEL_IDENTIFIER, Variable, model_description, variables};
pub use package::{LIBRARY_FILE, check_out, find_library, write_fmu};
pub use resource::{FmuModel, RESOURCE_FILE, guid, resource_dir};
pub use slave::{FmuState, Phase, Report, Slave, Status};

/// What can go wrong making or loading an FMU.
#[derive(Debug, thiserror::Error)]
pub enum FmuError {
    /// The scene or resource model cannot be read or checked.
    #[error(transparent)]
    Scene(Box<crate::scene::SceneError>),
    /// A scene the FMU cannot carry.
    #[error("{0}")]
    Unsupported(String),
    /// The FMU library is missing or is not one.
    #[error("{0}")]
    Library(String),
    /// The resource location given by the master.
    #[error("{0}")]
    Resource(String),
    /// A bad output path.
    #[error("{0}")]
    Usage(String),
    /// Reading or writing a file.
    #[error("{0}")]
    Io(String),
}
#[cfg(test)]
mod tests;
