//! The checks run on a LAS/LAZ file before the `las` crate reads it: `las` and `laz`
//! trust the header (buffers sized from the declared count and record length, EVLR
//! lengths, chunk tables and LAZ 1.4 layer sizes), so each of those is compared with the
//! bytes the file holds first. Offsets follow the LAS 1.4 R15 specification.

use std::io::Cursor;
use std::path::Path;

use super::header::{f64_at, text_at, u16_at, u32_at, u64_at, LasInfo, RawVlr, RECORD_LENGTH};
use super::laz_chunks::{Chunk, LazChunks};
use crate::points::{PointsError, MAX_POINTS};

/// Points a LAZ file may declare whatever its size (about half a second to decode).
pub(super) const LAZ_FREE_POINTS: u64 = 1_000_000;

/// Further points a LAZ file may declare per byte of compressed data (with
/// [`LAZ_FREE_POINTS`]: a file under 2 MB holds at most 3.1 million, read in about 1.5 s
/// of one core).
pub(super) const LAZ_POINTS_PER_BYTE: u64 = 1;

/// What reading a point costs against the LAZ bound, in thirds of a plain point: the
/// point itself, and one more third for each extra-bytes attribute (each is decoded,
/// kept as f64, converted and summarised: about a third of a point's time).
fn laz_cost(extras: usize) -> u64 {
    3 + extras as u64
}

/// The LAZ time bound: at most [`LAZ_FREE_POINTS`] plus [`LAZ_POINTS_PER_BYTE`] per byte
/// of compressed data, each extra-bytes attribute counting a third of a point. LAZ
/// decodes about 2.5 million points a second here and a stream of equal points (legal)
/// packs 85 into a byte, so without it a 2 MB file could take minutes; real lidar
/// compresses to less than a point a byte.
pub(super) fn laz_bound(
    name: &Path,
    b: &[u8],
    info: &LasInfo,
    count_at: usize,
    extras: usize,
) -> Result<(), PointsError> {
    if !info.compressed {
        return Ok(());
    }
    let data = b.len().saturating_sub(u32_at(b, 96) as usize) as u64;
    let allowed = LAZ_FREE_POINTS.saturating_add(LAZ_POINTS_PER_BYTE.saturating_mul(data));
    let cost = laz_cost(extras);
    if info.points.saturating_mul(cost) <= allowed.saturating_mul(3) {
        return Ok(());
    }
    Err(PointsError::format(
        name,
        count_at as u64,
        format!(
            "the header declares {} points{} in {data} bytes of LAZ data: this reader decodes \
             at most {LAZ_FREE_POINTS} points plus {LAZ_POINTS_PER_BYTE} a compressed byte \
             ({allowed} here{}), so that a file is read or refused in seconds (real lidar \
             compresses to less than a point a byte)",
            info.points,
            if extras > 0 {
                format!(" with {extras} extra-bytes attributes")
            } else {
                String::new()
            },
            if extras > 0 {
                format!(
                    ", {} with {extras} attributes, each a third of a point",
                    allowed.saturating_mul(3) / cost
                )
            } else {
                String::new()
            }
        ),
    ))
}

/// What the checks found in the header.
pub(super) struct Checked {
    pub(super) info: LasInfo,
    pub(super) vlrs: Vec<RawVlr>,
    /// Byte offset of the point count in force (107, or 247 for LAS 1.4's 64-bit one).
    pub(super) count_at: usize,
    /// A chunked LAZ file's chunks (none for LAS, point-wise LAZ or LAZ without a table).
    pub(super) laz: Option<LazChunks>,
}

/// Check the header, VLRs and sizes before the `las` crate reads anything.
pub(super) fn check(name: &Path, b: &[u8]) -> Result<Checked, PointsError> {
    check_up_to(name, b, MAX_POINTS)
}

