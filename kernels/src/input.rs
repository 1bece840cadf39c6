//! The inputs every displacement-driven kernel is measured on, the same
//! for the firmware's `kernel-cost` probe and for the host timings of the
//! accuracy-cost report: a large sine, the same sine below every slip
//! distance, and band-limited noise. The report keeps the worst of the
//! three for each kernel and names it.

use bushing::Real;

use crate::{band_noise, sine};

/// The large sine's amplitude, mm.
pub const AMPLITUDE: f64 = 2.0;
/// Samples per period of both sines.
pub const PERIOD: usize = 100;
/// The small sine's amplitude, mm: below the smallest slip displacement of
/// every Iwan bank measured (0.02 mm), so that no cell slips and none is
/// skipped.
pub const SMALL: f64 = 0.01;
/// The noise's RMS, mm.
pub const NOISE_RMS: f64 = 1.0;
/// The corner of the noise's two low-pass poles, as a fraction of the
/// sample rate.
pub const NOISE_CORNER: f64 = 0.02;
/// The noise's seed.
pub const NOISE_SEED: u64 = 23;

/// One of the three inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// The sine of the accuracy figures: [`AMPLITUDE`], [`PERIOD`] samples
    /// a period.
    LargeSine,
    /// The same sine at [`SMALL`].
    SmallSine,
    /// Band-limited noise, [`NOISE_RMS`].
    Noise,
}

impl Input {
    /// The three, in the order the reports list them.
    pub const ALL: [Self; 3] = [Self::LargeSine, Self::SmallSine, Self::Noise];

    /// The name the reports give it (`input=` of a kernel line).
    pub fn name(self) -> &'static str {
        match self {
            Self::LargeSine => "sine",
            Self::SmallSine => "small-sine",
            Self::Noise => "noise",
        }
    }

    /// The input for a kernel whose nominal signal is a sine of
    /// `amplitude` over `period` samples: that sine, the same at
    /// `SMALL / AMPLITUDE` of it, or band-limited noise of
    /// `NOISE_RMS / AMPLITUDE` of it, in f32.
    pub fn signal<const N: usize>(self, amplitude: f64, period: usize) -> [f32; N] {
        let scale = amplitude / AMPLITUDE;
        match self {
            Self::LargeSine => sine::<f32, N>(amplitude, period),
            Self::SmallSine => sine::<f32, N>(SMALL * scale, period),
            Self::Noise => band_noise::<f32, N>(NOISE_RMS * scale, NOISE_CORNER, NOISE_SEED),
        }
    }

    /// The displacements, mm, in `T`.
    pub fn xs<T: Real, const N: usize>(self) -> [T; N] {
        match self {
            Self::LargeSine => sine::<T, N>(AMPLITUDE, PERIOD),
            Self::SmallSine => sine::<T, N>(SMALL, PERIOD),
            Self::Noise => band_noise::<T, N>(NOISE_RMS, NOISE_CORNER, NOISE_SEED),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peak(x: &[f64]) -> f64 {
        x.iter().fold(0.0, |m, v| m.max(v.abs()))
    }

    fn rms(x: &[f64]) -> f64 {
        libm::sqrt(x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64)
    }

    #[test]
    fn the_three_inputs_are_what_their_names_say() {
        let names = Input::ALL.map(Input::name);
        assert_eq!(names, ["sine", "small-sine", "noise"]);
        let [large, small, noise] = Input::ALL.map(|i| i.xs::<f64, 2000>());
        assert!((peak(&large) - AMPLITUDE).abs() < 1e-9 * AMPLITUDE);
        assert!((peak(&small) - SMALL).abs() < 1e-9 * SMALL);
        assert!((rms(&noise) - NOISE_RMS).abs() < 1e-9);
        // A kernel's own sine is scaled alike: the small one stays below
        // the slip distances in the same proportion.
        let own = Input::SmallSine.signal::<2000>(9.0, PERIOD);
        let own = own.map(f64::from);
        assert!((peak(&own) - 9.0 * SMALL / AMPLITUDE).abs() < 1e-6);
        assert_eq!(
            Input::LargeSine.signal::<2000>(AMPLITUDE, PERIOD),
            Input::LargeSine.xs::<f32, 2000>()
        );
    }
}
