//! What every entry point shares: the status codes, the instance, the
//! logger, and the reading of the master's pointers.
#![allow(unsafe_code)]

use std::ffi::{CStr, CString, c_char, c_int, c_void};

use bushing_sim::fmu::{Report, Slave, Status};

/// `fmi2Status`.
pub type Fmi2Status = c_int;
/// `fmi2OK`.
pub const FMI2_OK: Fmi2Status = 0;
/// `fmi2Warning`.
pub const FMI2_WARNING: Fmi2Status = 1;
/// `fmi2Discard`.
pub const FMI2_DISCARD: Fmi2Status = 2;
/// `fmi2Error`.
pub const FMI2_ERROR: Fmi2Status = 3;
/// `fmi2Fatal`.
pub const FMI2_FATAL: Fmi2Status = 4;

/// `fmi2Type` of a co-simulation instance.
pub const FMI2_COSIMULATION: c_int = 1;

/// `fmi2CallbackLogger`: `printf`-like, the message a format.
pub type Logger = unsafe extern "C" fn(
    env: *mut c_void,
    instance_name: *const c_char,
    status: Fmi2Status,
    category: *const c_char,
    message: *const c_char,
    ...
);

/// `fmi2CallbackFunctions`. Only the logger is used: the FMU allocates
/// with Rust's allocator (`canNotUseMemoryManagementFunctions`).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct CallbackFunctions {
    /// `logger`.
    pub logger: Option<Logger>,
    /// `allocateMemory` (not used).
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// `freeMemory` (not used).
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// `stepFinished` (not used: steps are synchronous).
    pub step_finished: Option<unsafe extern "C" fn(*mut c_void, Fmi2Status)>,
    /// `componentEnvironment`, handed back to the logger.
    pub component_environment: *mut c_void,
}

/// The log categories of the model description, by status.
pub(crate) const CATEGORIES: [(&CStr, Status); 3] = [
    (c"logStatusWarning", Status::Warning),
    (c"logStatusError", Status::Error),
    (c"logStatusFatal", Status::Fatal),
];

/// One FMU instance: the slave, or none once a failure inside made it
/// unusable, and what its logger needs.
#[derive(Debug)]
pub struct Instance {
    pub(crate) slave: Option<Slave>,
    pub(crate) name: CString,
    pub(crate) logger: Option<Logger>,
    pub(crate) env: *mut c_void,
    /// Which of [`CATEGORIES`] are logged.
    pub(crate) logged: [bool; 3],
}

impl Instance {
    /// Logs `message` with `status` (when its category is on).
    pub(crate) fn log(&self, status: Status, message: &str) {
        let Some((index, (category, _))) = CATEGORIES
            .iter()
            .enumerate()
            .find(|(_, (_, s))| *s == status)
        else {
            return;
        };
        if !self.logged.get(index).copied().unwrap_or(false) {
            return;
        }
        log_to(self.logger, self.env, &self.name, status, category, message);
    }

    /// The status code of a slave's answer, its message logged.
    fn answer(&self, result: Result<Option<Report>, Report>) -> Fmi2Status {
        match result {
            Ok(None) => FMI2_OK,
            Ok(Some(r)) | Err(r) => {
                self.log(r.status, &r.message);
                code(r.status)
            }
        }
    }
}

/// Calls `logger` with `message` as a `%s` argument (never as the format).
pub(crate) fn log_to(
    logger: Option<Logger>,
    env: *mut c_void,
    name: &CStr,
    status: Status,
    category: &CStr,
    message: &str,
) {
    let Some(logger) = logger else {
        return;
    };
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    // SAFETY: the logger is the master's `fmi2CallbackLogger`, called with
    // its own environment pointer, NUL-terminated strings that live over
    // the call, and a `%s` format consuming the one string argument given.
    unsafe {
        logger(
            env,
            name.as_ptr(),
            code(status),
            category.as_ptr(),
            c"%s".as_ptr(),
            text.as_ptr(),
        );
    }
}

/// `fmi2Status` of a [`Status`].
pub(crate) fn code(status: Status) -> Fmi2Status {
    match status {
        Status::Ok => FMI2_OK,
        Status::Warning => FMI2_WARNING,
        Status::Discard => FMI2_DISCARD,
        Status::Error => FMI2_ERROR,
        Status::Fatal => FMI2_FATAL,
    }
}

/// The text of a panic's payload.
pub(crate) fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into())
}

/// The instance behind a handle (`None` for null).
///
/// # Safety
/// `c` is null or an instance `fmi2Instantiate` returned and
/// `fmi2FreeInstance` has not freed (the standard's rule for every call),
/// used by one thread at a time.
pub(crate) unsafe fn instance<'a>(c: *mut Instance) -> Option<&'a mut Instance> {
    // SAFETY: the caller's contract.
    unsafe { c.as_mut() }
}

/// Runs `f` on the instance's slave: a null instance, an unusable slave
/// and a panic inside are answered here.
pub(crate) fn with_slave(
    instance: Option<&mut Instance>,
    call: &str,
    f: impl FnOnce(&mut Slave) -> Result<Option<Report>, Report>,
) -> Fmi2Status {
    let Some(instance) = instance else {
        return FMI2_ERROR;
    };
    let Some(slave) = instance.slave.as_mut() else {
        instance.log(
            Status::Fatal,
            &format!("{call}: the instance failed earlier and can only be freed"),
        );
        return FMI2_FATAL;
    };
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(slave))) {
        Ok(result) => instance.answer(result),
        Err(payload) => {
            instance.slave = None;
            let text = panic_text(&*payload);
            instance.log(
                Status::Fatal,
                &format!("{call}: internal failure ({text}); the instance can only be freed"),
            );
            FMI2_FATAL
        }
    }
}

/// Reads the C string `s` (null is `None`).
///
/// # Safety
/// A non-null `s` must be a NUL-terminated string alive for the call.
pub(crate) unsafe fn text<'a>(s: *const c_char) -> Option<&'a str> {
    if s.is_null() {
        return None;
    }
    // SAFETY: the caller's contract.
    unsafe { CStr::from_ptr(s) }.to_str().ok()
}

/// The slice of `n` elements at `p` (empty when `n` is 0; `None` when `p`
/// is null and `n` is not 0).
///
/// # Safety
/// A non-null `p` must point to `n` initialised elements alive for the
/// call.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: the caller's contract.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

/// The mutable slice of `n` elements at `p`, as [`slice`].
///
/// # Safety
/// A non-null `p` must point to `n` elements writable for the call and
/// not otherwise borrowed.
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: the caller's contract.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// A refusal for a null array or pointer argument.
pub(crate) fn null(slave: &mut Slave, call: &str, what: &str) -> Report {
    slave.refuse(format!("{call}: {what} is a null pointer"))
}
