//! The C entry points of the bushing, one set per number type: `f32` for a
//! core with an FPU and `Q16` (Q16.16 in an `int32_t`) for one without,
//! as in Rust. The caller owns every struct; nothing is allocated and
//! nothing is called back.
//!
//! A call per control period: `bushing_<type>_step(&model, &state, x,
//! &out)`. `init` checks the spec and builds the model into the caller's
//! `bushing_<type>_t`; `reset` puts a state at rest at a displacement;
//! `trial` is `step` without changing the state; `faults` reads the sticky
//! fault flags, `clear_faults` clears them.
// The boundary: raw pointers from C, read and written through `ffi`.
#![allow(unsafe_code)]

use core::ffi::{CStr, c_char};

use bushing::{Q16, Real};

use crate::ffi::{self, Storage};
use crate::model::{self, BushingSpec, Model, State};
use crate::status::*;

/// 64-bit words of a `bushing_f32_t` or `bushing_q16_t` (a model: its
/// coefficients, read only once built).
pub const BUSHING_MODEL_WORDS: usize = 160;
/// 64-bit words of a `bushing_f32_state_t` or `bushing_q16_state_t`.
pub const BUSHING_STATE_WORDS: usize = 48;

/// The status of a result, for the C side.
pub(crate) fn status(r: Result<BushingStatus, BushingStatus>) -> BushingStatusCode {
    r.unwrap_or_else(|e| e).code()
}

/// Ok, or Refused for a step the model refused.
fn accepted<R>(o: &bushing::Output<impl Real, R>) -> BushingStatus {
    if o.effects.is_some() {
        BushingStatus::Ok
    } else {
        BushingStatus::Refused
    }
}

/// A number type of the C API: its C representation and output struct.
trait CNumber: Real {
    /// The C type of a value.
    type C: Copy;
    /// The C output struct.
    type Out;
    fn from_c(c: Self::C) -> Self;
    fn output<R>(o: &bushing::Output<Self, R>) -> Self::Out;
}

/// A bushing model in caller-owned storage, `f32` (set by `init`).
#[repr(C)]
pub struct BushingF32 {
    /// Opaque.
    pub words: [u64; BUSHING_MODEL_WORDS],
}

/// A bushing state in caller-owned storage, `f32` (set by `reset`).
#[repr(C)]
pub struct BushingF32State {
    /// Opaque.
    pub words: [u64; BUSHING_STATE_WORDS],
}

/// A bushing model in caller-owned storage, Q16 (set by `init`).
#[repr(C)]
pub struct BushingQ16 {
    /// Opaque.
    pub words: [u64; BUSHING_MODEL_WORDS],
}

/// A bushing state in caller-owned storage, Q16 (set by `reset`).
#[repr(C)]
pub struct BushingQ16State {
    /// Opaque.
    pub words: [u64; BUSHING_STATE_WORDS],
}

/// What one `f32` step gives.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BushingF32Output {
    /// Total force F_n, N.
    pub force: f32,
    /// Algorithmic tangent dF_n/dx_n, N/mm.
    pub tangent: f32,
    /// Energy dissipated in the step, mJ (N·mm).
    pub dissipated: f32,
    /// Force of the long-term elastic branch, N.
    pub elastic: f32,
}

/// What one Q16 step gives, each value Q16.16 in an `int32_t`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BushingQ16Output {
    /// Total force F_n, N.
    pub force: i32,
    /// Algorithmic tangent dF_n/dx_n, N/mm.
    pub tangent: i32,
    /// Energy dissipated in the step, mJ (N·mm).
    pub dissipated: i32,
    /// Force of the long-term elastic branch, N.
    pub elastic: i32,
}

impl CNumber for f32 {
    type C = f32;
    type Out = BushingF32Output;
    fn from_c(c: f32) -> Self {
        c
    }
    fn output<R>(o: &bushing::Output<Self, R>) -> BushingF32Output {
        BushingF32Output {
            force: o.force,
            tangent: o.tangent,
            dissipated: o.dissipated,
            elastic: o.elastic,
        }
    }
}

impl CNumber for Q16 {
    type C = i32;
    type Out = BushingQ16Output;
    fn from_c(c: i32) -> Self {
        Q16::from_bits(c)
    }
    fn output<R>(o: &bushing::Output<Self, R>) -> BushingQ16Output {
        BushingQ16Output {
            force: o.force.to_bits(),
            tangent: o.tangent.to_bits(),
            dissipated: o.dissipated.to_bits(),
            elastic: o.elastic.to_bits(),
        }
    }
}

