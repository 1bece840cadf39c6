//! Fitting a bank of Maxwell cells to a complex modulus: the fractional
//! model of eqs 1.20-1.21 or measured points, over a chosen band.
//!
//! The bank's stiffness over K^∞ is eq 1.8,
//! `S(ω) = 1 - Σ g_i ω_i² / (ω² + ω_i²)` (storage) and
//! `L(ω) = Σ g_i ω ω_i / (ω² + ω_i²)` (loss), with every ω_i > 0 and
//! g_i > 0 (they are optimised as logarithms) and Σ g_i <= 1. The fit
//! minimises the largest relative error on storage and on loss at the
//! target points: Levenberg-Marquardt on weighted relative residuals, with
//! Lawson's reweighting driving the weighted least-squares optimum to the
//! minimax one; it starts from poles spread uniformly in log frequency
//! beyond the band, which the optimiser then moves. The firmware runs the
//! result as a `MaxwellBank` of the core.

use std::fmt;

use bushing::MaxwellSpec;
use bushing::fractional::FractionalSpec;

/// Target complex modulus over K^∞ at angular frequencies.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    /// Angular frequencies, rad/s, increasing.
    pub omega: Vec<f64>,
    /// Storage modulus over K^∞.
    pub storage: Vec<f64>,
    /// Loss modulus over K^∞.
    pub loss: Vec<f64>,
}

/// Why a fit was refused.
#[derive(Debug, Clone, PartialEq)]
pub enum FitError {
    /// Fewer than two points, or a zero cell count.
    TooFew(&'static str),
    /// Point `index` is not finite, not increasing in frequency, or has a
    /// storage outside (0, K^∞] or a loss <= 0.
    BadPoint {
        /// Point index.
        index: usize,
        /// What is wrong.
        why: &'static str,
    },
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooFew(what) => write!(f, "too few {what}"),
            Self::BadPoint { index, why } => write!(f, "point {index}: {why}"),
        }
    }
}

impl std::error::Error for FitError {}

impl Target {
    /// The fractional model (eqs 1.20-1.21, whole bushing on a linear
    /// backbone: storage g^0 + branch) at `per_decade` points per decade
    /// over `[lo, hi]` rad/s.
    pub fn fractional(spec: &FractionalSpec, lo: f64, hi: f64, per_decade: usize) -> Self {
        let omega = log_points(lo, hi, per_decade);
        let (storage, loss) = omega
            .iter()
            .map(|&w| {
                let (re, im) = spec.branch_modulus(w);
                (1.0 - spec.g + re, im)
            })
            .unzip();
        Self {
            omega,
            storage,
            loss,
        }
    }

    /// Measured points `(f_hz, K', K'')` with the high-frequency stiffness
    /// `k_inf` (the backbone tangent the bank's fractions refer to).
    pub fn measured(points: &[(f64, f64, f64)], k_inf: f64) -> Result<Self, FitError> {
        if points.len() < 2 {
            return Err(FitError::TooFew("points"));
        }
        if !(k_inf.is_finite() && k_inf > 0.0) {
            return Err(FitError::BadPoint {
                index: 0,
                why: "k_inf must be finite and > 0",
            });
        }
        let mut t = Self {
            omega: vec![],
            storage: vec![],
            loss: vec![],
        };
        for (index, &(f, s, l)) in points.iter().enumerate() {
            let bad = |why| Err(FitError::BadPoint { index, why });
            if !(f.is_finite() && s.is_finite() && l.is_finite()) {
                return bad("not finite");
            }
            if f <= 0.0
                || t.omega
                    .last()
                    .is_some_and(|&w| std::f64::consts::TAU * f <= w)
            {
                return bad("frequencies must be positive and increasing");
            }
            if !(s > 0.0 && s <= k_inf) {
                return bad("storage must lie in (0, k_inf]: a Maxwell bank never exceeds K^inf");
            }
            if l <= 0.0 {
                return bad("loss must be > 0");
            }
            t.omega.push(std::f64::consts::TAU * f);
            t.storage.push(s / k_inf);
            t.loss.push(l / k_inf);
        }
        Ok(t)
    }
}

/// `per_decade` log-spaced points per decade from `lo` to `hi` inclusive.
pub fn log_points(lo: f64, hi: f64, per_decade: usize) -> Vec<f64> {
    let decades = (hi / lo).log10();
    let n = ((decades * per_decade as f64).round() as usize).max(1);
    (0..=n)
        .map(|k| lo * 10f64.powf(decades * k as f64 / n as f64))
        .collect()
}

