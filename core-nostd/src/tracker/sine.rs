//! Two-state fixed-frequency tracker of a sine's complex amplitude and the
//! on-line instantaneous complex modulus of a sine test.
//!
//! **Signal model** (seed 004 eqs 3.24-3.26, seed 000 eq 1.1): a sine of
//! known angular frequency ω sampled every Δt is the real part of its
//! analytic signal `a_k + i b_k = u_1 e^{iωkΔt}`, which turns by
//! `θ = ωΔt` per sample:
//!
//! ```text
//! [a_k; b_k] = [cos θ  -sin θ; sin θ  cos θ] [a_{k-1}; b_{k-1}]   (eq 3.25, F)
//! z_k        = [1 0] [a_k; b_k] + ε_k                              (eq 3.26, H)
//! ```
//!
//! The model is linear, so the linear Kalman filter of eqs 3.8-3.23 is the
//! exact least-squares estimate: at start-up it is the least-squares fit
//! of seed 000 eq 1.3 over every sample seen so far (a growing window
//! instead of the thesis's sliding quarter cycle), and the process noise
//! then turns it into an exponentially weighted fit whose memory is set by
//! the tracking bandwidth. The instantaneous complex modulus is the ratio
//! of the force and displacement analytic signals (seed 000 §1.2.1, the
//! text after eq 1.3, and Fig 1.24): `K* = F / X = K' + i K''`, storage K',
//! loss K'' and loss factor `η = K''/K'` (seed 000 eq 1.5).
//!
//! - **Filter**: predict `x = F x`, `P = F P Fᵀ + q I`; update with the
//!   scalar sample, `k = P Hᵀ / (H P Hᵀ + r)`, `x += k (z - a)`, and the
//!   covariance in the Joseph form `(I - k H) P (I - k H)ᵀ + r k kᵀ`. The
//!   covariance is kept divided by r (it is then the same for every signal
//!   with the same initial signal-to-noise ratio, whatever its units) and
//!   stored as its three distinct entries, so it is symmetric by
//!   construction; the rotation `F P Fᵀ` turns `((P00 - P11)/2, P01)` by
//!   2θ and keeps the trace. A covariance that rounding would leave
//!   non-positive is repaired (counted in [`SineState::repairs`]; never
//!   seen in the tests, f32 included).
//! - **Tuning** ([`SineSpec`], [`Channel`]): the tracking bandwidth B in Hz
//!   sets the process noise `q / r = 2 K² / (1 - 2 K)` with
//!   `K = 1 - e^{-2π B Δt}`: averaged over a period, the steady-state
//!   filter follows the complex amplitude through a first-order low-pass of
//!   corner B (pole `1 - K` per sample; the exact steady state is within
//!   1 % of B for B ≤ f/5 at 50 samples per period or more, and within 5 %
//!   for B ≤ f/20 from 4 samples per period, tested). The initial
//!   standard deviation of a and b is the expected amplitude; its ratio to
//!   the noise only sets how much the first samples are trusted.
//! - **Stability**: the filter is linear and the steady-state error
//!   dynamics `(I - k H) F` have a pole pair of modulus about `1 - K`
//!   (`√(1 - k_a)` exactly) turning by about θ per sample, inside
//!   the unit circle for every accepted tuning. It needs `sin θ ≠ 0`:
//!   frequencies in (0, Nyquist) only. A non-finite sample, or one whose
//!   update would take a or b beyond [`Real::GUARD`] in magnitude (2^60 in
//!   f32, 2^500 in f64), is refused: the estimate is carried to the
//!   sample's time by the rotation alone (the covariance grows by q), so
//!   the phase stays right for the next sample. The state thus never leaves
//!   the guard, where the rotation, the update and the squares formed for
//!   [`SineState::amplitude`] and [`ModulusTracker::modulus`] cannot
//!   overflow. Should the rotation of a refused sample itself take a or b
//!   past the guard (only from a state at its edge, whose norm exceeds
//!   it), the rotated estimate is also halved, exactly: it is then well
//!   inside, and the next ordinary samples pull it back.
//! - **Construction**: θ is formed as `2π (f Δt)` and the decay as
//!   `2π (B Δt)`, which stay finite for any Δt, subnormal included, once f
//!   is below Nyquist; what would leave a coefficient that is not finite in
//!   the working type is refused with a [`ParamError`] (a bandwidth whose
//!   lower bound `K ≥ 1024 ε` is out of reach at a subnormal Δt, a channel
//!   noise whose square overflows it, a `min_snr σ_X` whose square does).
//! - **Accuracy**: a clean sine at the tuned frequency is fitted exactly
//!   (the model holds); on a steady sine, noise of standard deviation σ
//!   leaves about `σ √K` on each of a and b (tested; the filter's own
//!   covariance says `σ² 2K`, as it also allows for the amplitude wander
//!   the bandwidth is tuned for). In f32 a correction below half an ulp
//!   of the state is lost: up to about `ε / (8K)` of the amplitude (tested
//!   at the smallest accepted K). A frequency error δf biases each
//!   amplitude like the low-pass at δf, but the two channels of
//!   [`ModulusTracker`] share the rotation and the gain, so the bias
//!   cancels in `F / X` (tested at 1 % frequency error).
//! - **No mean state**: the model is eq 1.1 without `u_0`. A constant
//!   offset D (a prestrain, a drifting zero) leaks onto `(a, b)` as an
//!   error of about `2 (B/f) D` (tested): remove the mean first (seed 000
//!   eq 1.2) or keep B well below f.
//! - **Cost** per sample (counted from the code): covariance prediction 6
//!   multiplies, gain 2 and one division (by `P00 + 1 ≥ 1`), Joseph update
//!   9, positivity check 2; per channel 4 for the rotation and 2 for the
//!   state update: 25 multiplies and one division for [`SineTracker`], 31
//!   for [`ModulusTracker`]. No f64 and no libm call per sample: cos θ and
//!   sin θ are computed once, in f64, at construction. The modulus
//!   division happens only when the caller asks for it.

use crate::error::{Param, ParamError, in_range, positive};
use crate::real::Real;

/// Frequency and tracking bandwidth of a sine tracker, in Hz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SineSpec {
    /// Known frequency f of the sine, Hz, in (0, Nyquist).
    pub frequency: f64,
    /// Tracking bandwidth B, Hz: corner of the low-pass through which the
    /// steady-state filter follows the complex amplitude. At most f/2, and
    /// `K = 1 - e^{-2π B Δt}` at most 1/4 and at least 1024 ε of the
    /// working type (in f32, B ≥ 1.9e-5 / Δt: 0.19 Hz at 10 kHz), below
    /// which the rounding of the state update would leave more than about
    /// 1e-4 of the amplitude uncorrected.
    pub bandwidth: f64,
}

/// One measured channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Channel {
    /// Standard deviation of the measurement noise, in the signal's units;
    /// its square must be finite in the working type (in f32, noise below
    /// 1.8e19).
    pub noise: f64,
    /// Expected amplitude, in the signal's units: the initial standard
    /// deviation of a and b (the start estimate is zero).
    pub amplitude: f64,
}

/// Why a sample was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    /// A sample was NaN or infinite.
    NonFiniteSample,
    /// The update would have taken a or b beyond [`Real::GUARD`] in
    /// magnitude (a finite sample far larger than the signal, or one whose
    /// correction overflows): the state is kept within the guard.
    Overflow,
}

/// Covariance divided by the measurement noise variance, symmetric by
/// construction.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cov<T> {
    p00: T,
    p01: T,
    p11: T,
}

/// What the trackers share: the rotation and the normalised covariance
/// recursion.
#[derive(Debug, Clone, PartialEq)]
struct Kernel<T> {
    /// `1 - cos θ = 2 sin²(θ/2)`, exact to the working precision.
    vers: T,
    sin: T,
    /// `1 - cos 2θ` and `sin 2θ`, for the covariance.
    vers2: T,
    sin2: T,
    q: T,
    p0: T,
    dt: f64,
    frequency: f64,
    bandwidth: f64,
    pole: f64,
}

