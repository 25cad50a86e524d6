//! The disk cache of fetched bytes: one file per object (or per byte range of one), keyed
//! by the URL and the range, holding the object's ETag and size beside the bytes, so a
//! changed object is never served from its old bytes (a read checks the ETag, or asks the
//! server whether it still holds, with `If-None-Match`). Bounded in size (oldest use out
//! first), in a folder the user can set, and safe when several processes share it: an
//! entry is written to a file of its own and renamed into place, so a reader sees a whole
//! entry or none, and a file removed by another process's eviction is a miss.
//!
//! An entry's header holds the URL with its secrets hidden (a password, a signature:
//! [`arbvis_core::secrets`]), and the bytes' length and CRC-32C: a damaged entry (a
//! flipped bit, a cut) is a miss, fetched again. Only regular files are read, and no
//! more of them than the range's bytes and a header (a symlink to `/dev/zero` or a FIFO
//! planted in the folder is a miss, not a hang or a flood).
//!
//! Settings: `ARBVIS_CACHE_DIR` (default `$XDG_CACHE_HOME/arbvis/remote`, else
//! `~/.cache/arbvis/remote`), `ARBVIS_CACHE_BYTES` (default 2 GiB; 0 turns the cache off).

use std::hash::{Hash, Hasher};
use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::SystemTime;

/// First line of every entry (a format change renames it, and old entries are misses).
const MAGIC: &str = "arbvis fetch cache 2";

/// Longest header read: the magic, a URL of up to 8 KiB and the numbers.
const MAX_HEADER: u64 = 8192 + 256;

/// Default size limit: 2 GiB.
pub const DEFAULT_BYTES: u64 = 2 << 30;

/// A cache folder and its limit.
pub struct DiskCache {
    dir: PathBuf,
    limit: u64,
    /// Bytes written since the folder was last measured.
    written: AtomicU64,
}

/// An entry: the object's version and size when its bytes were fetched, and the bytes.
pub struct Entry {
    /// The object's ETag.
    pub etag: String,
    /// The whole object's size.
    pub size: u64,
    /// The bytes of the range.
    pub bytes: Vec<u8>,
}

/// The process's cache, unless it is turned off.
pub fn global() -> Option<&'static DiskCache> {
    static CACHE: OnceLock<Option<DiskCache>> = OnceLock::new();
    CACHE
        .get_or_init(|| {
            let limit = match std::env::var("ARBVIS_CACHE_BYTES") {
                Ok(v) => v.trim().parse::<u64>().unwrap_or(DEFAULT_BYTES),
                Err(_) => DEFAULT_BYTES,
            };
            (limit > 0).then(|| DiskCache::new(default_dir(), limit))
        })
        .as_ref()
}

/// The cache folder the settings name.
pub fn default_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("ARBVIS_CACHE_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("arbvis").join("remote")
}

/// The entry name of (`url`, `range`): 128 bits of two keyed hashes (collisions are also
/// caught by the URL and range written inside).
fn name(url: &str, range: &Range<u64>) -> String {
    let half = |salt: u64| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        salt.hash(&mut h);
        url.hash(&mut h);
        range.start.hash(&mut h);
        range.end.hash(&mut h);
        h.finish()
    };
    format!("{:016x}{:016x}", half(0x5eed), half(0xca11))
}

