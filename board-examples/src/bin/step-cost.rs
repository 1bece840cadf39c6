//! Guest instructions per bushing step on Cortex-M, read from SysTick under
//! QEMU `-icount shift=0` (one tick per 40 instructions at the 25 MHz core
//! clock of the MPS2 boards). Prints one line per kernel and exits through
//! semihosting. QEMU counts instructions: no pipeline, FPU latency or flash
//! wait states.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use bushing::tracker::{
        Channel, Filter, Measured, ModalTracker, ModeInit, ModulusSpec, ModulusTracker, SensorFit,
        SensorSpec, SineSpec, SineTracker, Tuning, UtParams, fit_first_period,
    };
    use bushing::{LibmExp, MaxwellForm, MicromathExp, ShiftFactor, XfForm};
    use bushing_boards::{
        berg, bouc_wen, composite, dahl, grunwald, iwan_oscillator, iwan4, maxwell4,
        maxwell4_compensated, maxwell8, polynomial, run, run_oscillator, sliders4, spline, sts16,
        triangle, xf2,
    };
    use cortex_m::peripheral::{SYST, syst::SystClkSource};
    use cortex_m_rt::entry;
    use cortex_m_semihosting::{debug, hprintln};
    use panic_semihosting as _;

    const STEPS: usize = 2000;
    const INSTRUCTIONS_PER_TICK: u32 = 40;

    /// SysTick ticks taken by `f` (the counter runs free and counts down).
    fn ticks(_: &mut SYST, f: impl FnOnce()) -> u32 {
        let start = SYST::get_current();
        f();
        let end = SYST::get_current();
        start.wrapping_sub(end) & 0x00FF_FFFF
    }

    /// Instructions per step, times 10, net of the empty loop.
    fn per_step(syst: &mut SYST, baseline: u32, f: impl FnOnce()) -> u32 {
        let t = ticks(syst, f).saturating_sub(baseline);
        t * INSTRUCTIONS_PER_TICK * 10 / STEPS as u32
    }

    /// Instructions per call of `f`, times 10, for arguments sweeping
    /// 1.0 to 3.0 (a shift factor, or a temperature offset).
    fn per_call(syst: &mut SYST, mut f: impl FnMut(f32)) -> u32 {
        let t = ticks(syst, || {
            for k in 0..STEPS {
                f(1.0 + core::hint::black_box(k as f32) * 1e-3);
            }
        });
        t * INSTRUCTIONS_PER_TICK * 10 / STEPS as u32
    }

    fn report_call(name: &str, tenths: u32) {
        hprintln!(
            "{:<44} {:>5}.{} instructions/call",
            name,
            tenths / 10,
            tenths % 10
        );
    }

    fn report(name: &str, tenths: u32) {
        hprintln!(
            "{:<44} {:>5}.{} instructions/step",
            name,
            tenths / 10,
            tenths % 10
        );
    }

    #[entry]
    fn main() -> ! {
        let Some(p) = cortex_m::Peripherals::take() else {
            debug::exit(debug::EXIT_FAILURE);
            loop {
                cortex_m::asm::nop();
            }
        };
        let mut syst = p.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        let xs = triangle::<STEPS>();
        let baseline = ticks(&mut syst, || {
            for &x in &xs {
                core::hint::black_box(x);
            }
        });
        let Ok(poly) = polynomial() else { fail() };
        let Ok(spl) = spline() else { fail() };
        let Ok(bare) = bushing::Bushing::new(poly, ()) else {
            fail()
        };
        let Ok(bare_spline) = bushing::Bushing::new(spl, ()) else {
            fail()
        };
        hprintln!("bushing step cost, f32, {} steps, triangle input", STEPS);
        let force_only = |f: f32, _: f32, _: f32| {
            core::hint::black_box(f);
        };
        let all = |f: f32, k: f32, e: f32| {
            core::hint::black_box((f, k, e));
        };
        let t = per_step(&mut syst, baseline, || run(&bare, &xs, force_only));
        report("polynomial backbone only", t);
        let t = per_step(&mut syst, baseline, || run(&bare_spline, &xs, force_only));
        report("spline backbone (8 points) only", t);
        for form in MaxwellForm::ALL {
            let Ok(b) = maxwell4(form) else { fail() };
            let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
            report(form.name(), t);
            let t = per_step(&mut syst, baseline, || run(&b, &xs, all));
            report("  + tangent and dissipated energy", t);
        }
        let Ok(b) = maxwell4_compensated() else {
            fail()
        };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("rate-exact-ramp, compensated state", t);
        let Ok(b) = iwan4() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("iwan clamp, 4 Jenkins cells", t);
        let t = per_step(&mut syst, baseline, || run(&b, &xs, all));
        report("  + tangent and dissipated energy", t);
        let Ok(b) = sliders4() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("iwan slider, 4 Jenkins cells", t);
        for form in XfForm::ALL {
            let Ok(b) = xf2(form) else { fail() };
            let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
            let name = match form {
                XfForm::Midpoint => "x_f midpoint (2.41), 2 cells",
                XfForm::ExactRamp => "x_f exact ramp, 2 cells",
            };
            report(name, t);
            let t = per_step(&mut syst, baseline, || run(&b, &xs, all));
            report("  + tangent and dissipated energy", t);
        }
        let Ok(b) = composite() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("3 Maxwell + 3 Jenkins + 1 x_f", t);
        let Ok(b) = maxwell8() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("rate-exact-ramp, 8 cells", t);
        // Re-tuning a running 8-cell bank to another temperature: exact in
        // f64 (soft-float on this core), or in place in f32.
        let bank = &b.effects().0;
        let t = per_call(&mut syst, |a_t| {
            let _ = core::hint::black_box(bank.shifted(f64::from(a_t)));
        });
        report_call("re-tune 8 Maxwell cells, f64 (libm, soft)", t);
        let mut bank = bank.clone();
        let t = per_call(&mut syst, |a_t| {
            let _ = core::hint::black_box(bank.retune::<LibmExp>(a_t));
        });
        report_call("re-tune 8 Maxwell cells, f32 libm", t);
        let t = per_call(&mut syst, |a_t| {
            let _ = core::hint::black_box(bank.retune::<MicromathExp>(a_t));
        });
        report_call("re-tune 8 Maxwell cells, f32 micromath", t);
        let Ok(wlf) = ShiftFactor::wlf(17.44, 51.6, 20.0) else {
            fail()
        };
        let t = per_call(&mut syst, |a_t| {
            let _ = core::hint::black_box(wlf.at(f64::from(a_t) + 19.0));
        });
        report_call("WLF shift factor a_T, f64 (libm, soft)", t);
        let t = per_call(&mut syst, |a_t| {
            let _ = core::hint::black_box(wlf.at_in::<f32, LibmExp>(a_t + 19.0));
        });
        report_call("WLF shift factor a_T, f32 libm", t);
        let t = per_call(&mut syst, |a_t| {
            let _ = core::hint::black_box(wlf.at_in::<f32, MicromathExp>(a_t + 19.0));
        });
        report_call("WLF shift factor a_T, f32 micromath", t);
        let Ok(b) = grunwald::<64>() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("Grünwald fractional cell, N = 64", t);
        let Ok(b) = grunwald::<1024>() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("Grünwald fractional cell, N = 1024", t);
        let Ok(b) = sts16() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("STS on a 16-deep turning-point stack", t);
        for (alpha, name) in [(1.0, "Dahl, alpha = 1"), (0.5, "Dahl, alpha = 0.5")] {
            let Ok(b) = dahl(alpha) else { fail() };
            let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
            report(name, t);
        }
        for (n, name) in [(2.0, "Bouc-Wen, n = 2"), (8.0, "Bouc-Wen, n = 8")] {
            let Ok(b) = bouc_wen(n) else { fail() };
            let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
            report(name, t);
        }
        let Ok(b) = berg() else { fail() };
        let t = per_step(&mut syst, baseline, || run(&b, &xs, force_only));
        report("Berg", t);
        let Ok(osc) = iwan_oscillator() else { fail() };
        let mut iterations = 0u32;
        let t = per_step(&mut syst, baseline, || {
            run_oscillator(&osc, STEPS, |p, n| {
                core::hint::black_box(p);
                iterations += n;
            })
        });
        report("Iwan oscillator (20 cells), one step", t);
        hprintln!(
            "  chord iterations per step: {}.{:02}",
            iterations as usize / STEPS,
            iterations as usize * 100 / STEPS % 100
        );
        // Modal tracker: one mode and one accelerometer, 50 samples per
        // period; then two modes on three accelerometers (16 states).
        let one = [SensorSpec {
            measured: Measured::Acceleration,
            noise: 0.01,
        }];
        let three = [one[0]; 3];
        let mode = ModeInit {
            frequency: 20.0,
            damping: 0.01,
        };
        let two = [
            mode,
            ModeInit {
                frequency: 51.0,
                damping: 0.005,
            },
        ];
        for (filter, small, large) in [
            (
                Filter::Ekf,
                "modal tracker EKF, 1 mode 1 sensor (4 states)",
                "modal tracker EKF, 2 modes 3 sensors (16 states)",
            ),
            (
                Filter::Ukf(UtParams::default()),
                "modal tracker UKF, 1 mode 1 sensor (4 states)",
                "modal tracker UKF, 2 modes 3 sensors (16 states)",
            ),
        ] {
            let t = tracker_cost::<4>(&mut syst, baseline, filter, &one, &[mode]);
            report(small, t);
            let t = tracker_cost::<16>(&mut syst, baseline, filter, &three, &two);
            report(large, t);
        }
        // Sine tracker and modulus tracker at 50 samples per period.
        let sine = SineSpec {
            frequency: 20.0,
            bandwidth: 1.0,
        };
        let channel = Channel {
            noise: 0.01,
            amplitude: 1.0,
        };
        let Ok(tracker) = SineTracker::<f32>::new(1e-3, &sine, channel) else {
            fail()
        };
        let mut state = tracker.start();
        let (c, s) = (0.992_114_7f32, 0.125_333_2f32);
        let (mut re, mut im) = (1.0f32, 0.0f32);
        let t = per_step(&mut syst, baseline, || {
            for _ in 0..STEPS {
                let r = c * re - s * im;
                im = s * re + c * im;
                re = r;
                let _ = core::hint::black_box(tracker.step(&mut state, re));
            }
        });
        report("sine tracker (2 states), one update", t);
        let Ok(modulus) = ModulusTracker::<f32>::new(
            1e-3,
            &ModulusSpec {
                sine,
                displacement: channel,
                force: channel,
                min_snr: 10.0,
            },
        ) else {
            fail()
        };
        let mut state = modulus.start();
        let t = per_step(&mut syst, baseline, || {
            for _ in 0..STEPS {
                let r = c * re - s * im;
                im = s * re + c * im;
                re = r;
                let _ = core::hint::black_box(modulus.step(&mut state, re, 0.9 * re - 0.2 * im));
            }
        });
        report("modulus tracker (x and F), one update", t);
        let t = per_step(&mut syst, baseline, || {
            for _ in 0..STEPS {
                let _ = core::hint::black_box(modulus.modulus(core::hint::black_box(&state)));
            }
        });
        report("modulus tracker, K* = F/X on request", t);
        // Start values: least-squares fit of one noisy 50-sample period, in
        // f64 (soft-float on the M4F).
        let mut record = [0.0f64; 50];
        let (c, s) = (0.992_114_701_314_478_f64, 0.125_333_233_564_304_2_f64);
        let (mut re, mut im) = (1.0f64, 0.0f64);
        for (k, x) in record.iter_mut().enumerate() {
            // A 1e-3 deterministic pseudo-noise, so the fit iterates.
            *x = re + 1e-3 * ((k * 7919 % 13) as f64 - 6.0) / 6.0;
            let r = 0.999 * (c * re - s * im);
            im = 0.999 * (s * re + c * im);
            re = r;
        }
        let mut out = [SensorFit::default()];
        let mut iterations = 0;
        let t = ticks(&mut syst, || {
            for _ in 0..10 {
                if let Ok(fit) = fit_first_period(1e-3, &[core::hint::black_box(&record)], &mut out)
                {
                    iterations = fit.iterations;
                }
            }
        });
        hprintln!(
            "{:<44} {:>8} instructions/call ({} iterations)",
            "first-period fit, 50 samples (f64)",
            t * INSTRUCTIONS_PER_TICK / 10,
            iterations
        );
        debug::exit(debug::EXIT_SUCCESS);
        loop {
            cortex_m::asm::nop();
        }
    }

    /// Instructions per tracker update, times 10, on a signal made by a
    /// rotation recurrence (a few instructions); sensor c reads the signal
    /// times a mode-shape-like factor.
    fn tracker_cost<const N: usize>(
        syst: &mut SYST,
        baseline: u32,
        filter: Filter,
        sensors: &[SensorSpec],
        modes: &[ModeInit],
    ) -> u32 {
        let amplitudes = [(1.0, 0.0); 8];
        let Some(amplitudes) = amplitudes.get(..sensors.len() * modes.len()) else {
            fail()
        };
        let Ok(tracker) = ModalTracker::<f32, N>::new(
            1e-3,
            sensors,
            modes,
            amplitudes,
            &Tuning::default(),
            filter,
        ) else {
            fail()
        };
        let mut state = tracker.start();
        let (c, s) = (0.992_114_7f32, 0.125_333_2f32); // 2π / 50
        let (mut re, mut im) = (1.0f32, 0.0f32);
        let shape = [1.0f32, 2.0, -1.8];
        let mut samples = [0.0f32; 3];
        let n = sensors.len().min(3);
        per_step(syst, baseline, || {
            for _ in 0..STEPS {
                let r = c * re - s * im;
                im = s * re + c * im;
                re = r;
                for (x, k) in samples.iter_mut().zip(shape) {
                    *x = k * re;
                }
                let _ = core::hint::black_box(tracker.step(&mut state, &samples[..n]));
            }
        })
    }

    fn fail() -> ! {
        hprintln!("parameters refused");
        debug::exit(debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::nop();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "step-cost is firmware: cargo run --release -p bushing-boards --target thumbv7em-none-eabihf"
    );
}