/// [`check`] with a limit of `max_points` points.
pub(super) fn check_up_to(name: &Path, b: &[u8], max_points: u64) -> Result<Checked, PointsError> {
    let (checked, offset_to_points) = check_head(name, b, b.len())?;
    let Checked {
        info,
        mut vlrs,
        count_at,
        ..
    } = checked;
    let fail = |at: usize, m: String| PointsError::format(name, at as u64, m);
    if info.points > max_points {
        return Err(fail(
            count_at,
            format!(
                "the header declares {} points, more than the {max_points} this reader loads",
                info.points
            ),
        ));
    }
    evlrs(name, b, info.version, offset_to_points, &mut vlrs)?;
    let laz = if info.compressed {
        check_laz(name, b, &info, offset_to_points, &vlrs)?
    } else {
        check_count(name, &info, offset_to_points, b.len())?;
        None
    };
    Ok(Checked {
        info,
        vlrs,
        count_at,
        laz,
    })
}

/// An uncompressed file of `len` bytes must hold the records its header declares.
pub(super) fn check_count(
    name: &Path,
    info: &LasInfo,
    offset_to_points: usize,
    len: usize,
) -> Result<(), PointsError> {
    let (points, record_length) = (info.points, info.record_length);
    let need = points.checked_mul(record_length as u64);
    let have = (len - offset_to_points) as u64;
    if need.is_none_or(|n| n > have) {
        return Err(PointsError::format(
            name,
            offset_to_points as u64,
            format!(
                "the header declares {points} points of {record_length} bytes, but the {have} bytes after the point offset hold only {}",
                have / record_length as u64
            ),
        ));
    }
    Ok(())
}

