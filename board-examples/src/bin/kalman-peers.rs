//! Our modal tracker against Kalman filter crates from crates.io, side by
//! side in one run, on the same problem and the same data: cost of an
//! update (predict + one scalar measurement) and estimation error.
//!
//! **Problem** (the 4-state modal problem of `bushing::tracker`, see
//! `docs/modal-tracker.md`): one mode, one accelerometer, state
//! `x = (θ, λ, a, b)` with `θ = ω dt`, `λ = σ dt` and `(a, b)` the
//! displacement's analytic-signal pair divided by a scale that makes it of
//! order one. Prediction: θ and λ random walks, `a + i b ← (a + i b)
//! e^{λ + iθ}`. Measurement: the sample times `dt² / scale` is
//! `Re((λ + iθ)² (a + i b))`. Every filter starts from the tracker's
//! `start()` (its `x()` and `covariance()`), and uses the process noise Q
//! and measurement noise R the tracker derives from its `Tuning` (default
//! tuning: Q = 0) and sensor noise, recomputed here by the formulas of
//! `ModalTracker::new`.
//!
//! **Filters**: ours (`ModalTracker<f32, 4>`, EKF and UKF; Joseph-form
//! update, rotation from a cached anchor by a short series), with the
//! default tuning and, as `ours-*-nofade`, with `fade_snr = 0`: this mode
//! sinks below 3 noise deviations after about 2.8 s, where the default
//! tuning *fades* it (ω and σ frozen, amplitudes kept loose), which the
//! peers have no counterpart for; without the fade ours runs the same
//! plain EKF/UKF as they do. And minikalman, kfilter and adskalman, each
//! as an extended Kalman filter built by hand on top of the crate: the
//! harness computes the nonlinear prediction of (a, b) and the Jacobian F
//! with the f32 functions our tracker uses (`bushing::tracker::fast::
//! exp_small` and `bushing::tracker::trig::sin_cos`, polynomials where
//! libm's `expf`, `cosf` and `sinf` would run in software double
//! precision on the Cortex-M4F), gives F and Q to the crate's covariance
//! prediction `F P Fᵀ + Q`, then the measurement Jacobian H (1 x 4) and
//! the nonlinear predicted measurement to the crate's update. The cost of
//! those model functions alone (one prediction and one measurement a
//! sample) is measured too and printed with each peer as `model=`, so
//! that the report can show what the filter itself costs. Covariance updates: minikalman `P - K (H P)`
//! (standard form, not symmetrised), kfilter `(I - K H) P` then its
//! symmetric part, adskalman the Joseph form
//! (`CovarianceUpdateMethod::JosephForm`, as ours).
//!
//! **Data** (generated here, the same on host and target): a decaying mode
//! f0 = 20 Hz, ξ = 1 %, sampled at dt = 1 ms, acceleration
//! `e^{σt} cos(ωt)` (amplitude 1) plus Gaussian noise of standard deviation
//! 0.01 (40 dB) from xorshift64* and Box-Muller, 4000 samples. All filters
//! start slightly wrong, at f0 = 20.2 Hz and ξ = 1.5 %, with the true
//! complex amplitude of the start, so the errors measure convergence.
//!
//! **Measured**: every filter's update runs through an `#[inline(never)]`
//! function (`ours_update`, `minikalman_update`, ...) over the 4000
//! samples, net of the same loop over an empty stand-in of the same
//! signature. On the host: nanoseconds per update (`std::time::Instant`),
//! the best of 5 runs. On Cortex-M4F under QEMU (`-icount shift=0`):
//! guest instructions per update through the kernels' harness
//! (`bushing_boards::probe::measure`), from SysTick (one tick per 40
//! instructions), with the probe windows of the filter and its stand-in
//! (`windows=`, `model_windows=`, and `calls=`) from which the report
//! takes exact counts and estimated cycles when the run had the
//! `bushing-qemu-mix` plugin. Errors, from a second pass over the data: final
//! frequency error in %, final damping error in points of ξ (%), and
//! `amp_rms`, the RMS of the estimated (from the state after each update)
//! minus the clean acceleration over the second half, relative to the
//! clean RMS; `nan` when a filter diverged. One line per filter:
//!
//! ```text
//! kalman name=ours-ekf crate=bushing filter=ekf cost=... unit=ns freq_err_pct=... damp_err_pts=... amp_rms=...
//! kalman name=minikalman crate=minikalman@0.8.1 filter=ekf cost=... unit=ns model=... freq_err_pct=... ...
//! kalman name=minikalman ... unit=instructions model=... amp_rms=... calls=4000 windows=12,13 model_windows=0,1
//! ```
//!
//! ```text
//! cargo run -q --release -p bushing-boards --features peers --bin kalman-peers
//! cargo run -q --release -p bushing-boards --features peers --target thumbv7em-none-eabihf --bin kalman-peers
//! ```
#![cfg_attr(target_os = "none", no_std, no_main)]