impl<T: Real> Kernel<T> {
    /// `snr2` is (amplitude / noise)², the normalised initial variance
    /// before the cap.
    fn new(dt: f64, spec: &SineSpec, snr2: f64) -> Result<Self, ParamError> {
        let dt = positive(Param::scalar("dt"), dt)?;
        let nyquist = 0.5 / dt;
        let f = positive(Param::scalar("frequency"), spec.frequency)?;
        if f >= nyquist {
            return Err(ParamError::OutOfRange {
                param: Param::scalar("frequency"),
                value: f,
                min: 0.0,
                min_open: true,
                max: nyquist,
            });
        }
        let tau = core::f64::consts::TAU;
        // K = 1 - e^{-2π B dt} <= 1/4, and >= 1024 ε of the working type:
        // a correction below half an ulp of the state is lost, which leaves
        // a dead band of about ε / (8 K) of the amplitude. Every product
        // with dt is formed as (rate * dt) or (number / 2π) / dt: 2π f or
        // 2π B first would overflow near f64::MAX with a subnormal dt, and
        // 2π dt would lose digits to underflow.
        let b_max = (0.5 * f).min(libm::log(4.0 / 3.0) / tau / dt);
        let k_min = 1024.0 * T::EPSILON.to_f64();
        let b_min = -libm::log1p(-k_min) / tau / dt;
        let bandwidth = positive(Param::scalar("bandwidth"), spec.bandwidth)?;
        let bandwidth = in_range(Param::scalar("bandwidth"), bandwidth, b_min, false, b_max)?;
        // B dt <= f dt < 1/2: both products and θ in (0, π) are finite.
        let k = -libm::expm1(-tau * (bandwidth * dt));
        let theta = tau * (f * dt);
        // The prior weighs at most 64 ulps of one sample: beyond that the
        // first two samples would be lost to rounding in the covariance.
        let p0 = snr2.min(1.0 / (64.0 * T::EPSILON.to_f64()));
        Ok(Self {
            vers: T::from_f64(2.0 * sq(libm::sin(0.5 * theta))),
            sin: T::from_f64(libm::sin(theta)),
            vers2: T::from_f64(2.0 * sq(libm::sin(theta))),
            sin2: T::from_f64(libm::sin(2.0 * theta)),
            q: T::from_f64(2.0 * k * k / (1.0 - 2.0 * k)),
            p0: T::from_f64(p0),
            dt,
            frequency: f,
            bandwidth,
            pole: 1.0 - k,
        })
    }

    fn start(&self) -> Cov<T> {
        Cov {
            p00: self.p0,
            p01: T::ZERO,
            p11: self.p0,
        }
    }

    /// `F (a, b)` (eq 3.25), written `x - (1 - cos θ) x + sin θ J x` so
    /// that the rounded coefficients keep `cos² + sin² = 1` to
    /// `O(θ² ε)`: with `cos θ` rounded next to 1 instead, the amplitude
    /// would grow or shrink by up to ε/2 per step, a bias of ε/(4K) on the
    /// tracked amplitude. 4 multiplies.
    #[inline(always)]
    fn rotate(&self, (a, b): (T, T)) -> (T, T) {
        (
            a - (self.vers * a + self.sin * b),
            b + (self.sin * a - self.vers * b),
        )
    }

    /// `F P Fᵀ + q I`: the mean of the diagonal is kept and
    /// `(d, e) = ((P00 - P11)/2, P01)` turns by 2θ. 6 multiplies.
    #[inline(always)]
    fn predict(&self, p: &Cov<T>) -> Cov<T> {
        let m = T::HALF * (p.p00 + p.p11);
        let d = T::HALF * (p.p00 - p.p11);
        let d2 = d - (self.vers2 * d + self.sin2 * p.p01);
        let e2 = p.p01 + (self.sin2 * d - self.vers2 * p.p01);
        let mq = m + self.q;
        Cov {
            p00: mq + d2,
            p01: e2,
            p11: mq - d2,
        }
    }

    /// Gain `P Hᵀ / (H P Hᵀ + 1)` of a predicted covariance: one division,
    /// by a number >= 1.
    #[inline(always)]
    fn gain(&self, p: &Cov<T>) -> (T, T) {
        let inv = T::ONE / (p.p00 + T::ONE);
        (p.p00 * inv, p.p01 * inv)
    }

    /// Joseph form `(I - k H) P (I - k H)ᵀ + k kᵀ` (r = 1): 9 multiplies;
    /// then the positivity check (2).
    #[inline(always)]
    fn joseph(&self, p: &Cov<T>, (k0, k1): (T, T)) -> (Cov<T>, bool) {
        let u = T::ONE - k0;
        let k1p01 = k1 * p.p01;
        let out = Cov {
            p00: u * u * p.p00 + k0 * k0,
            p01: u * (p.p01 - k1 * p.p00) + k0 * k1,
            p11: p.p11 - (k1p01 + k1p01) + k1 * k1 * (p.p00 + T::ONE),
        };
        let ok = out.p00 > T::ZERO
            && out.p11 > T::ZERO
            && out.p01 * out.p01 <= out.p00 * out.p11
            && out.p00.is_finite()
            && out.p11.is_finite();
        if ok {
            (out, false)
        } else {
            // Rounding broke positivity: keep the variances, drop the
            // correlation.
            let floor = self.q;
            let fix = |v: T| match v.is_finite() {
                true if v > floor => v,
                true => floor,
                false => self.p0,
            };
            (
                Cov {
                    p00: fix(out.p00),
                    p01: T::ZERO,
                    p11: fix(out.p11),
                },
                true,
            )
        }
    }

    /// One step of `C` channels sharing the covariance: predict, then
    /// update every channel with the same gain. Returns the innovations.
    ///
    /// The pairs are within [`Real::GUARD`] on entry (the start state is
    /// zero) and on return: an update that would leave the guard is
    /// refused, and the rotation of a refused sample is stored halved if
    /// it leaves the guard (keeping the old pair instead could lock the
    /// tracker: a state whose rotation leaves the guard every time, that no
    /// ordinary sample can pull back in one update). From a guarded state
    /// nothing here overflows: the rotation keeps the norm (each product in
    /// it is below 2 GUARD), `z - a` with a finite z rounds to at most the
    /// largest finite value (GUARD is far below an ulp of it), and a
    /// correction `k y` that overflows fails the guard.
    fn step<const C: usize>(
        &self,
        pairs: &mut [(T, T); C],
        cov: &mut Cov<T>,
        counters: &mut Counters,
        samples: [T; C],
    ) -> Result<[T; C], Refused> {
        let mut rotated = *pairs;
        for p in rotated.iter_mut() {
            *p = self.rotate(*p);
        }
        let prior = self.predict(cov);
        let refused = if samples.iter().all(|z| z.is_finite()) {
            let (k0, k1) = self.gain(&prior);
            let mut next = rotated;
            let mut innovations = [T::ZERO; C];
            for ((p, z), y) in next.iter_mut().zip(samples).zip(innovations.iter_mut()) {
                *y = z - p.0;
                *p = (p.0 + k0 * *y, p.1 + k1 * *y);
            }
            if guarded(&next) {
                let (post, repaired) = self.joseph(&prior, (k0, k1));
                if repaired {
                    counters.repairs = counters.repairs.saturating_add(1);
                }
                *pairs = next;
                *cov = post;
                return Ok(innovations);
            }
            Refused::Overflow
        } else {
            Refused::NonFiniteSample
        };
        *pairs = if guarded(&rotated) {
            rotated
        } else {
            // Beyond the guard by at most √2 (the norm of a guarded pair):
            // halved, exactly, it is back inside with room to turn.
            rotated.map(|(a, b)| (a * T::HALF, b * T::HALF))
        };
        *cov = prior;
        counters.refused = counters.refused.saturating_add(1);
        Err(refused)
    }
}

