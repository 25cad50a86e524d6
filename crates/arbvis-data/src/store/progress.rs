//! What makes a conversion safe to kill and to repeat: the lock that keeps a second writer
//! out, the progress log that lets the same command resume, and the checks that make a
//! damaged log an error naming its line instead of a panic.
//!
//! The log's first line is the job (input, its length and time, options); every finished
//! column appends one line. It is created whole (a temporary renamed into place) before
//! anything else of the store, so a conversion killed at any moment leaves either nothing
//! but the lock (a fresh start) or a log to resume from.

use std::collections::HashMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::meta::StoreMeta;
use super::StoreError;

/// The progress log's name inside the store.
pub const PROGRESS_LOG: &str = "arbvis-progress.log";

/// The lock file's name inside the store.
pub const LOCK_FILE: &str = "arbvis-convert.lock";

/// The job, as the progress log's first line (a resumed run must match it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct Job {
    pub input: String,
    pub bytes: u64,
    pub modified: u64,
    pub brick: usize,
    pub attributes: Vec<String>,
    /// The chunks' compression (`Compression`'s name; a log from before it has none).
    #[serde(default)]
    pub compression: String,
    /// A log from before `compression`: its zstd level (0: none), read as `compression`.
    #[serde(default, rename = "zstd", skip_serializing)]
    pub legacy_zstd: Option<i32>,
    pub raw: Option<String>,
    /// The store layout's version (a log written before version 2 has none).
    #[serde(default = "layout_one")]
    pub layout: u32,
}

fn layout_one() -> u32 {
    1
}

/// One finished column: `u` = `[level, j brick, k brick]`; per attribute, the ranges of
/// its bricks along i and `[sum, finite count, non-finite count]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct Unit {
    pub u: [usize; 3],
    pub ranges: Vec<Vec<[f32; 2]>>,
    pub sums: Vec<[f64; 3]>,
    /// Per attribute, the sum of squares of the finite values (MDIO's statsV1).
    #[serde(default)]
    pub squares: Vec<f64>,
}

impl Unit {
    /// Why this record cannot belong to a conversion of `meta`, if it cannot.
    fn check(&self, meta: &StoreMeta) -> Result<(), String> {
        let [level, j, k] = self.u;
        if level >= meta.levels {
            return Err(format!("level {level}, but the store has {}", meta.levels));
        }
        let counts = meta.brick_counts(level);
        if j >= counts[1] || k >= counts[2] {
            return Err(format!(
                "column {j}, {k} of level {level}, which has {} x {} columns",
                counts[1], counts[2]
            ));
        }
        let attrs = meta.attributes.len();
        if self.ranges.len() != attrs || self.sums.len() != attrs || self.squares.len() != attrs {
            return Err(format!(
                "{} ranges, {} sums and {} squares for {attrs} attributes",
                self.ranges.len(),
                self.sums.len(),
                self.squares.len()
            ));
        }
        if let Some(r) = self.ranges.iter().find(|r| r.len() != counts[0]) {
            return Err(format!(
                "{} brick ranges in a column of {} bricks",
                r.len(),
                counts[0]
            ));
        }
        let bricks_voxels = (meta.brick as f64).powi(3) * counts[0] as f64;
        for (s, q) in self.sums.iter().zip(&self.squares) {
            let counted = s[1] >= 0.0 && s[2] >= 0.0 && s[1] + s[2] <= bricks_voxels;
            if !(s.iter().all(|v| v.is_finite()) && counted && q.is_finite() && *q >= 0.0) {
                return Err(format!("statistics {s:?} and {q} cannot be a column's"));
            }
        }
        Ok(())
    }
}

/// The bytes a progress log of `meta` can hold: a first line, then at most one line per
/// column of every level (two numbers of at most ~20 characters a brick per attribute,
/// and sums).
fn log_bound(meta: &StoreMeta) -> u64 {
    let columns: u64 = (0..meta.levels)
        .map(|l| {
            let c = meta.brick_counts(l);
            (c[1] * c[2]) as u64
        })
        .sum();
    let line = 1024 + 48 * meta.attributes.len() as u64 * (meta.brick_counts(0)[0] as u64 + 4);
    4096u64.saturating_add(columns.saturating_add(1).saturating_mul(line))
}

/// The columns a log lists, without checking them (for `inspect`).
pub(crate) fn logged_columns(path: &Path, meta: &StoreMeta) -> Result<usize, StoreError> {
    let text = arbvis_core::input::read_regular(path, log_bound(meta))
        .map_err(|e| StoreError::io(path, e))?;
    Ok(text
        .split(|&b| b == b'\n')
        .skip(1)
        .filter(|l| !l.is_empty())
        .count())
}

