//! zarr v2 arrays (`.zarray`), as MDIO v0 datasets hold them: the same checks as a v3
//! array's, the v2 spellings mapped onto [`ArrayMeta`] (numpy type strings, one
//! `compressor`, no `filters`, C order, `dimension_separator`).

use std::path::Path;

use serde_json::{json, Value};

use super::{chunk_sizes, fill, read_json, sizes, ArrayMeta, ChunkKeys, Codec, DataType};
use crate::store::StoreError;

/// A numpy type string (`<f4`, `>i2`, `|b1`) as a data type and its byte order.
fn numpy_type(s: &str) -> Option<(DataType, bool)> {
    if !s.is_char_boundary(1) {
        return None;
    }
    let (order, code) = s.split_at(1);
    let big = match order {
        ">" => true,
        "<" | "|" => false,
        _ => return None,
    };
    use DataType::*;
    let t = match code {
        "b1" => Bool,
        "i1" => Int8,
        "i2" => Int16,
        "i4" => Int32,
        "i8" => Int64,
        "u1" => UInt8,
        "u2" => UInt16,
        "u4" => UInt32,
        "u8" => UInt64,
        "f2" => Float16,
        "f4" => Float32,
        "f8" => Float64,
        _ => return None,
    };
    Some((t, big))
}

/// The v2 array at `folder` (its `.zarray`), every field checked.
pub fn open_array(folder: &Path) -> Result<ArrayMeta, StoreError> {
    let file = folder.join(".zarray");
    let doc = read_json(&file)?;
    let invalid = |m: String| StoreError::invalid(&file, m);
    if doc.get("zarr_format").and_then(Value::as_u64) != Some(2) {
        return Err(invalid("`zarr_format` is not 2".into()));
    }
    let shape = sizes(doc.get("shape").unwrap_or(&Value::Null), "shape", &file, 0)?;
    let type_name = doc.get("dtype").and_then(Value::as_str).unwrap_or("");
    let (data_type, big_endian) = numpy_type(type_name).ok_or_else(|| {
        let what = match doc.get("dtype") {
            Some(Value::Array(_)) => "a structured type".to_string(),
            other => arbvis_core::input::shorten(&other.unwrap_or(&Value::Null).to_string(), 60),
        };
        invalid(format!(
            "`dtype` {what}: arbvis reads bool, (u)int8-64 and float16-64"
        ))
    })?;
    let chunks = chunk_sizes(
        doc.get("chunks").unwrap_or(&Value::Null),
        "chunks",
        (&shape, data_type),
        &file,
    )?;
    if doc.get("order").and_then(Value::as_str) != Some("C") {
        return Err(invalid(
            "`order` is not \"C\": arbvis reads row-major chunks".into(),
        ));
    }
    if doc.get("filters").is_some_and(|f| !f.is_null()) {
        return Err(invalid(format!(
            "`filters` {}: arbvis reads arrays without filters",
            doc["filters"]
        )));
    }
    let (zfp, codecs) = match doc.get("compressor") {
        None | Some(Value::Null) => (None, Vec::new()),
        // ZFP replaces the raw bytes: it is the array-to-bytes stage.
        Some(c) if c.get("id").and_then(Value::as_str) == Some("zfpy") => {
            let z = super::zfp::Zfp::new(c, data_type)
                .map_err(|e| invalid(format!("`compressor` {c}: {e}")))?;
            (Some(z), Vec::new())
        }
        Some(c) => (None, vec![compressor(c, data_type, &file)?]),
    };
    let separator = match doc.get("dimension_separator").and_then(Value::as_str) {
        None | Some(".") => '.',
        Some("/") => '/',
        Some(other) => {
            return Err(invalid(format!(
                "`dimension_separator` {other:?}: expected \".\" or \"/\""
            )))
        }
    };
    let fill_value = fill(
        doc.get("fill_value").unwrap_or(&Value::Null),
        data_type,
        &file,
    )?;
    let attributes = match read_json(&folder.join(".zattrs")) {
        Ok(Value::Object(m)) => m,
        _ => serde_json::Map::new(),
    };
    // xarray's convention for v2: the dimension names in `_ARRAY_DIMENSIONS`.
    let dimension_names = attributes
        .get("_ARRAY_DIMENSIONS")
        .and_then(Value::as_array)
        .filter(|names| names.len() == shape.len())
        .map(|names| {
            names
                .iter()
                .map(|n| n.as_str().map(str::to_string))
                .collect()
        });
    Ok(ArrayMeta {
        folder: folder.to_path_buf(),
        shape,
        chunks,
        data_type,
        fill_value,
        big_endian: big_endian && zfp.is_none(),
        zfp,
        codecs,
        dimension_names,
        attributes,
        keys: ChunkKeys::V2(separator),
        v2: true,
    })
}

/// A v2 `compressor` as the codec that undoes it.
fn compressor(c: &Value, t: DataType, file: &Path) -> Result<Codec, StoreError> {
    let refuse = |why: String| StoreError::invalid(file, format!("`compressor` {c}: {why}"));
    match c.get("id").and_then(Value::as_str) {
        Some("blosc") => {
            let shuffle = match c.get("shuffle").and_then(Value::as_i64) {
                Some(0) => "noshuffle",
                Some(2) => "bitshuffle",
                Some(1) | None => "shuffle",
                Some(-1) => "shuffle",
                Some(other) => return Err(refuse(format!("shuffle {other}"))),
            };
            let config = json!({
                "cname": c.get("cname").cloned().unwrap_or(json!("lz4")),
                "clevel": c.get("clevel").cloned().unwrap_or(json!(5)),
                "shuffle": shuffle,
                "typesize": t.size(),
                "blocksize": c.get("blocksize").cloned().unwrap_or(json!(0)),
            });
            super::blosc_codec(&config).map_err(|e| refuse(e.message))?;
            Ok(Codec::Blosc(config))
        }
        Some("zstd") => Ok(Codec::Zstd),
        Some("gzip") => Ok(Codec::Gzip),
        Some(id) => Err(refuse(format!(
            "{id:?} is not a compressor arbvis reads (blosc, zstd, gzip, zfpy)"
        ))),
        None => Err(refuse("no `id`".into())),
    }
}
