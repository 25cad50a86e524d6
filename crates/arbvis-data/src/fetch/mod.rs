//! Where data lies: a local path, or a URL (`s3://bucket/key`, `http://`, `https://`;
//! `file://` is the local path it names). A store or a COPC cloud named by a URL is read
//! through [`object_store`] (Apache Arrow's S3 and HTTP clients: request signing, retries
//! with backoff on 429, 5xx and dropped connections, timeouts), with
//! - [`read_object`]: whole objects (a zarr store's metadata and chunks), an absent one
//!   (404) being `None`, as an absent file is;
//! - [`prefetch`]: objects fetched ahead, many at a time, for a view's bricks;
//! - [`File`]: a file read by byte ranges (COPC), its nodes fetched ahead and merged;
//! - [`cache`]: the disk cache shared by every process of the user.
//!
//! A URL travels in a `Path` (`Path::new("s3://b/store").join("zarr.json")` is the URL of
//! the store's `zarr.json`), so every error that names a file names the URL. The readers
//! above read through this module alike; they ask [`url_of`] only to fetch ahead, or to
//! pass over what a URL has not (a listing, a modification time). Request counts are
//! kept ([`stats`]) for the tests, `--stats` and the viewer's status line.

// Without `remote`, the request-side helpers below serve no caller.
#![cfg_attr(not(feature = "remote"), allow(dead_code))]

pub mod cache;
#[cfg(feature = "remote")]
pub mod client;
#[cfg(feature = "remote")]
mod connect;
pub mod count;
mod file;
#[cfg(not(feature = "remote"))]
mod offline;
#[cfg(feature = "remote")]
pub mod ranged;
#[cfg(feature = "remote")]
mod whole;
// Without `remote`, the same two names stand for the refusals.
#[cfg(not(feature = "remote"))]
pub(crate) use offline::{ranged, whole};

pub use count::{stats, status, Stats};
pub use file::{Cursor, File};

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// The cache key of a whole object (no range).
const WHOLE: Range<u64> = 0..u64::MAX;

/// Why an object could not be read: its URL and byte range where a request failed, and
/// the message (which names them for a reader of the error line).
#[derive(Debug, Clone, thiserror::Error)]
pub enum FetchError {
    /// It holds more than the reader may read.
    #[error("it holds {bytes} bytes, more than the {max} read")]
    TooLarge {
        /// Its size.
        bytes: u64,
        /// The most the reader takes.
        max: u64,
    },
    /// It could not be read.
    #[error("{message}")]
    Failed {
        /// The URL asked for (`None`: a local file, or no request was made).
        url: Option<String>,
        /// The bytes asked for (`None`: the whole object).
        range: Option<Range<u64>>,
        /// What went wrong, in words.
        message: String,
    },
}

impl FetchError {
    /// A failure of no particular request (a local file, a URL that is not one).
    pub fn failed(message: impl Into<String>) -> FetchError {
        FetchError::Failed {
            url: None,
            range: None,
            message: message.into(),
        }
    }

    /// A failure of the request for `range` (`None`: the whole object) of `url`; the
    /// URL and the message (which may quote it) keep no password or signature
    /// ([`arbvis_core::secrets`]).
    pub fn at(url: &str, range: Option<&Range<u64>>, message: impl Into<String>) -> FetchError {
        use arbvis_core::secrets::redact;
        FetchError::Failed {
            url: Some(redact(url)),
            range: range.cloned(),
            message: redact(&message.into()),
        }
    }

    /// The URL whose request failed, where one did.
    pub fn url(&self) -> Option<&str> {
        match self {
            FetchError::Failed { url, .. } => url.as_deref(),
            FetchError::TooLarge { .. } => None,
        }
    }

    /// The byte range whose request failed, where one did.
    pub fn range(&self) -> Option<&Range<u64>> {
        match self {
            FetchError::Failed { range, .. } => range.as_ref(),
            FetchError::TooLarge { .. } => None,
        }
    }
}

/// The remote URL `path` holds, if it holds one (`file://` URLs are local paths).
pub fn url_of(path: &Path) -> Option<&str> {
    let s = path.to_str()?;
    ["s3://", "http://", "https://"]
        .iter()
        .any(|p| s.starts_with(p))
        .then_some(s)
}

/// Whether `name` (as a scene or the command line gives it) is a URL, `file://` included.
pub fn is_url(name: &str) -> bool {
    ["s3://", "http://", "https://", "file://"]
        .iter()
        .any(|p| name.starts_with(p))
}

