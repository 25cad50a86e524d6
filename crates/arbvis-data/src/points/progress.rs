//! A progress bar for big clouds: [`arbvis_core::progress`]'s bar, drawn only when the work has
//! at least [`MIN_POINTS`] points (and bars are drawn at all: stderr a terminal, not CI).

use arbvis_core::progress::{Bar, Unit};

/// Smallest number of points for which a bar is shown.
pub const MIN_POINTS: u64 = 1_000_000;

/// True when bars can be drawn at all (see [`arbvis_core::progress::enabled`]).
pub fn enabled() -> bool {
    arbvis_core::progress::enabled()
}

/// A bar that may not be shown; cleared when dropped.
pub struct Progress(Bar);

impl Progress {
    /// A bar for `total` points of work described by `what` (e.g. "reading x.laz").
    pub fn new(total: u64, what: &str) -> Progress {
        if total < MIN_POINTS {
            return Progress::hidden();
        }
        Progress(Bar::new(total, what, Unit::Points))
    }

    /// A bar that is never shown.
    pub fn hidden() -> Progress {
        Progress(Bar::hidden())
    }

    /// `n` more points done (callable from several threads).
    pub fn inc(&self, n: u64) {
        self.0.inc(n);
    }

    /// True when the bar is drawn.
    pub fn is_shown(&self) -> bool {
        self.0.is_shown()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_work_or_no_terminal_draws_nothing() {
        assert!(!Progress::new(10, "x").is_shown());
        if !enabled() {
            assert!(!Progress::new(MIN_POINTS * 10, "x").is_shown());
        }
        let p = Progress::hidden();
        p.inc(5);
        assert!(!p.is_shown());
    }
}
