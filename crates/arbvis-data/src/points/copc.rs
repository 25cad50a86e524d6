//! COPC, Cloud Optimized Point Cloud (copc.io): a LAZ 1.4 file (point formats 6-8) whose
//! points are an octree of nodes, each one LAZ chunk, found through a hierarchy EVLR of
//! pages of (level, x, y, z) keys with the chunk's offset, byte size and point count. The
//! first VLR (`copc`, record 1) gives the octree's centre, half-size and root spacing.
//!
//! The header and VLRs through the `las` crate and a node's chunk through `laz`'s layered
//! decompressor (the crates arbvis already reads LAS/LAZ with); the hierarchy is walked
//! here, because `las` 0.11's `CopcReader` follows child pages by key without a visited
//! set: a page that points to itself (a 4-byte change) makes it collect entries until
//! memory runs out. Before `las` is called the LAS 1.4 header and every VLR and EVLR
//! header are checked against the file's length and the memory budget, and the laszip
//! items against the record length. The hierarchy is read a page at a time: the root's
//! at opening, the others when a view reaches them (`copc_hierarchy`, with its checks). The octree's centre, half-size and spacing must be
//! finite and the sizes positive. Errors name the byte (an entry's own). A node's points
//! are decoded only on request from its chunk alone, under `catch_unwind` (`laz` panics on
//! some corrupt streams), the error naming the node.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use las::{Header, PointData, PointDataBuilder};
use laz::record::{LayeredPointRecordDecompressor, RecordDecompressor};

use super::copc_hierarchy::Hierarchy;
pub use super::copc_hierarchy::Node;
use super::guarded;
use super::PointsError;

/// LAS 1.4's header size.
const HEADER: usize = 375;
/// A VLR header; an EVLR header.
const VLR_HEADER: u64 = 54;
const EVLR_HEADER: u64 = 60;

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
    /// Nodes whose bounding sphere projects under this radius in pixels are not drawn
    /// (Potree's `minimumNodePixelSize`, 150); 0 draws every node the budget allows.
    #[serde(default = "default_min_node_pixels")]
    pub min_node_pixels: f64,
}

/// Potree's `minimumNodePixelSize`: nodes whose bounding sphere projects under this
/// radius in pixels are not drawn.
pub const DEFAULT_MIN_NODE_PIXELS: f64 = 150.0;

fn default_min_node_pixels() -> f64 {
    DEFAULT_MIN_NODE_PIXELS
}

fn default_budget() -> u64 {
    1_000_000
}

/// An open COPC file: header, octree description and the hierarchy pages read so far.
pub struct Copc {
    path: PathBuf,
    /// The octree's centre, half-size and root spacing (file units).
    pub info: OctreeInfo,
    /// Point format (6, 7 or 8) and record length.
    pub format: (u8, u16),
    /// The header's point count.
    pub points: u64,
    /// The header's bounds (min, max), inside the octree's cube.
    pub bounds: [[f64; 3]; 2],
    /// The hierarchy pages read so far (the root's at opening, the others on demand).
    hierarchy: Mutex<Hierarchy>,
    header: Header,
    items: Vec<laz::LazItem>,
    file: Mutex<BufReader<File>>,
}

/// The COPC info VLR's octree: centre, half-size (centre to a face of the root node) and
/// the spacing of the root's points (halved at each level).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OctreeInfo {
    /// Centre x.
    pub center_x: f64,
    /// Centre y.
    pub center_y: f64,
    /// Centre z.
    pub center_z: f64,
    /// Half the root node's side.
    pub halfsize: f64,
    /// Spacing of the root's points.
    pub spacing: f64,
    /// The earliest and latest GPS time of the points (as the info VLR says; unchecked).
    pub gps_range: [f64; 2],
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

