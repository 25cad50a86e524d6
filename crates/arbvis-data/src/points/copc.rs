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
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use las::{Header, PointData, PointDataBuilder};
use laz::record::{LayeredPointRecordDecompressor, RecordDecompressor};

use super::copc_hierarchy::Hierarchy;
pub use super::copc_hierarchy::Node;
use super::guarded;
use super::PointsError;
use crate::le::u32_at;

mod open;

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
    /// The file, local or remote.
    file: crate::fetch::File,
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

pub use crate::sniff::is_copc;

impl Copc {
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
        for &key in keys {
            h.read_key(key, &mut |at, buf| self.file.read_at(at, buf))
                .map_err(|(at, m)| PointsError::format(&self.path, at, m))?;
        }
        Ok(())
    }

    /// Every node holding points, by level then key: the whole hierarchy, every page read
    /// (and the counts checked against the header's).
    pub fn all_nodes(&self) -> Result<Vec<Node>, PointsError> {
        let mut h = self.hierarchy();
        h.read_all(&mut |at, buf| self.file.read_at(at, buf))
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
        arbvis_core::budget::check(
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
        self.file
            .read_at(node.offset, &mut chunk)
            .map_err(|e| what(e.to_string()))?;
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
        .map_err(|e| what(e.to_string()))?;
        PointDataBuilder::new()
            .for_header(&self.header)
            .build_from_bytes(out)
            .map_err(|e| what(e.to_string()))
    }

    /// Fetch the chunks of `nodes` ahead, when the file is remote: their ranges merged
    /// where close, many requests at once. A failure is left to the node's own read,
    /// which names the node.
    pub fn prefetch(&self, nodes: &[Node]) {
        let ranges: Vec<std::ops::Range<u64>> = nodes
            .iter()
            .map(|n| n.offset..n.offset.saturating_add(n.bytes))
            .collect();
        let _ = self.file.prefetch(&ranges);
    }

    /// The file, local or remote.
    pub(crate) fn file(&self) -> &crate::fetch::File {
        &self.file
    }

    /// The ETag the file had when opened, where it is remote.
    pub fn etag(&self) -> Option<&str> {
        self.file.etag()
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
