extern crate std;
use std::vec;
use std::vec::Vec;

use bushing::Q16;
use embedded_hal::spi::Operation;
use embedded_hal_mock::eh1::spi::{Mock, Transaction};

use super::sim::{Plant, Protocol, SimAdc, SimDac};
use super::*;

/// The transactions of one period: conversion of `code` on input 0, then
/// the DAC frame of `dac` on output A.
fn period_transactions(code: i16, dac: u16) -> [Transaction<u8>; 7] {
    let [chi, clo] = code.to_be_bytes();
    let [dhi, dlo] = dac.to_be_bytes();
    [
        Transaction::transaction_start(),
        Transaction::write_vec(vec![0x80]),
        Transaction::read_vec(vec![chi, clo]),
        Transaction::transaction_end(),
        Transaction::transaction_start(),
        Transaction::write_vec(vec![0x31, dhi, dlo]),
        Transaction::transaction_end(),
    ]
}

/// Runs three periods against mocks that check every transfer: the codes
/// read, and the DAC frames of the forces the model gives for them.
fn periods_on_mocks<T: Sample>() {
    let rig = Rig::<T>::new().unwrap();
    let codes = [4096i16, -2048, 12_000];
    // The expected DAC codes, from a second copy of the model.
    let mut reference = rig.start(0);
    let dacs: Vec<u16> = codes
        .iter()
        .map(|&c| rig.step(&mut reference, c).force.dac_code())
        .collect();
    let mut adc_tx = Vec::new();
    let mut dac_tx = Vec::new();
    for (&c, &d) in codes.iter().zip(&dacs) {
        let t = period_transactions(c, d);
        adc_tx.extend_from_slice(&t[..4]);
        dac_tx.extend_from_slice(&t[4..]);
    }
    let mut adc = Adc::new(Mock::new(&adc_tx), AdcChannel::In0);
    let mut dac = Dac::new(Mock::new(&dac_tx), DacChannel::A);
    let mut state = rig.start(0);
    for (&c, &d) in codes.iter().zip(&dacs) {
        let p = rig.period(&mut state, &mut adc, &mut dac).unwrap();
        assert_eq!((p.code, p.dac), (c, d));
        assert!(p.faults.is_empty());
    }
    assert_eq!(state, reference);
    adc.release().done();
    dac.release().done();
    // 1 mm is 150 N on the spline's slope; 2.93 mm about 1200 N.
    assert!(dacs[0] > 0x8000 + 8 * 150 && dacs[1] < 0x8000);
}

#[test]
fn f32_periods_make_exactly_the_expected_transfers() {
    periods_on_mocks::<f32>();
}

#[test]
fn q16_periods_make_exactly_the_expected_transfers() {
    periods_on_mocks::<Q16>();
}

/// A bus whose every transfer fails.
struct Broken;

impl embedded_hal::spi::ErrorType for Broken {
    type Error = embedded_hal::spi::ErrorKind;
}

impl SpiDevice for Broken {
    fn transaction(&mut self, _: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        Err(embedded_hal::spi::ErrorKind::Other)
    }
}

#[test]
fn a_failed_transfer_is_reported_and_a_failed_conversion_leaves_the_model_alone() {
    let rig = Rig::<f32>::new().unwrap();
    let none: [Transaction<u8>; 0] = [];
    let mut adc = Adc::new(Broken, AdcChannel::In0);
    let mut dac = Dac::new(Mock::new(&none), DacChannel::A);
    let mut state = rig.start(0);
    let before = state.clone();
    let r = rig.period(&mut state, &mut adc, &mut dac);
    assert_eq!(
        r,
        Err(PeriodError::Adc(embedded_hal::spi::ErrorKind::Other))
    );
    assert_eq!(state, before);
    dac.release().done();
    // A failed DAC write comes after the step.
    let mut sim = SimAdc::default();
    assert!(sim.feed(4096));
    let mut adc = Adc::new(sim, AdcChannel::In0);
    let mut dac = Dac::new(Broken, DacChannel::A);
    let r = rig.period(&mut state, &mut adc, &mut dac);
    assert_eq!(
        r,
        Err(PeriodError::Dac(embedded_hal::spi::ErrorKind::Other))
    );
    assert_ne!(state, before);
}

