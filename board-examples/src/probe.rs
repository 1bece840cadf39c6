//! Counting guest instructions under QEMU: SysTick runs free from the core
//! clock, and with `-icount shift=0` (the runner in `.cargo/config.toml`)
//! QEMU advances it one tick per 40 guest instructions.
//!
//! Each measurement is also a numbered window between calls of
//! [`window_open`] and [`window_close`]: the `bushing-qemu-mix` QEMU plugin
//! records which instructions ran in each window, for cycle estimates.

use core::sync::atomic::{AtomicU32, Ordering};

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

/// One measurement: its SysTick ticks and its window's number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// SysTick ticks (at most 2^24 - 1: about 670 million instructions).
    pub ticks: u32,
    /// The window's number, counted from 0 in the order of the calls of
    /// [`span`]; `None` for a stand-in that measured nothing.
    pub window: Option<u32>,
}

impl Span {
    /// Nothing measured: zero ticks, no window.
    pub const NONE: Self = Self {
        ticks: 0,
        window: None,
    };
}

/// Windows opened so far.
static WINDOWS: AtomicU32 = AtomicU32::new(0);

/// Marks the start of a window for the QEMU plugin (its address is looked
/// up in the ELF by name; one `nop` so that it differs from
/// [`window_close`] and the linker cannot fold the two).
#[inline(never)]
pub fn window_open() {
    cortex_m::asm::nop();
}

/// Marks the end of a window for the QEMU plugin.
#[inline(never)]
pub fn window_close() {
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

/// Measures `f`: its SysTick ticks, in a numbered window. The window
/// markers sit outside the SysTick reads, so the ticks count `f` alone;
/// the window adds the two reads and a return, the same for every
/// measurement (they cancel in a difference of two windows).
pub fn span(f: impl FnOnce()) -> Span {
    let window = WINDOWS.load(Ordering::Relaxed);
    WINDOWS.store(window.wrapping_add(1), Ordering::Relaxed);
    window_open();
    let start = SYST::get_current();
    f();
    let end = SYST::get_current();
    window_close();
    Span {
        ticks: start.wrapping_sub(end) & 0x00FF_FFFF,
        window: Some(window),
    }
}

/// SysTick ticks taken by `f` (at most 2^24 - 1: about 670 million
/// instructions).
pub fn ticks(f: impl FnOnce()) -> u32 {
    span(f).ticks
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
