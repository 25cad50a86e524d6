//! A store's own numbers, checked at open: the `arbvis` attribute's fields bounded and
//! consistent with each other (checked arithmetic throughout), and every array's shape,
//! chunk shape and data type agreeing with them, level by level. A disagreement names the
//! array and both values; a type error in the metadata names its field
//! (`attributes.arbvis.dims[0]`) with its line and column.

use std::path::Path;

use serde::Deserialize;

use super::meta::{StoreMeta, FORMAT, VERSIONS};
use super::zarr::{self, ArrayMeta, DataType};
use super::StoreError;

/// Longest axis of a survey, in voxels.
pub const MAX_SIDE: usize = 1 << 31;

/// Most bricks in one level (its ranges, LOD tables and page tables are sized by it).
pub const MAX_BRICKS_PER_LEVEL: u64 = 1 << 26;

/// Brick sides `arbvis convert` writes and the renderers draw.
pub const BRICK_SIDES: std::ops::RangeInclusive<usize> = 2..=512;

/// The root `zarr.json` of an arbvis store, as far as arbvis reads it.
#[derive(Deserialize)]
struct GroupDoc {
    zarr_format: u64,
    node_type: String,
    #[serde(default)]
    attributes: GroupAttributes,
}

#[derive(Deserialize, Default)]
struct GroupAttributes {
    arbvis: Option<StoreMeta>,
}

/// Why a folder without `zarr.json` is not read: a zarr v2 store (an MDIO v0 dataset among
/// them) says so, with the way forward.
pub fn not_v3(store: &Path) -> String {
    let v2 = [".zgroup", ".zarray", ".zmetadata"]
        .iter()
        .any(|f| crate::fetch::exists(&store.join(f)));
    let mdio_v0 = crate::fetch::exists(&store.join("data").join(".zgroup"))
        || crate::fetch::exists(&store.join("metadata").join(".zgroup"));
    if mdio_v0 {
        "an MDIO v0 dataset (zarr v2) without its variable data/chunked_012: not a dataset arbvis reads".into()
    } else if v2 {
        "a zarr v2 store that is not an MDIO dataset (its .zattrs has no apiVersion): arbvis reads zarr v3 stores and MDIO datasets on zarr v2 or v3; rewrite it as v3 (e.g. zarr-python 3: zarr.open_group(..., zarr_format=3) and copy the arrays)".into()
    } else {
        "no zarr.json: not a zarr store (make one with `arbvis convert SURVEY STORE`)".into()
    }
}

/// The `arbvis` attribute of the group at `store`, parsed (a type error names its field,
/// line and column) and checked ([`check_meta`]).
pub fn read_meta(store: &Path) -> Result<StoreMeta, StoreError> {
    let file = store.join("zarr.json");
    if !crate::fetch::exists(&file) {
        return Err(StoreError::invalid(store, not_v3(store)));
    }
    let text = crate::fetch::read_text(&file, zarr::MAX_METADATA_BYTES)
        .map_err(|e| StoreError::io(&file, e))?;
    let mut de = serde_json::Deserializer::from_str(&text);
    let doc: GroupDoc = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let inner = e.inner();
        StoreError::invalid(
            &file,
            format!(
                "line {}, column {}: {}: {inner}",
                inner.line(),
                inner.column(),
                e.path()
            ),
        )
    })?;
    if doc.zarr_format != 3 || doc.node_type != "group" {
        return Err(StoreError::invalid(
            &file,
            format!(
                "zarr_format {} node_type {:?}: not a zarr v3 group",
                doc.zarr_format, doc.node_type
            ),
        ));
    }
    // Fields the spec has a reader refuse (read again untyped: the typed read skips them).
    if let Ok(value) = serde_json::from_str::<serde_json::Value>(&text) {
        zarr::check_group(&value, &file)?;
    }
    let meta = doc.attributes.arbvis.ok_or_else(|| {
        StoreError::invalid(
            &file,
            "no `arbvis` attribute: a zarr group that arbvis did not write (make a store with `arbvis convert SURVEY STORE`)",
        )
    })?;
    check_meta(&file, &meta)?;
    Ok(meta)
}

