//! The memory budget: how much memory one file, scene or computation may make arbvis
//! allocate, checked *before* the allocation from what the input declares or implies.
//!
//! A small file can ask for a great deal (a compressed array that inflates a thousandfold,
//! a point count that a LAZ file repeats cheaply, a grid size in a scene), so every large
//! allocation is first estimated and compared with the budget; where no estimate is
//! possible the allocation is fallible ([`vec_for`], `try_reserve`), so it ends in an error,
//! never in an abort.
//!
//! How the budget is set, first match wins:
//! 1. the command line's `--memory-budget SIZE` (or a library caller's [`set`]);
//! 2. the environment variable `ARBVIS_MEMORY_BUDGET=SIZE`;
//! 3. a scene's top-level `memory_budget = "SIZE"`;
//! 4. the default: half of the memory this process may use: the smallest of `MemTotal` in
//!    `/proc/meminfo`, a cgroup limit, and the process's own limits (`ulimit -v`, the
//!    address space, and `ulimit -d`, the data segment; of the address space, only what
//!    is left after the 1 GiB that the GL driver and the program's code map); 4 GiB where
//!    none can be read.
//!
//! SIZE is bytes with an optional unit (`512M`, `16G`, `1.5T`; K/M/G/T are powers of 1024,
//! an optional `iB`/`B` is accepted) or a share of physical memory (`75%`).
//!
//! While a reader runs inside [`for_input`] and the budget is the default, it is also
//! bounded by the size of the file being read: [`INPUT_RATIO`] bytes per byte of the
//! file, at least [`INPUT_FLOOR`]. A legal file that makes far more than it holds (a
//! zlib array that inflates a thousandfold, gmsh data sections that each make a dense
//! array) is then refused in milliseconds instead of being made for tens of seconds;
//! choosing a budget (1 to 3 above) lifts the ratio, so a user who wants such a file read
//! says so with a size.
//!
//! The check is per allocation (or per group of allocations made together), not a running
//! total: it bounds what one input can make arbvis ask for.

use std::cell::Cell;
use std::sync::atomic::{AtomicU64, AtomicU8, Ordering};
use std::sync::OnceLock;

/// Where the budget in force came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// Half of physical memory.
    Default,
    /// `ARBVIS_MEMORY_BUDGET`.
    Environment,
    /// A scene's `memory_budget`.
    Scene,
    /// `--memory-budget` or [`set`].
    Explicit,
    /// The default bounded by the size (bytes) of the file being read ([`for_input`]).
    Input(u64),
}

impl Source {
    fn describe(self) -> String {
        match self {
            Source::Default => format!("the default, half of {}", default_limit().1),
            Source::Environment => "from ARBVIS_MEMORY_BUDGET".into(),
            Source::Scene => "from the scene's memory_budget".into(),
            Source::Explicit => "from --memory-budget".into(),
            Source::Input(len) => format!(
                "the default for a file of {}: {INPUT_RATIO} bytes per byte of the file, at least {}",
                format_bytes(len),
                format_bytes(INPUT_FLOOR)
            ),
        }
    }
}

/// Bytes a reader may make per byte of its file while the budget is the default.
pub const INPUT_RATIO: u64 = 32;

/// What a reader may make whatever the size of its file, while the budget is the default.
pub const INPUT_FLOOR: u64 = 64 << 20;

thread_local! {
    /// The size of the file the reader running on this thread reads ([`for_input`]).
    static INPUT: Cell<Option<u64>> = const { Cell::new(None) };
}

/// Run `read`, a reader of a file of `len` bytes, with the default budget also bounded by
/// that size (see the module doc); on this thread only, and restored afterwards (also
/// when `read` panics).
pub fn for_input<R>(len: u64, read: impl FnOnce() -> R) -> R {
    struct Restore(Option<u64>);
    impl Drop for Restore {
        fn drop(&mut self) {
            INPUT.set(self.0);
        }
    }
    let _restore = Restore(INPUT.replace(Some(len)));
    read()
}

/// The budget in force: bytes and where they came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// Largest allocation (or group of allocations) allowed, in bytes.
    pub bytes: u64,
    /// Where that number came from.
    pub source: Source,
}

/// An allocation the budget refuses, or one the system could not make.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum OverBudget {
    /// The estimate is over the budget.
    #[error(
        "{what} needs about {}, more than the memory budget of {} ({}); raise it with \
         --memory-budget SIZE, ARBVIS_MEMORY_BUDGET=SIZE or memory_budget = \"SIZE\" in the \
         scene (e.g. 16G or 75%)",
        format_bytes(*.estimate), format_bytes(.budget.bytes), .budget.source.describe()
    )]
    Over {
        /// What was to be allocated.
        what: String,
        /// Its estimated size in bytes.
        estimate: u64,
        /// The budget it was held to.
        budget: Budget,
    },
    /// Within the budget, but the system refused the memory.
    #[error("{what}: the system could not provide {} of memory", format_bytes(*.bytes))]
    Refused {
        /// What was to be allocated.
        what: String,
        /// How much.
        bytes: u64,
    },
}

