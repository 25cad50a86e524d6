//! A progress bar for big clouds: drawn on stderr with indicatif when stderr is a
//! terminal and the work has at least [`MIN_POINTS`] points; otherwise nothing at all
//! (no output in tests, pipes, CI logs or the viewer's log).

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Smallest number of points for which a bar is shown.
pub const MIN_POINTS: u64 = 1_000_000;

/// True when bars can be drawn at all (stderr is a terminal).
pub fn enabled() -> bool {
    std::io::stderr().is_terminal()
}

/// A bar that may not be shown; cleared when dropped.
pub struct Progress(Option<ProgressBar>);

impl Progress {
    /// A bar for `total` points of work described by `what` (e.g. "reading x.laz").
    pub fn new(total: u64, what: &str) -> Progress {
        if total < MIN_POINTS || !enabled() {
            return Progress(None);
        }
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        if let Ok(style) =
            ProgressStyle::with_template("{msg} [{bar:40}] {human_pos}/{human_len} points {eta}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(what.to_string());
        Progress(Some(bar))
    }

    /// A bar that is never shown.
    pub fn hidden() -> Progress {
        Progress(None)
    }

    /// `n` more points done (callable from several threads).
    pub fn inc(&self, n: u64) {
        if let Some(bar) = &self.0 {
            bar.inc(n);
        }
    }

    /// True when the bar is drawn.
    pub fn is_shown(&self) -> bool {
        self.0.is_some()
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(bar) = &self.0 {
            bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_work_or_no_terminal_draws_nothing() {
        assert!(!Progress::new(10, "x").is_shown());
        if !std::io::stderr().is_terminal() {
            assert!(!Progress::new(MIN_POINTS * 10, "x").is_shown());
        }
        let p = Progress::hidden();
        p.inc(5);
        assert!(!p.is_shown());
    }
}
