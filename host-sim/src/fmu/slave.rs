//! The co-simulation slave: FMI 2.0's state machine, variables, steps and
//! FMU states in safe Rust. The library `bushing-fmu` calls it from the C
//! entry points; the tests call it directly.
//!
//! The bushing is the scene's own ([`crate::model::build`]) in the model's
//! working type, so an FMU steps bit for bit as `bushing-sim run` does on
//! the same inputs. Each communication step of `h` runs `h / dt` model
//! steps with the input held. Every call the standard does not allow in
//! the current phase, and every bad value, is refused with
//! [`Status::Error`] and a message naming what was wrong; the slave is
//! then in [`Phase::Error`], from which `fmi2SetFMUstate` (a state saved
//! before) or `fmi2Reset` bring it back. A refused call changes nothing
//! else.

use bushing::{Faults, Real};
use serde::{Deserialize, Serialize};

use super::description::{ENERGY, FAULTS, FORCE, REFUSED, TANGENT, TEMPERATURE, X};
use super::resource::FmuModel;
use crate::model::{SceneBushing, SceneState, build, shifted_bushing};
use crate::scene::NumberType;

/// The status of an FMI call (`fmi2Status`, without `fmi2Pending`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `fmi2OK`.
    Ok,
    /// `fmi2Warning`: done, with something to log.
    Warning,
    /// `fmi2Discard`.
    Discard,
    /// `fmi2Error`: refused; the instance is in [`Phase::Error`].
    Error,
    /// `fmi2Fatal`: the instance cannot be used any more.
    Fatal,
}

/// A call answered with something other than `fmi2OK`: its status and the
/// message to log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Report {
    /// The status.
    pub status: Status,
    /// What happened, for the master's log.
    pub message: String,
}

impl Report {
    fn error(message: impl Into<String>) -> Self {
        Self {
            status: Status::Error,
            message: message.into(),
        }
    }
}

/// Where the slave is in FMI 2.0's co-simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and
    /// `fmi2ExitInitializationMode`.
    Initialization,
    /// Initialised: steps may be taken.
    StepComplete,
    /// After `fmi2Terminate`.
    Terminated,
    /// A call was refused with `fmi2Error`.
    Error,
}

impl Phase {
    fn name(self) -> &'static str {
        match self {
            Self::Instantiated => "instantiated",
            Self::Initialization => "initialization mode",
            Self::StepComplete => "step complete",
            Self::Terminated => "terminated",
            Self::Error => "error",
        }
    }
}

/// Most model steps one `fmi2DoStep` may ask for (about a second of host
/// time for the default bushing).
pub const MAX_STEPS_PER_CALL: u64 = 100_000_000;

/// Tolerance on a communication step's length and point, in model steps:
/// a master's sums of `h` may be off by a rounding, not by a fraction of a
/// step.
const STEP_TOLERANCE: f64 = 1e-6;

/// Everything of a slave that is not its model: saved and restored whole
/// by an FMU state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct Common {
    phase: Phase,
    /// Start time of the experiment, s.
    start: f64,
    /// Model steps taken.
    steps: u64,
    /// The displacement input, mm.
    x: f64,
    /// The temperature input (models with a shift law).
    temperature: Option<f64>,
    /// The shift factor the Maxwell banks are tuned to.
    shift: f64,
    /// Energy dissipated since the start, mJ, summed in f64.
    energy: f64,
}

/// A slave's state in one working type.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: Serialize",
    deserialize = "T: serde::de::DeserializeOwned"
))]
struct Saved<T: Real> {
    common: Common,
    state: SceneState<T>,
}

/// The bushing of one working type and its state.
#[derive(Debug, Clone)]
struct Kernel<T: Real> {
    bushing: SceneBushing<T>,
    state: SceneState<T>,
}

