//! The rig loop: what one control period of a test-rig controller does.
//!
//! Each period reads the bushing displacement through an SPI [`Adc`],
//! steps the bushing model (spline backbone, 4 Maxwell cells, 3 Jenkins
//! cells: [`RigBushing`]), writes the force command through an SPI [`Dac`]
//! and feeds the displacement to a one-mode modal tracker ([`Monitor`]).
//! The same code runs in `f32` on a Cortex-M4F and in the fixed-point
//! [`Q16`] on a Cortex-M3 (the [`Sample`] conversions are the only
//! per-type code). `scenes/rig-loop.toml` describes the same bushing,
//! excitation and ADC for `bushing-sim`, so a host run of that scene in
//! f32 gives, bit for bit, the force trace of the M4F firmware.
//!
//! [`sim`] holds the simulated converters that stand in for the hardware
//! under QEMU, behind the same `SpiDevice` trait.

pub mod drivers;
pub mod sim;

use bushing::excitation::{Spacing, Sweep};
use bushing::tracker::{
    Filter, Measured, ModalReport, ModalState, ModalTracker, ModeInit, ModeStatus, SensorSpec,
    Tuning,
};
use bushing::{
    Bushing, BushingState, Effect, Exponentials, Faults, IwanBank, IwanCellSpec, MaxwellBank,
    MaxwellForm, MaxwellSpec, MonotoneSpline, Output, ParamError, Plain, Q16, Real,
};
use embedded_hal::spi::SpiDevice;

pub use drivers::{Adc, AdcChannel, Dac, DacChannel};

/// Control rate, Hz.
pub const RATE_HZ: f64 = 5000.0;
/// ADC resolution, bits.
pub const ADC_BITS: u32 = 16;
/// ADC step: 2^-12 mm (±8 mm full scale). A power of two, so that a code
/// scales to millimetres exactly in `f32` and in [`Q16`].
pub const LSB_MM: f64 = 1.0 / 4096.0;
/// [`LSB_MM`] written out in decimal (exact), for logs that print no
/// floating-point numbers.
pub const LSB_MM_TEXT: &str = "0.000244140625";
/// DAC step: 1/8 N (±4096 N full scale, offset binary).
pub const DAC_LSB_N: f64 = 0.125;
/// Excitation: a log sweep of 2 mm from 5 Hz to 40 Hz over 2 s.
pub const SWEEP_HZ: (f64, f64) = (5.0, 40.0);
/// Duration of the sweep, s.
pub const SWEEP_S: f64 = 2.0;
/// Amplitude of the sweep, mm.
pub const AMPLITUDE_MM: f64 = 2.0;

/// The rig's sweep law.
pub fn sweep() -> Result<Sweep, ParamError> {
    Sweep::new(SWEEP_HZ.0, SWEEP_HZ.1, SWEEP_S, Spacing::Log)
}

/// The bushing of the rig: an 8-point spline backbone, 4 Maxwell cells
/// (exact ramp, plain states) and 3 Jenkins cells (clamp form).
pub type RigBushing<T> = Bushing<T, MonotoneSpline<T, 8>, RigEffects<T>>;
/// The effects of the [`RigBushing`].
pub type RigEffects<T> = (MaxwellBank<T, 4>, IwanBank<T, 3>);
/// Its state.
pub type RigState<T> = BushingState<T, <RigEffects<T> as Effect<T>>::State>;
/// The output of one model step.
pub type RigOutput<T> = Output<T, <RigEffects<T> as Effect<T>>::Report>;

/// Builds the [`RigBushing`] for a step of `dt` s: corners 0.05, 0.5, 5
/// and 50 Hz; slip forces 0.6, 2.4 and 6 N (slip distances 0.05, 0.2 and
/// 0.5 mm on 150 N/mm). The values are those of `scenes/rig-loop.toml`.
pub fn rig_bushing<T: Real>(dt: f64) -> Result<RigBushing<T>, ParamError> {
    let cells = [
        MaxwellSpec::hz(0.05, 0.1),
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(5.0, 0.15),
        MaxwellSpec::hz(50.0, 0.1),
    ];
    let jenkins = [
        IwanCellSpec::new(0.08, 0.6),
        IwanCellSpec::new(0.08, 2.4),
        IwanCellSpec::new(0.08, 6.0),
    ];
    Bushing::new(
        bushing_kernels::spline()?,
        (
            MaxwellBank::<T, 4, Plain<T>>::new(MaxwellForm::RateExactRamp, &cells, dt)?,
            IwanBank::new(&jenkins)?,
        ),
    )
}