use core::f64::consts::TAU;
use core::fmt;
use core::hint::black_box;

use bushing::ParamError;
use bushing::tracker::fast::exp_small;
use bushing::tracker::trig::sin_cos;
use bushing::tracker::{
    Filter, Measured, ModalState, ModalTracker, ModeInit, SensorSpec, Tuning, UtParams,
};
use bushing_kernels::Noise;
#[cfg(target_os = "none")]
use cortex_m_semihosting::hprintln as say;
#[cfg(not(target_os = "none"))]
use std::println as say;

/// Sampling period, s.
const DT: f64 = 1e-3;
/// The true mode.
const F0: f64 = 20.0;
const XI: f64 = 0.01;
/// The filters' start.
const F0_START: f64 = 20.2;
const XI_START: f64 = 0.015;
/// Accelerometer noise standard deviation (the signal's amplitude is 1).
const NOISE: f64 = 0.01;
const SAMPLES: usize = 4000;

/// State vector and covariance of the 4-state problem, row-major.
type Vector = [f32; 4];
type Matrix = [[f32; 4]; 4];

// ---------------------------------------------------------------------------
// Data

/// The record: clean acceleration and what the accelerometer reads.
struct Record {
    clean: [f32; SAMPLES],
    noisy: [f32; SAMPLES],
}

/// `e^{σt} cos(ωt)` at `t = (k + 1) dt` (the filters' start is `t = 0`:
/// they predict, then take the sample), plus noise.
fn record() -> Record {
    let w0 = TAU * F0;
    let (sigma, omega) = (-XI * w0, w0 * libm::sqrt(1.0 - XI * XI));
    let mut rng = Noise::new(0x9E37_79B9_7F4A_7C15);
    let mut r = Record {
        clean: [0.0; SAMPLES],
        noisy: [0.0; SAMPLES],
    };
    for (k, (c, y)) in r.clean.iter_mut().zip(r.noisy.iter_mut()).enumerate() {
        let t = (k + 1) as f64 * DT;
        let a = libm::exp(sigma * t) * libm::cos(omega * t);
        *c = a as f32;
        *y = (a + NOISE * rng.gauss()) as f32;
    }
    r
}

// ---------------------------------------------------------------------------
// The problem, as the tracker sets it up

/// Everything every filter starts from.
struct Problem {
    /// Ours with the default tuning.
    ekf: ModalTracker<f32, 4>,
    ukf: ModalTracker<f32, 4>,
    /// Ours with `fade_snr = 0`: a mode never fades, as in a plain EKF.
    ekf_nofade: ModalTracker<f32, 4>,
    ukf_nofade: ModalTracker<f32, 4>,
    x0: Vector,
    p0: Matrix,
    /// Diagonal of Q, per step (θ, λ, a, b).
    q: Vector,
    /// Measurement variance, scaled units.
    r: f32,
    /// From a sample to the scaled units, `dt² / scale`.
    gain: f32,
}

impl Problem {
    fn new() -> Result<Self, ParamError> {
        let sensors = [SensorSpec {
            measured: Measured::Acceleration,
            noise: NOISE,
        }];
        let mode = [ModeInit {
            frequency: F0_START,
            damping: XI_START,
        }];
        // The true complex amplitude of the acceleration at t = 0.
        let amplitude = (1.0, 0.0);
        let tuning = Tuning::default();
        // The fade (a mode below `fade_snr` times the noise keeps its
        // amplitudes loose and its ω and σ frozen) has no counterpart in
        // the peers; this record decays below 3 noise deviations after
        // about 2.8 s, so ours runs with and without it.
        let nofade = Tuning {
            fade_snr: 0.0,
            ..tuning
        };
        let make = |tuning: &Tuning, filter| {
            ModalTracker::new(DT, &sensors, &mode, &[amplitude], tuning, filter)
        };
        let ukf = Filter::Ukf(UtParams::default());
        let ekf_nofade = make(&nofade, Filter::Ekf)?;
        let ukf_nofade = make(&nofade, ukf)?;
        let ukf = make(&tuning, ukf)?;
        let ekf = make(&tuning, Filter::Ekf)?;
        let start = ekf.start();

        // As `ModalTracker::new`: the displacement amplitude
        // `w dt² / (λ + iθ)²` sets the scale, the scale the gain and R.
        let w0dt = TAU * F0_START * DT;
        let (theta, lambda) = (
            w0dt * libm::sqrt(1.0 - XI_START * XI_START),
            -XI_START * w0dt,
        );
        let dt2 = DT * DT;
        let (mut dr, mut di) = (amplitude.0 * dt2, amplitude.1 * dt2);
        for _ in 0..2 {
            let den = lambda * lambda + theta * theta;
            (dr, di) = (
                (dr * lambda + di * theta) / den,
                (di * lambda - dr * theta) / den,
            );
        }
        let scale = libm::hypot(dr, di);
        let gain = dt2 / scale;
        // Q from the tuning's random walks (all zero by default).
        let q_theta = sq(TAU * tuning.frequency_walk * DT) * DT;
        let q_lambda = sq(tuning.damping_walk * w0dt) * DT;
        let q_amp = sq(tuning.amplitude_walk) * DT;
        Ok(Self {
            x0: *start.x(),
            p0: *start.covariance(),
            q: [q_theta as f32, q_lambda as f32, q_amp as f32, q_amp as f32],
            r: sq(NOISE * gain) as f32,
            gain: gain as f32,
            ekf,
            ukf,
            ekf_nofade,
            ukf_nofade,
        })
    }
}