/// A fitted bank.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// The cells, by increasing ω.
    pub cells: Vec<MaxwellSpec>,
    /// Largest relative error on the storage modulus at the target points.
    pub storage_error: f64,
    /// Largest relative error on the loss modulus at the target points.
    pub loss_error: f64,
}

impl Fit {
    /// The larger of the two errors.
    pub fn error(&self) -> f64 {
        self.storage_error.max(self.loss_error)
    }

    /// Poles inside `[lo, hi]` rad/s per decade of that band.
    pub fn poles_per_decade(&self, lo: f64, hi: f64) -> f64 {
        let inside = self
            .cells
            .iter()
            .filter(|c| c.omega >= lo && c.omega <= hi)
            .count();
        inside as f64 / (hi / lo).log10()
    }
}

/// (storage, loss) over K^∞ of cells at ω.
pub fn bank_modulus(cells: &[MaxwellSpec], omega: f64) -> (f64, f64) {
    cells.iter().fold((1.0, 0.0), |(s, l), c| {
        let d = omega * omega + c.omega * c.omega;
        (
            s - c.g * c.omega * c.omega / d,
            l + c.g * omega * c.omega / d,
        )
    })
}

fn errors(target: &Target, cells: &[MaxwellSpec]) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for ((&w, &s), &l) in target.omega.iter().zip(&target.storage).zip(&target.loss) {
        let (ms, ml) = bank_modulus(cells, w);
        worst.0 = worst.0.max((ms / s - 1.0).abs());
        worst.1 = worst.1.max((ml / l - 1.0).abs());
    }
    worst
}

/// Fits `m` cells to `target`. Tries a few initial pole spans and keeps the
/// best minimax result.
pub fn fit(target: &Target, m: usize) -> Result<Fit, FitError> {
    if m == 0 {
        return Err(FitError::TooFew("cells"));
    }
    if target.omega.len() < 2 {
        return Err(FitError::TooFew("points"));
    }
    let lo = target.omega.first().copied().unwrap_or(1.0);
    let hi = target.omega.last().copied().unwrap_or(1.0);
    let mut best: Option<Fit> = None;
    for extend in [0.25, 0.5, 1.0] {
        let cells = minimax(target, initial(target, m, lo, hi, extend));
        let (storage_error, loss_error) = errors(target, &cells);
        let candidate = Fit {
            cells,
            storage_error,
            loss_error,
        };
        if best.as_ref().is_none_or(|b| candidate.error() < b.error()) {
            best = Some(candidate);
        }
    }
    best.ok_or(FitError::TooFew("cells"))
}

/// Poles log-spaced over the band widened by `extend` decades each side;
/// gains from the target's loss at each pole (a Maxwell cell's loss peaks
/// at g/2 at its pole), scaled to the poles' spacing.
fn initial(target: &Target, m: usize, lo: f64, hi: f64, extend: f64) -> Vec<f64> {
    let (a, b) = (lo.ln() - extend * 10f64.ln(), hi.ln() + extend * 10f64.ln());
    let spacing = if m > 1 { (b - a) / (m - 1) as f64 } else { 1.0 };
    let mut params = Vec::with_capacity(2 * m);
    for i in 0..m {
        let ln_p = if m > 1 {
            a + (b - a) * i as f64 / (m - 1) as f64
        } else {
            0.5 * (a + b)
        };
        let p = ln_p.exp();
        // Loss density per ln ω times the spacing: g ≈ (2/π) L(p) Δ ln ω.
        let l = interpolate(&target.omega, &target.loss, p);
        let g = (2.0 / std::f64::consts::PI * l * spacing).max(1e-4);
        params.push(ln_p);
        params.push(g.ln());
    }
    params
}

fn interpolate(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let k = xs.partition_point(|&v| v < x);
    match (
        k.checked_sub(1).and_then(|i| xs.get(i).zip(ys.get(i))),
        xs.get(k).zip(ys.get(k)),
    ) {
        (Some((&x0, &y0)), Some((&x1, &y1))) => {
            let t = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
            y0 + t * (y1 - y0)
        }
        (Some((_, &y)), None) | (None, Some((_, &y))) => y,
        (None, None) => 0.0,
    }
}

fn cells_of(params: &[f64]) -> Vec<MaxwellSpec> {
    let mut cells: Vec<MaxwellSpec> = params
        .chunks_exact(2)
        .map(|c| MaxwellSpec::new(c[0].exp(), c[1].exp()))
        .collect();
    cells.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    cells
}