/// The message, for the readers that place it at a position in their file.
impl From<OverBudget> for String {
    fn from(e: OverBudget) -> String {
        e.to_string()
    }
}

const NOT_SET: u8 = 0;
static CHOSEN_BYTES: AtomicU64 = AtomicU64::new(0);
static CHOSEN_SOURCE: AtomicU8 = AtomicU8::new(NOT_SET);

fn source_code(s: Source) -> u8 {
    match s {
        Source::Default => 1,
        Source::Environment => 2,
        Source::Scene => 3,
        Source::Explicit => 4,
        Source::Input(_) => 1,
    }
}

fn source_of(code: u8) -> Source {
    match code {
        2 => Source::Environment,
        3 => Source::Scene,
        4 => Source::Explicit,
        _ => Source::Default,
    }
}

/// The budget before anything was chosen: the environment's, else the default.
fn initial() -> Budget {
    static INITIAL: OnceLock<Budget> = OnceLock::new();
    *INITIAL.get_or_init(|| {
        if let Ok(text) = std::env::var("ARBVIS_MEMORY_BUDGET") {
            if let Ok(bytes) = parse(&text) {
                return Budget {
                    bytes,
                    source: Source::Environment,
                };
            }
        }
        Budget {
            bytes: default_bytes(),
            source: Source::Default,
        }
    })
}

/// Half of the memory this process may use ([`default_limit`]).
pub fn default_bytes() -> u64 {
    default_limit().0 / 2
}

/// Address space the GL driver, its threads and the program's code take before any data
/// (llvmpipe maps several hundred MiB): what `ulimit -v` leaves for data is its limit
/// less this.
const MAPPED_BEFORE_DATA: u64 = 1 << 30;