/// The per-type conversions of the loop: ADC code to millimetres, force to
/// DAC code, and the bits a firmware logs.
pub trait Sample: Real {
    /// The displacement of an ADC code, `code * LSB_MM` (exact).
    fn from_code(code: i16) -> Self;
    /// The offset-binary DAC code of a force: rounded toward zero to
    /// [`DAC_LSB_N`] and saturated (NaN gives the mid code, 0 N).
    fn dac_code(self) -> u16;
    /// The raw bits: IEEE single for `f32` (and for `f64`, narrowed), the
    /// two's-complement Q16.16 word for [`Q16`].
    fn log_bits(self) -> u32;
}

/// Offset binary of a signed DAC count.
fn offset(count: i32) -> u16 {
    // After the clamp the sum is in [0, 65535].
    (count.clamp(-32768, 32767) + 32768) as u16
}

impl Sample for f32 {
    fn from_code(code: i16) -> Self {
        f32::from(code) * (LSB_MM as f32)
    }
    fn dac_code(self) -> u16 {
        // `as` saturates and maps NaN to 0.
        offset((self * (1.0 / DAC_LSB_N as f32)) as i32)
    }
    fn log_bits(self) -> u32 {
        self.to_bits()
    }
}

impl Sample for f64 {
    fn from_code(code: i16) -> Self {
        f64::from(code) * LSB_MM
    }
    fn dac_code(self) -> u16 {
        offset((self * (1.0 / DAC_LSB_N)) as i32)
    }
    fn log_bits(self) -> u32 {
        (self as f32).to_bits()
    }
}

impl Sample for Q16 {
    fn from_code(code: i16) -> Self {
        // LSB_MM = 2^-12 and Q16 has 16 fractional bits.
        Q16::from_bits(i32::from(code) << 4)
    }
    fn dac_code(self) -> u16 {
        // DAC_LSB_N = 2^-3 N = 2^13 raw units; `/` rounds toward zero.
        offset(self.to_bits() / 8192)
    }
    fn log_bits(self) -> u32 {
        self.to_bits() as u32
    }
}

/// What one control period did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Period<T> {
    /// The ADC code read.
    pub code: i16,
    /// The bushing force, N.
    pub force: T,
    /// The DAC code written.
    pub dac: u16,
    /// The model's sticky fault flags after the step.
    pub faults: Faults,
}

/// Why a control period did not complete.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeriodError<A, D> {
    /// The ADC transfer failed: the model was not stepped, the output kept.
    Adc(A),
    /// The DAC transfer failed after the model was stepped.
    Dac(D),
}

/// The rig controller: the bushing model between the converters.
#[derive(Debug, Clone)]
pub struct Rig<T: Sample> {
    bushing: RigBushing<T>,
}

impl<T: Sample> Rig<T> {
    /// The controller at [`RATE_HZ`].
    pub fn new() -> Result<Self, ParamError> {
        Ok(Self {
            bushing: rig_bushing(1.0 / RATE_HZ)?,
        })
    }

    /// The bushing model.
    pub fn bushing(&self) -> &RigBushing<T> {
        &self.bushing
    }

    /// Re-tunes the Maxwell cells to the shift factor `a_t` (absolute,
    /// see [`MaxwellBank::retune`]) with the exponentials `E`, in the
    /// working type: the call a firmware makes between two periods when
    /// its temperature reading changes, on a copy that it then swaps in.
    /// The running state carries over. On error the controller is left as
    /// it was.
    pub fn retune<E: Exponentials<T>>(&mut self, a_t: T) -> Result<(), ParamError> {
        self.bushing.retune::<E>(a_t)
    }

