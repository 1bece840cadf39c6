//! Iwan equivalents of the order-independent hysteresis laws: "order
//! selection is the result of the numerical implementation" (seed 000 §1.1).
//!
//! Both discretisations run once, in `f64`, at configuration time, and
//! return `N` Jenkins cells (a spring and its virgin slip distance) for an
//! [`IwanSliders`](crate::IwanSliders) or [`IwanBank`](crate::IwanBank) bank.
//!
//! - [`iwan_from_relaxation`]: the finite-order equivalent of a hysteretic
//!   relaxation law, such as the continuous STS (eqs 1.39-1.40). Breakpoints
//!   r_j (reversal spans) are placed up to `span_max`; between two of them the
//!   Iwan stiffness is the secant of H, so the Iwan reversal curve equals H at
//!   every breakpoint and the cell j that starts sliding at r_j takes the drop
//!   of that secant. For a non-increasing K_f (H concave) every cell stiffness
//!   is >= 0. Beyond `span_max` every cell slides.
//! - [`Segalman::discretize`]: Segalman's four-parameter Iwan (eqs
//!   1.36-1.38), the slip-distance density `R φ^χ` on (0, φ_max) plus a
//!   point mass S at φ_max, cut into `N - 1` bins and a last cell for the
//!   point mass. Each bin's cell has the bin's stiffness and the
//!   stiffness-weighted mean slip distance, so the initial stiffness K_T and
//!   the macro-slip force F_S are exact for every N.
//!
//! Where the breakpoints sit decides the accuracy ([`Placement`]);
//! `docs/iwan-discretization.md` tabulates both laws for N = 4 to 64.

use crate::error::{Param, ParamError, positive};
use crate::iwan::IwanCellSpec;
use crate::stack::Relaxation;

/// One Jenkins cell: spring stiffness and virgin slip distance (its slip
/// force is `stiffness * slip`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Jenkins {
    /// Spring stiffness k (N/mm).
    pub stiffness: f64,
    /// Virgin slip distance φ (mm); after a reversal it sticks over 2φ.
    pub slip: f64,
}

impl Jenkins {
    /// The cell as an Iwan cell on reference stiffness `k_ref`: fraction
    /// `k / k_ref`, slip force `k φ`.
    pub fn spec(&self, k_ref: f64) -> IwanCellSpec {
        IwanCellSpec::new(self.stiffness / k_ref, self.stiffness * self.slip)
    }
}

/// Total stiffness of a set of cells (use it as `k_ref` so that the
/// fractions add up to one).
pub fn total_stiffness(cells: &[Jenkins]) -> f64 {
    cells.iter().map(|c| c.stiffness).sum()
}

/// Where the breakpoints go between a small and the largest one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Placement {
    /// Equally spaced.
    Uniform,
    /// Geometrically spaced over `decades` decades below the largest.
    Logarithmic {
        /// Decades covered.
        decades: f64,
    },
}

impl Placement {
    /// Breakpoint `j` of `n` (1-based) below `top`.
    fn point(self, j: usize, n: usize, top: f64) -> f64 {
        match self {
            Self::Uniform => top * j as f64 / n as f64,
            Self::Logarithmic { decades } => {
                if n == 1 {
                    top
                } else {
                    top * libm::pow(10.0, -decades * (n - j) as f64 / (n - 1) as f64)
                }
            }
        }
    }

    fn check(self) -> Result<(), ParamError> {
        match self {
            Self::Uniform => Ok(()),
            Self::Logarithmic { decades } => {
                positive(Param::scalar("decades"), decades).map(|_| ())
            }
        }
    }
}