fn sq(x: f64) -> f64 {
    x * x
}

/// The nonlinear prediction `x' = f(x)` and its Jacobian F, with the f32
/// exponential and sine-cosine of our tracker (θ in [0, π], |λ| small).
fn predict(x: &Vector) -> (Vector, Matrix) {
    let [theta, lambda, a, b] = *x;
    let e = exp_small(lambda);
    let (sin, cos) = sin_cos(theta);
    let (ec, es) = (e * cos, e * sin);
    let (a1, b1) = (ec * a - es * b, es * a + ec * b);
    let f = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [-b1, a1, ec, -es],
        [a1, b1, es, ec],
    ];
    ([theta, lambda, a1, b1], f)
}

/// The predicted (scaled) accelerometer sample `Re((λ + iθ)² (a + i b))`
/// and its gradient H.
fn observe(x: &Vector) -> (f32, Vector) {
    let [t, l, a, b] = *x;
    let (ca, cb) = (l * l - t * t, -2.0 * l * t);
    (
        ca * a + cb * b,
        [-2.0 * (t * a + l * b), 2.0 * (l * a - t * b), ca, cb],
    )
}

/// Every filter tells its current state.
trait Estimate {
    fn x(&self) -> Vector;
}

// ---------------------------------------------------------------------------
// Ours

/// Our tracker and its running state.
struct Ours<'a> {
    tracker: &'a ModalTracker<f32, 4>,
    state: ModalState<f32, 4>,
}

impl<'a> Ours<'a> {
    fn new(tracker: &'a ModalTracker<f32, 4>) -> Self {
        Self {
            tracker,
            state: tracker.start(),
        }
    }
}

impl Estimate for Ours<'_> {
    fn x(&self) -> Vector {
        *self.state.x()
    }
}

/// One step of our tracker (it scales the sample itself).
#[inline(never)]
fn ours_update(f: &mut Ours<'_>, y: f32) {
    black_box(f.tracker.step(&mut f.state, &[y]));
}

// ---------------------------------------------------------------------------
// minikalman: owned array buffers (no alloc, no unsafe)

mod mk {
    use minikalman::buffers::types::{
        DirectProcessNoiseCovarianceMatrixMutBuffer, EstimateCovarianceMatrixBuffer,
        InnovationCovarianceMatrixBuffer, InnovationVectorBuffer, KalmanGainMatrixBuffer,
        MeasurementNoiseCovarianceMatrixBuffer, MeasurementVectorBuffer,
        ObservationMatrixMutBuffer, PredictedStateEstimateVectorBuffer,
        StateTransitionMatrixMutBuffer, StateVectorBuffer, TemporaryHPMatrixBuffer,
        TemporaryKHPMatrixBuffer, TemporaryPHTMatrixBuffer,
        TemporaryResidualCovarianceInvertedMatrixBuffer, TemporaryStateMatrixBuffer,
    };
    use minikalman::extended::{
        ExtendedKalman, ExtendedKalmanBuilder, ExtendedObservation, ExtendedObservationBuilder,
    };
    use minikalman::matrix::MatrixDataArray;
    use minikalman::prelude::{
        MatrixMut, RowMajorSequentialData, RowMajorSequentialDataMut, RowVectorMut,
    };

    use super::{Estimate, Problem, Vector, observe, predict};

    type Array<const R: usize, const C: usize, const T: usize> = MatrixDataArray<R, C, T, f32>;

    type Kalman = ExtendedKalman<
        4,
        f32,
        StateTransitionMatrixMutBuffer<4, f32, Array<4, 4, 16>>,
        StateVectorBuffer<4, f32, Array<4, 1, 4>>,
        EstimateCovarianceMatrixBuffer<4, f32, Array<4, 4, 16>>,
        DirectProcessNoiseCovarianceMatrixMutBuffer<4, f32, Array<4, 4, 16>>,
        PredictedStateEstimateVectorBuffer<4, f32, Array<4, 1, 4>>,
        TemporaryStateMatrixBuffer<4, f32, Array<4, 4, 16>>,
    >;

