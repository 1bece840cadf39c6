//! Stage 3b, the x_f cells (eq 1.36): unlike a Maxwell cell, an x_f
//! cell's storage and loss depend on the amplitude as well as the
//! frequency (its relaxation frequency grows with the speed, `ω + |ẋ|/x_f`),
//! so the cells are fitted to the sines' first harmonics themselves: each
//! candidate (the model of the earlier stages with the x_f cells added) is
//! replayed on every sine's record by the core, and its K′ and K″ are
//! matched to the measured ones by Levenberg-Marquardt on ln f, ln r and
//! ln x_f of each cell (`r = g / g⁰`), the Jacobian by forward differences.
//!
//! The cells start log-spaced in frequency from a twentieth of the lowest
//! tested frequency to half the highest (a slow cell below the band is the
//! seed's rule, Table 3.1), each with r = 0.2 and x_f the geometric mean
//! of the tested amplitudes. Corners are kept within three decades below
//! the band and one above it, r ≤ 10, and x_f within a thousandth of the
//! smallest amplitude and ten times the largest.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};

use super::campaign::Test;
use super::class::Candidate;
use super::replay::Drive;
use super::sine::{SinePoint, model_harmonic};

/// One x_f cell of the stage: (corner f Hz, r = g / g⁰, x_f mm).
pub type XfRatioCell = (f64, f64, f64);

/// Makes the candidate of the earlier stages with the given x_f cells.
pub type Compose<'a> = &'a dyn Fn(&[XfRatioCell]) -> Candidate;

/// Largest g_i / g⁰ of an x_f cell.
const MAX_RATIO: f64 = 10.0;
/// Most residual evaluations (each replays every sine).
const MAX_EVALUATIONS: usize = 400;
/// Forward-difference step on a logarithm.
const STEP: f64 = 1e-4;
/// Smallest loss a loss residual is taken relative to, as a share of the
/// storage (a nearly elastic sine's K″ is not fitted to its last digit).
const LOSS_FLOOR: f64 = 0.01;

/// A sine the stage fits: its replay, its record and its measured first
/// harmonic.
#[derive(Debug, Clone)]
pub struct Target {
    drive: Drive,
    test: Test,
    measured: SinePoint,
}

impl Target {
    /// The target of `test`, measured as `measured`; `None` when the
    /// record cannot be replayed.
    pub fn new(test: &Test, measured: SinePoint) -> Option<Self> {
        Some(Self {
            drive: Drive::new(test).ok()?,
            test: test.clone(),
            measured,
        })
    }

    /// The relative storage and loss errors of `candidate` on this sine.
    fn errors(&self, candidate: &Candidate) -> Option<(f64, f64)> {
        let forces = self.drive.run(&candidate.model()).ok()??;
        let mut t = self.test.clone();
        t.record.force = forces;
        let q = model_harmonic(&t).ok()?;
        let m = &self.measured;
        let loss_scale = m.loss.abs().max(LOSS_FLOOR * m.storage.abs()).max(1e-300);
        Some((
            (q.storage - m.storage) / m.storage.abs().max(1e-300),
            (q.loss - m.loss) / loss_scale,
        ))
    }
}

/// `n` x_f cells `(f Hz, r, x_f mm)` fitted to `targets`, each candidate
/// made by `compose` from the cells.
pub fn fit(targets: &[Target], compose: Compose<'_>, n: usize) -> Vec<XfRatioCell> {
    if n == 0 || targets.is_empty() {
        return Vec::new();
    }
    let (f_lo, f_hi) = super::extremes(targets.iter().map(|t| &t.measured.frequency_hz));
    let (a_lo, a_hi) = super::extremes(targets.iter().map(|t| &t.measured.amplitude_mm));
    let (lo, hi) = ((f_lo / 20.0).ln(), (f_hi / 2.0).ln());
    let mut start = Vec::with_capacity(3 * n);
    for k in 0..n {
        let ln_f = if n > 1 {
            lo + (hi - lo) * k as f64 / (n - 1) as f64
        } else {
            0.5 * (f_lo.ln() + f_hi.ln())
        };
        start.extend([ln_f, 0.2f64.ln(), 0.5 * (a_lo.ln() + a_hi.ln())]);
    }
    let problem = Problem {
        targets,
        compose,
        params: DVector::from_vec(start),
        bounds: [
            ((f_lo / 1000.0).ln(), (f_hi * 10.0).ln()),
            (f64::NEG_INFINITY, MAX_RATIO.ln()),
            ((a_lo / 1000.0).ln(), (a_hi * 10.0).ln()),
        ],
    };
    let (solved, _) = LevenbergMarquardt::new()
        .with_patience(MAX_EVALUATIONS / (3 * n + 1))
        .minimize(problem);
    let mut cells = solved.cells();
    cells.sort_by(|x, y| x.0.total_cmp(&y.0));
    cells
}

/// The stage as a least-squares problem: the storage then loss error of
/// each sine, then one residual per parameter outside its box.
struct Problem<'a> {
    targets: &'a [Target],
    compose: Compose<'a>,
    params: DVector<f64>,
    /// The box of (ln f, ln r, ln x_f).
    bounds: [(f64, f64); 3],
}

impl Problem<'_> {
    fn cells_of(p: &DVector<f64>) -> Vec<XfRatioCell> {
        p.as_slice()
            .chunks_exact(3)
            .map(|c| (c[0].exp(), c[1].exp(), c[2].exp()))
            .collect()
    }

    fn cells(&self) -> Vec<XfRatioCell> {
        Self::cells_of(&self.params)
    }

    fn residuals_at(&self, p: &DVector<f64>) -> Option<DVector<f64>> {
        let candidate = (self.compose)(&Self::cells_of(p));
        let n = self.targets.len();
        let mut r = DVector::zeros(2 * n + p.len());
        for (k, t) in self.targets.iter().enumerate() {
            let (s, l) = t.errors(&candidate)?;
            r[2 * k] = s;
            r[2 * k + 1] = l;
        }
        for (i, &v) in p.iter().enumerate() {
            let (lo, hi) = self.bounds[i % 3];
            r[2 * n + i] = (v - hi).max(0.0) + (lo - v).max(0.0);
        }
        r.iter().all(|v| v.is_finite()).then_some(r)
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.params.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.params.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.residuals_at(&self.params)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let base = self.residuals_at(&self.params)?;
        let mut j = DMatrix::zeros(base.len(), self.params.len());
        for i in 0..self.params.len() {
            let mut p = self.params.clone();
            p[i] += STEP;
            let r = self.residuals_at(&p)?;
            j.set_column(i, &((r - &base) / STEP));
        }
        Some(j)
    }
}
