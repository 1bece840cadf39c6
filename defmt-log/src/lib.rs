//! Decodes a firmware's `defmt` log: the bytes its logger wrote (over
//! semihosting, to QEMU's standard output) and the table of format
//! strings in its ELF. Nothing was formatted on the target; the text is
//! made here, one line per frame.
//!
//! Decoding is strict, so that a log CI checks is the log the firmware
//! wrote: a malformed frame, a log that ends inside a frame, an ELF without
//! a defmt table or one from another defmt version are errors, never
//! skipped.

use std::io::Write;

use defmt_decoder::{DecodeError, Table};

/// Why a log could not be decoded.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The ELF could not be read, or its defmt version is not this
    /// decoder's.
    #[error("the ELF's defmt table cannot be read: {0}")]
    Table(String),
    /// The ELF holds no defmt table (a firmware that does not log with
    /// defmt).
    #[error("the ELF has no defmt table: was it linked with defmt.x?")]
    NoTable,
    /// A frame does not decode against the table.
    #[error("frame {frame} is malformed (counted from 0)")]
    Malformed {
        /// Frames decoded before it.
        frame: usize,
    },
    /// The log ends inside a frame (a firmware stopped mid-frame, or a
    /// truncated capture).
    #[error("the log ends inside a frame, after {frames} frames ({trailing} B left)")]
    Truncated {
        /// Frames decoded.
        frames: usize,
        /// Bytes after the last frame's end.
        trailing: usize,
    },
    /// Writing the text failed.
    #[error("writing the decoded log: {0}")]
    Write(#[from] std::io::Error),
}

/// Decodes `raw` with the table of `elf`, writing one line per frame to
/// `out`; returns the number of frames.
pub fn decode(elf: &[u8], raw: &[u8], out: &mut impl Write) -> Result<usize, LogError> {
    let table = Table::parse(elf)
        .map_err(|e| LogError::Table(format!("{e:#}")))?
        .ok_or(LogError::NoTable)?;
    let mut decoder = table.new_stream_decoder();
    decoder.received(raw);
    let mut frames = 0;
    loop {
        match decoder.decode() {
            Ok(frame) => {
                writeln!(out, "{}", frame.display_message())?;
                frames += 1;
            }
            Err(DecodeError::UnexpectedEof) => break,
            Err(DecodeError::Malformed) => return Err(LogError::Malformed { frame: frames }),
        }
    }
    // An rzcobs frame ends with a zero byte: bytes after the last one are
    // a frame the decoder is still waiting for.
    let trailing = tail_after_last_zero(raw);
    if trailing > 0 {
        return Err(LogError::Truncated { frames, trailing });
    }
    Ok(frames)
}

/// Bytes after the last zero byte (all of them when there is none).
fn tail_after_last_zero(raw: &[u8]) -> usize {
    raw.iter().rev().take_while(|&&b| b != 0).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_that_is_not_an_elf_is_refused() {
        let err = decode(b"not an elf", &[], &mut Vec::new()).unwrap_err();
        assert!(matches!(err, LogError::Table(_)), "{err}");
    }

    #[test]
    fn an_elf_without_a_defmt_table_is_refused() {
        // This test's own executable: an ELF that does not log with defmt.
        let exe = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        let err = decode(&exe, &[1, 2, 0], &mut Vec::new()).unwrap_err();
        assert!(matches!(err, LogError::NoTable), "{err}");
    }

    #[test]
    fn the_tail_after_the_last_frame_end_is_counted() {
        assert_eq!(tail_after_last_zero(&[]), 0);
        assert_eq!(tail_after_last_zero(&[5, 6, 0]), 0);
        assert_eq!(tail_after_last_zero(&[5, 6, 0, 7, 0, 8, 9]), 2);
        assert_eq!(tail_after_last_zero(&[8, 9]), 2);
    }
}
