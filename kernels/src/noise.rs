//! The project's one seeded generator: reproducible white noise for the
//! test records, the reports' noise seeds, the peer comparison and the fuzz
//! runs, the same numbers on the host and on Cortex-M.

/// Reproducible white noise for the test records: xorshift64* seeded
/// through splitmix64 (so that small or similar seeds give unrelated
/// streams from the first draw), and Box-Muller with libm, so the host and
/// the Cortex-M targets draw the same numbers.
#[derive(Debug, Clone)]
pub struct Noise(u64);

impl Noise {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Self((z ^ (z >> 31)) | 1)
    }

    /// The stream of a raw xorshift64* state, without the seeding: the
    /// same numbers as [`Noise::new`]'s generator from a state chosen by
    /// hand (records kept from before the seeding, whose expected values
    /// were taken with them); a state of 0, which xorshift never leaves,
    /// is taken as 1.
    pub fn from_state(state: u64) -> Self {
        Self(if state == 0 { 1 } else { state })
    }

    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Uniform in (-1, 1).
    pub fn symmetric(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }

    /// Standard normal.
    pub fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        libm::sqrt(-2.0 * libm::log(u)) * libm::cos(core::f64::consts::TAU * v)
    }
}
