//! LAS 1.0-1.4 and LAZ files through the `las` crate (with its `laz` feature): point
//! formats 0-10, 64-bit point counts, colours, extra bytes.
//!
//! What becomes of a point: its coordinates with the header's scale and offset; the
//! attributes `intensity`, `classification`, `return_number`, `number_of_returns`
//! (integers); RGB when the format has it (u16 as stored); and every extra-bytes
//! attribute described by the Extra Bytes VLR (`LASF_Spec` record 4, or an EVLR) by its
//! name (`name[0]`, `name[1]` for the deprecated 2- and 3-element arrays), with its scale
//! and offset applied and its no-data value read as NaN; integer ones without scale stay
//! integers when they fit i32, the others become f32. Undescribed extra bytes are
//! skipped.
//!
//! Hostile files: `las` trusts the header (it sizes buffers from the declared count
//! and record length, and from EVLR lengths; `laz` sizes its chunk table from the file
//! and, in LAZ 1.4, each layer from its declared size), so `check.rs` checks the header
//! itself before calling them: version and format known, header, VLRs and the first
//! EVLR inside the file, `count × record length` within the bytes after the point
//! offset for LAS, at most [`MAX_POINTS`](super::MAX_POINTS) points; for LAZ the laszip
//! VLR's items must match the record length, the chunk table must be smaller than the
//! compressed data and hold at least the declared points, and every LAZ 1.4 chunk's
//! layer sizes must fit in the file.
//!
//! Memory and time: the header's count, times what each point costs once loaded
//! ([`super::footprint`] and an f64 per extra-bytes value), plus the file and one batch of
//! records, is checked against [`arbvis_core::budget`] before anything is decoded; the columns
//! are then reserved once. A LAZ file may declare at most 1,000,000 points plus 1 per byte
//! of compressed data, each extra-bytes attribute counting a third of a point (see
//! `check::laz_bound`): LAZ decodes about 2.5 million points a second here and a stream
//! of equal points (legal) packs 85 into a byte, so without it a 2 MB file could take
//! minutes; real lidar compresses to less than a point a byte. Points are decoded in
//! batches of at most 65,536 points and 16 MiB of records, and a decoder error names the
//! batch.
//! `laz` panics on some corrupt compressed streams; those calls run under
//! `catch_unwind` and the panic becomes an error (see `guarded`).

use std::io::Cursor;
use std::path::Path;

use las::{PointData, PointDataBuilder, Reader};
use rayon::prelude::*;

mod check;
mod check_laz;
mod extra;
mod header;
pub mod layout;
mod laz_chunks;
pub(crate) mod stream;

use check::{check, laz_bound};
use extra::{decode_extra, extra_bytes, extra_type_size, Extra};
pub use header::LasInfo;
use header::RECORD_LENGTH;

use super::guarded;
use super::progress::Progress;
use super::{read_file, CloudParts, PartsError, PointCloud, PointsError, Values};
use arbvis_core::budget::{vec_for, OverBudget};

/// Points decoded per batch, at most.
const BATCH: u64 = 65_536;

/// Bytes of records decoded per batch, at most (a record may be 64 KiB long).
const BATCH_BYTES: u64 = 16 << 20;

/// Points per batch for records of `record` bytes.
fn batch_points(record: usize) -> u64 {
    (BATCH_BYTES / record.max(1) as u64).clamp(1, BATCH)
}

/// A LAS/LAZ file's cloud and header facts.
#[derive(Debug, Clone)]
pub struct LasCloud {
    /// The points.
    pub cloud: PointCloud,
    /// The header.
    pub info: LasInfo,
}

/// Read a LAS or LAZ file.
pub fn read(path: &Path) -> Result<LasCloud, PointsError> {
    parse_owned(path, read_file(path)?)
}

/// Parse LAS or LAZ bytes named `name` (copies them: the decoder needs to own its input).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<LasCloud, PointsError> {
    parse_owned(name, bytes.to_vec())
}