    type Observation = ExtendedObservation<
        4,
        1,
        f32,
        ObservationMatrixMutBuffer<1, 4, f32, Array<1, 4, 4>>,
        MeasurementVectorBuffer<1, f32, Array<1, 1, 1>>,
        MeasurementNoiseCovarianceMatrixBuffer<1, f32, Array<1, 1, 1>>,
        InnovationVectorBuffer<1, f32, Array<1, 1, 1>>,
        InnovationCovarianceMatrixBuffer<1, f32, Array<1, 1, 1>>,
        KalmanGainMatrixBuffer<4, 1, f32, Array<4, 1, 4>>,
        TemporaryResidualCovarianceInvertedMatrixBuffer<1, f32, Array<1, 1, 1>>,
        TemporaryHPMatrixBuffer<1, 4, f32, Array<1, 4, 4>>,
        TemporaryPHTMatrixBuffer<4, 1, f32, Array<4, 1, 4>>,
        TemporaryKHPMatrixBuffer<4, f32, Array<4, 4, 16>>,
    >;

    /// minikalman's EKF and its accelerometer.
    pub struct Minikalman {
        filter: Kalman,
        sensor: Observation,
        gain: f32,
    }

    impl Minikalman {
        pub fn new(p: &Problem) -> Self {
            let flat =
                |m: &[[f32; 4]; 4]| -> [f32; 16] { core::array::from_fn(|i| m[i / 4][i % 4]) };
            let mut q = [0.0; 16];
            for (i, &v) in p.q.iter().enumerate() {
                q[5 * i] = v;
            }
            let filter = ExtendedKalmanBuilder::new::<4, f32>(
                StateTransitionMatrixMutBuffer::from([0.0; 16]),
                StateVectorBuffer::from(p.x0),
                EstimateCovarianceMatrixBuffer::from(flat(&p.p0)),
                DirectProcessNoiseCovarianceMatrixMutBuffer::from(q),
                PredictedStateEstimateVectorBuffer::from([0.0; 4]),
                TemporaryStateMatrixBuffer::from([0.0; 16]),
            );
            let sensor = ExtendedObservationBuilder::new::<4, 1, f32>(
                ObservationMatrixMutBuffer::from([0.0; 4]),
                MeasurementVectorBuffer::from([0.0; 1]),
                MeasurementNoiseCovarianceMatrixBuffer::from([p.r]),
                InnovationVectorBuffer::from([0.0; 1]),
                InnovationCovarianceMatrixBuffer::from([0.0; 1]),
                KalmanGainMatrixBuffer::from([0.0; 4]),
                TemporaryResidualCovarianceInvertedMatrixBuffer::from([0.0; 1]),
                TemporaryHPMatrixBuffer::from([0.0; 4]),
                TemporaryPHTMatrixBuffer::from([0.0; 4]),
                TemporaryKHPMatrixBuffer::from([0.0; 16]),
            );
            Self {
                filter,
                sensor,
                gain: p.gain,
            }
        }
    }

    impl Estimate for Minikalman {
        fn x(&self) -> Vector {
            let s = self.filter.state_vector().as_slice();
            core::array::from_fn(|i| s.get(i).copied().unwrap_or(f32::NAN))
        }
    }

    /// One EKF step with minikalman: F into its Jacobian buffer, the
    /// predicted state through `predict_nonlinear` (P = F P Fᵀ + Q), then H
    /// and the sample, and `correct_nonlinear` with h(x).
    #[inline(never)]
    pub fn minikalman_update(f: &mut Minikalman, y: f32) {
        let (x1, jac) = predict(&f.x());
        f.filter.state_transition_jacobian_mut().apply(|m| {
            for (i, row) in jac.iter().enumerate() {
                for (j, &v) in row.iter().enumerate() {
                    m.set_at(i, j, v);
                }
            }
        });
        f.filter.predict_nonlinear(|_, next| {
            for (i, &v) in x1.iter().enumerate() {
                next.set_row(i, v);
            }
        });
        let (zhat, h) = observe(&x1);
        f.sensor.observation_jacobian_matrix_mut().apply(|m| {
            for (j, &v) in h.iter().enumerate() {
                m.set_at(0, j, v);
            }
        });
        let z = y * f.gain;
        f.sensor.measurement_vector_mut().apply(|v| v.set_row(0, z));
        f.filter
            .correct_nonlinear(&mut f.sensor, |_, predicted| predicted.set_row(0, zhat));
    }
}

// ---------------------------------------------------------------------------
// kfilter: its `Kalman` over a system and a measurement written here

