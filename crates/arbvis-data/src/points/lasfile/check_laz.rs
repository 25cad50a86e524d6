//! The checks on a LAZ file's compression before `laz` reads it: the laszip VLR's items
//! against the record, the chunk table against the data, LAZ 1.4 layer sizes against
//! the file, and the chunks that hold the header's points.

use std::io::Cursor;
use std::path::Path;

use laz::laszip::ChunkTableEntry;

use super::header::LasInfo;
use super::layout::Vlr as RawVlr;
use super::laz_chunks::{Chunk, LazChunks};
use crate::le::{u16_at, u32_at, u64_at};
use crate::points::PointsError;

/// A refusal: the byte it names and the message.
type Refusal = (usize, String);

/// LAZ: laszip VLR items against the record, chunk table against the data, and LAZ 1.4
/// layer sizes against the file; the chunks that hold the header's points, where the
/// file is chunked and has a table (each decodable alone, [`super::laz_chunks`]).
pub(super) fn check_laz(
    name: &Path,
    b: &[u8],
    info: &LasInfo,
    data_start: usize,
    vlrs: &[RawVlr],
) -> Result<Option<LazChunks>, PointsError> {
    let fail = |(at, m): Refusal| PointsError::format(name, at as u64, m);
    let vlr = laszip_vlr(b, vlrs).map_err(fail)?;
    let data = &b[vlr.data.clone()];
    let items = check_items(vlr, data, info.record_length).map_err(fail)?;
    let laz_vlr =
        laz::LazVlr::read_from(data).map_err(|e| fail((vlr.at, format!("the laszip VLR: {e}"))))?;
    // The chunk table, located as laz does: offset at the start of the data, else in
    // the last 8 bytes of the file.
    if items.compressor == 1 {
        return Ok(None); // point-wise: one stream, no table; points are read in batches
    }
    let Some(table) = table_offset(b, data_start, &items).map_err(fail)? else {
        return Ok(None);
    };
    let mut cursor = Cursor::new(b);
    cursor.set_position(data_start as u64);
    let entries = laz::laszip::ChunkTable::read_from(&mut cursor, &laz_vlr)
        .map_err(|e| fail((table, format!("the LAZ chunk table: {e}"))))?;
    let table = Table {
        at: table,
        data_start,
        entries: entries.as_ref(),
        chunk_size: items.chunk_size,
        points: info.points,
    };
    table.check_capacity().map_err(fail)?;
    // Layered chunks are decoded by the items' types (10 to 14), whatever the VLR's
    // compressor field says, so their layer sizes are checked by the types too (a file
    // that said compressor 2 over point-14 items once made laz allocate 600 MB).
    if items.compressor == 3 || items.layers > 0 {
        table.check_layers(b, &items).map_err(fail)?;
    }
    let chunks = table.chunks().map_err(fail)?;
    Ok(Some(LazChunks {
        vlr: laz_vlr,
        chunks,
    }))
}

/// The laszip VLR, with at least its 34 bytes of fixed fields.
fn laszip_vlr<'v>(b: &[u8], vlrs: &'v [RawVlr]) -> Result<&'v RawVlr, Refusal> {
    let Some(vlr) = vlrs
        .iter()
        .find(|v| v.user_id == "laszip encoded" && v.record_id == 22204)
    else {
        return Err((
            104,
            "a compressed point format without the laszip VLR (\"laszip encoded\", 22204)".into(),
        ));
    };
    let data = &b[vlr.data.clone()];
    if data.len() < 34 {
        return Err((
            vlr.at,
            format!(
                "the laszip VLR holds {} bytes, at least 34 needed",
                data.len()
            ),
        ));
    }
    Ok(vlr)
}

/// What the laszip VLR says of the compression.
struct Items {
    /// 1 point-wise, 2 chunked, 3 layered (LAZ 1.4).
    compressor: u16,
    /// Points per chunk (0 or `u32::MAX`: variable).
    chunk_size: u32,
    /// Bytes of a point's items.
    total: u64,
    /// Layers of a LAZ 1.4 chunk.
    layers: u64,
}

