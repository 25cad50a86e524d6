//! Decoded COPC nodes kept between cuts: when the camera stops a little further on, the
//! new cut shares most of its nodes with the last, and only the others are read and
//! decoded. One cache per process, keyed by the file (path, length and modification time,
//! so a rewritten file is never served stale) and the node; least recently used nodes are
//! dropped past its budget, an eighth of the memory budget and at most 1 GiB.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::SystemTime;

use las::PointData;

/// A file as the cache knows it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct FileId {
    path: PathBuf,
    len: u64,
    modified: Option<SystemTime>,
    /// A remote file's ETag.
    etag: Option<String>,
}

impl FileId {
    /// The identity of the file at `path` now.
    pub fn of(path: &Path) -> FileId {
        let meta = std::fs::metadata(path).ok();
        FileId {
            path: path.to_path_buf(),
            len: meta.as_ref().map_or(0, |m| m.len()),
            modified: meta.and_then(|m| m.modified().ok()),
            etag: crate::fetch::version(path),
        }
    }
}

struct Entry {
    data: Arc<PointData>,
    bytes: u64,
    used: u64,
}

#[derive(Default)]
struct Cache {
    entries: HashMap<(FileId, [i32; 4]), Entry>,
    bytes: u64,
    clock: u64,
}

fn cache() -> std::sync::MutexGuard<'static, Cache> {
    static CACHE: OnceLock<Mutex<Cache>> = OnceLock::new();
    CACHE
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

/// The cache's budget in bytes.
pub fn budget() -> u64 {
    (arbvis_core::budget::current().bytes / 8).min(1 << 30)
}

/// Node `key` of `file`, if it is held (it becomes the most recently used).
pub fn get(file: &FileId, key: [i32; 4]) -> Option<Arc<PointData>> {
    let mut c = cache();
    c.clock += 1;
    let now = c.clock;
    let e = c.entries.get_mut(&(file.clone(), key))?;
    e.used = now;
    Some(e.data.clone())
}

/// Whether node `key` of `file` is held (its use is not recorded).
pub fn holds(file: &FileId, key: [i32; 4]) -> bool {
    cache().entries.contains_key(&(file.clone(), key))
}

/// Keep node `key` of `file`, dropping the least recently used past the budget.
pub fn put(file: &FileId, key: [i32; 4], data: Arc<PointData>) {
    let bytes = data.raw_bytes().len() as u64;
    let budget = budget();
    if bytes > budget {
        return;
    }
    let mut c = cache();
    c.clock += 1;
    let used = c.clock;
    if let Some(old) = c
        .entries
        .insert((file.clone(), key), Entry { data, bytes, used })
    {
        c.bytes -= old.bytes;
    }
    c.bytes += bytes;
    while c.bytes > budget {
        let Some(oldest) = c
            .entries
            .iter()
            .min_by_key(|(_, e)| e.used)
            .map(|(k, _)| k.clone())
        else {
            break;
        };
        if let Some(e) = c.entries.remove(&oldest) {
            c.bytes -= e.bytes;
        }
    }
}

/// Bytes held.
pub fn held() -> u64 {
    cache().bytes
}

/// The file at `path` opened, or the one opened before if it has not changed since: the
/// hierarchy pages an earlier cut read stay read. The last few files are held.
pub fn open(path: &Path) -> Result<Arc<super::copc::Copc>, super::PointsError> {
    type Opened = Vec<(FileId, Arc<super::copc::Copc>)>;
    static OPENED: OnceLock<Mutex<Opened>> = OnceLock::new();
    const HELD: usize = 4;
    let id = FileId::of(path);
    let opened = OPENED.get_or_init(Default::default);
    let held = |o: &Opened| o.iter().find(|(f, _)| *f == id).map(|(_, c)| c.clone());
    if let Some(c) = held(&opened.lock().unwrap_or_else(|e| e.into_inner())) {
        return Ok(c);
    }
    let c = Arc::new(super::copc::Copc::open(path)?);
    let mut o = opened.lock().unwrap_or_else(|e| e.into_inner());
    o.retain(|(f, _)| f.path != id.path);
    if o.len() >= HELD {
        o.remove(0);
    }
    o.push((id, c.clone()));
    Ok(c)
}