#[test]
fn the_logged_lsb_is_exact() {
    assert_eq!(LSB_MM_TEXT.parse::<f64>(), Ok(LSB_MM));
}

#[test]
fn codes_scale_exactly_and_forces_round_toward_zero() {
    for code in [i16::MIN, -4097, -1, 0, 1, 4095, i16::MAX] {
        let mm = f64::from(code) / 4096.0;
        assert_eq!(f64::from(f32::from_code(code)), mm);
        assert_eq!(Q16::from_code(code).to_f64(), mm);
        assert_eq!(f64::from_code(code), mm);
    }
    for (force, count) in [
        (0.0, 0),
        (0.124, 0),
        (0.125, 1),
        (-0.249, -1),
        (-0.25, -2),
        (1000.0, 8000),
        (1e9, 32767),
        (-1e9, -32768),
    ] {
        let code = (count + 32768) as u16;
        assert_eq!(f32::dac_code(force as f32), code, "{force}");
        assert_eq!(f64::dac_code(force), code, "{force}");
        assert_eq!(Q16::from_f64(force).dac_code(), code, "{force}");
    }
    assert_eq!(f32::NAN.dac_code(), 0x8000);
    assert_eq!(f32::INFINITY.dac_code(), 0xFFFF);
    assert_eq!(Q16::MIN.dac_code(), 0);
    assert_eq!((-1.5f32).log_bits(), (-1.5f32).to_bits());
    assert_eq!(Q16::from_f64(-1.5).log_bits(), 0xFFFE_8000);
}

#[test]
fn simulated_converters_check_their_frames() {
    let mut adc = SimAdc::default();
    let mut rx = [0u8; 2];
    // Wrong command, wrong length, wrong shape.
    for command in [&[0x40u8][..], &[0x80, 0][..]] {
        let mut ops = [Operation::Write(command), Operation::Read(&mut rx)];
        assert_eq!(adc.transaction(&mut ops), Err(Protocol));
    }
    assert_eq!(
        adc.transaction(&mut [Operation::Read(&mut rx)]),
        Err(Protocol)
    );
    assert!(adc.feed(-300));
    let mut a = Adc::new(adc, AdcChannel::In5);
    assert_eq!(a.read(), Ok(-300));
    // Empty queue: the last code again, and an underrun.
    assert_eq!(a.read(), Ok(-300));
    let adc = a.release();
    assert_eq!(
        (adc.conversions(), adc.underruns(), adc.queued()),
        (2, 1, 0)
    );

    let mut dac = SimDac::default();
    assert_eq!(dac.code(), 0x8000);
    assert_eq!(dac.write(&[0x33, 1, 2]), Err(Protocol));
    assert_eq!(dac.write(&[0x31, 1]), Err(Protocol));
    let mut d = Dac::new(dac, DacChannel::D);
    assert_eq!(d.write(0xBEEF), Ok(()));
    let dac = d.release();
    assert_eq!((dac.code(), dac.writes()), (0xBEEF, 1));
}

/// Runs the whole sweep through the simulated converters in `T`: the
/// forces, and the tracker's last frequency estimate.
fn sweep_in<T: Sample>() -> (Vec<f64>, Vec<u32>, Plant) {
    let plant = Plant::new().unwrap();
    let rig = Rig::<T>::new().unwrap();
    let mut state = rig.start(plant.code(0));
    let mut adc = Adc::new(SimAdc::default(), AdcChannel::In0);
    let mut dac = Dac::new(SimDac::default(), DacChannel::A);
    let (mut forces, mut bits) = (Vec::new(), Vec::new());
    for i in 1..=plant.steps() {
        let mut sim = adc.release();
        assert!(sim.feed(plant.code(i)));
        adc = Adc::new(sim, AdcChannel::In0);
        let p = rig.period(&mut state, &mut adc, &mut dac).unwrap();
        forces.push(p.force.to_f64());
        bits.push(p.force.log_bits());
    }
    assert_eq!(adc.release().underruns(), 0);
    assert_eq!(dac.release().writes(), plant.steps());
    (forces, bits, plant)
}