impl<T: Real + 'static> Kernel<T> {
    fn new(model: &FmuModel) -> Result<Self, String> {
        let bushing = build::<T>(&model.scene).map_err(|e| e.to_string())?;
        let state = bushing.state_at(T::ZERO);
        Ok(Self { bushing, state })
    }

    /// `steps` model steps at `x`: the energy they dissipate (f64 sum
    /// onto `energy`) and how many were refused.
    #[inline(never)]
    fn run(&mut self, x: f64, steps: u64, energy: &mut f64) -> u64 {
        let x = T::from_f64(x);
        let mut refused = 0;
        for _ in 0..steps {
            let out = self.bushing.step(&mut self.state, x);
            *energy += out.dissipated.to_f64();
            refused += u64::from(out.effects.is_none());
        }
        refused
    }

    fn retune(&mut self, shift: f64) -> Result<(), String> {
        self.bushing = shifted_bushing(&self.bushing, shift).map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// The kernel in the model's working type.
#[derive(Debug, Clone)]
enum Kernels {
    F32(Kernel<f32>),
    F64(Kernel<f64>),
}

/// Runs `$body` with `$k` bound to the kernel, whatever its type.
macro_rules! with_kernel {
    ($kernels:expr, |$k:ident| $body:expr) => {
        match $kernels {
            Kernels::F32($k) => $body,
            Kernels::F64($k) => $body,
        }
    };
}

/// A saved slave (`fmi2FMUstate`): plain data, restored by
/// [`Slave::set_state`] and written as bytes by [`Slave::serialize`].
#[derive(Debug, Clone, PartialEq)]
pub struct FmuState {
    guid: String,
    saved: SavedAny,
}

#[derive(Debug, Clone, PartialEq)]
enum SavedAny {
    F32(Saved<f32>),
    F64(Saved<f64>),
}

/// The first bytes of a serialised FMU state.
const MAGIC: &[u8; 8] = b"BUSHFMU\x01";

/// One bushing as an FMI 2.0 co-simulation slave.
#[derive(Debug, Clone)]
pub struct Slave {
    model: FmuModel,
    kernel: Kernels,
    common: Common,
}

impl Slave {
    /// A slave of `model`, instantiated by a master that read the model
    /// description of GUID `guid`: refused when the two GUIDs differ (the
    /// FMU's resource is not the model its description was made from).
    pub fn new(model: FmuModel, guid: &str) -> Result<Self, Report> {
        if guid != model.guid {
            return Err(Report::error(format!(
                "the GUID {guid:?} the master read from the model description is not the \
                 GUID {} of the model in the FMU's resources: the two are of different \
                 models (was resources/model.toml edited after the FMU was made?)",
                model.guid
            )));
        }
        let kernel = match model.scene.number {
            NumberType::F32 => Kernel::new(&model).map(Kernels::F32),
            NumberType::F64 => Kernel::new(&model).map(Kernels::F64),
        }
        .map_err(|e| Report::error(format!("the model cannot be built: {e}")))?;
        let mut slave = Self {
            model,
            kernel,
            common: Common {
                phase: Phase::Instantiated,
                start: 0.0,
                steps: 0,
                x: 0.0,
                temperature: None,
                shift: 1.0,
                energy: 0.0,
            },
        };
        if let Some(t) = slave.model.scene.temperature.as_ref().map(|h| h.at(0.0)) {
            slave.set_temperature(t)?;
        }
        Ok(slave)
    }

    /// The model.
    pub fn model(&self) -> &FmuModel {
        &self.model
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.common.phase
    }

    /// The model's time step, s.
    pub fn dt(&self) -> f64 {
        self.model.scene.dt
    }

    /// Time of the last communication point reached, s.
    pub fn time(&self) -> f64 {
        self.common.start + self.common.steps as f64 * self.dt()
    }

    /// A call refused by the caller of the slave (a null pointer, a
    /// function the FMU does not provide): [`Status::Error`] with
    /// `message`, the slave in [`Phase::Error`].
    pub fn refuse(&mut self, message: String) -> Report {
        self.common.phase = Phase::Error;
        Report::error(message)
    }

    /// Puts the slave in [`Phase::Error`] when `result` is an error.
    fn guard<R>(&mut self, result: Result<R, Report>) -> Result<R, Report> {
        if let Err(r) = &result
            && r.status == Status::Error
        {
            self.common.phase = Phase::Error;
        }
        result
    }

    fn expect(&self, call: &str, allowed: &[Phase]) -> Result<(), Report> {
        if allowed.contains(&self.common.phase) {
            return Ok(());
        }
        let names: Vec<&str> = allowed.iter().map(|p| p.name()).collect();
        Err(Report::error(format!(
            "{call} called in phase {}; it is allowed in: {}",
            self.common.phase.name(),
            names.join(", ")
        )))
    }

    /// `fmi2SetupExperiment`: the start time (finite).
    pub fn setup_experiment(&mut self, start: f64) -> Result<(), Report> {
        let r = self
            .expect("fmi2SetupExperiment", &[Phase::Instantiated])
            .and_then(|()| {
                if start.is_finite() {
                    self.common.start = start;
                    Ok(())
                } else {
                    Err(Report::error(format!(
                        "fmi2SetupExperiment: the start time must be finite, got {start}"
                    )))
                }
            });
        self.guard(r)
    }

    /// `call` moves the slave from phase `from` to phase `to`, and is
    /// refused in any other phase.
    fn transition(&mut self, call: &str, from: Phase, to: Phase) -> Result<(), Report> {
        let r = self.expect(call, &[from]);
        if r.is_ok() {
            self.common.phase = to;
        }
        self.guard(r)
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Result<(), Report> {
        self.transition(
            "fmi2EnterInitializationMode",
            Phase::Instantiated,
            Phase::Initialization,
        )
    }

    /// `fmi2ExitInitializationMode`: the bushing is at rest at the
    /// displacement input.
    pub fn exit_initialization(&mut self) -> Result<(), Report> {
        self.transition(
            "fmi2ExitInitializationMode",
            Phase::Initialization,
            Phase::StepComplete,
        )
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<(), Report> {
        self.transition("fmi2Terminate", Phase::StepComplete, Phase::Terminated)
    }

    /// `fmi2Reset`: as instantiated, every input at its start value.
    pub fn reset(&mut self) -> Result<(), Report> {
        let model = self.model.clone();
        let guid = model.guid.clone();
        let fresh = Self::new(model, &guid);
        let r = fresh.map(|s| *self = s);
        self.guard(r)
    }

    /// `fmi2GetReal` of one variable.
    pub fn get_real(&mut self, vr: u32) -> Result<f64, Report> {
        let r = self.read_real(vr);
        self.guard(r)
    }

    fn read_real(&self, vr: u32) -> Result<f64, Report> {
        self.expect_read("fmi2GetReal")?;
        let c = &self.common;
        Ok(match vr {
            X => c.x,
            FORCE => with_kernel!(&self.kernel, |k| k.state.force().to_f64()),
            TANGENT => with_kernel!(&self.kernel, |k| k.state.tangent().to_f64()),
            ENERGY => c.energy,
            TEMPERATURE if c.temperature.is_some() => c.temperature.unwrap_or(f64::NAN),
            _ => return Err(unknown("fmi2GetReal", "Real", vr)),
        })
    }

    fn expect_read(&self, call: &str) -> Result<(), Report> {
        self.expect(
            call,
            &[
                Phase::Initialization,
                Phase::StepComplete,
                Phase::Terminated,
                Phase::Error,
            ],
        )
    }

    /// The fault flags raised so far.
    pub fn faults(&self) -> Faults {
        with_kernel!(&self.kernel, |k| k.state.faults())
    }

    /// `fmi2GetInteger` of one variable.
    pub fn get_integer(&mut self, vr: u32) -> Result<i32, Report> {
        let r = self.expect_read("fmi2GetInteger").and_then(|()| match vr {
            FAULTS => Ok(i32::from(self.faults().bits())),
            REFUSED => Ok(with_kernel!(&self.kernel, |k| {
                i32::try_from(k.state.rejected()).unwrap_or(i32::MAX)
            })),
            _ => Err(unknown("fmi2GetInteger", "Integer", vr)),
        });
        self.guard(r)
    }

    /// `fmi2SetReal` of one input.
    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<(), Report> {
        let r = self
            .expect(
                "fmi2SetReal",
                &[
                    Phase::Instantiated,
                    Phase::Initialization,
                    Phase::StepComplete,
                ],
            )
            .and_then(|()| match vr {
                X if value.is_finite() => {
                    self.common.x = value;
                    if self.common.phase != Phase::StepComplete {
                        with_kernel!(&mut self.kernel, |k| {
                            k.state = k.bushing.state_at(Real::from_f64(value));
                        });
                    }
                    Ok(())
                }
                X => Err(Report::error(format!(
                    "fmi2SetReal: x = {value}: the displacement must be finite"
                ))),
                TEMPERATURE if self.common.temperature.is_some() => self.set_temperature(value),
                FORCE | TANGENT | ENERGY => Err(Report::error(format!(
                    "fmi2SetReal: value reference {vr} is an output"
                ))),
                _ => Err(unknown("fmi2SetReal", "Real", vr)),
            });
        self.guard(r)
    }

    /// The temperature input: the Maxwell banks re-tuned to its a_T when
    /// it moves (nothing changes when it is refused).
    fn set_temperature(&mut self, t: f64) -> Result<(), Report> {
        let Some(history) = &self.model.scene.temperature else {
            return Err(unknown("fmi2SetReal", "Real", TEMPERATURE));
        };
        let shift = history
            .law
            .at(t)
            .map_err(|e| Report::error(format!("fmi2SetReal: temperature = {t}: {e}")))?;
        if shift != self.common.shift {
            with_kernel!(&mut self.kernel, |k| k.retune(shift)).map_err(|e| {
                Report::error(format!(
                    "fmi2SetReal: temperature = {t} (a_T = {shift}): the re-tuned model is \
                     refused: {e}"
                ))
            })?;
            self.common.shift = shift;
        }
        self.common.temperature = Some(t);
        Ok(())
    }

    /// `fmi2SetInteger`: the FMU has no Integer input.
    pub fn set_integer(&mut self, vr: u32) -> Result<(), Report> {
        let r = Err(match vr {
            FAULTS | REFUSED => {
                Report::error(format!("fmi2SetInteger: value reference {vr} is an output"))
            }
            _ => unknown("fmi2SetInteger", "Integer", vr),
        });
        self.guard(r)
    }

    /// `fmi2DoStep` from `t` over `h` s: `h / dt` model steps with the
    /// inputs held. A step the model refuses (a displacement out of the
    /// backbone's range) keeps the force and is reported as a
    /// [`Status::Warning`]; a communication step that is not a whole
    /// number of model steps, or a point that is not where the slave is,
    /// is refused.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Option<Report>, Report> {
        let r = self.step_inner(t, h);
        self.guard(r)
    }

    fn step_inner(&mut self, t: f64, h: f64) -> Result<Option<Report>, Report> {
        self.expect("fmi2DoStep", &[Phase::StepComplete])?;
        let dt = self.dt();
        let ratio = h / dt;
        let steps = ratio.round();
        if !(h.is_finite() && steps >= 1.0 && (ratio - steps).abs() <= STEP_TOLERANCE) {
            return Err(Report::error(format!(
                "fmi2DoStep: the communication step {h} s is not a whole number of the \
                 model's steps of {dt} s (h / dt = {ratio})"
            )));
        }
        if steps > MAX_STEPS_PER_CALL as f64 {
            return Err(Report::error(format!(
                "fmi2DoStep: {steps} model steps in one call, more than the limit of \
                 {MAX_STEPS_PER_CALL}"
            )));
        }
        let now = self.time();
        let off = (t - now).abs();
        if off.is_nan() || off > STEP_TOLERANCE * dt {
            return Err(Report::error(format!(
                "fmi2DoStep: the communication point {t} s is not the FMU's time {now} s \
                 (a step skipped, repeated or out of order)"
            )));
        }
        let (steps, x) = (steps as u64, self.common.x);
        let energy = &mut self.common.energy;
        let refused = with_kernel!(&mut self.kernel, |k| k.run(x, steps, energy));
        self.common.steps += steps;
        if refused == 0 {
            return Ok(None);
        }
        Ok(Some(Report {
            status: Status::Warning,
            message: format!(
                "fmi2DoStep: {refused} of the {steps} model steps from t = {t} s were refused at \
                 x = {x} mm (faults {}); the force is held",
                self.faults()
            ),
        }))
    }

    /// `fmi2GetFMUstate`: a copy of everything that changes.
    pub fn get_state(&mut self) -> Result<FmuState, Report> {
        let r = self.expect(
            "fmi2GetFMUstate",
            &[
                Phase::Instantiated,
                Phase::Initialization,
                Phase::StepComplete,
                Phase::Terminated,
            ],
        );
        let r = r.map(|()| FmuState {
            guid: self.model.guid.clone(),
            saved: match &self.kernel {
                Kernels::F32(k) => SavedAny::F32(Saved {
                    common: self.common,
                    state: k.state.clone(),
                }),
                Kernels::F64(k) => SavedAny::F64(Saved {
                    common: self.common,
                    state: k.state.clone(),
                }),
            },
        });
        self.guard(r)
    }

    /// `fmi2SetFMUstate`: back to a saved state (also out of
    /// [`Phase::Error`]).
    pub fn set_state(&mut self, saved: &FmuState) -> Result<(), Report> {
        let r = self.restore(saved);
        self.guard(r)
    }

    fn restore(&mut self, saved: &FmuState) -> Result<(), Report> {
        if saved.guid != self.model.guid {
            return Err(Report::error(
                "fmi2SetFMUstate: the state is of another model (GUID differs)",
            ));
        }
        let common = match (&saved.saved, &self.kernel) {
            (SavedAny::F32(s), Kernels::F32(_)) => s.common,
            (SavedAny::F64(s), Kernels::F64(_)) => s.common,
            _ => {
                return Err(Report::error(
                    "fmi2SetFMUstate: the state is of another number type",
                ));
            }
        };
        if common.shift != self.common.shift {
            with_kernel!(&mut self.kernel, |k| k.retune(common.shift)).map_err(|e| {
                Report::error(format!("fmi2SetFMUstate: the saved tuning is refused: {e}"))
            })?;
        }
        match (&saved.saved, &mut self.kernel) {
            (SavedAny::F32(s), Kernels::F32(k)) => k.state.clone_from(&s.state),
            (SavedAny::F64(s), Kernels::F64(k)) => k.state.clone_from(&s.state),
            _ => {}
        }
        self.common = common;
        Ok(())
    }

    /// `fmi2SerializeFMUstate`: the state as bytes (a header with the
    /// model's GUID and a CRC-32, then the state in postcard).
    pub fn serialize(&self, saved: &FmuState) -> Vec<u8> {
        let (number, payload) = match &saved.saved {
            SavedAny::F32(s) => (0u8, postcard::to_allocvec(s)),
            SavedAny::F64(s) => (1u8, postcard::to_allocvec(s)),
        };
        // Serialising plain data into a vector cannot fail.
        let payload = payload.unwrap_or_default();
        let mut out = Vec::with_capacity(MAGIC.len() + saved.guid.len() + 9 + payload.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(saved.guid.as_bytes());
        out.push(number);
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }

    /// `fmi2DeSerializeFMUstate`: a state read back from
    /// [`Slave::serialize`]'s bytes, refused when they are not a state of
    /// this model (magic, GUID, number type) or were damaged (CRC-32).
    pub fn deserialize(&mut self, bytes: &[u8]) -> Result<FmuState, Report> {
        let r = self.read_state(bytes);
        self.guard(r)
    }

    fn read_state(&self, bytes: &[u8]) -> Result<FmuState, Report> {
        let bad = |what: &str| Report::error(format!("fmi2DeSerializeFMUstate: {what}"));
        let guid = self.model.guid.as_bytes();
        let rest = bytes
            .strip_prefix(MAGIC.as_slice())
            .ok_or_else(|| bad("not a serialised state of this FMU (no header)"))?;
        let rest = rest
            .strip_prefix(guid)
            .ok_or_else(|| bad("the state is of another model (GUID differs)"))?;
        let (&number, rest) = rest
            .split_first()
            .ok_or_else(|| bad("the state is cut short"))?;
        let (crc, payload) = rest
            .split_first_chunk::<4>()
            .ok_or_else(|| bad("the state is cut short"))?;
        if crc32fast::hash(payload) != u32::from_le_bytes(*crc) {
            return Err(bad("the state is damaged (CRC-32 differs)"));
        }
        let decoded = match (number, &self.kernel) {
            (0, Kernels::F32(_)) => postcard::from_bytes(payload).map(SavedAny::F32),
            (1, Kernels::F64(_)) => postcard::from_bytes(payload).map(SavedAny::F64),
            _ => return Err(bad("the state is of another number type")),
        };
        let saved = decoded.map_err(|e| bad(&format!("the state cannot be read: {e}")))?;
        Ok(FmuState {
            guid: self.model.guid.clone(),
            saved,
        })
    }
}

fn unknown(call: &str, kind: &str, vr: u32) -> Report {
    Report::error(format!(
        "{call}: no {kind} variable has value reference {vr}"
    ))
}