/// Every component finite and within [`Real::GUARD`] in magnitude (a NaN
/// fails): 2 comparisons per channel.
#[inline(always)]
fn guarded<T: Real, const C: usize>(pairs: &[(T, T); C]) -> bool {
    pairs
        .iter()
        .all(|&(a, b)| a.abs() <= T::GUARD && b.abs() <= T::GUARD)
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Counters {
    refused: u32,
    repairs: u32,
}

/// Running state of a [`SineTracker`]: the analytic signal `(a, b)` at the
/// last sample and its covariance (divided by the noise variance).
#[derive(Debug, Clone, PartialEq)]
pub struct SineState<T> {
    pair: (T, T),
    cov: Cov<T>,
    counters: Counters,
}

impl<T: Real> SineState<T> {
    /// Real part a: the fitted sample.
    pub fn a(&self) -> T {
        self.pair.0
    }
    /// Imaginary part b.
    pub fn b(&self) -> T {
        self.pair.1
    }
    /// `(a, b)`: the complex amplitude `u_1 e^{iωt}` at the last sample.
    pub fn pair(&self) -> (T, T) {
        self.pair
    }
    /// Amplitude `|a + ib|` (one square root; an output, not part of the
    /// update).
    pub fn amplitude(&self) -> T {
        let (a, b) = self.pair;
        (a * a + b * b).sqrt()
    }
    /// Samples refused since the start.
    pub fn refused(&self) -> u32 {
        self.counters.refused
    }
    /// Covariance repairs since the start.
    pub fn repairs(&self) -> u32 {
        self.counters.repairs
    }
}

/// Two-state Kalman tracker of the complex amplitude of a sine of known
/// frequency (seed 004 eqs 3.24-3.26 with the linear filter of eqs
/// 3.8-3.23; see the module docs for tuning, stability and cost: 25
/// multiplies and one division per sample).
///
/// States: `(a, b)`, the analytic signal at the last sample (seed 000 eq
/// 1.1 without the mean), and their 2×2 covariance.
#[derive(Debug, Clone, PartialEq)]
pub struct SineTracker<T> {
    kernel: Kernel<T>,
    noise2: T,
}

impl<T: Real> SineTracker<T> {
    /// A tracker at time step `dt` (s) for the sine of `spec`, measured
    /// through `channel`.
    pub fn new(dt: f64, spec: &SineSpec, channel: Channel) -> Result<Self, ParamError> {
        let (noise, amplitude) = check_channel(channel, "noise", "amplitude")?;
        let kernel = Kernel::new(dt, spec, sq(amplitude / noise))?;
        Ok(Self {
            kernel,
            noise2: finite_square::<T>("noise", noise)?,
        })
    }

    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.kernel.dt
    }
    /// Tracked frequency, Hz.
    pub fn frequency(&self) -> f64 {
        self.kernel.frequency
    }
    /// Tracking bandwidth, Hz.
    pub fn bandwidth(&self) -> f64 {
        self.kernel.bandwidth
    }
    /// Designed steady-state pole of the amplitude error per sample,
    /// `e^{-2π B Δt}`.
    pub fn envelope_pole(&self) -> f64 {
        self.kernel.pole
    }

    /// The start state: zero amplitude, variance `amplitude²` on a and b
    /// (normalised by the noise variance and capped at `1 / (64 ε)`).
    pub fn start(&self) -> SineState<T> {
        SineState {
            pair: (T::ZERO, T::ZERO),
            cov: self.kernel.start(),
            counters: Counters::default(),
        }
    }

    /// One sample: predict (eq 3.25), update (eqs 3.21-3.23, Joseph form).
    /// Returns the innovation `z - a_predicted`. A refused sample leaves
    /// the prediction in the state (see the module docs).
    pub fn step(&self, state: &mut SineState<T>, sample: T) -> Result<T, Refused> {
        self.kernel
            .step(
                core::array::from_mut(&mut state.pair),
                &mut state.cov,
                &mut state.counters,
                [sample],
            )
            .map(|[y]| y)
    }

    /// The sample expected at the next step, `Re[e^{iθ}(a + ib)]`.
    pub fn predict(&self, state: &SineState<T>) -> T {
        self.kernel.rotate(state.pair).0
    }

    /// Gain `(k_a, k_b)` the next sample will get.
    pub fn gain(&self, state: &SineState<T>) -> (T, T) {
        self.kernel.gain(&self.kernel.predict(&state.cov))
    }

    /// Covariance of `(a, b)`, in the signal's units squared.
    pub fn covariance(&self, state: &SineState<T>) -> [[T; 2]; 2] {
        scaled(&state.cov, self.noise2)
    }
}

/// Parameters of a [`ModulusTracker`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModulusSpec {
    /// Test frequency and tracking bandwidth.
    pub sine: SineSpec,
    /// Displacement channel (units of x).
    pub displacement: Channel,
    /// Force channel (units of F).
    pub force: Channel,
    /// The modulus is reported only when the displacement amplitude
    /// exceeds this many standard deviations of its estimate (10 keeps the
    /// error from the displacement estimate alone near 10 % at worst).
    /// `(min_snr σ_X)²`, with σ_X the displacement noise, must be finite in
    /// the working type.
    pub min_snr: f64,
}

/// Complex modulus `K* = K' + i K''` (seed 000 eq 1.5), force over
/// displacement units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Modulus<T> {
    /// Storage modulus K'.
    pub storage: T,
    /// Loss modulus K'' (positive when the force leads).
    pub loss: T,
}

impl<T: Real> Modulus<T> {
    /// `|K*|` (one square root).
    pub fn magnitude(&self) -> T {
        (self.storage * self.storage + self.loss * self.loss).sqrt()
    }
    /// Loss factor `η = K''/K' = tan δ`, `None` if K' is zero or the
    /// ratio is not finite.
    pub fn loss_factor(&self) -> Option<T> {
        if self.storage == T::ZERO {
            return None;
        }
        let eta = self.loss / self.storage;
        eta.is_finite().then_some(eta)
    }
}

/// Running state of a [`ModulusTracker`]: the displacement and force
/// analytic signals and their shared normalised covariance.
#[derive(Debug, Clone, PartialEq)]
pub struct ModulusState<T> {
    pairs: [(T, T); 2],
    cov: Cov<T>,
    counters: Counters,
}

impl<T: Real> ModulusState<T> {
    /// Displacement analytic signal `(a_X, b_X)`.
    pub fn displacement(&self) -> (T, T) {
        let [x, _] = self.pairs;
        x
    }
    /// Force analytic signal `(a_F, b_F)`.
    pub fn force(&self) -> (T, T) {
        let [_, f] = self.pairs;
        f
    }
    /// Sample pairs refused since the start.
    pub fn refused(&self) -> u32 {
        self.counters.refused
    }
    /// Covariance repairs since the start.
    pub fn repairs(&self) -> u32 {
        self.counters.repairs
    }
}

/// On-line instantaneous complex modulus of a sine test (seed 000 §1.2.1,
/// text after eq 1.3, Fig 1.24): two [`SineTracker`]s on the same
/// frequency, one on the displacement and one on the force, and
/// `K* = F / X = (a_F + i b_F)(a_X - i b_X) / (a_X² + b_X²)`.
///
/// The two channels share the rotation and one normalised covariance, so
/// they get the same gain at every sample and the two estimates are the
/// same linear filter of their signals. Whatever that filter does to the
/// phase of a sine, it does to both: the rounding of cos θ and sin θ, the
/// lag of a mistuned frequency and the start-up transient rotate and scale
/// X and F alike and cancel in the ratio (for channels with different
/// noise levels this is the Kalman filter of each one for the shared
/// initial signal-to-noise ratio, the larger of the two). States: `(a_X,
/// b_X, a_F, b_F)` and a 2×2 covariance. Cost: 31 multiplies and one
/// division per sample; [`ModulusTracker::modulus`] adds 9 and one
/// division when called. Stability and tuning as [`SineTracker`].
#[derive(Debug, Clone, PartialEq)]
pub struct ModulusTracker<T> {
    kernel: Kernel<T>,
    noise2: [T; 2],
    /// `min_snr² σ_X²`: the displacement's `|X|²` must exceed it times the
    /// trace of the normalised covariance.
    threshold: T,
}

