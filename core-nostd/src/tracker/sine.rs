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
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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
///
/// ```
/// use bushing::ParamError;
/// use bushing::tracker::{Channel, SineSpec, SineTracker};
///
/// // A 10 Hz sine of 2 mm sampled at 1 kHz, tracked in a 2 Hz band.
/// let spec = SineSpec { frequency: 10.0, bandwidth: 2.0 };
/// let tracker = SineTracker::<f32>::new(1e-3, &spec, Channel { noise: 0.01, amplitude: 2.0 })?;
/// let mut state = tracker.start();
/// for n in 0..2000 {
///     let t = n as f64 * 1e-3;
///     let x = 2.0 * (core::f64::consts::TAU * 10.0 * t).sin();
///     tracker.step(&mut state, x as f32).map_err(|_| ParamError::TooFew {
///         param: bushing::Param::scalar("sample"), min: 0, got: 0 })?;
/// }
/// assert!((state.amplitude() - 2.0).abs() < 0.01);
/// // A non-finite sample is refused, the estimate carried on.
/// assert!(tracker.step(&mut state, f32::NAN).is_err());
/// // The band must stay below half the frequency.
/// let wide = SineSpec { frequency: 10.0, bandwidth: 6.0 };
/// assert!(SineTracker::<f32>::new(1e-3, &wide, Channel { noise: 0.01, amplitude: 2.0 }).is_err());
/// # Ok::<(), ParamError>(())
/// ```
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
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Modulus<T> {
    /// Storage modulus K', force over displacement units (N/mm).
    pub storage: T,
    /// Loss modulus K'' (positive when the force leads), N/mm.
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
///
/// ```
/// use bushing::ParamError;
/// use bushing::tracker::{Channel, ModulusSpec, ModulusTracker, SineSpec};
///
/// // A 5 Hz test, F = 100 x + 20 x' / ω: K' = 100 N/mm, K'' = 20 N/mm.
/// let spec = ModulusSpec {
///     sine: SineSpec { frequency: 5.0, bandwidth: 1.0 },
///     displacement: Channel { noise: 1e-3, amplitude: 1.0 },
///     force: Channel { noise: 0.1, amplitude: 100.0 },
///     min_snr: 10.0,
/// };
/// let tracker = ModulusTracker::<f32>::new(1e-3, &spec)?;
/// let mut state = tracker.start();
/// assert!(tracker.modulus(&state).is_none()); // nothing to divide by yet
/// let w = core::f64::consts::TAU * 5.0;
/// for n in 0..3000 {
///     let t = n as f64 * 1e-3;
///     let (x, f) = ((w * t).sin(), 100.0 * (w * t).sin() + 20.0 * (w * t).cos());
///     let _ = tracker.step(&mut state, x as f32, f as f32);
/// }
/// let k = tracker.modulus(&state);
/// assert!(k.is_some_and(|k| (k.storage - 100.0).abs() < 0.5 && (k.loss - 20.0).abs() < 0.5));
/// // min_snr must be positive.
/// assert!(ModulusTracker::<f32>::new(1e-3, &ModulusSpec { min_snr: 0.0, ..spec }).is_err());
/// # Ok::<(), ParamError>(())
/// ```
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
mod tests;
