//! A rig controller skeleton: the bushing model stepped once per SysTick
//! period at 5 kHz, on a Cortex-M4F in QEMU (`cargo run --release`).
//!
//! The interrupt reads a displacement (here a simulated 10 Hz, 2 mm sine:
//! put your ADC read there), steps the model and would write the force to
//! a DAC. Thread mode sleeps, then prints a summary over semihosting and
//! exits QEMU with the verdict. Units: mm, N, s, mJ.
#![no_std]
#![no_main]

use core::cell::RefCell;

use bushing::{
    Bushing, IwanBank, IwanCellSpec, MaxwellBank, MaxwellForm, MaxwellSpec, MonotoneSpline,
    ParamError, StateOf,
};
use cortex_m::interrupt::{self, Mutex};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;

/// Control rate, Hz.
const RATE_HZ: f32 = 5000.0;
/// SysTick ticks per period: a 168 MHz part has 33 600 cycles per period,
/// and QEMU (`-icount shift=0`) advances SysTick once per 40 instructions.
const PERIOD_TICKS: u32 = 33_600 / 40;
/// Periods to run: one second.
const PERIODS: u32 = 5000;

/// The effects: 3 Maxwell cells and 2 Jenkins cells.
type Effects = (MaxwellBank<f32, 3>, IwanBank<f32, 2>);
/// The model: a measured backbone of up to 8 points and the effects.
type Model = Bushing<f32, MonotoneSpline<f32, 8>, Effects>;

/// What the interrupt owns.
struct Rig {
    model: Model,
    state: StateOf<f32, Effects>,
    period: u32,
    peak: f32,
    dissipated: f32,
    worst_ticks: u32,
}

static RIG: Mutex<RefCell<Option<Rig>>> = Mutex::new(RefCell::new(None));

/// The bushing, from its identified parameters (checked here, once).
fn model() -> Result<Model, ParamError> {
    let backbone = MonotoneSpline::new(
        &[-4.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.0, 4.0],
        &[-2500.0, -700.0, -250.0, 0.0, 110.0, 240.0, 600.0, 1900.0],
    )?;
    let maxwell = [
        MaxwellSpec::hz(0.5, 0.1),
        MaxwellSpec::hz(5.0, 0.15),
        MaxwellSpec::hz(50.0, 0.1),
    ];
    let jenkins = [IwanCellSpec::new(0.08, 0.6), IwanCellSpec::new(0.08, 2.4)];
    Bushing::new(
        backbone,
        (
            MaxwellBank::new(
                MaxwellForm::RateExactRamp,
                &maxwell,
                1.0 / f64::from(RATE_HZ),
            )?,
            IwanBank::new(&jenkins)?,
        ),
    )
}

impl Rig {
    /// One control period.
    fn tick(&mut self, start: u32) {
        if self.period >= PERIODS {
            return;
        }
        // The displacement, mm: your ADC read goes here.
        let t = self.period as f32 / RATE_HZ;
        let x = 2.0 * libm::sinf(core::f32::consts::TAU * 10.0 * t);
        let out = self.model.step(&mut self.state, x);
        // The force, N: your DAC write goes here.
        self.peak = self.peak.max(out.force.abs());
        self.dissipated += out.dissipated;
        self.period += 1;
        self.worst_ticks = self.worst_ticks.max(elapsed().wrapping_sub(start));
    }
}

/// SysTick ticks since the period began. The counter counts down and
/// shows 0 for one tick as the interrupt is raised, before it reloads.
fn elapsed() -> u32 {
    PERIOD_TICKS.wrapping_sub(SYST::get_current()) % PERIOD_TICKS
}

#[exception]
fn SysTick() {
    let start = elapsed();
    interrupt::free(|cs| {
        if let Some(rig) = RIG.borrow(cs).borrow_mut().as_mut() {
            rig.tick(start);
        }
    });
}

fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::nop();
    }
}

#[entry]
fn main() -> ! {
    let model = match model() {
        Ok(m) => m,
        Err(e) => {
            hprintln!("parameters refused: {}", e);
            exit(false)
        }
    };
    let state = model.state_at(0.0);
    interrupt::free(|cs| {
        RIG.borrow(cs).replace(Some(Rig {
            model,
            state,
            period: 0,
            peak: 0.0,
            dissipated: 0.0,
            worst_ticks: 0,
        }))
    });
    let Some(mut core) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    core.SYST.set_clock_source(SystClkSource::Core);
    core.SYST.set_reload(PERIOD_TICKS - 1);
    core.SYST.clear_current();
    core.SYST.enable_interrupt();
    core.SYST.enable_counter();

    loop {
        cortex_m::asm::wfi();
        let done = interrupt::free(|cs| {
            RIG.borrow(cs)
                .borrow()
                .as_ref()
                .map(|r| r.period >= PERIODS)
        });
        if done != Some(false) {
            break;
        }
    }
    core.SYST.disable_interrupt();

    let summary = interrupt::free(|cs| {
        RIG.borrow(cs).borrow().as_ref().map(|r| {
            (
                r.period,
                r.peak,
                r.dissipated,
                r.worst_ticks,
                r.state.faults(),
            )
        })
    });
    let Some((periods, peak, dissipated, worst, faults)) = summary else {
        exit(false)
    };
    hprintln!(
        "template periods {} peak_force_n {} dissipated_mj {} worst_step_instructions {} faults {}",
        periods,
        peak as u32,
        dissipated as u32,
        worst * 40,
        faults
    );
    let ok = periods == PERIODS && faults.is_empty() && peak > 100.0 && dissipated > 0.0;
    hprintln!("verdict {}", if ok { "pass" } else { "fail" });
    exit(ok)
}