mod kf {
    use kfilter::measurement::{LinearisableMeasurement, Measurement};
    use kfilter::system::{LinearisableSystem, NoInputSystem, System};
    use kfilter::{Kalman, KalmanFilter, KalmanPredict, KalmanUpdate};
    use nalgebra_034::{SMatrix, SVector};

    use super::{Estimate, Problem, Vector, observe, predict};

    /// The modal process for kfilter: `step` sets x = f(x) and F.
    #[derive(Clone)]
    pub struct Modal {
        x: SVector<f32, 4>,
        f: SMatrix<f32, 4, 4>,
        ft: SMatrix<f32, 4, 4>,
        q: SMatrix<f32, 4, 4>,
    }

    impl System<f32, 4, 0> for Modal {
        fn covariance(&self) -> &SMatrix<f32, 4, 4> {
            &self.q
        }
        fn state(&self) -> &SVector<f32, 4> {
            &self.x
        }
        fn state_mut(&mut self) -> &mut SVector<f32, 4> {
            &mut self.x
        }
    }

    impl LinearisableSystem<f32, 4, 0> for Modal {
        fn transition(&self) -> &SMatrix<f32, 4, 4> {
            &self.f
        }
        fn transition_transpose(&self) -> &SMatrix<f32, 4, 4> {
            &self.ft
        }
    }

    impl NoInputSystem<f32, 4> for Modal {
        fn step(&mut self) -> &SVector<f32, 4> {
            let (x1, f) = predict(&self.x.into());
            self.x = x1.into();
            self.f = SMatrix::from_fn(|i, j| f[i][j]);
            self.ft = self.f.transpose();
            &self.x
        }
        fn predict(&self, x: &SVector<f32, 4>) -> SVector<f32, 4> {
            predict(&(*x).into()).0.into()
        }
    }

    /// The accelerometer for kfilter: H and h(x) set by the harness at
    /// the predicted state (`predict` returns that h(x)).
    #[derive(Clone)]
    pub struct Accelerometer {
        z: SVector<f32, 1>,
        zhat: f32,
        h: SMatrix<f32, 1, 4>,
        ht: SMatrix<f32, 4, 1>,
        r: SMatrix<f32, 1, 1>,
    }

    impl Measurement<f32, 4, 1> for Accelerometer {
        fn covariance(&self) -> &SMatrix<f32, 1, 1> {
            &self.r
        }
        fn measurement(&self) -> &SVector<f32, 1> {
            &self.z
        }
        fn set_measurement(&mut self, z: SVector<f32, 1>) {
            self.z = z;
        }
        fn predict(&self, _: &SVector<f32, 4>) -> SVector<f32, 1> {
            SVector::<f32, 1>::new(self.zhat)
        }
    }

    impl LinearisableMeasurement<f32, 4, 1> for Accelerometer {
        fn observation(&self) -> &SMatrix<f32, 1, 4> {
            &self.h
        }
        fn observation_transpose(&self) -> &SMatrix<f32, 4, 1> {
            &self.ht
        }
    }

    /// kfilter's Kalman filter and its accelerometer.
    #[derive(Clone)]
    pub struct Kfilter {
        kalman: Kalman<f32, 4, 0, Modal>,
        sensor: Accelerometer,
        gain: f32,
    }

    impl Kfilter {
        pub fn new(p: &Problem) -> Self {
            let system = Modal {
                x: p.x0.into(),
                f: SMatrix::identity(),
                ft: SMatrix::identity(),
                q: SMatrix::from_diagonal(&p.q.into()),
            };
            let p0 = SMatrix::from_fn(|i, j| p.p0[i][j]);
            Self {
                kalman: Kalman::new_custom(system, p0),
                sensor: Accelerometer {
                    z: SVector::zeros(),
                    zhat: 0.0,
                    h: SMatrix::zeros(),
                    ht: SMatrix::zeros(),
                    r: SMatrix::<f32, 1, 1>::new(p.r),
                },
                gain: p.gain,
            }
        }
    }

    impl Estimate for Kfilter {
        fn x(&self) -> Vector {
            (*self.kalman.state()).into()
        }
    }

    /// One EKF step with kfilter: `predict` (x = f(x), P = F P Fᵀ + Q),
    /// then H and h(x) at the prediction and `update`.
    #[inline(never)]
    pub fn kfilter_update(f: &mut Kfilter, y: f32) {
        // Neither call fails here but for a singular 1 x 1 innovation
        // variance, which leaves the state as it was.
        let _ = f.kalman.predict();
        let (zhat, h) = observe(&(*f.kalman.state()).into());
        f.sensor.zhat = zhat;
        f.sensor.h = SMatrix::from_row_slice(&h);
        f.sensor.ht = f.sensor.h.transpose();
        f.sensor.z = SVector::<f32, 1>::new(y * f.gain);
        let _ = f.kalman.update(&f.sensor);
    }
}

