//! Hysteretic relaxation with a turning-point stack (seed 000 eqs
//! 1.27-1.29, 1.41-1.42): `type = "turning-points"`.
//!
//! ```toml
//! [[effects]]
//! type = "turning-points"
//! law = "sts"                # sts (needs c, k1) or table (needs d, k)
//! c = 40.0                   # N²/mm
//! k1 = 60.0                  # N/mm
//! first_loading = "masing"   # masing (default) or ignored
//! ```

use bushing::{FirstLoading, KfTable, ParamError, Real, Relaxation, Sts, TurningPoints};
use serde::Deserialize;

use super::AnyEffect;
use crate::reference::{INNER_SPAN, Line, Measured, compared, no, simpson};

/// Turning points a scene's stack model holds.
pub const STACK_DEPTH: usize = 32;
/// Points a scene's K_f table may hold.
pub const TABLE_POINTS: usize = 64;

/// Turning-point model with the STS law.
pub type StsStack<T> = TurningPoints<Sts<T>, STACK_DEPTH>;
/// Turning-point model with a measured K_f table.
pub type TableStack<T> = TurningPoints<KfTable<T, TABLE_POINTS>, STACK_DEPTH>;

/// `[[effects]] type = "turning-points"`, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackTable {
    /// Which law: its parameters follow.
    pub law: LawName,
    /// STS constant C in N²/mm.
    #[serde(default)]
    pub c: Option<f64>,
    /// STS stiffness at a turning point K_1 in N/mm.
    #[serde(default)]
    pub k1: Option<f64>,
    /// Table: distances from the turning point in mm.
    #[serde(default)]
    pub d: Option<Vec<f64>>,
    /// Table: K_f in N/mm, non-increasing.
    #[serde(default)]
    pub k: Option<Vec<f64>>,
    /// Masing's rule (default) or the initial point as a turning point.
    #[serde(default = "masing")]
    pub first_loading: FirstLoading,
}

fn masing() -> FirstLoading {
    FirstLoading::Masing
}

/// The law a table names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LawName {
    /// Continuous STS (eq 1.29), with `c` and `k1`.
    Sts,
    /// Measured K_f(d) (eq 1.28), with `d` and `k`.
    Table,
}

/// A hysteretic relaxation law, checked.
#[derive(Debug, Clone, PartialEq)]
pub enum Law {
    /// Continuous STS.
    Sts {
        /// C in N²/mm.
        c: f64,
        /// K_1 in N/mm.
        k1: f64,
    },
    /// Measured K_f(d).
    Table {
        /// Distances, mm.
        d: Vec<f64>,
        /// K_f, N/mm.
        k: Vec<f64>,
    },
}

/// A checked turning-point model.
#[derive(Debug, Clone, PartialEq)]
pub struct Stack {
    /// The law.
    pub law: Law,
    /// First loading rule.
    pub first_loading: FirstLoading,
}

impl StackTable {
    /// The law with exactly its own parameters.
    pub(super) fn check(self) -> Result<Stack, String> {
        let law = match (self.law, self.c, self.k1, self.d, self.k) {
            (LawName::Sts, Some(c), Some(k1), None, None) => Law::Sts { c, k1 },
            (LawName::Sts, ..) => {
                return Err("law 'sts' takes c (N²/mm) and k1 (N/mm), and no d or k".into());
            }
            (LawName::Table, None, None, Some(d), Some(k)) => Law::Table { d, k },
            (LawName::Table, ..) => {
                return Err("law 'table' takes d (mm) and k (N/mm), and no c or k1".into());
            }
        };
        Ok(Stack {
            law,
            first_loading: self.first_loading,
        })
    }
}

impl Stack {
    /// The model in `T`.
    pub fn build<T: Real>(&self) -> Result<AnyEffect<T>, ParamError> {
        Ok(match &self.law {
            Law::Sts { c, k1 } => {
                AnyEffect::Sts(TurningPoints::new(Sts::new(*c, *k1)?, self.first_loading))
            }
            Law::Table { d, k } => {
                AnyEffect::Table(TurningPoints::new(KfTable::new(d, k)?, self.first_loading))
            }
        })
    }

    /// Name for reports and trace columns.
    pub fn name(&self) -> String {
        match &self.law {
            Law::Sts { .. } => "turning-points sts".into(),
            Law::Table { d, .. } => format!("turning-points table x{}", d.len()),
        }
    }

    /// H(d) of the law, in f64.
    fn branch(&self, d: f64) -> Option<f64> {
        match &self.law {
            Law::Sts { c, k1 } => Sts::<f64>::new(*c, *k1).ok().map(|s| s.branch(d).0),
            Law::Table { d: ds, k } => KfTable::<f64, TABLE_POINTS>::new(ds, k)
                .ok()
                .map(|t| t.branch(d).0),
        }
    }

    /// Masing's loop of the law (in f64): the half peak-to-peak force
    /// `H(2A)/2`, the energy per cycle `2 ∫_0^{2A} H - 2A H(2A)`, and the
    /// asymmetric inner loop.
    pub(super) fn references(&self, m: &Measured) -> Vec<Line> {
        let a = m.amplitude;
        let h = |d: f64| self.branch(d);
        let Some(h2a) = h(2.0 * a) else {
            return no("the law could not be built");
        };
        // Masing's loop of span s: 2 ∫_0^s H - s H(s).
        let masing = |s: f64| {
            let integral = simpson(|d| h(d).unwrap_or(f64::NAN), 0.0, s, 20_000);
            2.0 * integral - s * h(s).unwrap_or(f64::NAN)
        };
        vec![
            compared("half peak-to-peak force, H(2A)/2", "N", 0.5 * h2a, m.swing),
            compared(
                "energy per steady cycle, Masing loop 2 int_0^2A H - 2A H(2A)",
                "mJ",
                masing(2.0 * a),
                m.per_cycle,
            ),
            m.inner_loop(masing(INNER_SPAN * a)),
        ]
    }
}