/// The `N`-cell Iwan equivalent of a relaxation law up to reversal spans of
/// `span_max` (see the module docs).
pub fn iwan_from_relaxation<R: Relaxation<f64>, const N: usize>(
    law: &R,
    span_max: f64,
    placement: Placement,
) -> Result<[Jenkins; N], ParamError> {
    let span_max = positive(Param::scalar("span_max"), span_max)?;
    placement.check()?;
    if N == 0 {
        return Err(ParamError::TooFew {
            param: Param::scalar("cells"),
            min: 1,
            got: 0,
        });
    }
    // Secant stiffness on each interval (r_{j-1}, r_j].
    let mut secant = [0.0f64; N];
    let mut r_prev = 0.0;
    let mut h_prev = 0.0;
    for (j, s) in secant.iter_mut().enumerate() {
        let r = placement.point(j + 1, N, span_max);
        let h = law.branch(r).0;
        *s = (h - h_prev) / (r - r_prev);
        r_prev = r;
        h_prev = h;
    }
    let mut cells = [Jenkins::default(); N];
    for (j, c) in cells.iter_mut().enumerate() {
        let here = secant.get(j).copied().unwrap_or(0.0);
        let next = secant.get(j + 1).copied().unwrap_or(0.0);
        let r = placement.point(j + 1, N, span_max);
        *c = Jenkins {
            stiffness: (here - next).max(0.0),
            slip: 0.5 * r,
        };
    }
    Ok(cells)
}

/// Segalman's four-parameter Iwan model (eqs 1.36-1.38).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segalman {
    f_s: f64,
    k_t: f64,
    chi: f64,
    beta: f64,
}

impl Segalman {
    /// `f_s`: force at macro-slip (N); `k_t`: initial stiffness (N/mm);
    /// `chi` in (-1, 0]: exponent of the slip density (dissipation grows as
    /// amplitude^(3+χ) in micro-slip); `beta` >= 0: weight of the point
    /// mass at φ_max.
    pub fn new(f_s: f64, k_t: f64, chi: f64, beta: f64) -> Result<Self, ParamError> {
        positive(Param::scalar("f_s"), f_s)?;
        positive(Param::scalar("k_t"), k_t)?;
        if !(chi > -1.0 && chi <= 0.0) {
            return Err(ParamError::NotPositive {
                param: Param::scalar("chi + 1"),
                value: chi + 1.0,
            });
        }
        if !(beta.is_finite() && beta >= 0.0) {
            return Err(ParamError::NotPositive {
                param: Param::scalar("beta"),
                value: beta,
            });
        }
        Ok(Self {
            f_s,
            k_t,
            chi,
            beta,
        })
    }

    fn q(&self) -> f64 {
        self.beta + (self.chi + 1.0) / (self.chi + 2.0)
    }

    /// φ_max = F_S (1 + β) / (K_T (β + (χ+1)/(χ+2))) (eq 1.37).
    pub fn phi_max(&self) -> f64 {
        self.f_s * (1.0 + self.beta) / (self.k_t * self.q())
    }

    /// R = F_S (χ+1) / (φ_max^(χ+2) (β + (χ+1)/(χ+2))) (eq 1.37).
    pub fn r(&self) -> f64 {
        self.f_s * (self.chi + 1.0) / (libm::pow(self.phi_max(), self.chi + 2.0) * self.q())
    }

    /// S = (F_S / φ_max) β / (β + (χ+1)/(χ+2)) (eq 1.37).
    pub fn s(&self) -> f64 {
        self.f_s / self.phi_max() * self.beta / self.q()
    }

    /// Energy dissipated per cycle of amplitude `a` <= φ_max by the
    /// continuous model: `4 ∫_0^a φ (a - φ) R φ^χ dφ
    /// = 4 R a^(χ+3) / ((χ+2)(χ+3))`.
    pub fn cycle_energy(&self, a: f64) -> f64 {
        let (c2, c3) = (self.chi + 2.0, self.chi + 3.0);
        4.0 * self.r() * libm::pow(a, c3) / (c2 * c3)
    }