// SAFETY: a struct of `u64` words only; its tag is its own (ASCII name,
// the last byte the layout's version).
unsafe impl Storage for BushingF32 {
    type Value = Model<f32>;
    const TAG: u64 = u64::from_le_bytes(*b"BshF32M\x01");
}
// SAFETY: as above.
unsafe impl Storage for BushingF32State {
    type Value = State<f32>;
    const TAG: u64 = u64::from_le_bytes(*b"BshF32S\x01");
}
// SAFETY: as above.
unsafe impl Storage for BushingQ16 {
    type Value = Model<Q16>;
    const TAG: u64 = u64::from_le_bytes(*b"BshQ16M\x01");
}
// SAFETY: as above.
unsafe impl Storage for BushingQ16State {
    type Value = State<Q16>;
    const TAG: u64 = u64::from_le_bytes(*b"BshQ16S\x01");
}

/// `init` of any model: builds with `make` from the spec at `spec` into
/// the storage at `out`, the refusal also into `error`.
///
/// # Safety
///
/// The contract of `bushing_f32_init`: `out` writable, `spec` readable,
/// `error` null or writable, none overlapping.
pub(crate) unsafe fn init<S: Storage, P>(
    out: *mut S,
    spec: *const P,
    error: *mut BushingError,
    make: impl FnOnce(&P) -> Result<S::Value, BushingError>,
) -> BushingStatusCode {
    let built = (|| {
        // SAFETY: `spec` is null or readable, and nothing writes it
        // during the call (the contract).
        let spec = unsafe { ffi::input(spec) }.map_err(BushingError::of)?;
        let value = make(spec)?;
        // SAFETY: `out` is null or writable and unaliased (the contract).
        unsafe { ffi::put(out, value) }.map_err(BushingError::of)
    })();
    match built {
        Ok(()) => BushingStatus::Ok.code(),
        Err(e) => {
            // SAFETY: `error` is null or writable (the contract).
            unsafe { ffi::optional_output(error, e) };
            e.status
        }
    }
}

/// `reset` of one number type.
///
/// # Safety
///
/// The contract of `bushing_f32_reset`.
unsafe fn reset<N: CNumber, M, S>(model: *const M, state: *mut S, x0: N::C) -> BushingStatusCode
where
    M: Storage<Value = Model<N>>,
    S: Storage<Value = State<N>>,
{
    status((|| {
        // SAFETY: `model` was set by `init` and is only read (the contract).
        let m = unsafe { ffi::get(model) }?;
        // SAFETY: `state` is writable and does not overlap `model`.
        unsafe { ffi::put(state, m.state_at(N::from_c(x0))) }?;
        Ok(BushingStatus::Ok)
    })())
}

/// The body of every `step` call: the model read, the state advanced by
/// `f`, its output written. A null `out` is refused before the state
/// moves.
///
/// # Safety
///
/// `model` set by `init` and only read, `state` set by `reset` and
/// referenced by nothing else, `out` writable; none overlap.
pub(crate) unsafe fn step_with<M: Storage, S: Storage, O>(
    model: *const M,
    state: *mut S,
    out: *mut O,
    f: impl FnOnce(&M::Value, &mut S::Value) -> (O, BushingStatus),
) -> BushingStatusCode {
    if out.is_null() {
        return BushingStatus::NullPointer.code();
    }
    status((|| {
        // SAFETY: `model` was set by `init` and is only read (the contract).
        let m = unsafe { ffi::get(model) }?;
        // SAFETY: `state` was set by `reset`, and nothing else references
        // it during the call (the contract).
        let s = unsafe { ffi::get_mut(state) }?;
        let (o, done) = f(m, s);
        // SAFETY: `out` is writable and overlaps neither (the contract).
        unsafe { ffi::output(out, o) }?;
        Ok(done)
    })())
}

/// The body of every `trial` call: [`step_with`] on a copy of the state.
///
/// # Safety
///
/// As [`step_with`], `state` only read.
pub(crate) unsafe fn trial_with<M: Storage, S: Storage, O>(
    model: *const M,
    state: *const S,
    out: *mut O,
    f: impl FnOnce(&M::Value, &mut S::Value) -> (O, BushingStatus),
) -> BushingStatusCode
where
    S::Value: Clone,
{
    status((|| {
        // SAFETY: `model` was set by `init` and is only read (the contract).
        let m = unsafe { ffi::get(model) }?;
        // SAFETY: `state` was set by `reset` and is only read (copied).
        let mut s = unsafe { ffi::get(state) }?.clone();
        let (o, done) = f(m, &mut s);
        // SAFETY: `out` is writable and overlaps neither (the contract).
        unsafe { ffi::output(out, o) }?;
        Ok(done)
    })())
}

/// One bushing step of one number type: its output and status.
fn advance<N: CNumber>(m: &Model<N>, s: &mut State<N>, x: N::C) -> (N::Out, BushingStatus) {
    let o = m.step(s, N::from_c(x));
    (N::output(&o), accepted(&o))
}

