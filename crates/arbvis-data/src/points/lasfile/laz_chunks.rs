//! A chunked LAZ file's records decoded chunk by chunk in parallel, ahead of the reader
//! (`arbvis convert CLOUD X.copc.laz`). LAZ keeps its points in chunks (50,000 points by
//! default; COPC's and other writers' of any size), each decodable alone from its bytes
//! and the items of the laszip VLR, found through the chunk table that
//! [`super::check`] reads and bounds. A thread of its own decodes windows of chunks on
//! rayon's pool and hands them over in file order through a bounded channel, so decoding
//! overlaps what the reader does with the records, and at most [`AHEAD`] windows are held
//! beyond the one being read. A chunk that fails names its index and its byte; `laz`'s
//! panics on corrupt data are caught as errors.

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::Arc;
use std::thread::JoinHandle;

use laz::record::{
    LayeredPointRecordDecompressor, RecordDecompressor, SequentialPointRecordDecompressor,
};
use rayon::prelude::*;

use crate::points::PointsError;

/// Windows decoded ahead of the one being read.
const AHEAD: usize = 2;

/// Most records in one window (all its chunks but the first: a chunk is never split).
const WINDOW_POINTS: u64 = 1 << 20;

/// One chunk: its bytes in the file and its points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Chunk {
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) points: u64,
}

/// What decoding a chunked LAZ file needs: the laszip VLR's items and the chunks that
/// hold the header's points, in file order.
#[derive(Debug, Clone)]
pub(super) struct LazChunks {
    pub(super) vlr: laz::LazVlr,
    pub(super) chunks: Vec<Chunk>,
}

/// The chunks' records, decoded ahead on a thread of their own.
pub(super) struct Decoded {
    receiver: Option<Receiver<Result<Vec<u8>, PointsError>>>,
    thread: Option<JoinHandle<()>>,
    current: Vec<u8>,
    at: usize,
}

/// Decode `chunk` of `bytes` with `vlr`'s items into `out` (exactly its records).
fn decode_chunk(
    vlr: &laz::LazVlr,
    bytes: &[u8],
    chunk: Chunk,
    out: &mut [u8],
) -> Result<(), crate::points::DecoderError> {
    let source = Cursor::new(&bytes[chunk.start..chunk.end]);
    let layered = vlr.items().first().is_some_and(|i| i.version() >= 3);
    let run = |d: &mut dyn RecordDecompressor<Cursor<&[u8]>>, out: &mut [u8]| -> las::Result<()> {
        d.set_fields_from(vlr.items())
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        d.decompress_many(out)?;
        Ok(())
    };
    crate::points::guarded(|| {
        if layered {
            run(&mut LayeredPointRecordDecompressor::new(source), out)
        } else {
            run(&mut SequentialPointRecordDecompressor::new(source), out)
        }
    })
}

impl Decoded {
    /// Start decoding `chunks` of `bytes` (the whole file, `path` in errors) into records
    /// of `record` bytes.
    pub(super) fn start(
        path: &Path,
        bytes: Arc<Vec<u8>>,
        chunks: LazChunks,
        record: usize,
    ) -> Decoded {
        let (sender, receiver) = sync_channel(AHEAD);
        let path: PathBuf = path.to_path_buf();
        let thread = std::thread::spawn(move || {
            let LazChunks { vlr, chunks } = chunks;
            let mut first = 0;
            while first < chunks.len() {
                // A window: whole chunks up to WINDOW_POINTS records (at least one).
                let mut last = first + 1;
                let mut points = chunks[first].points;
                while last < chunks.len() && points + chunks[last].points <= WINDOW_POINTS {
                    points += chunks[last].points;
                    last += 1;
                }
                let window = &chunks[first..last];
                let decoded: Result<Vec<Vec<u8>>, PointsError> = window
                    .par_iter()
                    .enumerate()
                    .map(|(k, &chunk)| {
                        let n = chunk.points as usize * record;
                        let mut out =
                            arbvis_core::budget::vec_for::<u8>(n, "a LAZ chunk's records")
                                .map_err(|e| PointsError::unsupported(&path, e.to_string()))?;
                        out.resize(n, 0);
                        decode_chunk(&vlr, &bytes, chunk, &mut out).map_err(|m| {
                            PointsError::format(
                                &path,
                                chunk.start as u64,
                                format!("LAZ chunk {} ({} points): {m}", first + k, chunk.points),
                            )
                        })?;
                        Ok(out)
                    })
                    .collect();
                let decoded = match decoded {
                    Ok(d) => d,
                    Err(e) => {
                        let _ = sender.send(Err(e));
                        return;
                    }
                };
                for records in decoded {
                    // The reader stopped (rewound or dropped): stop too.
                    if sender.send(Ok(records)).is_err() {
                        return;
                    }
                }
                first = last;
            }
        });
        Decoded {
            receiver: Some(receiver),
            thread: Some(thread),
            current: Vec::new(),
            at: 0,
        }
    }

    /// Append up to `n` records of `record` bytes to `out`; returns how many (fewer only
    /// at the end of the chunks).
    pub(super) fn next(
        &mut self,
        n: u64,
        record: usize,
        out: &mut Vec<u8>,
    ) -> Result<u64, PointsError> {
        let mut got = 0u64;
        while got < n {
            if self.at == self.current.len() {
                let next = self.receiver.as_ref().and_then(|r| r.recv().ok());
                match next {
                    Some(Ok(records)) => {
                        self.current = records;
                        self.at = 0;
                        continue;
                    }
                    Some(Err(e)) => return Err(e),
                    None => break,
                }
            }
            let take = ((self.current.len() - self.at) / record).min((n - got) as usize);
            out.extend_from_slice(&self.current[self.at..self.at + take * record]);
            self.at += take * record;
            got += take as u64;
        }
        Ok(got)
    }
}

impl Drop for Decoded {
    fn drop(&mut self) {
        // The receiver first: the thread's next send fails and it ends.
        self.receiver = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
