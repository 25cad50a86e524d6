//! The COPC file as it is written: header and VLRs (rewritten with the final numbers at
//! the end), one LAZ chunk per node, the chunk table, the hierarchy EVLR (its pages:
//! `pages`).

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use laz::laszip::{ChunkTable, ChunkTableEntry, LazVlr, LazVlrBuilder};
use laz::record::{LayeredPointRecordCompressor, RecordCompressor};
use rayon::prelude::*;

use super::octree::{Cube, Key};
use super::records::{gps_time, return_number, xyz};
use super::source::Source;
use crate::points::PointsError;

/// Bytes of node records gathered before they are compressed together.
const PENDING: usize = 64 << 20;

/// A COPC file being written to a temporary beside its name.
pub(super) struct CopcFile {
    path: PathBuf,
    temporary: arbvis_core::png_io::Temporary,
    spill: arbvis_core::png_io::Temporary,
    file: BufWriter<File>,
    at: u64,
    header: Vec<u8>,
    laz: LazVlr,
    point_start: u64,
    record: usize,
    entries: Vec<super::pages::Entry>,
    chunks: ChunkTable,
    pending: Vec<(Key, Vec<u8>)>,
    pending_bytes: usize,
    stats: Stats,
}

/// What the header and the info VLR need to know of every point.
struct Stats {
    points: u64,
    bounds: [[i32; 3]; 2],
    gps: [f64; 2],
    by_return: [u64; 15],
}

/// What was written.
pub(super) struct Written {
    pub(super) points: u64,
    pub(super) nodes: usize,
    pub(super) depth: i32,
    pub(super) bytes: u64,
}

fn vlr_header(user: &str, record: u16, length: u16, description: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 54];
    h[2..2 + user.len().min(16)].copy_from_slice(&user.as_bytes()[..user.len().min(16)]);
    h[18..20].copy_from_slice(&record.to_le_bytes());
    h[20..22].copy_from_slice(&length.to_le_bytes());
    let d = description.len().min(32);
    h[22..22 + d].copy_from_slice(&description[..d]);
    h
}

impl CopcFile {
    /// Create the temporary and write the header and VLRs (placeholders for the numbers
    /// known only at the end).
    pub(super) fn create(
        path: &Path,
        source: &Source,
        cube: &Cube,
    ) -> Result<CopcFile, PointsError> {
        let io = |e| PointsError::io(path, e);
        let temporary = arbvis_core::png_io::Temporary::beside(path, "").map_err(io)?;
        let spill = arbvis_core::png_io::Temporary::beside(path, ".spill").map_err(io)?;
        std::fs::create_dir(spill.path()).map_err(io)?;
        let file = File::create(temporary.path()).map_err(io)?;
        let extra = source.record - super::records::BASE[source.format as usize];
        let laz = LazVlrBuilder::default()
            .with_point_format(source.format, extra as u16)
            .map_err(|e| PointsError::unsupported(path, e.to_string()))?
            .with_variable_chunk_size()
            .build();
        let mut out = CopcFile {
            path: path.to_path_buf(),
            temporary,
            spill,
            file: BufWriter::with_capacity(4 << 20, file),
            at: 0,
            header: Vec::new(),
            laz,
            point_start: 0,
            record: source.record,
            entries: Vec::new(),
            chunks: ChunkTable::default(),
            pending: Vec::new(),
            pending_bytes: 0,
            stats: Stats {
                points: 0,
                bounds: [[i32::MAX; 3], [i32::MIN; 3]],
                gps: [f64::INFINITY, f64::NEG_INFINITY],
                by_return: [0; 15],
            },
        };
        out.header = out.head(source, cube, 0, 0);
        out.point_start = out.header.len() as u64;
        let mut start = out.header.clone();
        start.extend_from_slice(&[0u8; 8]); // the chunk table's offset, set at the end
        out.write(&start)?;
        Ok(out)
    }

    /// The spill folder beside the output.
    pub(super) fn spill_dir(&self) -> &Path {
        self.spill.path()
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), PointsError> {
        self.file
            .write_all(bytes)
            .map_err(|e| PointsError::io(self.temporary.path(), e))?;
        self.at += bytes.len() as u64;
        Ok(())
    }

