//! The parameter checks the profiles share: each names the parameter and
//! the bound it breaks.

use super::MAX_LIST;

pub(super) fn finite(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} must be finite, got {v}"))
    }
}

pub(super) fn finite_positive(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{name} must be finite and > 0, got {v}"))
    }
}

pub(super) fn finite_non_negative(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("{name} must be finite and >= 0, got {v}"))
    }
}

pub(super) fn list_len(name: &str, n: usize) -> Result<(), String> {
    if n == 0 || n > MAX_LIST {
        Err(format!("{name}: 1 to {MAX_LIST} values expected, got {n}"))
    } else {
        Ok(())
    }
}

/// A sampled sine must stay below half the rate.
pub(super) fn below_nyquist(name: &str, f: f64, dt: f64) -> Result<(), String> {
    if f * dt < 0.5 {
        Ok(())
    } else {
        Err(format!(
            "{name} = {f} Hz must be below half the rate ({} Hz)",
            0.5 / dt
        ))
    }
}
