//! The rig loop under QEMU: one control period per SysTick interrupt at
//! 5 kHz.
//!
//! Each period reads the displacement through the SPI ADC driver, steps
//! the bushing (spline backbone, 4 Maxwell cells, 3 Jenkins cells), writes
//! the force command through the SPI DAC driver and, on the Cortex-M4F,
//! updates the modal tracker (on the Cortex-M3 the thread-mode loop runs
//! it on every 20th period). The converters are simulated behind the same
//! `SpiDevice` trait: the thread-mode loop computes the sweep of
//! `scenes/rig-loop.toml` ahead into the ADC's queue and logs one line
//! per period for the comparison with `bushing-sim`.
//!
//! The log is `defmt` frames over semihosting (`bushing_boards::log`),
//! decoded on the host by `bushing-defmt-log` with this ELF: the interrupt
//! hands each period's entry to thread mode through a lock-free queue and
//! never logs, and the logger never masks interrupts, so logging adds
//! nothing to the interrupt latency. Decoded:
//!
//! ```text
//! rig-loop number=f32 lsb_mm=0.000244140625 rate_hz=5000 part_hz=168000000 budget=33600
//! step 1 51 4035d941
//! ...
//! periods 10000 overruns 0 adc_underruns 0 plant_lead_min 63 ... faults NONE
//! ```
//!
//! The same source builds for the Cortex-M4F in `f32`
//! (`--target thumbv7em-none-eabihf`, mps2-an386) and for the Cortex-M3 in
//! the fixed-point `Q16` (`--target thumbv7m-none-eabi`, mps2-an385),
//! where one update of the `f32` tracker, in software floating point,
//! costs more than a whole period. The SysTick period is the cycle budget of the
//! reference part (168 MHz for the M4F, 72 MHz for the M3) counted as guest
//! instructions: QEMU `-icount shift=0` runs one instruction per ns and
//! SysTick counts one tick per 40. The run exits with success only when no
//! period overran, the ADC queue never ran dry, every transfer succeeded,
//! the tracker followed the sweep, and flash and static RAM are within
//! 64 KiB and 16 KiB.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;

    use bushing::Faults;
    use bushing::tracker::ModeStatus;
    use bushing_boards::memory;
    use bushing_boards::rig::sim::{Plant, SimAdc, SimDac};
    use bushing_boards::rig::{
        Adc, AdcChannel, Dac, DacChannel, LSB_MM_TEXT, M3_TRACKER_DECIMATION, Monitor, RATE_HZ,
        Rig, RigState, Sample,
    };
    use cortex_m::interrupt::{self, Mutex};
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m::peripheral::{SCB, SYST};
    use cortex_m_rt::{entry, exception};
    use heapless::spsc::{Consumer, Producer, Queue};

    #[cfg(feature = "panic-never")]
    use panic_never as _;

    /// Logs where the panic happened (no message: formatting it would link
    /// `core::fmt`) and ends the run with failure.
    #[cfg(not(feature = "panic-never"))]
    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
        match info.location() {
            Some(at) => fail_at("panic", at.file(), at.line()),
            None => fail("panic"),
        }
    }

    /// Ends the run with `why`: QEMU exits with failure.
    fn fail(why: &str) -> ! {
        defmt::println!("error: {=str}", why);
        bushing_boards::probe::exit(false)
    }

    /// [`fail`] with a source location.
    #[cfg(not(feature = "panic-never"))]
    fn fail_at(why: &str, file: &str, line: u32) -> ! {
        defmt::println!("error: {=str} at {=str}:{=u32}", why, file, line);
        bushing_boards::probe::exit(false)
    }

    /// Working type: `f32` with an FPU, `Q16` without.
    #[cfg(target_abi = "eabihf")]
    type Num = f32;
    #[cfg(not(target_abi = "eabihf"))]
    type Num = bushing::Q16;

    /// Whether the modal tracker runs in the period (FPU targets) or in
    /// thread mode on every `M3_TRACKER_DECIMATION`-th period (no FPU).
    const TRACK: bool = cfg!(target_abi = "eabihf");
    /// Periods per tracker update.
    const TRACKER_EVERY: u32 = if TRACK { 1 } else { M3_TRACKER_DECIMATION };
    /// Clock of the reference part, Hz.
    const PART_HZ: u32 = if TRACK { 168_000_000 } else { 72_000_000 };
    /// Cycles of the reference part in one control period.
    const BUDGET: u32 = PART_HZ / RATE_HZ as u32;
    /// Guest instructions per SysTick tick under `-icount shift=0`.
    const PER_TICK: u32 = bushing_boards::probe::INSTRUCTIONS_PER_TICK;
    /// SysTick ticks per control period.
    const PERIOD_TICKS: u32 = BUDGET / PER_TICK;
    /// Flash and static RAM budgets of the rig loop, bytes.
    const FLASH_BUDGET: usize = 64 * 1024;
    const RAM_BUDGET: usize = 16 * 1024;
    /// Tracker frequency error allowed after the first 0.3 s, ppm.
    const TRACKER_BOUND_PPM: u32 = 10_000;
    /// Log entries the interrupt can queue ahead of thread mode, plus one.
    const LOG_SLOTS: usize = 33;

    /// One period, as logged by the thread-mode loop.
    #[derive(Clone, Copy)]
    struct Entry {
        period: u32,
        code: i16,
        bits: u32,
        /// Frequency tracked in the interrupt, Hz (0 when the tracker runs
        /// in thread mode).
        frequency: f32,
    }

    /// Everything the interrupt owns.
    struct Loop {
        rig: Rig<Num>,
        state: RigState<Num>,
        monitor: Option<Monitor>,
        adc: Adc<SimAdc>,
        dac: Dac<SimDac>,
        periods: u32,
        last: u32,
        errors: u32,
        overruns: u32,
        /// Ticks from the tick to the start of the handler (latency), and
        /// from there to the DAC write and to the end of the tracker
        /// update: worst and sum.
        latency_worst: u32,
        output_worst: u32,
        output_sum: u32,
        total_worst: u32,
        total_sum: u32,
        faults: Faults,
        /// The interrupt's end of the log queue.
        log: Producer<'static, Entry>,
        dropped: u32,
    }

    static LOOP: Mutex<RefCell<Option<Loop>>> = Mutex::new(RefCell::new(None));

    /// Ticks since the current period began. The interrupt is raised as
    /// the counter reaches 0, which it shows for one tick before it
    /// reloads with `PERIOD_TICKS - 1`.
    fn elapsed() -> u32 {
        PERIOD_TICKS.wrapping_sub(SYST::get_current()) % PERIOD_TICKS
    }

    impl Loop {
        /// One control period.
        fn tick(&mut self) {
            if self.periods >= self.last {
                return;
            }
            let start = elapsed();
            let result = self
                .rig
                .period(&mut self.state, &mut self.adc, &mut self.dac);
            let output = elapsed().wrapping_sub(start);
            let mut frequency = 0.0;
            let entry = match result {
                Ok(p) => {
                    // `TRACK` first, so that a build without the tracker
                    // does not link its code.
                    if TRACK && let Some(m) = self.monitor.as_mut() {
                        m.push(f32::from_code(p.code));
                        frequency = m.mode().frequency;
                    }
                    self.faults = p.faults;
                    Some((p.code, p.force.log_bits()))
                }
                Err(_) => {
                    self.errors = self.errors.saturating_add(1);
                    None
                }
            };
            #[cfg(feature = "deliberate-panic")]
            {
                const TABLE: [u32; 4] = [1, 2, 3, 4];
                let i = core::hint::black_box(self.periods as usize);
                core::hint::black_box(TABLE[i]);
            }
            let total = elapsed().wrapping_sub(start);
            self.latency_worst = self.latency_worst.max(start);
            // At most `last`: no overflow.
            self.periods += 1;
            self.output_worst = self.output_worst.max(output);
            self.output_sum = self.output_sum.saturating_add(output);
            self.total_worst = self.total_worst.max(total);
            self.total_sum = self.total_sum.saturating_add(total);
            if let Some((code, bits)) = entry {
                let e = Entry {
                    period: self.periods,
                    code,
                    bits,
                    frequency,
                };
                if self.log.enqueue(e).is_err() {
                    self.dropped = self.dropped.saturating_add(1);
                }
            }
            // The next tick is already pending: this period overran.
            if SCB::is_pendst_pending() {
                self.overruns = self.overruns.saturating_add(1);
            }
        }
    }

    #[exception]
    fn SysTick() {
        interrupt::free(|cs| {
            if let Ok(mut l) = LOOP.borrow(cs).try_borrow_mut()
                && let Some(l) = l.as_mut()
            {
                l.tick();
            }
        });
    }

    fn build(plant: &Plant, log: Producer<'static, Entry>) -> Result<Loop, bushing::ParamError> {
        let rig = Rig::<Num>::new()?;
        let state = rig.start(plant.code(0));
        let monitor = if TRACK { Some(Monitor::new(1)?) } else { None };
        Ok(Loop {
            rig,
            state,
            monitor,
            adc: Adc::new(SimAdc::default(), AdcChannel::In0),
            dac: Dac::new(SimDac::default(), DacChannel::A),
            periods: 0,
            last: plant.steps(),
            errors: 0,
            overruns: 0,
            latency_worst: 0,
            output_worst: 0,
            output_sum: 0,
            total_worst: 0,
            total_sum: 0,
            faults: Faults::default(),
            log,
            dropped: 0,
        })
    }

    /// What thread mode learns from the interrupt in one pass.
    struct Exchanged {
        /// The offered code went into the ADC queue.
        fed: bool,
        /// Codes queued before the offer.
        queued: usize,
        done: bool,
    }

    /// Builds the loop into [`LOOP`] with the ADC queue filled; returns
    /// the next period whose code is to be queued.
    #[inline(never)]
    fn setup(plant: &Plant, log: Producer<'static, Entry>) -> Result<u32, &'static str> {
        let mut lp = match build(plant, log) {
            Ok(lp) => lp,
            Err(e) => {
                defmt::println!("rig parameters refused: {}", e);
                return Err("rig parameters refused");
            }
        };
        let mut next = 1u32;
        while next <= plant.steps() && lp.adc.device_mut().feed(plant.code(next)) {
            next += 1;
        }
        interrupt::free(|cs| {
            let mut slot = LOOP
                .borrow(cs)
                .try_borrow_mut()
                .map_err(|_| "loop state busy")?;
            *slot = Some(lp);
            Ok(next)
        })
    }

    /// Offers `code` to the ADC queue, in a critical section of a few
    /// dozen instructions (the log entries come through their own
    /// lock-free queue).
    #[inline(never)]
    fn exchange(code: Option<i16>) -> Exchanged {
        interrupt::free(|cs| {
            let mut out = Exchanged {
                fed: false,
                queued: 0,
                done: true,
            };
            if let Ok(mut l) = LOOP.borrow(cs).try_borrow_mut()
                && let Some(l) = l.as_mut()
            {
                out.queued = l.adc.device().queued();
                out.fed = code.is_some_and(|c| l.adc.device_mut().feed(c));
                out.done = l.periods >= l.last;
            }
            out
        })
    }

    #[entry]
    fn main() -> ! {
        // The log queue: the interrupt's producer, thread mode's consumer
        // (cortex-m-rt makes this a `&'static mut`).
        static mut LOG: Queue<Entry, LOG_SLOTS> = Queue::new();
        memory::paint_stack();
        let Some(mut core) = cortex_m::Peripherals::take() else {
            fail("core peripherals already taken")
        };
        let Ok(plant) = Plant::new() else {
            fail("sweep refused")
        };
        let (producer, mut entries): (_, Consumer<'static, Entry>) = LOG.split();
        let mut next = match setup(&plant, producer) {
            Ok(n) => n,
            Err(why) => fail(why),
        };
        // Stack of the set-up, then of the running loop alone.
        let setup_stack = memory::stack_high_water();
        memory::paint_stack();

        defmt::println!(
            "rig-loop number={=str} lsb_mm={=str} rate_hz={=u32} part_hz={=u32} budget={=u32}",
            if TRACK { "f32" } else { "q16" },
            LSB_MM_TEXT,
            RATE_HZ as u32,
            PART_HZ,
            BUDGET
        );
        let syst = &mut core.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(PERIOD_TICKS - 1);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();

        let mut worst_tracking = 0.0f32;
        // The fewest codes queued ahead of the loop while the plant still
        // had codes to give: the thread-mode margin, in periods.
        let mut lead = usize::MAX;
        // Without an FPU the tracker runs here, between periods.
        let mut thread_monitor = if TRACK {
            None
        } else {
            match Monitor::new(TRACKER_EVERY) {
                Ok(m) => Some(m),
                Err(_) => fail("tracker parameters refused"),
            }
        };
        loop {
            // The next code, computed outside the critical section.
            let code = (next <= plant.steps()).then(|| plant.code(next));
            let exchanged = exchange(code);
            if code.is_some() {
                lead = lead.min(exchanged.queued);
            }
            if exchanged.fed {
                next += 1;
            }
            while let Some(e) = entries.dequeue() {
                defmt::println!("step {=u32} {=i16} {=u32:08x}", e.period, e.code, e.bits);
                let mut frequency = e.frequency;
                if let Some(m) = thread_monitor.as_mut() {
                    // Only built without an FPU, where TRACKER_EVERY is this.
                    if e.period % M3_TRACKER_DECIMATION != 0 {
                        continue;
                    }
                    m.push(f32::from_code(e.code));
                    frequency = m.mode().frequency;
                }
                if f64::from(e.period) / RATE_HZ > 0.3 {
                    let f = plant.frequency(e.period) as f32;
                    worst_tracking = worst_tracking.max((frequency - f).abs() / f);
                }
            }
            // The interrupt queues a period's entry before it returns, so
            // once every period has run the queue was drained above.
            if exchanged.done {
                break;
            }
            // Sleep until the next period when the queue is full.
            if !exchanged.fed {
                cortex_m::asm::wfi();
            }
        }
        core.SYST.disable_interrupt();
        core.SYST.disable_counter();
        let loop_stack = memory::stack_high_water();
        let summary = interrupt::free(|cs| {
            LOOP.borrow(cs)
                .try_borrow()
                .ok()
                .and_then(|l| l.as_ref().map(Loop::summary))
        });
        match summary {
            Some(s) => {
                // The last estimate of the tracker, wherever it ran.
                let mode = s.mode.or(thread_monitor.as_ref().map(Monitor::mode));
                report(&s, mode, worst_tracking, lead, setup_stack, loop_stack)
            }
            None => fail("loop state lost"),
        }
    }

    /// The figures of a finished run.
    #[derive(Clone, Copy)]
    struct Summary {
        periods: u32,
        last: u32,
        overruns: u32,
        errors: u32,
        dropped: u32,
        underruns: u32,
        conversions: u32,
        faults: Faults,
        /// The interrupt's tracker's last estimate (on FPU targets).
        mode: Option<ModeStatus<f32>>,
        latency_worst: u32,
        output_worst: u32,
        output_sum: u32,
        total_worst: u32,
        total_sum: u32,
    }

    impl Loop {
        fn summary(&self) -> Summary {
            Summary {
                periods: self.periods,
                last: self.last,
                overruns: self.overruns,
                errors: self.errors,
                dropped: self.dropped,
                underruns: self.adc.device().underruns(),
                conversions: self.adc.device().conversions(),
                faults: self.faults,
                mode: self.monitor.as_ref().map(Monitor::mode),
                latency_worst: self.latency_worst,
                output_worst: self.output_worst,
                output_sum: self.output_sum,
                total_worst: self.total_worst,
                total_sum: self.total_sum,
            }
        }
    }

    fn report(
        l: &Summary,
        mode: Option<ModeStatus<f32>>,
        worst_tracking: f32,
        lead: usize,
        setup_stack: usize,
        stack: usize,
    ) -> ! {
        // Sums of ticks: at most 10 000 periods of 840 ticks, far from
        // u32::MAX even in instructions (no 64-bit division linked).
        let n = l.periods.max(1);
        // `as` saturates: a NaN or huge error reads as 0 or u32::MAX.
        let tracking_ppm = if worst_tracking.is_nan() {
            u32::MAX
        } else {
            (worst_tracking * 1e6) as u32
        };
        let flash = memory::flash_bytes();
        let ram = memory::static_ram_bytes();
        let (underruns, conversions) = (l.underruns, l.conversions);
        let log_dropped = bushing_boards::log::dropped_frames();
        defmt::println!(
            "periods {=u32} overruns {=u32} adc_underruns {=u32} plant_lead_min {=usize} conversions {=u32} transfer_errors {=u32} dropped_log {=u32} dropped_frames {=u32} faults {}",
            l.periods,
            l.overruns,
            underruns,
            lead,
            conversions,
            l.errors,
            l.dropped,
            log_dropped,
            l.faults
        );
        defmt::println!(
            "instructions latency_worst {=u32} to_dac_mean {=u32} to_dac_worst {=u32} period_mean {=u32} period_worst {=u32} budget {=u32} (±{=u32} per figure)",
            l.latency_worst * PER_TICK,
            l.output_sum.saturating_mul(PER_TICK) / n,
            l.output_worst * PER_TICK,
            l.total_sum.saturating_mul(PER_TICK) / n,
            l.total_worst * PER_TICK,
            BUDGET,
            PER_TICK
        );
        defmt::println!(
            "memory flash {=usize} static_ram {=usize} stack_loop {=usize} stack_setup {=usize} flash_budget {=usize} ram_budget {=usize}",
            flash,
            ram,
            stack,
            setup_stack,
            FLASH_BUDGET,
            RAM_BUDGET
        );
        defmt::println!(
            "tracker every {=u32} worst_frequency_error_ppm {=u32} bound_ppm {=u32} last {}",
            TRACKER_EVERY,
            tracking_ppm,
            TRACKER_BOUND_PPM,
            mode
        );
        let ok = l.periods == l.last
            && l.overruns == 0
            && underruns == 0
            && l.errors == 0
            && l.dropped == 0
            && log_dropped == 0
            && l.faults.is_empty()
            && flash <= FLASH_BUDGET
            && ram <= RAM_BUDGET
            && tracking_ppm <= TRACKER_BOUND_PPM;
        if ok {
            defmt::println!("verdict pass");
            bushing_boards::probe::exit(true)
        } else {
            fail("verdict fail")
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("rig-loop is firmware: build it for a Cortex-M target (see docs/firmware.md)");
}
