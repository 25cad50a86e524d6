//! Opening a COPC file: its LAS 1.4 header, VLRs and EVLRs checked against the file
//! (read through [`crate::points::lasfile::layout`]), the info VLR's octree, the checks
//! every LAS reader runs, the root hierarchy page and the laszip items.

use std::io::BufReader;
use std::path::Path;
use std::sync::Mutex;

use crate::fetch::{Cursor, File};

use las::Header;

use super::{Copc, OctreeInfo};
use crate::le::{f64_at, u64_at};
use crate::points::copc_hierarchy::Hierarchy;
use crate::points::guarded;
use crate::points::lasfile::layout::{RawHeader, Vlr, Walk, WalkError, HEADER_14, VLR_HEADER};
use crate::points::PointsError;

/// The file being opened and its length.
struct Opening<'p> {
    path: &'p Path,
    file: File,
    len: u64,
}

impl Opening<'_> {
    /// A refusal naming byte `offset`.
    fn bad(&self, offset: u64, m: String) -> PointsError {
        PointsError::format(self.path, offset, m)
    }

    /// An I/O failure.
    fn io(&self, e: std::io::Error) -> PointsError {
        PointsError::io(self.path, e)
    }
}

impl Copc {
    /// Open `path`, checking its header, VLRs, EVLRs and hierarchy.
    pub fn open(path: &Path) -> Result<Copc, PointsError> {
        // A FIFO, a device or a folder is refused here, never waited on; a URL costs one
        // request (the first 64 KiB: the header and VLRs).
        let file = File::open(path).map_err(|e| PointsError::io(path, std::io::Error::other(e)))?;
        let len = file.len();
        let mut f = Opening { path, file, len };
        let h = f.header()?;
        f.vlrs(&h)?;
        let (hierarchy, evlrs_end) = f.evlrs(&h)?;
        arbvis_core::budget::check(
            format!("the hierarchy and other EVLRs of {}", path.display()),
            (evlrs_end - h.evlr_start).saturating_mul(3),
        )
        .map_err(|e| f.bad(h.evlr_start, e.to_string()))?;
        let (octree, root) = f.octree(&h)?;
        if hierarchy.is_empty() {
            return Err(f.bad(
                h.evlr_start,
                "no hierarchy EVLR (user `copc`, record 1000)".into(),
            ));
        }
        // The checks every LAS/LAZ reader runs on the header and VLRs, and the
        // extra-bytes descriptors against the record: what `render` decodes with, so
        // `inspect` refuses what `render` would.
        crate::points::lasfile::stream::check_las_head(path, &mut Cursor::new(&f.file), len)?;
        let info_at = h.header_size as u64 + VLR_HEADER;
        let hierarchy = Hierarchy::open(
            hierarchy,
            (h.point_offset as u64, h.evlr_start),
            h.count_64,
            (root, info_at + 40),
            &mut |at, buf| f.file.read_at(at, buf),
        )
        .map_err(|(at, m)| PointsError::format(path, at, m))?;
        let (header, items) = f.las_header(&h)?;
        Ok(Copc {
            bounds: h.bounds,
            path: path.to_path_buf(),
            info: octree,
            format: (h.point_format(), h.record_length),
            points: h.count_64,
            hierarchy: Mutex::new(hierarchy),
            header,
            items,
            file: f.file,
        })
    }
}

