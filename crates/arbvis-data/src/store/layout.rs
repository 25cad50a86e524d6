//! The layout `arbvis convert` writes (version 2): an MDIO v1 post-stack dataset that also
//! carries arbvis's pyramid, so that xarray, mdio-python and Dask open the survey and
//! arbvis streams it.
//!
//! - The root group is MDIO's: attributes `apiVersion`, `name` (`PostStack3DTime` for a
//!   SEG-Y survey), `attributes` (`surveyType`, `gatherType`, `defaultVariableName`), and
//!   arbvis's own `arbvis` ([`StoreMeta`]).
//! - Level 0 is the group's variables on dimensions `inline, crossline, time` (`sample`
//!   for a survey without a sample interval): `amplitude` and the derived attributes,
//!   each with MDIO's `statsV1`; the coordinates `inline`, `crossline`, `time` (ms);
//!   `trace_mask` (a trace is live unless every sample is NaN); `cdp_x`, `cdp_y` where
//!   the SEG-Y gives them (bytes 181-188, scaled by bytes 71-72); per-brick ranges
//!   `NAME_range` on dimensions `inline_brick, crossline_brick, time_brick, min_max`.
//! - Level `L` is the group `level_L`, a dataset of its own: the same variables and
//!   ranges, halved per axis, on dimensions of its own (`inline_L`, `crossline_L`,
//!   `time_L`: a data tree aligns a group's dimensions with its parent's of the same
//!   name), with coordinates that are the means of the cells' level-0 coordinates
//!   (`xarray.open_datatree` opens every level).
//! - As mdio-python 1.1.3 writes them: the root's `createdOn` (Python's `str` of a UTC
//!   time); `_FillValue` (xarray's base64 of a float64 NaN) on the float variables and map
//!   coordinates; `unitsV1` (`{"length": "m"}`) on `cdp_x`, `cdp_y`; `coordinates` on the
//!   variables and the trace mask; integer dimension coordinates filled with `i32::MAX`.
//! - SEG-Y trace headers (mdio-python's `headers`, a structured type) are not written
//!   (docs/stores.md says why).
//!
//! Every `zarr.json` is written whole (a temporary renamed into place), and all of them
//! again when the conversion resumes and when it finishes (with the statistics), the root
//! last, so that the root's `complete` flag never precedes the rest.

use std::path::Path;
use std::sync::Arc;

use serde_json::{json, Map, Value};
use zarrs::array::{Array, ArrayBuilder, DataType};
use zarrs::filesystem::FilesystemStore;
use zarrs::group::GroupBuilder;

use super::compression::Compression;
use super::meta::StoreMeta;
use super::StoreError;

mod write;
pub use write::{write_layout, Writers};

/// The MDIO version whose layout this follows (as multidimio 1.1.3 writes it).
pub const MDIO_API_VERSION: &str = "1.1.3";

/// What every node of the layout is written with: the chunks' compression, whether the
/// survey has map coordinates (`cdp_x`, `cdp_y`), and the root's `createdOn`.
#[derive(Debug, Clone)]
pub struct LayoutOptions {
    /// The chunks' codec.
    pub compression: Compression,
    /// `cdp_x` and `cdp_y` are written.
    pub has_cdp: bool,
    /// The root's `createdOn`, as mdio-python writes it (`2026-12-06 04:52:17.387247+00:00`).
    pub created_on: String,
}

/// Now, as mdio-python's `createdOn` says a time (Python's `str` of a UTC datetime).
pub fn created_now() -> String {
    chrono::Utc::now()
        .format("%Y-%m-%d %H:%M:%S%.6f+00:00")
        .to_string()
}

/// xarray's `_FillValue` of a float variable whose fill is NaN: the base64 of a
/// little-endian float64 NaN, as mdio-python's datasets carry it.
const NAN_FILL_VALUE: &str = "AAAAAAAA+H8=";

/// One attribute's statistics over level 0, as MDIO's `statsV1`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stats {
    /// Finite samples.
    pub count: f64,
    /// Their sum.
    pub sum: f64,
    /// Their sum of squares.
    pub sum_squares: f64,
}

fn storage_error(path: &Path, e: impl std::fmt::Display) -> StoreError {
    StoreError::io(path, e)
}

