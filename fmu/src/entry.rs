//! The `fmi2*` functions, in the order of the FMI 2.0 standard's
//! chapter 2 and 4 (common functions, then co-simulation).
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int};

use bushing_sim::fmu::{FmuModel, FmuState, Report, Slave, Status, resource_dir};

use super::boundary::{
    CATEGORIES, CallbackFunctions, FMI2_COSIMULATION, FMI2_ERROR, FMI2_OK, Fmi2Status, Instance,
    instance, log_to, null, slice, slice_mut, text, with_slave,
};

/// `fmi2FMUstate`: a boxed [`FmuState`].
pub type StateHandle = *mut FmuState;

/// `fmi2GetTypesPlatform`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `fmi2GetVersion`.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2Instantiate`: reads `resources/model.toml` at the resource
/// location and checks it against the GUID. Null, with the reason logged,
/// when anything is wrong (a model-exchange request, a missing or
/// malformed model, another GUID).
///
/// # Safety
/// The strings are null or NUL-terminated; `functions` is null or points
/// to the master's callback functions, which outlive the instance.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    guid: *const c_char,
    resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    _logging_on: c_int,
) -> *mut Instance {
    // SAFETY: the master's callbacks, valid for the instance's life.
    let callbacks = unsafe { functions.as_ref() }.copied();
    let (logger, env) = callbacks.map_or((None, std::ptr::null_mut()), |f| {
        (f.logger, f.component_environment)
    });
    // SAFETY: the master's strings, NUL-terminated.
    let (name, guid, location) =
        unsafe { (text(instance_name), text(guid), text(resource_location)) };
    let name = std::ffi::CString::new(name.unwrap_or("bushing")).unwrap_or_default();
    let fail = |message: String| {
        log_to(
            logger,
            env,
            &name,
            Status::Error,
            c"logStatusError",
            &message,
        );
        std::ptr::null_mut()
    };
    let built = std::panic::catch_unwind(|| {
        if fmu_type != FMI2_COSIMULATION {
            return Err(format!(
                "fmi2Instantiate: this FMU is for co-simulation only (fmuType {fmu_type})"
            ));
        }
        let guid = guid.ok_or("fmi2Instantiate: the GUID is null or not UTF-8")?;
        let location =
            location.ok_or("fmi2Instantiate: the resource location is null or not UTF-8")?;
        let dir = resource_dir(location).map_err(|e| format!("fmi2Instantiate: {e}"))?;
        let model =
            FmuModel::load(&dir).map_err(|e| format!("fmi2Instantiate: the FMU's model: {e}"))?;
        Slave::new(model, guid).map_err(|r| format!("fmi2Instantiate: {}", r.message))
    });
    match built {
        Ok(Ok(slave)) => Box::into_raw(Box::new(Instance {
            slave: Some(slave),
            name,
            logger,
            env,
            logged: [true; 3],
        })),
        Ok(Err(message)) => fail(message),
        Err(payload) => fail(format!(
            "fmi2Instantiate: internal failure ({})",
            super::boundary::panic_text(&*payload)
        )),
    }
}

/// `fmi2FreeInstance`.
///
/// # Safety
/// `c` is null or an instance from [`fmi2Instantiate`] not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: *mut Instance) {
    if !c.is_null() {
        // SAFETY: the caller's contract: `c` came from `Box::into_raw`.
        drop(unsafe { Box::from_raw(c) });
    }
}