    /// A relaxed state at the displacement of ADC code `code`.
    pub fn start(&self, code: i16) -> RigState<T> {
        self.bushing.state_at(T::from_code(code))
    }

    /// The model step of one period, from an ADC code (pure arithmetic).
    pub fn step(&self, state: &mut RigState<T>, code: i16) -> RigOutput<T> {
        self.bushing.step(state, T::from_code(code))
    }

    /// One control period: read the ADC, step the model, write the DAC.
    pub fn period<A: SpiDevice, D: SpiDevice>(
        &self,
        state: &mut RigState<T>,
        adc: &mut Adc<A>,
        dac: &mut Dac<D>,
    ) -> Result<Period<T>, PeriodError<A::Error, D::Error>> {
        let code = adc.read().map_err(PeriodError::Adc)?;
        let force = self.step(state, code).force;
        let out = Period {
            code,
            force,
            dac: force.dac_code(),
            faults: state.faults(),
        };
        dac.write(out.dac).map_err(PeriodError::Dac)?;
        Ok(out)
    }
}

/// The modal tracker of the rig, in `f32`: one mode followed in the
/// measured displacement, started at the sweep's first frequency.
#[derive(Debug, Clone)]
pub struct Monitor {
    tracker: ModalTracker<f32, 4>,
    state: ModalState<f32, 4>,
}

/// The M3 build runs the tracker in thread mode on every 10th period
/// (500 Hz): in software floating point one update costs more than a whole
/// period.
pub const M3_TRACKER_DECIMATION: u32 = 20;

/// Displacement noise the tracker assumes, mm: 1 µm, the sensor's noise
/// rather than the ADC's quantization (LSB/√12 = 0.07 µm), so that the
/// filter does not over-trust a mode model that a sweep only approximates.
pub const TRACKER_NOISE_MM: f64 = 1e-3;

/// The tuning of the rig's tracker, matched to a sweep of constant
/// amplitude: the frequency walks 5 Hz/√s (the sweep climbs 42 Hz/s at its
/// end), the damping and the amplitude are held. A rig whose amplitude
/// drifts raises `amplitude_walk`: at 0.1/√s (with a damping walk of
/// 0.01/√s) the worst frequency error on this sweep grows from 0.62 % to
/// 1.6 %.
pub fn tracker_tuning() -> Tuning {
    Tuning {
        frequency_walk: 5.0,
        damping_walk: 0.0,
        amplitude_walk: 0.0,
        ..Tuning::default()
    }
}

impl Monitor {
    /// The rig's tracker, fed every `decimation`-th control period.
    pub fn new(decimation: u32) -> Result<Self, ParamError> {
        Self::tuned(decimation, TRACKER_NOISE_MM, tracker_tuning())
    }

    /// A tracker fed every `decimation`-th period, assuming a displacement
    /// noise of `noise` mm, with `tuning`.
    pub fn tuned(decimation: u32, noise: f64, tuning: Tuning) -> Result<Self, ParamError> {
        let tracker = ModalTracker::new(
            f64::from(decimation.max(1)) / RATE_HZ,
            &[SensorSpec {
                measured: Measured::Displacement,
                noise,
            }],
            &[ModeInit {
                frequency: SWEEP_HZ.0,
                damping: 0.0,
            }],
            // x = A sin φ is the real part of A (sin φ - i cos φ): at the
            // first sample, φ ≈ 0.
            &[(0.0, -AMPLITUDE_MM)],
            &tuning,
            Filter::Ekf,
        )?;
        let state = tracker.start();
        Ok(Self { tracker, state })
    }

    /// Feeds one displacement sample, mm.
    pub fn push(&mut self, x_mm: f32) -> ModalReport {
        self.tracker.step(&mut self.state, &[x_mm])
    }

    /// The tracked mode.
    pub fn mode(&self) -> ModeStatus<f32> {
        self.tracker.mode(&self.state, 0)
    }

    /// The tracked amplitude of the mode, mm.
    pub fn amplitude(&self) -> f32 {
        let (re, im) = self.tracker.displacement(&self.state, 0, 0);
        // Host-side and report use only; one sqrt per call.
        libm::sqrtf(re * re + im * im)
    }
}

#[cfg(test)]
mod tests;
