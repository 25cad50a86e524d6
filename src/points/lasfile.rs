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
//! and, in LAZ 1.4, each layer from its declared size), so this module checks the
//! header itself before calling them: version and format known, header, VLRs and the
//! first EVLR inside the file, `count × record length` within the bytes after the
//! point offset for LAS, at most [`MAX_POINTS`] points; for LAZ the laszip VLR's items
//! must match the record length, the chunk table must be smaller than the compressed
//! data and hold at least the declared points, and every LAZ 1.4 chunk's layer sizes
//! must fit in the file. Points are then decoded in batches of 65,536, so memory grows
//! only with points actually decoded, and a decoder error names the batch.

use std::io::Cursor;
use std::path::Path;

use las::{PointData, PointDataBuilder, Reader};

use super::progress::Progress;
use super::{read_file, CloudParts, PointCloud, PointsError, Values, MAX_POINTS};

/// Header facts of a LAS/LAZ file.
#[derive(Debug, Clone, PartialEq)]
pub struct LasInfo {
    /// Version, major and minor.
    pub version: (u8, u8),
    /// Point data record format (0-10), without the compression bit.
    pub point_format: u8,
    /// True for LAZ.
    pub compressed: bool,
    /// Bytes per point record (uncompressed).
    pub record_length: u16,
    /// Points declared by the header.
    pub points: u64,
    /// Scale factors of x, y, z.
    pub scale: [f64; 3],
    /// Offsets of x, y, z.
    pub offset: [f64; 3],
    /// Bounds written in the header (min, max).
    pub header_bounds: [[f64; 3]; 2],
    /// Names of the extra-bytes attributes read.
    pub extra_bytes: Vec<String>,
}

impl LasInfo {
    /// The format lines of `arbvis inspect`.
    pub fn describe(&self) -> String {
        let [lo, hi] = self.header_bounds;
        format!(
            "format: LAS {}.{}, point format {}, {}, {}-byte records\nheader: {} points, scale {} {} {}, offset {} {} {}, bounds x {} .. {}, y {} .. {}, z {} .. {}\nextra bytes: {}\n",
            self.version.0,
            self.version.1,
            self.point_format,
            if self.compressed { "compressed (LAZ)" } else { "uncompressed" },
            self.record_length,
            self.points,
            self.scale[0],
            self.scale[1],
            self.scale[2],
            self.offset[0],
            self.offset[1],
            self.offset[2],
            lo[0],
            hi[0],
            lo[1],
            hi[1],
            lo[2],
            hi[2],
            if self.extra_bytes.is_empty() {
                "none".to_string()
            } else {
                self.extra_bytes.join(", ")
            }
        )
    }
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

/// Bytes of a point record of each format, without extra bytes.
const RECORD_LENGTH: [u16; 11] = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67];

/// Points decoded per batch.
const BATCH: u64 = 65_536;

/// A variable length record: where its data is in the file.
struct RawVlr {
    user_id: String,
    record_id: u16,
    /// Byte offset of the record's header.
    at: usize,
    data: std::ops::Range<usize>,
}

/// What the checks found in the header.
struct Checked {
    info: LasInfo,
    vlrs: Vec<RawVlr>,
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}
fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}
fn text_at(b: &[u8], range: std::ops::Range<usize>) -> String {
    let s = &b[range];
    let end = s.iter().position(|&c| c == 0).unwrap_or(s.len());
    String::from_utf8_lossy(&s[..end]).trim().to_string()
}