/// Weighted relative residuals (storage then loss) and, when Σ g > 1, a
/// penalty residual that pushes the sum back to one.
fn residuals(target: &Target, params: &[f64], weights: &[f64], out: &mut Vec<f64>) {
    out.clear();
    let n = target.omega.len();
    let cells = cells_of(params);
    for k in 0..n {
        let (s, l) = bank_modulus(&cells, target.omega[k]);
        out.push(weights[k] * (s / target.storage[k] - 1.0));
        out.push(weights[n + k] * (l / target.loss[k] - 1.0));
    }
    let sum: f64 = cells.iter().map(|c| c.g).sum();
    out.push(1e3 * (sum - 1.0).max(0.0));
}

/// Analytic Jacobian of [`residuals`] (row-major, rows × params).
fn jacobian(target: &Target, params: &[f64], weights: &[f64], jac: &mut Vec<f64>) {
    let n = target.omega.len();
    let np = params.len();
    jac.clear();
    jac.resize((2 * n + 1) * np, 0.0);
    let sum: f64 = params.chunks_exact(2).map(|c| c[1].exp()).sum();
    for (i, c) in params.chunks_exact(2).enumerate() {
        let (p, g) = (c[0].exp(), c[1].exp());
        for k in 0..n {
            let w = target.omega[k];
            let d = w * w + p * p;
            let ds_dg = -g * p * p / d;
            let ds_dp = -g * 2.0 * p * p * w * w / (d * d);
            let dl_dg = g * w * p / d;
            let dl_dp = g * w * p * (w * w - p * p) / (d * d);
            let rs = 2 * k * np;
            let rl = (2 * k + 1) * np;
            jac[rs + 2 * i] = weights[k] * ds_dp / target.storage[k];
            jac[rs + 2 * i + 1] = weights[k] * ds_dg / target.storage[k];
            jac[rl + 2 * i] = weights[n + k] * dl_dp / target.loss[k];
            jac[rl + 2 * i + 1] = weights[n + k] * dl_dg / target.loss[k];
        }
        if sum > 1.0 {
            jac[2 * n * np + 2 * i + 1] = 1e3 * g;
        }
    }
}

