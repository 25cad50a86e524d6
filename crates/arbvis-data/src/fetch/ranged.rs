//! A remote file read a range at a time (a COPC cloud): small reads (headers, VLRs,
//! hierarchy pages) in aligned 64 KiB blocks, so the header and VLRs cost one request;
//! a view's nodes fetched ahead together ([`RemoteFile::prefetch`]), ranges closer than
//! 32 KiB merged into one request, many requests in flight. Every request after the
//! first carries the ETag the file had when it was opened (`If-Match`), and every answer's
//! ETag and size are checked against it: a file that changes while it is read is an
//! error naming it, never a cloud of two versions. Ranges are kept in memory (up to
//! 256 MiB) and on disk ([`super::cache`]), keyed by the ETag.

use std::collections::BTreeMap;
use std::ops::Range;
use std::sync::{Arc, Mutex};

use futures::StreamExt;
use object_store::{GetOptions, GetRange};

use super::client::{self, Object};
use super::count;
use super::FetchError;

/// Small reads are rounded out to blocks of this size.
pub const BLOCK: u64 = 64 << 10;

/// Requested ranges closer than this are fetched as one.
pub const MERGE_GAP: u64 = 32 << 10;

/// A merged request is not grown past this.
const MERGE_MAX: u64 = 16 << 20;

const MEMORY_BYTES: u64 = 256 << 20;

/// A fetched range and its bytes.
type Span = (Range<u64>, Arc<Vec<u8>>);

/// An open remote file.
pub struct RemoteFile {
    object: Object,
    /// Its size.
    pub size: u64,
    /// Its ETag when opened (None where the server gives none: then nothing is cached).
    etag: Option<String>,
    /// Ranges held, by start: (end, bytes).
    held: Mutex<Held>,
}

#[derive(Default)]
struct Held {
    ranges: BTreeMap<u64, (u64, Arc<Vec<u8>>)>,
    bytes: u64,
}

impl Held {
    fn find(&self, r: &Range<u64>) -> Option<Vec<u8>> {
        let (start, (end, data)) = self.ranges.range(..=r.start).next_back()?;
        (*end >= r.end).then(|| data[(r.start - start) as usize..(r.end - start) as usize].to_vec())
    }
    fn keep(&mut self, start: u64, data: Arc<Vec<u8>>) {
        let end = start + data.len() as u64;
        if self.ranges.get(&start).is_some_and(|(e, _)| *e >= end) {
            return;
        }
        self.bytes += data.len() as u64;
        if let Some((_, old)) = self.ranges.insert(start, (end, data)) {
            self.bytes -= old.len() as u64;
        }
        // Past the budget: drop the ranges furthest into the file (the coarse levels and
        // the header come first in a COPC file's reads).
        while self.bytes > MEMORY_BYTES {
            let Some((_, (_, d))) = self.ranges.pop_last() else {
                break;
            };
            self.bytes -= d.len() as u64;
        }
    }
}

impl RemoteFile {
    /// Open `url`: one request for its first block (or none, when the block on disk is
    /// still the object's: then one `If-None-Match` request answered 304).
    pub fn open(url: &str) -> Result<RemoteFile, FetchError> {
        let object = client::object(url)?;
        let first = 0..BLOCK;
        let disk = super::cache::global().and_then(|c| c.get(url, &first));
        let options = GetOptions {
            range: Some(GetRange::Bounded(first.clone())),
            if_none_match: disk.as_ref().map(|e| e.etag.clone()),
            ..Default::default()
        };
        let _busy = count::request();
        // The answer (None: the block on disk still holds), within the request deadline.
        let asked = async {
            match object.store.get_opts(&object.path, options).await {
                Err(object_store::Error::NotModified { .. }) if disk.is_some() => Ok(None),
                Err(e) => Err(client::failure(&object, Some(&first), &e)),
                Ok(got) => {
                    let (size, etag) = (got.meta.size, got.meta.e_tag.clone());
                    let (range, bytes) = body(&object, &first, got).await?;
                    Ok(Some((size, etag, range, bytes)))
                }
            }
        };
        let answer = client::runtime().block_on(client::within(url, Some(&first), asked))?;
        let (size, etag, bytes) = match answer {
            None => {
                let e = disk.expect("a 304 answers only a request with the block on disk");
                count::from_disk(e.bytes.len());
                (e.size, Some(e.etag), e.bytes)
            }
            Some((size, etag, range, bytes)) => {
                check_length(url, &range, bytes.len())?;
                count::fetched(bytes.len());
                if let (Some(c), Some(t)) = (super::cache::global(), &etag) {
                    c.put(url, &first, t, size, &bytes);
                }
                (size, etag, bytes)
            }
        };
        if let Some(t) = &etag {
            super::learn_etag(url, t, size)?;
        }
        let file = RemoteFile {
            object,
            size,
            etag,
            held: Mutex::new(Held::default()),
        };
        file.held().keep(0, Arc::new(bytes));
        Ok(file)
    }

