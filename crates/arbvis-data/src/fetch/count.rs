//! Request counts: what this process has fetched, for the tests, `--stats` and the
//! viewer's status line.

// Without `remote` no request is counted.
#![cfg_attr(not(feature = "remote"), allow(dead_code))]

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

static REQUESTS: AtomicU64 = AtomicU64::new(0);
static BYTES: AtomicU64 = AtomicU64::new(0);
static FROM_DISK: AtomicU64 = AtomicU64::new(0);
static IN_FLIGHT: AtomicU64 = AtomicU64::new(0);

/// What this process has fetched.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Requests sent (GET and HEAD, retries not counted).
    pub requests: u64,
    /// Body bytes received.
    pub bytes: u64,
    /// Bytes served by the disk cache.
    pub from_disk: u64,
    /// Requests in flight now.
    pub in_flight: u64,
}

/// The counts so far.
pub fn stats() -> Stats {
    Stats {
        requests: REQUESTS.load(Relaxed),
        bytes: BYTES.load(Relaxed),
        from_disk: FROM_DISK.load(Relaxed),
        in_flight: IN_FLIGHT.load(Relaxed),
    }
}

/// What is loading, for a status line: `None` while nothing is in flight.
pub fn status() -> Option<String> {
    let s = stats();
    (s.in_flight > 0).then(|| {
        format!(
            "fetching: {} request{} in flight, {:.1} MB fetched",
            s.in_flight,
            if s.in_flight == 1 { "" } else { "s" },
            s.bytes as f64 / 1e6
        )
    })
}

/// A request under way, until dropped.
pub struct Busy;

impl Drop for Busy {
    fn drop(&mut self) {
        IN_FLIGHT.fetch_sub(1, Relaxed);
    }
}

pub(super) fn request() -> Busy {
    REQUESTS.fetch_add(1, Relaxed);
    IN_FLIGHT.fetch_add(1, Relaxed);
    Busy
}

pub(super) fn fetched(n: usize) {
    BYTES.fetch_add(n as u64, Relaxed);
}

pub(super) fn from_disk(n: usize) {
    FROM_DISK.fetch_add(n as u64, Relaxed);
}