/// Fill `buf` from byte `at` of `file`.
fn read_at(file: &mut (impl Read + Seek), at: u64, buf: &mut [u8]) -> std::io::Result<()> {
    file.seek(SeekFrom::Start(at))?;
    file.read_exact(buf)
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
        // A FIFO, a device or a folder is refused here, never waited on.
        let (mut file, len) =
            crate::input::open_regular(path).map_err(|e| PointsError::io(path, e))?;
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
        let f64_at_head = |at: usize| f64::from_le_bytes(head[at..at + 8].try_into().expect("8"));
        for (axis, at) in [("x", 131), ("y", 139), ("z", 147)] {
            let (scale, offset) = (f64_at_head(at), f64_at_head(at + 24));
            if !(scale.is_finite() && scale != 0.0 && offset.is_finite()) {
                return Err(bad(at as u64, format!("{axis} scale {scale}, offset {offset}: expected a finite, non-zero scale and a finite offset")));
            }
            let (max, min) = (
                f64_at_head(179 + (at - 131) * 2),
                f64_at_head(187 + (at - 131) * 2),
            );
            if !(min.is_finite() && max.is_finite() && min <= max) {
                return Err(bad(
                    (179 + (at - 131) * 2) as u64,
                    format!("{axis} bounds {min}..{max}: expected finite, min <= max"),
                ));
            }
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
            read_at(&mut file, at, &mut h).map_err(|e| PointsError::io(path, e))?;
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
        // Every hierarchy EVLR: one holding every page, or one a page (copclib).
        let mut hierarchy = Vec::new();
        for k in 0..evlr_count {
            let mut h = [0u8; EVLR_HEADER as usize];
            if at.checked_add(EVLR_HEADER).is_none_or(|e| e > len) {
                return Err(bad(
                    at,
                    format!("EVLR {k} of {evlr_count} runs past the end of the file ({len} bytes)"),
                ));
            }
            read_at(&mut file, at, &mut h).map_err(|e| PointsError::io(path, e))?;
            let size = u64_at(&h, 20);
            if &h[2..6] == b"copc" && h[6..18].iter().all(|&b| b == 0) && u16_at(&h, 18) == 1000 {
                hierarchy.push((at + EVLR_HEADER, at + EVLR_HEADER + size.min(len)));
            }
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
        // The info VLR's octree and root page.
        let mut info = [0u8; 160];
        read_at(&mut file, header_size + VLR_HEADER, &mut info)
            .map_err(|e| PointsError::io(path, e))?;
        let f64_at = |at: usize| f64::from_le_bytes(info[at..at + 8].try_into().expect("8"));
        let octree = OctreeInfo {
            center_x: f64_at(0),
            center_y: f64_at(8),
            center_z: f64_at(16),
            halfsize: f64_at(24),
            spacing: f64_at(32),
            gps_range: [f64_at(56), f64_at(64)],
        };
        let info_at = header_size + VLR_HEADER;
        let finite = [octree.center_x, octree.center_y, octree.center_z]
            .iter()
            .all(|v| v.is_finite());
        let sizes = [octree.halfsize, octree.spacing]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !finite || !sizes {
            return Err(bad(
                info_at,
                format!("COPC info: centre ({}, {}, {}), half-size {}, spacing {}: expected a finite centre and positive sizes", octree.center_x, octree.center_y, octree.center_z, octree.halfsize, octree.spacing),
            ));
        }
        // The header's bounds inside the root node's cube (a scale step of slack).
        let centre = [octree.center_x, octree.center_y, octree.center_z];
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            let (max, min) = (f64_at_head(179 + 16 * a), f64_at_head(187 + 16 * a));
            let slack = f64_at_head(131 + 8 * a).abs() + 1e-9 * octree.halfsize;
            if min < centre[a] - octree.halfsize - slack
                || max > centre[a] + octree.halfsize + slack
            {
                return Err(bad(
                    info_at,
                    format!("the points' {axis} bounds {min}..{max} are outside the octree's cube ({} +- {})", centre[a], octree.halfsize),
                ));
            }
        }
        let root = (u64_at(&info, 40), u64_at(&info, 48));
        if hierarchy.is_empty() {
            return Err(bad(
                evlr_start,
                "no hierarchy EVLR (user `copc`, record 1000)".into(),
            ));
        }
        // The checks every LAS/LAZ reader runs on the header and VLRs, and the
        // extra-bytes descriptors against the record: what `render` decodes with, so
        // `inspect` refuses what `render` would.
        super::lasfile::stream::check_las_head(path, &mut file, len)?;
        let hierarchy = Hierarchy::open(
            hierarchy,
            (point_offset, evlr_start),
            points,
            (root, info_at + 40),
            &mut |at, buf| read_at(&mut file, at, buf),
        )
        .map_err(|(at, m)| bad(at, m))?;
        file.seek(SeekFrom::Start(0))
            .map_err(|e| PointsError::io(path, e))?;
        let header = guarded(|| Header::new(BufReader::new(&mut file)))
            .map_err(|e| bad(0, format!("the LAS header: {e}")))?;
        let laz = guarded(|| header.laz_vlr())
            .map_err(|e| bad(header_size, format!("the laszip VLR: {e}")))?;
        // COPC's points are compressed in layers (compressor 3), with the items of their
        // format: Point14, then RGB14 (7) or RGBNIR14 (8), then any extra bytes.
        let compressor = header
            .vlrs()
            .iter()
            .find(|v| v.user_id == laz::LazVlr::USER_ID && v.record_id == laz::LazVlr::RECORD_ID)
            .and_then(|v| v.data.get(..2))
            .map(|b| u16::from_le_bytes([b[0], b[1]]));
        if compressor != Some(3) {
            return Err(bad(
                header_size,
                format!(
                    "the laszip VLR's compressor {compressor:?}: COPC is compressed in layers (3)"
                ),
            ));
        }
        let types: Vec<laz::LazItemType> = laz.items().iter().map(|i| i.item_type()).collect();
        use laz::LazItemType::{Byte14, Point14, RGB14, RGBNIR14};
        let colour = match format & 0x3f {
            6 => None,
            7 => Some(RGB14),
            _ => Some(RGBNIR14),
        };
        let expected = types.first() == Some(&Point14)
            && types
                .get(1)
                .copied()
                .filter(|t| *t == RGB14 || *t == RGBNIR14)
                == colour
            && types[1 + usize::from(colour.is_some())..]
                .iter()
                .all(|t| matches!(t, Byte14(_)));
        if !expected {
            return Err(bad(
                104,
                format!(
                    "point format {}: the laszip items are {types:?}",
                    format & 0x3f
                ),
            ));
        }
        if laz.items_size() != record as u64 {
            return Err(bad(
                105,
                format!(
                    "the LAZ items hold {} bytes, the point records {record}",
                    laz.items_size()
                ),
            ));
        }
        let bounds = [
            [f64_at_head(187), f64_at_head(203), f64_at_head(219)],
            [f64_at_head(179), f64_at_head(195), f64_at_head(211)],
        ];
        Ok(Copc {
            bounds,
            path: path.to_path_buf(),
            info: octree,
            format: (format & 0x3f, record),
            points,
            hierarchy: Mutex::new(hierarchy),
            header,
            items: laz.items().clone(),
            file: Mutex::new(BufReader::new(file)),
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Nodes holding points in the hierarchy pages read so far, by level then key.
    pub fn nodes_read(&self) -> Vec<Node> {
        self.hierarchy().nodes()
    }

    /// Keys of the child pages of the hierarchy named and not read yet.
    pub fn unread_pages(&self) -> Vec<[i32; 4]> {
        self.hierarchy().unread()
    }

    /// Hierarchy pages read, and named but not read.
    pub fn pages(&self) -> (usize, usize) {
        self.hierarchy().pages()
    }

    /// Read the child pages of `keys` (keys that name no unread page are passed over).
    pub fn read_pages(&self, keys: &[[i32; 4]]) -> Result<(), PointsError> {
        let mut h = self.hierarchy();
        let mut file = self.file.lock().unwrap_or_else(|e| e.into_inner());
        for &key in keys {
            h.read_key(key, &mut |at, buf| read_at(&mut *file, at, buf))
                .map_err(|(at, m)| PointsError::format(&self.path, at, m))?;
        }
        Ok(())
    }

    /// Every node holding points, by level then key: the whole hierarchy, every page read
    /// (and the counts checked against the header's).
    pub fn all_nodes(&self) -> Result<Vec<Node>, PointsError> {
        let mut h = self.hierarchy();
        let mut file = self.file.lock().unwrap_or_else(|e| e.into_inner());
        h.read_all(&mut |at, buf| read_at(&mut *file, at, buf))
            .map_err(|(at, m)| PointsError::format(&self.path, at, m))?;
        Ok(h.nodes())
    }

    fn hierarchy(&self) -> std::sync::MutexGuard<'_, Hierarchy> {
        self.hierarchy.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The nodes of the whole levels from the root down whose points fit in `budget`
    /// (the root's level always), and their levels' count. Reads the whole hierarchy.
    pub fn cut(&self, budget: u64) -> Result<(Vec<Node>, usize), PointsError> {
        let mut total = 0u64;
        let mut levels = Vec::new();
        for (level, _, points) in self.levels()? {
            if !levels.is_empty() && total + points > budget {
                break;
            }
            total += points;
            levels.push(level);
        }
        let nodes = self
            .all_nodes()?
            .into_iter()
            .filter(|n| levels.contains(&n.key[0]))
            .collect();
        Ok((nodes, levels.len()))
    }

    /// (level, nodes, points) of every level holding points, from the root down. Reads
    /// the whole hierarchy.
    pub fn levels(&self) -> Result<Vec<(i32, usize, u64)>, PointsError> {
        let mut by: BTreeMap<i32, (usize, u64)> = BTreeMap::new();
        for n in self.all_nodes()? {
            let e = by.entry(n.key[0]).or_default();
            e.0 += 1;
            e.1 += n.points;
        }
        Ok(by.into_iter().map(|(l, (n, p))| (l, n, p)).collect())
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
        let what = |e: String| PointsError::Decode {
            path: self.path.clone(),
            message: format!(
                "node {:?} ({} points, {} bytes at byte {}): {e}",
                node.key, node.points, node.bytes, node.offset
            ),
        };
        let mut chunk = vec![0u8; node.bytes as usize];
        {
            let mut file = self.file.lock().expect("COPC file");
            read_at(&mut *file, node.offset, &mut chunk).map_err(|e| what(e.to_string()))?;
        }
        // A layered chunk: the first point raw, a u32 point count, a u32 size per layer,
        // the layers. `laz` allocates each layer at its declared size: the sizes must fit
        // in the chunk first.
        let layers: usize = self
            .items
            .iter()
            .map(|i| match i.item_type() {
                laz::LazItemType::Point14 => 9,
                laz::LazItemType::RGB14 => 1,
                laz::LazItemType::RGBNIR14 => 2,
                laz::LazItemType::Byte14(n) => n as usize,
                _ => 0,
            })
            .sum();
        let sizes_at = record as usize + 4;
        let sizes_end = sizes_at + 4 * layers;
        if chunk.len() < sizes_end {
            return Err(what(format!(
                "a layered chunk needs {sizes_end} bytes before its layers"
            )));
        }
        let count = u32_at(&chunk, record as usize) as u64;
        if count != node.points {
            return Err(what(format!("the chunk holds {count} points")));
        }
        let sum: u64 = (0..layers)
            .map(|l| u32_at(&chunk, sizes_at + 4 * l) as u64)
            .sum();
        if sum > (chunk.len() - sizes_end) as u64 {
            return Err(what(format!(
                "its layers declare {sum} bytes, {} follow",
                chunk.len() - sizes_end
            )));
        }
        let mut out = vec![0u8; (node.points * record) as usize];
        guarded(|| {
            let mut d = LayeredPointRecordDecompressor::new(std::io::Cursor::new(&chunk));
            d.set_fields_from(&self.items)?;
            d.decompress_many(&mut out)?;
            Ok(())
        })
        .map_err(what)?;
        PointDataBuilder::new()
            .for_header(&self.header)
            .build_from_bytes(out)
            .map_err(|e| what(e.to_string()))
    }

    /// What `inspect` says of the octree (the whole hierarchy read).
    pub fn describe(&self) -> Result<String, PointsError> {
        let i = &self.info;
        let levels = self.levels()?;
        let (pages, _) = self.pages();
        let mut out = format!(
            "COPC octree: centre ({:.3}, {:.3}, {:.3}), half-size {:.3}, root spacing {:.4}; {} nodes with points, {} points, hierarchy in {pages} page{}\n",
            i.center_x,
            i.center_y,
            i.center_z,
            i.halfsize,
            i.spacing,
            levels.iter().map(|l| l.1).sum::<usize>(),
            self.points,
            if pages == 1 { "" } else { "s" }
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
        for (level, nodes, points) in levels {
            out.push_str(&format!(
                "  level {level}: {nodes} nodes, {points} points, spacing {:.4}\n",
                i.spacing / f64::powi(2.0, level)
            ));
        }
        Ok(out)
    }
}