/// Parse LAS/LAZ bytes named `name`, taking ownership of them.
pub(crate) fn parse_owned(name: &Path, bytes: Vec<u8>) -> Result<LasCloud, PointsError> {
    let checked = check(name, &bytes)?;
    let mut info = checked.info;
    let base = RECORD_LENGTH[info.point_format as usize] as usize;
    let record = info.record_length as usize;
    let extras = extra_bytes(name, &bytes, &checked.vlrs, base, record)?;
    info.extra_bytes = extras.iter().map(|e| e.name.clone()).collect();
    laz_bound(name, &bytes, &info, checked.count_at, extras.len())?;
    let count = info.points;
    let decode_error = |what: String| PointsError::Decode {
        path: name.to_path_buf(),
        message: what,
    };
    let has_rgb = matches!(info.point_format, 2 | 3 | 5 | 7 | 8 | 10);
    let has_gps = matches!(info.point_format, 1 | 3..=10);
    // Memory before reading: what the points become, what decoding holds besides (an f64
    // per extra-bytes value and GPS time, one batch of records) and the file itself.
    let batch = batch_points(record);
    let f64_columns = extras.len() + usize::from(has_gps);
    let extra_values = arbvis_core::budget::times(count, 8 * f64_columns as u64);
    let estimate = super::footprint(count, 4 + f64_columns, has_rgb, false)
        .saturating_add(extra_values)
        .saturating_add(bytes.len() as u64)
        .saturating_add(batch * record as u64);
    let over = |e: arbvis_core::budget::OverBudget| {
        PointsError::format(
            name,
            checked.count_at as u64,
            format!("the header declares {count} points: {e}"),
        )
    };
    arbvis_core::budget::check(
        format!("reading {count} points of {record} bytes"),
        estimate,
    )
    .map_err(over)?;
    let mut cols = Columns::new(count, extras.len(), has_rgb, has_gps).map_err(over)?;
    let mut reader = guarded(|| Reader::new(Cursor::new(bytes)))
        .map_err(|e| decode_error(format!("the header: {e}")))?;
    let mut pd: PointData = PointDataBuilder::new().for_header(reader.header()).build();
    let progress = Progress::new(count, &format!("reading {}", name.display()));
    let mut done = 0u64;
    while done < count {
        let want = batch.min(count - done);
        let n = guarded(|| reader.fill_points(want, &mut pd)).map_err(|e| {
            decode_error(format!(
                "decoding points {done}..{} of {count}: {e}",
                done + want
            ))
        })?;
        if n == 0 {
            return Err(decode_error(format!(
                "the point data ends after {done} of the {count} points the header declares"
            )));
        }
        cols.append(&pd, &extras, record).map_err(|_| {
            decode_error(format!(
                "points {done}..{}: more points than the {count} the header declares",
                done + n
            ))
        })?;
        done += n;
        progress.inc(n);
    }
    drop(progress);
    let cloud =
        cloud_of(cols, &extras, has_rgb, (None, None)).map_err(|e| decode_error(e.to_string()))?;
    Ok(LasCloud { cloud, info })
}

/// The cloud of the gathered columns: the LAS attributes, GPS time (where the format has
/// it: seconds after `gps_reference`, else after the earliest point's), then every
/// extra-bytes attribute.
fn cloud_of(
    cols: Columns,
    extras: &[Extra],
    has_rgb: bool,
    (gps_reference, frame): (Option<f64>, Option<&[[f64; 3]; 2]>),
) -> Result<PointCloud, PartsError> {
    let mut attributes = vec![
        ("intensity".to_string(), Values::Int(cols.intensity)),
        (
            "classification".to_string(),
            Values::Int(cols.classification),
        ),
        ("return_number".to_string(), Values::Int(cols.return_number)),
        (
            "number_of_returns".to_string(),
            Values::Int(cols.number_of_returns),
        ),
    ];
    if cols.has_gps {
        attributes.push((
            "gps_time".to_string(),
            gps_after(&cols.gps_time, gps_reference),
        ));
    }
    for (e, values) in extras.iter().zip(cols.extras) {
        let integral =
            e.ty <= 6 && e.ty != 5 && e.scale == 1.0 && e.offset == 0.0 && e.no_data.is_none();
        let mut label = e.name.clone();
        while attributes.iter().any(|(n, _)| *n == label) {
            label.push_str("_extra");
        }
        let values = if integral {
            Values::Int(values.iter().map(|&v| v as i32).collect())
        } else {
            Values::Float(values.iter().map(|&v| v as f32).collect())
        };
        attributes.push((label, values));
    }
    let parts = CloudParts {
        positions: cols.positions,
        attributes,
        rgb: has_rgb.then_some(cols.rgb),
        normals: None,
    };
    PointCloud::from_parts_framed(parts, frame)
}