    /// Its size in bytes.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// The ETag the file had when opened.
    pub fn etag(&self) -> Option<&str> {
        self.etag.as_deref()
    }

    fn held(&self) -> std::sync::MutexGuard<'_, Held> {
        self.held.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Fill `buf` from byte `at`.
    pub fn read_at(&self, at: u64, buf: &mut [u8]) -> Result<(), FetchError> {
        let want = at..at + buf.len() as u64;
        if want.end > self.size {
            let (first, last) = (want.start, want.end.saturating_sub(1));
            let m = format!(
                "bytes {first}-{last}: past the end of its {} bytes",
                self.size
            );
            return Err(FetchError::at(&self.object.url, Some(&want), m));
        }
        if let Some(data) = self.held().find(&want) {
            buf.copy_from_slice(&data);
            return Ok(());
        }
        let fetch = if want.end - want.start <= BLOCK {
            (want.start / BLOCK * BLOCK)..(want.end.div_ceil(BLOCK) * BLOCK).min(self.size)
        } else {
            want.clone()
        };
        self.prefetch(std::slice::from_ref(&fetch))?;
        let data = self.held().find(&want).ok_or_else(|| {
            let m = format!(
                "bytes {}-{}: not held after their fetch (the memory budget of remote ranges is too small)",
                want.start,
                want.end - 1
            );
            FetchError::at(&self.object.url, Some(&want), m)
        })?;
        buf.copy_from_slice(&data);
        Ok(())
    }

    /// Fetch `ranges` ahead (from the disk cache where it holds them, else merged where
    /// close, many at once), so that reading them waits for nothing; the first error is
    /// returned, naming its range.
    pub fn prefetch(&self, ranges: &[Range<u64>]) -> Result<(), FetchError> {
        let mut wanted: Vec<Range<u64>> = {
            let held = self.held();
            ranges
                .iter()
                .filter(|r| r.start < r.end && r.end <= self.size && held.find(r).is_none())
                .cloned()
                .collect()
        };
        // From disk first.
        if let (Some(c), Some(etag)) = (super::cache::global(), &self.etag) {
            wanted.retain(|r| match c.get(&self.object.url, r) {
                Some(e) if &e.etag == etag && e.bytes.len() as u64 == r.end - r.start => {
                    count::from_disk(e.bytes.len());
                    self.held().keep(r.start, Arc::new(e.bytes));
                    false
                }
                _ => true,
            });
        }
        if wanted.is_empty() {
            return Ok(());
        }
        let merged = merge(&wanted);
        let limit = client::in_flight();
        let fetched: Vec<Result<Span, FetchError>> = client::runtime().block_on(async {
            futures::stream::iter(merged)
                .map(|(span, _)| async move {
                    let data = self.range(span.clone()).await?;
                    Ok((span, data))
                })
                .buffer_unordered(limit)
                .collect()
                .await
        });
        let mut spans = Vec::new();
        for f in fetched {
            spans.push(f?);
        }
        // Each requested range kept (and cached) on its own: the next view asks for the
        // same nodes, merged otherwise.
        for r in &wanted {
            let Some((span, data)) = spans
                .iter()
                .find(|(s, _)| s.start <= r.start && r.end <= s.end)
            else {
                continue;
            };
            let part =
                data[(r.start - span.start) as usize..(r.end - span.start) as usize].to_vec();
            if let (Some(c), Some(etag)) = (super::cache::global(), &self.etag) {
                c.put(&self.object.url, r, etag, self.size, &part);
            }
            self.held().keep(r.start, Arc::new(part));
        }
        Ok(())
    }

    /// One range GET, pinned to the ETag the file was opened with, within the request
    /// deadline.
    async fn range(&self, r: Range<u64>) -> Result<Arc<Vec<u8>>, FetchError> {
        client::within(&self.object.url, Some(&r), self.range_unbounded(r.clone())).await
    }