/// Check the header, VLRs and sizes before the `las` crate reads anything.
fn check(name: &Path, b: &[u8]) -> Result<Checked, PointsError> {
    let len = b.len();
    let fail = |at: usize, m: String| PointsError::format(name, at as u64, m);
    if len < 227 {
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
        return Err(PointsError::unsupported(
            name,
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
    let format_byte = b[104];
    let compressed = format_byte & 0x80 != 0;
    let point_format = format_byte & 0x3f;
    if point_format > 10 {
        return Err(PointsError::unsupported(
            name,
            format!("point data format {format_byte}: formats 0 to 10 are read"),
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
    let legacy_count = u32_at(b, 107) as u64;
    let points = if legacy_count == 0 && version.1 >= 4 {
        u64_at(b, 247)
    } else {
        legacy_count
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
    if points > MAX_POINTS {
        return Err(PointsError::unsupported(
            name,
            format!(
                "the header declares {points} points, more than the {MAX_POINTS} this reader loads"
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
    // The first EVLR (LAS 1.4), the only one `las` reads.
    if version.1 >= 4 && u32_at(b, 243) > 0 && u64_at(b, 235) > 0 {
        let start = u64_at(b, 235);
        let fits = usize::try_from(start)
            .ok()
            .filter(|&s| s >= offset_to_points && s.checked_add(60).is_some_and(|e| e <= len));
        let Some(start) = fits else {
            return Err(fail(
                235,
                format!("the first EVLR at byte {start} lies outside the data ({offset_to_points}..{len})"),
            ));
        };
        let size = u64_at(b, start + 20);
        if size > (len - start - 60) as u64 {
            return Err(fail(
                start,
                format!(
                    "the EVLR declares {size} bytes, but {} remain",
                    len - start - 60
                ),
            ));
        }
        vlrs.push(RawVlr {
            user_id: text_at(b, start + 2..start + 18),
            record_id: u16_at(b, start + 18),
            at: start,
            data: start + 60..start + 60 + size as usize,
        });
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
    if compressed {
        check_laz(name, b, &info, offset_to_points, &vlrs)?;
    } else {
        let need = points.checked_mul(record_length as u64);
        let have = (len - offset_to_points) as u64;
        if need.is_none_or(|n| n > have) {
            return Err(fail(
                offset_to_points,
                format!(
                    "the header declares {points} points of {record_length} bytes, but the {have} bytes after the point offset hold only {}",
                    have / record_length as u64
                ),
            ));
        }
    }
    Ok(Checked { info, vlrs })
}

/// LAZ: laszip VLR items against the record, chunk table against the data, and LAZ 1.4
/// layer sizes against the file.
fn check_laz(
    name: &Path,
    b: &[u8],
    info: &LasInfo,
    data_start: usize,
    vlrs: &[RawVlr],
) -> Result<(), PointsError> {
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
                return Err(PointsError::unsupported(
                    name,
                    format!("LAZ item type {ty}: not a laszip item"),
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
        return Ok(()); // point-wise: one stream, no table; points are read in batches
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
        if compressor == 3 {
            return Err(PointsError::unsupported(
                name,
                "a LAZ 1.4 (layered) file without a chunk table",
            ));
        }
        return Ok(());
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
    // Each chunk takes at least a byte of the data between its start and the table.
    let room = table.saturating_sub(data_start + 8) as u64;
    if chunks > room {
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
    if compressor == 3 {
        // Each chunk: first point raw, a u32 count, the layer sizes, the layers.
        let mut start = data_start as u64 + 8;
        for (k, e) in entries.iter().enumerate() {
            let sizes_at = start + total + 4;
            let sizes_end = sizes_at + 4 * layers;
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
            if start >= table as u64 {
                break;
            }
        }
    }
    Ok(())
}

/// One extra-bytes attribute: where it is in the record and how to decode it.
struct Extra {
    name: String,
    /// Byte offset within the record.
    at: usize,
    /// Data type 1..10 of the LAS 1.4 table.
    ty: u8,
    no_data: Option<f64>,
    scale: f64,
    offset: f64,
}

fn extra_type_size(ty: u8) -> usize {
    match ty {
        1 | 2 => 1,
        3 | 4 => 2,
        5 | 6 | 9 => 4,
        _ => 8,
    }
}

fn decode_extra(ty: u8, b: &[u8]) -> f64 {
    let mut a = [0u8; 8];
    a[..b.len()].copy_from_slice(b);
    let raw = u64::from_le_bytes(a);
    match ty {
        1 => b[0] as f64,
        2 => b[0] as i8 as f64,
        3 => raw as u16 as f64,
        4 => raw as u16 as i16 as f64,
        5 => raw as u32 as f64,
        6 => raw as u32 as i32 as f64,
        7 => raw as f64,
        8 => raw as i64 as f64,
        9 => f32::from_bits(raw as u32) as f64,
        _ => f64::from_bits(raw),
    }
}

/// The extra-bytes descriptors of the Extra Bytes VLR, laid out after `base` bytes.
fn extra_bytes(
    name: &Path,
    b: &[u8],
    vlrs: &[RawVlr],
    base: usize,
    record: usize,
) -> Result<Vec<Extra>, PointsError> {
    let Some(vlr) = vlrs
        .iter()
        .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
    else {
        return Ok(Vec::new());
    };
    let data = &b[vlr.data.clone()];
    if !data.len().is_multiple_of(192) {
        return Err(PointsError::format(
            name,
            vlr.at as u64,
            format!(
                "the Extra Bytes VLR holds {} bytes, not a multiple of its 192-byte descriptors",
                data.len()
            ),
        ));
    }
    let mut extras = Vec::new();
    let mut at = base;
    for (k, d) in data.chunks_exact(192).enumerate() {
        let (ty, options) = (d[2], d[3]);
        let label = text_at(d, 4..36);
        let label = if label.is_empty() {
            format!("extra{k}")
        } else {
            label
        };
        let (scalar, parts) = match ty {
            0 => {
                at += options as usize; // undocumented bytes: skipped
                continue;
            }
            1..=10 => (ty, 1),
            11..=20 => (ty - 10, 2),
            21..=30 => (ty - 20, 3),
            _ => {
                return Err(PointsError::format(
                    name,
                    (vlr.data.start + 192 * k + 2) as u64,
                    format!("extra bytes \"{label}\": data type {ty} is not 0..30"),
                ))
            }
        };
        for p in 0..parts {
            let size = extra_type_size(scalar);
            let field = |base: usize| &d[base + 8 * p..base + 8 * p + 8];
            let value = |base: usize| {
                if scalar >= 9 {
                    f64::from_le_bytes(field(base).try_into().unwrap_or([0; 8]))
                } else if matches!(scalar, 2 | 4 | 6 | 8) {
                    i64::from_le_bytes(field(base).try_into().unwrap_or([0; 8])) as f64
                } else {
                    u64::from_le_bytes(field(base).try_into().unwrap_or([0; 8])) as f64
                }
            };
            let no_data = if options & 1 != 0 {
                Some(if scalar == 9 {
                    // a float's no-data is stored as a double
                    value(40) as f32 as f64
                } else {
                    value(40)
                })
            } else {
                None
            };
            let f = |base: usize| f64::from_le_bytes(field(base).try_into().unwrap_or([0; 8]));
            extras.push(Extra {
                name: if parts == 1 {
                    label.clone()
                } else {
                    format!("{label}[{p}]")
                },
                at,
                ty: scalar,
                no_data,
                scale: if options & 8 != 0 { f(112) } else { 1.0 },
                offset: if options & 16 != 0 { f(136) } else { 0.0 },
            });
            at += size;
        }
    }
    if at > record {
        return Err(PointsError::format(
            name,
            vlr.at as u64,
            format!(
                "the Extra Bytes VLR describes {} bytes, but the records have {} extra bytes",
                at - base,
                record - base
            ),
        ));
    }
    Ok(extras)
}

/// Parse LAS/LAZ bytes named `name`, taking ownership of them.
pub(crate) fn parse_owned(name: &Path, bytes: Vec<u8>) -> Result<LasCloud, PointsError> {
    let checked = check(name, &bytes)?;
    let mut info = checked.info;
    let base = RECORD_LENGTH[info.point_format as usize] as usize;
    let record = info.record_length as usize;
    let extras = extra_bytes(name, &bytes, &checked.vlrs, base, record)?;
    info.extra_bytes = extras.iter().map(|e| e.name.clone()).collect();
    let count = info.points;
    let decode_error = |what: String| PointsError::Decode {
        path: name.to_path_buf(),
        message: what,
    };
    let mut reader = guarded(|| Reader::new(Cursor::new(bytes)))
        .map_err(|e| decode_error(format!("the header: {e}")))?;
    let has_rgb = reader.header().point_format().has_color;
    let mut pd: PointData = PointDataBuilder::new().for_header(reader.header()).build();
    let mut cols = Columns::new(extras.len(), has_rgb);
    let progress = Progress::new(count, &format!("reading {}", name.display()));
    let mut done = 0u64;
    while done < count {
        let want = BATCH.min(count - done);
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
        cols.append(&pd, &extras, record)
            .map_err(|_| decode_error(format!("cannot allocate memory for {count} points")))?;
        done += n;
        progress.inc(n);
    }
    drop(progress);
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
    let cloud = PointCloud::from_parts(CloudParts {
        positions: cols.positions,
        attributes,
        rgb: has_rgb.then_some(cols.rgb),
        normals: None,
    })
    .map_err(decode_error)?;
    Ok(LasCloud { cloud, info })
}

/// Run a `las`/`laz` call, turning a panic into an error message. `laz` asserts on
/// some corrupt compressed streams (e.g. `assert!(sym < (1 << 16))` in its arithmetic
/// decoder) where it could return an error; the checks above cannot foresee what an
/// arithmetic-coded stream decodes to, so this is the last guard: the decoder that
/// panicked is dropped with the error, never reused.
fn guarded<T>(f: impl FnOnce() -> las::Result<T>) -> Result<T, String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(result) => result.map_err(|e| e.to_string()),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(format!(
                "the decoder failed on corrupt data ({})",
                crate::input::shorten(&what, 80)
            ))
        }
    }
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
    extras: Vec<Vec<f64>>,
}

impl Columns {
    fn new(extras: usize, has_rgb: bool) -> Columns {
        Columns {
            positions: Vec::new(),
            intensity: Vec::new(),
            classification: Vec::new(),
            return_number: Vec::new(),
            number_of_returns: Vec::new(),
            rgb: Vec::new(),
            has_rgb,
            extras: vec![Vec::new(); extras],
        }
    }

    fn append(
        &mut self,
        pd: &PointData,
        extras: &[Extra],
        record: usize,
    ) -> Result<(), std::collections::TryReserveError> {
        let n = pd.len();
        self.positions.try_reserve(n)?;
        for v in [
            &mut self.intensity,
            &mut self.classification,
            &mut self.return_number,
            &mut self.number_of_returns,
        ] {
            v.try_reserve(n)?;
        }
        self.positions
            .extend(pd.x().zip(pd.y()).zip(pd.z()).map(|((x, y), z)| [x, y, z]));
        self.intensity.extend(pd.intensity().map(i32::from));
        self.classification
            .extend(pd.classification().map(i32::from));
        self.return_number.extend(pd.return_number().map(i32::from));
        self.number_of_returns
            .extend(pd.number_of_returns().map(i32::from));
        if self.has_rgb {
            self.rgb.try_reserve(n)?;
            if let Some(rgb) = pd.rgb() {
                self.rgb.extend(rgb.map(|(r, g, b)| [r, g, b]));
            }
        }
        for (e, column) in extras.iter().zip(&mut self.extras) {
            column.try_reserve(n)?;
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
