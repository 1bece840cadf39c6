//! What a case returns: a failed check with the value it measured and the
//! bound it broke, and the checks that make one.

use core::fmt;

use bushing::ParamError;

/// A failed check: what was measured, the value and the bound it broke.
#[derive(Debug, Clone, Copy)]
pub struct Failure {
    /// What was checked.
    pub what: &'static str,
    /// Value measured.
    pub got: f64,
    /// Bound it had to meet.
    pub bound: f64,
    /// For bit-exact checks: the pattern found and the one required.
    pub bits: Option<(u64, u64)>,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.bits {
            Some((got, want)) => write!(f, "{}: got {got:#018x}, want {want:#018x}", self.what),
            None => write!(
                f,
                "{}: got {:e}, bound {:e}",
                self.what, self.got, self.bound
            ),
        }
    }
}

/// Result of one case.
pub type CaseResult = Result<(), Failure>;

/// Fails with `what` unless `got <= bound` (NaN fails).
pub fn at_most(what: &'static str, got: f64, bound: f64) -> CaseResult {
    if got <= bound {
        Ok(())
    } else {
        Err(Failure {
            what,
            got,
            bound,
            bits: None,
        })
    }
}

/// Fails with `what` unless `cond`.
pub fn holds(what: &'static str, cond: bool) -> CaseResult {
    if cond {
        Ok(())
    } else {
        Err(Failure {
            what,
            got: 0.0,
            bound: 1.0,
            bits: None,
        })
    }
}

pub(crate) fn param(_: ParamError) -> Failure {
    Failure {
        what: "parameters refused",
        got: 1.0,
        bound: 0.0,
        bits: None,
    }
}