/// Levenberg-Marquardt on the weighted residuals from `params`.
fn levenberg_marquardt(target: &Target, params: &mut [f64], weights: &[f64], iterations: usize) {
    let np = params.len();
    let (mut r, mut jac, mut trial_r) = (vec![], vec![], vec![]);
    residuals(target, params, weights, &mut r);
    let mut cost: f64 = r.iter().map(|v| v * v).sum();
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        jacobian(target, params, weights, &mut jac);
        let rows = r.len();
        let mut jtj = vec![0.0; np * np];
        let mut jtr = vec![0.0; np];
        for row in 0..rows {
            let jr = &jac[row * np..(row + 1) * np];
            for a in 0..np {
                jtr[a] += jr[a] * r[row];
                for b in a..np {
                    jtj[a * np + b] += jr[a] * jr[b];
                }
            }
        }
        for a in 0..np {
            for b in 0..a {
                jtj[a * np + b] = jtj[b * np + a];
            }
        }
        let mut improved = false;
        for _ in 0..12 {
            let mut m = jtj.clone();
            for a in 0..np {
                m[a * np + a] += lambda * (jtj[a * np + a] + 1e-12);
            }
            let rhs: Vec<f64> = jtr.iter().map(|v| -v).collect();
            let Some(step) = solve(m, rhs, np) else {
                lambda *= 10.0;
                continue;
            };
            // Poles move at most a decade per iteration.
            let trial: Vec<f64> = params
                .iter()
                .zip(&step)
                .map(|(p, s)| p + s.clamp(-2.3, 2.3))
                .collect();
            residuals(target, &trial, weights, &mut trial_r);
            let trial_cost: f64 = trial_r.iter().map(|v| v * v).sum();
            if trial_cost < cost {
                params.copy_from_slice(&trial);
                std::mem::swap(&mut r, &mut trial_r);
                let gain = cost - trial_cost;
                cost = trial_cost;
                lambda = (lambda / 3.0).max(1e-12);
                improved = gain > 1e-15 * cost.max(1e-300);
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
}

/// Lawson's reweighting around Levenberg-Marquardt: weights grow where the
/// error is largest until the largest relative error stops falling.
fn minimax(target: &Target, mut params: Vec<f64>) -> Vec<MaxwellSpec> {
    let n = target.omega.len();
    let mut weights = vec![1.0; 2 * n];
    let mut best = (f64::INFINITY, params.clone());
    let mut r = vec![];
    for _ in 0..40 {
        levenberg_marquardt(target, &mut params, &weights, 60);
        let (es, el) = errors(target, &cells_of(&params));
        if es.max(el) < best.0 {
            best = (es.max(el), params.clone());
        }
        let unit = vec![1.0; 2 * n];
        residuals(target, &params, &unit, &mut r);
        let total: f64 = r
            .iter()
            .take(2 * n)
            .map(|v| v.abs())
            .sum::<f64>()
            .max(1e-300);
        for (w, e) in weights.iter_mut().zip(&r) {
            // Square roots of the Lawson weights, since LM squares them.
            *w = (*w * *w * e.abs() / total * (2 * n) as f64)
                .sqrt()
                .max(1e-6);
        }
    }
    cells_of(&best.1)
}

/// Solves `m x = rhs` (m is np × np, row-major) by Gaussian elimination with
/// partial pivoting; `None` if singular.
fn solve(mut m: Vec<f64>, mut rhs: Vec<f64>, np: usize) -> Option<Vec<f64>> {
    for col in 0..np {
        let pivot =
            (col..np).max_by(|&a, &b| m[a * np + col].abs().total_cmp(&m[b * np + col].abs()))?;
        if m[pivot * np + col].abs() < 1e-300 {
            return None;
        }
        if pivot != col {
            for k in 0..np {
                m.swap(pivot * np + k, col * np + k);
            }
            rhs.swap(pivot, col);
        }
        for row in col + 1..np {
            let f = m[row * np + col] / m[col * np + col];
            if f != 0.0 {
                for k in col..np {
                    m[row * np + k] -= f * m[col * np + k];
                }
                rhs[row] -= f * rhs[col];
            }
        }
    }
    let mut x = vec![0.0; np];
    for row in (0..np).rev() {
        let s: f64 = (row + 1..np).map(|k| m[row * np + k] * x[k]).sum();
        x[row] = (rhs[row] - s) / m[row * np + row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bank_is_recovered_from_its_own_modulus() {
        let cells = [
            MaxwellSpec::new(0.3, 0.1),
            MaxwellSpec::new(3.0, 0.2),
            MaxwellSpec::new(30.0, 0.15),
        ];
        let omega = log_points(0.03, 300.0, 10);
        let (storage, loss) = omega.iter().map(|&w| bank_modulus(&cells, w)).unzip();
        let target = Target {
            omega,
            storage,
            loss,
        };
        let f = fit(&target, 3).unwrap();
        assert!(f.error() < 1e-6, "{f:?}");
        for (a, b) in f.cells.iter().zip(&cells) {
            assert!((a.omega / b.omega - 1.0).abs() < 1e-4 && (a.g / b.g - 1.0).abs() < 1e-4);
        }
    }

    #[test]
    fn fractional_fit_meets_one_percent_with_eight_cells() {
        let spec = FractionalSpec::new(1.0, 0.5, 0.6);
        let target = Target::fractional(&spec, 0.01, 100.0, 12);
        let f = fit(&target, 8).unwrap();
        assert!(f.error() < 0.01, "{f:?}");
        assert!(f.cells.iter().all(|c| c.omega > 0.0 && c.g > 0.0));
        assert!(f.cells.iter().map(|c| c.g).sum::<f64>() <= 1.0 + 1e-9);
        assert!(f.poles_per_decade(0.01, 100.0) > 1.0);
    }

    #[test]
    fn measured_points_are_checked() {
        let e = Target::measured(&[(1.0, 50.0, 5.0)], 100.0).unwrap_err();
        assert_eq!(e, FitError::TooFew("points"));
        let e = Target::measured(&[(1.0, 50.0, 5.0), (0.5, 60.0, 5.0)], 100.0).unwrap_err();
        assert!(matches!(e, FitError::BadPoint { index: 1, .. }));
        let e = Target::measured(&[(1.0, 50.0, 5.0), (2.0, 160.0, 5.0)], 100.0).unwrap_err();
        assert!(
            e.to_string()
                .contains("point 1: storage must lie in (0, k_inf]")
        );
        let e = Target::measured(&[(1.0, 50.0, -5.0), (2.0, 60.0, 5.0)], 100.0).unwrap_err();
        assert!(matches!(e, FitError::BadPoint { index: 0, .. }));
        let t = Target::measured(&[(1.0, 50.0, 5.0), (2.0, 60.0, 5.0)], 100.0).unwrap();
        assert_eq!(t.storage, [0.5, 0.6]);
    }
}