// ---------------------------------------------------------------------------
// adskalman: its transition and observation models, written here

mod ads {
    use adskalman::{
        CovarianceUpdateMethod, ObservationModel, StateAndCovariance,
        TransitionModelLinearNoControl,
    };
    use nalgebra::{Matrix1, Matrix1x4, Matrix4, Matrix4x1, U1, U4, Vector1, Vector4};

    use super::{Estimate, Problem, Vector, observe, predict};

    /// F (the Jacobian at the current estimate) and Q.
    #[derive(Clone)]
    pub struct Modal {
        f: Matrix4<f32>,
        ft: Matrix4<f32>,
        q: Matrix4<f32>,
    }

    impl TransitionModelLinearNoControl<f32, U4> for Modal {
        fn F(&self) -> &Matrix4<f32> {
            &self.f
        }
        fn FT(&self) -> &Matrix4<f32> {
            &self.ft
        }
        fn Q(&self) -> &Matrix4<f32> {
            &self.q
        }
    }

    /// H and h(x) at the predicted state, and R.
    #[derive(Clone)]
    pub struct Accelerometer {
        h: Matrix1x4<f32>,
        ht: Matrix4x1<f32>,
        r: Matrix1<f32>,
        zhat: f32,
    }

    impl ObservationModel<f32, U4, U1> for Accelerometer {
        fn H(&self) -> &Matrix1x4<f32> {
            &self.h
        }
        fn HT(&self) -> &Matrix4x1<f32> {
            &self.ht
        }
        fn R(&self) -> &Matrix1<f32> {
            &self.r
        }
        fn predict_observation(&self, _: &Vector4<f32>) -> Vector1<f32> {
            Vector1::new(self.zhat)
        }
    }

    /// adskalman's models and the running estimate.
    #[derive(Clone)]
    pub struct Adskalman {
        process: Modal,
        sensor: Accelerometer,
        estimate: StateAndCovariance<f32, U4>,
        gain: f32,
    }

    impl Adskalman {
        pub fn new(p: &Problem) -> Self {
            Self {
                process: Modal {
                    f: Matrix4::identity(),
                    ft: Matrix4::identity(),
                    q: Matrix4::from_diagonal(&p.q.into()),
                },
                sensor: Accelerometer {
                    h: Matrix1x4::zeros(),
                    ht: Matrix4x1::zeros(),
                    r: Matrix1::new(p.r),
                    zhat: 0.0,
                },
                estimate: StateAndCovariance::new(p.x0.into(), Matrix4::from_fn(|i, j| p.p0[i][j])),
                gain: p.gain,
            }
        }
    }

    impl Estimate for Adskalman {
        fn x(&self) -> Vector {
            (*self.estimate.state()).into()
        }
    }

    /// One EKF step with adskalman: its `predict` with F and Q
    /// (`P = F P Fᵀ + Q`; its linear state F x is replaced by f(x)), then
    /// `update` in the Joseph form with H and h(x) at the prediction.
    #[inline(never)]
    pub fn adskalman_update(f: &mut Adskalman, y: f32) {
        let (x1, jac) = predict(&(*f.estimate.state()).into());
        f.process.f = Matrix4::from_fn(|i, j| jac[i][j]);
        f.process.ft = f.process.f.transpose();
        let mut prior = f.process.predict(&f.estimate);
        *prior.state_mut() = x1.into();
        let (zhat, h) = observe(&x1);
        f.sensor.zhat = zhat;
        f.sensor.h = Matrix1x4::from_row_slice(&h);
        f.sensor.ht = f.sensor.h.transpose();
        let z = Vector1::new(y * f.gain);
        f.estimate = match f
            .sensor
            .update(&prior, &z, CovarianceUpdateMethod::JosephForm)
        {
            Ok(posterior) => posterior,
            // A non-positive innovation variance: the sample is skipped.
            Err(_) => prior,
        };
    }
}

// ---------------------------------------------------------------------------
// Measurement

/// The stand-in for every `*_update`: same signature, does nothing.
#[inline(never)]
fn empty_update<F>(f: &mut F, y: f32) {
    black_box((f, y));
}

/// One pass of `update` over the samples.
#[cfg(not(target_os = "none"))]
fn pass<F>(f: &mut F, update: fn(&mut F, f32), ys: &[f32]) {
    for &y in ys {
        update(f, black_box(y));
    }
    black_box(f);
}

/// Host: nanoseconds for a pass from a fresh filter, the best of 5 (no
/// window).
#[cfg(not(target_os = "none"))]
fn elapsed<F>(make: &dyn Fn() -> F, update: fn(&mut F, f32), ys: &[f32]) -> (f64, Option<u32>) {
    let best = (0..5)
        .map(|_| {
            let mut f = make();
            let t = std::time::Instant::now();
            pass(&mut f, update, ys);
            t.elapsed().as_nanos() as f64
        })
        .fold(f64::INFINITY, f64::min);
    (best, None)
}

