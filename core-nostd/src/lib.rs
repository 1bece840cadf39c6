//! # bushing: real-time models of rubber bushings and bolted joints
//!
//! Fixed-step, allocation-free, panic-free models for test-rig controller
//! firmware, after the recursive schemes of R. Penas, *Models of dissipative
//! bushings in multibody dynamics* (2021), "seed 000" in the project docs.
//!
//! A bushing force is a hyperelastic **backbone** F^∞(x) ([`backbone`]) plus
//! dissipative **effects** that take fractions g^i of it: the generalised
//! Maxwell cells of [`maxwell`] in all five discrete forms of the thesis,
//! the Iwan banks of Jenkins cells of [`iwan`] (force-saturation and slider
//! forms) and the nonlinear viscous x_f cells of [`xf`], between
//! viscoelasticity and friction. The order-independent hysteresis laws
//! (a measured K_f(d) or the continuous STS) run on the turning-point stack
//! of [`stack`]; [`discretize`] turns them, and Segalman's four-parameter
//! Iwan, into banks of Jenkins cells; [`friction`] holds the Dahl, Bouc-Wen
//! and Berg cells the thesis compares them with. A [`Bushing`] joins them;
//! effects compose as tuples at compile time, so an effect a firmware build
//! does not name costs nothing. [`fractional`] holds the order-independent
//! fractional-derivative cell (truncated Grünwald sum), which the host crate
//! replaces by a fitted Maxwell bank for firmware; [`temperature`] shifts the
//! viscoelastic corners with the temperature (WLF, Arrhenius);
//! [`MaxwellBank::shifted`] re-tunes a running bank in f64 and
//! [`MaxwellBank::retune`] on line in the working type, with the
//! [`Exponentials`] of libm or (feature `micromath`) micromath. [`oscillator`]
//! integrates a unit-mass mode
//! whose restoring force is any bushing (the Iwan oscillator of the joint
//! thesis, "seed 004"), and [`tracker`] follows the frequency and damping
//! of measured modes on line (the modal Kalman tracker of seed 004).
//! With feature `serde`, the module `specs` reads the parameter specs from a
//! configuration file through their checked constructors (no alloc), and
//! every state ([`BushingState`] and the effects' states) and
//! [`EffectOutput`] is `Serialize` and `Deserialize`: a state is saved and
//! restored as plain data, for example with `postcard` (the FMU of
//! `bushing-sim fmu` rolls back with it).
//!
//! ## The contract
//!
//! - Parameters are validated at construction (`Result<_, ParamError>`, a
//!   variant per broken rule) and immutable; every coefficient is computed
//!   there in `f64` (exponentials with `expm1`) and stored in the working
//!   type `T: Real` (`f32` or `f64`); only an explicit on-line re-tune
//!   ([`MaxwellBank::retune`]) recomputes them in the working type.
//! - State is plain data apart from the parameters:
//!   `params.step(&mut state, x) -> Output`, and the pure
//!   `params.trial(&state, x) -> (Output, State)` beside it.
//! - The output carries the force, the algorithmic tangent dF_n/dx_n and the
//!   energy dissipated in the step, per effect.
//! - A non-finite or out-of-range input never poisons the state: the step is
//!   refused, the last force returned and a fault flag raised. So is a step
//!   whose effects' forces or tangents, or the totals, would not be finite
//!   or would exceed [`Real::GUARD`]: every accepted output is within it.
//! - The energy dissipated in a step is finite and never negative, except
//!   for the Grünwald cell ([`EffectOutput::dissipated`]).
//!
//! ## Units and conventions
//!
//! - **Displacement** in mm, **force** in N, so a stiffness or tangent is
//!   in N/mm and an energy in N·mm = **mJ**. **Time** in s: every step
//!   size `dt` is in seconds. Nothing in the crate converts units; a
//!   consistent other set (m, N, J) works the same way if every parameter
//!   uses it.
//! - **Frequencies**: a spec built with `hz` takes Hz
//!   ([`MaxwellSpec::hz`], [`XfSpec::hz`]); the fields `omega` are angular
//!   frequencies in rad/s (ω = 2π f). The trackers report both: a mode's
//!   `frequency` in Hz and its `omega` in rad/s.
//! - **Signs**: the force has the sign of the displacement on the
//!   backbone (F^∞(x) increases with x). It is the force that holds the
//!   bushing at x, which a load cell in series reads. The 6-DOF bushing
//!   gives the load on each node ([`six_dof`]).
//! - **Fractions** g are of the high-frequency backbone F^∞: the long-term
//!   branch carries g^0 = 1 - Σ g^i.
//! - **Dissipated energy** is per step (sum it for a cycle's loop area);
//!   the **tangent** is the algorithmic dF_n/dx_n with the state at the
//!   start of the step held fixed.
//!
//! ```
//! use bushing::{Bushing, MaxwellBank, MaxwellForm, MaxwellSpec, Polynomial};
//!
//! let dt = 1e-3; // 1 kHz control loop
//! let backbone = Polynomial::<f32, 4>::new(&[0.0, 200.0, 0.0, 8.0], (-5.0, 5.0))?; // N, mm
//! let cells = [MaxwellSpec::hz(0.5, 0.1), MaxwellSpec::hz(5.0, 0.1), MaxwellSpec::hz(50.0, 0.1)];
//! let bank = MaxwellBank::<f32, 3>::new(MaxwellForm::RateExactRamp, &cells, dt)?;
//! let bushing = Bushing::new(backbone, (bank,))?;
//! let mut state = bushing.state_at(0.0);
//! let out = bushing.step(&mut state, 0.1);
//! assert!(out.force > 0.0 && out.tangent > 0.0 && out.dissipated >= 0.0);
//! # Ok::<(), bushing::ParamError>(())
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::indexing_slicing,
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic
    )
)]

#[cfg(test)]
extern crate alloc;

/// The crate README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeExample;

pub mod accumulator;
pub mod backbone;
pub mod bushing;
pub mod discretize;
pub mod error;
pub mod excitation;
#[cfg(feature = "fixed")]
pub mod fixed;
pub mod fractional;
pub mod friction;
pub mod iwan;
pub mod maxwell;
pub mod oscillator;
pub mod real;
#[cfg(feature = "serde")]
mod serde_array;
pub mod six_dof;
#[cfg(feature = "serde")]
pub mod specs;
pub mod stack;
pub mod temperature;
pub mod tracker;
pub mod viscous;
pub mod xf;

#[cfg(feature = "fixed")]
pub use self::fixed::{Q16, Q32};
pub use accumulator::{Accumulator, Compensated, Multiplied, Plain};
pub use backbone::{Backbone, MonotoneSpline, Polynomial};
pub use bushing::{Bushing, BushingState, Drive, Effect, EffectOutput, Output, OutputOf, StateOf};
pub use error::{Faults, Param, ParamError};
pub use fractional::{FractionalSpec, Grunwald, GrunwaldState};
pub use friction::{Berg, BoucWen, Dahl};
pub use iwan::{IwanBank, IwanCellSpec, IwanSliders};
pub use maxwell::{MaxwellBank, MaxwellCell, MaxwellForm, MaxwellSpec};
pub use oscillator::{Oscillator, OscillatorState, OscillatorStep};
#[cfg(feature = "micromath")]
pub use real::MicromathExp;
pub use real::{Exponentials, LibmExp, Real};
pub use stack::{FirstLoading, KfTable, Relaxation, StackState, Sts, TurningPoints};
pub use temperature::ShiftFactor;
pub use viscous::Dashpot;
pub use xf::{XfBank, XfForm, XfSpec};
