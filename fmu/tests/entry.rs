//! The C entry points called as a master calls them: the handles, null
//! pointers, the calls the FMU does not provide, the status kinds and the
//! state buffers. (`scripts/fmu.sh` runs the packed FMU under fmpy.)
#![allow(unsafe_code)]

use std::ffi::{CString, c_char, c_int};
use std::path::Path;
use std::ptr::{null, null_mut};

use bushing_fmu::*;
use bushing_sim::fmu::FmuModel;
use bushing_sim::scene::LoadOptions;

/// An instance of the Maxwell scene's FMU (resources in `dir`).
fn instance(dir: &Path, guid: Option<&str>) -> *mut Instance {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/maxwell4.toml");
    let model = FmuModel::from_scene(&scene, LoadOptions::default()).unwrap();
    std::fs::write(dir.join("model.toml"), &model.text).unwrap();
    let location = CString::new(format!("file://{}", dir.display())).unwrap();
    let guid = CString::new(guid.unwrap_or(&model.guid)).unwrap();
    // SAFETY: NUL-terminated strings that outlive the call; no callbacks.
    unsafe {
        fmi2Instantiate(
            c"test".as_ptr(),
            FMI2_COSIMULATION,
            guid.as_ptr(),
            location.as_ptr(),
            null(),
            0,
            0,
        )
    }
}

/// Initialised at rest at 0.
fn started(dir: &Path) -> *mut Instance {
    let c = instance(dir, None);
    assert!(!c.is_null());
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), FMI2_OK);
        assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
        assert_eq!(fmi2ExitInitializationMode(c), FMI2_OK);
    }
    c
}

#[test]
fn version_and_platform() {
    // SAFETY: static strings.
    let (v, p) = unsafe {
        (
            std::ffi::CStr::from_ptr(fmi2GetVersion()),
            std::ffi::CStr::from_ptr(fmi2GetTypesPlatform()),
        )
    };
    assert_eq!(v.to_str(), Ok("2.0"));
    assert_eq!(p.to_str(), Ok("default"));
}

#[test]
fn instantiation_is_refused_with_null() {
    let dir = tempfile::tempdir().unwrap();
    assert!(instance(dir.path(), Some("{not-the-guid}")).is_null());
    let location = CString::new(format!("file://{}", dir.path().display())).unwrap();
    // SAFETY: NUL-terminated strings or null; no callbacks.
    unsafe {
        // Model exchange, and null arguments.
        let me = fmi2Instantiate(
            c"m".as_ptr(),
            0,
            c"{g}".as_ptr(),
            location.as_ptr(),
            null(),
            0,
            0,
        );
        assert!(me.is_null());
        let no_guid = fmi2Instantiate(null(), 1, null(), location.as_ptr(), null(), 0, 0);
        assert!(no_guid.is_null());
        let no_place = fmi2Instantiate(null(), 1, c"{g}".as_ptr(), null(), null(), 0, 0);
        assert!(no_place.is_null());
        let elsewhere = fmi2Instantiate(
            null(),
            1,
            c"{g}".as_ptr(),
            c"http://x/r".as_ptr(),
            null(),
            0,
            0,
        );
        assert!(elsewhere.is_null());
    }
}

#[test]
fn null_handles_and_arrays_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let c = started(dir.path());
    let vr = [0u32];
    let mut v = [0.0f64];
    // SAFETY: a live instance, null pointers where the test says so.
    unsafe {
        assert_eq!(fmi2DoStep(null_mut(), 0.0, 1e-3, 0), FMI2_ERROR);
        assert_eq!(
            fmi2GetReal(null_mut(), vr.as_ptr(), 1, v.as_mut_ptr()),
            FMI2_ERROR
        );
        assert_eq!(fmi2GetReal(c, null(), 1, v.as_mut_ptr()), FMI2_ERROR);
        // An error is left by a reset.
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(fmi2SetReal(c, vr.as_ptr(), 1, null()), FMI2_ERROR);
        assert_eq!(fmi2Reset(c), FMI2_OK);
        // No values asked: nothing read, fine.
        assert_eq!(fmi2SetReal(c, null(), 0, null()), FMI2_OK);
        assert_eq!(fmi2GetFMUstate(c, null_mut()), FMI2_ERROR);
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(fmi2SetFMUstate(c, null_mut()), FMI2_ERROR);
        fmi2FreeInstance(c);
        fmi2FreeInstance(null_mut());
    }
}

#[test]
fn variables_the_fmu_does_not_have() {
    let dir = tempfile::tempdir().unwrap();
    let c = started(dir.path());
    let vr = [0u32];
    let mut b = [0 as c_int];
    let mut s = [null::<c_char>()];
    // SAFETY: a live instance and arrays of one element.
    unsafe {
        assert_eq!(fmi2GetBoolean(c, vr.as_ptr(), 0, b.as_mut_ptr()), FMI2_OK);
        assert_eq!(
            fmi2GetBoolean(c, vr.as_ptr(), 1, b.as_mut_ptr()),
            FMI2_ERROR
        );
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(fmi2SetString(c, vr.as_ptr(), 1, s.as_ptr()), FMI2_ERROR);
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(fmi2GetString(c, vr.as_ptr(), 1, s.as_mut_ptr()), FMI2_ERROR);
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(fmi2SetInteger(c, vr.as_ptr(), 1, b.as_ptr()), FMI2_ERROR);
        fmi2FreeInstance(c);
    }
}

