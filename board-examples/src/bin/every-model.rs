//! Every public model and tracker of the core, built and stepped: the
//! firmware of the panic-never link check (`--features panic-never`, see
//! `scripts/rig-loop.sh` and `docs/firmware.md` §5).
//!
//! Parameters and inputs pass through `core::hint::black_box`, so the
//! optimiser can fold neither a constructor's checks nor a step away, and
//! every output is folded into a per-model checksum. The image therefore
//! holds each model's construction (its f64 coefficient code and its
//! refusals), its `step` and `trial`, and its effect's `step_force`. One
//! line per model:
//!
//! ```text
//! every-model target=m4f type=f32 tracker=f32 steps=400
//! model backbone/polynomial type=f32 calls=1600 last=00000000c196c2b8 checksum=c6aaabded4b61480 faults=0x0 not_finite=0
//! ...
//! models 31 refused 0 faulted 0
//! memory flash 301620 static_ram 8 stack 43440
//! verdict pass
//! ```
//!
//! `last` is the raw bits of the last force (of the first output of a
//! tracker): IEEE single for f32, the two's-complement Q16.16 word for Q16,
//! IEEE double for the f64 fit. The run exits with failure if a model
//! refuses its parameters (they are all valid), raises a fault flag or
//! gives a value that is not finite.
//!
//! Number types:
//!
//! - Cortex-M4F (`thumbv7em-none-eabihf`, mps2-an386): everything in f32.
//! - Cortex-M3 (`thumbv7m-none-eabi`, mps2-an385): every model generic over
//!   `Real` in [`Q16`](bushing::Q16), including those whose step calls libm
//!   through a conversion (x_f cells, STS, Dahl, Bouc-Wen, the 6-DOF
//!   bushing's angle), which `bushing::fixed` does not support for
//!   accuracy: they are linked to show that their Q16 path has no
//!   panicking branch. In f32 (software floating point) instead:
//!   - the oscillator: its Newmark coefficient β = dt²/4 is below the
//!     resolution of Q16 (2^-16) at any control rate (6e-8 at 2 kHz); it
//!     would round to 0 and the scheme would lose its implicit part;
//!   - the tracker (modal EKF and UKF, sine and modulus trackers, scalar
//!     unscented transform, `trig`, `fast`): its variances span many
//!     decades, which Q16 cannot hold (`bushing::fixed`);
//!   - `MaxwellBank::retune` with [`MicromathExp`], which gives
//!     exponentials for f32 only.
//!
//! The f64 helpers stay in f64 on both cores: the discretisations of
//! `discretize`, `ShiftFactor::at`, `MaxwellBank::shifted`, the responses
//! of the Maxwell bank and the Grünwald cell, the first-period fit of the
//! tracker and the relevance check.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::f64::consts::TAU;
    use core::fmt;
    use core::hint::black_box as bb;

    use bushing::discretize::{Placement, Segalman, iwan_from_relaxation, total_stiffness};
    use bushing::excitation::adc_code;
    use bushing::six_dof::Connectivity;
    use bushing::tracker::{
        Channel, Filter, FitError, Measured, ModalTracker, ModeInit, ModulusSpec, ModulusTracker,
        ScalarUt, SensorFit, SensorSpec, SineSpec, SineTracker, Tuning, UtParams,
        damping_from_frequency, damping_from_frequency_uniform, fast, fit_amplitudes,
        fit_first_period, frequency_from_damping_uniform, linearised_scalar, trig,
        unscented_scalar,
    };
    use bushing::xf::midpoint_saturation_ratio;
    use bushing::{
        Accumulator, Backbone, Berg, BoucWen, Bushing, Compensated, Dahl, Dashpot, Drive, Effect,
        Faults, FirstLoading, FractionalSpec, Grunwald, IwanBank, IwanSliders, KfTable, LibmExp,
        MaxwellBank, MaxwellForm, MicromathExp, MonotoneSpline, Multiplied, Oscillator, Param,
        ParamError, Plain, Polynomial, Real, ShiftFactor, Sts, TurningPoints, XfBank, XfForm,
        XfSpec,
    };
    use bushing_boards::rig::{
        ADC_BITS, AMPLITUDE_MM, LSB_MM, Monitor, RATE_HZ, Sample, TRACKER_NOISE_MM, rig_bushing,
        tracker_tuning,
    };
    use bushing_boards::{memory, probe};
    use bushing_kernels::{
        CELLS, DT, JENKINS, drives, engine_mount_scaled, jenkins, mount_motion, sine,
    };
    use cortex_m_rt::entry;
    use cortex_m_semihosting::hprintln;
    #[cfg(feature = "panic-never")]
    use panic_never as _;
    #[cfg(not(feature = "panic-never"))]
    use panic_semihosting as _;

    /// Working type of the models: `f32` with an FPU, `Q16` without.
    #[cfg(target_abi = "eabihf")]
    type Num = f32;
    #[cfg(not(target_abi = "eabihf"))]
    type Num = bushing::Q16;

    const TARGET: &str = if cfg!(target_abi = "eabihf") {
        "m4f"
    } else {
        "m3"
    };

    /// Steps per model: four periods of the input sine.
    const STEPS: usize = 400;
    /// Samples per period of the input sine.
    const PERIOD: usize = 100;

    /// What a model's run leaves: the calls counted, a hash of the bits of
    /// every output, the last force (or the tracker's first output), the
    /// fault flags and the count of values that were not finite.
    #[derive(Clone, Copy)]
    struct Tally {
        calls: u32,
        hash: u64,
        last: u64,
        faults: u8,
        not_finite: u32,
    }

    impl Tally {
        const EMPTY: Self = Self {
            calls: 0,
            hash: 0xcbf2_9ce4_8422_2325,
            last: 0,
            faults: 0,
            not_finite: 0,
        };

        /// Folds one word into the hash (FNV-1a on 64-bit words).
        fn word(&mut self, w: u64) {
            self.hash = (self.hash ^ w).wrapping_mul(0x0000_0100_0000_01b3);
        }

        /// Folds values into the hash.
        fn fold<T: Real>(&mut self, values: &[T]) {
            for v in values {
                self.word(v.bits());
                if !v.is_finite() {
                    self.not_finite = self.not_finite.saturating_add(1);
                }
            }
        }

        /// Folds one call's outputs; the first is the force.
        fn push<T: Real>(&mut self, values: &[T]) {
            self.fold(values);
            if let Some(f) = values.first() {
                self.last = f.bits();
            }
            self.calls = self.calls.saturating_add(1);
        }

        fn raise(mut self, faults: Faults) -> Self {
            self.faults |= faults.bits();
            self
        }

        /// This run followed by `other`.
        fn then(mut self, other: Self) -> Self {
            self.word(other.hash);
            self.calls = self.calls.saturating_add(other.calls);
            self.last = other.last;
            self.faults |= other.faults;
            self.not_finite = self.not_finite.saturating_add(other.not_finite);
            self
        }
    }

    /// Why a model could not be run: the parameter its constructor
    /// refused, or what else failed.
    #[derive(Clone, Copy)]
    enum Failure {
        Param(Param),
        Other(&'static str),
    }

    impl From<ParamError> for Failure {
        fn from(e: ParamError) -> Self {
            use ParamError as E;
            match e {
                E::NotFinite { param }
                | E::NotPositive { param, .. }
                | E::TooFew { param, .. }
                | E::TooMany { param, .. }
                | E::LengthMismatch { param, .. }
                | E::NotIncreasing { param }
                | E::Increasing { param }
                | E::OutOfRange { param, .. } => Self::Param(param),
                _ => Self::Other("parameters"),
            }
        }
    }

    impl From<FitError> for Failure {
        fn from(e: FitError) -> Self {
            match e {
                FitError::Param(p) => p.into(),
                _ => Self::Other("first-period fit"),
            }
        }
    }

    // Prints no floating-point number, which would link core's float
    // formatter (about 20 KB).
    impl fmt::Display for Failure {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            match self {
                Self::Param(p) => write!(f, "parameter {p}"),
                Self::Other(what) => f.write_str(what),
            }
        }
    }

    type Outcome = Result<Tally, Failure>;

    /// The input of every model in one number type: a 2 mm sine of
    /// [`PERIOD`] samples, as the drives the polynomial backbone gives it
    /// (each holds its displacement).
    struct Input<T> {
        drives: [Drive<T>; STEPS],
    }

    impl<T: Real> Input<T> {
        fn new() -> Result<Self, ParamError> {
            let drives = drives(&backbone()?, &sine::<T, STEPS>(bb(2.0), bb(PERIOD)));
            Ok(Self { drives })
        }

        /// The displacements.
        fn xs(&self) -> impl Iterator<Item = T> + '_ {
            self.drives.iter().map(|d| d.x)
        }
    }

    /// The backbone of the one-effect bushings: 150 N/mm, hardening by
    /// 4 N/mm³, on ±6 mm.
    fn backbone<T: Real>() -> Result<Polynomial<T, 4>, ParamError> {
        Polynomial::new(&bb([0.0, 150.0, 0.0, 4.0]), bb((-6.0, 6.0)))
    }

    /// Steps `b` over the input, every fourth step through `trial`, and folds
    /// the force, tangent, dissipated energy, elastic force and the
    /// effects' total force.
    fn run<T: Real, B: Backbone<T>, E: Effect<T>>(b: &Bushing<T, B, E>, input: &Input<T>) -> Tally {
        let mut state = b.state_at(T::ZERO);
        let mut t = Tally::EMPTY;
        for (k, x) in input.xs().enumerate() {
            let out = if k % 4 == 3 {
                let (out, next) = b.trial(&state, bb(x));
                state = next;
                out
            } else {
                b.step(&mut state, bb(x))
            };
            let effects = out.effects.map_or(T::ZERO, |r| E::total(&r).force);
            t.push(&[out.force, out.tangent, out.dissipated, out.elastic, effects]);
        }
        t.word(u64::from(state.rejected()));
        t.raise(state.faults())
    }

    /// Steps the effect alone over the drives with `Effect::step_force`.
    fn forces<T: Real, E: Effect<T>>(e: &E, drives: &[Drive<T>]) -> Tally {
        let mut state = e.rest(T::ZERO);
        let mut t = Tally::EMPTY;
        for d in drives {
            t.push(&[e.step_force(&mut state, bb(d))]);
        }
        t
    }

    /// `effects` on `backbone`: the effects alone through `step_force`,
    /// then the bushing over the input.
    fn bushing<T: Real, B: Backbone<T>, E: Effect<T>>(
        backbone: B,
        effects: E,
        input: &Input<T>,
    ) -> Outcome {
        let b = Bushing::new(backbone, effects)?;
        Ok(forces(b.effects(), &input.drives).then(run(&b, input)))
    }

    /// One effect on the polynomial backbone.
    fn single<T: Real, E: Effect<T>>(effect: E, input: &Input<T>) -> Outcome {
        bushing(backbone()?, (effect,), input)
    }

    /// One effect in each of `variants` (forms, exponents, first-loading
    /// rules), built by `build`, one after the other.
    fn each<T: Real, V: Copy, E: Effect<T>>(
        variants: &[V],
        input: &Input<T>,
        build: impl Fn(V) -> Result<E, ParamError>,
    ) -> Outcome {
        let mut t = Tally::EMPTY;
        for &v in variants {
            t = t.then(single(build(bb(v))?, input)?);
        }
        Ok(t)
    }

    // The effects, each built from black-boxed parameters.

    fn maxwell_bank<T: Real, A: Accumulator<T>>(
        form: MaxwellForm,
    ) -> Result<MaxwellBank<T, 4, A>, ParamError> {
        MaxwellBank::new(bb(form), &bb(CELLS), bb(DT))
    }

    fn iwan_bank<T: Real>() -> Result<IwanBank<T, 4>, ParamError> {
        IwanBank::new(&bb(JENKINS))
    }

    fn xf_bank<T: Real, const N: usize>(
        form: XfForm,
        cells: [XfSpec; N],
    ) -> Result<XfBank<T, N>, ParamError> {
        XfBank::new(bb(form), &bb(cells), bb(DT))
    }

    fn dashpot<T: Real>() -> Result<Dashpot<T>, ParamError> {
        Dashpot::new(bb(0.5), bb(DT))
    }

    fn sts<T: Real>(first: FirstLoading) -> Result<TurningPoints<Sts<T>, 8>, ParamError> {
        Ok(TurningPoints::new(Sts::new(bb(400.0), bb(300.0))?, first))
    }

    fn berg<T: Real>() -> Result<Berg<T>, ParamError> {
        Berg::new(bb(12.0), bb(0.05))
    }

    /// WLF shift factor of a natural rubber (T_0 = 20 °C, in kelvin).
    fn wlf() -> Result<ShiftFactor, ParamError> {
        ShiftFactor::wlf(bb(8.86), bb(101.6), bb(293.15))
    }

    /// 10 K below the reference of [`wlf`].
    const COLD_K: f64 = 283.15;

    // The models in the working type.

    fn polynomial<T: Real>(input: &Input<T>) -> Outcome {
        let linear = Polynomial::<T, 2>::linear(bb(150.0))?;
        Ok(bushing(linear, (), input)?.then(bushing(backbone()?, (), input)?))
    }

    fn spline<T: Real>(input: &Input<T>) -> Outcome {
        let spline = MonotoneSpline::<T, 6>::new(
            &bb([-4.0, -1.0, 0.0, 0.5, 2.0, 4.0]),
            &bb([-2500.0, -250.0, 0.0, 110.0, 600.0, 1900.0]),
        )?;
        bushing(spline, (), input)
    }

    fn maxwell<T: Real, A: Accumulator<T>>(input: &Input<T>) -> Outcome {
        each(&MaxwellForm::ALL, input, maxwell_bank::<T, A>)
    }

    fn iwan_clamp<T: Real>(input: &Input<T>) -> Outcome {
        single(iwan_bank()?, input)
    }

    fn iwan_sliders<T: Real>(input: &Input<T>) -> Outcome {
        single(IwanSliders::<T, 4>::new(&bb(JENKINS), bb(150.0))?, input)
    }

    fn xf<T: Real>(input: &Input<T>) -> Outcome {
        let cells = [XfSpec::hz(0.005, 0.2, 0.02), XfSpec::hz(5.0, 0.1, 0.002)];
        let mut t = each(&XfForm::ALL, input, |form| xf_bank(form, cells))?;
        t.fold(&[midpoint_saturation_ratio(bb(0.5))]);
        Ok(t)
    }

    fn dahl<T: Real>(input: &Input<T>) -> Outcome {
        each(&[1.0, 0.5], input, |alpha| {
            Dahl::new(bb(200.0), bb(10.0), alpha)
        })
    }

    fn bouc_wen<T: Real>(input: &Input<T>) -> Outcome {
        let cell = BoucWen::<T>::new(bb(20.0), bb(10.0), bb(60.0), bb(20.0), bb(2.0))?;
        let mut t = single(cell, input)?;
        t.fold(&[cell.ultimate_force()]);
        Ok(t)
    }

    fn berg_cell<T: Real>(input: &Input<T>) -> Outcome {
        single(berg()?, input)
    }

    fn grunwald<T: Real>(input: &Input<T>) -> Outcome {
        let spec = bb(FractionalSpec::hz(1.0, 0.5, 0.6));
        let cell = Grunwald::<T, 64>::new(spec, bb(DT))?;
        let (storage, loss) = cell.branch_response(bb(TAU));
        let leak = cell.dc_leak();
        let mut t = single(cell, input)?;
        t.fold(&[storage, loss, leak]);
        Ok(t)
    }

    fn dashpot_cell<T: Real>(input: &Input<T>) -> Outcome {
        single(dashpot()?, input)
    }

    fn sts_stack<T: Real>(input: &Input<T>) -> Outcome {
        each(&[FirstLoading::Masing, FirstLoading::Ignored], input, sts)
    }

    fn kf_table<T: Real>(input: &Input<T>) -> Outcome {
        let law = KfTable::<T, 4>::new(&bb([0.0, 0.1, 0.5, 2.0]), &bb([300.0, 150.0, 50.0, 0.0]))?;
        single(
            TurningPoints::<_, 8>::new(law, bb(FirstLoading::Masing)),
            input,
        )
    }

    /// The 16-cell Iwan equivalent of the STS law (clamp form, fractions
    /// adding up to one half).
    fn sts_iwan<T: Real>(input: &Input<T>) -> Outcome {
        let law = Sts::<f64>::new(bb(400.0), bb(300.0))?;
        let placement = bb(Placement::Logarithmic { decades: 3.0 });
        let cells = iwan_from_relaxation::<_, 16>(&law, bb(4.0), placement)?;
        let k_ref = 2.0 * total_stiffness(&cells);
        single(
            IwanBank::<T, 16>::new(&cells.map(|c| c.spec(k_ref)))?,
            input,
        )
    }

    /// Segalman's four-parameter Iwan in 8 sliders.
    fn segalman<T: Real>(input: &Input<T>) -> Outcome {
        let law = Segalman::new(bb(50.0), bb(400.0), bb(-0.5), bb(0.3))?;
        let cells = law.discretize::<8>(bb(Placement::Uniform))?;
        let k_ref = 2.0 * total_stiffness(&cells);
        let sliders = IwanSliders::<T, 8>::new(&cells.map(|c| c.spec(k_ref)), k_ref)?;
        let mut t = single(sliders, input)?;
        t.fold(&[law.phi_max(), law.r(), law.s(), law.cycle_energy(bb(0.5))]);
        Ok(t)
    }

    /// A bank shifted to 10 K below its reference in f64 (WLF), and one
    /// re-tuned on line in the working type (WLF and libm exponentials),
    /// with the Arrhenius factor in f64 and the bank's response beside
    /// them.
    fn temperature<T: Real>(input: &Input<T>) -> Outcome {
        let wlf = wlf()?;
        let arrhenius = ShiftFactor::arrhenius(bb(9000.0), bb(293.15))?;
        let cold = bb(COLD_K);
        let bank = maxwell_bank::<T, Plain<T>>(MaxwellForm::RateExactRamp)?;
        let shifted = bank.shifted(wlf.at(cold)?)?;
        let mut retuned = bank.clone();
        retuned.retune::<LibmExp>(wlf.at_in::<T, LibmExp>(T::from_f64(cold))?)?;
        let (storage, loss) = bank.branch_response(bb(TAU));
        let branches = bank.branch_forces(&bb([Plain(T::ONE); 4]), T::from_f64(bb(2.0)));
        let mut t = single(shifted, input)?.then(single(retuned, input)?);
        t.fold(&[arrhenius.at(cold)?, storage, loss]);
        t.fold(&branches);
        Ok(t)
    }

    /// The six effects at once (the largest tuple), one of them chosen at
    /// run time (`Option`).
    fn composite<T: Real>(input: &Input<T>) -> Outcome {
        let xf = xf_bank(XfForm::ExactRamp, [XfSpec::hz(5.0, 0.1, 0.02)])?;
        let berg = if bb(true) { Some(berg()?) } else { None };
        let effects = (
            maxwell_bank::<T, Plain<T>>(MaxwellForm::RateExactRamp)?,
            iwan_bank()?,
            xf,
            dashpot()?,
            sts(FirstLoading::Masing)?,
            berg,
        );
        bushing(backbone()?, effects, input)
    }

    /// The rig loop's bushing (spline, 4 Maxwell cells, 3 Jenkins cells).
    fn rig<T: Real>(input: &Input<T>) -> Outcome {
        let b = rig_bushing::<T>(bb(1.0 / RATE_HZ))?;
        Ok(run(&b, input))
    }

    /// The 6-DOF engine mount over its motion: step (every fourth a
    /// trial) and the 12×12 tangent of every step.
    fn six_dof<T: Real>(connectivity: Connectivity) -> Outcome {
        // The stiffest law (5e5 N·mm/rad, hardening by 6 % over the
        // motion) kept below half the working type's guard: the mount as
        // it is in f32, rotations 60 times softer in Q16.
        let rotations = (0.5 * T::GUARD.to_f64() / 5.0e5).min(1.0);
        let mount = engine_mount_scaled::<T>(bb(connectivity), bb(rotations))?;
        let motion = bb(mount_motion::<T, 32>());
        let Some([n1, n2]) = motion.first() else {
            return Err(Failure::Other("no motion"));
        };
        let mut state = mount.state_at(n1, n2);
        let mut t = Tally::EMPTY;
        for (k, [n1, n2]) in motion.iter().enumerate() {
            let out = if k % 4 == 3 {
                let (out, next) = mount.trial(&state, n1, n2);
                state = next;
                out
            } else {
                mount.step(&mut state, n1, n2)
            };
            let loads = out.loads;
            t.push(loads.force.as_flattened());
            t.fold(loads.moment.as_flattened());
            t.fold(&[out.dissipated, out.frame.w]);
            t.fold(&out.strain);
            t.fold(&out.local);
            t.fold(&out.tangent);
            let Some(tangent) = mount.tangent(&out, n1, n2) else {
                return Err(Failure::Other("no 12x12 tangent"));
            };
            t.fold(tangent.as_flattened());
        }
        Ok(t.raise(state.faults()))
    }

    fn six_dof_attached<T: Real>(_: &Input<T>) -> Outcome {
        six_dof::<T>(Connectivity::Attached)
    }

    fn six_dof_invariant<T: Real>(_: &Input<T>) -> Outcome {
        six_dof::<T>(Connectivity::Invariant)
    }

    /// The Iwan oscillator: unit mass on the polynomial backbone with
    /// eight Jenkins cells, released from 1.5 mm and driven by the input
    /// as a force.
    fn oscillator<T: Real>(input: &Input<T>) -> Outcome {
        let restoring = Bushing::new(backbone::<T>()?, (IwanBank::<T, 8>::new(&bb(jenkins()))?,))?;
        let osc = Oscillator::new(restoring, bb(DT))?.with_max_iterations(bb(16));
        let mut state = osc.state_at(T::from_f64(bb(1.5)), T::ZERO, T::ZERO);
        let mut t = Tally::EMPTY;
        for f in input.xs() {
            let o = osc.step(&mut state, bb(f));
            t.push(&[
                o.force,
                o.p,
                o.v,
                o.a,
                o.dissipated,
                o.work,
                state.kinetic(),
            ]);
            t.word(u64::from(o.iterations) | u64::from(o.converged) << 32);
        }
        t.fold(&[osc.reference_stiffness()]);
        Ok(t.raise(state.faults()))
    }

    /// The `MaxwellBank::retune` of a firmware with micromath's
    /// exponentials (f32 only).
    fn micromath(input: &Input<f32>) -> Outcome {
        let a_t = wlf()?.at_in::<f32, MicromathExp>(bb(COLD_K as f32))?;
        let mut bank = maxwell_bank::<f32, Plain<f32>>(MaxwellForm::RateExactRamp)?;
        bank.retune::<MicromathExp>(a_t)?;
        single(bank, input)
    }

    // The tracker, in f32 on both cores.

    /// The rig's modal tracker (EKF, one mode, one displacement sensor)
    /// over the rig's sweep, read through the rig's ADC.
    fn modal_ekf(_: &Input<f32>) -> Outcome {
        let mut monitor = Monitor::tuned(bb(1), bb(TRACKER_NOISE_MM), bb(tracker_tuning()))?;
        let sweep = bushing_boards::rig::sweep()?;
        let mut t = Tally::EMPTY;
        for k in 0..bb(STEPS) {
            let x = AMPLITUDE_MM * sweep.unit(k as f64 / RATE_HZ);
            let code = adc_code(x, LSB_MM, ADC_BITS);
            let r = monitor.push(f32::from_code(code as i16));
            let mode = monitor.mode();
            t.push(&[mode.frequency, mode.damping, mode.omega, mode.sigma]);
            t.word(u64::from(r.accepted) | u64::from(r.gated) << 8 | u64::from(mode.faded) << 16);
        }
        t.fold(&[monitor.amplitude()]);
        Ok(t)
    }

    /// A UKF on two modes seen by a velocity and an acceleration sensor
    /// (12 states), the mode count given at run time.
    fn modal_ukf(input: &Input<f32>) -> Outcome {
        modal_ukf_as::<0>(input)
    }

    /// The same UKF with the mode count fixed at compile time: the same
    /// numbers, so the same checksum (`scripts/rig-loop.sh` compares them).
    fn modal_ukf_fixed(input: &Input<f32>) -> Outcome {
        modal_ukf_as::<2>(input)
    }

    /// [`modal_ukf`] with `M` modes fixed at compile time (0: at run time).
    fn modal_ukf_as<const M: usize>(input: &Input<f32>) -> Outcome {
        let sensor = |measured, noise| SensorSpec { measured, noise };
        let sensors = bb([
            sensor(Measured::Velocity, 0.05),
            sensor(Measured::Acceleration, 0.5),
        ]);
        let mode = |frequency, damping| ModeInit { frequency, damping };
        let modes = bb([mode(10.0, 0.01), mode(31.0, 0.005)]);
        let ut = UtParams::new(bb(1.0), bb(2.0), bb(0.0))?;
        let dt = bb(1e-3);
        let amplitudes = bb([(1.0, 0.0), (60.0, 0.0), (0.1, 0.0), (4.0, 0.0)]);
        let tracker = ModalTracker::<f32, 12, M>::new(
            dt,
            &sensors,
            &modes,
            &amplitudes,
            &bb(Tuning::default()),
            Filter::Ukf(ut),
        )?;
        let mut state = tracker.start();
        let mut t = Tally::EMPTY;
        for x in input.xs() {
            let r = tracker.step(&mut state, &[x, 60.0 * x]);
            let mode = tracker.mode(&state, 0);
            t.push(&[mode.frequency, mode.damping, mode.omega, mode.sigma]);
            t.word(
                u64::from(r.accepted) | u64::from(r.reacquired) << 8 | u64::from(r.refused) << 9,
            );
        }
        for m in 0..tracker.modes() {
            let s = tracker.mode(&state, m);
            let (re, im) = tracker.displacement(&state, m, tracker.sensors() - 1);
            t.fold(&[s.frequency, s.damping, re, im]);
        }
        t.fold(state.x());
        t.fold(state.covariance().as_flattened());
        Ok(t)
    }

    /// Start values by least squares on the first pseudo-period, then the
    /// amplitudes of the mode found, in f64.
    fn first_period(input: &Input<f32>) -> Outcome {
        let mut record = [0.0f64; 60];
        for (k, (r, x)) in record.iter_mut().zip(input.xs()).enumerate() {
            // A deterministic 1e-3 pseudo-noise, so that the fit iterates.
            *r = f64::from(x) + 1e-3 * ((k * 7919 % 13) as f64 - 6.0) / 6.0;
        }
        let records: [&[f64]; 1] = [&record];
        let dt = bb(1e-3);
        let mut out = [SensorFit::default()];
        let fit = fit_first_period(dt, &records, &mut out)?;
        let mut t = Tally::EMPTY;
        t.push(&[fit.mode.frequency, fit.mode.damping, out[0].residual]);
        fit_amplitudes(dt, &[fit.mode], &records, &mut out)?;
        t.push(&[out[0].amplitude.0, out[0].amplitude.1, out[0].residual]);
        t.word(u64::from(fit.iterations));
        Ok(t)
    }

    /// The sine tracker on the input, and the modulus tracker on the input
    /// and the backbone force it gives.
    fn sine_trackers(input: &Input<f32>) -> Outcome {
        let sine = bb(SineSpec {
            frequency: 10.0,
            bandwidth: 1.0,
        });
        let channel = |noise, amplitude| Channel { noise, amplitude };
        let dt = bb(1e-3);
        let tracker = SineTracker::<f32>::new(dt, &sine, bb(channel(0.01, 2.0)))?;
        let spec = ModulusSpec {
            sine,
            displacement: channel(0.01, 2.0),
            force: channel(1.0, 300.0),
            min_snr: 10.0,
        };
        let modulus = ModulusTracker::<f32>::new(dt, &bb(spec))?;
        let (mut s, mut m) = (tracker.start(), modulus.start());
        let mut t = Tally::EMPTY;
        // A refused sample counts as a value that is not finite.
        for d in &input.drives {
            let x = d.x;
            let y = tracker.step(&mut s, bb(x)).unwrap_or(f32::NAN);
            let (ix, iff) = modulus
                .step(&mut m, bb(x), bb(d.f_inf))
                .unwrap_or((f32::NAN, 0.0));
            t.push(&[y, ix, iff, s.amplitude()]);
            if let Some(k) = modulus.modulus(&m) {
                t.fold(&[
                    k.storage,
                    k.loss,
                    k.magnitude(),
                    k.loss_factor().unwrap_or(0.0),
                ]);
            }
        }
        let (g0, g1) = tracker.gain(&s);
        t.fold(&[tracker.predict(&s), g0, g1]);
        t.fold(tracker.covariance(&s).as_flattened());
        t.fold(modulus.covariance(&m, 1).as_flattened());
        t.word(u64::from(s.refused()) | u64::from(m.refused()) << 32);
        Ok(t)
    }

    /// The scalar unscented transform and linearisation of a cubic, and
    /// the per-sample helpers of the tracker.
    fn unscented(input: &Input<f32>) -> Outcome {
        let ut = ScalarUt::<f32>::new(&bb(UtParams::default()))?;
        let cubic = |x: f32| x * (1.0 + x * x);
        let mut t = Tally::EMPTY;
        for x in input.xs().take(bb(40)) {
            let variance = x * x;
            let (mean, var) = ut.transform(x, variance, cubic)?;
            let set2 = UtParams::new(bb(1.0), bb(0.0), bb(2.0))?;
            let (mean2, var2) = unscented_scalar(&set2, x, variance, cubic)?;
            let (lin, lin_var) = linearised_scalar(x, variance, cubic, |x| 1.0 + 3.0 * x * x)?;
            let [_, plus, minus] = ut.sigma_points(x, variance)?;
            let (sin, cos) = trig::sin_cos(x.abs());
            let fast = [
                fast::exp_small(-x.abs() * 0.01),
                fast::rsqrt(1.0 + variance),
            ];
            t.push(&[mean, var, mean2, var2, lin, lin_var, plus, minus, sin, cos]);
            t.fold(&fast);
        }
        let (w0m, w1) = ut.mean_weights();
        let (w0c, _) = ut.covariance_weights();
        t.fold(&[ut.spread(), w0m, w1, w0c, fast::min_positive::<f32>()]);
        Ok(t)
    }

    /// The Iwan relevance check: damping from a softening frequency curve
    /// (uniform and measured grids) and the frequency curve back from it.
    fn relevance(_: &Input<f32>) -> Outcome {
        let omega = bb([10.0, 9.9, 9.7, 9.4, 9.0, 8.5]);
        let amplitude = bb([0.1, 0.2, 0.4, 0.7, 1.1, 1.6]);
        let mut damping = [0.0; 6];
        let mut back = [0.0; 6];
        let mut t = Tally::EMPTY;
        damping_from_frequency_uniform(&omega, &mut damping)?;
        frequency_from_damping_uniform(omega[0], &damping, &mut back)?;
        t.push(&damping);
        t.push(&back);
        damping_from_frequency(&amplitude, &omega, &mut damping)?;
        t.push(&damping);
        Ok(t)
    }

    /// One model: its name and how it runs on an input of type `T`.
    type Model<T> = (&'static str, fn(&Input<T>) -> Outcome);

    /// The models in the working type (Q16 on the Cortex-M3).
    fn in_working_type<T: Real>() -> [Model<T>; 22] {
        [
            ("backbone/polynomial", polynomial::<T>),
            ("backbone/spline", spline::<T>),
            ("maxwell/plain", maxwell::<T, Plain<T>>),
            ("maxwell/multiplied", maxwell::<T, Multiplied<T>>),
            ("maxwell/compensated", maxwell::<T, Compensated<T>>),
            ("temperature/shift-retune", temperature::<T>),
            ("iwan/clamp", iwan_clamp::<T>),
            ("iwan/sliders", iwan_sliders::<T>),
            ("xf", xf::<T>),
            ("friction/dahl", dahl::<T>),
            ("friction/bouc-wen", bouc_wen::<T>),
            ("friction/berg", berg_cell::<T>),
            ("fractional/grunwald-64", grunwald::<T>),
            ("viscous/dashpot", dashpot_cell::<T>),
            ("stack/sts", sts_stack::<T>),
            ("stack/kf-table", kf_table::<T>),
            ("discretize/sts-iwan-16", sts_iwan::<T>),
            ("discretize/segalman-8", segalman::<T>),
            ("bushing/six-effects", composite::<T>),
            ("bushing/rig", rig::<T>),
            ("six-dof/attached", six_dof_attached::<T>),
            ("six-dof/invariant", six_dof_invariant::<T>),
        ]
    }

    /// The models in f32 on both cores (software floating point on the
    /// Cortex-M3; see the module docs for why each is not in Q16).
    const IN_F32: [Model<f32>; 9] = [
        ("oscillator/iwan-8", oscillator::<f32>),
        ("temperature/micromath", micromath),
        ("tracker/modal-ekf", modal_ekf),
        ("tracker/modal-ukf", modal_ukf),
        ("tracker/modal-ukf-modes-fixed", modal_ukf_fixed),
        ("tracker/first-period-fit", first_period),
        ("tracker/sine-modulus", sine_trackers),
        ("tracker/unscented", unscented),
        ("tracker/relevance", relevance),
    ];

    /// The number type as the lines name it.
    fn number<T: Real>() -> &'static str {
        if T::NAME == "I16F16" { "q16" } else { T::NAME }
    }

    /// Counts of the run.
    #[derive(Default)]
    struct Verdict {
        models: u32,
        refused: u32,
        faulted: u32,
    }

    impl Verdict {
        /// Runs each model on `input` and prints its line.
        fn run<T: Real>(&mut self, models: &[Model<T>], input: &Input<T>) {
            for (name, model) in models {
                self.models += 1;
                match model(input) {
                    Ok(t) => {
                        hprintln!(
                            "model {} type={} calls={} last={:016x} checksum={:016x} faults={:#x} not_finite={}",
                            name,
                            number::<T>(),
                            t.calls,
                            t.last,
                            t.hash,
                            t.faults,
                            t.not_finite
                        );
                        if t.faults != 0 || t.not_finite != 0 {
                            self.faulted += 1;
                        }
                    }
                    Err(why) => {
                        hprintln!("model {} type={} refused: {}", name, number::<T>(), why);
                        self.refused += 1;
                    }
                }
            }
        }
    }

    #[entry]
    fn main() -> ! {
        memory::paint_stack();
        hprintln!(
            "every-model target={} type={} tracker=f32 steps={}",
            TARGET,
            number::<Num>(),
            STEPS
        );
        let (Ok(working), Ok(single)) = (Input::<Num>::new(), Input::<f32>::new()) else {
            probe::fail("input refused")
        };
        let mut verdict = Verdict::default();
        verdict.run(&in_working_type::<Num>(), &working);
        verdict.run(&IN_F32, &single);
        let stack = memory::stack_high_water();
        hprintln!(
            "models {} refused {} faulted {}",
            verdict.models,
            verdict.refused,
            verdict.faulted
        );
        hprintln!(
            "memory flash {} static_ram {} stack {}",
            memory::flash_bytes(),
            memory::static_ram_bytes(),
            stack
        );
        if verdict.refused == 0 && verdict.faulted == 0 {
            hprintln!("verdict pass");
            probe::pass()
        } else {
            probe::fail("verdict fail")
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("every-model is firmware: build it for a Cortex-M target (see docs/firmware.md)");
}