/// `fmi2SetDebugLogging`: with no categories, every category on or off;
/// else the named ones (an unknown name is an error).
///
/// # Safety
/// `c` as for every call; `categories` points to `n` strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: *mut Instance,
    logging_on: c_int,
    n: usize,
    categories: *const *const c_char,
) -> Fmi2Status {
    // SAFETY: the caller's contract (see `with_slave`).
    let Some(instance) = (unsafe { c.as_mut() }) else {
        return FMI2_ERROR;
    };
    // SAFETY: `n` string pointers at `categories`.
    let Some(names) = (unsafe { slice(categories, n) }) else {
        return FMI2_ERROR;
    };
    let on = logging_on != 0;
    if names.is_empty() {
        instance.logged = [on; 3];
        return FMI2_OK;
    }
    for &p in names {
        // SAFETY: each is a NUL-terminated string.
        let name = unsafe { text(p) }.unwrap_or("");
        match CATEGORIES.iter().position(|(c, _)| c.to_str() == Ok(name)) {
            Some(i) => instance.logged[i] = on,
            None => {
                instance.log(
                    Status::Error,
                    &format!("fmi2SetDebugLogging: no log category {name:?}"),
                );
                return FMI2_ERROR;
            }
        }
    }
    FMI2_OK
}

/// `fmi2SetupExperiment`: the start time (tolerance and stop time are
/// not used: the model's step is fixed).
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: *mut Instance,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    _stop_time_defined: c_int,
    _stop_time: f64,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2SetupExperiment", |s| {
        s.setup_experiment(start_time).map(|()| None)
    })
}

/// `fmi2EnterInitializationMode`.
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: *mut Instance) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2EnterInitializationMode", |s| {
        s.enter_initialization().map(|()| None)
    })
}

/// `fmi2ExitInitializationMode`.
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: *mut Instance) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2ExitInitializationMode", |s| {
        s.exit_initialization().map(|()| None)
    })
}

/// `fmi2Terminate`.
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: *mut Instance) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2Terminate", |s| s.terminate().map(|()| None))
}

/// `fmi2Reset`.
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: *mut Instance) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2Reset", |s| s.reset().map(|()| None))
}

/// The getters' shape: `n` value references, and `n` values written with
/// what `get` reads, until one is refused.
///
/// # Safety
/// `vr` points to `n` elements and `values` to `n` writable ones, not
/// aliasing `vr`.
unsafe fn get_values<V>(
    c: *mut Instance,
    call: &str,
    vr: *const u32,
    n: usize,
    values: *mut V,
    get: impl Fn(&mut Slave, u32) -> Result<V, Report>,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, call, |s| {
        // SAFETY: the caller's contract.
        let (Some(refs), Some(values)) = (unsafe { slice(vr, n) }, unsafe { slice_mut(values, n) })
        else {
            return Err(null(s, call, "the value reference or value array"));
        };
        for (&r, v) in refs.iter().zip(values.iter_mut()) {
            *v = get(s, r)?;
        }
        Ok(None)
    })
}

/// The setters' shape: `n` value references and `n` values, each pair
/// handed to `set` until one is refused (the values are only read).
///
/// # Safety
/// `vr` and `values` point to `n` elements.
unsafe fn set_values<V: Copy>(
    c: *mut Instance,
    call: &str,
    vr: *const u32,
    n: usize,
    values: *const V,
    set: impl Fn(&mut Slave, u32, V) -> Result<(), Report>,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, call, |s| {
        // SAFETY: the caller's contract.
        let (Some(refs), Some(values)) = (unsafe { slice(vr, n) }, unsafe { slice(values, n) })
        else {
            return Err(null(s, call, "the value reference or value array"));
        };
        for (&r, &v) in refs.iter().zip(values) {
            set(s, r, v)?;
        }
        Ok(None)
    })
}

/// `fmi2GetReal`.
///
/// # Safety
/// `c` as for every call; `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    value: *mut f64,
) -> Fmi2Status {
    // SAFETY: the caller's contract.
    unsafe { get_values(c, "fmi2GetReal", vr, n, value, Slave::get_real) }
}

/// `fmi2GetInteger`.
///
/// # Safety
/// `c` as for every call; `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    value: *mut c_int,
) -> Fmi2Status {
    // SAFETY: the caller's contract.
    unsafe { get_values(c, "fmi2GetInteger", vr, n, value, Slave::get_integer) }
}