/// Check the header and the VLRs of a file of `len` bytes whose first bytes are `b`
/// (the whole file, or at least up to the point data); returns them and the offset of
/// the point data.
pub(super) fn check_head(
    name: &Path,
    b: &[u8],
    len: usize,
) -> Result<(Checked, usize), PointsError> {
    let fail = |at: usize, m: String| PointsError::format(name, at as u64, m);
    if b.len() < 227 {
        return Err(fail(
            len,
            format!("the file ends inside the LAS header (227 bytes needed, {len} present)"),
        ));
    }
    if &b[0..4] != b"LASF" {
        return Err(fail(
            0,
            format!(
                "not a LAS file: expected the signature \"LASF\", found {:?}",
                String::from_utf8_lossy(&b[0..4])
            ),
        ));
    }
    let version = (b[24], b[25]);
    if version.0 != 1 || version.1 > 4 {
        return Err(fail(
            24,
            format!(
                "LAS version {}.{}: 1.0 to 1.4 are read",
                version.0, version.1
            ),
        ));
    }
    let minimum_header = match version.1 {
        0..=2 => 227,
        3 => 235,
        _ => 375,
    };
    let header_size = u16_at(b, 94) as usize;
    if header_size < minimum_header || header_size > len {
        return Err(fail(
            94,
            format!(
                "header size {header_size}: LAS {}.{} needs at least {minimum_header} and the file has {len} bytes",
                version.0, version.1
            ),
        ));
    }
    let offset_to_points = u32_at(b, 96) as usize;
    if offset_to_points < header_size || offset_to_points > len {
        return Err(fail(
            96,
            format!(
                "offset to point data {offset_to_points} lies outside {header_size}..{len} (after the header, inside the file)"
            ),
        ));
    }
    if offset_to_points > b.len() {
        return Err(fail(
            96,
            format!(
                "offset to point data {offset_to_points}: the header and VLRs may take at most {} bytes here",
                b.len()
            ),
        ));
    }
    let format_byte = b[104];
    let compressed = format_byte & 0x80 != 0;
    let point_format = format_byte & 0x3f;
    if point_format > 10 || (!compressed && format_byte > 10) {
        return Err(fail(
            104,
            format!(
                "point data format {format_byte} ({point_format}{}): formats 0 to 10 are read, \
                 +128 when compressed",
                if compressed { ", compressed" } else { "" }
            ),
        ));
    }
    // Formats 6-10 came with LAS 1.4 (R15, 2.4): an older header cannot hold them (its
    // point count is 32-bit, its readers decode formats 0-5).
    if point_format >= 6 && version.1 < 4 {
        return Err(fail(
            104,
            format!(
                "point data format {point_format} in a LAS {}.{} file: formats 6 to 10 need LAS 1.4",
                version.0, version.1
            ),
        ));
    }
    let record_length = u16_at(b, 105);
    let minimum_record = RECORD_LENGTH[point_format as usize];
    if record_length < minimum_record {
        return Err(fail(
            105,
            format!(
                "point record length {record_length} is less than the {minimum_record} bytes of point format {point_format}"
            ),
        ));
    }
    // LAS 1.4 counts in 64 bits at byte 247; the legacy 32-bit count at 107 is 0 or, for
    // formats 0-5 that fit, the same number. One that disagrees is refused rather than
    // trusted (taking it would drop points silently).
    let legacy_count = u32_at(b, 107) as u64;
    let (points, count_at) = if version.1 >= 4 {
        let count = u64_at(b, 247);
        if legacy_count != 0 && legacy_count != count {
            return Err(fail(
                107,
                format!(
                    "the legacy point count {legacy_count} disagrees with LAS 1.4's 64-bit count {count} at byte 247"
                ),
            ));
        }
        (count, 247)
    } else {
        (legacy_count, 107)
    };
    let read3 = |at: usize| -> [f64; 3] { std::array::from_fn(|a| f64_at(b, at + 8 * a)) };
    let scale = read3(131);
    let offset = read3(155);
    let bounds = [
        [f64_at(b, 187), f64_at(b, 203), f64_at(b, 219)],
        [f64_at(b, 179), f64_at(b, 195), f64_at(b, 211)],
    ];
    if scale.iter().chain(&offset).any(|v| !v.is_finite()) {
        return Err(fail(
            131,
            format!("scale {scale:?} and offset {offset:?} must be finite"),
        ));
    }
    // A stored coordinate is an i32 times the scale plus the offset: every one must be a
    // finite f64, or positions would become infinite.
    if let Some(a) =
        (0..3).find(|&a| !(scale[a].abs() * 2f64.powi(31) + offset[a].abs()).is_finite())
    {
        return Err(fail(
            131 + 8 * a,
            format!(
                "{} scale {:e} and offset {:e}: an i32 coordinate times the scale plus the \
                 offset overflows f64 (|scale| * 2^31 + |offset| must be below 1.8e308)",
                ["x", "y", "z"][a],
                scale[a],
                offset[a]
            ),
        ));
    }
    // VLRs: each inside the file, before the point data.
    let mut vlrs = Vec::new();
    let mut at = header_size;
    for i in 0..u32_at(b, 100) {
        if at + 54 > offset_to_points {
            return Err(fail(
                at,
                format!("VLR {i} (of {}) starts where its 54-byte header would pass the point data at byte {offset_to_points}", u32_at(b, 100)),
            ));
        }
        let data = at + 54..at + 54 + u16_at(b, at + 20) as usize;
        if data.end > offset_to_points {
            return Err(fail(
                at,
                format!(
                    "VLR {i} holds {} bytes and would pass the point data at byte {offset_to_points}",
                    data.len()
                ),
            ));
        }
        vlrs.push(RawVlr {
            user_id: text_at(b, at + 2..at + 18),
            record_id: u16_at(b, at + 18),
            at,
            data: data.clone(),
        });
        at = data.end;
    }
    let info = LasInfo {
        version,
        point_format,
        compressed,
        record_length,
        points,
        scale,
        offset,
        header_bounds: bounds,
        extra_bytes: Vec::new(),
    };
    Ok((
        Checked {
            info,
            vlrs,
            count_at,
            laz: None,
        },
        offset_to_points,
    ))
}

/// Every EVLR (LAS 1.4): each inside the file, one after another from the header's
/// start offset. `las` reads only the first; the Extra Bytes descriptors may be in any.
fn evlrs(
    name: &Path,
    b: &[u8],
    version: (u8, u8),
    offset_to_points: usize,
    vlrs: &mut Vec<RawVlr>,
) -> Result<(), PointsError> {
    if version.1 < 4 {
        return Ok(());
    }
    let count = u32_at(b, 243);
    if count == 0 || u64_at(b, 235) == 0 {
        return Ok(());
    }
    let len = b.len();
    let fail = |at: usize, m: String| PointsError::format(name, at as u64, m);
    let start = u64_at(b, 235);
    let mut at = usize::try_from(start)
        .ok()
        .filter(|&s| s >= offset_to_points && s <= len)
        .ok_or_else(|| {
            fail(
                235,
                format!("the first EVLR at byte {start} lies outside the data ({offset_to_points}..{len})"),
            )
        })?;
    for i in 0..count {
        // Each EVLR takes at least its 60-byte header, so this loop ends within the file.
        if len - at < 60 {
            return Err(fail(
                at,
                format!(
                    "EVLR {i} (of {count}) would start here, but {} bytes remain and its header takes 60",
                    len - at
                ),
            ));
        }
        let size = u64_at(b, at + 20);
        if size > (len - at - 60) as u64 {
            return Err(fail(
                at,
                format!(
                    "EVLR {i} (of {count}) declares {size} bytes, but {} remain",
                    len - at - 60
                ),
            ));
        }
        let data = at + 60..at + 60 + size as usize;
        vlrs.push(RawVlr {
            user_id: text_at(b, at + 2..at + 18),
            record_id: u16_at(b, at + 18),
            at,
            data: data.clone(),
        });
        at = data.end;
    }
    Ok(())
}