/// The points of a COPC file's `nodes`, as one cloud (the LAS attributes, RGB and every
/// extra-bytes attribute its VLRs describe), held to the memory budget before a node is
/// decoded.
pub(super) fn copc_cloud(
    copc: &super::copc::Copc,
    nodes: &[super::copc::Node],
    stride: u64,
) -> Result<(PointCloud, usize), PointsError> {
    use super::copc_cache::FileId;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;
    let file = FileId::of(copc.path());
    let cached = AtomicUsize::new(0);
    let count: u64 = nodes.iter().map(|n| n.points).sum();
    let has_rgb = matches!(copc.format.0, 7 | 8);
    let extras = {
        let path = copc.path();
        let file = copc.file();
        let (head, checked, _) =
            stream::read_head(path, &mut crate::fetch::Cursor::new(file), file.len())?;
        let base = RECORD_LENGTH[copc.format.0 as usize] as usize;
        extra_bytes(path, &head, &checked.vlrs, base, copc.format.1 as usize)?
    };
    let over = |e: OverBudget| PointsError::format(copc.path(), 247, e.to_string());
    arbvis_core::budget::check(
        format!("{count} points of {}", copc.path().display()),
        super::footprint(count, 5 + extras.len(), has_rgb, false),
    )
    .map_err(over)?;
    // Formats 6-8 all carry GPS time.
    let mut cols = Columns::new(count, extras.len(), has_rgb, true).map_err(over)?;
    // Decoded in parallel a batch at a time (a batch's records held at once: at most
    // BATCH_BYTES beyond a node), appended in the nodes' order.
    let mut batches: Vec<&[super::copc::Node]> = Vec::new();
    let (mut start, mut bytes) = (0, 0u64);
    for (k, n) in nodes.iter().enumerate() {
        bytes += n.points * copc.format.1 as u64;
        if bytes > BATCH_BYTES {
            batches.push(&nodes[start..=k]);
            (start, bytes) = (k + 1, 0);
        }
    }
    batches.push(&nodes[start..]);
    for batch in batches {
        prefetch_missing(copc, &file, batch);
        // Nodes decoded for an earlier cut come from the cache.
        let decoded: Vec<Arc<PointData>> = batch
            .par_iter()
            .map(|node| {
                let (d, held) = decoded_node(copc, &file, node)?;
                cached.fetch_add(usize::from(held), Ordering::Relaxed);
                Ok(d)
            })
            .collect::<Result<_, PointsError>>()?;
        for (node, pd) in batch.iter().zip(&decoded) {
            append_node(&mut cols, copc, node, pd, &extras)?;
        }
    }
    if stride > 1 {
        cols.thin(stride as usize);
    }
    // GPS time after the file's earliest (its info VLR's) and positions framed by the
    // file's bounds: the same for every cut.
    let reference = Some(copc.info.gps_range[0]).filter(|t| t.is_finite());
    let frame = (reference, Some(&copc.bounds));
    let cloud = cloud_of(cols, &extras, has_rgb, frame).map_err(|e| PointsError::Decode {
        path: copc.path().to_path_buf(),
        message: e.to_string(),
    })?;
    Ok((cloud, cached.into_inner()))
}

/// Node `node` of `copc` (the file `file`) decoded, from the decoded-node cache where it
/// is held (then `true`), else read and kept there.
fn decoded_node(
    copc: &super::copc::Copc,
    file: &super::copc_cache::FileId,
    node: &super::copc::Node,
) -> Result<(std::sync::Arc<PointData>, bool), PointsError> {
    use super::copc_cache;
    if let Some(d) = copc_cache::get(file, node.key) {
        return Ok((d, true));
    }
    let d = std::sync::Arc::new(copc.read_node(node)?);
    copc_cache::put(file, node.key, d.clone());
    Ok((d, false))
}

/// Decode `nodes` of `copc` in parallel into the decoded-node cache (those it holds are
/// passed over).
pub(super) fn decode_nodes(
    copc: &super::copc::Copc,
    nodes: &[super::copc::Node],
) -> Result<(), PointsError> {
    let file = super::copc_cache::FileId::of(copc.path());
    prefetch_missing(copc, &file, nodes);
    nodes
        .par_iter()
        .try_for_each(|node| decoded_node(copc, &file, node).map(|_| ()))
}

/// Fetch ahead the chunks of `nodes` that the decoded-node cache does not hold (a
/// remote file's: all at once, rather than one request per decoding thread).
fn prefetch_missing(
    copc: &super::copc::Copc,
    file: &super::copc_cache::FileId,
    nodes: &[super::copc::Node],
) {
    let missing: Vec<_> = nodes
        .iter()
        .filter(|n| !super::copc_cache::holds(file, n.key))
        .copied()
        .collect();
    copc.prefetch(&missing);
}