impl<T: Real> ModulusTracker<T> {
    /// A tracker at time step `dt` (s).
    pub fn new(dt: f64, spec: &ModulusSpec) -> Result<Self, ParamError> {
        let (nx, ax) = check_channel(
            spec.displacement,
            "displacement_noise",
            "displacement_amplitude",
        )?;
        let (nf, af) = check_channel(spec.force, "force_noise", "force_amplitude")?;
        let min_snr = positive(Param::scalar("min_snr"), spec.min_snr)?;
        let kernel = Kernel::new(dt, &spec.sine, sq(ax / nx).max(sq(af / nf)))?;
        Ok(Self {
            kernel,
            noise2: [
                finite_square::<T>("displacement_noise", nx)?,
                finite_square::<T>("force_noise", nf)?,
            ],
            threshold: finite_square::<T>("min_snr", min_snr * nx)?,
        })
    }

    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.kernel.dt
    }
    /// Test frequency, Hz.
    pub fn frequency(&self) -> f64 {
        self.kernel.frequency
    }
    /// Tracking bandwidth, Hz.
    pub fn bandwidth(&self) -> f64 {
        self.kernel.bandwidth
    }

    /// The start state (zero amplitudes).
    pub fn start(&self) -> ModulusState<T> {
        ModulusState {
            pairs: [(T::ZERO, T::ZERO); 2],
            cov: self.kernel.start(),
            counters: Counters::default(),
        }
    }

    /// One displacement and one force sample taken at the same instant.
    /// Returns their innovations. If either is not finite, neither is
    /// used and both estimates are carried to the sample's time.
    pub fn step(
        &self,
        state: &mut ModulusState<T>,
        displacement: T,
        force: T,
    ) -> Result<(T, T), Refused> {
        self.kernel
            .step(
                &mut state.pairs,
                &mut state.cov,
                &mut state.counters,
                [displacement, force],
            )
            .map(|[x, f]| (x, f))
    }

    /// The instantaneous complex modulus `F / X`, or `None` while the
    /// displacement amplitude is below `min_snr` standard deviations of its
    /// estimate (at start-up, or when the displacement is too small to
    /// divide by).
    pub fn modulus(&self, state: &ModulusState<T>) -> Option<Modulus<T>> {
        let [(ax, bx), (af, bf)] = state.pairs;
        let x2 = ax * ax + bx * bx;
        let floor = self.threshold * (state.cov.p00 + state.cov.p11);
        if !(x2 > floor && x2 > T::ZERO && x2.is_finite()) {
            return None;
        }
        let inv = T::ONE / x2;
        let m = Modulus {
            storage: (af * ax + bf * bx) * inv,
            loss: (bf * ax - af * bx) * inv,
        };
        (m.storage.is_finite() && m.loss.is_finite()).then_some(m)
    }

    /// Covariance of the displacement's `(a, b)` (channel 0) or the
    /// force's (channel 1), in the signal's units squared.
    pub fn covariance(&self, state: &ModulusState<T>, channel: usize) -> [[T; 2]; 2] {
        let n2 = self.noise2.get(channel).copied().unwrap_or(T::ZERO);
        scaled(&state.cov, n2)
    }
}

fn sq(x: f64) -> f64 {
    x * x
}

/// `x²` in the working type, refused as [`ParamError::NotFinite`] on
/// `name` if it overflows there.
fn finite_square<T: Real>(name: &'static str, x: f64) -> Result<T, ParamError> {
    let v = T::from_f64(sq(x));
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ParamError::NotFinite {
            param: Param::scalar(name),
        })
    }
}

fn scaled<T: Real>(p: &Cov<T>, n2: T) -> [[T; 2]; 2] {
    [[p.p00 * n2, p.p01 * n2], [p.p01 * n2, p.p11 * n2]]
}