#[test]
fn functions_not_provided_and_status_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let c = started(dir.path());
    let mut status = -1;
    let mut time = -1.0;
    let mut flag = -1;
    // SAFETY: a live instance and writable values.
    unsafe {
        assert_eq!(fmi2DoStep(c, 0.0, 2.0 * 5e-4, 0), FMI2_OK);
        assert_eq!(fmi2GetStatus(c, 0, &mut status), FMI2_OK);
        assert_eq!(status, FMI2_OK);
        assert_eq!(fmi2GetRealStatus(c, 2, &mut time), FMI2_OK);
        assert_eq!(time, 1e-3);
        assert_eq!(fmi2GetBooleanStatus(c, 3, &mut flag), FMI2_OK);
        assert_eq!(flag, 0);
        assert_eq!(fmi2CancelStep(c), FMI2_ERROR);
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(
            fmi2GetDirectionalDerivative(c, null(), 0, null(), 0, null(), null_mut()),
            FMI2_ERROR
        );
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(
            fmi2SetRealInputDerivatives(c, null(), 0, null(), null()),
            FMI2_ERROR
        );
        assert_eq!(fmi2Reset(c), FMI2_OK);
        let mut n = 0;
        assert_eq!(fmi2GetIntegerStatus(c, 0, &mut n), FMI2_ERROR);
        fmi2FreeInstance(c);
    }
}

#[test]
fn logging_categories() {
    let dir = tempfile::tempdir().unwrap();
    let c = started(dir.path());
    let known = [c"logStatusError".as_ptr()];
    let unknown = [c"logEverything".as_ptr()];
    // SAFETY: a live instance and arrays of C strings.
    unsafe {
        assert_eq!(fmi2SetDebugLogging(c, 1, 0, null()), FMI2_OK);
        assert_eq!(fmi2SetDebugLogging(c, 0, 1, known.as_ptr()), FMI2_OK);
        assert_eq!(fmi2SetDebugLogging(c, 1, 1, unknown.as_ptr()), FMI2_ERROR);
        fmi2FreeInstance(c);
    }
}

#[test]
fn states_through_handles_and_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let c = started(dir.path());
    let (x, force) = ([0u32], [1u32]);
    let step = |k: u32| {
        let v = [0.5 * f64::from(k).sin()];
        let mut f = [0.0];
        // SAFETY: a live instance and arrays of one element.
        unsafe {
            let mut t = 0.0;
            assert_eq!(fmi2GetRealStatus(c, 2, &mut t), FMI2_OK);
            assert_eq!(fmi2SetReal(c, x.as_ptr(), 1, v.as_ptr()), FMI2_OK);
            assert_eq!(fmi2DoStep(c, t, 3.0 * 5e-4, 1), FMI2_OK);
            assert_eq!(fmi2GetReal(c, force.as_ptr(), 1, f.as_mut_ptr()), FMI2_OK);
        }
        f[0].to_bits()
    };
    (0..50).for_each(|k| {
        step(k);
    });
    let mut state = null_mut();
    // SAFETY: a live instance; the state handle is ours until freed.
    unsafe {
        assert_eq!(fmi2GetFMUstate(c, &mut state), FMI2_OK);
        assert!(!state.is_null());
        let first: Vec<u64> = (50..100).map(step).collect();
        // Overwritten in place when the handle is not null.
        let kept = state;
        assert_eq!(fmi2SetFMUstate(c, state), FMI2_OK);
        assert_eq!(fmi2GetFMUstate(c, &mut state), FMI2_OK);
        assert_eq!(state, kept);
        assert_eq!((50..100).map(step).collect::<Vec<_>>(), first);

        let mut size = 0;
        assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), FMI2_OK);
        let mut bytes = vec![0 as c_char; size];
        // A buffer of another size is refused.
        assert_eq!(
            fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr(), size - 1),
            FMI2_ERROR
        );
        assert_eq!(fmi2SetFMUstate(c, state), FMI2_OK);
        assert_eq!(
            fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr(), size),
            FMI2_OK
        );
        let mut copy = null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(c, bytes.as_ptr(), size, &mut copy),
            FMI2_OK
        );
        assert_eq!(fmi2SetFMUstate(c, copy), FMI2_OK);
        assert_eq!((50..100).map(step).collect::<Vec<_>>(), first);
        bytes[size / 2] ^= 1;
        let mut damaged = null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(c, bytes.as_ptr(), size, &mut damaged),
            FMI2_ERROR
        );
        assert!(damaged.is_null());

        assert_eq!(fmi2FreeFMUstate(c, &mut copy), FMI2_OK);
        assert!(copy.is_null());
        assert_eq!(fmi2FreeFMUstate(c, &mut state), FMI2_OK);
        assert_eq!(fmi2FreeFMUstate(c, &mut state), FMI2_OK);
        fmi2FreeInstance(c);
    }
}