/// Append one decoded node to the columns.
fn append_node(
    cols: &mut Columns,
    copc: &super::copc::Copc,
    node: &super::copc::Node,
    pd: &PointData,
    extras: &[Extra],
) -> Result<(), PointsError> {
    cols.append(pd, extras, copc.format.1 as usize)
        .map_err(|_| PointsError::Decode {
            path: copc.path().to_path_buf(),
            message: format!("node {:?}: more points than its entry declares", node.key),
        })
}

/// GPS times as seconds after `reference` (where it lies at most a day before the earliest
/// finite time: a header's 0 or wrong value is not taken; else after that earliest time),
/// in f32:
/// a survey's hours keep millisecond steps, where the absolute times (about 1e9 s of
/// adjusted standard GPS time) would keep only steps of 64 s.
fn gps_after(times: &[f64], reference: Option<f64>) -> Values {
    let earliest = times
        .iter()
        .copied()
        .filter(|t| t.is_finite())
        .fold(f64::INFINITY, f64::min);
    let earliest = if earliest.is_finite() { earliest } else { 0.0 };
    let reference = reference
        .filter(|r| *r <= earliest && earliest - *r <= 86_400.0)
        .unwrap_or(earliest);
    Values::Float(times.iter().map(|&t| (t - reference) as f32).collect())
}

/// Columns gathered batch by batch.
struct Columns {
    positions: Vec<[f64; 3]>,
    intensity: Vec<i32>,
    classification: Vec<i32>,
    return_number: Vec<i32>,
    number_of_returns: Vec<i32>,
    rgb: Vec<[u16; 3]>,
    has_rgb: bool,
    gps_time: Vec<f64>,
    has_gps: bool,
    extras: Vec<Vec<f64>>,
}

impl Columns {
    /// Columns with room for `count` points, reserved at once (the caller checked the
    /// estimate against the budget), so that appending never grows them.
    fn new(count: u64, extras: usize, has_rgb: bool, has_gps: bool) -> Result<Columns, OverBudget> {
        let n = usize::try_from(count).unwrap_or(usize::MAX);
        let ints = || vec_for::<i32>(n, "the integer attributes");
        Ok(Columns {
            positions: vec_for(n, "the positions")?,
            intensity: ints()?,
            classification: ints()?,
            return_number: ints()?,
            number_of_returns: ints()?,
            rgb: vec_for(if has_rgb { n } else { 0 }, "the colours")?,
            has_rgb,
            gps_time: vec_for(if has_gps { n } else { 0 }, "the GPS times")?,
            has_gps,
            extras: (0..extras)
                .map(|_| vec_for(n, "the extra-bytes attributes"))
                .collect::<Result<_, _>>()?,
        })
    }

    /// Keep every `stride`th point.
    fn thin(&mut self, stride: usize) {
        fn every<T: Copy>(v: &mut Vec<T>, stride: usize) {
            let kept: Vec<T> = v.iter().step_by(stride).copied().collect();
            *v = kept;
        }
        every(&mut self.positions, stride);
        every(&mut self.intensity, stride);
        every(&mut self.classification, stride);
        every(&mut self.return_number, stride);
        every(&mut self.number_of_returns, stride);
        every(&mut self.rgb, stride);
        every(&mut self.gps_time, stride);
        for e in &mut self.extras {
            every(e, stride);
        }
    }

    /// Append a batch; fails (without allocating) when the points would pass the
    /// reserved count.
    fn append(&mut self, pd: &PointData, extras: &[Extra], record: usize) -> Result<(), ()> {
        let n = pd.len();
        if self.positions.len() + n > self.positions.capacity() {
            return Err(());
        }
        self.positions
            .extend(pd.x().zip(pd.y()).zip(pd.z()).map(|((x, y), z)| [x, y, z]));
        self.intensity.extend(pd.intensity().map(i32::from));
        self.classification
            .extend(pd.classification().map(i32::from));
        self.return_number.extend(pd.return_number().map(i32::from));
        self.number_of_returns
            .extend(pd.number_of_returns().map(i32::from));
        if self.has_gps {
            if let Some(t) = pd.gps_time() {
                self.gps_time.extend(t);
            }
        }
        if self.has_rgb {
            if let Some(rgb) = pd.rgb() {
                self.rgb.extend(rgb.map(|(r, g, b)| [r, g, b]));
            }
        }
        for (e, column) in extras.iter().zip(&mut self.extras) {
            let size = extra_type_size(e.ty);
            column.extend(pd.raw_bytes().chunks_exact(record).map(|r| {
                let v = decode_extra(e.ty, &r[e.at..e.at + size]);
                if e.no_data == Some(v) {
                    f64::NAN
                } else {
                    v * e.scale + e.offset
                }
            }));
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests;
