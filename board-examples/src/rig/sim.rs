//! The hardware a rig loop talks to, simulated for QEMU and host tests
//! behind the same [`SpiDevice`] trait as the real converters.
//!
//! - [`Plant`]: the displacement the rig imposes (the sweep of
//!   `scenes/rig-loop.toml`), as the codes an ideal 16-bit ADC reads.
//! - [`SimAdc`]: answers the [`Adc`](super::Adc) frame with the next code
//!   of a queue the plant fills ahead of the loop; an empty queue is an
//!   underrun, counted.
//! - [`SimDac`]: checks the [`Dac`](super::Dac) frame and keeps the last
//!   code.

use bushing::ParamError;
use bushing::excitation::{Sweep, adc_code};
use embedded_hal::spi::{self, ErrorKind, ErrorType, Operation, SpiDevice};
use heapless::Deque;

use super::drivers::{ADC_READ, DAC_WRITE_UPDATE};
use super::{ADC_BITS, AMPLITUDE_MM, LSB_MM, RATE_HZ, sweep};

/// A transfer the simulated converter does not understand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Protocol;

impl spi::Error for Protocol {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// The imposed displacement: x(t) = A sin φ(t), the rig's sweep, read by
/// an ideal ADC. Computed in f64 through libm, as `bushing-sim` does.
#[derive(Debug, Clone, Copy)]
pub struct Plant {
    sweep: Sweep,
    dt: f64,
}

impl Plant {
    /// The sweep of the rig at [`RATE_HZ`].
    pub fn new() -> Result<Self, ParamError> {
        Ok(Self {
            sweep: sweep()?,
            dt: 1.0 / RATE_HZ,
        })
    }

    /// Control periods of the sweep (steps 1 to `steps()`).
    pub fn steps(&self) -> u32 {
        // A few thousand periods: the cast of a rounded small value is exact.
        libm::round(self.sweep.duration() / self.dt) as u32
    }

    /// The ADC code at period `i` (time `i * dt`).
    pub fn code(&self, i: u32) -> i16 {
        let x = AMPLITUDE_MM * self.sweep.unit(f64::from(i) * self.dt);
        // adc_code clamps to the 16-bit range.
        adc_code(x, LSB_MM, ADC_BITS) as i16
    }

    /// The sweep's frequency at period `i`, Hz.
    pub fn frequency(&self, i: u32) -> f64 {
        self.sweep
            .frequency((f64::from(i) * self.dt).max(0.0).min(self.sweep.duration()))
    }
}

/// Depth of the [`SimAdc`] queue.
pub const QUEUE: usize = 64;

/// A simulated ADC: a queue of codes, one per conversion.
#[derive(Debug, Default)]
pub struct SimAdc {
    queue: Deque<i16, QUEUE>,
    last: i16,
    underruns: u32,
    conversions: u32,
}

impl SimAdc {
    /// Queues the code of a coming conversion; `false` when full.
    pub fn feed(&mut self, code: i16) -> bool {
        self.queue.push_back(code).is_ok()
    }

    /// Whether the queue has room.
    pub fn wants(&self) -> bool {
        !self.queue.is_full()
    }

    /// Conversions that found the queue empty (and repeated the last code).
    pub fn underruns(&self) -> u32 {
        self.underruns
    }

    /// Conversions made.
    pub fn conversions(&self) -> u32 {
        self.conversions
    }

    /// Codes queued: how many periods ahead of the loop the feeder is.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }
}

impl ErrorType for SimAdc {
    type Error = Protocol;
}

impl SpiDevice for SimAdc {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Protocol> {
        let [Operation::Write(command), Operation::Read(rx)] = operations else {
            return Err(Protocol);
        };
        let ([command], [hi, lo]) = (&command[..], &mut rx[..]) else {
            return Err(Protocol);
        };
        if command & 0xF8 != ADC_READ {
            return Err(Protocol);
        }
        let code = match self.queue.pop_front() {
            Some(c) => c,
            None => {
                self.underruns = self.underruns.saturating_add(1);
                self.last
            }
        };
        self.last = code;
        self.conversions = self.conversions.saturating_add(1);
        [*hi, *lo] = code.to_be_bytes();
        Ok(())
    }
}

/// A simulated DAC: keeps the last code written.
#[derive(Debug, Default)]
pub struct SimDac {
    code: u16,
    writes: u32,
}

impl SimDac {
    /// The last code written (mid scale, 0 N, before the first).
    pub fn code(&self) -> u16 {
        if self.writes == 0 { 0x8000 } else { self.code }
    }

    /// Frames written.
    pub fn writes(&self) -> u32 {
        self.writes
    }
}

impl ErrorType for SimDac {
    type Error = Protocol;
}

impl SpiDevice for SimDac {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Protocol> {
        let [Operation::Write(frame)] = operations else {
            return Err(Protocol);
        };
        let [command, hi, lo] = frame[..] else {
            return Err(Protocol);
        };
        if command & 0xF0 != DAC_WRITE_UPDATE || (command & 0x0F).count_ones() != 1 {
            return Err(Protocol);
        }
        self.code = u16::from_be_bytes([hi, lo]);
        self.writes = self.writes.saturating_add(1);
        Ok(())
    }
}