/// A filter's updates as the measuring harness calls them: the update is
/// a field, so a filter and its stand-in share one compiled call.
#[cfg(target_os = "none")]
struct Updates<'a, F> {
    f: F,
    update: fn(&mut F, f32),
    ys: &'a [f32],
}

#[cfg(target_os = "none")]
impl<F> bushing_boards::probe::Kernel for Updates<'_, F> {
    #[inline(never)]
    fn call(&mut self, i: usize) {
        if let Some(&y) = self.ys.get(i) {
            (self.update)(&mut self.f, black_box(y));
        }
    }

    fn calls(&self) -> usize {
        self.ys.len()
    }
}

/// Target: guest instructions for a pass from a fresh filter through the
/// kernels' harness (`bushing_boards::probe::measure`), from SysTick
/// (one tick per 40 instructions under `-icount shift=0`), and the
/// pass's probe window, for the report's cycle estimate.
#[cfg(target_os = "none")]
fn elapsed<F>(make: &dyn Fn() -> F, update: fn(&mut F, f32), ys: &[f32]) -> (f64, Option<u32>) {
    use bushing_boards::probe::{INSTRUCTIONS_PER_TICK, measure};
    let span = measure(&mut Updates {
        f: make(),
        update,
        ys,
    });
    (f64::from(span.ticks * INSTRUCTIONS_PER_TICK), span.window)
}

/// A filter's cost per update, net of the same pass over an empty
/// stand-in, and on the target the two probe windows (filter, stand-in).
struct Cost {
    per_update: f64,
    windows: Option<[u32; 2]>,
}

impl Cost {
    fn of<F>(make: &dyn Fn() -> F, update: fn(&mut F, f32), ys: &[f32]) -> Self {
        let busy = elapsed(make, update, ys);
        let idle = elapsed(make, empty_update::<F>, ys);
        Self {
            per_update: (busy.0 - idle.0) / ys.len().max(1) as f64,
            windows: busy.1.zip(idle.1).map(|(b, i)| [b, i]),
        }
    }
}

/// ` NAME=B,I` for a cost measured with windows, nothing otherwise.
struct Windows(&'static str, Option<[u32; 2]>);

impl fmt::Display for Windows {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.1 {
            Some([b, i]) => write!(f, " {}={b},{i}", self.0),
            None => Ok(()),
        }
    }
}

const UNIT: &str = if cfg!(target_os = "none") {
    "instructions"
} else {
    "ns"
};

/// Errors of a filter run over the record.
struct Errors {
    freq_pct: f64,
    damp_pts: f64,
    amp_rms: f64,
}

/// Runs a fresh filter over the record and scores it against the truth.
fn errors<F: Estimate>(mut f: F, update: fn(&mut F, f32), rec: &Record, gain: f32) -> Errors {
    let (mut err2, mut ref2) = (0.0f64, 0.0f64);
    for (k, (&y, &clean)) in rec.noisy.iter().zip(&rec.clean).enumerate() {
        update(&mut f, y);
        if k >= SAMPLES / 2 {
            let acc = f64::from(observe(&f.x()).0) / f64::from(gain);
            let c = f64::from(clean);
            err2 += (acc - c) * (acc - c);
            ref2 += c * c;
        }
    }
    let [theta, lambda, ..] = f.x().map(f64::from);
    let w0dt = libm::sqrt(theta * theta + lambda * lambda);
    let e = Errors {
        freq_pct: 100.0 * (w0dt / (TAU * DT) / F0 - 1.0),
        damp_pts: 100.0 * (-lambda / w0dt - XI),
        amp_rms: libm::sqrt(err2 / ref2),
    };
    let finite = e.freq_pct.is_finite() && e.damp_pts.is_finite() && e.amp_rms.is_finite();
    if finite {
        e
    } else {
        Errors {
            freq_pct: f64::NAN,
            damp_pts: f64::NAN,
            amp_rms: f64::NAN,
        }
    }
}

/// A number with a fixed count of decimals, `nan` if not finite.
struct Num(f64, usize);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_finite() {
            write!(f, "{:.*}", self.1, self.0)
        } else {
            f.write_str("nan")
        }
    }
}

/// The peers' model functions alone: the state advanced by the
/// prediction, the measurement taken at it, as in one EKF step.
struct ModelOnly {
    x: Vector,
}

/// One sample's model functions: `f(x)` with F, then `h(x)` with H.
#[inline(never)]
fn model_update(m: &mut ModelOnly, y: f32) {
    let (x1, jac) = predict(&m.x);
    let (zhat, h) = observe(&x1);
    m.x = x1;
    black_box((jac, zhat + y, h));
}