impl DiskCache {
    /// A cache in `dir` holding at most about `limit` bytes.
    pub fn new(dir: PathBuf, limit: u64) -> DiskCache {
        DiskCache {
            dir,
            limit,
            written: AtomicU64::new(limit),
        }
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The entry of `url`'s bytes `range`, if one is cached (and marked as used now).
    pub fn get(&self, url: &str, range: &Range<u64>) -> Option<Entry> {
        let file = self.dir.join(name(url, range));
        let data = read_entry(&file, range)?;
        let entry = parse(&data, url, range)?;
        if let Ok(f) = std::fs::File::options().write(true).open(&file) {
            let _ = f.set_modified(SystemTime::now());
        }
        Some(entry)
    }

    /// Keep `entry` as `url`'s bytes `range` (errors are ignored: a cache that cannot
    /// write is a cache that misses).
    pub fn put(&self, url: &str, range: &Range<u64>, etag: &str, size: u64, bytes: &[u8]) {
        if self.write(url, range, (etag, size), bytes).is_err() {
            return;
        }
        let grown = self
            .written
            .fetch_add(bytes.len() as u64, Ordering::Relaxed)
            + bytes.len() as u64;
        // Measure the folder when a tenth of the limit has been written since it was.
        if grown >= self.limit / 10 {
            self.written.store(0, Ordering::Relaxed);
            self.evict();
        }
    }

    fn write(
        &self,
        url: &str,
        range: &Range<u64>,
        (etag, size): (&str, u64),
        bytes: &[u8],
    ) -> std::io::Result<()> {
        // The name keys the whole URL; the header holds it with its secrets hidden.
        let shown = arbvis_core::secrets::redact(url);
        if etag.contains('\n') || shown.contains('\n') || shown.len() as u64 > MAX_HEADER - 256 {
            return Err(std::io::Error::other("a newline in a cache key"));
        }
        std::fs::create_dir_all(&self.dir)?;
        let final_name = self.dir.join(name(url, range));
        static SEQ: AtomicU64 = AtomicU64::new(0);
        let tmp = self.dir.join(format!(
            ".tmp-{}-{}",
            std::process::id(),
            SEQ.fetch_add(1, Ordering::Relaxed)
        ));
        let mut f = std::fs::File::create(&tmp)?;
        let head = format!(
            "{MAGIC}\n{shown}\n{} {}\n{etag}\n{size}\n{} {:08x}\n",
            range.start,
            range.end,
            bytes.len(),
            crc32c::crc32c(bytes)
        );
        let done = f
            .write_all(head.as_bytes())
            .and_then(|_| f.write_all(bytes))
            .and_then(|_| std::fs::rename(&tmp, &final_name));
        if done.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        done
    }

    /// Remove the least recently used entries until the folder holds at most 80 % of
    /// the limit (and partial files of writers that died over an hour ago).
    pub fn evict(&self) {
        let Ok(list) = std::fs::read_dir(&self.dir) else {
            return;
        };
        let now = SystemTime::now();
        let mut entries: Vec<(SystemTime, u64, PathBuf)> = Vec::new();
        for e in list.flatten() {
            let Ok(m) = e.metadata() else { continue };
            let used = m.modified().unwrap_or(now);
            let path = e.path();
            if e.file_name().to_string_lossy().starts_with(".tmp-") {
                let stale = now.duration_since(used).is_ok_and(|d| d.as_secs() > 3600);
                if stale {
                    let _ = std::fs::remove_file(&path);
                }
                continue;
            }
            if m.is_file() {
                entries.push((used, m.len(), path));
            }
        }
        let mut total: u64 = entries.iter().map(|e| e.1).sum();
        if total <= self.limit {
            return;
        }
        entries.sort();
        for (_, len, path) in entries {
            if total <= self.limit / 10 * 8 {
                break;
            }
            if std::fs::remove_file(&path).is_ok() {
                total = total.saturating_sub(len);
            }
        }
    }

    /// Bytes the folder's entries hold.
    pub fn bytes(&self) -> u64 {
        std::fs::read_dir(&self.dir)
            .map(|l| {
                l.flatten()
                    .filter_map(|e| e.metadata().ok())
                    .filter(|m| m.is_file())
                    .map(|m| m.len())
                    .sum()
            })
            .unwrap_or(0)
    }
}

/// The bytes of the entry file `file` of `range`, if it is a regular file (not followed
/// through a link) of no more than the range's bytes and a header.
fn read_entry(file: &Path, range: &Range<u64>) -> Option<Vec<u8>> {
    use std::io::Read;
    let meta = std::fs::symlink_metadata(file).ok()?;
    let most = (range.end - range.start).saturating_add(MAX_HEADER);
    if !meta.is_file() || meta.len() > most {
        return None;
    }
    let mut data = Vec::with_capacity(meta.len() as usize);
    let f = std::fs::File::open(file).ok()?;
    f.take(most.saturating_add(1)).read_to_end(&mut data).ok()?;
    Some(data)
}

/// An entry's file, if it is whole, undamaged and of (`url`, `range`).
fn parse(data: &[u8], url: &str, range: &Range<u64>) -> Option<Entry> {
    let mut at = 0;
    let mut line = || {
        let end = data[at..].iter().position(|&b| b == b'\n')? + at;
        let text = std::str::from_utf8(&data[at..end]).ok()?;
        at = end + 1;
        Some(text)
    };
    if line()? != MAGIC || line()? != arbvis_core::secrets::redact(url) {
        return None;
    }
    if line()? != format!("{} {}", range.start, range.end) {
        return None;
    }
    let etag = line()?.to_string();
    let size = line()?.parse().ok()?;
    let (len, crc) = line()?.split_once(' ')?;
    let bytes = &data[at..];
    if len.parse::<usize>().ok()? != bytes.len()
        || u32::from_str_radix(crc, 16).ok()? != crc32c::crc32c(bytes)
    {
        return None;
    }
    Some(Entry {
        etag,
        size,
        bytes: bytes.to_vec(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_are_kept_checked_and_evicted_oldest_first() {
        let dir = std::env::temp_dir().join(format!("arbvis-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cache = DiskCache::new(dir.clone(), 10_000);
        let url = "s3://b/k";
        cache.put(url, &(0..5), "\"e1\"", 99, b"hello");
        let e = cache.get(url, &(0..5)).expect("kept");
        assert_eq!(
            (e.etag.as_str(), e.size, e.bytes.as_slice()),
            ("\"e1\"", 99, &b"hello"[..])
        );
        // Another range, another URL: misses.
        assert!(cache.get(url, &(0..4)).is_none());
        assert!(cache.get("s3://b/k2", &(0..5)).is_none());
        // A truncated file is a miss, never a short entry.
        let file = dir.join(name(url, &(0..5)));
        let data = std::fs::read(&file).unwrap();
        std::fs::write(&file, &data[..10]).unwrap();
        assert!(cache.get(url, &(0..5)).is_none());
        // Every bit of the bytes flipped in turn, and the body cut by one: each a miss.
        for bit in 0..5 * 8 {
            let mut bad = data.clone();
            bad[data.len() - 5 + bit / 8] ^= 1 << (bit % 8);
            std::fs::write(&file, &bad).unwrap();
            assert!(cache.get(url, &(0..5)).is_none(), "bit {bit}");
        }
        std::fs::write(&file, &data[..data.len() - 1]).unwrap();
        assert!(cache.get(url, &(0..5)).is_none());
        // Not a regular file: a link to /dev/zero, a FIFO (opening it would block).
        std::fs::remove_file(&file).unwrap();
        std::os::unix::fs::symlink("/dev/zero", &file).unwrap();
        assert!(cache.get(url, &(0..5)).is_none());
        std::fs::remove_file(&file).unwrap();
        let made = std::process::Command::new("mkfifo").arg(&file).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo (coreutils) is needed"
        );
        assert!(cache.get(url, &(0..5)).is_none());
        std::fs::remove_file(&file).unwrap();
        // A password in the URL is not written into the entry, yet the entry is found.
        let secret = "http://me:hunter2@h/k?X-Amz-Signature=abcd";
        cache.put(secret, &(0..5), "e", 5, b"bytes");
        let written = std::fs::read(dir.join(name(secret, &(0..5)))).unwrap();
        let text = String::from_utf8_lossy(&written);
        assert!(
            !text.contains("hunter2") && !text.contains("abcd"),
            "{text}"
        );
        assert_eq!(cache.get(secret, &(0..5)).unwrap().bytes, b"bytes");
        // Over the limit: the oldest entries go first, down to 80 % of it. Filled through
        // a handle with room for all, then evicted by another on the same folder with a
        // limit of 10,000 bytes (as a second process would).
        let roomy = DiskCache::new(dir.clone(), 1 << 30);
        for i in 0..12u64 {
            let r = i * 1000..(i + 1) * 1000;
            roomy.put(url, &r, "e", 1 << 20, &[i as u8; 1000]);
            let f = dir.join(name(url, &r));
            let t = SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000 + i);
            std::fs::File::options()
                .write(true)
                .open(f)
                .unwrap()
                .set_modified(t)
                .unwrap();
        }
        assert!(roomy.bytes() > 12_000);
        let small = DiskCache::new(dir.clone(), 10_000);
        small.evict();
        assert!(small.bytes() <= 8_000, "{} bytes left", small.bytes());
        assert!(small.get(url, &(0..1000)).is_none(), "the oldest went");
        assert!(
            small.get(url, &(11_000..12_000)).is_some(),
            "the newest stayed"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