/// Write the `zarr.json` of the node at zarr path `node` whole: a temporary renamed into
/// place, so that a kill leaves the old file or the new one, never a cut one.
pub fn write_json(
    store: &Path,
    node: &str,
    metadata: &impl serde::Serialize,
) -> Result<(), StoreError> {
    let folder = store.join(node.trim_start_matches('/'));
    std::fs::create_dir_all(&folder).map_err(|e| StoreError::io(&folder, e))?;
    let file = folder.join("zarr.json");
    let json = serde_json::to_vec_pretty(metadata).map_err(|e| StoreError::io(&file, e))?;
    arbvis_core::png_io::write_atomic(&file, &json).map_err(|e| StoreError::io(&file, e))
}

/// A group at `node` with `attributes`.
fn group(
    storage: &Arc<FilesystemStore>,
    store: &Path,
    node: &str,
    attributes: Map<String, Value>,
) -> Result<(), StoreError> {
    let mut g = GroupBuilder::new()
        .build(storage.clone(), node)
        .map_err(|e| storage_error(store, e))?;
    *g.attributes_mut() = attributes;
    write_json(store, node, g.metadata())
}

/// An array's metadata written; the array, to write chunks into.
#[allow(clippy::too_many_arguments)]
fn array(
    storage: &Arc<FilesystemStore>,
    store: &Path,
    node: &str,
    shape: Vec<u64>,
    chunks: Vec<u64>,
    dtype: DataType,
    fill: impl Into<zarrs::array::builder::ArrayBuilderFillValue>,
    dims: &[&str],
    compression: Compression,
    attributes: Map<String, Value>,
) -> Result<Array<FilesystemStore>, StoreError> {
    let typesize = dtype.fixed_size();
    let mut b = ArrayBuilder::new(shape, chunks, dtype, fill);
    b.bytes_to_bytes_codecs(compression.codecs(typesize));
    b.dimension_names(Some(dims.to_vec()));
    b.attributes(attributes);
    let a = b
        .build(storage.clone(), node)
        .map_err(|e| storage_error(store, e))?;
    write_json(store, node, a.metadata())?;
    Ok(a)
}

/// The level-0 coordinate values along each axis: inline and crossline numbers (the
/// survey's, else indices), and the sample axis's (time in ms, depth in m, else indices).
pub fn coordinates(meta: &StoreMeta) -> [Vec<f64>; 3] {
    let [ni, nj, nk] = meta.dims;
    let numbers = |n: usize, first_step: Option<[i64; 2]>| -> Vec<f64> {
        let [first, step] = first_step.unwrap_or([0, 1]);
        (0..n).map(|x| (first + step * x as i64) as f64).collect()
    };
    let s = meta.source.sample_axis();
    [
        (0..ni).map(|i| s.first + i as f64 * s.step).collect(),
        numbers(nj, meta.source.crosslines),
        numbers(nk, meta.source.inlines),
    ]
}

/// `values` (a level-0 axis) at level `level`: the mean over each cell of `2^level`.
fn coarsen(values: &[f64], level: usize) -> Vec<f64> {
    values
        .chunks(1 << level)
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect()
}

/// The `statsV1` attribute of an attribute, as MDIO writes it (a JSON text).
fn stats_v1(meta: &StoreMeta, attr: usize, s: &Stats) -> Value {
    let a = &meta.attributes[attr];
    let v = json!({
        "count": s.count as u64,
        "sum": s.sum,
        "sumSquares": s.sum_squares,
        "min": a.min.unwrap_or(0.0),
        "max": a.max.unwrap_or(0.0),
        "histogram": {"counts": [], "binCenters": []},
    });
    Value::String(v.to_string())
}

/// The root group's attributes: MDIO's and `arbvis`.
fn root_attributes(
    meta: &StoreMeta,
    created_on: &str,
) -> Result<Map<String, Value>, serde_json::Error> {
    let mut m = Map::new();
    m.insert("apiVersion".into(), json!(MDIO_API_VERSION));
    m.insert("createdOn".into(), json!(created_on));
    let name = match meta.domain().as_str() {
        "time" => "PostStack3DTime",
        "depth" => "PostStack3DDepth",
        _ => "PostStack3D",
    };
    m.insert("name".into(), json!(name));
    m.insert(
        "attributes".into(),
        json!({"surveyType": "3D", "gatherType": "stacked", "defaultVariableName": "amplitude"}),
    );
    m.insert("arbvis".into(), serde_json::to_value(meta)?);
    Ok(m)
}