/// The columns a log lists as done, each checked against `meta`. A last line torn by
/// an interruption is dropped (its column is done again); any other bad line is an
/// error naming it.
pub(crate) fn read_log(
    path: &Path,
    job: &Job,
    meta: &StoreMeta,
) -> Result<HashMap<[usize; 3], Unit>, StoreError> {
    let text = arbvis_core::input::read_regular(path, log_bound(meta))
        .map_err(|e| StoreError::io(path, e))?;
    let text = String::from_utf8_lossy(&text);
    let mut lines = text.split_terminator('\n');
    let first = lines.next().unwrap_or_default();
    let mut was: Job = serde_json::from_str(first).map_err(|e| {
        StoreError::invalid(path, format!("line 1 is not the job's description: {e}"))
    })?;
    // A log written before `--compression` named its zstd level.
    if let Some(level) = was.legacy_zstd.take() {
        if was.compression.is_empty() {
            was.compression = if level > 0 {
                format!("zstd:{level}")
            } else {
                "none".into()
            };
        }
    }
    if &was != job {
        return Err(StoreError::invalid(
            path,
            format!(
                "the interrupted conversion here was of {} ({} bytes, brick {}, attributes {}, compression {}); this one is of {} ({} bytes, brick {}, attributes {}, compression {}): run the same command to resume, or name a new store",
                was.input, was.bytes, was.brick, was.attributes.join(","), was.compression,
                job.input, job.bytes, job.brick, job.attributes.join(","), job.compression
            ),
        ));
    }
    let all: Vec<&str> = lines.collect();
    let torn_ok = !text.ends_with('\n');
    let mut done = HashMap::new();
    for (n, line) in all.iter().enumerate() {
        let last = n + 1 == all.len();
        let unit = serde_json::from_str::<Unit>(line)
            .map_err(|e| e.to_string())
            .and_then(|u| u.check(meta).map(|_| u));
        match unit {
            Ok(u) => {
                done.insert(u.u, u);
            }
            // A line torn by the interruption: its column is done again.
            Err(_) if last && torn_ok => {}
            Err(e) => {
                return Err(StoreError::invalid(
                    path,
                    format!(
                        "line {}: {e} (the log is damaged: remove the store and convert again)",
                        n + 2
                    ),
                ))
            }
        }
    }
    Ok(done)
}

/// Create the log with the job's line, whole or not at all.
pub(crate) fn start_log(path: &Path, job: &Job) -> Result<(), StoreError> {
    let line = serde_json::to_string(job).map_err(|e| StoreError::io(path, e))?;
    arbvis_core::png_io::write_atomic(path, format!("{line}\n").as_bytes())
        .map_err(|e| StoreError::io(path, e))
}

/// The exclusive right to write a store, held until dropped (then the lock file goes).
pub(crate) struct StoreLock {
    _lock: arbvis_core::png_io::WriterLock,
}

impl StoreLock {
    /// Take the store's lock, or say which process holds it.
    pub(crate) fn acquire(store: &Path) -> Result<StoreLock, StoreError> {
        let path = store.join(LOCK_FILE);
        match arbvis_core::png_io::WriterLock::acquire(&path).map_err(|e| StoreError::io(&path, e))? {
            Ok(lock) => {
                if let Some(pid) = lock.taken_over() {
                    arbvis_core::progress::line(&format!(
                        "note: {}: the lock of pid {pid}, which is no longer running, taken over",
                        path.display()
                    ));
                }
                Ok(StoreLock { _lock: lock })
            }
            Err(holder) => Err(StoreError::invalid(
                store,
                format!(
                    "another conversion ({holder}) is writing this store; wait for it, or stop it and run this command again to resume"
                ),
            )),
        }
    }
}

/// A store folder that holds nothing of a conversion's but its lock and temporaries
/// (a conversion killed before its log existed): safe to start afresh in.
pub(crate) fn holds_nothing(store: &Path) -> Result<bool, StoreError> {
    let entries = std::fs::read_dir(store).map_err(|e| StoreError::io(store, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| StoreError::io(store, e))?;
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name != LOCK_FILE && !name.contains(arbvis_core::png_io::TMP_MARK) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// A conversion's watcher (`ConvertOptions::watch`): called with (columns done, all
/// columns) from the workers; false stops the conversion.
#[derive(Clone)]
pub struct Watch(pub std::sync::Arc<dyn Fn(usize, usize) -> bool + Send + Sync>);

impl std::fmt::Debug for Watch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Watch")
    }
}