/// `name` as a path: a `file://` URL as its local path (percent-escapes decoded), any
/// other name unchanged.
pub fn local_or_url(name: &Path) -> PathBuf {
    match name.to_str().and_then(|s| s.strip_prefix("file://")) {
        Some(rest) => {
            // file:///abs/path and file://localhost/abs/path.
            let rest = rest.strip_prefix("localhost").unwrap_or(rest);
            PathBuf::from(percent_decode(rest))
        }
        None => name.to_path_buf(),
    }
}

/// `name` relative to `base` (a scene's folder): a URL or an absolute path as it is.
pub fn resolve(base: &Path, name: &Path) -> PathBuf {
    let name = local_or_url(name);
    if url_of(&name).is_some() {
        name
    } else {
        base.join(name)
    }
}

/// `s` with its `%XX` escapes decoded (invalid UTF-8 replaced).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The most bytes a prefetched object may hold: twice a store's largest decoded chunk (1
/// GiB, `store::zarr::MAX_CHUNK_BYTES`); the reader then holds it to its own bound.
fn zarr_max() -> u64 {
    2 << 30
}

/// The most bytes of an object `exists` fetches whole to answer (a zarr metadata file:
/// `store::zarr::MAX_METADATA_BYTES`).
const METADATA_MAX: u64 = 16 << 20;

/// The object or file at `path`, at most `max` bytes; `None` where it is absent (a
/// missing file, a 404). A local one must be a regular file.
pub fn read_object(path: &Path, max: u64) -> Result<Option<std::sync::Arc<Vec<u8>>>, FetchError> {
    if let Some(url) = url_of(path) {
        let found = whole::read(url, max)?;
        if let Some(b) = &found {
            if b.len() as u64 > max {
                return Err(FetchError::TooLarge {
                    bytes: b.len() as u64,
                    max,
                });
            }
        }
        return Ok(found);
    }
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(FetchError::failed(e.to_string())),
    };
    if meta.is_file() && meta.len() > max {
        return Err(FetchError::TooLarge {
            bytes: meta.len(),
            max,
        });
    }
    arbvis_core::input::read_regular(path, max)
        .map(|b| Some(std::sync::Arc::new(b)))
        .map_err(|e| FetchError::failed(e.to_string()))
}

/// The object or file at `path` as text, at most `max` bytes; an absent one is an error.
pub fn read_text(path: &Path, max: u64) -> Result<String, FetchError> {
    if url_of(path).is_none() {
        return arbvis_core::input::read_regular(path, max)
            .and_then(arbvis_core::input::utf8)
            .map_err(|e| FetchError::failed(e.to_string()));
    }
    let url = url_of(path).unwrap_or_default();
    match read_object(path, max)? {
        Some(b) => String::from_utf8(b.to_vec()).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            FetchError::at(url, None, format!("not UTF-8 text (byte {at})"))
        }),
        None => Err(FetchError::at(url, None, "no such object (HTTP 404)")),
    }
}