/// `fmi2SetReal`.
///
/// # Safety
/// `c` as for every call; `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    value: *const f64,
) -> Fmi2Status {
    // SAFETY: the caller's contract; the values are only read.
    unsafe { set_values(c, "fmi2SetReal", vr, n, value, Slave::set_real) }
}

/// `fmi2SetInteger`: the FMU has no Integer input.
///
/// # Safety
/// `c` as for every call; `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    value: *const c_int,
) -> Fmi2Status {
    // SAFETY: the caller's contract; the values are only read.
    unsafe {
        set_values(c, "fmi2SetInteger", vr, n, value, |s, r, _| {
            s.set_integer(r)
        })
    }
}

/// The Boolean and String accessors: the FMU has no such variable, so
/// any value reference is refused (none at all is fine).
unsafe fn no_variable(
    c: *mut Instance,
    call: &str,
    kind: &str,
    vr: *const u32,
    n: usize,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, call, |s| {
        // SAFETY: the caller's contract: `n` value references at `vr`.
        match unsafe { slice(vr, n) } {
            None => Err(null(s, call, "the value reference array")),
            Some([]) => Ok(None),
            Some([r, ..]) => Err(s.refuse(format!(
                "{call}: no {kind} variable has value reference {r}"
            ))),
        }
    })
}

/// `fmi2GetBoolean`: no Boolean variable.
///
/// # Safety
/// `c` as for every call; `vr` points to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    _value: *mut c_int,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe { no_variable(c, "fmi2GetBoolean", "Boolean", vr, n) }
}

/// `fmi2SetBoolean`: no Boolean variable.
///
/// # Safety
/// `c` as for every call; `vr` points to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    _value: *const c_int,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe { no_variable(c, "fmi2SetBoolean", "Boolean", vr, n) }
}

/// `fmi2GetString`: no String variable.
///
/// # Safety
/// `c` as for every call; `vr` points to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    _value: *mut *const c_char,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe { no_variable(c, "fmi2GetString", "String", vr, n) }
}

/// `fmi2SetString`: no String variable.
///
/// # Safety
/// `c` as for every call; `vr` points to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: *mut Instance,
    vr: *const u32,
    n: usize,
    _value: *const *const c_char,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe { no_variable(c, "fmi2SetString", "String", vr, n) }
}

/// `fmi2GetFMUstate`: a new state in `*state` when it is null, else the
/// state there overwritten.
///
/// # Safety
/// `c` as for every call; `state` points to null or to a state from this
/// FMU not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: *mut Instance, state: *mut StateHandle) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2GetFMUstate", |s| {
        // SAFETY: the caller's contract.
        let Some(handle) = (unsafe { state.as_mut() }) else {
            return Err(null(s, "fmi2GetFMUstate", "the state pointer"));
        };
        let saved = s.get_state()?;
        // SAFETY: a non-null handle is a `Box<FmuState>` of ours.
        match unsafe { handle.as_mut() } {
            Some(old) => *old = saved,
            None => *handle = Box::into_raw(Box::new(saved)),
        }
        Ok(None)
    })
}

/// `fmi2SetFMUstate`.
///
/// # Safety
/// `c` as for every call; `state` is null or a state from this FMU not
/// freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: *mut Instance, state: StateHandle) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2SetFMUstate", |s| {
        // SAFETY: the caller's contract.
        match unsafe { state.as_ref() } {
            Some(saved) => s.set_state(saved).map(|()| None),
            None => Err(null(s, "fmi2SetFMUstate", "the state")),
        }
    })
}