    /// [`RemoteFile::range`] with no deadline of its own.
    async fn range_unbounded(&self, r: Range<u64>) -> Result<Arc<Vec<u8>>, FetchError> {
        let options = GetOptions {
            range: Some(GetRange::Bounded(r.clone())),
            // A weak ETag (`W/"..."`) never matches an If-Match (RFC 9110 compares strongly):
            // the answer's ETag is compared below instead.
            if_match: self.etag.clone().filter(|e| !e.starts_with("W/")),
            ..Default::default()
        };
        let describe = |e: &object_store::Error| client::failure(&self.object, Some(&r), e);
        let _busy = count::request();
        let got = self
            .object
            .store
            .get_opts(&self.object.path, options)
            .await
            .map_err(|e| describe(&e))?;
        if got.meta.size != self.size || (self.etag.is_some() && got.meta.e_tag != self.etag) {
            return Err(FetchError::at(&self.object.url, Some(&r), format!(
                "bytes {}-{}: the object changed while it was read (it had {} bytes and ETag {}; now {} bytes and ETag {}); open it again",
                r.start,
                r.end - 1,
                self.size,
                self.etag.as_deref().unwrap_or("none"),
                got.meta.size,
                got.meta.e_tag.as_deref().unwrap_or("none"),
            )));
        }
        let (range, bytes) = body(&self.object, &r, got).await?;
        check_length(&self.object.url, &range, bytes.len())?;
        count::fetched(bytes.len());
        Ok(Arc::new(bytes))
    }
}

/// The body of `got`, the answer to a request for bytes `asked` of `object`, with the
/// range the server says it holds: read part by part and refused as soon as it holds
/// more than `asked` (a server declaring a 2 GiB body for a 64 KiB range is never
/// buffered past the range).
async fn body(
    object: &Object,
    asked: &Range<u64>,
    got: object_store::GetResult,
) -> Result<(Range<u64>, Vec<u8>), FetchError> {
    let range = got.range.clone();
    let (first, last) = (asked.start, asked.end.saturating_sub(1));
    let most = asked.end - asked.start;
    if range.start != asked.start || range.end - range.start > most {
        let m = format!(
            "bytes {first}-{last}: the server answered bytes {}-{}, not the range asked for",
            range.start,
            range.end.saturating_sub(1)
        );
        return Err(FetchError::at(&object.url, Some(asked), m));
    }
    let mut bytes = Vec::with_capacity((range.end - range.start) as usize);
    let mut parts = got.into_stream();
    while let Some(part) = parts.next().await {
        let part = part.map_err(|e| client::failure(object, Some(asked), &e))?;
        if (bytes.len() + part.len()) as u64 > most {
            let m = format!("bytes {first}-{last}: the body held more than the range's {most} bytes (its declared length is not believed)");
            return Err(FetchError::at(&object.url, Some(asked), m));
        }
        bytes.extend_from_slice(&part);
    }
    Ok((range, bytes))
}

/// The body must hold the range the server said it sends.
fn check_length(url: &str, range: &Range<u64>, got: usize) -> Result<(), FetchError> {
    let want = range.end - range.start;
    if got as u64 != want {
        let (first, last) = (range.start, range.end.saturating_sub(1));
        let m = format!("bytes {first}-{last}: the body held {got} bytes, not the range's {want}");
        return Err(FetchError::at(url, Some(range), m));
    }
    Ok(())
}

/// `ranges` sorted and merged where closer than [`MERGE_GAP`] (up to [`MERGE_MAX`] a
/// request): each merged span with how many ranges it serves.
pub fn merge(ranges: &[Range<u64>]) -> Vec<(Range<u64>, usize)> {
    let mut sorted = ranges.to_vec();
    sorted.sort_by_key(|r| r.start);
    let mut out: Vec<(Range<u64>, usize)> = Vec::new();
    for r in sorted {
        match out.last_mut() {
            Some((span, n))
                if r.start <= span.end + MERGE_GAP
                    && r.end.max(span.end) - span.start <= MERGE_MAX =>
            {
                span.end = span.end.max(r.end);
                *n += 1;
            }
            _ => out.push((r, 1)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_ranges_merge_far_ones_do_not() {
        let m = merge(&[1000..2000, 0..100, 2000..3000, 10_000_000..10_000_010]);
        assert_eq!(m, vec![(0..3000, 3), (10_000_000..10_000_010, 1)]);
        // A gap of exactly MERGE_GAP merges; one byte more does not.
        assert_eq!(merge(&[0..10, 10 + MERGE_GAP..20 + MERGE_GAP]).len(), 1);
        assert_eq!(merge(&[0..10, 11 + MERGE_GAP..20 + MERGE_GAP]).len(), 2);
        // A span stops growing at MERGE_MAX.
        let many: Vec<_> = (0..40u64).map(|i| i << 20..(i << 20) + 1000).collect();
        assert!(merge(&many)
            .iter()
            .all(|(s, _)| s.end - s.start <= MERGE_MAX));
        assert_eq!(merge(&many).iter().map(|(_, n)| n).sum::<usize>(), 40);
    }
}
