//! The first harmonic of sampled signals by least squares: `c + a cos(ωt)
//! plus b sin(ωt)` fitted to samples at any times (a whole number of
//! periods, or not), streamed. `validate` fits a scene's steady cycle with it and
//! the identification each measured sine.

/// Least-squares accumulators of `c + a cos ωt + b sin ωt`: the normal
/// matrix, shared by every signal sampled at the same times, and one
/// right-hand side per signal.
pub struct Harmonic {
    omega: f64,
    m: [[f64; 3]; 3],
    rhs: Vec<[f64; 3]>,
}

impl Harmonic {
    /// Accumulators at ω (rad/s) for `signals` signals.
    pub fn new(omega: f64, signals: usize) -> Self {
        Self {
            omega,
            m: [[0.0; 3]; 3],
            rhs: vec![[0.0; 3]; signals],
        }
    }

    /// One sample of every signal at time `t`.
    pub fn push(&mut self, t: f64, values: impl Iterator<Item = f64>) {
        let (s, c) = (self.omega * t).sin_cos();
        let basis = [1.0, c, s];
        for (row, bi) in self.m.iter_mut().zip(basis) {
            for (cell, bj) in row.iter_mut().zip(basis) {
                *cell += bi * bj;
            }
        }
        for (r, y) in self.rhs.iter_mut().zip(values) {
            for (ri, bi) in r.iter_mut().zip(basis) {
                *ri += bi * y;
            }
        }
    }

    /// `(a, b)` of signal `k`.
    pub fn fit(&self, k: usize) -> Option<(f64, f64)> {
        let sol = solve3(self.m, *self.rhs.get(k)?)?;
        Some((sol[1], sol[2]))
    }
}

/// The complex ratio of signal `k` over signal `j` as (in phase, in
/// quadrature): with phasors `a - i b` of `a cos + b sin`, `F/X` gives the
/// storage and the loss modulus when `j` is the displacement and `k` the
/// force. `None` when either fit is singular or X is zero.
pub fn ratio(h: &Harmonic, j: usize, k: usize) -> Option<(f64, f64)> {
    let (x, f) = (h.fit(j)?, h.fit(k)?);
    let x2 = x.0 * x.0 + x.1 * x.1;
    (x2 > 0.0).then(|| ((f.0 * x.0 + f.1 * x.1) / x2, (f.0 * x.1 - f.1 * x.0) / x2))
}

/// Solves a 3×3 system by Cramer's rule (the normal equations of three
/// well-separated functions: no pivoting needed); `None` if singular.
pub fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let det = |[a, b, c]: [[f64; 3]; 3]| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    let d = det(m);
    let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    if d.is_nan() || d.abs() <= 1e-12 * scale * scale * scale {
        return None;
    }
    // Column j replaced by r.
    let with = |j: usize| {
        let mut c = m;
        for (row, v) in c.iter_mut().zip(r) {
            if let Some(x) = row.get_mut(j) {
                *x = v;
            }
        }
        det(c) / d
    };
    let x = [with(0), with(1), with(2)];
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use super::*;

    #[test]
    fn first_harmonic_fits_offset_and_phase() {
        let w = TAU * 3.0;
        let mut h = Harmonic::new(w, 2);
        // 1.1 periods: not a whole number, the fit is still exact.
        for i in 0..367 {
            let t = i as f64 * 1e-3;
            let v = 2.0 + 0.7 * (w * t).cos() - 1.3 * (w * t).sin();
            h.push(t, [v, -v].into_iter());
        }
        let (a, b) = h.fit(0).unwrap();
        assert!(
            (a - 0.7).abs() < 1e-12 && (b + 1.3).abs() < 1e-12,
            "{a} {b}"
        );
        let (a, b) = h.fit(1).unwrap();
        assert!((a + 0.7).abs() < 1e-12 && (b - 1.3).abs() < 1e-12);
        assert!(h.fit(2).is_none());
    }

    #[test]
    fn solve3_solves_and_refuses_a_singular_system() {
        let x = solve3(
            [[2.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 4.0]],
            [3.0, 5.0, 5.0],
        )
        .unwrap();
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-12), "{x:?}");
        assert!(solve3([[1.0; 3]; 3], [1.0; 3]).is_none());
    }
}