fn check_channel(
    c: Channel,
    noise: &'static str,
    amplitude: &'static str,
) -> Result<(f64, f64), ParamError> {
    let n = positive(Param::scalar(noise), c.noise)?;
    let a = positive(Param::scalar(amplitude), c.amplitude)?;
    if !(a / n).is_finite() {
        return Err(ParamError::NotFinite {
            param: Param::scalar(amplitude),
        });
    }
    Ok((n, a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::TAU;

    /// Deterministic standard normal samples (xorshift64* and Box-Muller).
    struct Gauss(u64);

    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let v = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
            ((v >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn next(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            libm::sqrt(-2.0 * libm::log(u)) * libm::cos(TAU * v)
        }
    }

    fn spec(frequency: f64, bandwidth: f64) -> SineSpec {
        SineSpec {
            frequency,
            bandwidth,
        }
    }

    const CH: Channel = Channel {
        noise: 1e-3,
        amplitude: 1.0,
    };

    #[test]
    fn bad_parameters_are_typed_errors() {
        let new = |dt, f, b, n, a| {
            SineTracker::<f32>::new(
                dt,
                &spec(f, b),
                Channel {
                    noise: n,
                    amplitude: a,
                },
            )
        };
        assert!(new(1e-3, 10.0, 0.5, 1e-3, 1.0).is_ok());
        let not_positive = |r: Result<SineTracker<f32>, ParamError>, name| matches!(r, Err(ParamError::NotPositive { param, .. }) if param == Param::scalar(name));
        let not_finite = |r: Result<SineTracker<f32>, ParamError>, name| matches!(r, Err(ParamError::NotFinite { param }) if param == Param::scalar(name));
        let out_of_range = |r: Result<SineTracker<f32>, ParamError>, name| matches!(r, Err(ParamError::OutOfRange { param, .. }) if param == Param::scalar(name));
        assert!(not_positive(new(0.0, 10.0, 0.5, 1e-3, 1.0), "dt"));
        assert!(not_positive(new(-1e-3, 10.0, 0.5, 1e-3, 1.0), "dt"));
        assert!(not_finite(new(f64::NAN, 10.0, 0.5, 1e-3, 1.0), "dt"));
        assert!(not_positive(new(1e-3, 0.0, 0.5, 1e-3, 1.0), "frequency"));
        assert!(not_finite(
            new(1e-3, f64::INFINITY, 0.5, 1e-3, 1.0),
            "frequency"
        ));
        // Nyquist is 500 Hz at 1 kHz: refused at and above it.
        assert!(out_of_range(new(1e-3, 500.0, 0.5, 1e-3, 1.0), "frequency"));
        assert!(new(1e-3, 499.0, 0.5, 1e-3, 1.0).is_ok());
        assert!(not_positive(new(1e-3, 10.0, 0.0, 1e-3, 1.0), "bandwidth"));
        assert!(not_finite(
            new(1e-3, 10.0, f64::NAN, 1e-3, 1.0),
            "bandwidth"
        ));
        // Above f/2, or so wide that K > 1/4.
        assert!(out_of_range(new(1e-3, 10.0, 5.1, 1e-3, 1.0), "bandwidth"));
        assert!(new(1e-3, 10.0, 5.0, 1e-3, 1.0).is_ok());
        assert!(out_of_range(new(1e-3, 400.0, 50.0, 1e-3, 1.0), "bandwidth"));
        // So narrow that the rounding of the update would matter in f32
        // (K < 1024 ε) but not in f64.
        let narrow = 1e-4 / (TAU * 1e-3);
        assert!(out_of_range(
            new(1e-3, 10.0, narrow, 1e-3, 1.0),
            "bandwidth"
        ));
        assert!(
            SineTracker::<f64>::new(
                1e-3,
                &spec(10.0, narrow),
                Channel {
                    noise: 1e-3,
                    amplitude: 1.0
                }
            )
            .is_ok()
        );
        assert!(not_positive(new(1e-3, 10.0, 0.5, 0.0, 1.0), "noise"));
        assert!(not_finite(new(1e-3, 10.0, 0.5, f64::NAN, 1.0), "noise"));
        assert!(not_positive(new(1e-3, 10.0, 0.5, 1e-3, -1.0), "amplitude"));
        assert!(not_finite(new(1e-3, 10.0, 0.5, 1e-300, 1e300), "amplitude"));

        let m = |x: Channel, f: Channel, snr| {
            ModulusTracker::<f32>::new(
                1e-3,
                &ModulusSpec {
                    sine: spec(10.0, 0.5),
                    displacement: x,
                    force: f,
                    min_snr: snr,
                },
            )
        };
        assert!(m(CH, CH, 10.0).is_ok());
        let bad = Channel {
            noise: -1.0,
            amplitude: 1.0,
        };
        assert!(matches!(
            m(bad, CH, 10.0),
            Err(ParamError::NotPositive { param, .. }) if param == Param::scalar("displacement_noise")
        ));
        assert!(matches!(
            m(CH, bad, 10.0),
            Err(ParamError::NotPositive { param, .. }) if param == Param::scalar("force_noise")
        ));
        assert!(matches!(
            m(CH, CH, 0.0),
            Err(ParamError::NotPositive { param, .. }) if param == Param::scalar("min_snr")
        ));
    }

    /// Runs a tracker on `x_n = Re[u e^{iθn}] (+ noise)` and returns the
    /// largest error `|a + ib - u e^{iθn}| / |u|` from sample `from` on.
    fn clean_error<T: Real>(samples: usize, periods: usize, from: usize) -> f64 {
        let f = 10.0;
        let dt = 1.0 / (f * samples as f64);
        let tr = SineTracker::<T>::new(dt, &spec(f, f / 20.0), CH).unwrap();
        let mut s = tr.start();
        let (ur, ui) = (0.6, -0.8);
        let mut worst: f64 = 0.0;
        for n in 0..samples * periods {
            let ph = TAU * (n % samples) as f64 / samples as f64;
            let (c, sn) = (libm::cos(ph), libm::sin(ph));
            let (re, im) = (ur * c - ui * sn, ur * sn + ui * c);
            assert_eq!(tr.predict(&s), tr.kernel.rotate(s.pair()).0);
            tr.step(&mut s, T::from_f64(re)).unwrap();
            if n >= from {
                let (a, b) = s.pair();
                let e = libm::hypot(a.to_f64() - re, b.to_f64() - im);
                worst = worst.max(e);
            }
        }
        assert_eq!(s.repairs(), 0);
        worst
    }

    #[test]
    fn clean_sine_is_fitted_exactly_after_one_period() {
        // The model holds, so the filter is exact once the prior is
        // outweighed: the prior's pull is about 2 / (N p0) with N samples and
        // p0 = (amplitude / noise)² = 1e6 (f64) or 1 / (64 ε) = 1.3e5 (f32).
        for samples in [4, 10, 50, 200] {
            let e64 = clean_error::<f64>(samples, 6, samples);
            assert!(e64 < 1e-6, "f64, {samples} samples/period: {e64:e}");
            let e32 = clean_error::<f32>(samples, 6, samples);
            assert!(e32 < 2e-5, "f32, {samples} samples/period: {e32:e}");
        }
    }

    #[test]
    fn steady_state_corner_is_the_bandwidth() {
        // The steady-state error dynamics (I - k H) F have the pole pair
        // ρ e^{±iθ} with ρ² = det = 1 - k_a: compare ρ with e^{-2π B Δt}.
        // The design averages the measurement over a period, so it holds
        // to O(B/f) and O(1/samples).
        for (samples, ratios, tol) in [
            (50usize, [0.01, 0.05, 0.2], 0.01),
            (200, [0.01, 0.05, 0.2], 0.01),
            (1000, [0.01, 0.05, 0.2], 0.01),
            (4, [0.01, 0.02, 0.05], 0.05),
            (10, [0.01, 0.02, 0.05], 0.05),
        ] {
            for r in ratios {
                let f = 1.0;
                let dt = 1.0 / (f * samples as f64);
                let tr = SineTracker::<f64>::new(dt, &spec(f, r * f), CH).unwrap();
                let mut s = tr.start();
                // The covariance does not depend on the data; 12 time
                // constants of the envelope.
                let n = (12.0 / (TAU * r * f * dt)) as usize;
                for _ in 0..n {
                    tr.step(&mut s, 0.0).unwrap();
                }
                let (k0, _) = tr.gain(&s);
                let rho = libm::sqrt(1.0 - k0);
                let corner = libm::log(rho) / libm::log(tr.envelope_pole());
                assert!(
                    (corner - 1.0).abs() < tol,
                    "{samples} samples/period, B = {r} f: corner {corner}"
                );
            }
        }
    }

    #[test]
    fn steady_noise_on_the_estimate_is_sigma_root_k() {
        // The envelope low-pass of pole 1 - K fed by the measurement noise
        // leaves σ² K on each of a and b; the filter's covariance, which
        // also allows for the amplitude wander, says 2K. 2e6 samples are
        // about 3000 correlation times: 1.3 % statistical spread on the
        // standard deviation.
        let (f, samples, sigma) = (10.0, 200usize, 0.01);
        let dt = 1.0 / (f * samples as f64);
        let ch = Channel {
            noise: sigma,
            amplitude: 1.0,
        };
        let tr = SineTracker::<f64>::new(dt, &spec(f, 0.05 * f), ch).unwrap();
        let k = 1.0 - tr.envelope_pole();
        let mut s = tr.start();
        let mut g = Gauss(0x2545_f491_4f6c_dd1d);
        let first = (20.0 / k) as usize;
        let (mut sa, mut sb, mut count) = (0.0, 0.0, 0.0);
        for n in 0..first + 2_000_000 {
            let ph = TAU * f * dt * n as f64;
            let (c, sn) = (libm::cos(ph), libm::sin(ph));
            tr.step(&mut s, c + sigma * g.next()).unwrap();
            if n >= first {
                let (a, b) = s.pair();
                sa += (a - c) * (a - c);
                sb += (b - sn) * (b - sn);
                count += 1.0;
            }
        }
        let expected = sigma * libm::sqrt(k);
        for (name, v) in [("a", sa), ("b", sb)] {
            let std = libm::sqrt(v / count);
            assert!(
                (std / expected - 1.0).abs() < 0.05,
                "{name}: {std:e} vs σ√K = {expected:e}"
            );
        }
        let p = tr.covariance(&s);
        let said = sigma * sigma * 2.0 * k;
        assert!((p[0][0] / said - 1.0).abs() < 0.05 && (p[1][1] / said - 1.0).abs() < 0.05);
    }

    #[test]
    fn a_constant_offset_leaks_as_two_b_over_f() {
        // In the frame turning with the sine, an offset D sits at -f, where
        // the envelope low-pass of corner B passes about 2 (B/f) D.
        for ratio in [0.01, 0.05] {
            let (f, samples, offset) = (10.0, 200usize, 0.3);
            let dt = 1.0 / (f * samples as f64);
            let tr = SineTracker::<f64>::new(dt, &spec(f, ratio * f), CH).unwrap();
            let k = 1.0 - tr.envelope_pole();
            let mut s = tr.start();
            let first = (30.0 / k) as usize;
            let mut worst: f64 = 0.0;
            for n in 0..first + 20 * samples {
                let ph = TAU * f * dt * n as f64;
                let (c, sn) = (libm::cos(ph), libm::sin(ph));
                tr.step(&mut s, c + offset).unwrap();
                if n >= first {
                    let (a, b) = s.pair();
                    worst = worst.max(libm::hypot(a - c, b - sn));
                }
            }
            let expected = 2.0 * ratio * offset;
            assert!(
                (worst / expected - 1.0).abs() < 0.05,
                "B = {ratio} f: {worst:e} vs {expected:e}"
            );
        }
    }

    #[test]
    fn non_finite_samples_are_refused_and_the_phase_kept() {
        let dt = 1e-3;
        let tr = SineTracker::<f32>::new(dt, &spec(10.0, 0.5), CH).unwrap();
        let mut s = tr.start();
        let x = |n: usize| libm::sin(TAU * 10.0 * dt * n as f64) as f32;
        for n in 0..300 {
            tr.step(&mut s, x(n)).unwrap();
        }
        for (n, bad) in [
            (300, f32::NAN),
            (301, f32::INFINITY),
            (302, f32::NEG_INFINITY),
        ] {
            let before = s.clone();
            assert_eq!(tr.step(&mut s, bad), Err(Refused::NonFiniteSample));
            // The prediction only: rotated estimate, grown covariance.
            assert_eq!(s.pair(), tr.kernel.rotate(before.pair()));
            assert!(tr.covariance(&s)[0][0] + tr.covariance(&s)[1][1] > 0.0);
            let _ = n;
        }
        assert_eq!(s.refused(), 3);
        // The next sample fits the phase carried through the gap.
        let y = tr.step(&mut s, x(303)).unwrap();
        assert!(y.abs() < 1e-3, "innovation after the gap {y}");
        assert!((s.amplitude() - 1.0).abs() < 1e-3);

        // A sample whose update would take the state beyond GUARD (2^60) is
        // refused too, with the same prediction; 2^59 is taken.
        let mut big = tr.start();
        assert_eq!(tr.step(&mut big, f32::MAX), Err(Refused::Overflow));
        assert_eq!(big.pair(), (0.0, 0.0));
        tr.step(&mut big, 2f32.powi(59)).unwrap();
        assert!(big.a() > 0.99 * 2f32.powi(59) && big.a() <= f32::GUARD);
        let kept = big.clone();
        assert_eq!(tr.step(&mut big, -f32::MAX), Err(Refused::Overflow));
        assert_eq!(big.pair(), tr.kernel.rotate(kept.pair()));
        assert_eq!(big.refused(), 2);

        // The modulus tracker refuses the pair if either sample is bad.
        let m = ModulusTracker::<f32>::new(
            dt,
            &ModulusSpec {
                sine: spec(10.0, 0.5),
                displacement: CH,
                force: CH,
                min_snr: 10.0,
            },
        )
        .unwrap();
        let mut ms = m.start();
        assert_eq!(
            m.step(&mut ms, 1.0, f32::NAN),
            Err(Refused::NonFiniteSample)
        );
        assert_eq!(ms.displacement(), (0.0, 0.0));
        assert_eq!(ms.refused(), 1);
    }

    /// Runs f32 and f64 trackers side by side on a noisy sine and checks
    /// the f32 covariance at every step.
    fn covariance_run(samples: usize, ratio: f64, snr: f64, steps: usize) {
        let f = 50.0;
        let dt = 1.0 / (f * samples as f64);
        let ch = Channel {
            noise: 1.0 / snr,
            amplitude: 1.0,
        };
        let t32 = SineTracker::<f32>::new(dt, &spec(f, ratio * f), ch).unwrap();
        let t64 = SineTracker::<f64>::new(dt, &spec(f, ratio * f), ch).unwrap();
        let (mut s32, mut s64) = (t32.start(), t64.start());
        let mut g = Gauss(0x9e37_79b9_7f4a_7c15);
        for n in 0..steps {
            let z = libm::sin(TAU * f * dt * n as f64 + 0.4) + g.next() / snr;
            t32.step(&mut s32, z as f32).unwrap();
            t64.step(&mut s64, z).unwrap();
            let p = t32.covariance(&s32);
            assert_eq!(p[0][1], p[1][0]);
            let det = p[0][0] as f64 * p[1][1] as f64 - p[0][1] as f64 * p[0][1] as f64;
            assert!(
                p[0][0] > 0.0 && p[1][1] > 0.0 && det >= 0.0,
                "{samples} samples/period, step {n}: {p:?}"
            );
        }
        assert_eq!(s32.repairs(), 0);
        assert_eq!(s64.repairs(), 0);
        // Steady state: the f32 covariance and estimate follow f64's.
        let (p32, p64) = (t32.covariance(&s32), t64.covariance(&s64));
        let scale = p64[0][0] + p64[1][1];
        for i in 0..2 {
            for j in 0..2 {
                let d = (p32[i][j] as f64 - p64[i][j]).abs() / scale;
                assert!(
                    d < 1e-3,
                    "{samples}: P[{i}][{j}] {} vs {}",
                    p32[i][j],
                    p64[i][j]
                );
            }
        }
        let (a32, b32) = s32.pair();
        let (a64, b64) = s64.pair();
        let d = libm::hypot(a32 as f64 - a64, b32 as f64 - b64);
        assert!(d < 1e-4, "{samples}: estimate differs by {d:e}");
    }

    #[test]
    fn f32_covariance_stays_symmetric_positive_over_long_runs() {
        // From 4 to 2000 samples per period, narrow and wide bandwidths,
        // noisy and near-clean signals (the cap on the initial variance
        // matters for the latter), 200 000 steps each.
        for (samples, ratio, snr) in [
            (4, 0.01, 100.0),
            (10, 0.05, 1e6),
            (200, 0.01, 100.0),
            (200, 0.2, 1e9),
            (2000, 0.05, 1e4),
        ] {
            covariance_run(samples, ratio, snr, 200_000);
        }
    }

    #[test]
    fn f32_clean_sine_at_the_narrowest_bandwidth_stays_within_the_dead_band() {
        // K = 1024 ε, the smallest accepted: a correction below half an ulp
        // is lost, so the error may wander up to about ε / (8K) = 1.2e-4 of
        // the amplitude; the rotation must not add a drift of its own (with
        // cos θ rounded next to 1 it would bias the amplitude by up to
        // ε/(4K) = 2.4e-4). Slow sines at fast sampling are the hard case.
        for (fs, f) in [(1e4, 1.0), (1e5, 50.0), (1e3, 10.0)] {
            let dt = 1.0 / fs;
            let k_min = 1024.0 * f32::EPSILON as f64;
            let b = -libm::log1p(-k_min) / (TAU * dt) * (1.0 + 1e-9);
            let tr = SineTracker::<f32>::new(dt, &spec(f, b), CH).unwrap();
            let k = 1.0 - tr.envelope_pole();
            let mut s = tr.start();
            // 40 envelope time constants, the second half checked.
            let total = (40.0 / k) as usize;
            let mut worst: f64 = 0.0;
            for n in 0..total {
                let ph = TAU * f * dt * n as f64;
                tr.step(&mut s, libm::cos(ph) as f32).unwrap();
                if n > total / 2 {
                    let (a, b) = s.pair();
                    let e = libm::hypot(a as f64 - libm::cos(ph), b as f64 - libm::sin(ph));
                    worst = worst.max(e);
                }
            }
            let band = f32::EPSILON as f64 / (8.0 * k);
            assert!(
                worst < band,
                "{fs} Hz sampling, {f} Hz: {worst:e} vs {band:e}"
            );
        }
    }

    fn modulus_tracker(f: f64, samples: usize, ratio: f64) -> ModulusTracker<f64> {
        ModulusTracker::new(
            1.0 / (f * samples as f64),
            &ModulusSpec {
                sine: spec(f, ratio * f),
                displacement: CH,
                force: CH,
                min_snr: 10.0,
            },
        )
        .unwrap()
    }

    #[test]
    fn modulus_of_a_clean_linear_pair_is_exact_and_waits_for_the_displacement() {
        let (f, samples) = (10.0, 100);
        let m = modulus_tracker(f, samples, 0.05);
        let (k1, k2) = (3.0, 0.7);
        let mut s = m.start();
        assert_eq!(m.modulus(&s), None);
        let mut first = None;
        for n in 0..samples * 3 {
            let ph = TAU * n as f64 / samples as f64 + 1.0;
            let x = 0.2 * libm::cos(ph);
            let force = 0.2 * (k1 * libm::cos(ph) - k2 * libm::sin(ph));
            m.step(&mut s, x, force).unwrap();
            if let Some(k) = m.modulus(&s) {
                first.get_or_insert(n);
                if n >= samples {
                    assert!((k.storage - k1).abs() < 1e-6 && (k.loss - k2).abs() < 1e-6);
                }
            }
        }
        // Available within the first tenth of a period.
        assert!(first.is_some_and(|n| n < samples / 10), "{first:?}");
        let k = m.modulus(&s).unwrap();
        assert!((k.loss_factor().unwrap() - k2 / k1).abs() < 1e-6);
        assert!((k.magnitude() - libm::hypot(k1, k2)).abs() < 1e-6);

        // No displacement: never a modulus, however large the force.
        let mut s = m.start();
        for n in 0..samples * 3 {
            let ph = TAU * n as f64 / samples as f64;
            m.step(&mut s, 0.0, 1e3 * libm::sin(ph)).unwrap();
            assert_eq!(m.modulus(&s), None);
        }
    }

    #[test]
    fn a_mistuned_frequency_biases_each_amplitude_but_not_the_modulus() {
        // The sine is 1 % above the tuned 10 Hz: 0.1 Hz off against a
        // 0.5 Hz corner, so each amplitude is seen through the low-pass at
        // the offset, |1/(1 + 0.2 i)| = 0.98 with a 0.2 rad lag (an error of
        // about 0.2 of the amplitude), identical on both channels.
        let (f, samples) = (10.0, 100);
        let m = modulus_tracker(f, samples, 0.05);
        let kstar = (3.0, 0.7);
        let mut s = m.start();
        let (mut amp_err, mut mod_err): (f64, f64) = (0.0, 0.0);
        let true_f = 1.01 * f;
        let dt = m.dt();
        for n in 0..samples * 40 {
            let ph = TAU * true_f * dt * n as f64;
            let (c, sn) = (libm::cos(ph), libm::sin(ph));
            let x = c;
            let force = kstar.0 * c - kstar.1 * sn;
            m.step(&mut s, x, force).unwrap();
            if n >= samples * 20 {
                let (a, b) = s.displacement();
                amp_err = amp_err.max(libm::hypot(a - c, b - sn));
                let k = m.modulus(&s).unwrap();
                let e = libm::hypot(k.storage - kstar.0, k.loss - kstar.1)
                    / libm::hypot(kstar.0, kstar.1);
                mod_err = mod_err.max(e);
            }
        }
        assert!(amp_err > 0.1, "displacement error {amp_err}");
        assert!(mod_err < 5e-3, "modulus error {mod_err}");
    }

    #[test]
    fn ordinary_tracking_is_unchanged_by_the_guard() {
        // Bit patterns of every a, b and innovation of a noisy f32 run
        // (FNV-style hash) and the end values, recorded before the state
        // guard was added: the guard only compares.
        let dt = 1e-3;
        let tr = SineTracker::<f32>::new(dt, &spec(10.0, 0.5), CH).unwrap();
        let mut s = tr.start();
        let mut g = Gauss(0x1234_5678_9abc_def1);
        let mut h: u64 = 0;
        for n in 0..5000 {
            let z = 2.0 * libm::sin(TAU * 10.3 * dt * n as f64 + 0.3) + 0.05 * g.next();
            let y = tr.step(&mut s, z as f32).unwrap();
            for v in [s.a(), s.b(), y] {
                h = (h ^ v.bits()).wrapping_mul(0x0100_0000_01b3);
            }
        }
        assert_eq!(h, 0x603c_8e0a_08c4_6e53);
        assert_eq!(s.pair(), (0.521_148_9, 1.612_143_2));
        let p = tr.covariance(&s);
        assert_eq!(
            (p[0][0], p[0][1], p[1][1]),
            (6.271_389e-9, -1.566_794_3e-10, 6.306_885_2e-9)
        );
        let m = ModulusTracker::<f32>::new(
            dt,
            &ModulusSpec {
                sine: spec(10.0, 0.5),
                displacement: CH,
                force: Channel {
                    noise: 1e-2,
                    amplitude: 5.0,
                },
                min_snr: 10.0,
            },
        )
        .unwrap();
        let mut ms = m.start();
        let mut h: u64 = 0;
        for n in 0..5000 {
            let ph = TAU * 10.0 * dt * n as f64;
            let x = libm::cos(ph) + 1e-3 * g.next();
            let f = 3.0 * libm::cos(ph) - 0.7 * libm::sin(ph) + 1e-2 * g.next();
            let (yx, yf) = m.step(&mut ms, x as f32, f as f32).unwrap();
            let ((ax, bx), (af, bf)) = (ms.displacement(), ms.force());
            for v in [ax, bx, af, bf, yx, yf] {
                h = (h ^ v.bits()).wrapping_mul(0x0100_0000_01b3);
            }
        }
        assert_eq!(h, 0x8f95_bba6_51f0_fc90);
        assert_eq!(ms.displacement(), (0.998_081_15, -0.062_783_33));
        assert_eq!(ms.force(), (3.037_794_6, 0.510_287_94));
        let k = m.modulus(&ms).unwrap();
        assert_eq!((k.storage, k.loss), (2.999_604_7, 0.699_956_2));
    }

    #[test]
    fn samples_near_f32_max_leave_the_state_within_the_guard() {
        // Accepted, they used to put a and b near f32::MAX, where the next
        // rotation overflowed (a = -inf, then NaN). Each would now take the
        // state beyond 2^60: all refused, the state stays zero, and the
        // tracker then follows a sine as from the start.
        let ys = [
            -3.4e38f32, -3.4e38, 3.4e38, 3.4e38, -1e38, 3.4e38, 1e38, -3.4e38, -3.4e38, -2e38,
        ];
        let ch = Channel {
            noise: 1.0,
            amplitude: 1.0,
        };
        let dt = 1e-3;
        let sine = SineSpec {
            frequency: 100.0,
            bandwidth: 1.0,
        };
        let t = SineTracker::<f32>::new(dt, &sine, ch).unwrap();
        let mut s = t.start();
        for y in ys {
            assert_eq!(t.step(&mut s, y), Err(Refused::Overflow));
            assert_eq!(s.pair(), (0.0, 0.0));
        }
        assert_eq!(s.refused(), 10);
        let m = ModulusTracker::<f32>::new(
            dt,
            &ModulusSpec {
                sine,
                displacement: ch,
                force: ch,
                min_snr: 1.0,
            },
        )
        .unwrap();
        let mut ms = m.start();
        // Either channel too large refuses the pair; a small one alone is
        // fine.
        for (i, y) in ys.into_iter().enumerate() {
            let (x, f) = if i % 2 == 0 { (y, 0.5) } else { (0.5, y) };
            assert_eq!(m.step(&mut ms, x, f), Err(Refused::Overflow));
            assert_eq!(ms.displacement(), (0.0, 0.0));
            assert_eq!(ms.force(), (0.0, 0.0));
        }
        assert_eq!(ms.refused(), 10);
        for n in 0..2000 {
            let ph = TAU * 100.0 * dt * n as f64;
            let (c, sn) = (libm::cos(ph), libm::sin(ph));
            t.step(&mut s, c as f32).unwrap();
            m.step(&mut ms, c as f32, (2.0 * c - 0.5 * sn) as f32)
                .unwrap();
        }
        assert!((s.amplitude() - 1.0).abs() < 1e-4, "{}", s.amplitude());
        let k = m.modulus(&ms).unwrap();
        assert!((k.storage - 2.0).abs() < 1e-4 && (k.loss - 0.5).abs() < 1e-4);
    }

    /// Drives a tracker of `C` channels with samples of the order of GUARD,
    /// the largest finite value, NaN and infinities, and checks the
    /// documented outcome of every step. Returns how often each path was
    /// taken: accepted, refused with the rotation stored, refused with the
    /// rotation halved.
    fn hostile<T: Real, const C: usize>(
        kernel: &Kernel<T>,
        mut step: impl FnMut([T; C]) -> (Result<[T; C], Refused>, [(T, T); C], u32),
        seed: u64,
    ) -> [u32; 3] {
        let g = T::GUARD.to_f64();
        let big = T::from_f64(f64::MAX).to_f64(); // the largest finite value
        let levels = [
            0.0,
            0.3,
            0.7,
            0.99,
            1.0,
            1.5,
            3.0,
            1e-20,
            1e20,
            big,
            f64::NAN,
            f64::INFINITY,
        ];
        let mut u = Gauss(seed);
        let mut pick = || {
            let v = levels[(u.uniform() * levels.len() as f64) as usize];
            let v = if v.is_finite() && v != big && v > 1e-10 && v < 1e10 {
                v * g
            } else {
                v
            };
            T::from_f64(if u.uniform() < 0.5 { -v } else { v })
        };
        let mut before = [(T::ZERO, T::ZERO); C];
        let mut counts = [0u32; 3];
        for n in 1..=20_000u32 {
            let z: [T; C] = core::array::from_fn(|_| pick());
            let rotated = before.map(|p| kernel.rotate(p));
            let (r, after, refused) = step(z);
            assert!(guarded(&after), "step {n}: {after:?}");
            match r {
                Ok(y) => {
                    assert!(y.iter().all(|v| v.is_finite()));
                    counts[0] += 1;
                }
                Err(e) => {
                    let expected = if z.iter().all(|v| v.is_finite()) {
                        Refused::Overflow
                    } else {
                        Refused::NonFiniteSample
                    };
                    assert_eq!(e, expected, "step {n}: {z:?}");
                    if guarded(&rotated) {
                        assert_eq!(after, rotated);
                        counts[1] += 1;
                    } else {
                        assert_eq!(after, rotated.map(|(a, b)| (a * T::HALF, b * T::HALF)));
                        counts[2] += 1;
                    }
                }
            }
            assert_eq!(refused, counts[1] + counts[2]);
            before = after;
        }
        counts
    }

    fn hostile_runs<T: Real>() {
        // θ = π/4 turns a state at the guard's corner past it.
        let (dt, sine) = (1e-3, spec(125.0, 10.0));
        let ch = Channel {
            noise: 1.0,
            amplitude: 1.0,
        };
        let t = SineTracker::<T>::new(dt, &sine, ch).unwrap();
        let mut s = t.start();
        let counts = hostile(
            &t.kernel,
            |[z]| {
                let r = t.step(&mut s, z).map(|y| [y]);
                assert!(s.amplitude().is_finite());
                (r, [s.pair()], s.refused())
            },
            0x2545_f491_4f6c_dd1d,
        );
        assert!(
            counts.iter().all(|&c| c > 0),
            "{} sine: {counts:?}",
            T::NAME
        );
        let m = ModulusTracker::<T>::new(
            dt,
            &ModulusSpec {
                sine,
                displacement: ch,
                force: ch,
                min_snr: 1.0,
            },
        )
        .unwrap();
        let mut ms = m.start();
        let counts = hostile(
            &m.kernel,
            |[x, f]| {
                let r = m.step(&mut ms, x, f).map(|(x, f)| [x, f]);
                if let Some(k) = m.modulus(&ms) {
                    assert!(k.storage.is_finite() && k.loss.is_finite());
                }
                (r, ms.pairs, ms.refused())
            },
            0x9e37_79b9_7f4a_7c15,
        );
        assert!(
            counts.iter().all(|&c| c > 0),
            "{} modulus: {counts:?}",
            T::NAME
        );
    }

    #[test]
    fn hostile_samples_never_take_the_state_past_the_guard() {
        hostile_runs::<f32>();
        hostile_runs::<f64>();
    }

    #[test]
    fn a_subnormal_time_step_gives_finite_coefficients() {
        // 2π f overflowed before f Δt was formed: θ was inf and the first
        // step gave a = b = NaN. With θ = 2π (f Δt) this is the tracker of
        // 360 Hz at 1 kHz, 36 Hz wide.
        let ch = Channel {
            noise: 1.0,
            amplitude: 1.0,
        };
        let tiny = SineTracker::<f64>::new(1e-308, &spec(3.6e307, 3.6e306), ch).unwrap();
        let plain = SineTracker::<f64>::new(1e-3, &spec(360.0, 36.0), ch).unwrap();
        let (vt, vp) = (&tiny.kernel, &plain.kernel);
        for (a, b) in [
            (vt.vers, vp.vers),
            (vt.sin, vp.sin),
            (vt.vers2, vp.vers2),
            (vt.sin2, vp.sin2),
            (vt.q, vp.q),
        ] {
            assert!((a / b - 1.0).abs() < 1e-14, "{a} vs {b}");
        }
        let (mut st, mut sp) = (tiny.start(), plain.start());
        for n in 0..100 {
            let z = libm::cos(TAU * 0.36 * n as f64 + 0.2);
            tiny.step(&mut st, z).unwrap();
            plain.step(&mut sp, z).unwrap();
            let (a, b) = st.pair();
            assert!(libm::hypot(a - sp.a(), b - sp.b()) < 1e-12, "step {n}");
        }
        assert!((st.amplitude() - 1.0).abs() < 1e-9);
        let modulus = |dt, f, b| {
            ModulusTracker::<f64>::new(
                dt,
                &ModulusSpec {
                    sine: spec(f, b),
                    displacement: ch,
                    force: ch,
                    min_snr: 10.0,
                },
            )
            .unwrap()
        };
        let (mt, mp) = (
            modulus(1e-308, 3.6e307, 3.6e306),
            modulus(1e-3, 360.0, 36.0),
        );
        let (mut st, mut sp) = (mt.start(), mp.start());
        for n in 0..100 {
            let ph = TAU * 0.36 * n as f64;
            let (x, f) = (libm::cos(ph), 2.0 * libm::cos(ph + 0.3));
            mt.step(&mut st, x, f).unwrap();
            mp.step(&mut sp, x, f).unwrap();
            for (a, b) in [
                (st.displacement(), sp.displacement()),
                (st.force(), sp.force()),
            ] {
                assert!(libm::hypot(a.0 - b.0, a.1 - b.1) < 1e-12, "step {n}");
            }
        }

        // Across time steps from the smallest subnormal to 1e300 and
        // frequencies up to Nyquist or f64::MAX: either a typed refusal or
        // finite coefficients and steps (f32: 48 of 216 built, f64: 85,
        // among them f = f64::MAX at Δt = 1e-310, where 2π f overflows).
        let mut built = [0; 2];
        for dt in [5e-324, 1e-320, 1e-310, 1e-308, 1e-300, 1e-3, 1.0, 1e300] {
            let near_nyquist = [1e-6, 0.01, 0.2, 0.49, 0.499_999_999_999].map(|r| r / dt);
            for f in near_nyquist
                .into_iter()
                .chain([1.0, 1e300, 0.5 * f64::MAX, f64::MAX])
            {
                for ratio in [1e-3, 0.05, 0.5] {
                    let sine = spec(f, ratio * f);
                    built[0] += check_built::<f32>(SineTracker::new(dt, &sine, ch), dt * f);
                    built[1] += check_built::<f64>(SineTracker::new(dt, &sine, ch), dt * f);
                }
            }
        }
        assert_eq!(built, [48, 85]);
    }

    /// Checks the coefficients and 20 steps of a built tracker; 1 if built.
    fn check_built<T: Real>(t: Result<SineTracker<T>, ParamError>, f_dt: f64) -> u32 {
        let Ok(t) = t else {
            return 0;
        };
        let k = &t.kernel;
        let coefficients = [k.vers, k.sin, k.vers2, k.sin2, k.q, k.p0];
        assert!(
            coefficients.iter().all(|c| c.is_finite()) && k.sin > T::ZERO,
            "{} f dt {f_dt:e}: {coefficients:?}",
            T::NAME
        );
        let mut s = t.start();
        for n in 0..20 {
            let z = libm::cos(TAU * f_dt * n as f64);
            t.step(&mut s, T::from_f64(z)).unwrap();
            assert!(s.a().is_finite() && s.b().is_finite());
        }
        1
    }

    #[test]
    fn squares_that_overflow_the_working_type_are_refused() {
        // The covariance is reported times noise²: 1e40 is infinite in f32.
        let ch = Channel {
            noise: 1e20,
            amplitude: 1e21,
        };
        assert_eq!(
            SineTracker::<f32>::new(1e-3, &spec(10.0, 0.5), ch),
            Err(ParamError::NotFinite {
                param: Param::scalar("noise")
            })
        );
        let t = SineTracker::<f64>::new(1e-3, &spec(10.0, 0.5), ch).unwrap();
        assert!(t.covariance(&t.start())[0][0].is_finite());
        let m = |displacement, force, min_snr| {
            ModulusTracker::<f32>::new(
                1e-3,
                &ModulusSpec {
                    sine: spec(10.0, 0.5),
                    displacement,
                    force,
                    min_snr,
                },
            )
        };
        let not_finite = |name| {
            Err(ParamError::NotFinite {
                param: Param::scalar(name),
            })
        };
        assert_eq!(m(ch, CH, 10.0), not_finite("displacement_noise"));
        assert_eq!(m(CH, ch, 10.0), not_finite("force_noise"));
        // (min_snr σ_X)² = (1e20 · 1e-3)² = 1e34 fits; (1e25 · 1e-3)² not.
        assert!(m(CH, CH, 1e20).is_ok());
        assert_eq!(m(CH, CH, 1e25), not_finite("min_snr"));
    }

    #[test]
    fn a_state_at_the_guards_corner_does_not_lock_the_tracker() {
        // (0.9, 0.9) GUARD turned by θ = π/4 has b = 1.27 GUARD, and no
        // ordinary sample moves b by that much in one update: each sample
        // is refused. Kept as it was, the state would stay there for good;
        // halved, it is back inside and the tracker follows the sine.
        let dt = 1e-3;
        let t = SineTracker::<f32>::new(dt, &spec(125.0, 10.0), CH).unwrap();
        let mut s = t.start();
        let g = 0.9 * f32::GUARD;
        s.pair = (g, g);
        let rotated = t.kernel.rotate(s.pair);
        assert!(rotated.1 > f32::GUARD);
        assert_eq!(t.step(&mut s, 0.0), Err(Refused::Overflow));
        assert_eq!(s.pair(), (0.5 * rotated.0, 0.5 * rotated.1));
        let mut refused = 1;
        for n in 1..5000 {
            let z = libm::cos(TAU * 0.125 * n as f64) as f32;
            refused += t.step(&mut s, z).is_err() as u32;
            assert!(guarded(&[s.pair()]));
        }
        assert_eq!(s.refused(), refused);
        assert!(refused < 10, "{refused}");
        assert!((s.amplitude() - 1.0).abs() < 1e-3, "{}", s.amplitude());
    }
}