    /// The header and VLRs, with the hierarchy at `hierarchy` (`size` bytes) once known.
    fn head(&self, source: &Source, cube: &Cube, hierarchy: u64, size: u64) -> Vec<u8> {
        let mut laz_data = Vec::new();
        self.laz.write_to(&mut laz_data).expect("to memory");
        let mut vlrs = Vec::new();
        let mut info = vec![0u8; 160];
        let half = 0.5 * cube.side;
        let spacing = cube.side / cube.grid as f64;
        for (k, v) in [
            cube.min[0] + half,
            cube.min[1] + half,
            cube.min[2] + half,
            half,
            spacing,
        ]
        .iter()
        .enumerate()
        {
            info[8 * k..8 * k + 8].copy_from_slice(&v.to_le_bytes());
        }
        info[40..48].copy_from_slice(&hierarchy.to_le_bytes());
        info[48..56].copy_from_slice(&size.to_le_bytes());
        let gps = if self.stats.points > 0 {
            self.stats.gps
        } else {
            [0.0; 2]
        };
        info[56..64].copy_from_slice(&gps[0].to_le_bytes());
        info[64..72].copy_from_slice(&gps[1].to_le_bytes());
        vlrs.extend(vlr_header("copc", 1, 160, b"copc info"));
        vlrs.extend(info);
        vlrs.extend(vlr_header(
            "laszip encoded",
            22204,
            laz_data.len() as u16,
            b"laz variable chunks",
        ));
        vlrs.extend(laz_data);
        let mut count = 2u32;
        for v in &source.vlrs {
            if v.data.len() <= u16::MAX as usize {
                vlrs.extend(vlr_header(
                    &v.user_id,
                    v.record_id,
                    v.data.len() as u16,
                    &v.description,
                ));
                vlrs.extend(&v.data);
                count += 1;
            }
        }
        let mut h = vec![0u8; 375];
        h[0..4].copy_from_slice(b"LASF");
        // Global encoding bit 4 (WKT): LAS 1.4 R15 requires it for point formats 6-10,
        // whether or not a coordinate system is given (copclib, PDAL and QGIS refuse a
        // file without it). An input's WKT (2112) and GeoTIFF keys are copied as they are.
        h[6..8].copy_from_slice(&16u16.to_le_bytes());
        h[24] = 1;
        h[25] = 4;
        let software = format!("arbvis {}", env!("CARGO_PKG_VERSION"));
        h[26..32].copy_from_slice(b"arbvis");
        h[58..58 + software.len().min(32)]
            .copy_from_slice(&software.as_bytes()[..software.len().min(32)]);
        h[94..96].copy_from_slice(&375u16.to_le_bytes());
        h[96..100].copy_from_slice(&(375 + vlrs.len() as u32).to_le_bytes());
        h[100..104].copy_from_slice(&count.to_le_bytes());
        h[104] = source.format | 0x80;
        h[105..107].copy_from_slice(&(source.record as u16).to_le_bytes());
        for a in 0..3 {
            h[131 + 8 * a..139 + 8 * a].copy_from_slice(&source.scale[a].to_le_bytes());
            h[155 + 8 * a..163 + 8 * a].copy_from_slice(&source.offset[a].to_le_bytes());
            let (lo, hi) = if self.stats.points > 0 {
                let b = self.stats.bounds;
                let v = |i: i32| i as f64 * source.scale[a] + source.offset[a];
                (v(b[0][a]), v(b[1][a]))
            } else {
                (0.0, 0.0)
            };
            h[179 + 16 * a..187 + 16 * a].copy_from_slice(&hi.to_le_bytes());
            h[187 + 16 * a..195 + 16 * a].copy_from_slice(&lo.to_le_bytes());
        }
        h[247..255].copy_from_slice(&self.stats.points.to_le_bytes());
        for (k, n) in self.stats.by_return.iter().enumerate() {
            h[255 + 8 * k..263 + 8 * k].copy_from_slice(&n.to_le_bytes());
        }
        h.extend(vlrs);
        h
    }