/// Every number of `meta` bounded and consistent (`file` names it in errors).
pub fn check_meta(file: &Path, meta: &StoreMeta) -> Result<(), StoreError> {
    let bad = |m: String| Err(StoreError::invalid(file, m));
    if meta.format != FORMAT || !VERSIONS.contains(&meta.version) {
        return bad(format!(
            "format {:?} version {}: arbvis reads {FORMAT:?} versions {VERSIONS:?}",
            meta.format, meta.version
        ));
    }
    if !BRICK_SIDES.contains(&meta.brick) {
        return bad(format!(
            "arbvis.brick is {}: must be {}..={} voxels",
            meta.brick,
            BRICK_SIDES.start(),
            BRICK_SIDES.end()
        ));
    }
    for (a, &d) in meta.dims.iter().enumerate() {
        if d == 0 || d > MAX_SIDE {
            return bad(format!("arbvis.dims[{a}] is {d}: must be 1..={MAX_SIDE}"));
        }
    }
    for (a, &s) in meta.spacing.iter().enumerate() {
        if !(s.is_finite() && s > 0.0) {
            return bad(format!(
                "arbvis.spacing[{a}] is {s}: must be a positive number"
            ));
        }
    }
    // Level 0 has the most bricks.
    let bricks = super::brick_counts(meta.dims, meta.brick)
        .iter()
        .try_fold(1u64, |n, &c| n.checked_mul(c as u64))
        .filter(|&n| n <= MAX_BRICKS_PER_LEVEL);
    if bricks.is_none() {
        return bad(format!(
            "dims {:?} in {}³ bricks: more than {MAX_BRICKS_PER_LEVEL} bricks in a level",
            meta.dims, meta.brick
        ));
    }
    let levels = super::level_count(meta.dims, meta.brick);
    if meta.levels != levels {
        return bad(format!(
            "arbvis.levels is {}, but dims {:?} in {}³ bricks make {levels} levels",
            meta.levels, meta.dims, meta.brick
        ));
    }
    if meta.attributes.is_empty() || meta.attributes.len() > 16 {
        return bad(format!(
            "arbvis.attributes has {} entries: must be 1..=16",
            meta.attributes.len()
        ));
    }
    for (n, a) in meta.attributes.iter().enumerate() {
        if a.attribute().is_none() {
            return bad(format!(
                "arbvis.attributes[{n}].name is {:?}: not an attribute arbvis knows",
                a.name
            ));
        }
        if meta.attributes[..n].iter().any(|b| b.name == a.name) {
            return bad(format!("arbvis.attributes[{n}]: {:?} twice", a.name));
        }
        if !matches!(a.dtype.as_str(), "float32" | "float16") {
            return bad(format!(
                "arbvis.attributes[{n}].dtype is {:?}: arbvis stores float32 or float16",
                a.dtype
            ));
        }
        for (what, v) in [("min", a.min), ("max", a.max), ("mean", a.mean)] {
            if v.is_some_and(|v| !v.is_finite()) {
                return bad(format!(
                    "arbvis.attributes[{n}].{what} is not a finite number"
                ));
            }
        }
        if let (Some(lo), Some(hi)) = (a.min, a.max) {
            if lo > hi {
                return bad(format!(
                    "arbvis.attributes[{n}]: min {lo} is above max {hi}"
                ));
            }
        }
    }
    Ok(())
}

/// Arrays by attribute, then level.
pub type ArraysByLevel = Vec<Vec<ArrayMeta>>;

/// One array of the store, opened and held to `shape`, `chunks` and `dtype`.
fn checked_array(
    store: &Path,
    name: &str,
    shape: &[u64],
    chunks: &[u64],
    dtype: &str,
) -> Result<ArrayMeta, StoreError> {
    let array = zarr::open_array(&store.join(name))?;
    let file = store.join(name).join("zarr.json");
    let disagree = |what: &str, found: String, want: String| {
        Err(StoreError::invalid(
            &file,
            format!("{name}: {what} is {found}, but the store's metadata makes it {want}"),
        ))
    };
    if array.shape != shape {
        return disagree("shape", format!("{:?}", array.shape), format!("{shape:?}"));
    }
    if array.chunks != chunks {
        return disagree(
            "chunk shape",
            format!("{:?}", array.chunks),
            format!("{chunks:?}"),
        );
    }
    if array.data_type != DataType::parse(dtype).unwrap_or(DataType::Float32) {
        return disagree("data type", array.data_type.name().into(), dtype.into());
    }
    Ok(array)
}

/// The arrays of every attribute and level: the data (`[inline, crossline, sample]` in
/// bricks) and the per-brick ranges (`[bricks k, j, i, 2]`, one chunk), checked against
/// `meta`.
pub fn open_arrays(
    store: &Path,
    meta: &StoreMeta,
) -> Result<(ArraysByLevel, ArraysByLevel), StoreError> {
    let b = meta.brick as u64;
    let mut data = Vec::with_capacity(meta.attributes.len());
    let mut ranges = Vec::with_capacity(meta.attributes.len());
    for (a, attribute) in meta.attributes.iter().enumerate() {
        let (mut d, mut r) = (Vec::new(), Vec::new());
        for level in 0..meta.levels {
            let n = meta.level_dims(level);
            let shape = [n[2] as u64, n[1] as u64, n[0] as u64];
            let name = meta.array_path(a, level)[1..].to_string();
            match (&meta.source_variable, a, level) {
                // An MDIO dataset's own variable, any chunk shape and type.
                (Some(variable), 0, 0) => {
                    let array = zarr::open_array(&store.join(variable))?;
                    if array.shape != shape {
                        return Err(StoreError::invalid(
                            &store.join(variable).join("zarr.json"),
                            format!(
                                "{variable}: shape is {:?}, but the store's metadata makes it {shape:?}",
                                array.shape
                            ),
                        ));
                    }
                    d.push(array);
                }
                _ => d.push(checked_array(
                    store,
                    &name,
                    &shape,
                    &[b; 3],
                    &attribute.dtype,
                )?),
            }
            let c = meta.brick_counts(level);
            let shape = [c[2] as u64, c[1] as u64, c[0] as u64, 2];
            let name = meta.range_path(a, level)[1..].to_string();
            r.push(checked_array(store, &name, &shape, &shape, "float32")?);
        }
        data.push(d);
        ranges.push(r);
    }
    Ok((data, ranges))
}