/// The laszip VLR's items: each a laszip type of its type's size, together the record.
fn check_items(vlr: &RawVlr, data: &[u8], record_length: u16) -> Result<Items, Refusal> {
    let items = u16_at(data, 32) as usize;
    if data.len() < 34 + 6 * items || items == 0 {
        return Err((
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
        let Some((natural, item_layers)) = item_size(ty, size) else {
            return Err((
                vlr.data.start + 34 + 6 * k,
                format!("LAZ item {k}: type {ty} is not a laszip item (0, 6 to 14)"),
            ));
        };
        if size != natural {
            return Err((
                vlr.at,
                format!("LAZ item {k} (type {ty}) declares {size} bytes, the type has {natural}"),
            ));
        }
        total += size as u64;
        layers += item_layers;
    }
    if total != record_length as u64 {
        return Err((
            vlr.at,
            format!("the LAZ items hold {total} bytes, the point records {record_length}"),
        ));
    }
    Ok(Items {
        compressor: u16_at(data, 0),
        chunk_size: u32_at(data, 12),
        total,
        layers,
    })
}

/// A laszip item type's (natural size, layers in LAZ 1.4 chunks); Byte items are any
/// size. `None` for a type laszip does not know.
fn item_size(ty: u16, size: u16) -> Option<(u16, u64)> {
    Some(match ty {
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
        _ => return None,
    })
}

/// The chunk table's offset, found as laz finds it: at the start of the point data, else
/// in the file's last 8 bytes; `None` for a file without one (refused when layered).
fn table_offset(b: &[u8], data_start: usize, items: &Items) -> Result<Option<usize>, Refusal> {
    if data_start + 8 > b.len() {
        return Err((
            data_start,
            "the file ends before the LAZ chunk table offset".into(),
        ));
    }
    let mut table = u64_at(b, data_start) as i64;
    if table <= data_start as i64 {
        table = u64_at(b, b.len() - 8) as i64;
    }
    if table <= data_start as i64 {
        if items.compressor == 3 || items.layers > 0 {
            return Err((
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
        return Err((
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
        return Err((
            table,
            format!("the LAZ chunk table lists {chunks} chunks in {room} bytes of data"),
        ));
    }
    Ok(Some(table))
}

/// A chunk table read, and what it must hold.
struct Table<'e> {
    /// Its offset.
    at: usize,
    /// The point data's offset (the first chunk starts 8 bytes after).
    data_start: usize,
    entries: &'e [ChunkTableEntry],
    /// Points per chunk (0 or `u32::MAX`: each entry says).
    chunk_size: u32,
    /// Points the header declares.
    points: u64,
}

impl Table<'_> {
    /// Whether each chunk's count is in its entry.
    fn variable(&self) -> bool {
        self.chunk_size == 0 || self.chunk_size == u32::MAX
    }

    /// Points in chunk `e`.
    fn points_in(&self, e: &ChunkTableEntry) -> u64 {
        if self.variable() {
            e.point_count
        } else {
            self.chunk_size as u64
        }
    }

    /// The chunks must hold the declared points.
    fn check_capacity(&self) -> Result<(), Refusal> {
        let capacity: u64 = if self.variable() {
            self.entries
                .iter()
                .fold(0u64, |a, e| a.saturating_add(e.point_count))
        } else {
            (self.entries.len() as u64).saturating_mul(self.chunk_size as u64)
        };
        if self.points > capacity {
            return Err((
                self.at,
                format!(
                    "the header declares {} points, but the LAZ chunk table holds at most {capacity}",
                    self.points
                ),
            ));
        }
        Ok(())
    }

    /// The layer sizes of each chunk the declared points reach (its first point raw, a
    /// u32 count, the sizes, the layers) must fit in the file.
    fn check_layers(&self, b: &[u8], items: &Items) -> Result<(), Refusal> {
        let mut start = self.data_start as u64 + 8;
        let mut covered = 0u64;
        for (k, e) in self.entries.iter().enumerate() {
            if covered >= self.points {
                break;
            }
            covered = covered.saturating_add(self.points_in(e));
            let sizes_at = start.saturating_add(items.total + 4);
            let sizes_end = sizes_at.saturating_add(4 * items.layers);
            if sizes_end > b.len() as u64 {
                return Err((
                    start as usize,
                    format!("LAZ chunk {k} starts too close to the end of the file"),
                ));
            }
            let sum: u64 = (0..items.layers as usize)
                .map(|l| u32_at(b, sizes_at as usize + 4 * l) as u64)
                .sum();
            if sum > b.len() as u64 - sizes_end {
                return Err((
                    sizes_at as usize,
                    format!(
                        "LAZ chunk {k} declares layers of {sum} bytes, past the end of the file"
                    ),
                ));
            }
            start = start.saturating_add(e.byte_count);
        }
        Ok(())
    }

    /// The chunks the declared points reach, each inside the data before the table.
    fn chunks(&self) -> Result<Vec<Chunk>, Refusal> {
        let table = self.at as u64;
        let mut chunks = Vec::new();
        let (mut start, mut left) = (self.data_start as u64 + 8, self.points);
        for (k, e) in self.entries.iter().enumerate() {
            if left == 0 {
                break;
            }
            let end = start.saturating_add(e.byte_count);
            if end > table {
                return Err((
                    start as usize,
                    format!(
                        "LAZ chunk {k} ({} bytes from byte {start}) runs past the chunk table at {table}",
                        e.byte_count
                    ),
                ));
            }
            let points = self.points_in(e).min(left);
            chunks.push(Chunk {
                start: start as usize,
                end: end as usize,
                points,
            });
            left -= points;
            start = end;
        }
        Ok(chunks)
    }
}