/// The documented bound of the Q16 loop against f64: one DAC step, so
/// that fixed point changes the command by at most one code
/// (docs/firmware.md).
pub const Q16_BOUND_N: f64 = DAC_LSB_N;

#[test]
fn q16_loop_stays_within_its_bound_of_f64() {
    let (f64_forces, _, _) = sweep_in::<f64>();
    let (q16_forces, _, _) = sweep_in::<Q16>();
    let (f32_forces, _, _) = sweep_in::<f32>();
    let worst = |a: &[f64]| {
        a.iter()
            .zip(&f64_forces)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let peak = f64_forces.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let (q16, f32e) = (worst(&q16_forces), worst(&f32_forces));
    std::println!("peak {peak:.1} N, Q16 error {q16:.4} N, f32 error {f32e:.2e} N");
    assert!(peak > 400.0, "the sweep loads the bushing: {peak}");
    assert!(q16 <= Q16_BOUND_N, "{q16}");
    assert!(f32e < 1e-3, "{f32e}");
}

/// Feeds every `decimation`-th code of the sweep to the rig's tracker:
/// the worst relative frequency error after the first 0.3 s.
fn tracking_error(decimation: u32) -> f64 {
    let plant = Plant::new().unwrap();
    let mut m = Monitor::new(decimation).unwrap();
    let mut worst = 0.0f64;
    for i in (decimation..=plant.steps()).step_by(decimation as usize) {
        let r = m.push(f32::from_code(plant.code(i)));
        assert!(!r.repaired && !r.refused && !r.reacquired, "{i}: {r:?}");
        if f64::from(i) / RATE_HZ > 0.3 {
            let f = plant.frequency(i);
            worst = worst.max((f64::from(m.mode().frequency) - f).abs() / f);
        }
    }
    assert!((f64::from(m.amplitude()) - AMPLITUDE_MM).abs() < 0.02 * AMPLITUDE_MM);
    worst
}

#[test]
fn tracker_follows_the_sweep_every_period_and_decimated() {
    // 5 kHz as on the M4F, 500 Hz as on the M3 (thread mode).
    for decimation in [1, M3_TRACKER_DECIMATION] {
        let worst = tracking_error(decimation);
        std::println!(
            "tracker every {decimation}: worst frequency error {:.3} %",
            100.0 * worst
        );
        assert!(worst < 0.01, "{decimation}: {worst}");
    }
}

#[test]
fn retuning_between_periods_keeps_the_state_and_refuses_bad_factors() {
    use bushing::LibmExp;
    use bushing::temperature::ShiftFactor;
    let rig = Rig::<f32>::new().unwrap();
    let mut state = rig.start(0);
    for code in [2000, 4000, 6000] {
        rig.step(&mut state, code);
    }
    // a_T = 1 gives the coefficients again, computed in f32 rather than
    // f64: the same force within a few ulps.
    let mut same = rig.clone();
    same.retune::<LibmExp>(1.0).unwrap();
    let (mut s1, mut s2) = (state.clone(), state.clone());
    let (f1, f2) = (
        rig.step(&mut s1, 5000).force,
        same.step(&mut s2, 5000).force,
    );
    assert!(
        (f1 - f2).abs() <= 4.0 * f32::EPSILON * f1.abs(),
        "{f1} {f2}"
    );
    // 20 K colder on a WLF law: slower cells, a stiffer bushing.
    let law = ShiftFactor::wlf(8.86, 101.6, 293.15).unwrap();
    let a_t = law.at_in::<f32, LibmExp>(273.15).unwrap();
    assert!(a_t > 1.0);
    let mut cold = rig.clone();
    cold.retune::<LibmExp>(a_t).unwrap();
    let (mut s1, mut s2) = (state.clone(), state.clone());
    let (warm_f, cold_f) = (
        rig.step(&mut s1, 8000).force,
        cold.step(&mut s2, 8000).force,
    );
    assert!(cold_f > warm_f, "{cold_f} {warm_f}");
    // A refused factor leaves the controller as it was.
    let before = cold.clone();
    assert!(cold.retune::<LibmExp>(f32::NAN).is_err());
    assert!(cold.retune::<LibmExp>(0.0).is_err());
    assert_eq!(cold.bushing(), before.bushing());
}