    /// `N - 1` cells for the density on `(0, φ_max)` and one for the point
    /// mass at φ_max.
    pub fn discretize<const N: usize>(
        &self,
        placement: Placement,
    ) -> Result<[Jenkins; N], ParamError> {
        placement.check()?;
        if N < 2 {
            return Err(ParamError::TooFew {
                param: Param::scalar("cells"),
                min: 2,
                got: N,
            });
        }
        let (c1, c2) = (self.chi + 1.0, self.chi + 2.0);
        let (phi_max, r) = (self.phi_max(), self.r());
        let bins = N - 1;
        let mut cells = [Jenkins::default(); N];
        let mut lo = 0.0f64;
        for (j, c) in cells.iter_mut().enumerate().take(bins) {
            let hi = placement.point(j + 1, bins, phi_max);
            let k = r * (libm::pow(hi, c1) - libm::pow(lo, c1)) / c1;
            let moment = r * (libm::pow(hi, c2) - libm::pow(lo, c2)) / c2;
            *c = Jenkins {
                stiffness: k,
                slip: moment / k,
            };
            lo = hi;
        }
        if let Some(last) = cells.last_mut() {
            *last = Jenkins {
                stiffness: self.s(),
                slip: phi_max,
            };
        }
        Ok(cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stack::Sts;

    #[test]
    fn sts_equivalent_matches_h_at_every_breakpoint() {
        let law = Sts::<f64>::new(400.0, 300.0).unwrap();
        for placement in [Placement::Uniform, Placement::Logarithmic { decades: 3.0 }] {
            let cells = iwan_from_relaxation::<_, 16>(&law, 4.0, placement).unwrap();
            for c in &cells {
                assert!(c.stiffness >= 0.0);
                let r = 2.0 * c.slip;
                // Iwan reversal curve: sum k min(d, 2 phi).
                let h_iwan: f64 = cells
                    .iter()
                    .map(|q| q.stiffness * r.min(2.0 * q.slip))
                    .sum();
                assert!(
                    (h_iwan - law.branch(r).0).abs() < 1e-9 * h_iwan,
                    "{placement:?} at {r}"
                );
            }
        }
    }

    #[test]
    fn segalman_cells_keep_k_t_and_f_s_for_any_n() {
        let m = Segalman::new(50.0, 400.0, -0.5, 0.3).unwrap();
        for placement in [Placement::Uniform, Placement::Logarithmic { decades: 4.0 }] {
            let cells = m.discretize::<9>(placement).unwrap();
            let k: f64 = cells.iter().map(|c| c.stiffness).sum();
            let f: f64 = cells.iter().map(|c| c.stiffness * c.slip).sum();
            assert!((k / 400.0 - 1.0).abs() < 1e-12, "{placement:?}: K_T {k}");
            assert!((f / 50.0 - 1.0).abs() < 1e-12, "{placement:?}: F_S {f}");
            assert!(
                cells
                    .iter()
                    .all(|c| c.slip > 0.0 && c.slip <= m.phi_max() * (1.0 + 1e-12))
            );
        }
    }

    #[test]
    fn parameter_errors() {
        assert!(matches!(
            Segalman::new(50.0, 400.0, -1.0, 0.3),
            Err(ParamError::NotPositive { .. })
        ));
        assert!(matches!(
            Segalman::new(50.0, 400.0, 0.2, 0.3),
            Err(ParamError::NotPositive { .. })
        ));
        assert!(matches!(
            Segalman::new(50.0, 400.0, -0.5, -0.1),
            Err(ParamError::NotPositive { .. })
        ));
        let law = Sts::<f64>::new(400.0, 300.0).unwrap();
        assert!(matches!(
            iwan_from_relaxation::<_, 4>(&law, 0.0, Placement::Uniform),
            Err(ParamError::NotPositive { .. })
        ));
        assert!(matches!(
            iwan_from_relaxation::<_, 4>(&law, 1.0, Placement::Logarithmic { decades: 0.0 }),
            Err(ParamError::NotPositive { .. })
        ));
    }
}
