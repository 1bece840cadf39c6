//! The firmware's `defmt` logger: frames over semihosting to the host's
//! standard output, where `bushing-defmt-log` decodes them with the ELF's
//! table (nothing is formatted on the target).
//!
//! `defmt-semihosting` holds a critical section from the start of a frame
//! to its end, so every frame logged from thread mode would delay the
//! control interrupt by its encoding and its semihosting calls. This
//! logger never masks interrupts. A frame takes the logger with an atomic
//! counter; a frame begun while another is in progress (an interrupt that
//! logs while thread mode holds the logger) is dropped whole and counted
//! ([`dropped_frames`]), never interleaved with the other. The rig loop
//! logs from thread mode only, so logging adds nothing to its interrupt
//! latency.
//!
//! A frame is encoded into a buffer and written to the host when it ends
//! or the buffer fills: one semihosting call for most frames.
// The logger is a shared static that defmt reaches through its
// `global_logger` symbols: `unsafe` for the trait and for the cell the
// frame in progress owns (see `with_sink`).
#![allow(unsafe_code)]

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m_semihosting::hio::{self, HostStream};

#[defmt::global_logger]
struct Logger;

/// Frames begun and not yet ended: 0 when the logger is free, 1 while a
/// frame owns it, more while interrupts nest frames that are dropped.
static DEPTH: AtomicU32 = AtomicU32::new(0);

/// Frames dropped because another frame was in progress.
static DROPPED: AtomicU32 = AtomicU32::new(0);

/// Bytes of encoded frame held before a semihosting write.
const BUFFER: usize = 96;

/// What the frame in progress writes to.
struct Sink {
    encoder: defmt::Encoder,
    /// The host's standard output, opened by the first frame.
    stream: Option<HostStream>,
    buffer: [u8; BUFFER],
    len: usize,
}

impl Sink {
    /// Runs `f` with the encoder and a writer of its output into the
    /// buffer.
    fn encode(&mut self, f: impl FnOnce(&mut defmt::Encoder, &mut dyn FnMut(&[u8]))) {
        let Self {
            encoder,
            stream,
            buffer,
            len,
        } = self;
        f(encoder, &mut |b| Self::push(buffer, len, stream, b));
    }

    /// Appends encoded bytes, writing the buffer out whenever it fills.
    /// Not inlined: one copy for the three callers (flash).
    #[inline(never)]
    fn push(
        buffer: &mut [u8; BUFFER],
        len: &mut usize,
        stream: &mut Option<HostStream>,
        bytes: &[u8],
    ) {
        for &b in bytes {
            if *len == BUFFER {
                Self::write_out(buffer, len, stream);
            }
            if let Some(slot) = buffer.get_mut(*len) {
                *slot = b;
                *len += 1;
            }
        }
    }

    /// Writes the buffered bytes to the host. A failed write loses them:
    /// the decoder then reports a malformed frame.
    fn write_out(buffer: &[u8; BUFFER], len: &mut usize, stream: &mut Option<HostStream>) {
        if let (Some(s), Some(bytes)) = (stream.as_mut(), buffer.get(..*len)) {
            // Semihosting has no other channel to report on.
            let _ = s.write_all(bytes);
        }
        *len = 0;
    }
}

struct Shared(UnsafeCell<Sink>);

// SAFETY: the sink is only reached through `with_sink`, by the one frame
// that owns the logger (see there).
unsafe impl Sync for Shared {}

static SINK: Shared = Shared(UnsafeCell::new(Sink {
    encoder: defmt::Encoder::new(),
    stream: None,
    buffer: [0; BUFFER],
    len: 0,
}));

/// Runs `f` on the sink when the caller's frame owns the logger (depth
/// 1); a nested frame's calls do nothing.
fn with_sink(f: impl FnOnce(&mut Sink)) {
    if DEPTH.load(Ordering::Acquire) != 1 {
        return;
    }
    // SAFETY: on one core, depth 1 seen here means this context began the
    // one frame in progress: a context that interrupts it raises the depth
    // before any call of its own and lowers it again before it returns, so
    // no other reference to the sink exists while this one lives.
    let sink = unsafe { &mut *SINK.0.get() };
    f(sink);
}

// SAFETY: `acquire` and `release` pair up as defmt requires; frames never
// interleave (a nested frame writes nothing), and nothing here panics.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        if DEPTH.fetch_add(1, Ordering::Acquire) != 0 {
            DROPPED.fetch_add(1, Ordering::Relaxed);
            return;
        }
        with_sink(|sink| {
            if sink.stream.is_none() {
                sink.stream = hio::hstdout().ok();
            }
            sink.encode(|e, w| e.start_frame(w));
        });
    }

    unsafe fn flush() {}

    unsafe fn release() {
        with_sink(|sink| {
            sink.encode(|e, w| e.end_frame(w));
            Sink::write_out(&sink.buffer, &mut sink.len, &mut sink.stream);
        });
        DEPTH.fetch_sub(1, Ordering::Release);
    }

    unsafe fn write(bytes: &[u8]) {
        with_sink(|sink| sink.encode(|e, w| e.write(bytes, w)));
    }
}

/// Frames dropped so far because another frame was in progress.
pub fn dropped_frames() -> u32 {
    DROPPED.load(Ordering::Relaxed)
}