/// `fmi2FreeFMUstate`: frees `*state` and sets it to null.
///
/// # Safety
/// `c` as for every call; `state` points to null or to a state from this
/// FMU not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: *mut Instance, state: *mut StateHandle) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2FreeFMUstate", |s| {
        // SAFETY: the caller's contract.
        let Some(handle) = (unsafe { state.as_mut() }) else {
            return Err(null(s, "fmi2FreeFMUstate", "the state pointer"));
        };
        if !handle.is_null() {
            // SAFETY: a `Box<FmuState>` of ours, freed once: the handle is
            // cleared.
            drop(unsafe { Box::from_raw(*handle) });
            *handle = std::ptr::null_mut();
        }
        Ok(None)
    })
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// `c` as for every call; `state` is a state of this FMU; `size` is
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: *mut Instance,
    state: StateHandle,
    size: *mut usize,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2SerializedFMUstateSize", |s| {
        // SAFETY: the caller's contract.
        let (Some(saved), Some(size)) = (unsafe { state.as_ref() }, unsafe { size.as_mut() })
        else {
            return Err(null(
                s,
                "fmi2SerializedFMUstateSize",
                "the state or the size",
            ));
        };
        *size = s.serialize(saved).len();
        Ok(None)
    })
}

/// `fmi2SerializeFMUstate`: refused when `size` is not the size
/// [`fmi2SerializedFMUstateSize`] gave.
///
/// # Safety
/// `c` as for every call; `state` is a state of this FMU; `bytes` points
/// to `size` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: *mut Instance,
    state: StateHandle,
    bytes: *mut c_char,
    size: usize,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2SerializeFMUstate", |s| {
        // SAFETY: the caller's contract.
        let (Some(saved), Some(out)) = (unsafe { state.as_ref() }, unsafe {
            slice_mut(bytes.cast::<u8>(), size)
        }) else {
            return Err(null(s, "fmi2SerializeFMUstate", "the state or the buffer"));
        };
        let data = s.serialize(saved);
        if data.len() != out.len() {
            return Err(s.refuse(format!(
                "fmi2SerializeFMUstate: the buffer has {} bytes, the state {}",
                out.len(),
                data.len()
            )));
        }
        out.copy_from_slice(&data);
        Ok(None)
    })
}

/// `fmi2DeSerializeFMUstate`: into `*state` as [`fmi2GetFMUstate`] does.
///
/// # Safety
/// `c` as for every call; `bytes` points to `size` bytes; `state` as for
/// [`fmi2GetFMUstate`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: *mut Instance,
    bytes: *const c_char,
    size: usize,
    state: *mut StateHandle,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2DeSerializeFMUstate", |s| {
        // SAFETY: the caller's contract.
        let (Some(data), Some(handle)) = (unsafe { slice(bytes.cast::<u8>(), size) }, unsafe {
            state.as_mut()
        }) else {
            return Err(null(
                s,
                "fmi2DeSerializeFMUstate",
                "the bytes or the state pointer",
            ));
        };
        let saved = s.deserialize(data)?;
        // SAFETY: a non-null handle is a `Box<FmuState>` of ours.
        match unsafe { handle.as_mut() } {
            Some(old) => *old = saved,
            None => *handle = Box::into_raw(Box::new(saved)),
        }
        Ok(None)
    })
}

/// A function the FMU does not provide (its capability flag is false).
unsafe fn not_provided(c: *mut Instance, call: &str, why: &str) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, call, |s| Err(s.refuse(format!("{call}: {why}"))))
}

/// `fmi2GetDirectionalDerivative`: not provided
/// (`providesDirectionalDerivative="false"`).
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: *mut Instance,
    _unknown: *const u32,
    _n_unknown: usize,
    _known: *const u32,
    _n_known: usize,
    _dv_known: *const f64,
    _dv_unknown: *mut f64,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        not_provided(
            c,
            "fmi2GetDirectionalDerivative",
            "not provided; the tangent output is dF/dx",
        )
    }
}

/// `fmi2SetRealInputDerivatives`: not provided (`canInterpolateInputs`
/// is false: inputs are held over a communication step).
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut Instance,
    _vr: *const u32,
    _n: usize,
    _order: *const c_int,
    _value: *const f64,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        not_provided(
            c,
            "fmi2SetRealInputDerivatives",
            "inputs are held over a communication step (canInterpolateInputs is false)",
        )
    }
}