/// The memory this process may use and what bounds it: physical memory (or the cgroup's
/// limit), or the process's own limits where smaller; 8 GiB where none can be read.
pub fn default_limit() -> (u64, &'static str) {
    static LIMIT: OnceLock<(u64, &'static str)> = OnceLock::new();
    *LIMIT.get_or_init(|| {
        let mut best = (8u64 << 30, "8 GiB (no memory size could be read)");
        if let Some(m) = physical_memory() {
            best = (m, "physical memory (or the cgroup's limit)");
        }
        let (address, data) = process_limits();
        if let Some(a) = address {
            let usable = a.saturating_sub(MAPPED_BEFORE_DATA);
            if usable < best.0 {
                best = (
                    usable,
                    "the address space `ulimit -v` allows, less 1 GiB for the driver and code",
                );
            }
        }
        if let Some(d) = data {
            if d < best.0 {
                best = (d, "the data size `ulimit -d` allows");
            }
        }
        best
    })
}

/// The soft limits on address space and data size (`/proc/self/limits`), where set.
fn process_limits() -> (Option<u64>, Option<u64>) {
    let Ok(text) = std::fs::read_to_string("/proc/self/limits") else {
        return (None, None);
    };
    let soft = |name: &str| {
        let line = text.lines().find(|l| l.starts_with(name))?;
        line[name.len()..]
            .split_whitespace()
            .next()?
            .parse::<u64>()
            .ok()
    };
    (soft("Max address space"), soft("Max data size"))
}

/// The machine's memory as this process may use it: the smaller of `MemTotal` and the
/// cgroup's `memory.max`, when either can be read.
pub fn physical_memory() -> Option<u64> {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        let line = t.lines().find(|l| l.starts_with("MemTotal:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        kib.checked_mul(1024)
    });
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|t| t.trim().parse::<u64>().ok());
    match (total, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// The budget chosen for the process (not bounded by an input).
fn chosen() -> Budget {
    let code = CHOSEN_SOURCE.load(Ordering::Acquire);
    if code == NOT_SET {
        return initial();
    }
    Budget {
        bytes: CHOSEN_BYTES.load(Ordering::Acquire),
        source: source_of(code),
    }
}

/// The budget in force (on this thread: see [`for_input`]).
pub fn current() -> Budget {
    let chosen = chosen();
    match (chosen.source, INPUT.get()) {
        (Source::Default, Some(len)) => {
            let bound = len.saturating_mul(INPUT_RATIO).max(INPUT_FLOOR);
            if bound < chosen.bytes {
                return Budget {
                    bytes: bound,
                    source: Source::Input(len),
                };
            }
            chosen
        }
        _ => chosen,
    }
}

/// Choose the budget for the rest of the process (`--memory-budget`, a test's bound).
pub fn set(bytes: u64) {
    choose(bytes, Source::Explicit);
}

/// A scene's `memory_budget`: taken only where neither `--memory-budget` nor
/// `ARBVIS_MEMORY_BUDGET` chose one.
pub fn set_from_scene(bytes: u64) {
    let now = chosen().source;
    if matches!(now, Source::Default | Source::Scene) {
        choose(bytes, Source::Scene);
    }
}

fn choose(bytes: u64, source: Source) {
    CHOSEN_BYTES.store(bytes, Ordering::Release);
    CHOSEN_SOURCE.store(source_code(source), Ordering::Release);
}

/// Refuse `estimate` bytes for `what` if it is over the budget.
pub fn check(what: impl Into<String>, estimate: u64) -> Result<(), OverBudget> {
    let budget = current();
    if estimate > budget.bytes {
        return Err(OverBudget::Over {
            what: what.into(),
            estimate,
            budget,
        });
    }
    Ok(())
}

/// One large allocation something will make, estimated before any work.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Estimate {
    /// What it is for, e.g. `the read-back of a 16384x16384 frame`.
    pub what: String,
    /// Its size in bytes.
    pub bytes: u64,
}

impl Estimate {
    /// `count` items of `each` bytes for `what`.
    pub fn of(what: impl Into<String>, count: u64, each: u64) -> Estimate {
        Estimate {
            what: what.into(),
            bytes: times(count, each),
        }
    }
}

/// Refuse `estimates`, made together for `of` (e.g. `rendering scene.toml`), when their
/// sum is over the budget; the error lists each part.
pub fn check_estimates(of: &str, estimates: &[Estimate]) -> Result<(), OverBudget> {
    let total = estimates
        .iter()
        .fold(0u64, |a, e| a.saturating_add(e.bytes));
    if total <= current().bytes {
        return Ok(());
    }
    let parts: Vec<String> = estimates
        .iter()
        .filter(|e| e.bytes > 0)
        .map(|e| format!("{}: {}", e.what, format_bytes(e.bytes)))
        .collect();
    check(format!("{of} ({})", parts.join("; ")), total)
}

/// `count` items of `each` bytes, saturating (an estimate, never an overflow).
pub fn times(count: u64, each: u64) -> u64 {
    count.saturating_mul(each)
}

/// An empty vector with room for `n` items: checked against the budget, then reserved
/// fallibly, so a refusal is an error value, never an abort.
pub fn vec_for<T>(n: usize, what: &str) -> Result<Vec<T>, OverBudget> {
    let bytes = times(n as u64, std::mem::size_of::<T>() as u64);
    check(what, bytes)?;
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| OverBudget::Refused {
        what: what.to_string(),
        bytes,
    })?;
    Ok(v)
}

/// Reserve room for `more` items in `v`, checked against the budget (counting what `v`
/// already holds) and fallible.
pub fn reserve<T>(v: &mut Vec<T>, more: usize, what: &str) -> Result<(), OverBudget> {
    let items = (v.len() as u64).saturating_add(more as u64);
    let bytes = times(items, std::mem::size_of::<T>() as u64);
    check(what, bytes)?;
    v.try_reserve(more).map_err(|_| OverBudget::Refused {
        what: what.to_string(),
        bytes,
    })
}

/// A SIZE (`--memory`, `gpu_memory`) that is not one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SizeError {
    /// Not a number with a unit or a percentage.
    #[error(
        "{0:?} is not a memory size: write bytes with an optional unit (512M, 16G, 1.5T) \
         or a share of physical memory (75%)"
    )]
    NotASize(String),
    /// A percentage outside (0, 100].
    #[error("{0:?}: a share of memory must be in (0, 100] %")]
    Share(String),
    /// Below one byte or from 8 EiB up.
    #[error("{0:?}: a memory budget must be at least 1 byte and below 8 EiB")]
    Range(String),
}

/// Parse a SIZE: bytes with an optional K/M/G/T unit (powers of 1024, `B`/`iB` optional),
/// or a percentage of physical memory.
pub fn parse(text: &str) -> Result<u64, SizeError> {
    let t = text.trim();
    let bad = || SizeError::NotASize(text.to_string());
    if let Some(p) = t.strip_suffix('%') {
        let share: f64 = p.trim().parse().map_err(|_| bad())?;
        if !(share > 0.0 && share <= 100.0) {
            return Err(SizeError::Share(text.to_string()));
        }
        let mem = physical_memory().unwrap_or(8 << 30) as f64;
        return Ok((mem * share / 100.0) as u64);
    }
    let upper = t.to_ascii_uppercase();
    let body = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (number, scale) = match body.chars().last() {
        Some('K') => (&body[..body.len() - 1], 1u64 << 10),
        Some('M') => (&body[..body.len() - 1], 1 << 20),
        Some('G') => (&body[..body.len() - 1], 1 << 30),
        Some('T') => (&body[..body.len() - 1], 1 << 40),
        _ => (body, 1),
    };
    let value: f64 = number.trim().parse().map_err(|_| bad())?;
    let bytes = value * scale as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < 2f64.powi(63)) {
        return Err(SizeError::Range(text.to_string()));
    }
    Ok(bytes as u64)
}

