//! Guest instructions per call of each kernel's public step, for the
//! accuracy-cost report (`bushing-sim accuracy-cost`).
//!
//! Every kernel is called through an `#[inline(never)]` function whose body
//! is the library's public call (`Effect::step`, `Bushing::step`,
//! `ModalTracker::step`, ...), and every one is measured by the same
//! harness, `probe::measure`: the kernel, then a stand-in of the same
//! signature, then the idle harness, each in a window of its own. The
//! kernel less its stand-in (`net`) is what the kernel adds to a control
//! loop; less the idle harness (`per_call`), the whole call. The counts are
//! read from SysTick under QEMU `-icount shift=0` (one tick per 40
//! instructions), and exactly from the windows by the `bushing-qemu-mix`
//! plugin.
//!
//! With the feature `headline-only` the firmware measures only the
//! report's headline kernels: a much smaller binary, in which the same
//! kernels must cost the same (the report's "Harness" section).
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

    use bushing::six_dof::{Connectivity, Loads, Pose, SixDofState};
    use bushing::tracker::{
        Channel, Modulus, ModulusSpec, ModulusState, ModulusTracker, Refused, SineSpec, SineState,
        SineTracker,
    };
    use bushing::tracker::{
        Filter, Measured, ModalReport, ModalTracker, ModeInit, SensorFit, SensorSpec, Tuning,
        UtParams, fit_first_period,
    };
    use bushing::{
        Accumulator, Backbone, Bushing, BushingState, Compensated, Drive, Effect, EffectOutput,
        LibmExp, MaxwellForm, MicromathExp, Multiplied, Plain, Q16, Real, XfBank, XfForm, XfSpec,
    };
    use bushing::{
        Exponentials, IwanBank, IwanSliders, MaxwellBank, OscillatorState, OscillatorStep,
        ShiftFactor,
    };
    use bushing_boards::probe::{self, INSTRUCTIONS_PER_TICK, Span, measure_three};
    use bushing_kernels::input::{
        AMPLITUDE, Input, NOISE_CORNER, NOISE_RMS, NOISE_SEED, PERIOD, SMALL,
    };
    use bushing_kernels::{
        DT, IwanOscillator, MountEffects, berg, bouc_wen, composite, dahl, default_bushing, drives,
        engine_mount, grunwald, iwan_bank, iwan_oscillator, jenkins, maxwell_bank,
        mount_motion_scaled, mount_noise, polynomial, spline, sts16, xf2,
    };
    use cortex_m_rt::entry;
    use cortex_m_semihosting::hprintln;
    use panic_semihosting as _;

    const STEPS: usize = 2000;
    /// The input of the kernels that take no signal (re-tuning, the WLF
    /// factor, the first-period fit): one fixed set of arguments.
    const OWN: &str = "own";

    /// What the measurements on one input share: the displacements and
    /// the drives the polynomial backbone gives for them.
    struct Run<'a, T> {
        input: &'static str,
        xs: &'a [T],
        drives: &'a [Drive<T>],
    }

    /// Measures `each` on every input, in number type `T`.
    fn on_every_input<T: Real>(mut each: impl FnMut(&Run<'_, T>)) {
        let Ok(poly) = polynomial::<T>() else { fail() };
        for input in Input::ALL {
            let xs = input.xs::<T, STEPS>();
            let ds = drives(&poly, &xs);
            each(&Run {
                input: input.name(),
                xs: &xs,
                drives: &ds,
            });
        }
    }

    /// The core the lines name: `BUSHING_KERNEL_TARGET` at build time
    /// (`m7` for the M4F target built for the Cortex-M7, which the target
    /// triple does not tell apart), else the triple's.
    const TARGET: &str = match option_env!("BUSHING_KERNEL_TARGET") {
        Some(t) => t,
        None if cfg!(target_abi = "eabihf") => "m4f",
        None => "m3",
    };

    /// What one measurement printed.
    struct Line<'a> {
        /// Number type as the report names it (`f32`, `f64`, `fixed`).
        number: &'a str,
        /// The input's name ([`Input`], or [`OWN`]).
        input: &'a str,
        family: &'a str,
        name: &'a str,
        n: usize,
        state_bytes: usize,
        params_bytes: usize,
        function: usize,
    }

    /// Prints a line from the windows of `probe::measure_three` over
    /// `calls` calls: the kernel (`t`), its stand-in of the same signature
    /// (`empty`) and the idle harness (`baseline`). `per_call` counts the
    /// call, the return and the harness's dispatch and use of the result;
    /// `net` only what the kernel itself adds (what it costs inlined into a
    /// control loop).
    fn report(line: &Line<'_>, [t, empty, baseline]: [Span; 3], calls: usize) {
        let tenths = |ticks: u32| ticks * INSTRUCTIONS_PER_TICK * 10 / calls.max(1) as u32;
        let gross = tenths(t.ticks.saturating_sub(baseline.ticks));
        let net = tenths(t.ticks.saturating_sub(empty.ticks));
        let window = |s: Span| s.window.map_or(-1, |w| w as i64);
        hprintln!(
            "kernel target={} type={} family={} name={} n={} input={} per_call={}.{} net={}.{} state_bytes={} params_bytes={} fn={:#010x} calls={} windows={},{},{}",
            TARGET,
            line.number,
            line.family,
            line.name,
            line.n,
            line.input,
            gross / 10,
            gross % 10,
            net / 10,
            net % 10,
            line.state_bytes,
            line.params_bytes,
            line.function & !1,
            calls,
            window(t),
            window(empty),
            window(baseline)
        );
    }

    #[inline(never)]
    fn effect_step<T: Real, E: Effect<T>>(e: &E, s: &mut E::State, d: &Drive<T>) -> E::Report {
        e.step(s, d)
    }

    /// The harness's stand-in for [`effect_step`]: same arguments, a
    /// three-word result, one load.
    #[inline(never)]
    fn effect_empty<T: Real, E: Effect<T>>(
        _: &E,
        _: &mut E::State,
        d: &Drive<T>,
    ) -> EffectOutput<T> {
        EffectOutput {
            force: d.dx,
            tangent: d.dx,
            dissipated: d.dx,
        }
    }

    #[inline(never)]
    fn effect_force<T: Real, E: Effect<T>>(e: &E, s: &mut E::State, d: &Drive<T>) -> T {
        e.step_force(s, d)
    }

    /// The stand-in for [`effect_force`].
    #[inline(never)]
    fn force_empty<T: Real, E: Effect<T>>(_: &E, _: &mut E::State, d: &Drive<T>) -> T {
        d.dx
    }

    /// Prints the cost of `kernel` called on `e` over `drives` from a
    /// rested state, net of `empty` (a stand-in with the same signature).
    fn effect_cost<T: Real, E: Effect<T>, R>(
        (family, name, n): (&str, &str, usize),
        e: &E,
        run: &Run<'_, T>,
        kernel: fn(&E, &mut E::State, &Drive<T>) -> R,
        empty: fn(&E, &mut E::State, &Drive<T>) -> R,
    ) {
        let spans = measure_three(e, || e.rest(T::ZERO), run.drives, kernel, empty);
        let line = Line {
            number: number_name::<T>(),
            input: run.input,
            family,
            name,
            n,
            state_bytes: size_of_val(&e.rest(T::ZERO)),
            params_bytes: size_of_val(e),
            function: kernel as usize,
        };
        report(&line, spans, run.drives.len());
    }

    /// Cost of one `Effect::step_force` of `e` over `drives` (the state
    /// advanced, the force returned; no energy, no tangent).
    fn force_only<T: Real, E: Effect<T>>(label: (&str, &str, usize), e: &E, run: &Run<'_, T>) {
        let kernel = effect_force::<T, E>;
        effect_cost(label, e, run, kernel, force_empty::<T, E>);
    }

    /// Cost of one `Effect::step` of `e` over `drives`.
    fn effect<T: Real, E: Effect<T, Report = EffectOutput<T>>>(
        label: (&str, &str, usize),
        e: &E,
        run: &Run<'_, T>,
    ) {
        let kernel = effect_step::<T, E>;
        effect_cost(label, e, run, kernel, effect_empty::<T, E>);
    }

    /// One `Bushing::step`, returning what a rig loop reads: force,
    /// tangent and dissipated energy (the per-branch reports are dropped).
    #[inline(never)]
    fn bushing_step<T: Real, B: Backbone<T>, E: Effect<T>>(
        b: &Bushing<T, B, E>,
        s: &mut BushingState<T, E::State>,
        x: &T,
    ) -> [T; 3] {
        let o = b.step(s, *x);
        [o.force, o.tangent, o.dissipated]
    }

    /// The stand-in for [`bushing_step`].
    #[inline(never)]
    fn bushing_empty<T: Real, B: Backbone<T>, E: Effect<T>>(
        _: &Bushing<T, B, E>,
        _: &mut BushingState<T, E::State>,
        x: &T,
    ) -> [T; 3] {
        [*x, *x, *x]
    }

    /// Cost of one `Bushing::step` of `b` over `xs` (force, tangent and
    /// dissipated energy all returned).
    fn whole<T: Real, B: Backbone<T>, E: Effect<T>>(
        (family, name, n): (&str, &str, usize),
        b: &Bushing<T, B, E>,
        input: &Run<'_, T>,
    ) {
        let xs = input.xs;
        type Kernel<T, B, E> =
            fn(&Bushing<T, B, E>, &mut BushingState<T, <E as Effect<T>>::State>, &T) -> [T; 3];
        let f: Kernel<T, B, E> = bushing_step::<T, B, E>;
        let spans = measure_three(b, || b.state_at(T::ZERO), xs, f, bushing_empty::<T, B, E>);
        let line = Line {
            number: number_name::<T>(),
            input: input.input,
            family,
            name,
            n,
            state_bytes: size_of_val(&b.state_at(T::ZERO)),
            params_bytes: size_of_val(b),
            function: f as usize,
        };
        report(&line, spans, xs.len());
    }

    /// The number type as the report names it: Q16 (I16F16) is `fixed`.
    fn number_name<T: Real>() -> &'static str {
        match T::NAME {
            "I16F16" => "fixed",
            other => other,
        }
    }

    /// Every Maxwell form with `N` cells and storage `A` (named `storage`).
    fn maxwell<T: Real, const N: usize, A: Accumulator<T>>(storage: &str, run: &Run<'_, T>) {
        for form in MaxwellForm::ALL {
            maxwell_form::<T, N, A>(form, storage, run);
        }
    }

    /// One Maxwell form with `N` cells and storage `A`: the whole step and
    /// the force alone.
    fn maxwell_form<T: Real, const N: usize, A: Accumulator<T>>(
        form: MaxwellForm,
        storage: &str,
        run: &Run<'_, T>,
    ) {
        let Ok(bank) = maxwell_bank::<T, N, A>(form) else {
            fail()
        };
        let mut name = heapless_name();
        name.push(form.name());
        name.push("/");
        name.push(storage);
        effect(("maxwell", name.as_str(), N), &bank, run);
        force_only(("maxwell-force", name.as_str(), N), &bank, run);
    }

    /// Maxwell banks of 1 to 16 cells in every storage.
    fn maxwell_orders<T: Real>(run: &Run<'_, T>) {
        maxwell::<T, 1, Plain<T>>("plain", run);
        maxwell::<T, 2, Plain<T>>("plain", run);
        maxwell::<T, 4, Plain<T>>("plain", run);
        maxwell::<T, 8, Plain<T>>("plain", run);
        maxwell::<T, 16, Plain<T>>("plain", run);
        maxwell::<T, 1, Multiplied<T>>("multiplied", run);
        maxwell::<T, 2, Multiplied<T>>("multiplied", run);
        maxwell::<T, 4, Multiplied<T>>("multiplied", run);
        maxwell::<T, 8, Multiplied<T>>("multiplied", run);
        maxwell::<T, 16, Multiplied<T>>("multiplied", run);
        maxwell::<T, 1, Compensated<T>>("compensated", run);
        maxwell::<T, 2, Compensated<T>>("compensated", run);
        maxwell::<T, 4, Compensated<T>>("compensated", run);
        maxwell::<T, 8, Compensated<T>>("compensated", run);
        maxwell::<T, 16, Compensated<T>>("compensated", run);
    }

    fn iwan<T: Real, const N: usize>(run: &Run<'_, T>) {
        let Ok(bank) = iwan_bank::<T, N>() else {
            fail()
        };
        effect(("iwan", "clamp/log", N), &bank, run);
    }

    /// Iwan banks of 1 to 64 cells.
    fn iwan_orders<T: Real>(run: &Run<'_, T>) {
        iwan::<T, 1>(run);
        iwan::<T, 2>(run);
        iwan::<T, 4>(run);
        iwan::<T, 8>(run);
        iwan::<T, 16>(run);
        iwan::<T, 32>(run);
        iwan::<T, 64>(run);
    }

    /// The kernels measured in every number type: Maxwell, Iwan and the
    /// default bushing, over the same sine.
    fn in_type<T: Real>() {
        let Ok(b) = default_bushing::<T>() else {
            fail()
        };
        on_every_input::<T>(|run| {
            maxwell_orders(run);
            iwan_orders(run);
            whole(("bushing", "default/spline+4maxwell+3jenkins", 7), &b, run);
        });
    }

    type Mount = bushing_kernels::Mount<f32>;
    type MountState = SixDofState<f32, <MountEffects<f32> as Effect<f32>>::State>;

    /// One 6-DOF step, returning the node loads.
    #[inline(never)]
    fn six_dof_step(b: &Mount, s: &mut MountState, nodes: &[Pose<f32>; 2]) -> Loads<f32> {
        b.step(s, &nodes[0], &nodes[1]).loads
    }

    /// The stand-in for [`six_dof_step`].
    #[inline(never)]
    fn six_dof_empty(_: &Mount, _: &mut MountState, nodes: &[Pose<f32>; 2]) -> Loads<f32> {
        let p = [nodes[0].position, nodes[1].position];
        Loads {
            force: p,
            moment: p,
        }
    }

    /// One 6-DOF engine mount (six 1D laws of 2 Maxwell and 3 Jenkins
    /// cells) in each connectivity, over its motion: the mount's cycle (up
    /// to 1 mm and 0.02 rad), the same at 0.005 of it, or band-limited
    /// noise (0.5 mm and 0.01 rad RMS per axis).
    fn six_dof() {
        const N: usize = 100;
        for input in Input::ALL {
            let motion = match input {
                Input::LargeSine => mount_motion_scaled::<f32, N>(1.0),
                Input::SmallSine => mount_motion_scaled::<f32, N>(SMALL / AMPLITUDE),
                Input::Noise => mount_noise::<f32, N>(NOISE_RMS / AMPLITUDE * 2.0, NOISE_SEED),
            };
            six_dof_on(input, &motion);
        }
    }

    /// [`six_dof`] on one motion.
    fn six_dof_on<const N: usize>(input: Input, motion: &[[Pose<f32>; 2]; N]) {
        for (connectivity, name) in [
            (Connectivity::Attached, "mount/attached"),
            (Connectivity::Invariant, "mount/invariant"),
        ] {
            let Ok(b) = engine_mount::<f32>(connectivity) else {
                fail()
            };
            let Some([n1, n2]) = motion.first() else {
                fail()
            };
            let spans = measure_three(
                &b,
                || b.state_at(n1, n2),
                motion,
                six_dof_step,
                six_dof_empty,
            );
            let line = Line {
                number: "f32",
                input: input.name(),
                family: "six-dof",
                name,
                n: 6,
                state_bytes: size_of_val(&b.state_at(n1, n2)),
                params_bytes: size_of_val(&b),
                function: six_dof_step as *const () as usize,
            };
            report(&line, spans, N);
        }
    }

    fn grunwald_cost<const N: usize>(run: &Run<'_, f32>) {
        let Ok(b) = grunwald::<N>() else { fail() };
        whole(("grunwald", "bushing/alpha-0.5", N), &b, run);
    }

    type TrackerState<const N: usize> = bushing::tracker::ModalState<f32, N>;
    type TrackerStep<const N: usize, const S: usize, const M: usize> =
        fn(&ModalTracker<f32, N, M>, &mut TrackerState<N>, &[f32; S]) -> ModalReport;

    #[inline(never)]
    fn tracker_step<const N: usize, const S: usize, const M: usize>(
        t: &ModalTracker<f32, N, M>,
        s: &mut TrackerState<N>,
        y: &[f32; S],
    ) -> ModalReport {
        t.step(s, y)
    }

    /// The stand-in for [`tracker_step`].
    #[inline(never)]
    fn tracker_empty<const N: usize, const S: usize, const M: usize>(
        _: &ModalTracker<f32, N, M>,
        _: &mut TrackerState<N>,
        y: &[f32; S],
    ) -> ModalReport {
        ModalReport {
            accepted: u8::from(y.first().is_some_and(|x| *x > 0.0)),
            ..ModalReport::default()
        }
    }

    /// One tracker update (predict, then every sensor's scalar update) on a
    /// 20 Hz sine at 1 kHz seen by `S` accelerometers with mode-shape-like
    /// factors, `N` states, `M` modes fixed at compile time (0: the number
    /// of `modes`, given at run time).
    fn tracker<const N: usize, const S: usize, const M: usize>(
        name: &str,
        filter: Filter,
        modes: &[ModeInit],
    ) {
        let sensors = [SensorSpec {
            measured: Measured::Acceleration,
            noise: 0.01,
        }; S];
        let amplitudes = [(1.0, 0.0); 8];
        let Some(amplitudes) = amplitudes.get(..modes.len() * S) else {
            fail()
        };
        let Ok(tracker) = ModalTracker::<f32, N, M>::new(
            1e-3,
            &sensors,
            modes,
            amplitudes,
            &Tuning::default(),
            filter,
        ) else {
            fail()
        };
        // The accelerations: a 20 Hz sine of amplitude 1 at 1 kHz, the
        // same at 0.005 (below the sensors' noise: the tracker fades the
        // mode), or band-limited noise; times mode-shape-like factors.
        for input in Input::ALL {
            let xs = input.signal::<STEPS>(1.0, 50);
            let shape = [1.0f32, 2.0, -1.8];
            let samples: [[f32; S]; STEPS] = core::array::from_fn(|k| {
                let x = xs.get(k).copied().unwrap_or(0.0);
                core::array::from_fn(|i| x * shape[i % 3])
            });
            let f: TrackerStep<N, S, M> = tracker_step::<N, S, M>;
            let spans = measure_three(
                &tracker,
                || tracker.start(),
                &samples,
                f,
                tracker_empty::<N, S, M>,
            );
            let line = Line {
                number: "f32",
                input: input.name(),
                family: "tracker",
                name,
                n: N,
                state_bytes: size_of_val(&tracker.start()),
                params_bytes: size_of_val(&tracker),
                function: f as usize,
            };
            report(&line, spans, STEPS);
        }
    }

    type OscillatorStateOf = OscillatorState<f32, <(IwanBank<f32, 20>,) as Effect<f32>>::State>;

    #[inline(never)]
    fn oscillator_step(
        o: &IwanOscillator,
        s: &mut OscillatorStateOf,
        f: &f32,
    ) -> OscillatorStep<f32> {
        o.step(s, *f)
    }

    /// The stand-in for [`oscillator_step`].
    #[inline(never)]
    fn oscillator_empty(
        _: &IwanOscillator,
        _: &mut OscillatorStateOf,
        f: &f32,
    ) -> OscillatorStep<f32> {
        OscillatorStep {
            p: *f,
            v: *f,
            a: *f,
            force: *f,
            dissipated: *f,
            work: *f,
            iterations: 0,
            converged: true,
        }
    }

    /// The reference Iwan oscillator of seed 004 from rest under a force:
    /// a sine of 9 over 100 steps (1.5 times the backbone's stiffness of 6,
    /// a static displacement of 1.5 inside the cells' slip distances of 0.2
    /// to 2), the same at 0.005 of it, or band-limited noise.
    fn oscillator() {
        let Ok(osc) = iwan_oscillator() else { fail() };
        for input in Input::ALL {
            let fs = input.signal::<STEPS>(9.0, PERIOD);
            let rest = || osc.state_at(0.0, 0.0, 0.0);
            let spans = measure_three(&osc, rest, &fs, oscillator_step, oscillator_empty);
            let line = Line {
                number: "f32",
                input: input.name(),
                family: "oscillator",
                name: "iwan-20/newmark",
                n: 20,
                state_bytes: size_of_val(&rest()),
                params_bytes: size_of_val(&osc),
                function: oscillator_step as *const () as usize,
            };
            report(&line, spans, STEPS);
        }
    }

    /// One sample of the sine tracker: the displacement (the force of
    /// the pair is the modulus tracker's).
    #[inline(never)]
    fn sine_step(
        t: &SineTracker<f32>,
        s: &mut SineState<f32>,
        &(y, _): &(f32, f32),
    ) -> Result<f32, Refused> {
        t.step(s, y)
    }

    /// The stand-in for [`sine_step`].
    #[inline(never)]
    fn sine_empty(
        _: &SineTracker<f32>,
        _: &mut SineState<f32>,
        &(y, _): &(f32, f32),
    ) -> Result<f32, Refused> {
        Ok(y)
    }

    /// One displacement and force sample of the modulus tracker, and K*.
    #[inline(never)]
    fn modulus_step(
        t: &ModulusTracker<f32>,
        s: &mut ModulusState<f32>,
        &(x, f): &(f32, f32),
    ) -> Option<Modulus<f32>> {
        let _ = t.step(s, x, f);
        t.modulus(s)
    }

    /// The stand-in for [`modulus_step`].
    #[inline(never)]
    fn modulus_empty(
        _: &ModulusTracker<f32>,
        _: &mut ModulusState<f32>,
        &(x, f): &(f32, f32),
    ) -> Option<Modulus<f32>> {
        Some(Modulus {
            storage: x,
            loss: f,
        })
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
        // The displacement: a 20 Hz sine of amplitude 1 at 1 kHz, the same
        // at 0.005 (below the channel's noise), or band-limited noise; the
        // force 0.9 x less 0.2 of the previous x.
        for input in Input::ALL {
            let xs = input.signal::<STEPS>(1.0, 50);
            let pairs: [(f32, f32); STEPS] = core::array::from_fn(|k| {
                let x = xs.get(k).copied().unwrap_or(0.0);
                let previous = k.checked_sub(1).and_then(|j| xs.get(j)).copied();
                (x, 0.9 * x - 0.2 * previous.unwrap_or(0.0))
            });
            let spans = measure_three(&tracker, || tracker.start(), &pairs, sine_step, sine_empty);
            let line = Line {
                number: "f32",
                input: input.name(),
                family: "sine-tracker",
                name: "sine/2-states",
                n: 2,
                state_bytes: size_of_val(&tracker.start()),
                params_bytes: size_of_val(&tracker),
                function: sine_step as *const () as usize,
            };
            report(&line, spans, STEPS);
            let spans = measure_three(
                &modulus,
                || modulus.start(),
                &pairs,
                modulus_step,
                modulus_empty,
            );
            let line = Line {
                number: "f32",
                input: input.name(),
                family: "sine-tracker",
                name: "modulus/x-and-f",
                n: 4,
                state_bytes: size_of_val(&modulus.start()),
                params_bytes: size_of_val(&modulus),
                function: modulus_step as *const () as usize,
            };
            report(&line, spans, STEPS);
        }
    }

    type Bank8 = MaxwellBank<f32, 8, Plain<f32>>;

    /// A per-call kernel taking a temperature-like scalar, its subject
    /// (a bank, a shift factor) as its state.
    type Call<S> = fn(&(), &mut S, &f32) -> bool;

    /// Re-tunes a running bank in place in f32 (16 exponentials by `E`).
    #[inline(never)]
    fn retune<E: Exponentials<f32>>(_: &(), bank: &mut Bank8, a_t: &f32) -> bool {
        bank.retune::<E>(*a_t).is_ok()
    }

    /// Re-tunes by rebuilding the cells from their specifications in f64
    /// (software double precision on these cores).
    #[inline(never)]
    fn retune_f64(_: &(), bank: &mut Bank8, a_t: &f32) -> bool {
        match bank.shifted(f64::from(*a_t)) {
            Ok(b) => {
                *bank = b;
                true
            }
            Err(_) => false,
        }
    }

    /// The WLF shift factor `a_T` at a temperature, in f64.
    #[inline(never)]
    fn wlf_f64(_: &(), wlf: &mut ShiftFactor, t: &f32) -> bool {
        black_box(wlf.at(f64::from(*t))).is_ok()
    }

    /// The WLF shift factor `a_T` at a temperature, in f32 by `E`.
    #[inline(never)]
    fn wlf_f32<E: Exponentials<f32>>(_: &(), wlf: &mut ShiftFactor, t: &f32) -> bool {
        black_box(wlf.at_in::<f32, E>(*t)).is_ok()
    }

    /// The stand-in for the calls above.
    #[inline(never)]
    fn call_empty<S>(_: &(), _: &mut S, x: &f32) -> bool {
        *x > 0.0
    }

    /// Calls of a [`Call`]: a tenth of the signal kernels' (each is dear).
    const CALLS: usize = STEPS / 10;

    /// Cost of `kernel` called with 1.0, 1.01, 1.02, ... plus `offset`, on
    /// a copy of `subject`.
    fn call_cost<S: Clone>(
        (family, name, n): (&str, &str, usize),
        subject: &S,
        offset: f32,
        kernel: Call<S>,
    ) {
        let xs: [f32; CALLS] = core::array::from_fn(|k| offset + 1.0 + k as f32 * 1e-2);
        let spans = measure_three(&(), || subject.clone(), &xs, kernel, call_empty::<S>);
        let line = Line {
            number: "f32",
            input: OWN,
            family,
            name,
            n,
            state_bytes: 0,
            params_bytes: size_of_val(subject),
            function: kernel as usize,
        };
        report(&line, spans, CALLS);
    }

    /// Re-tuning 8 running Maxwell cells to a new temperature, and the WLF
    /// shift factor that gives it, by libm and micromath in f32 and in f64.
    fn temperature() {
        let Ok(bank) = maxwell_bank::<f32, 8, Plain<f32>>(MaxwellForm::RateExactRamp) else {
            fail()
        };
        let f = ("retune", "retune-8/libm", 8);
        call_cost(f, &bank, 0.0, retune::<LibmExp>);
        let f = ("retune", "retune-8/micromath", 8);
        call_cost(f, &bank, 0.0, retune::<MicromathExp>);
        let f = ("retune", "retune-8/f64", 8);
        call_cost(f, &bank, 0.0, retune_f64);
        let Ok(wlf) = ShiftFactor::wlf(17.44, 51.6, 20.0) else {
            fail()
        };
        // Temperatures from 20 degC up.
        call_cost(("retune", "wlf/libm", 1), &wlf, 19.0, wlf_f32::<LibmExp>);
        call_cost(
            ("retune", "wlf/micromath", 1),
            &wlf,
            19.0,
            wlf_f32::<MicromathExp>,
        );
        call_cost(("retune", "wlf/f64", 1), &wlf, 19.0, wlf_f64);
    }

    #[inline(never)]
    fn fit(record: &[f64; 50], out: &mut [SensorFit; 1], _: &()) -> u32 {
        fit_first_period(1e-3, &[record], out).map_or(0, |f| f.iterations)
    }

    /// The stand-in for [`fit`].
    #[inline(never)]
    fn fit_empty(record: &[f64; 50], _: &mut [SensorFit; 1], _: &()) -> u32 {
        u32::from(record.first().is_some_and(|x| *x > 0.0))
    }

    /// Start values of the modal tracker: the least-squares fit of one
    /// noisy 50-sample pseudo-period, in f64 (software double precision on
    /// these cores).
    fn first_period_fit() {
        let mut record = [0.0f64; 50];
        let (c, s) = (0.992_114_701_314_478_f64, 0.125_333_233_564_304_2_f64);
        let (mut re, mut im) = (1.0f64, 0.0f64);
        for (k, x) in record.iter_mut().enumerate() {
            // A 1e-3 deterministic pseudo-noise, so that the fit iterates.
            *x = re + 1e-3 * ((k * 7919 % 13) as f64 - 6.0) / 6.0;
            let r = 0.999 * (c * re - s * im);
            im = 0.999 * (s * re + c * im);
            re = r;
        }
        let calls = [(); 10];
        let fresh = || [SensorFit::default()];
        let spans = measure_three(&record, fresh, &calls, fit, fit_empty);
        let line = Line {
            number: "f64",
            input: OWN,
            family: "tracker",
            name: "first-period-fit/50-samples",
            n: 50,
            state_bytes: 0,
            params_bytes: size_of_val(&record),
            function: fit as *const () as usize,
        };
        report(&line, spans, calls.len());
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

    /// The f32 kernels beyond those of [`in_type`], on one input.
    fn f32_kernels(run: &Run<'_, f32>) {
        for form in XfForm::ALL {
            let Ok(bank) = XfBank::<f32, 1>::new(form, &[XfSpec::hz(5.0, 0.1, 0.02)], DT) else {
                fail()
            };
            let name = match form {
                XfForm::Midpoint => "midpoint",
                XfForm::ExactRamp => "exact-ramp",
            };
            effect(("xf", name, 1), &bank, run);
        }

        let Ok(poly) = polynomial::<f32>() else {
            fail()
        };
        let Ok(b) = Bushing::new(poly, ()) else {
            fail()
        };
        whole(("backbone", "polynomial-4", 1), &b, run);
        let Ok(spl) = spline::<f32>() else { fail() };
        let Ok(b) = Bushing::new(spl, ()) else { fail() };
        whole(("backbone", "spline-8", 1), &b, run);
        let Ok(b) = sts16() else { fail() };
        whole(("sts", "stack-16", 16), &b, run);

        grunwald_cost::<16>(run);
        grunwald_cost::<64>(run);
        grunwald_cost::<256>(run);
        grunwald_cost::<1024>(run);

        // Friction and smooth hysteresis cells on the polynomial backbone.
        for (alpha, name) in [(1.0, "dahl/alpha-1"), (0.5, "dahl/alpha-0.5")] {
            let Ok(b) = dahl(alpha) else { fail() };
            whole(("friction", name, 1), &b, run);
        }
        for (n, name) in [(2.0, "bouc-wen/n-2"), (8.0, "bouc-wen/n-8")] {
            let Ok(b) = bouc_wen(n) else { fail() };
            whole(("friction", name, 1), &b, run);
        }
        let Ok(b) = berg() else { fail() };
        whole(("friction", "berg", 1), &b, run);
        let Ok(bank) = IwanSliders::<f32, 16>::new(&jenkins::<16>(), 150.0) else {
            fail()
        };
        effect(("iwan", "slider/log", 16), &bank, run);
        for form in XfForm::ALL {
            let Ok(b) = xf2(form) else { fail() };
            let name = match form {
                XfForm::Midpoint => "bushing/midpoint-2",
                XfForm::ExactRamp => "bushing/exact-ramp-2",
            };
            whole(("xf", name, 2), &b, run);
        }
        let Ok(b) = composite() else { fail() };
        whole(("bushing", "final/poly+3maxwell+3jenkins+1xf", 7), &b, run);
    }

    #[entry]
    fn main() -> ! {
        probe::start();
        hprintln!(
            "# kernel cost, {} calls each, dt = {} s; inputs: sine {} mm and {} mm over {} samples, band-limited noise {} mm RMS (corner {} of the rate, seed {})",
            STEPS,
            DT,
            AMPLITUDE,
            SMALL,
            PERIOD,
            NOISE_RMS,
            NOISE_CORNER,
            NOISE_SEED
        );

        // The modal tracker: one mode on one accelerometer (4 states), two
        // modes on three accelerometers (16 states), and the sizes between.
        let mode = ModeInit {
            frequency: 20.0,
            damping: 0.01,
        };
        if cfg!(feature = "headline-only") {
            headline(mode);
            probe::pass()
        }

        in_type::<f32>();
        in_type::<f64>();
        in_type::<Q16>();
        on_every_input::<f32>(f32_kernels);

        oscillator();
        six_dof();
        sine_trackers();
        let two = [
            mode,
            ModeInit {
                frequency: 51.0,
                damping: 0.005,
            },
        ];
        let ukf = Filter::Ukf(UtParams::default());
        // From 8 states on with the mode count fixed at compile time, the
        // form a firmware names; the 16 states also with it given at run
        // time, for comparison.
        tracker::<4, 1, 0>("ekf/1-mode-1-acc", Filter::Ekf, &[mode]);
        tracker::<4, 1, 0>("ukf/1-mode-1-acc", ukf, &[mode]);
        tracker::<16, 3, 2>("ekf/2-modes-3-acc", Filter::Ekf, &two);
        tracker::<16, 3, 2>("ukf/2-modes-3-acc", ukf, &two);
        tracker::<16, 3, 0>("ekf/2-modes-3-acc/modes-at-run-time", Filter::Ekf, &two);
        tracker::<16, 3, 0>("ukf/2-modes-3-acc/modes-at-run-time", ukf, &two);
        // The sizes between, for the growth of the cost with the states.
        tracker::<6, 2, 0>("ekf/1-mode-2-acc", Filter::Ekf, &[mode]);
        tracker::<6, 2, 0>("ukf/1-mode-2-acc", ukf, &[mode]);
        tracker::<8, 1, 2>("ekf/2-modes-1-acc", Filter::Ekf, &two);
        tracker::<8, 1, 2>("ukf/2-modes-1-acc", ukf, &two);
        tracker::<12, 2, 2>("ekf/2-modes-2-acc", Filter::Ekf, &two);
        tracker::<12, 2, 2>("ukf/2-modes-2-acc", ukf, &two);

        first_period_fit();
        temperature();
        probe::pass()
    }

    /// The report's headline kernels alone, in f32: the whole binary of
    /// the `headline-only` build.
    fn headline(mode: ModeInit) {
        let Ok(b) = default_bushing::<f32>() else {
            fail()
        };
        on_every_input::<f32>(|run| {
            maxwell_form::<f32, 8, Plain<f32>>(MaxwellForm::RateExactRamp, "plain", run);
            iwan::<f32, 16>(run);
            whole(("bushing", "default/spline+4maxwell+3jenkins", 7), &b, run);
        });
        tracker::<4, 1, 0>("ekf/1-mode-1-acc", Filter::Ekf, &[mode]);
        six_dof();
    }

    fn fail() -> ! {
        probe::fail("parameters refused")
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "kernel-cost is firmware: cargo run --release -p bushing-boards --target thumbv7em-none-eabihf --bin kernel-cost"
    );
}
