//! The checks run on a LAS/LAZ file before the `las` crate reads it: `las` and `laz`
//! trust the header (buffers sized from the declared count and record length, EVLR
//! lengths, chunk tables and LAZ 1.4 layer sizes), so each of those is compared with the
//! bytes the file holds first. Offsets follow the LAS 1.4 R15 specification.

use std::path::Path;

use super::check_laz::check_laz;
use super::header::{LasInfo, RECORD_LENGTH};
use super::layout::{from_bytes, RawHeader, Vlr as RawVlr, Walk, WalkError};
use super::laz_chunks::LazChunks;
use crate::le::u32_at;
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
    let h = signature(b, len).map_err(|(at, m)| fail(at, m))?;
    let offset_to_points = data_offset(&h, b.len(), len).map_err(|(at, m)| fail(at, m))?;
    let (point_format, record_length) = point_format(&h).map_err(|(at, m)| fail(at, m))?;
    let (points, count_at) = point_count(&h).map_err(|(at, m)| fail(at, m))?;
    check_scale(&h).map_err(|(at, m)| fail(at, m))?;
    let vlrs = walk_vlrs(b, &h, offset_to_points).map_err(|(at, m)| fail(at, m))?;
    let info = LasInfo {
        version: h.version,
        point_format,
        compressed: h.compressed(),
        record_length,
        points,
        scale: h.scale,
        offset: h.offset,
        header_bounds: h.bounds,
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

/// A refusal: the byte it names and the message.
type Refusal = (usize, String);

/// The header of a file of `len` bytes, read once its size, signature and version pass.
fn signature(b: &[u8], len: usize) -> Result<RawHeader, Refusal> {
    let Some(h) = RawHeader::parse(b) else {
        return Err((
            len,
            format!("the file ends inside the LAS header (227 bytes needed, {len} present)"),
        ));
    };
    if &b[0..4] != b"LASF" {
        return Err((
            0,
            format!(
                "not a LAS file: expected the signature \"LASF\", found {:?}",
                String::from_utf8_lossy(&b[0..4])
            ),
        ));
    }
    let version = h.version;
    if version.0 != 1 || version.1 > 4 {
        return Err((
            24,
            format!(
                "LAS version {}.{}: 1.0 to 1.4 are read",
                version.0, version.1
            ),
        ));
    }
    Ok(h)
}

/// The offset of the point data: after a header of the version's size, inside the file
/// of `len` bytes and inside the `held` bytes read.
fn data_offset(h: &RawHeader, held: usize, len: usize) -> Result<usize, Refusal> {
    let version = h.version;
    let minimum_header = match version.1 {
        0..=2 => 227,
        3 => 235,
        _ => 375,
    };
    let header_size = h.header_size as usize;
    if header_size < minimum_header || header_size > len {
        return Err((
            94,
            format!(
                "header size {header_size}: LAS {}.{} needs at least {minimum_header} and the file has {len} bytes",
                version.0, version.1
            ),
        ));
    }
    let offset_to_points = h.point_offset as usize;
    if offset_to_points < header_size || offset_to_points > len {
        return Err((
            96,
            format!(
                "offset to point data {offset_to_points} lies outside {header_size}..{len} (after the header, inside the file)"
            ),
        ));
    }
    if offset_to_points > held {
        return Err((
            96,
            format!(
                "offset to point data {offset_to_points}: the header and VLRs may take at most {held} bytes here"
            ),
        ));
    }
    Ok(offset_to_points)
}

/// The point format (0-10, formats 6-10 only in LAS 1.4) and a record length that
/// holds it.
fn point_format(h: &RawHeader) -> Result<(u8, u16), Refusal> {
    let (format_byte, version) = (h.format_byte, h.version);
    let compressed = h.compressed();
    let point_format = h.point_format();
    if point_format > 10 || (!compressed && format_byte > 10) {
        return Err((
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
        return Err((
            104,
            format!(
                "point data format {point_format} in a LAS {}.{} file: formats 6 to 10 need LAS 1.4",
                version.0, version.1
            ),
        ));
    }
    let record_length = h.record_length;
    let minimum_record = RECORD_LENGTH[point_format as usize];
    if record_length < minimum_record {
        return Err((
            105,
            format!(
                "point record length {record_length} is less than the {minimum_record} bytes of point format {point_format}"
            ),
        ));
    }
    Ok((point_format, record_length))
}

/// The point count in force and its offset. LAS 1.4 counts in 64 bits at byte 247; the
/// legacy 32-bit count at 107 is 0 or, for formats 0-5 that fit, the same number. One
/// that disagrees is refused rather than trusted (taking it would drop points silently).
fn point_count(h: &RawHeader) -> Result<(u64, usize), Refusal> {
    let legacy_count = h.legacy_count as u64;
    if h.version.1 < 4 {
        return Ok((legacy_count, 107));
    }
    let count = h.count_64;
    if legacy_count != 0 && legacy_count != count {
        return Err((
            107,
            format!(
                "the legacy point count {legacy_count} disagrees with LAS 1.4's 64-bit count {count} at byte 247"
            ),
        ));
    }
    Ok((count, 247))
}

/// Scales and offsets finite, and every stored coordinate (an i32 times the scale plus
/// the offset) a finite f64, or positions would become infinite.
fn check_scale(h: &RawHeader) -> Result<(), Refusal> {
    let (scale, offset) = (h.scale, h.offset);
    if scale.iter().chain(&offset).any(|v| !v.is_finite()) {
        return Err((
            131,
            format!("scale {scale:?} and offset {offset:?} must be finite"),
        ));
    }
    if let Some(a) =
        (0..3).find(|&a| !(scale[a].abs() * 2f64.powi(31) + offset[a].abs()).is_finite())
    {
        return Err((
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
    Ok(())
}

/// The VLRs: each inside the file, before the point data.
fn walk_vlrs(b: &[u8], h: &RawHeader, offset_to_points: usize) -> Result<Vec<RawVlr>, Refusal> {
    let count = h.vlr_count;
    let mut walk = Walk::vlrs(h.header_size as u64, count, offset_to_points as u64);
    let mut read = from_bytes(b);
    let mut vlrs = Vec::new();
    while let Some(next) = walk.next(&mut read) {
        match next {
            Ok(vlr) => vlrs.push(vlr),
            Err(WalkError::Header { index, at }) => {
                return Err((
                    at as usize,
                    format!("VLR {index} (of {count}) starts where its 54-byte header would pass the point data at byte {offset_to_points}"),
                ))
            }
            Err(WalkError::Data { index, vlr, size }) => {
                return Err((
                    vlr.at,
                    format!(
                        "VLR {index} holds {size} bytes and would pass the point data at byte {offset_to_points}"
                    ),
                ))
            }
            Err(WalkError::Io(e)) => return Err((walk.at() as usize, e.to_string())),
        }
    }
    Ok(vlrs)
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
    let Some(h) = RawHeader::parse(b).filter(|_| version.1 >= 4) else {
        return Ok(());
    };
    let (count, start) = (h.evlr_count, h.evlr_start);
    if count == 0 || start == 0 {
        return Ok(());
    }
    let len = b.len();
    let fail = |at: usize, m: String| PointsError::format(name, at as u64, m);
    let at = usize::try_from(start)
        .ok()
        .filter(|&s| s >= offset_to_points && s <= len)
        .ok_or_else(|| {
            fail(
                235,
                format!("the first EVLR at byte {start} lies outside the data ({offset_to_points}..{len})"),
            )
        })?;
    // Each EVLR takes at least its 60-byte header, so this walk ends within the file.
    let mut walk = Walk::evlrs(at as u64, count, len as u64);
    let mut read = from_bytes(b);
    while let Some(next) = walk.next(&mut read) {
        match next {
            Ok(vlr) => vlrs.push(vlr),
            Err(WalkError::Header { index, at }) => {
                return Err(fail(
                    at as usize,
                    format!(
                        "EVLR {index} (of {count}) would start here, but {} bytes remain and its header takes 60",
                        len - at as usize
                    ),
                ))
            }
            Err(WalkError::Data { index, vlr, size }) => {
                return Err(fail(
                    vlr.at,
                    format!(
                        "EVLR {index} (of {count}) declares {size} bytes, but {} remain",
                        len - vlr.at - 60
                    ),
                ))
            }
            Err(WalkError::Io(e)) => return Err(fail(walk.at() as usize, e.to_string())),
        }
    }
    Ok(())
}
