//! A LAS/LAZ file read a batch of records at a time, for a writer that never holds the
//! cloud (`arbvis convert CLOUD X.copc.laz`).
//!
//! An uncompressed file is read from disk as it goes: its header and VLRs are checked
//! as the reader checks them (`check::check_head`, at most [`MAX_HEAD`] bytes before the
//! points) and the records must fit in the file. A LAZ file is held in memory (its
//! size, not its points', counted against the budget) and checked whole as the reader
//! checks it, with no limit on its point count; a chunked one's records are decoded
//! chunk by chunk in parallel, ahead of the reader ([`super::laz_chunks`]), a point-wise
//! one's a batch at a time, both under `guarded`.

use std::fs::File;
use std::io::{BufReader, Cursor, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use las::{PointData, PointDataBuilder, Reader};

use super::check::{check_count, check_head, check_up_to, Checked};
use super::header::LasInfo;
use super::layout::Vlr as RawVlr;
use super::laz_chunks::{Decoded, LazChunks};
use crate::le::u32_at;
use crate::points::{guarded, read_file, PointsError};

/// Bytes of header and VLRs read before the points of an uncompressed file, at most.
const MAX_HEAD: u64 = 64 << 20;

/// A VLR copied from the input: its ids, description and data.
pub(crate) struct CopiedVlr {
    /// User id (`LASF_Projection`, `LASF_Spec`, ...).
    pub(crate) user_id: String,
    /// Record id.
    pub(crate) record_id: u16,
    /// Its 32-byte description.
    pub(crate) description: [u8; 32],
    /// Its data.
    pub(crate) data: Vec<u8>,
}

enum Kind {
    /// Uncompressed: the file at the first record.
    Plain { file: BufReader<File>, start: u64 },
    /// LAZ without chunks to decode apart (point-wise), decoded from memory.
    Laz {
        reader: Box<Reader>,
        data: PointData,
    },
    /// Chunked LAZ, its chunks decoded in parallel ahead of the reader.
    Chunked {
        bytes: Arc<Vec<u8>>,
        chunks: LazChunks,
        decoded: Decoded,
    },
}

/// Records of a LAS or LAZ file, a batch at a time.
pub(crate) struct Records {
    path: PathBuf,
    /// The header's facts.
    pub(crate) info: LasInfo,
    /// The VLRs and EVLRs the checks found (EVLRs only in LAZ files, read whole).
    pub(crate) vlrs: Vec<CopiedVlr>,
    kind: Kind,
    done: u64,
}

fn copied(b: &[u8], vlrs: &[RawVlr]) -> Vec<CopiedVlr> {
    vlrs.iter()
        .map(|v| CopiedVlr {
            user_id: v.user_id.clone(),
            record_id: v.record_id,
            // The description ends where the data starts, in a VLR or an EVLR header.
            description: b[v.data.start - 32..v.data.start]
                .try_into()
                .expect("32 bytes"),
            data: b[v.data.clone()].to_vec(),
        })
        .collect()
}

/// The header and VLRs of `file` (`len` bytes), checked: the bytes up to the point
/// data (at most [`MAX_HEAD`]), what the checks found, and the point data's offset.
pub(super) fn read_head(
    path: &Path,
    file: &mut (impl Read + Seek),
    len: u64,
) -> Result<(Vec<u8>, Checked, usize), PointsError> {
    let io = |e| PointsError::io(path, e);
    let mut head = vec![0u8; len.min(375) as usize];
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    file.read_exact(&mut head).map_err(io)?;
    let offset = if head.len() >= 100 {
        u32_at(&head, 96) as u64
    } else {
        0
    };
    let want = offset.max(head.len() as u64).min(len).min(MAX_HEAD);
    head.resize(want as usize, 0);
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    file.read_exact(&mut head).map_err(io)?;
    let (checked, start) = check_head(path, &head, len as usize)?;
    Ok((head, checked, start))
}

/// The checks every LAS/LAZ reader here runs on a file's header and VLRs
/// ([`check_head`]) and on its extra-bytes descriptors against its records: a COPC file
/// is opened only when they pass, so `inspect` refuses what `render` refuses.
pub(crate) fn check_las_head(
    path: &Path,
    file: &mut (impl Read + Seek),
    len: u64,
) -> Result<(), PointsError> {
    let (head, checked, _) = read_head(path, file, len)?;
    let base = super::header::RECORD_LENGTH[checked.info.point_format as usize] as usize;
    super::extra::extra_bytes(
        path,
        &head,
        &checked.vlrs,
        base,
        checked.info.record_length as usize,
    )?;
    Ok(())
}

impl Records {
    /// Open `path` and check it.
    pub(crate) fn open(path: &Path) -> Result<Records, PointsError> {
        let io = |e| PointsError::io(path, e);
        let (mut file, len) = arbvis_core::input::open_regular(path).map_err(io)?;
        let mut head = vec![0u8; len.min(375) as usize];
        file.read_exact(&mut head).map_err(io)?;
        let compressed = head.len() > 104 && head[104] & 0x80 != 0;
        if compressed {
            let bytes = read_file(path)?;
            let checked = check_up_to(path, &bytes, u64::MAX)?;
            let vlrs = copied(&bytes, &checked.vlrs);
            if let Some(chunks) = checked.laz {
                let bytes = Arc::new(bytes);
                let record = checked.info.record_length as usize;
                let decoded = Decoded::start(path, bytes.clone(), chunks.clone(), record);
                return Ok(Records {
                    path: path.to_path_buf(),
                    info: checked.info,
                    vlrs,
                    kind: Kind::Chunked {
                        bytes,
                        chunks,
                        decoded,
                    },
                    done: 0,
                });
            }
            let reader =
                guarded(|| Reader::new(Cursor::new(bytes))).map_err(|e| PointsError::Decode {
                    path: path.to_path_buf(),
                    message: format!("the header: {e}"),
                })?;
            let data = PointDataBuilder::new().for_header(reader.header()).build();
            return Ok(Records {
                path: path.to_path_buf(),
                info: checked.info,
                vlrs,
                kind: Kind::Laz {
                    reader: Box::new(reader),
                    data,
                },
                done: 0,
            });
        }
        let (head, checked, start) = read_head(path, &mut file, len)?;
        check_count(path, &checked.info, start, len as usize)?;
        let vlrs = copied(&head, &checked.vlrs);
        file.seek(SeekFrom::Start(start as u64)).map_err(io)?;
        Ok(Records {
            path: path.to_path_buf(),
            info: checked.info,
            vlrs,
            kind: Kind::Plain {
                file: BufReader::with_capacity(1 << 20, file),
                start: start as u64,
            },
            done: 0,
        })
    }

    /// Append up to `max` more records to `out`; returns how many (0 at the end).
    pub(crate) fn next(&mut self, max: u64, out: &mut Vec<u8>) -> Result<u64, PointsError> {
        let count = self.info.points;
        let n = max.min(count - self.done);
        if n == 0 {
            return Ok(0);
        }
        let record = self.info.record_length as usize;
        let decode = |m: String| PointsError::Decode {
            path: self.path.clone(),
            message: m,
        };
        let got = match &mut self.kind {
            Kind::Plain { file, .. } => {
                let at = out.len();
                out.resize(at + n as usize * record, 0);
                file.read_exact(&mut out[at..])
                    .map_err(|e| decode(format!("records {}..: {e}", self.done)))?;
                n
            }
            Kind::Laz { reader, data } => {
                let got = guarded(|| reader.fill_points(n, data)).map_err(|e| {
                    decode(format!(
                        "decoding points {}..{} of {count}: {e}",
                        self.done,
                        self.done + n
                    ))
                })?;
                if got == 0 {
                    return Err(decode(format!(
                        "the point data ends after {} of the {count} points the header declares",
                        self.done
                    )));
                }
                out.extend_from_slice(&data.raw_bytes()[..got as usize * record]);
                got
            }
            Kind::Chunked { decoded, .. } => {
                let got = decoded.next(n, record, out)?;
                if got == 0 {
                    return Err(decode(format!(
                        "the chunks end after {} of the {count} points the header declares",
                        self.done
                    )));
                }
                got
            }
        };
        self.done += got;
        Ok(got)
    }

    /// Back to the first record.
    pub(crate) fn rewind(&mut self) -> Result<(), PointsError> {
        match &mut self.kind {
            Kind::Plain { file, start } => {
                file.seek(SeekFrom::Start(*start))
                    .map_err(|e| PointsError::io(&self.path, e))?;
            }
            Kind::Laz { reader, .. } => {
                guarded(|| reader.seek(0)).map_err(|e| PointsError::Decode {
                    path: self.path.clone(),
                    message: format!("seeking to the first point: {e}"),
                })?;
            }
            Kind::Chunked {
                bytes,
                chunks,
                decoded,
            } => {
                let record = self.info.record_length as usize;
                *decoded = Decoded::start(&self.path, bytes.clone(), chunks.clone(), record);
            }
        }
        self.done = 0;
        Ok(())
    }
}
