//! Extra bytes (LAS 1.4): the descriptors of the Extra Bytes VLR (`LASF_Spec`, record 4;
//! 192 bytes each) and the decoding of each attribute from the point records.

use std::path::Path;

use super::layout::Vlr as RawVlr;
use crate::le::text_at;
use crate::points::PointsError;

/// One extra-bytes attribute: where it is in the record and how to decode it.
pub(super) struct Extra {
    pub(super) name: String,
    /// Byte offset within the record.
    pub(super) at: usize,
    /// Data type 1..10 of the LAS 1.4 table.
    pub(super) ty: u8,
    pub(super) no_data: Option<f64>,
    pub(super) scale: f64,
    pub(super) offset: f64,
}

pub(super) fn extra_type_size(ty: u8) -> usize {
    match ty {
        1 | 2 => 1,
        3 | 4 => 2,
        5 | 6 | 9 => 4,
        _ => 8,
    }
}

pub(super) fn decode_extra(ty: u8, b: &[u8]) -> f64 {
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

/// The extra-bytes descriptors of every Extra Bytes record (`LASF_Spec` record 4, VLRs
/// then EVLRs, in file order), laid out one after another after `base` bytes. (A file may
/// split its descriptors over several such records; laspy reads them all.)
pub(super) fn extra_bytes(
    name: &Path,
    b: &[u8],
    vlrs: &[RawVlr],
    base: usize,
    record: usize,
) -> Result<Vec<Extra>, PointsError> {
    let mut extras = Vec::new();
    let mut at = base;
    let mut k = 0;
    for vlr in vlrs
        .iter()
        .filter(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
    {
        let data = &b[vlr.data.clone()];
        if !data.len().is_multiple_of(192) {
            return Err(PointsError::format(
                name,
                vlr.at as u64,
                format!(
                    "the Extra Bytes record holds {} bytes, not a multiple of its 192-byte descriptors",
                    data.len()
                ),
            ));
        }
        for (j, d) in data.chunks_exact(192).enumerate() {
            let at_type = vlr.data.start + 192 * j + 2;
            describe(name, d, k, at_type, &mut at, &mut extras)?;
            k += 1;
            if at > record {
                return Err(PointsError::format(
                    name,
                    at_type as u64,
                    format!(
                        "extra bytes descriptor {k} ends at byte {} of the record, but the records have {} extra bytes",
                        at - base,
                        record - base
                    ),
                ));
            }
        }
    }
    Ok(extras)
}

/// Add the attributes of descriptor `d` (the `k`-th, its data type at byte `at_type` of the
/// file) that start at byte `at` of the record; `at` moves past them.
fn describe(
    name: &Path,
    d: &[u8],
    k: usize,
    at_type: usize,
    at: &mut usize,
    extras: &mut Vec<Extra>,
) -> Result<(), PointsError> {
    let (ty, options) = (d[2], d[3]);
    let label = text_at(d, 4..36);
    let label = if label.is_empty() {
        format!("extra{k}")
    } else {
        label
    };
    let (scalar, parts) = match ty {
        0 => {
            *at += options as usize; // undocumented bytes: skipped
            return Ok(());
        }
        1..=10 => (ty, 1),
        11..=20 => (ty - 10, 2),
        21..=30 => (ty - 20, 3),
        _ => {
            return Err(PointsError::format(
                name,
                at_type as u64,
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
            at: *at,
            ty: scalar,
            no_data,
            scale: if options & 8 != 0 { f(112) } else { 1.0 },
            offset: if options & 16 != 0 { f(136) } else { 0.0 },
        });
        *at += size;
    }
    Ok(())
}
