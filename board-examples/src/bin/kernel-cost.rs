//! Guest instructions per call of each kernel's public step, for the
//! accuracy-cost report (`bushing-sim accuracy-cost`).
//!
//! Every kernel is called through an `#[inline(never)]` function whose body
//! is the library's public call (`Effect::step`, `Bushing::step`,
//! `ModalTracker::step`, ...), so the figure includes the call, the argument
//! passing and the output, as a firmware pays them. The count is read from
//! SysTick under QEMU `-icount shift=0` (one tick per 40 instructions),
//! over many calls, net of the empty loop.
//!
//! One line per kernel:
//!
//! ```text
//! kernel target=m4f type=f32 family=maxwell name=rate-exact-ramp/plain n=8 per_call=61.0 state_bytes=32 params_bytes=212 fn=0x00001234
//! ```
//!
//! `fn` is the address of the measured function: the report generator looks
//! it up in the ELF symbol table for its code size. The same binary runs on
//! the Cortex-M4F (FPU) and the Cortex-M3 (software floating point).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::hint::black_box;
    use core::mem::size_of_val;

    use bushing::tracker::{
        Channel, Modulus, ModulusSpec, ModulusState, ModulusTracker, Refused, SineSpec, SineState,
        SineTracker,
    };
    use bushing::tracker::{
        Filter, Measured, ModalTracker, ModeInit, SensorSpec, Tuning, UtParams,
    };
    use bushing::{
        Accumulator, Backbone, Bushing, Compensated, Drive, Effect, EffectOutput, LibmExp,
        MaxwellForm, MicromathExp, Multiplied, Plain, XfBank, XfForm, XfSpec,
    };
    use bushing::{IwanBank, IwanSliders, OscillatorState, OscillatorStep};
    use bushing_boards::{
        DT, IwanOscillator, berg, bouc_wen, composite, dahl, default_bushing, drives, grunwald,
        iwan_bank, iwan_oscillator, jenkins, maxwell_bank, polynomial, sine, spline, sts16, xf2,
    };
    use cortex_m::peripheral::{SYST, syst::SystClkSource};
    use cortex_m_rt::entry;
    use cortex_m_semihosting::{debug, hprintln};
    use panic_semihosting as _;

    const STEPS: usize = 2000;
    const INSTRUCTIONS_PER_TICK: u32 = 40;
    /// Sine input: 2 mm amplitude, 100 samples per period (20 periods).
    const AMPLITUDE: f64 = 2.0;
    const PERIOD: usize = 100;

    const TARGET: &str = if cfg!(target_abi = "eabihf") {
        "m4f"
    } else {
        "m3"
    };

    /// SysTick ticks taken by `f` (the counter runs free and counts down).
    fn ticks(f: impl FnOnce()) -> u32 {
        let start = SYST::get_current();
        f();
        let end = SYST::get_current();
        start.wrapping_sub(end) & 0x00FF_FFFF
    }

    /// What one measurement printed.
    struct Line<'a> {
        family: &'a str,
        name: &'a str,
        n: usize,
        state_bytes: usize,
        params_bytes: usize,
        function: usize,
    }

    /// Prints a line from the loop's ticks with the kernel (`t`), with an
    /// empty function of the same signature (`empty`) and with nothing
    /// (`baseline`), over `calls` passes: `per_call` counts the call, the
    /// return and the harness's use of the result; `net` only what the
    /// kernel itself adds (what it costs inlined into a control loop).
    fn report(line: &Line<'_>, t: u32, empty: u32, baseline: u32, calls: usize) {
        let tenths = |ticks: u32| ticks * INSTRUCTIONS_PER_TICK * 10 / calls.max(1) as u32;
        let gross = tenths(t.saturating_sub(baseline));
        let net = tenths(t.saturating_sub(empty));
        hprintln!(
            "kernel target={} type=f32 family={} name={} n={} per_call={}.{} net={}.{} state_bytes={} params_bytes={} fn={:#010x}",
            TARGET,
            line.family,
            line.name,
            line.n,
            gross / 10,
            gross % 10,
            net / 10,
            net % 10,
            line.state_bytes,
            line.params_bytes,
            line.function & !1
        );
    }

    #[inline(never)]
    fn effect_step<E: Effect<f32>>(e: &E, s: &mut E::State, d: &Drive<f32>) -> E::Report {
        e.step(s, d)
    }

    /// The harness's stand-in for [`effect_step`]: same arguments, a
    /// three-word result, one load.
    #[inline(never)]
    fn effect_empty<E: Effect<f32>>(_: &E, _: &mut E::State, d: &Drive<f32>) -> EffectOutput<f32> {
        EffectOutput {
            force: d.dx,
            tangent: d.dx,
            dissipated: d.dx,
        }
    }

    #[inline(never)]
    fn effect_force<E: Effect<f32>>(e: &E, s: &mut E::State, d: &Drive<f32>) -> f32 {
        e.step_force(s, d)
    }

    /// The stand-in for [`effect_force`].
    #[inline(never)]
    fn force_empty<E: Effect<f32>>(_: &E, _: &mut E::State, d: &Drive<f32>) -> f32 {
        d.dx
    }

    /// Ticks of `kernel` called over `drives` from a rested state.
    fn over_drives<E: Effect<f32>, R>(
        e: &E,
        drives: &[Drive<f32>],
        kernel: fn(&E, &mut E::State, &Drive<f32>) -> R,
    ) -> u32 {
        let mut s = e.rest(0.0);
        ticks(|| {
            for d in drives {
                black_box(kernel(e, &mut s, black_box(d)));
            }
        })
    }

    /// Cost of one `Effect::step_force` of `e` over `drives` (the state
    /// advanced, the force returned; no energy, no tangent).
    fn force_only<E: Effect<f32>>(
        family: &str,
        name: &str,
        n: usize,
        e: &E,
        drives: &[Drive<f32>],
        baseline: u32,
    ) {
        let t = over_drives(e, drives, effect_force::<E>);
        let empty = over_drives(e, drives, force_empty::<E>);
        let f: fn(&E, &mut E::State, &Drive<f32>) -> f32 = effect_force::<E>;
        let line = Line {
            family,
            name,
            n,
            state_bytes: size_of_val(&e.rest(0.0)),
            params_bytes: size_of_val(e),
            function: f as usize,
        };
        report(&line, t, empty, baseline, drives.len());
    }

    /// Cost of one `Effect::step` of `e` over `drives`.
    fn effect<E: Effect<f32, Report = EffectOutput<f32>>>(
        family: &str,
        name: &str,
        n: usize,
        e: &E,
        drives: &[Drive<f32>],
        baseline: u32,
    ) {
        let t = over_drives(e, drives, effect_step::<E>);
        let empty = over_drives(e, drives, effect_empty::<E>);
        let f: fn(&E, &mut E::State, &Drive<f32>) -> EffectOutput<f32> = effect_step::<E>;
        let line = Line {
            family,
            name,
            n,
            state_bytes: size_of_val(&e.rest(0.0)),
            params_bytes: size_of_val(e),
            function: f as usize,
        };
        report(&line, t, empty, baseline, drives.len());
    }

    /// One `Bushing::step`, returning what a rig loop reads: force,
    /// tangent and dissipated energy (the per-branch reports are dropped).
    #[inline(never)]
    fn bushing_step<B: Backbone<f32>, E: Effect<f32>>(
        b: &Bushing<f32, B, E>,
        s: &mut bushing::BushingState<f32, E::State>,
        x: f32,
    ) -> [f32; 3] {
        let o = b.step(s, x);
        [o.force, o.tangent, o.dissipated]
    }

    /// The stand-in for [`bushing_step`].
    #[inline(never)]
    fn bushing_empty<B: Backbone<f32>, E: Effect<f32>>(
        _: &Bushing<f32, B, E>,
        _: &mut bushing::BushingState<f32, E::State>,
        x: f32,
    ) -> [f32; 3] {
        [x, x, x]
    }

    /// Cost of one `Bushing::step` of `b` over `xs` (force, tangent and
    /// dissipated energy all returned).
    fn whole<B: Backbone<f32>, E: Effect<f32>>(
        family: &str,
        name: &str,
        n: usize,
        b: &Bushing<f32, B, E>,
        xs: &[f32],
        baseline: u32,
    ) {
        type Kernel<B, E> = fn(
            &Bushing<f32, B, E>,
            &mut bushing::BushingState<f32, <E as Effect<f32>>::State>,
            f32,
        ) -> [f32; 3];
        let run = |kernel: Kernel<B, E>| {
            let mut s = b.state_at(0.0);
            ticks(|| {
                for x in xs {
                    black_box(kernel(b, &mut s, *black_box(x)));
                }
            })
        };
        let t = run(bushing_step::<B, E>);
        let empty = run(bushing_empty::<B, E>);
        let f: Kernel<B, E> = bushing_step::<B, E>;
        let line = Line {
            family,
            name,
            n,
            state_bytes: size_of_val(&b.state_at(0.0)),
            params_bytes: size_of_val(b),
            function: f as usize,
        };
        report(&line, t, empty, baseline, xs.len());
    }

    fn maxwell<const N: usize, A: Accumulator<f32>>(
        kind: &str,
        drives: &[Drive<f32>],
        baseline: u32,
    ) {
        for form in MaxwellForm::ALL {
            let Ok(bank) = maxwell_bank::<N, A>(form) else {
                fail()
            };
            let mut name = heapless_name();
            name.push(form.name());
            name.push("/");
            name.push(kind);
            effect("maxwell", name.as_str(), N, &bank, drives, baseline);
            force_only("maxwell-force", name.as_str(), N, &bank, drives, baseline);
        }
    }

    fn iwan<const N: usize>(drives: &[Drive<f32>], baseline: u32) {
        let Ok(bank) = iwan_bank::<N>() else { fail() };
        effect("iwan", "clamp/log", N, &bank, drives, baseline);
    }

    fn grunwald_cost<const N: usize>(xs: &[f32], baseline: u32) {
        let Ok(b) = grunwald::<N>() else { fail() };
        whole("grunwald", "bushing/alpha-0.5", N, &b, xs, baseline);
    }

    type TrackerState = bushing::tracker::ModalState<f32, 4>;

    #[inline(never)]
    fn tracker_step(
        t: &ModalTracker<f32, 4>,
        s: &mut TrackerState,
        y: &[f32],
    ) -> bushing::tracker::ModalReport {
        t.step(s, y)
    }

    /// The stand-in for [`tracker_step`].
    #[inline(never)]
    fn tracker_empty(_: &ModalTracker<f32, 4>, _: &mut TrackerState, y: &[f32]) -> f32 {
        y.first().copied().unwrap_or(0.0)
    }

    fn tracker(name: &str, filter: Filter) {
        let sensors = [SensorSpec {
            measured: Measured::Acceleration,
            noise: 0.01,
        }];
        let mode = [ModeInit {
            frequency: 20.0,
            damping: 0.01,
        }];
        let Ok(tracker) = ModalTracker::<f32, 4>::new(
            1e-3,
            &sensors,
            &mode,
            &[(1.0, 0.0)],
            &Tuning::default(),
            filter,
        ) else {
            fail()
        };
        // A 20 Hz sine at 1 kHz by a rotation recurrence (a few
        // instructions, in every loop below).
        let run = |kernel: &mut dyn FnMut(&mut TrackerState, f32)| {
            let mut state = tracker.start();
            let (c, s) = (0.992_114_7f32, 0.125_333_2f32);
            let (mut re, mut im) = (1.0f32, 0.0f32);
            ticks(|| {
                for _ in 0..STEPS {
                    let r = c * re - s * im;
                    im = s * re + c * im;
                    re = r;
                    kernel(&mut state, re);
                }
            })
        };
        let t = run(&mut |state, y| {
            black_box(tracker_step(&tracker, state, &[y]));
        });
        let empty = run(&mut |state, y| {
            black_box(tracker_empty(&tracker, state, &[y]));
        });
        let baseline = run(&mut |_, y| {
            black_box(y);
        });
        let f: fn(
            &ModalTracker<f32, 4>,
            &mut TrackerState,
            &[f32],
        ) -> bushing::tracker::ModalReport = tracker_step;
        let line = Line {
            family: "tracker",
            name,
            n: 4,
            state_bytes: size_of_val(&tracker.start()),
            params_bytes: size_of_val(&tracker),
            function: f as usize,
        };
        report(&line, t, empty, baseline, STEPS);
    }

    #[inline(never)]
    fn oscillator_step(
        o: &IwanOscillator,
        s: &mut OscillatorState<f32, <(IwanBank<f32, 20>,) as Effect<f32>>::State>,
        f: f32,
    ) -> OscillatorStep<f32> {
        o.step(s, f)
    }

    /// The reference Iwan oscillator of seed 004 in free decay from 1.5.
    fn oscillator() {
        let Ok(osc) = iwan_oscillator() else { fail() };
        let mut s = osc.state_at(1.5, 0.0, 0.0);
        let t = ticks(|| {
            for _ in 0..STEPS {
                black_box(oscillator_step(&osc, &mut s, black_box(0.0)));
            }
        });
        let baseline = ticks(|| {
            for _ in 0..STEPS {
                black_box(black_box(0.0f32));
            }
        });
        let line = Line {
            family: "oscillator",
            name: "iwan-20/newmark",
            n: 20,
            state_bytes: size_of_val(&s),
            params_bytes: size_of_val(&osc),
            function: oscillator_step as *const () as usize,
        };
        report(&line, t, baseline, baseline, STEPS);
    }

    #[inline(never)]
    fn sine_step(t: &SineTracker<f32>, s: &mut SineState<f32>, y: f32) -> Result<f32, Refused> {
        t.step(s, y)
    }

    #[inline(never)]
    fn modulus_step(
        t: &ModulusTracker<f32>,
        s: &mut ModulusState<f32>,
        x: f32,
        f: f32,
    ) -> Option<Modulus<f32>> {
        let _ = t.step(s, x, f);
        t.modulus(s)
    }

    /// The sine tracker and the modulus tracker (x and F, K* on every
    /// step) at 50 samples per period.
    fn sine_trackers() {
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
        let signal = |kernel: &mut dyn FnMut(f32, f32)| {
            let (c, s) = (0.992_114_7f32, 0.125_333_2f32);
            let (mut re, mut im) = (1.0f32, 0.0f32);
            ticks(|| {
                for _ in 0..STEPS {
                    let r = c * re - s * im;
                    im = s * re + c * im;
                    re = r;
                    kernel(re, im);
                }
            })
        };
        let baseline = signal(&mut |re, im| {
            black_box((re, im));
        });
        let mut state = tracker.start();
        let t = signal(&mut |re, _| {
            let _ = black_box(sine_step(&tracker, &mut state, re));
        });
        let line = Line {
            family: "sine-tracker",
            name: "sine/2-states",
            n: 2,
            state_bytes: size_of_val(&state),
            params_bytes: size_of_val(&tracker),
            function: sine_step as *const () as usize,
        };
        report(&line, t, baseline, baseline, STEPS);
        let mut state = modulus.start();
        let t = signal(&mut |re, im| {
            black_box(modulus_step(&modulus, &mut state, re, 0.9 * re - 0.2 * im));
        });
        let line = Line {
            family: "sine-tracker",
            name: "modulus/x-and-f",
            n: 4,
            state_bytes: size_of_val(&state),
            params_bytes: size_of_val(&modulus),
            function: modulus_step as *const () as usize,
        };
        report(&line, t, baseline, baseline, STEPS);
    }

    /// A short fixed-capacity name.
    fn heapless_name() -> Name {
        Name {
            bytes: [0; 48],
            len: 0,
        }
    }

    /// A kernel name built from parts (no allocation).
    struct Name {
        bytes: [u8; 48],
        len: usize,
    }

    impl Name {
        fn push(&mut self, s: &str) {
            for &b in s.as_bytes() {
                if let Some(slot) = self.bytes.get_mut(self.len) {
                    *slot = b;
                    self.len += 1;
                }
            }
        }
        fn as_str(&self) -> &str {
            let bytes = self.bytes.get(..self.len).unwrap_or(&[]);
            core::str::from_utf8(bytes).unwrap_or("?")
        }
    }

    #[entry]
    fn main() -> ! {
        let Some(p) = cortex_m::Peripherals::take() else {
            fail()
        };
        let mut syst = p.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();

        let xs = sine::<STEPS>(AMPLITUDE, PERIOD);
        let Ok(poly) = polynomial() else { fail() };
        let ds = drives(&poly, &xs);
        let baseline = ticks(|| {
            for d in &ds {
                black_box(black_box(d));
            }
        });
        let xs_baseline = ticks(|| {
            for x in &xs {
                black_box(*black_box(x));
            }
        });
        hprintln!(
            "# kernel cost, {} calls each, sine {} mm over {} samples, dt = {} s",
            STEPS,
            AMPLITUDE,
            PERIOD,
            DT
        );

        maxwell::<1, Plain<f32>>("plain", &ds, baseline);
        maxwell::<2, Plain<f32>>("plain", &ds, baseline);
        maxwell::<4, Plain<f32>>("plain", &ds, baseline);
        maxwell::<8, Plain<f32>>("plain", &ds, baseline);
        maxwell::<16, Plain<f32>>("plain", &ds, baseline);
        maxwell::<1, Multiplied<f32>>("multiplied", &ds, baseline);
        maxwell::<2, Multiplied<f32>>("multiplied", &ds, baseline);
        maxwell::<4, Multiplied<f32>>("multiplied", &ds, baseline);
        maxwell::<8, Multiplied<f32>>("multiplied", &ds, baseline);
        maxwell::<16, Multiplied<f32>>("multiplied", &ds, baseline);
        maxwell::<1, Compensated<f32>>("compensated", &ds, baseline);
        maxwell::<2, Compensated<f32>>("compensated", &ds, baseline);
        maxwell::<4, Compensated<f32>>("compensated", &ds, baseline);
        maxwell::<8, Compensated<f32>>("compensated", &ds, baseline);
        maxwell::<16, Compensated<f32>>("compensated", &ds, baseline);

        iwan::<1>(&ds, baseline);
        iwan::<2>(&ds, baseline);
        iwan::<4>(&ds, baseline);
        iwan::<8>(&ds, baseline);
        iwan::<16>(&ds, baseline);
        iwan::<32>(&ds, baseline);

        for form in XfForm::ALL {
            let Ok(bank) = XfBank::<f32, 1>::new(form, &[XfSpec::hz(5.0, 0.1, 0.02)], DT) else {
                fail()
            };
            let name = match form {
                XfForm::Midpoint => "midpoint",
                XfForm::ExactRamp => "exact-ramp",
            };
            effect("xf", name, 1, &bank, &ds, baseline);
        }

        let Ok(b) = Bushing::new(poly, ()) else {
            fail()
        };
        whole("backbone", "polynomial-4", 1, &b, &xs, xs_baseline);
        let Ok(spl) = spline() else { fail() };
        let Ok(b) = Bushing::new(spl, ()) else { fail() };
        whole("backbone", "spline-8", 1, &b, &xs, xs_baseline);
        let Ok(b) = default_bushing() else { fail() };
        whole(
            "bushing",
            "default/spline+4maxwell+3jenkins",
            7,
            &b,
            &xs,
            xs_baseline,
        );
        let Ok(b) = sts16() else { fail() };
        whole("sts", "stack-16", 16, &b, &xs, xs_baseline);

        grunwald_cost::<16>(&xs, xs_baseline);
        grunwald_cost::<64>(&xs, xs_baseline);
        grunwald_cost::<256>(&xs, xs_baseline);

        // Friction and smooth hysteresis cells on the polynomial backbone.
        for (alpha, name) in [(1.0, "dahl/alpha-1"), (0.5, "dahl/alpha-0.5")] {
            let Ok(b) = dahl(alpha) else { fail() };
            whole("friction", name, 1, &b, &xs, xs_baseline);
        }
        for (n, name) in [(2.0, "bouc-wen/n-2"), (8.0, "bouc-wen/n-8")] {
            let Ok(b) = bouc_wen(n) else { fail() };
            whole("friction", name, 1, &b, &xs, xs_baseline);
        }
        let Ok(b) = berg() else { fail() };
        whole("friction", "berg", 1, &b, &xs, xs_baseline);
        let Ok(bank) = IwanSliders::<f32, 16>::new(&jenkins::<16>(), 150.0) else {
            fail()
        };
        effect("iwan", "slider/log", 16, &bank, &ds, baseline);
        for form in XfForm::ALL {
            let Ok(b) = xf2(form) else { fail() };
            let name = match form {
                XfForm::Midpoint => "bushing/midpoint-2",
                XfForm::ExactRamp => "bushing/exact-ramp-2",
            };
            whole("xf", name, 2, &b, &xs, xs_baseline);
        }
        let Ok(b) = composite() else { fail() };
        whole(
            "bushing",
            "final/poly+3maxwell+3jenkins+1xf",
            7,
            &b,
            &xs,
            xs_baseline,
        );
        oscillator();
        sine_trackers();

        tracker("ekf/1-mode-1-acc", Filter::Ekf);
        tracker("ukf/1-mode-1-acc", Filter::Ukf(UtParams::default()));

        // Re-tuning 8 running cells to a new temperature: exponentials in
        // f32 by libm or micromath.
        let Ok(mut bank) = maxwell_bank::<8, Plain<f32>>(MaxwellForm::RateExactRamp) else {
            fail()
        };
        for (name, micromath) in [("retune-8/libm", false), ("retune-8/micromath", true)] {
            let t = ticks(|| {
                for k in 0..STEPS / 10 {
                    let a_t = 1.0 + black_box(k as f32) * 1e-2;
                    let _ = black_box(if micromath {
                        bank.retune::<MicromathExp>(a_t)
                    } else {
                        bank.retune::<LibmExp>(a_t)
                    });
                }
            });
            let line = Line {
                family: "retune",
                name,
                n: 8,
                state_bytes: 0,
                params_bytes: size_of_val(&bank),
                function: 0,
            };
            report(&line, t, 0, 0, STEPS / 10);
        }
        debug::exit(debug::EXIT_SUCCESS);
        loop {
            cortex_m::asm::nop();
        }
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
        "kernel-cost is firmware: cargo run --release -p bushing-boards --target thumbv7em-none-eabihf --bin kernel-cost"
    );
}
