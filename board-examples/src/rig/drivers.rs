//! embedded-hal 1.0 drivers of the rig's converters, generic over
//! [`SpiDevice`] (the device owns its chip select).
//!
//! - [`Adc`]: a 16-bit two's-complement SPI ADC. One conversion is one
//!   transaction: the command byte `0x80 | channel`, then two bytes read
//!   back, most significant first.
//! - [`Dac`]: a 16-bit SPI DAC in the AD5686 frame: `0x30 | address`
//!   ("write and update"), then the offset-binary code, most significant
//!   byte first; the address has one bit per channel (A = 1, B = 2, C = 4,
//!   D = 8).

use embedded_hal::spi::{Operation, SpiDevice};

/// An input of the [`Adc`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum AdcChannel {
    /// Input 0.
    In0 = 0,
    /// Input 1.
    In1,
    /// Input 2.
    In2,
    /// Input 3.
    In3,
    /// Input 4.
    In4,
    /// Input 5.
    In5,
    /// Input 6.
    In6,
    /// Input 7.
    In7,
}

/// An output of the [`Dac`]: the frame's address bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum DacChannel {
    /// Output A.
    A = 1,
    /// Output B.
    B = 2,
    /// Output C.
    C = 4,
    /// Output D.
    D = 8,
}

/// Command byte of an ADC conversion on channel 0.
pub const ADC_READ: u8 = 0x80;
/// Command nibble of a DAC "write and update".
pub const DAC_WRITE_UPDATE: u8 = 0x30;

/// A 16-bit SPI ADC (see the module docs for the frame).
#[derive(Debug)]
pub struct Adc<SPI> {
    spi: SPI,
    command: u8,
}

impl<SPI: SpiDevice> Adc<SPI> {
    /// The converter on `spi`, reading `channel`.
    pub fn new(spi: SPI, channel: AdcChannel) -> Self {
        Self {
            spi,
            command: ADC_READ | channel as u8,
        }
    }

    /// One conversion: the signed code.
    pub fn read(&mut self) -> Result<i16, SPI::Error> {
        let mut rx = [0u8; 2];
        self.spi
            .transaction(&mut [Operation::Write(&[self.command]), Operation::Read(&mut rx)])?;
        Ok(i16::from_be_bytes(rx))
    }

    /// The bus device, for its diagnostics.
    pub fn device(&self) -> &SPI {
        &self.spi
    }

    /// The bus device, mutably (a simulated converter is fed through it).
    pub fn device_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// The bus device back (to check a mock, or to share the bus).
    pub fn release(self) -> SPI {
        self.spi
    }
}

/// A 16-bit SPI DAC (see the module docs for the frame).
#[derive(Debug)]
pub struct Dac<SPI> {
    spi: SPI,
    command: u8,
}

impl<SPI: SpiDevice> Dac<SPI> {
    /// The converter on `spi`, writing `channel`.
    pub fn new(spi: SPI, channel: DacChannel) -> Self {
        Self {
            spi,
            command: DAC_WRITE_UPDATE | channel as u8,
        }
    }

    /// Writes and updates the output with the offset-binary `code`.
    pub fn write(&mut self, code: u16) -> Result<(), SPI::Error> {
        let [hi, lo] = code.to_be_bytes();
        self.spi.write(&[self.command, hi, lo])
    }

    /// The bus device, for its diagnostics.
    pub fn device(&self) -> &SPI {
        &self.spi
    }

    /// The bus device, mutably (a simulated converter is fed through it).
    pub fn device_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// The bus device back.
    pub fn release(self) -> SPI {
        self.spi
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec;

    use embedded_hal_mock::eh1::spi::{Mock, Transaction};

    use super::*;

    #[test]
    fn adc_reads_one_conversion_per_transaction() {
        let expected = [
            Transaction::transaction_start(),
            Transaction::write_vec(vec![0x83]),
            Transaction::read_vec(vec![0x12, 0x34]),
            Transaction::transaction_end(),
            Transaction::transaction_start(),
            Transaction::write_vec(vec![0x83]),
            Transaction::read_vec(vec![0xff, 0xfe]),
            Transaction::transaction_end(),
        ];
        let mut adc = Adc::new(Mock::new(&expected), AdcChannel::In3);
        assert_eq!(adc.read(), Ok(0x1234));
        assert_eq!(adc.read(), Ok(-2));
        adc.release().done();
    }

    #[test]
    fn dac_writes_the_ad5686_frame() {
        let expected = [
            Transaction::transaction_start(),
            Transaction::write_vec(vec![0x34, 0x80, 0x01]),
            Transaction::transaction_end(),
            Transaction::transaction_start(),
            Transaction::write_vec(vec![0x34, 0x00, 0x00]),
            Transaction::transaction_end(),
        ];
        let mut dac = Dac::new(Mock::new(&expected), DacChannel::C);
        assert_eq!(dac.write(0x8001), Ok(()));
        assert_eq!(dac.write(0), Ok(()));
        dac.release().done();
    }
}