/// Whether something lies at `path`: for a URL, a small object is fetched (metadata
/// read next anyway) and a large one asked for with a HEAD.
pub fn exists(path: &Path) -> bool {
    let Some(url) = url_of(path) else {
        return std::fs::symlink_metadata(path).is_ok();
    };
    // Without `remote` a URL is taken to be there: reading it then says why it cannot be
    // read (the build), where "not there" would send the user looking for the data.
    if !cfg!(feature = "remote") {
        return true;
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let metadata = name == "zarr.json" || name.starts_with(".z");
    if metadata {
        return matches!(read_object(path, METADATA_MAX), Ok(Some(_)));
    }
    whole::head(url)
}

/// Whether `path` is a folder (for a URL: a zarr group or array, v3 or v2, lies there),
/// or why a URL could not be asked (the server could not be reached, refused, redirected
/// in a loop): a store that cannot be reached is not "no such store".
pub fn probe_folder(path: &Path) -> Result<bool, FetchError> {
    if url_of(path).is_none() || !cfg!(feature = "remote") {
        return Ok(is_folder(path));
    }
    for marker in ["zarr.json", ".zgroup", ".zarray"] {
        if read_object(&path.join(marker), METADATA_MAX)?.is_some() {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Whether `path` is a folder (for a URL: a zarr group or array, v3 or v2, lies there).
pub fn is_folder(path: &Path) -> bool {
    if url_of(path).is_none() {
        return path.is_dir();
    }
    ["zarr.json", ".zgroup", ".zarray"]
        .iter()
        .any(|m| exists(&path.join(m)))
}

/// Start fetching the objects at `paths` ahead, many at once, in this order (local
/// files are passed over).
pub fn prefetch(paths: impl IntoIterator<Item = PathBuf>) {
    prefetch_in_stages(vec![paths.into_iter().collect()]);
}

/// [`prefetch`] a stage at a time: a stage's objects start once the stage before is in.
pub fn prefetch_in_stages(stages: Vec<Vec<PathBuf>>) {
    let stages: Vec<Vec<String>> = stages
        .into_iter()
        .map(|s| {
            s.iter()
                .filter_map(|p| url_of(p).map(str::to_string))
                .collect()
        })
        .filter(|s: &Vec<String>| !s.is_empty())
        .collect();
    if !stages.is_empty() {
        whole::prefetch(stages);
    }
}

/// The ETag this process has seen for the object at `path` (None for a local file).
pub fn version(path: &Path) -> Option<String> {
    url_of(path).and_then(known_etag)
}

/// ETags and sizes of the remote objects this process has read: an object seen with
/// another ETag since is an object that changed while it was read.
fn known() -> std::sync::MutexGuard<'static, HashMap<String, (String, u64)>> {
    static KNOWN: OnceLock<Mutex<HashMap<String, (String, u64)>>> = OnceLock::new();
    KNOWN
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

fn known_etag(url: &str) -> Option<String> {
    known().get(url).map(|(e, _)| e.clone())
}

fn learn_etag(url: &str, etag: &str, size: u64) -> Result<(), FetchError> {
    let mut k = known();
    match k.get(url) {
        Some((e, s)) if e != etag || *s != size => Err(FetchError::at(url, None, format!(
            "the object changed while it was read (ETag {e}, {s} bytes when first read; now ETag {etag}, {size} bytes); open it again"
        ))),
        Some(_) => Ok(()),
        None => {
            k.insert(url.to_string(), (etag.to_string(), size));
            Ok(())
        }
    }
}

/// One line on stderr of what this process fetched, if it fetched anything.
pub fn print_stats() {
    let s = stats();
    if s.requests > 0 || s.from_disk > 0 {
        eprintln!(
            "fetched: {} request{}, {:.2} MB; {:.2} MB from the disk cache ({})",
            s.requests,
            if s.requests == 1 { "" } else { "s" },
            s.bytes as f64 / 1e6,
            s.from_disk as f64 / 1e6,
            cache::global().map_or("off".into(), |c| c.dir().display().to_string())
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_sorted_into_urls_and_paths() {
        assert_eq!(url_of(Path::new("s3://b/k")), Some("s3://b/k"));
        assert_eq!(
            url_of(&Path::new("https://h:8/a").join("zarr.json")),
            Some("https://h:8/a/zarr.json")
        );
        assert_eq!(url_of(Path::new("data/x.copc.laz")), None);
        assert_eq!(url_of(Path::new("file:///tmp/x")), None);
        assert_eq!(
            local_or_url(Path::new("file:///tmp/a%20b")),
            Path::new("/tmp/a b")
        );
        assert_eq!(
            local_or_url(Path::new("file://localhost/t")),
            Path::new("/t")
        );
        assert_eq!(
            resolve(Path::new("scenes"), Path::new("s3://b/k")),
            Path::new("s3://b/k")
        );
        assert_eq!(
            resolve(Path::new("scenes"), Path::new("a")),
            Path::new("scenes/a")
        );
        assert_eq!(percent_decode("%4"), "%4");
        assert_eq!(percent_decode("%41%zz"), "A%zz");
    }
}

#[cfg(all(test, feature = "remote"))]
mod error_tests {
    use super::*;

    #[test]
    fn a_failed_fetch_is_an_error_with_its_url_and_range_as_fields() {
        let e = client::object("s3://bucket-only")
            .err()
            .expect("no object named");
        assert_eq!(e.url(), Some("s3://bucket-only"));
        assert_eq!(e.range(), None);
        assert!(
            e.to_string().contains("names a bucket and an object"),
            "{e}"
        );
        let e = read_text(Path::new("ftp://h/o"), 10);
        // Not a URL arbvis fetches: read as a local path that is not there.
        assert!(e.is_err_and(|e| e.url().is_none()));
        let e = FetchError::at("http://h/o", Some(&(3..9)), "bytes 3-8: reset");
        assert_eq!((e.url(), e.range()), (Some("http://h/o"), Some(&(3..9))));
        // A std::error::Error, as every other layer's error is.
        let boxed: Box<dyn std::error::Error + Send + Sync> = Box::new(e);
        assert_eq!(boxed.to_string(), "bytes 3-8: reset");
        // A password in the URL, or quoted in the message, stays out of both.
        let secret = "http://me:hunter2@h/o";
        let e = FetchError::at(secret, None, format!("GET {secret}: refused"));
        assert_eq!(e.url(), Some("http://me:***@h/o"));
        assert!(!e.to_string().contains("hunter2"), "{e}");
    }
}