/// `fmi2GetRealOutputDerivatives`: not provided
/// (`maxOutputDerivativeOrder` is 0).
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: *mut Instance,
    _vr: *const u32,
    _n: usize,
    _order: *const c_int,
    _value: *mut f64,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        not_provided(
            c,
            "fmi2GetRealOutputDerivatives",
            "not provided (maxOutputDerivativeOrder is 0)",
        )
    }
}

/// `fmi2DoStep`: a whole number of model steps, the inputs held.
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: *mut Instance,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior: c_int,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, "fmi2DoStep", |s| {
        s.do_step(current_communication_point, communication_step_size)
    })
}

/// `fmi2CancelStep`: steps are synchronous, there is nothing to cancel.
///
/// # Safety
/// `c` as for every call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: *mut Instance) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        not_provided(
            c,
            "fmi2CancelStep",
            "steps are synchronous (no step is pending)",
        )
    }
}

/// `fmi2StatusKind`: `fmi2DoStepStatus`.
const DO_STEP_STATUS: c_int = 0;
/// `fmi2StatusKind`: `fmi2PendingStatus`.
const PENDING_STATUS: c_int = 1;
/// `fmi2StatusKind`: `fmi2LastSuccessfulTime`.
const LAST_SUCCESSFUL_TIME: c_int = 2;
/// `fmi2StatusKind`: `fmi2Terminated`.
const TERMINATED: c_int = 3;

/// The status getters: `read` answers the kinds it knows.
unsafe fn status_of<V>(
    c: *mut Instance,
    call: &str,
    kind: c_int,
    value: *mut V,
    read: impl FnOnce(&Slave, c_int) -> Option<V>,
) -> Fmi2Status {
    // SAFETY: `c` is null or a live instance of ours (the caller's contract).
    let c = unsafe { instance(c) };
    with_slave(c, call, |s| {
        // SAFETY: the caller's contract: `value` is writable.
        let Some(out) = (unsafe { value.as_mut() }) else {
            return Err(null(s, call, "the value pointer"));
        };
        match read(&*s, kind) {
            Some(v) => {
                *out = v;
                Ok(None)
            }
            None => Err(s.refuse(format!("{call}: no status of kind {kind}"))),
        }
    })
}

/// `fmi2GetStatus`: `fmi2DoStepStatus` is always `fmi2OK` (steps are
/// synchronous).
///
/// # Safety
/// `c` as for every call; `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: *mut Instance,
    kind: c_int,
    value: *mut Fmi2Status,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        status_of(c, "fmi2GetStatus", kind, value, |_, k| {
            matches!(k, DO_STEP_STATUS | PENDING_STATUS).then_some(FMI2_OK)
        })
    }
}

/// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime`.
///
/// # Safety
/// `c` as for every call; `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: *mut Instance,
    kind: c_int,
    value: *mut f64,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        status_of(c, "fmi2GetRealStatus", kind, value, |s, k| {
            (k == LAST_SUCCESSFUL_TIME).then(|| s.time())
        })
    }
}

/// `fmi2GetIntegerStatus`: no Integer status.
///
/// # Safety
/// `c` as for every call; `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: *mut Instance,
    kind: c_int,
    value: *mut c_int,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe { status_of(c, "fmi2GetIntegerStatus", kind, value, |_, _| None) }
}

/// `fmi2GetBooleanStatus`: `fmi2Terminated` is false (the slave never
/// ends a simulation itself).
///
/// # Safety
/// `c` as for every call; `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: *mut Instance,
    kind: c_int,
    value: *mut c_int,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        status_of(c, "fmi2GetBooleanStatus", kind, value, |_, k| {
            (k == TERMINATED).then_some(0)
        })
    }
}

/// `fmi2GetStringStatus`: no String status.
///
/// # Safety
/// `c` as for every call; `value` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: *mut Instance,
    kind: c_int,
    value: *mut *const c_char,
) -> Fmi2Status {
    // SAFETY: the caller's contract, passed on.
    unsafe { status_of(c, "fmi2GetStringStatus", kind, value, |_, _| None) }
}
