//! Counting guest instructions under QEMU: SysTick runs free from the core
//! clock, and with `-icount shift=0` (the runner in `.cargo/config.toml`)
//! QEMU advances it one tick per 40 guest instructions.
//!
//! Each measurement is also a numbered window between calls of
//! [`window_open`] and [`window_close`]: the `bushing-qemu-mix` QEMU plugin
//! records which instructions ran in each window, for cycle estimates.
//!
//! [`measure`] is the one harness every kernel is measured with, whatever
//! its shape: a loop, compiled once, that calls a [`Kernel`] through a
//! trait object. A kernel and its stand-in (the same signature, nothing
//! computed) run through the same [`Calls::call`], so their difference is
//! the kernel's own code, and does not depend on what else the binary
//! holds.

use core::hint::black_box;
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
    /// [`span`]; `None` when a harness opened none.
    pub window: Option<u32>,
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

/// Something to call once per input, as the harness sees it.
pub trait Kernel {
    /// Calls on the `i`-th input; nothing when there is none.
    fn call(&mut self, i: usize);
    /// How many inputs there are.
    fn calls(&self) -> usize;
}

/// A public step measured over a run of inputs: `kernel(params, &mut
/// state, &inputs[i])` for each `i`, its result kept (`black_box`).
///
/// The function is a field, not a type: a kernel and its stand-in of the
/// same signature share one compiled [`Kernel::call`].
pub struct Calls<'a, P: ?Sized, S, I, O> {
    /// The parameters, read only.
    pub params: &'a P,
    /// The state the calls advance.
    pub state: S,
    /// One input per call.
    pub inputs: &'a [I],
    /// The function called.
    pub kernel: fn(&P, &mut S, &I) -> O,
}

impl<P: ?Sized, S, I, O> Kernel for Calls<'_, P, S, I, O> {
    #[inline(never)]
    fn call(&mut self, i: usize) {
        if let Some(x) = self.inputs.get(i) {
            black_box((self.kernel)(self.params, &mut self.state, black_box(x)));
        }
    }

    fn calls(&self) -> usize {
        self.inputs.len()
    }
}

/// The harness with nothing to call: its window is the loop and the
/// dispatch alone.
struct Idle(usize);

impl Kernel for Idle {
    #[inline(never)]
    fn call(&mut self, i: usize) {
        black_box(i);
    }

    fn calls(&self) -> usize {
        self.0
    }
}

/// The harness: every call of `kernel`, in one window. Not inlined and not
/// generic, so that its loop is the same code for every kernel.
#[inline(never)]
pub fn measure(kernel: &mut dyn Kernel) -> Span {
    let calls = kernel.calls();
    span(|| {
        for i in 0..calls {
            kernel.call(i);
        }
    })
}

/// The three windows of one kernel over `inputs`, each from the state
/// `fresh` gives: the kernel, its stand-in, and the idle harness. The
/// kernel less the stand-in is what the kernel adds to a call; the kernel
/// less the idle harness is the whole call, the harness's dispatch and
/// input fetch included.
pub fn measure_three<P: ?Sized, S, I, O>(
    params: &P,
    fresh: impl Fn() -> S,
    inputs: &[I],
    kernel: fn(&P, &mut S, &I) -> O,
    stand_in: fn(&P, &mut S, &I) -> O,
) -> [Span; 3] {
    let run = |f: fn(&P, &mut S, &I) -> O| {
        measure(&mut Calls {
            params,
            state: fresh(),
            inputs,
            kernel: f,
        })
    };
    let t = run(kernel);
    let e = run(stand_in);
    let idle = measure(&mut Idle(inputs.len()));
    [t, e, idle]
}

/// Ends the run: QEMU exits with success.
pub fn pass() -> ! {
    exit(true)
}

/// Ends the run with `why`: QEMU exits with failure.
pub fn fail(why: &str) -> ! {
    hprintln!("{}", why);
    exit(false)
}

/// Ends the run, QEMU exiting with success or failure (nothing printed).
pub fn exit(success: bool) -> ! {
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::nop();
    }
}
