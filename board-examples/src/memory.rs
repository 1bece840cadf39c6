//! Flash, static RAM and stack of the running firmware, read from the
//! symbols of cortex-m-rt's `link.x`.
//!
//! The stack high-water mark is measured by painting: [`paint_stack`] fills
//! the free RAM between the end of the statics (`__sheap`) and the current
//! stack pointer with a pattern, and [`stack_high_water`] finds the lowest
//! word the stack has overwritten since. Under QEMU the result is exact
//! and repeats run to run.
#![allow(unsafe_code)]

use core::ptr::{addr_of, read_volatile, write_volatile};

/// The paint pattern.
const PAINT: u32 = 0xCCCC_CCCC;
/// Bytes left unpainted below the stack pointer of the caller (its own
/// frame and the painting loop's).
const MARGIN: usize = 256;

unsafe extern "C" {
    static __sidata: u32;
    static __sdata: u32;
    static __edata: u32;
    static __ebss: u32;
    static __sheap: u32;
    static _stack_start: u32;
}

/// Address of a linker symbol.
fn at(symbol: *const u32) -> usize {
    symbol as usize
}

/// Bytes of flash the image takes: code, read-only data and the initial
/// values of `.data` (everything up to the end of `.data`'s load image;
/// the image starts at address 0, the vector table).
pub fn flash_bytes() -> usize {
    let (sidata, sdata, edata) = (
        at(addr_of!(__sidata)),
        at(addr_of!(__sdata)),
        at(addr_of!(__edata)),
    );
    sidata + (edata - sdata)
}

/// Bytes of static RAM: `.data` and `.bss`.
pub fn static_ram_bytes() -> usize {
    let (sdata, ebss) = (at(addr_of!(__sdata)), at(addr_of!(__ebss)));
    ebss - sdata
}

/// Paints the free RAM below the current stack frame.
#[inline(never)]
pub fn paint_stack() {
    // SAFETY: the words between the end of the statics and MARGIN bytes
    // below the stack pointer belong to no live object: nothing but the
    // stack grows there, and it has not reached them yet.
    unsafe {
        let low = at(addr_of!(__sheap));
        let sp = cortex_m::register::msp::read() as usize;
        let mut a = low;
        while a + MARGIN < sp {
            write_volatile(a as *mut u32, PAINT);
            a += 4;
        }
    }
}

/// Bytes of stack used since [`paint_stack`]: from the top of RAM down to
/// the lowest word that no longer holds the pattern.
pub fn stack_high_water() -> usize {
    // SAFETY: reads words of RAM between the end of the statics and the
    // top of the stack, all mapped and aligned.
    unsafe {
        let (low, top) = (at(addr_of!(__sheap)), at(addr_of!(_stack_start)));
        let mut a = low;
        while a < top && read_volatile(a as *const u32) == PAINT {
            a += 4;
        }
        top - a
    }
}
