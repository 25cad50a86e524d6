//! A build without the `remote` feature (the main job's: no S3 or HTTP clients to
//! compile): every URL is refused by name, saying how to build arbvis to read it.

use std::ops::Range;

use super::FetchError;

/// Why a URL cannot be read in this build.
fn refused(url: &str) -> FetchError {
    FetchError::at(
        url,
        None,
        "this arbvis was built without reading URLs (the `remote` feature, in the default \
         build: build without --no-default-features, or with --features remote)",
    )
}

/// Whole objects: refused.
pub mod whole {
    use super::*;

    /// What a read of a whole object found.
    pub type Found = Option<std::sync::Arc<Vec<u8>>>;

    /// Refused: no URL is read in this build.
    pub fn read(url: &str, _max: u64) -> Result<Found, FetchError> {
        Err(refused(url))
    }

    /// Taken to be there (reading it says why it cannot be read).
    pub fn head(_url: &str) -> bool {
        true
    }

    /// Nothing to fetch ahead.
    pub fn prefetch(_stages: Vec<Vec<String>>) {}
}

/// Files by byte range: refused at opening, so none is ever held.
pub mod ranged {
    use super::*;

    /// A remote file this build cannot open (no value of it exists).
    pub enum RemoteFile {}

    impl RemoteFile {
        /// Refused: no URL is read in this build.
        pub fn open(url: &str) -> Result<RemoteFile, FetchError> {
            Err(refused(url))
        }

        /// Its size (never called: no value exists).
        pub fn size(&self) -> u64 {
            match *self {}
        }

        /// Never called: no value exists.
        pub fn read_at(&self, _at: u64, _buf: &mut [u8]) -> Result<(), FetchError> {
            match *self {}
        }

        /// Never called: no value exists.
        pub fn prefetch(&self, _ranges: &[Range<u64>]) -> Result<(), FetchError> {
            match *self {}
        }

        /// Never called: no value exists.
        pub fn etag(&self) -> Option<&str> {
            match *self {}
        }
    }
}