/// Cost of a peer's model functions per update, net of the loop.
fn model_cost(p: &Problem, rec: &Record) -> Cost {
    let make = || ModelOnly { x: p.x0 };
    Cost::of(&make, model_update, &rec.noisy)
}

/// Measures one filter and prints its line; `model` is the cost of the
/// harness's model functions inside its update (none for ours, whose
/// model is its own).
#[allow(clippy::too_many_arguments)]
fn compare<F: Estimate>(
    name: &str,
    krate: &str,
    filter: &str,
    make: &dyn Fn() -> F,
    update: fn(&mut F, f32),
    rec: &Record,
    gain: f32,
    model: Option<&Cost>,
) {
    let cost = Cost::of(make, update, &rec.noisy);
    let e = errors(make(), update, rec, gain);
    let model_windows = model.and_then(|m| m.windows);
    let model = model.map(|m| Num(m.per_update, 1));
    say!(
        "kalman name={} crate={} filter={} cost={} unit={}{}{} freq_err_pct={} damp_err_pts={} amp_rms={}{}{}{}",
        name,
        krate,
        filter,
        Num(cost.per_update, 1),
        UNIT,
        if model.is_some() { " model=" } else { "" },
        Maybe(model),
        Num(e.freq_pct, 6),
        Num(e.damp_pts, 6),
        Num(e.amp_rms, 6),
        Calls(cost.windows.map(|_| rec.noisy.len())),
        Windows("windows", cost.windows),
        Windows("model_windows", model_windows)
    );
}

/// ` calls=N` where the cost has windows.
struct Calls(Option<usize>);

impl fmt::Display for Calls {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(n) => write!(f, " calls={n}"),
            None => Ok(()),
        }
    }
}

/// An optional number: nothing when absent.
struct Maybe(Option<Num>);

impl fmt::Display for Maybe {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Some(n) => n.fmt(f),
            None => Ok(()),
        }
    }
}

/// The whole comparison.
fn run() -> Result<(), ParamError> {
    let p = Problem::new()?;
    let rec = record();
    say!(
        "# one mode f0 = {} Hz, xi = {}, dt = {} s, {} samples, accelerometer noise {}; start f0 = {} Hz, xi = {}",
        F0,
        XI,
        DT,
        SAMPLES,
        NOISE,
        F0_START,
        XI_START
    );
    say!(
        "# peers: EKF by hand, f(x) and F with our tracker's f32 exp_small and sin_cos (model= their cost per update); updates: minikalman P - K H P, kfilter (I - K H) P symmetrised, adskalman Joseph; ours Joseph"
    );
    say!(
        "# ours: default Tuning (a mode below fade_snr = 3 noise deviations fades: amplitudes kept loose, here after ~2.8 s); -nofade: fade_snr = 0, the peers' plain EKF"
    );
    let g = p.gain;
    let model = model_cost(&p, &rec);
    compare(
        "ours-ekf",
        "bushing",
        "ekf",
        &|| Ours::new(&p.ekf),
        ours_update,
        &rec,
        g,
        None,
    );
    compare(
        "ours-ukf",
        "bushing",
        "ukf",
        &|| Ours::new(&p.ukf),
        ours_update,
        &rec,
        g,
        None,
    );
    compare(
        "ours-ekf-nofade",
        "bushing",
        "ekf",
        &|| Ours::new(&p.ekf_nofade),
        ours_update,
        &rec,
        g,
        None,
    );
    compare(
        "ours-ukf-nofade",
        "bushing",
        "ukf",
        &|| Ours::new(&p.ukf_nofade),
        ours_update,
        &rec,
        g,
        None,
    );
    compare(
        "minikalman",
        "minikalman@0.8.1",
        "ekf",
        &|| mk::Minikalman::new(&p),
        mk::minikalman_update,
        &rec,
        g,
        Some(&model),
    );
    compare(
        "kfilter",
        "kfilter@0.5.1",
        "ekf",
        &|| kf::Kfilter::new(&p),
        kf::kfilter_update,
        &rec,
        g,
        Some(&model),
    );
    compare(
        "adskalman",
        "adskalman@0.18.0",
        "ekf",
        &|| ads::Adskalman::new(&p),
        ads::adskalman_update,
        &rec,
        g,
        Some(&model),
    );
    Ok(())
}

#[cfg(not(target_os = "none"))]
fn main() {
    if let Err(e) = run() {
        eprintln!("parameters refused: {e:?}");
        std::process::exit(1);
    }
}

#[cfg(target_os = "none")]
mod firmware {
    use bushing_boards::probe;
    use cortex_m_rt::entry;
    use panic_semihosting as _;

    #[entry]
    fn main() -> ! {
        probe::start();
        match super::run() {
            Ok(()) => probe::pass(),
            Err(_) => probe::fail("parameters refused"),
        }
    }
}
