//! Progress bars with an estimate of the time left, for everything that can run long:
//! studies, benches, the f64 references and big loaders. One place builds them, so that
//! every bar looks alike and obeys one rule for when it is drawn.
//!
//! A bar is drawn on stderr only when stderr is a terminal and the `CI` environment
//! variable is unset, empty, `0` or `false` ([`decide`]); otherwise nothing at all is
//! drawn (no output in tests, pipes, CI logs or the viewer's log). All bars of a process
//! share one [`indicatif::MultiProgress`], so nested work (a study's reference computation
//! under the study's own bar) stacks instead of overwriting. Lines a study prints go
//! through [`line`], which lifts the bars, prints, and redraws them.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// What a bar counts (its template).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Points of a cloud: `12.3M/57.0M points`.
    Points,
    /// Image rows of a CPU reference: `180/512 rows`.
    Rows,
    /// Weighted work units of a study or bench, shown as a percentage.
    Work,
}

impl Unit {
    fn template(self) -> &'static str {
        match self {
            Unit::Points => "{msg} [{bar:40}] {human_pos}/{human_len} points, about {eta} left",
            Unit::Rows => "{msg} [{bar:30}] {pos}/{len} rows, about {eta} left",
            Unit::Work => "{msg} [{bar:30}] {percent:>3}%, {elapsed} so far, about {eta} left",
        }
    }
}

/// Whether bars are drawn, given whether stderr is a terminal and the value of `CI`.
pub fn decide(terminal: bool, ci: Option<&str>) -> bool {
    let in_ci = ci.is_some_and(|v| {
        let v = v.trim();
        !(v.is_empty() || v == "0" || v.eq_ignore_ascii_case("false"))
    });
    terminal && !in_ci
}

/// True when bars are drawn in this process (see [`decide`]).
pub fn enabled() -> bool {
    static ENABLED: OnceLock<bool> = OnceLock::new();
    *ENABLED.get_or_init(|| {
        decide(
            std::io::stderr().is_terminal(),
            std::env::var("CI").ok().as_deref(),
        )
    })
}

/// The process's bars (created on the first drawn bar).
fn multi() -> &'static MultiProgress {
    static MULTI: OnceLock<MultiProgress> = OnceLock::new();
    MULTI.get_or_init(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr()))
}

/// Print `text` as a line on stderr, above any bars being drawn.
pub fn line(text: &str) {
    if enabled() {
        multi().suspend(|| eprintln!("{text}"));
    } else {
        eprintln!("{text}");
    }
}

/// A bar that may not be drawn; cleared when dropped. Counting is thread-safe.
pub struct Bar {
    bar: Option<ProgressBar>,
    /// For a delayed bar: when counting began and whether it is on screen yet.
    delay: Option<(Instant, Duration, AtomicBool)>,
}

impl Bar {
    /// A bar for `total` units of work described by `what`, drawn from the start.
    pub fn new(total: u64, what: &str, unit: Unit) -> Bar {
        Bar::build(total, what, unit, None)
    }

    /// A bar that appears only if the work is still going after `after` (for work that
    /// is often quick, such as a reference at a small size: no flicker).
    pub fn delayed(total: u64, what: &str, unit: Unit, after: Duration) -> Bar {
        Bar::build(total, what, unit, Some(after))
    }

    /// A bar that is never drawn.
    pub fn hidden() -> Bar {
        Bar {
            bar: None,
            delay: None,
        }
    }

    fn build(total: u64, what: &str, unit: Unit, after: Option<Duration>) -> Bar {
        if !enabled() {
            return Bar::hidden();
        }
        let bar = ProgressBar::hidden();
        bar.set_length(total);
        if let Ok(style) = ProgressStyle::with_template(unit.template()) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(what.to_string());
        let delay = match after {
            Some(after) => Some((Instant::now(), after, AtomicBool::new(false))),
            None => {
                let bar = multi().add(bar.clone());
                bar.tick();
                None
            }
        };
        Bar {
            bar: Some(bar),
            delay,
        }
    }

    /// `n` more units done.
    pub fn inc(&self, n: u64) {
        let Some(bar) = &self.bar else { return };
        bar.inc(n);
        if let Some((start, after, shown)) = &self.delay {
            if !shown.load(Ordering::Relaxed)
                && start.elapsed() >= *after
                && !shown.swap(true, Ordering::Relaxed)
            {
                multi().add(bar.clone());
            }
        }
    }

    /// Say what is being done now (the text before the bar).
    pub fn set_message(&self, what: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(what.to_string());
        }
    }

    /// True when the bar may be drawn (bars are enabled; a delayed bar may still wait).
    pub fn is_shown(&self) -> bool {
        self.bar.is_some()
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
            multi().remove(bar);
        }
    }
}

/// Plain progress lines for long work whose bar is not drawn (stderr is a file or a
/// pipe, or CI): after `first`, a line of how far it got and the time left, then one
/// every `every`. Silent where a bar shows the same. Counting is thread-safe.
pub struct Lines {
    what: String,
    total: u64,
    done: std::sync::atomic::AtomicU64,
    start: Instant,
    /// Milliseconds after `start` when the next line is due.
    next_ms: std::sync::atomic::AtomicU64,
    every: Duration,
}

impl Lines {
    /// Lines for `total` units of `unit_name` of `what`.
    pub fn new(what: &str, total: u64, first: Duration, every: Duration) -> Lines {
        Lines {
            what: what.to_string(),
            total,
            done: std::sync::atomic::AtomicU64::new(0),
            start: Instant::now(),
            next_ms: std::sync::atomic::AtomicU64::new(first.as_millis() as u64),
            every,
        }
    }

    /// `n` more units done; prints a line when one is due.
    pub fn inc(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        if enabled() {
            return;
        }
        let elapsed = self.start.elapsed();
        let ms = elapsed.as_millis() as u64;
        let due = self.next_ms.load(Ordering::Relaxed);
        if ms < due || done >= self.total {
            return;
        }
        let next = ms + self.every.as_millis() as u64;
        if self
            .next_ms
            .compare_exchange(due, next, Ordering::Relaxed, Ordering::Relaxed)
            .is_ok()
        {
            let left = elapsed.as_secs_f64() * (self.total - done) as f64 / done.max(1) as f64;
            line(&format!(
                "{}: {done} of {} done in {:.0} s, about {left:.0} s left",
                self.what,
                self.total,
                elapsed.as_secs_f64()
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawn_only_on_a_terminal_outside_ci() {
        assert!(decide(true, None));
        // CI providers set CI=true (GitHub, GitLab) or CI=1; an empty, 0 or false value
        // means "not CI", as most tools read it.
        for ci in ["", "0", "false", "FALSE", " "] {
            assert!(decide(true, Some(ci)), "{ci:?}");
        }
        for ci in ["true", "1", "yes", "True"] {
            assert!(!decide(true, Some(ci)), "{ci:?}");
        }
        assert!(!decide(false, None));
        assert!(!decide(false, Some("false")));
    }

    #[test]
    fn a_bar_off_a_terminal_is_hidden_and_counts_nothing() {
        // cargo test captures stderr through a pipe: no terminal, so no bar.
        if std::io::stderr().is_terminal() {
            return;
        }
        let bar = Bar::new(10, "x", Unit::Work);
        bar.inc(3);
        bar.set_message("y");
        assert!(!bar.is_shown());
        assert!(!Bar::delayed(10, "x", Unit::Rows, Duration::ZERO).is_shown());
        assert!(!Bar::hidden().is_shown());
    }
}