/// `faults` of one number type.
///
/// # Safety
///
/// The contract of `bushing_f32_faults`.
unsafe fn faults<N: CNumber, S: Storage<Value = State<N>>>(
    state: *const S,
    flags: *mut u8,
) -> BushingStatusCode {
    status((|| {
        // SAFETY: `state` was set by `reset` and is only read.
        let s = unsafe { ffi::get(state) }?;
        // SAFETY: `flags` is writable (the contract).
        unsafe { ffi::output(flags, s.faults().bits()) }?;
        Ok(BushingStatus::Ok)
    })())
}

/// `clear_faults` of one number type.
///
/// # Safety
///
/// The contract of `bushing_f32_clear_faults`.
unsafe fn clear_faults<N: CNumber, S: Storage<Value = State<N>>>(
    state: *mut S,
) -> BushingStatusCode {
    status((|| {
        // SAFETY: `state` was set by `reset`, and nothing else references
        // it during the call (the contract).
        unsafe { ffi::get_mut(state) }?.clear_faults();
        Ok(BushingStatus::Ok)
    })())
}

/// The name of a status code, as the header spells it
/// (`"BUSHING_STATUS_TOO_MANY"`), for a log; `"BUSHING_STATUS_UNKNOWN"`
/// for a value that is no code. The string is static and NUL-terminated.
#[unsafe(no_mangle)]
pub extern "C" fn bushing_status_name(code: BushingStatusCode) -> *const c_char {
    let name: &'static CStr = match code {
        BUSHING_STATUS_OK => c"BUSHING_STATUS_OK",
        BUSHING_STATUS_REFUSED => c"BUSHING_STATUS_REFUSED",
        BUSHING_STATUS_NULL_POINTER => c"BUSHING_STATUS_NULL_POINTER",
        BUSHING_STATUS_NOT_INITIALISED => c"BUSHING_STATUS_NOT_INITIALISED",
        BUSHING_STATUS_UNKNOWN_KIND => c"BUSHING_STATUS_UNKNOWN_KIND",
        BUSHING_STATUS_NOT_FINITE => c"BUSHING_STATUS_NOT_FINITE",
        BUSHING_STATUS_NOT_POSITIVE => c"BUSHING_STATUS_NOT_POSITIVE",
        BUSHING_STATUS_FRACTIONS_ABOVE_ONE => c"BUSHING_STATUS_FRACTIONS_ABOVE_ONE",
        BUSHING_STATUS_CELL_FRACTION_ABOVE_ONE => c"BUSHING_STATUS_CELL_FRACTION_ABOVE_ONE",
        BUSHING_STATUS_EXPLICIT_UNSTABLE => c"BUSHING_STATUS_EXPLICIT_UNSTABLE",
        BUSHING_STATUS_TOO_FEW => c"BUSHING_STATUS_TOO_FEW",
        BUSHING_STATUS_TOO_MANY => c"BUSHING_STATUS_TOO_MANY",
        BUSHING_STATUS_LENGTH_MISMATCH => c"BUSHING_STATUS_LENGTH_MISMATCH",
        BUSHING_STATUS_NOT_INCREASING => c"BUSHING_STATUS_NOT_INCREASING",
        BUSHING_STATUS_INCREASING => c"BUSHING_STATUS_INCREASING",
        BUSHING_STATUS_TANGENT_NOT_POSITIVE => c"BUSHING_STATUS_TANGENT_NOT_POSITIVE",
        BUSHING_STATUS_EMPTY_RANGE => c"BUSHING_STATUS_EMPTY_RANGE",
        BUSHING_STATUS_OUT_OF_RANGE => c"BUSHING_STATUS_OUT_OF_RANGE",
        BUSHING_STATUS_TIME_STEP_MISMATCH => c"BUSHING_STATUS_TIME_STEP_MISMATCH",
        _ => c"BUSHING_STATUS_UNKNOWN",
    };
    name.as_ptr()
}

/// Checks `spec` and builds the model into `model`. Returns
/// `BUSHING_STATUS_OK`, or the rule broken, also written to `error` with
/// the parameter and its bound when `error` is not null; on a refusal
/// `model` is left as it was.
///
/// # Safety
///
/// `model` points to a writable model struct, `spec` to a readable spec,
/// and `error` is null or points to a writable error struct; none of them
/// overlap or are used by another call meanwhile.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_f32_init(
    model: *mut BushingF32,
    spec: *const BushingSpec,
    error: *mut BushingError,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { init(model, spec, error, model::build) }
}

/// Puts `state` at rest at displacement `x0` (mm): no force in any
/// branch, no fault. A displacement that is not finite or is beyond the
/// guard starts the state at 0 with its flag raised.
///
/// # Safety
///
/// `model` points to a model set by `init`, `state` to a writable state
/// struct; they do not overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_f32_reset(
    model: *const BushingF32,
    state: *mut BushingF32State,
    x0: f32,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { reset(model, state, x0) }
}

