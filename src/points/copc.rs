//! COPC, Cloud Optimized Point Cloud (copc.io): a LAZ 1.4 file (point formats 6-8) whose
//! points are an octree of nodes, each one LAZ chunk, found through a hierarchy EVLR of
//! pages of (level, x, y, z) keys with the chunk's offset, byte size and point count. The
//! first VLR (`copc`, record 1) gives the octree's centre, half-size and root spacing.
//!
//! Read through the `las` crate's `CopcReader` (the crate arbvis already reads LAS/LAZ
//! with; it pages the hierarchy into one table and decodes a node's chunk with `laz`'s
//! layered decompressor), so only what no crate does is here: the checks. `las` trusts
//! the file (it reads every EVLR whole at the size its header declares, and a node's
//! points at the count its entry declares), so before it is called the LAS 1.4 header,
//! every VLR and EVLR header is checked against the file's length and the memory budget,
//! and after it every hierarchy entry: key inside the octree, chunk inside the point
//! data, at most 1,000,000 points plus one per compressed byte (as for LAZ files), the
//! counts summing to the header's. A node's points are decoded only on request, under
//! `catch_unwind` (`laz` panics on some corrupt streams), the error naming the node.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use las::copc::{CopcInfoVlr, Entry, VoxelKey};
use las::{CopcReader, PointData};

use super::lasfile::guarded;
use super::PointsError;

/// LAS 1.4's header size.
const HEADER: usize = 375;
/// A VLR header; an EVLR header.
const VLR_HEADER: u64 = 54;
const EVLR_HEADER: u64 = 60;
/// Deepest octree level read (keys are i32: 2^30 nodes a side is far past any survey).
const MAX_LEVEL: i32 = 30;

/// A COPC cloud in a scene: the file, and the most points drawn (whole levels from the
/// root; the root's level always).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CopcSpec {
    /// The `.copc.laz` file.
    pub path: PathBuf,
    /// The point budget (default 1,000,000, Potree's).
    #[serde(default = "default_budget")]
    pub points: u64,
}

fn default_budget() -> u64 {
    1_000_000
}

/// One octree node: its key, where its chunk lies and how many points it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Node {
    /// Level (0: the root), then x, y, z in `0..2^level`.
    pub key: [i32; 4],
    /// Byte offset of its LAZ chunk.
    pub offset: u64,
    /// Compressed bytes.
    pub bytes: u64,
    /// Points.
    pub points: u64,
}

/// An open COPC file: header, octree description and every node with points.
pub struct Copc {
    path: PathBuf,
    /// The octree's centre, half-size and root spacing (file units).
    pub info: CopcInfoVlr,
    /// Point format (6, 7 or 8) and record length.
    pub format: (u8, u16),
    /// The header's point count.
    pub points: u64,
    /// Nodes holding points, by level then key.
    pub nodes: Vec<Node>,
    reader: Mutex<CopcReader<'static, BufReader<File>>>,
}

