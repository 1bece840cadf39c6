//! The progress bar of a long run, on stderr through `indicatif`: shown
//! only when stderr is a terminal and the run is long (more than a million
//! steps, or about a second expected), at most ten updates a second.

use std::time::Instant;

use bushing::Real;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::RunError;
use super::pipeline::{Sink, Step};

/// Runs above this many steps show the bar from the start.
const LONG_RUN: u64 = 1_000_000;

/// A progress bar that appears once a run proves long.
pub struct Progress {
    bar: Option<ProgressBar>,
    enabled: bool,
    total: u64,
    start: Instant,
}

impl Progress {
    /// A bar for `total` steps; `enabled` is the caller's wish, honoured
    /// only on a terminal.
    pub fn new(enabled: bool, total: u64) -> Self {
        let enabled = enabled && std::io::IsTerminal::is_terminal(&std::io::stderr());
        Self {
            bar: None,
            enabled,
            total,
            start: Instant::now(),
        }
    }

    fn show(&mut self) -> Option<&ProgressBar> {
        if self.bar.is_none() {
            let bar = ProgressBar::with_draw_target(
                Some(self.total),
                ProgressDrawTarget::stderr_with_hz(10),
            );
            if let Ok(style) = ProgressStyle::with_template(
                "[{bar:30}] {percent:>3} % {pos}/{len} steps, {eta} left",
            ) {
                bar.set_style(style.progress_chars("#>-"));
            }
            self.bar = Some(bar);
        }
        self.bar.as_ref()
    }

    /// Clears the bar.
    pub fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

impl<T: Real> Sink<T> for Progress {
    fn step(&mut self, _: &Step<'_, T>) -> Result<(), RunError> {
        Ok(())
    }

    fn chunk_done(&mut self, done: u64) {
        if !self.enabled || done >= self.total {
            return;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        let expected = elapsed * self.total as f64 / done.max(1) as f64;
        if self.bar.is_none() && self.total <= LONG_RUN && expected < 1.0 {
            return;
        }
        if let Some(bar) = self.show() {
            bar.set_position(done);
        }
    }
}