impl Opening<'_> {
    /// The LAS 1.4 header: a compressed point format 6-8, finite non-zero scales,
    /// finite offsets and bounds, the point data inside the file after the header.
    fn header(&mut self) -> Result<RawHeader, PointsError> {
        let len = self.len;
        let mut head = vec![0u8; HEADER_14];
        self.file.read_at(0, &mut head).map_err(|_| {
            self.bad(
                0,
                format!("{len} bytes: shorter than a LAS 1.4 header ({HEADER_14} bytes)"),
            )
        })?;
        if !head.starts_with(b"LASF") || head[24..26] != [1, 4] {
            return Err(self.bad(
                0,
                "expected LAS 1.4 (`LASF`, version 1.4): COPC files are LAS 1.4".into(),
            ));
        }
        let h = RawHeader::parse(&head).expect("a LAS 1.4 header's bytes");
        let format = h.format_byte;
        if format & 0x80 == 0 || !(6..=8).contains(&(format & 0x3f)) {
            return Err(self.bad(
                104,
                format!(
                    "point format byte {format:#04x}: COPC is compressed (LAZ) point format 6, 7 or 8"
                ),
            ));
        }
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            let at = 131 + 8 * a as u64;
            let (scale, offset) = (h.scale[a], h.offset[a]);
            if !(scale.is_finite() && scale != 0.0 && offset.is_finite()) {
                return Err(self.bad(at, format!("{axis} scale {scale}, offset {offset}: expected a finite, non-zero scale and a finite offset")));
            }
            let (min, max) = (h.bounds[0][a], h.bounds[1][a]);
            if !(min.is_finite() && max.is_finite() && min <= max) {
                return Err(self.bad(
                    179 + 16 * a as u64,
                    format!("{axis} bounds {min}..{max}: expected finite, min <= max"),
                ));
            }
        }
        let (header_size, point_offset) = (h.header_size as u64, h.point_offset as u64);
        if header_size < HEADER_14 as u64 || point_offset < header_size || point_offset > len {
            return Err(self.bad(
                94,
                format!("header size {header_size}, point data at {point_offset}: must lie inside the {len}-byte file, after the header"),
            ));
        }
        Ok(h)
    }

    /// The VLRs, between the header and the points, the first COPC's info.
    fn vlrs(&mut self, h: &RawHeader) -> Result<(), PointsError> {
        let (count, point_offset) = (h.vlr_count, h.point_offset as u64);
        let is_info =
            |v: &Vlr| &v.user_raw[..4] == b"copc" && v.record_id == 1 && v.data.len() == 160;
        let past =
            |k: u32| format!("VLR {k} of {count} runs past the point data at {point_offset}");
        let mut walk = Walk::vlrs(h.header_size as u64, count, point_offset);
        let path = self.path;
        let bad = |offset: u64, m: String| PointsError::format(path, offset, m);
        let file = &self.file;
        let mut read = |at, buf: &mut [u8]| file.read_at(at, buf);
        let mut first = true;
        while let Some(next) = walk.next(&mut read) {
            let vlr = match next {
                Ok(vlr) => Ok(vlr),
                Err(WalkError::Data { index, vlr, .. }) => Err((index, vlr)),
                Err(WalkError::Header { index, at }) => return Err(bad(at, past(index))),
                Err(WalkError::Io(e)) => return Err(PointsError::io(path, e)),
            };
            let (Ok(v) | Err((_, v))) = &vlr;
            if first && !is_info(v) {
                return Err(bad(v.at as u64, "the first VLR is not COPC's info (user `copc`, record 1, 160 bytes): not a COPC file".into()));
            }
            first = false;
            if let Err((index, v)) = vlr {
                return Err(bad(v.data.end as u64, past(index)));
            }
        }
        Ok(())
    }

    /// The EVLRs, read whole by `las`: inside the file. Returns the data of every
    /// hierarchy EVLR (one holding every page, or one a page: copclib) and where the
    /// EVLRs end.
    fn evlrs(&mut self, h: &RawHeader) -> Result<(Vec<(u64, u64)>, u64), PointsError> {
        let (start, count, len) = (h.evlr_start, h.evlr_count, self.len);
        let point_offset = h.point_offset as u64;
        if start < point_offset || start > len {
            return Err(self.bad(235, format!("the first EVLR at {start}: must lie between the point data ({point_offset}) and the end ({len})")));
        }
        let path = self.path;
        let bad = |offset: u64, m: String| PointsError::format(path, offset, m);
        let file = &self.file;
        let mut hierarchy = Vec::new();
        let mut walk = Walk::evlrs(start, count, len);
        let mut read = |at, buf: &mut [u8]| file.read_at(at, buf);
        while let Some(next) = walk.next(&mut read) {
            match next {
                Ok(v) => {
                    let page = &v.user_raw[..4] == b"copc"
                        && v.user_raw[4..].iter().all(|&b| b == 0)
                        && v.record_id == 1000;
                    if page {
                        hierarchy.push((v.data.start as u64, v.data.end as u64));
                    }
                }
                Err(WalkError::Header { index, at }) => {
                    return Err(bad(
                        at,
                        format!("EVLR {index} of {count} runs past the end of the file ({len} bytes)"),
                    ))
                }
                Err(WalkError::Data { index, vlr, size }) => {
                    return Err(bad(vlr.at as u64, format!("EVLR {index} of {count} declares {size} bytes, past the end of the file ({len} bytes)")))
                }
                Err(WalkError::Io(e)) => return Err(PointsError::io(path, e)),
            }
        }
        Ok((hierarchy, walk.at()))
    }

    /// The info VLR's octree (finite centre, positive sizes, the header's bounds inside
    /// its cube) and the root page's offset and size.
    fn octree(&mut self, h: &RawHeader) -> Result<(OctreeInfo, (u64, u64)), PointsError> {
        let info_at = h.header_size as u64 + VLR_HEADER;
        let mut info = [0u8; 160];
        self.file
            .read_at(info_at, &mut info)
            .map_err(|e| self.io(e))?;
        let f = |at: usize| f64_at(&info, at);
        let octree = OctreeInfo {
            center_x: f(0),
            center_y: f(8),
            center_z: f(16),
            halfsize: f(24),
            spacing: f(32),
            gps_range: [f(56), f(64)],
        };
        let centre = [octree.center_x, octree.center_y, octree.center_z];
        let finite = centre.iter().all(|v| v.is_finite());
        let sizes = [octree.halfsize, octree.spacing]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0);
        if !finite || !sizes {
            return Err(self.bad(
                info_at,
                format!("COPC info: centre ({}, {}, {}), half-size {}, spacing {}: expected a finite centre and positive sizes", octree.center_x, octree.center_y, octree.center_z, octree.halfsize, octree.spacing),
            ));
        }
        // The header's bounds inside the root node's cube (a scale step of slack).
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            let (min, max) = (h.bounds[0][a], h.bounds[1][a]);
            let slack = h.scale[a].abs() + 1e-9 * octree.halfsize;
            if min < centre[a] - octree.halfsize - slack
                || max > centre[a] + octree.halfsize + slack
            {
                return Err(self.bad(
                    info_at,
                    format!("the points' {axis} bounds {min}..{max} are outside the octree's cube ({} +- {})", centre[a], octree.halfsize),
                ));
            }
        }
        Ok((octree, (u64_at(&info, 40), u64_at(&info, 48))))
    }

    /// The header as `las` reads it, and the laszip items: layered (compressor 3), of
    /// the point format's types, as long as a record.
    fn las_header(&mut self, h: &RawHeader) -> Result<(Header, Vec<laz::LazItem>), PointsError> {
        let header_size = h.header_size as u64;
        let header = guarded(|| Header::new(BufReader::new(Cursor::new(&self.file))))
            .map_err(|e| self.bad(0, format!("the LAS header: {e}")))?;
        let laz = guarded(|| header.laz_vlr())
            .map_err(|e| self.bad(header_size, format!("the laszip VLR: {e}")))?;
        // COPC's points are compressed in layers (compressor 3), with the items of their
        // format: Point14, then RGB14 (7) or RGBNIR14 (8), then any extra bytes.
        let compressor = header
            .vlrs()
            .iter()
            .find(|v| v.user_id == laz::LazVlr::USER_ID && v.record_id == laz::LazVlr::RECORD_ID)
            .and_then(|v| v.data.get(..2))
            .map(|b| u16::from_le_bytes([b[0], b[1]]));
        if compressor != Some(3) {
            return Err(self.bad(
                header_size,
                format!(
                    "the laszip VLR's compressor {compressor:?}: COPC is compressed in layers (3)"
                ),
            ));
        }
        let types: Vec<laz::LazItemType> = laz.items().iter().map(|i| i.item_type()).collect();
        if !expected_items(h.point_format(), &types) {
            return Err(self.bad(
                104,
                format!(
                    "point format {}: the laszip items are {types:?}",
                    h.point_format()
                ),
            ));
        }
        let record = h.record_length;
        if laz.items_size() != record as u64 {
            return Err(self.bad(
                105,
                format!(
                    "the LAZ items hold {} bytes, the point records {record}",
                    laz.items_size()
                ),
            ));
        }
        Ok((header, laz.items().clone()))
    }
}

/// Whether `types` are COPC's items for point format `format` (6, 7 or 8): Point14,
/// then RGB14 (7) or RGBNIR14 (8), then any extra bytes.
fn expected_items(format: u8, types: &[laz::LazItemType]) -> bool {
    use laz::LazItemType::{Byte14, Point14, RGB14, RGBNIR14};
    let colour = match format {
        6 => None,
        7 => Some(RGB14),
        _ => Some(RGBNIR14),
    };
    types.first() == Some(&Point14)
        && types
            .get(1)
            .copied()
            .filter(|t| *t == RGB14 || *t == RGBNIR14)
            == colour
        && types[1 + usize::from(colour.is_some())..]
            .iter()
            .all(|t| matches!(t, Byte14(_)))
}