/// Whether `head` (a file's first bytes) is a COPC file's: LAS 1.4 whose first VLR is
/// `copc` record 1.
pub fn is_copc(head: &[u8]) -> bool {
    head.len() >= HEADER + VLR_HEADER as usize
        && head.starts_with(b"LASF")
        && head[24..26] == [1, 4]
        && &head[HEADER + 2..HEADER + 6] == b"copc"
        && head[HEADER + 6..HEADER + 18].iter().all(|&b| b == 0)
        && u16::from_le_bytes([head[HEADER + 18], head[HEADER + 19]]) == 1
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

impl Copc {
    /// Open `path`, checking its header, VLRs, EVLRs and hierarchy.
    pub fn open(path: &Path) -> Result<Copc, PointsError> {
        let bad = |offset: u64, m: String| PointsError::format(path, offset, m);
        let mut file = File::open(path).map_err(|e| PointsError::io(path, e))?;
        let len = file.metadata().map_err(|e| PointsError::io(path, e))?.len();
        let mut head = vec![0u8; HEADER];
        file.read_exact(&mut head).map_err(|_| {
            bad(
                0,
                format!("{len} bytes: shorter than a LAS 1.4 header ({HEADER} bytes)"),
            )
        })?;
        if !head.starts_with(b"LASF") || head[24..26] != [1, 4] {
            return Err(bad(
                0,
                "expected LAS 1.4 (`LASF`, version 1.4): COPC files are LAS 1.4".into(),
            ));
        }
        let header_size = u16_at(&head, 94) as u64;
        let point_offset = u32_at(&head, 96) as u64;
        let vlr_count = u32_at(&head, 100);
        let format = head[104];
        let record = u16_at(&head, 105);
        let evlr_start = u64_at(&head, 235);
        let evlr_count = u32_at(&head, 243);
        let points = u64_at(&head, 247);
        if format & 0x80 == 0 || !(6..=8).contains(&(format & 0x3f)) {
            return Err(bad(
                104,
                format!(
                    "point format byte {format:#04x}: COPC is compressed (LAZ) point format 6, 7 or 8"
                ),
            ));
        }
        if header_size < HEADER as u64 || point_offset < header_size || point_offset > len {
            return Err(bad(
                94,
                format!("header size {header_size}, point data at {point_offset}: must lie inside the {len}-byte file, after the header"),
            ));
        }
        // The VLRs, between the header and the points.
        let mut at = header_size;
        for k in 0..vlr_count {
            let mut h = [0u8; VLR_HEADER as usize];
            if at + VLR_HEADER > point_offset {
                return Err(bad(
                    at,
                    format!("VLR {k} of {vlr_count} runs past the point data at {point_offset}"),
                ));
            }
            file.seek(SeekFrom::Start(at))
                .map_err(|e| PointsError::io(path, e))?;
            file.read_exact(&mut h)
                .map_err(|e| PointsError::io(path, e))?;
            let size = u16_at(&h, 20) as u64;
            if k == 0 && !(&h[2..6] == b"copc" && u16_at(&h, 18) == 1 && size == 160) {
                return Err(bad(at, "the first VLR is not COPC's info (user `copc`, record 1, 160 bytes): not a COPC file".into()));
            }
            at += VLR_HEADER + size;
            if at > point_offset {
                return Err(bad(
                    at,
                    format!("VLR {k} of {vlr_count} runs past the point data at {point_offset}"),
                ));
            }
        }
        // The EVLRs, read whole by `las`: inside the file and within the memory budget.
        if evlr_start < point_offset || evlr_start > len {
            return Err(bad(235, format!("the first EVLR at {evlr_start}: must lie between the point data ({point_offset}) and the end ({len})")));
        }
        let mut at = evlr_start;
        for k in 0..evlr_count {
            let mut h = [0u8; EVLR_HEADER as usize];
            if at.checked_add(EVLR_HEADER).is_none_or(|e| e > len) {
                return Err(bad(
                    at,
                    format!("EVLR {k} of {evlr_count} runs past the end of the file ({len} bytes)"),
                ));
            }
            file.seek(SeekFrom::Start(at))
                .map_err(|e| PointsError::io(path, e))?;
            file.read_exact(&mut h)
                .map_err(|e| PointsError::io(path, e))?;
            let size = u64_at(&h, 20);
            at = at
                .checked_add(EVLR_HEADER)
                .and_then(|a| a.checked_add(size))
                .filter(|&e| e <= len)
                .ok_or_else(|| bad(at, format!("EVLR {k} of {evlr_count} declares {size} bytes, past the end of the file ({len} bytes)")))?;
        }
        crate::budget::check(
            format!("the hierarchy and other EVLRs of {}", path.display()),
            (at - evlr_start).saturating_mul(3),
        )
        .map_err(|e| bad(evlr_start, e.to_string()))?;
        drop(file);
        let reader = guarded(|| CopcReader::from_path(path))
            .map_err(|e| bad(evlr_start, format!("the COPC header or hierarchy: {e}")))?;
        let info = reader
            .header()
            .copc_info_vlr()
            .ok_or_else(|| bad(HEADER as u64, "no COPC info VLR".into()))?;
        let mut nodes = Vec::new();
        let mut total = 0u64;
        for e in reader.hierarchy_entries() {
            let node = check_entry(&e, point_offset, evlr_start).map_err(|m| {
                bad(
                    evlr_start,
                    format!("hierarchy entry {:?}: {m}", key(&e.key)),
                )
            })?;
            if node.points > 0 {
                total += node.points;
                nodes.push(node);
            }
        }
        if total != points {
            return Err(bad(
                247,
                format!("the header declares {points} points, the hierarchy's nodes hold {total}"),
            ));
        }
        nodes.sort();
        Ok(Copc {
            path: path.to_path_buf(),
            info,
            format: (format & 0x3f, record),
            points,
            nodes,
            reader: Mutex::new(reader),
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The nodes of the whole levels from the root down whose points fit in `budget`
    /// (the root's level always), and their levels' count.
    pub fn cut(&self, budget: u64) -> (Vec<Node>, usize) {
        let mut total = 0u64;
        let mut levels = Vec::new();
        for (level, _, points) in self.levels() {
            if !levels.is_empty() && total + points > budget {
                break;
            }
            total += points;
            levels.push(level);
        }
        let nodes = self
            .nodes
            .iter()
            .filter(|n| levels.contains(&n.key[0]))
            .copied()
            .collect();
        (nodes, levels.len())
    }

    /// (level, nodes, points) of every level holding points, from the root down.
    pub fn levels(&self) -> Vec<(i32, usize, u64)> {
        let mut by: BTreeMap<i32, (usize, u64)> = BTreeMap::new();
        for n in &self.nodes {
            let e = by.entry(n.key[0]).or_default();
            e.0 += 1;
            e.1 += n.points;
        }
        by.into_iter().map(|(l, (n, p))| (l, n, p)).collect()
    }

    /// The points of `node`, decoded (its record bytes with the header's format and
    /// scales: `las::PointData`).
    pub fn read_node(&self, node: &Node) -> Result<PointData, PointsError> {
        let record = self.format.1 as u64;
        crate::budget::check(
            format!("node {:?} of {}", node.key, self.path.display()),
            node.points.saturating_mul(record).saturating_mul(2),
        )
        .map_err(|e| PointsError::format(&self.path, node.offset, e.to_string()))?;
        let entry = Entry {
            key: VoxelKey {
                l: node.key[0],
                x: node.key[1],
                y: node.key[2],
                z: node.key[3],
            },
            offset: node.offset,
            byte_size: node.bytes as i32,
            point_count: node.points as i32,
        };
        let mut reader = self.reader.lock().expect("COPC reader");
        guarded(|| reader.read_entry(&entry)).map_err(|e| PointsError::Decode {
            path: self.path.clone(),
            message: format!(
                "node {:?} ({} points, {} bytes at byte {}): {e}",
                node.key, node.points, node.bytes, node.offset
            ),
        })
    }

    /// What `inspect` says of the octree.
    pub fn describe(&self) -> String {
        let i = &self.info;
        let mut out = format!(
            "COPC octree: centre ({:.3}, {:.3}, {:.3}), half-size {:.3}, root spacing {:.4}; {} nodes with points, {} points\n",
            i.center_x,
            i.center_y,
            i.center_z,
            i.halfsize,
            i.spacing,
            self.nodes.len(),
            self.points
        );
        let (f, record) = self.format;
        let base = [30u16, 36, 38][(f - 6) as usize];
        let colours = [
            "",
            ", red, green, blue",
            ", red, green, blue, near infrared",
        ][(f - 6) as usize];
        out.push_str(&format!(
            "attributes: x, y, z, intensity, return number, number of returns, classification, scan angle, user data, point source id, gps time{colours}{}\n",
            if record > base {
                format!(", {} extra bytes a point", record - base)
            } else {
                String::new()
            }
        ));
        for (level, nodes, points) in self.levels() {
            out.push_str(&format!(
                "  level {level}: {nodes} nodes, {points} points, spacing {:.4}\n",
                i.spacing / f64::powi(2.0, level)
            ));
        }
        out
    }
}

fn key(k: &VoxelKey) -> [i32; 4] {
    [k.l, k.x, k.y, k.z]
}

/// A hierarchy entry checked: key inside the octree, chunk inside the point data, a
/// point count the chunk can hold.
fn check_entry(e: &Entry, point_offset: u64, evlr_start: u64) -> Result<Node, String> {
    let k = key(&e.key);
    let side = if (0..=MAX_LEVEL).contains(&k[0]) {
        1i64 << k[0]
    } else {
        return Err(format!("level {}: expected 0..={MAX_LEVEL}", k[0]));
    };
    if k[1..].iter().any(|&c| c < 0 || c as i64 >= side) {
        return Err(format!("x, y, z must lie in 0..{side} at level {}", k[0]));
    }
    if e.point_count < 0 || e.byte_size < 0 {
        return Err(format!(
            "{} points in {} bytes: expected counts of 0 or more",
            e.point_count, e.byte_size
        ));
    }
    let (points, bytes) = (e.point_count as u64, e.byte_size as u64);
    if points > 0 {
        if e.offset < point_offset || e.offset.saturating_add(bytes) > evlr_start || bytes == 0 {
            return Err(format!(
                "its chunk ({bytes} bytes at {}) must lie in the point data ({point_offset}..{evlr_start})",
                e.offset
            ));
        }
        if points > 1_000_000 + bytes {
            return Err(format!(
                "{points} points in {bytes} compressed bytes: more than 1,000,000 plus one a byte"
            ));
        }
    }
    Ok(Node {
        key: k,
        offset: e.offset,
        bytes,
        points,
    })
}