/// One step to displacement `x` (mm): advances `state` and writes the
/// output. `BUSHING_STATUS_REFUSED` when the model refused the step (the
/// state kept, a fault flag raised, the last force in `out`).
///
/// # Safety
///
/// `model` points to a model set by `init`, `state` to a state set by
/// `reset` for it, `out` to a writable output; none overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_f32_step(
    model: *const BushingF32,
    state: *mut BushingF32State,
    x: f32,
    out: *mut BushingF32Output,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { step_with(model, state, out, |m, s| advance::<f32>(m, s, x)) }
}

/// The output `step` would give, `state` left unchanged.
///
/// # Safety
///
/// As `bushing_f32_step`, `state` only read.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_f32_trial(
    model: *const BushingF32,
    state: *const BushingF32State,
    x: f32,
    out: *mut BushingF32Output,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { trial_with(model, state, out, |m, s| advance::<f32>(m, s, x)) }
}

/// The sticky fault flags of `state` (`BUSHING_FAULT_*`) into `flags`.
///
/// # Safety
///
/// `state` points to a state set by `reset`, `flags` to a writable byte.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_f32_faults(
    state: *const BushingF32State,
    flags: *mut u8,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { faults(state, flags) }
}

/// Clears the fault flags and the count of refused steps.
///
/// # Safety
///
/// `state` points to a state set by `reset`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_f32_clear_faults(
    state: *mut BushingF32State,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { clear_faults(state) }
}

/// `bushing_f32_init` in Q16.
///
/// # Safety
///
/// As `bushing_f32_init`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_q16_init(
    model: *mut BushingQ16,
    spec: *const BushingSpec,
    error: *mut BushingError,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { init(model, spec, error, model::build) }
}

/// `bushing_f32_reset` in Q16: `x0` in Q16.16 mm.
///
/// # Safety
///
/// As `bushing_f32_reset`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_q16_reset(
    model: *const BushingQ16,
    state: *mut BushingQ16State,
    x0: i32,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { reset(model, state, x0) }
}

/// `bushing_f32_step` in Q16: `x` in Q16.16 mm.
///
/// # Safety
///
/// As `bushing_f32_step`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_q16_step(
    model: *const BushingQ16,
    state: *mut BushingQ16State,
    x: i32,
    out: *mut BushingQ16Output,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { step_with(model, state, out, |m, s| advance::<Q16>(m, s, x)) }
}

/// `bushing_f32_trial` in Q16.
///
/// # Safety
///
/// As `bushing_f32_trial`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_q16_trial(
    model: *const BushingQ16,
    state: *const BushingQ16State,
    x: i32,
    out: *mut BushingQ16Output,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { trial_with(model, state, out, |m, s| advance::<Q16>(m, s, x)) }
}

/// `bushing_f32_faults` in Q16.
///
/// # Safety
///
/// As `bushing_f32_faults`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_q16_faults(
    state: *const BushingQ16State,
    flags: *mut u8,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { faults(state, flags) }
}

/// `bushing_f32_clear_faults` in Q16.
///
/// # Safety
///
/// As `bushing_f32_clear_faults`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn bushing_q16_clear_faults(
    state: *mut BushingQ16State,
) -> BushingStatusCode {
    // SAFETY: the same contract.
    unsafe { clear_faults(state) }
}

/// Fault flag: an input was NaN or infinite.
pub const BUSHING_FAULT_NON_FINITE_INPUT: u8 = 1;
/// Fault flag: the input, or the backbone force or tangent there, beyond
/// the guard.
pub const BUSHING_FAULT_OUT_OF_RANGE: u8 = 2;
/// Fault flag: a step's dissipated energy was not finite (reported as 0).
pub const BUSHING_FAULT_ENERGY_OVERFLOW: u8 = 4;
/// Fault flag: a force or tangent would have left the guard; the step was
/// refused.
pub const BUSHING_FAULT_FORCE_OUT_OF_RANGE: u8 = 8;

#[cfg(test)]
mod tests {
    use super::*;
    use bushing::Faults;

    #[test]
    fn the_fault_constants_are_the_cores() {
        let c = [
            BUSHING_FAULT_NON_FINITE_INPUT,
            BUSHING_FAULT_OUT_OF_RANGE,
            BUSHING_FAULT_ENERGY_OVERFLOW,
            BUSHING_FAULT_FORCE_OUT_OF_RANGE,
        ];
        let core: Vec<u8> = Faults::FLAGS.iter().map(|(f, _)| f.bits()).collect();
        assert_eq!(c.to_vec(), core);
    }
}