/// Bytes for people: `512 B`, `3.5 MiB`, `2.00 GiB`.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{bytes} B")
    } else if v >= 100.0 {
        format!("{v:.0} {}", UNITS[u])
    } else {
        format!("{v:.2} {}", UNITS[u])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_units_and_shares() {
        assert_eq!(parse("1024").unwrap(), 1024);
        assert_eq!(parse("512M").unwrap(), 512 << 20);
        assert_eq!(parse("16g").unwrap(), 16 << 30);
        assert_eq!(parse("2GiB").unwrap(), 2 << 30);
        assert_eq!(parse("1.5K").unwrap(), 1536);
        assert_eq!(parse(" 3 TB ").unwrap(), 3 << 40);
        let half = parse("50%").unwrap();
        assert!(half > 0);
        for bad in [
            "", "G", "-1G", "0", "abc", "101%", "0%", "nan", "1e30T", "inf",
        ] {
            assert!(parse(bad).is_err(), "{bad:?} should be refused");
        }
    }

    #[test]
    fn estimates_add_up_and_name_their_parts() {
        let parts = [
            Estimate::of("a read-back", 1 << 40, 16),
            Estimate::of("nothing", 0, 16),
            Estimate::of("a grid", 10, 8),
        ];
        let e = check_estimates("rendering x.toml", &parts)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("rendering x.toml (a read-back: 16.00 TiB; a grid: 80 B)"),
            "{e}"
        );
        assert!(!e.contains("nothing"), "{e}");
        assert!(check_estimates("small", &parts[1..]).is_ok());
        assert_eq!(Estimate::of("x", u64::MAX, 3).bytes, u64::MAX);
    }

    #[test]
    fn bytes_format_for_people() {
        assert_eq!(format_bytes(512), "512 B");
        assert_eq!(format_bytes(1536), "1.50 KiB");
        assert_eq!(format_bytes(4 << 30), "4.00 GiB");
        assert_eq!(format_bytes(300 << 20), "300 MiB");
    }

    #[test]
    fn the_default_is_half_of_memory() {
        if let Some(m) = physical_memory() {
            assert_eq!(default_bytes(), m / 2);
        }
    }

    #[test]
    fn a_reader_is_bounded_by_its_file_while_the_budget_is_the_default() {
        // Run where nothing else sets the budget: on a thread of its own, with the
        // source read back (another test may have chosen one for the process).
        std::thread::spawn(|| {
            let outside = current();
            let inside = for_input(1 << 20, current);
            if outside.source == Source::Default && outside.bytes > 320 << 20 {
                // 1 MiB of file: max(32 MiB, 64 MiB) = 64 MiB.
                assert_eq!(inside.bytes, INPUT_FLOOR);
                assert_eq!(inside.source, Source::Input(1 << 20));
                let big = for_input(10 << 20, current);
                assert_eq!(big.bytes, 320 << 20);
                let e = for_input(10 << 20, || check("x", 1 << 30)).unwrap_err();
                assert!(
                    e.to_string().contains(
                        "more than the memory budget of 320 MiB (the default for a file of 10.00 MiB: 32 bytes per byte of the file, at least 64.00 MiB)"
                    ),
                    "{e}"
                );
            } else {
                // A chosen budget is not bounded by the file.
                assert_eq!(inside, outside);
            }
            assert_eq!(current(), outside, "restored after the reader");
        })
        .join()
        .unwrap();
    }

    #[test]
    fn over_budget_names_the_estimate_the_budget_and_the_way_out() {
        let budget = Budget {
            bytes: 1 << 30,
            source: Source::Default,
        };
        let e = OverBudget::Over {
            what: "the point cloud (5 points)".into(),
            estimate: 3 << 30,
            budget,
        };
        let m = e.to_string();
        for part in [
            "the point cloud",
            "3.00 GiB",
            "1.00 GiB",
            "--memory-budget",
            "ARBVIS_MEMORY_BUDGET",
            "memory_budget",
        ] {
            assert!(m.contains(part), "{m}");
        }
        assert_eq!(times(u64::MAX, 2), u64::MAX);
    }
}