    /// Add a node's records (compressed with others once enough are gathered).
    pub(super) fn add(&mut self, key: Key, records: Vec<u8>) -> Result<(), PointsError> {
        if records.is_empty() {
            return Ok(());
        }
        self.pending_bytes += records.len();
        self.pending.push((key, records));
        if self.pending_bytes >= PENDING {
            self.flush()?;
        }
        Ok(())
    }

    /// Compress the gathered nodes in parallel and append their chunks.
    fn flush(&mut self) -> Result<(), PointsError> {
        let items = self.laz.items().clone();
        let pending = std::mem::take(&mut self.pending);
        self.pending_bytes = 0;
        let chunks: Vec<Vec<u8>> = pending
            .par_iter()
            .map(|(_, records)| {
                let mut c = LayeredPointRecordCompressor::new(Vec::new());
                c.set_fields_from(&items)?;
                c.compress_many(records)?;
                c.done()?;
                Ok(std::mem::take(c.get_mut()))
            })
            .collect::<Result<_, laz::LasZipError>>()
            .map_err(|e| PointsError::unsupported(&self.path, format!("compressing: {e}")))?;
        for ((key, records), chunk) in pending.iter().zip(chunks) {
            let points = (records.len() / self.record) as u64;
            for r in records.chunks_exact(self.record) {
                for (a, q) in xyz(r).into_iter().enumerate() {
                    self.stats.bounds[0][a] = self.stats.bounds[0][a].min(q);
                    self.stats.bounds[1][a] = self.stats.bounds[1][a].max(q);
                }
                let t = gps_time(r);
                self.stats.gps = [self.stats.gps[0].min(t), self.stats.gps[1].max(t)];
                let k = return_number(r) as usize;
                if (1..=15).contains(&k) {
                    self.stats.by_return[k - 1] += 1;
                }
            }
            self.stats.points += points;
            self.entries
                .push((*key, self.at, chunk.len() as u64, points));
            self.chunks.push(ChunkTableEntry {
                point_count: points,
                byte_count: chunk.len() as u64,
            });
            self.write(&chunk)?;
        }
        Ok(())
    }

    /// Write the chunk table and the hierarchy, rewrite the header, and rename the file
    /// to its name.
    pub(super) fn finish(mut self, source: &Source, cube: &Cube) -> Result<Written, PointsError> {
        self.flush()?;
        let table_at = self.at;
        let mut table = Vec::new();
        self.chunks
            .write_to(&mut table, &self.laz)
            .map_err(|e| PointsError::io(&self.path, e))?;
        self.write(&table)?;
        let evlr_at = self.at;
        let (page, root_page) = super::pages::hierarchy(&self.entries, evlr_at + 60);
        let mut evlr = vec![0u8; 60];
        evlr[2..6].copy_from_slice(b"copc");
        evlr[18..20].copy_from_slice(&1000u16.to_le_bytes());
        evlr[20..28].copy_from_slice(&(page.len() as u64).to_le_bytes());
        evlr[28..37].copy_from_slice(b"hierarchy");
        self.write(&evlr)?;
        self.write(&page)?;
        let mut head = self.head(source, cube, evlr_at + 60, root_page);
        head[235..243].copy_from_slice(&evlr_at.to_le_bytes());
        head[243..247].copy_from_slice(&1u32.to_le_bytes());
        debug_assert_eq!(head.len(), self.header.len());
        let io = |e| PointsError::io(&self.path, e);
        self.file.seek(SeekFrom::Start(0)).map_err(io)?;
        self.file.write_all(&head).map_err(io)?;
        self.file.write_all(&table_at.to_le_bytes()).map_err(io)?;
        let file = self.file.into_inner().map_err(|e| io(e.into_error()))?;
        file.sync_all().map_err(io)?;
        drop(file);
        let depth = self.entries.iter().map(|e| e.0[0]).max().unwrap_or(0);
        let written = Written {
            points: self.stats.points,
            nodes: self.entries.len(),
            depth,
            bytes: self.at,
        };
        self.temporary.commit(&self.path).map_err(io)?;
        Ok(written)
    }
}
