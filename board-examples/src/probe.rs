//! Counting guest instructions under QEMU: SysTick runs free from the core
//! clock, and with `-icount shift=0` (the runner in `.cargo/config.toml`)
//! QEMU advances it one tick per 40 guest instructions.

use cortex_m::peripheral::{SYST, syst::SystClkSource};
use cortex_m_semihosting::{debug, hprintln};

/// Guest instructions per SysTick tick under `-icount shift=0`.
pub const INSTRUCTIONS_PER_TICK: u32 = 40;

/// Starts SysTick counting down from its largest reload, without
/// interrupts. Exits with failure when the core peripherals were taken.
pub fn start() {
    let Some(p) = cortex_m::Peripherals::take() else {
        fail("core peripherals already taken")
    };
    let mut syst = p.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();
}

/// SysTick ticks taken by `f` (at most 2^24 - 1: about 670 million
/// instructions).
pub fn ticks(f: impl FnOnce()) -> u32 {
    let start = SYST::get_current();
    f();
    let end = SYST::get_current();
    start.wrapping_sub(end) & 0x00FF_FFFF
}

/// Ends the run: QEMU exits with success.
pub fn pass() -> ! {
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::nop();
    }
}

/// Ends the run with `why`: QEMU exits with failure.
pub fn fail(why: &str) -> ! {
    hprintln!("{}", why);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}
