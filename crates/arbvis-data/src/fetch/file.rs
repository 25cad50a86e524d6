//! A file read by byte ranges, local or remote (a COPC cloud), and a `Read + Seek` view of
//! it for the readers that want one.

use std::ops::Range;
use std::path::Path;
use std::sync::Mutex;

use super::{local_or_url, ranged, url_of, FetchError};

/// A file read by byte ranges: local, or remote.
pub enum File {
    /// A local file.
    Local(Mutex<std::fs::File>, u64),
    /// A remote object.
    Remote(ranged::RemoteFile),
}

impl File {
    /// Open `path` (a URL: one request for its first block).
    pub fn open(path: &Path) -> Result<File, FetchError> {
        let path = &local_or_url(path);
        if let Some(url) = url_of(path) {
            return ranged::RemoteFile::open(url).map(File::Remote);
        }
        let (f, len) = arbvis_core::input::open_regular(path)
            .map_err(|e| FetchError::failed(e.to_string()))?;
        Ok(File::Local(Mutex::new(f), len))
    }

    /// Its length in bytes.
    pub fn len(&self) -> u64 {
        match self {
            File::Local(_, len) => *len,
            File::Remote(r) => r.size(),
        }
    }

    /// Whether it is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Fill `buf` from byte `at`.
    pub fn read_at(&self, at: u64, buf: &mut [u8]) -> std::io::Result<()> {
        match self {
            File::Local(f, _) => {
                use std::os::unix::fs::FileExt;
                let f = f.lock().unwrap_or_else(|e| e.into_inner());
                f.read_exact_at(buf, at)
            }
            File::Remote(r) => r.read_at(at, buf).map_err(std::io::Error::other),
        }
    }

    /// Fetch `ranges` ahead (a remote file; nothing for a local one).
    pub fn prefetch(&self, ranges: &[Range<u64>]) -> Result<(), FetchError> {
        match self {
            File::Local(..) => Ok(()),
            File::Remote(r) => r.prefetch(ranges),
        }
    }

    /// The remote object's ETag (a local file has none).
    pub fn etag(&self) -> Option<&str> {
        match self {
            File::Local(..) => None,
            File::Remote(r) => r.etag(),
        }
    }
}

/// A reader of a [`File`] from its start (for readers that want `Read + Seek`).
pub struct Cursor<'f> {
    file: &'f File,
    at: u64,
}

impl<'f> Cursor<'f> {
    /// At the start of `file`.
    pub fn new(file: &'f File) -> Cursor<'f> {
        Cursor { file, at: 0 }
    }
}

impl std::io::Read for Cursor<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = (self.file.len().saturating_sub(self.at)).min(buf.len() as u64) as usize;
        self.file.read_at(self.at, &mut buf[..n])?;
        self.at += n as u64;
        Ok(n)
    }
}

impl std::io::Seek for Cursor<'_> {
    fn seek(&mut self, to: std::io::SeekFrom) -> std::io::Result<u64> {
        use std::io::SeekFrom;
        let at = match to {
            SeekFrom::Start(a) => Some(a),
            SeekFrom::End(d) => self.file.len().checked_add_signed(d),
            SeekFrom::Current(d) => self.at.checked_add_signed(d),
        };
        self.at = at.ok_or_else(|| std::io::Error::other("a seek before the start"))?;
        Ok(self.at)
    }
}