/// LAZ: laszip VLR items against the record, chunk table against the data, and LAZ 1.4
/// layer sizes against the file; the chunks that hold the header's points, where the
/// file is chunked and has a table (each decodable alone, [`super::laz_chunks`]).
fn check_laz(
    name: &Path,
    b: &[u8],
    info: &LasInfo,
    data_start: usize,
    vlrs: &[RawVlr],
) -> Result<Option<LazChunks>, PointsError> {
    let fail = |at: usize, m: String| PointsError::format(name, at as u64, m);
    let Some(vlr) = vlrs
        .iter()
        .find(|v| v.user_id == "laszip encoded" && v.record_id == 22204)
    else {
        return Err(fail(
            104,
            "a compressed point format without the laszip VLR (\"laszip encoded\", 22204)".into(),
        ));
    };
    let data = &b[vlr.data.clone()];
    if data.len() < 34 {
        return Err(fail(
            vlr.at,
            format!(
                "the laszip VLR holds {} bytes, at least 34 needed",
                data.len()
            ),
        ));
    }
    let compressor = u16_at(data, 0);
    let chunk_size = u32_at(data, 12);
    let items = u16_at(data, 32) as usize;
    if data.len() < 34 + 6 * items || items == 0 {
        return Err(fail(
            vlr.at,
            format!(
                "the laszip VLR lists {items} items in {} bytes ({} needed, at least one item)",
                data.len(),
                34 + 6 * items
            ),
        ));
    }
    let mut total = 0u64;
    let mut layers = 0u64;
    for k in 0..items {
        let (ty, size) = (u16_at(data, 34 + 6 * k), u16_at(data, 36 + 6 * k));
        // (natural size, layers in LAZ 1.4 chunks); Byte items are any size.
        let (natural, item_layers) = match ty {
            0 => (size, 0),
            6 => (20, 0),
            7 => (8, 0),
            8 => (6, 0),
            9 => (29, 0),
            10 => (30, 9),
            11 => (6, 1),
            12 => (8, 2),
            13 => (29, 1),
            14 => (size, size as u64),
            _ => {
                return Err(fail(
                    vlr.data.start + 34 + 6 * k,
                    format!("LAZ item {k}: type {ty} is not a laszip item (0, 6 to 14)"),
                ))
            }
        };
        if size != natural {
            return Err(fail(
                vlr.at,
                format!("LAZ item {k} (type {ty}) declares {size} bytes, the type has {natural}"),
            ));
        }
        total += size as u64;
        layers += item_layers;
    }
    if total != info.record_length as u64 {
        return Err(fail(
            vlr.at,
            format!(
                "the LAZ items hold {total} bytes, the point records {}",
                info.record_length
            ),
        ));
    }
    let laz_vlr =
        laz::LazVlr::read_from(data).map_err(|e| fail(vlr.at, format!("the laszip VLR: {e}")))?;
    // The chunk table, located as laz does: offset at the start of the data, else in
    // the last 8 bytes of the file.
    if compressor == 1 {
        return Ok(None); // point-wise: one stream, no table; points are read in batches
    }
    if data_start + 8 > b.len() {
        return Err(fail(
            data_start,
            "the file ends before the LAZ chunk table offset".into(),
        ));
    }
    let mut table = u64_at(b, data_start) as i64;
    if table <= data_start as i64 {
        table = u64_at(b, b.len() - 8) as i64;
    }
    if table <= data_start as i64 {
        if compressor == 3 || layers > 0 {
            return Err(fail(
                data_start,
                "a LAZ 1.4 (layered) file without a chunk table: neither the offset here nor \
                 the one in the file's last 8 bytes points after the point data"
                    .into(),
            ));
        }
        return Ok(None);
    }
    let table = table as u64;
    if table.checked_add(8).is_none_or(|e| e > b.len() as u64) {
        return Err(fail(
            data_start,
            format!("the LAZ chunk table offset {table} lies past the end of the file"),
        ));
    }
    let table = table as usize;
    let chunks = u32_at(b, table + 4) as u64;
    // Each chunk takes at least a byte of the data between its start and the table,
    // but the last may be empty (writers close an empty file with one empty chunk).
    let room = table.saturating_sub(data_start + 8) as u64;
    if chunks > room + 1 {
        return Err(fail(
            table,
            format!("the LAZ chunk table lists {chunks} chunks in {room} bytes of data"),
        ));
    }
    let mut cursor = Cursor::new(b);
    cursor.set_position(data_start as u64);
    let entries = laz::laszip::ChunkTable::read_from(&mut cursor, &laz_vlr)
        .map_err(|e| fail(table, format!("the LAZ chunk table: {e}")))?;
    let entries = entries.as_ref();
    let variable = chunk_size == 0 || chunk_size == u32::MAX;
    let capacity: u64 = if variable {
        entries
            .iter()
            .fold(0u64, |a, e| a.saturating_add(e.point_count))
    } else {
        (entries.len() as u64).saturating_mul(chunk_size as u64)
    };
    if info.points > capacity {
        return Err(fail(
            table,
            format!(
                "the header declares {} points, but the LAZ chunk table holds at most {capacity}",
                info.points
            ),
        ));
    }
    // Layered chunks are decoded by the items' types (10 to 14), whatever the VLR's
    // compressor field says, so their layer sizes are checked by the types too (a file
    // that said compressor 2 over point-14 items once made laz allocate 600 MB).
    if compressor == 3 || layers > 0 {
        // Each chunk: first point raw, a u32 count, the layer sizes, the layers.
        let mut start = data_start as u64 + 8;
        // Only the chunks the declared points reach are decoded.
        let mut covered = 0u64;
        for (k, e) in entries.iter().enumerate() {
            if covered >= info.points {
                break;
            }
            covered = covered.saturating_add(if variable {
                e.point_count
            } else {
                chunk_size as u64
            });
            let sizes_at = start.saturating_add(total + 4);
            let sizes_end = sizes_at.saturating_add(4 * layers);
            if sizes_end > b.len() as u64 {
                return Err(fail(
                    start as usize,
                    format!("LAZ chunk {k} starts too close to the end of the file"),
                ));
            }
            let sum: u64 = (0..layers as usize)
                .map(|l| u32_at(b, sizes_at as usize + 4 * l) as u64)
                .sum();
            if sum > b.len() as u64 - sizes_end {
                return Err(fail(
                    sizes_at as usize,
                    format!(
                        "LAZ chunk {k} declares layers of {sum} bytes, past the end of the file"
                    ),
                ));
            }
            start = start.saturating_add(e.byte_count);
        }
    }
    // The chunks the declared points reach, each inside the data before the table.
    let mut chunks = Vec::new();
    let (mut start, mut left) = (data_start as u64 + 8, info.points);
    for (k, e) in entries.iter().enumerate() {
        if left == 0 {
            break;
        }
        let end = start.saturating_add(e.byte_count);
        if end > table as u64 {
            return Err(fail(
                start as usize,
                format!(
                    "LAZ chunk {k} ({} bytes from byte {start}) runs past the chunk table at {table}",
                    e.byte_count
                ),
            ));
        }
        let points = if variable {
            e.point_count
        } else {
            chunk_size as u64
        }
        .min(left);
        chunks.push(Chunk {
            start: start as usize,
            end: end as usize,
            points,
        });
        left -= points;
        start = end;
    }
    Ok(Some(LazChunks {
        vlr: laz_vlr,
        chunks,
    }))
}
