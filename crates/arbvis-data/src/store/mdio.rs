//! MDIO v1 stores (TGS's open zarr format for seismic, written by `multidimio`) opened as
//! a store of one level: the dataset's default variable (`amplitude`, dimensions
//! `inline, crossline, time` or `depth`) is level 0, read through [`super::zarr`] (blosc
//! and every other codec it reads, any chunk shape) and cut into the renderer's bricks;
//! dead traces (`trace_mask` false) read as NaN, so they draw as no data; the axes take
//! the dataset's own inline, crossline and time (or depth) coordinates; the statistics
//! come from the variable's `statsV1`. MDIO keeps no coarser levels and no per-brick
//! ranges: every brick may show something, and the renderer draws level 0.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::{Arc, Mutex};

use serde_json::Value;

use super::meta::{AttributeMeta, SampleAxis, SourceMeta, StoreMeta};
use super::zarr::{self, ArrayMeta};
use super::StoreError;

/// Brick side the renderer cuts an MDIO variable into.
pub const BRICK: usize = 64;

/// Most bytes of decoded MDIO chunks kept (a 128³ float32 chunk is 8 MiB).
const CHUNK_CACHE_BYTES: u64 = 1 << 30;

/// Decoded chunks by index, with their last use.
type DecodedChunks = HashMap<Vec<u64>, (Arc<Vec<f32>>, u64)>;

/// An open MDIO dataset's level 0.
#[derive(Debug)]
pub struct Mdio {
    /// The variable drawn.
    pub data: ArrayMeta,
    /// Its fill value (absent chunks) is NaN: samples may be "no data" though no trace is dead.
    pub nan_fill: bool,
    /// Live traces, inline-major (`k * crosslines + j`), where the dataset has a mask.
    pub live: Option<Vec<bool>>,
    /// `cdp_x`, `cdp_y` per trace, inline-major, where the dataset has them.
    pub cdp: Option<[Vec<f64>; 2]>,
    cache: Mutex<(DecodedChunks, u64)>,
    /// Chunks the cache keeps: enough for four columns of chunks along the traces (two
    /// workers, each with the neighbouring column that shares its chunks), at least 8,
    /// within [`CHUNK_CACHE_BYTES`].
    capacity: usize,
}

/// Whether the root attributes are an MDIO dataset's.
pub fn is_mdio(root: &Value) -> bool {
    let a = &root["attributes"];
    a.get("apiVersion").is_some() && a.get("attributes").is_some_and(Value::is_object)
}

/// The whole of a one- or two-dimensional array (a coordinate, the trace mask), held to
/// the memory budget; absent chunks are the fill value.
fn read_whole(array: &ArrayMeta) -> Result<Vec<f64>, StoreError> {
    let file = array.metadata_file();
    let (rows, cols) = match array.shape[..] {
        [n] => (1, n),
        [r, c] => (r, c),
        _ => {
            return Err(StoreError::invalid(
                &file,
                format!("shape {:?}: expected one or two axes", array.shape),
            ))
        }
    };
    let n = rows
        .checked_mul(cols)
        .filter(|&n| n <= 1 << 40)
        .ok_or_else(|| {
            StoreError::invalid(&file, format!("shape {:?}: too many values", array.shape))
        })?;
    let mut out = arbvis_core::budget::vec_for::<f64>(n as usize, "an MDIO coordinate or mask")
        .map_err(|e| StoreError::Budget(e.to_string()))?;
    out.resize(n as usize, array.fill_value);
    let (cr, cc) = match array.chunks[..] {
        [c] => (1, c),
        [r, c] => (r, c),
        _ => unreachable!("chunks have the shape's axes"),
    };
    for a in 0..rows.div_ceil(cr) {
        for b in 0..cols.div_ceil(cc) {
            let index: Vec<u64> = if array.shape.len() == 1 {
                vec![b]
            } else {
                vec![a, b]
            };
            let values = array
                .read_chunk_f64(&index)
                .map_err(|e| StoreError::invalid(&array.chunk_file(&index), e.to_string()))?;
            let Some(values) = values else { continue };
            for y in 0..cr.min(rows - a * cr) {
                for x in 0..cc.min(cols - b * cc) {
                    out[((a * cr + y) * cols + b * cc + x) as usize] =
                        values[(y * cc + x) as usize];
                }
            }
        }
    }
    Ok(out)
}

/// `first, step` of a coordinate that is a whole-number progression.
fn first_step(values: &[f64]) -> Option<[i64; 2]> {
    let first = *values.first()?;
    let step = values.get(1).map_or(1.0, |v| v - first);
    (first.fract() == 0.0 && step.fract() == 0.0).then_some([first as i64, step as i64])
}

/// The variable's `statsV1` (a JSON object, or a string holding one).
fn stats(array: &ArrayMeta) -> Option<Value> {
    match array.attributes.get("statsV1")? {
        Value::String(s) => serde_json::from_str(s).ok(),
        v @ Value::Object(_) => Some(v.clone()),
        _ => None,
    }
}

/// What an MDIO dataset of either version says of its survey, before it is checked and
/// described alike.
struct Parts {
    api: String,
    /// The variable drawn and its path in the dataset.
    data: ArrayMeta,
    variable: String,
    /// Dimension names, slowest first; the last is the sample axis.
    names: Vec<String>,
    /// Coordinates along inline, crossline and samples, where given.
    coordinates: [Option<Vec<f64>>; 3],
    live: Option<Vec<bool>>,
    min: Option<f64>,
    max: Option<f64>,
    /// The sum of the live samples (v1's statsV1), or their mean (v0's attributes).
    sum: Option<f64>,
    mean: Option<f64>,
    facts: BTreeMap<String, String>,
    /// Levels may be added in place (v1; a v0 dataset is zarr v2).
    in_place: bool,
    /// `cdp_x`, `cdp_y` over (inline, crossline), where given.
    cdp: Option<[Vec<f64>; 2]>,
}

/// The map coordinates `cdp_x` and `cdp_y` of the dataset or store at `store` (zarr v3
/// arrays of shape `[nk, nj]` at its root), inline-major; `None` where it has none.
pub fn map_coordinates(
    store: &Path,
    nk: usize,
    nj: usize,
) -> Result<Option<[Vec<f64>; 2]>, StoreError> {
    let read = |name: &str| -> Result<Option<Vec<f64>>, StoreError> {
        let folder = store.join(name);
        if !array_at(&folder) {
            return Ok(None);
        }
        let array = zarr::open_array(&folder)?;
        if array.shape != [nk as u64, nj as u64] {
            return Err(StoreError::invalid(
                &array.metadata_file(),
                format!(
                    "{name} has shape {:?}, the survey [{nk}, {nj}] traces",
                    array.shape
                ),
            ));
        }
        read_whole(&array).map(Some)
    };
    Ok(match (read("cdp_x")?, read("cdp_y")?) {
        (Some(x), Some(y)) => Some([x, y]),
        _ => None,
    })
}

/// Whether `store` is an MDIO v0 dataset (zarr v2: `data/chunked_012`).
pub fn is_mdio_v0(store: &Path) -> bool {
    crate::fetch::exists(&store.join("data/chunked_012/.zarray"))
        && crate::fetch::exists(&store.join(".zattrs"))
}

/// Which MDIO dataset a folder holds.
#[derive(Debug, Clone)]
pub enum Flavour {
    /// MDIO v1: the root's attributes (`apiVersion`, `attributes.defaultVariableName`) as
    /// a v3 root document holds them, on zarr v3 (`zarr.json`) or zarr v2 (`.zgroup` and
    /// `.zattrs`, as mdio-python writes with zarr's `default_zarr_format = 2`).
    V1 { root: Value, zarr_v2: bool },
    /// MDIO v0 (zarr v2, `data/chunked_012`).
    V0,
}

impl Flavour {
    /// Whether it is read in place as one level: not a dataset whose levels arbvis added
    /// beside its arrays (its root then has an `arbvis` attribute, and it opens as a
    /// store).
    pub fn in_place(&self) -> bool {
        match self {
            Flavour::V1 { root, .. } => root["attributes"].get("arbvis").is_none(),
            Flavour::V0 => true,
        }
    }
}

/// The MDIO dataset at `store`, if it is one.
pub fn flavour(store: &Path) -> Result<Option<Flavour>, StoreError> {
    let v3 = store.join("zarr.json");
    if crate::fetch::exists(&v3) {
        let root = zarr::read_json(&v3)?;
        zarr::check_group(&root, &v3)?;
        return Ok(is_mdio(&root).then_some(Flavour::V1 {
            root,
            zarr_v2: false,
        }));
    }
    if crate::fetch::exists(&store.join(".zgroup")) && crate::fetch::exists(&store.join(".zattrs"))
    {
        let attributes = zarr::read_json(&store.join(".zattrs"))?;
        let root = serde_json::json!({ "attributes": attributes });
        if is_mdio(&root) {
            return Ok(Some(Flavour::V1 {
                root,
                zarr_v2: true,
            }));
        }
    }
    Ok(is_mdio_v0(store).then_some(Flavour::V0))
}

/// Open the MDIO dataset at `store` of `flavour`.
pub fn open_flavour(store: &Path, flavour: &Flavour) -> Result<(StoreMeta, Mdio), StoreError> {
    match flavour {
        Flavour::V1 { root, zarr_v2 } => assemble(store, parts_v1(store, root, *zarr_v2)?),
        Flavour::V0 => assemble(store, parts_v0(store)?),
    }
}

/// Open the MDIO v1 dataset at `store` on zarr v3, whose root `zarr.json` is `root`.
pub fn open(store: &Path, root: &Value) -> Result<(StoreMeta, Mdio), StoreError> {
    assemble(store, parts_v1(store, root, false)?)
}

/// Whether an array (zarr v3 `zarr.json` or v2 `.zarray`) is at `folder`.
fn array_at(folder: &Path) -> bool {
    crate::fetch::exists(&folder.join("zarr.json")) || crate::fetch::exists(&folder.join(".zarray"))
}

fn parts_v1(store: &Path, root: &Value, zarr_v2: bool) -> Result<Parts, StoreError> {
    let file = store.join(if zarr_v2 { ".zattrs" } else { "zarr.json" });
    let a = &root["attributes"];
    let api = a["apiVersion"].as_str().unwrap_or("?").to_string();
    let variable = a["attributes"]["defaultVariableName"]
        .as_str()
        .unwrap_or("amplitude")
        .to_string();
    if variable.contains(['/', '\\']) || variable.starts_with('.') {
        return Err(StoreError::invalid(
            &file,
            format!("defaultVariableName {variable:?}: not a variable's name"),
        ));
    }
    let data = zarr::open_array(&store.join(&variable))?;
    let names: Vec<String> = data
        .dimension_names
        .clone()
        .unwrap_or_default()
        .into_iter()
        .map(Option::unwrap_or_default)
        .collect();
    let coordinate = |name: &str| -> Result<Option<Vec<f64>>, StoreError> {
        let folder = store.join(name);
        if name.is_empty() || !array_at(&folder) {
            return Ok(None);
        }
        Ok(Some(read_whole(&zarr::open_array(&folder)?)?))
    };
    let name = |i: usize| names.get(i).cloned().unwrap_or_default();
    let coordinates = [
        coordinate(&name(0))?,
        coordinate(&name(1))?,
        coordinate(&name(2))?,
    ];
    let (nk, nj) = (
        data.shape.first().copied().unwrap_or(0) as usize,
        data.shape.get(1).copied().unwrap_or(0) as usize,
    );
    let live = match array_at(&store.join("trace_mask")) {
        false => None,
        true => Some(trace_mask(
            &zarr::open_array(&store.join("trace_mask"))?,
            nk,
            nj,
        )?),
    };
    let s = stats(&data);
    let number = |key: &str| {
        s.as_ref()
            .and_then(|s| s[key].as_f64())
            .filter(|v| v.is_finite())
    };
    let mut facts = BTreeMap::new();
    facts.insert("MDIO apiVersion".to_string(), api.clone());
    if let Some(n) = a["name"].as_str() {
        facts.insert("template".into(), n.to_string());
    }
    for key in ["surveyType", "gatherType"] {
        if let Some(v) = a["attributes"][key].as_str() {
            facts.insert(key.into(), v.to_string());
        }
    }
    // Map coordinates, where the dataset has them.
    let cdp = map_coordinates(store, nk, nj)?;
    for (values, name) in cdp.iter().flatten().zip(["cdp_x", "cdp_y"]) {
        let (lo, hi) = values
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if lo <= hi {
            facts.insert(name.into(), format!("{lo} .. {hi}"));
        }
    }
    Ok(Parts {
        api,
        data,
        variable,
        names,
        coordinates,
        live,
        min: number("min"),
        max: number("max"),
        sum: number("sum"),
        mean: None,
        facts,
        in_place: !zarr_v2,
        cdp,
    })
}

fn parts_v0(store: &Path) -> Result<Parts, StoreError> {
    let attrs = zarr::read_json(&store.join(".zattrs"))?;
    let api = attrs["api_version"].as_str().unwrap_or("0").to_string();
    let data = zarr::open_array(&store.join("data/chunked_012"))?;
    let dimensions = attrs["dimension"].as_array().cloned().unwrap_or_default();
    let names: Vec<String> = dimensions
        .iter()
        .map(|d| d["name"].as_str().unwrap_or_default().to_string())
        .collect();
    let coordinate = |i: usize| -> Option<Vec<f64>> {
        dimensions.get(i)?["coords"]
            .as_array()
            .map(|c| c.iter().filter_map(Value::as_f64).collect())
    };
    let coordinates = [coordinate(0), coordinate(1), coordinate(2)];
    let (nk, nj) = (
        data.shape.first().copied().unwrap_or(0) as usize,
        data.shape.get(1).copied().unwrap_or(0) as usize,
    );
    let mask = store.join("metadata/live_mask");
    let live = match crate::fetch::exists(&mask.join(".zarray")) {
        false => None,
        true => Some(trace_mask(&zarr::open_array(&mask)?, nk, nj)?),
    };
    let number = |key: &str| attrs[key].as_f64().filter(|v| v.is_finite());
    let mut facts = BTreeMap::new();
    facts.insert("MDIO api_version".to_string(), api.clone());
    if let Some(n) = attrs["trace_count"].as_u64() {
        facts.insert("trace count".into(), n.to_string());
    }
    Ok(Parts {
        api,
        data,
        variable: "data/chunked_012".into(),
        names,
        coordinates,
        live,
        min: number("min"),
        max: number("max"),
        sum: None,
        mean: number("mean"),
        facts,
        in_place: false,
        cdp: None,
    })
}

/// One dataset's parts checked and described as a store of one level.
fn assemble(store: &Path, parts: Parts) -> Result<(StoreMeta, Mdio), StoreError> {
    let Parts {
        api,
        data,
        variable,
        names,
        coordinates,
        live,
        min,
        max,
        sum,
        mean,
        mut facts,
        in_place,
        cdp,
    } = parts;
    let vfile = data.metadata_file();
    let domain = names.get(2).cloned().unwrap_or_default();
    let [ni, nj, nk] = post_stack_dims(&vfile, &variable, &names, &data.shape)?;
    for (values, n, name) in [
        (&coordinates[0], nk, &names[0]),
        (&coordinates[1], nj, &names[1]),
        (&coordinates[2], ni, &domain),
    ] {
        check_coordinate(store, values.as_deref(), n, name, &variable)?;
    }
    let dead = live
        .as_ref()
        .map_or(0, |l| l.iter().filter(|&&x| !x).count());
    // v1's statsV1 counts the non-zero samples of the live traces (mdio-python leaves
    // zeros out), so its sum over the live samples is their mean.
    let live_samples = ((nk * nj - dead) * ni) as u64;
    let mean = mean.or(match sum {
        Some(sum) if live_samples > 0 => Some(sum / live_samples as f64),
        _ => None,
    });
    facts.insert(
        "variable".into(),
        format!(
            "{variable} ({}, dimensions {})",
            data.data_type.name(),
            names.join(", ")
        ),
    );
    facts.insert("chunks".into(), format!("{:?}", data.chunks));
    facts.insert("codecs".into(), data.codec_names());
    if let Some(l) = &live {
        facts.insert(
            "live traces".into(),
            format!("{} of {}", l.len() - dead, l.len()),
        );
    }
    let (interval_us, sample_axis) = sample_axis(coordinates[2].as_deref(), &domain, &mut facts);
    let spacing = crate::volume::segy::geometry::survey_spacing(
        cdp.as_ref(),
        live.as_deref(),
        [nj, nk],
        sample_axis.as_ref().map(|a| (a.domain.as_str(), a.step)),
    );
    let meta = StoreMeta {
        format: format!("MDIO v{}", api.split('.').next().unwrap_or("1")),
        version: 1,
        dims: [ni, nj, nk],
        spacing,
        brick: BRICK,
        levels: 1,
        filter: "none: MDIO keeps one resolution".into(),
        attributes: vec![AttributeMeta {
            name: "amplitude".into(),
            dtype: "float32".into(),
            min,
            max,
            mean,
            non_finite: (dead * ni) as u64,
        }],
        source: SourceMeta {
            path: store.display().to_string(),
            kind: format!("MDIO v{api}"),
            bytes: 0,
            facts,
            inlines: coordinates[0].as_deref().and_then(first_step),
            crosslines: coordinates[1].as_deref().and_then(first_step),
            interval_us,
            samples: sample_axis,
        },
        compression: data.codec_names(),
        complete: true,
        source_variable: in_place.then(|| variable.clone()),
    };
    check_bricks(&vfile, meta.dims)?;
    let capacity = cache_capacity(&data);
    Ok((
        meta,
        Mdio {
            nan_fill: data.fill_value.is_nan(),
            data,
            live,
            cdp,
            cache: Mutex::new((HashMap::new(), 0)),
            capacity,
        },
    ))
}

/// The sides (samples, crosslines, inlines) of a post-stack 3D variable (dimensions
/// inline, crossline and time, depth or sample), each 1 to [`super::check::MAX_SIDE`].
fn post_stack_dims(
    vfile: &Path,
    variable: &str,
    names: &[String],
    shape: &[u64],
) -> Result<[usize; 3], StoreError> {
    let domain = names.get(2).map_or("", String::as_str);
    let post_stack =
        shape.len() == 3 && names.len() == 3 && matches!(domain, "time" | "depth" | "sample");
    if !post_stack {
        return Err(StoreError::invalid(
            vfile,
            format!(
                "{variable} has dimensions {names:?}: arbvis draws post-stack 3D variables (inline, crossline, time or depth); a pre-stack or 2D dataset is not drawn"
            ),
        ));
    }
    let [nk, nj, ni] = [shape[0], shape[1], shape[2]].map(|n| n as usize);
    for (n, name) in [(ni, &names[2]), (nj, &names[1]), (nk, &names[0])] {
        if n == 0 || n > super::check::MAX_SIDE {
            return Err(StoreError::invalid(
                vfile,
                format!("{name}: {n} values: must be 1..={}", super::check::MAX_SIDE),
            ));
        }
    }
    Ok([ni, nj, nk])
}

/// The sample interval in µs (time or sample axes) and the sample axis as the dataset
/// numbers it (its first value, step and domain); a depth axis's range goes into
/// `facts`.
fn sample_axis(
    samples: Option<&[f64]>,
    domain: &str,
    facts: &mut BTreeMap<String, String>,
) -> (Option<u32>, Option<SampleAxis>) {
    let interval_us = match (samples, domain) {
        (Some(t), "time" | "sample") if t.len() > 1 => {
            Some(((t[1] - t[0]) * 1000.0).round().max(0.0) as u32)
        }
        _ => None,
    };
    if let Some(d) = samples {
        if domain == "depth" {
            facts.insert("depth".into(), format!("{} .. {} m", d[0], d[d.len() - 1]));
        }
    }
    let axis = samples.filter(|d| !d.is_empty()).map(|d| SampleAxis {
        domain: domain.to_string(),
        unit: match domain {
            "time" => "ms",
            "depth" => "m",
            _ => "",
        }
        .into(),
        first: d[0],
        step: if d.len() > 1 { d[1] - d[0] } else { 1.0 },
    });
    (interval_us, axis)
}

/// A survey of `dims` samples must make no more bricks than arbvis draws.
fn check_bricks(vfile: &Path, dims: [usize; 3]) -> Result<(), StoreError> {
    let bricks = super::brick_counts(dims, BRICK)
        .iter()
        .try_fold(1u64, |n, &c| n.checked_mul(c as u64))
        .filter(|&n| n <= super::check::MAX_BRICKS_PER_LEVEL);
    if bricks.is_none() {
        return Err(StoreError::invalid(
            vfile,
            format!("{dims:?} samples: more bricks than arbvis draws"),
        ));
    }
    Ok(())
}

/// Chunks the variable's cache holds: four rows of chunks along the samples, at least 8,
/// within [`CHUNK_CACHE_BYTES`].
fn cache_capacity(data: &ArrayMeta) -> usize {
    let along = data.shape[2].div_ceil(data.chunks[2]) as usize;
    let chunk_bytes = (data.chunk_elements() * 4).max(1) as u64;
    (4 * along).clamp(8, (CHUNK_CACHE_BYTES / chunk_bytes).max(8) as usize)
}

/// A dimension coordinate as the axes will number it: present (MDIO writes one per
/// dimension), as long as the variable is along it, every value finite, and strictly
/// increasing or strictly decreasing (a repeated or out-of-order value would put two
/// lines of the survey at one place, or lines out of their order). The error names the
/// array and the index.
fn check_coordinate(
    store: &Path,
    values: Option<&[f64]>,
    n: usize,
    name: &str,
    variable: &str,
) -> Result<(), StoreError> {
    let array = store.join(name);
    let Some(v) = values else {
        return Err(StoreError::invalid(
            &array,
            format!(
                "no `{name}` coordinate: {variable} runs along {name}, and an MDIO dataset has one coordinate array per dimension"
            ),
        ));
    };
    let bad = |m: String| Err(StoreError::invalid(&array, m));
    if v.len() != n {
        return bad(format!(
            "{name} has {} values, {variable} {n} along it",
            v.len()
        ));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return bad(format!(
            "{name}[{i}] is {}: coordinates must be finite",
            v[i]
        ));
    }
    let rising = v.len() < 2 || v[1] > v[0];
    if let Some(i) = (1..v.len()).find(|&i| {
        if rising {
            v[i] <= v[i - 1]
        } else {
            v[i] >= v[i - 1]
        }
    }) {
        let what = if v[i] == v[i - 1] {
            "repeats"
        } else {
            "breaks the order of"
        };
        return bad(format!(
            "{name}[{i}] = {} {what} {name}[{}] = {}: coordinates must be unique and {} ",
            v[i],
            i - 1,
            v[i - 1],
            if rising { "increasing" } else { "decreasing" }
        )
        .trim_end()
        .to_string());
    }
    Ok(())
}

/// The trace mask over (inline, crossline).
fn trace_mask(mask: &ArrayMeta, nk: usize, nj: usize) -> Result<Vec<bool>, StoreError> {
    if mask.shape != [nk as u64, nj as u64] {
        return Err(StoreError::invalid(
            &mask.folder,
            format!(
                "the trace mask has shape {:?}, the survey [{nk}, {nj}] traces",
                mask.shape
            ),
        ));
    }
    Ok(read_whole(mask)?.into_iter().map(|v| v != 0.0).collect())
}

/// A chunk of the variable that cannot be read: its own index and file (not the brick
/// being filled, which may span several chunks or lie inside one).
#[derive(Debug)]
pub struct ChunkFailure {
    /// The chunk's index `[inline, crossline, sample]` in the variable's chunk grid.
    pub index: [u64; 3],
    /// Its file.
    pub path: std::path::PathBuf,
    /// What is wrong.
    pub message: String,
}

impl ChunkFailure {
    /// The store's error for it, naming the variable `array`.
    pub fn into_error(self, array: &str) -> StoreError {
        StoreError::Chunk {
            path: self.path,
            array: array.to_string(),
            chunk: self.index,
            message: self.message,
        }
    }
}

impl Mdio {
    /// The variable's name in the dataset (`amplitude`, `data/chunked_012`).
    pub fn variable(&self) -> String {
        self.data
            .folder
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    }

    /// One decoded chunk of the variable (cached), or its fill where absent.
    fn chunk(&self, index: &[u64; 3]) -> Result<Arc<Vec<f32>>, ChunkFailure> {
        let mut guard = self.cache.lock().expect("MDIO chunk cache");
        let (cache, tick) = &mut *guard;
        *tick += 1;
        if let Some((v, t)) = cache.get_mut(index.as_slice()) {
            *t = *tick;
            return Ok(v.clone());
        }
        let values = match self.data.read_chunk(index).map_err(|e| ChunkFailure {
            index: *index,
            path: self.data.chunk_file(index),
            message: e.to_string(),
        })? {
            Some(v) => v,
            None => vec![self.data.fill_value as f32; self.data.chunk_elements()],
        };
        let values = Arc::new(values);
        if cache.len() >= self.capacity {
            if let Some(oldest) = cache
                .iter()
                .min_by_key(|(_, (_, t))| *t)
                .map(|(k, _)| k.clone())
            {
                cache.remove(&oldest);
            }
        }
        cache.insert(index.to_vec(), (values.clone(), *tick));
        Ok(values)
    }

    /// Samples over the box `lo..hi` (i, j, k) into `out`, whose rows are `sx` and planes
    /// `sx * sy` long; dead traces NaN.
    fn read_box(
        &self,
        dims: [usize; 3],
        lo: [usize; 3],
        hi: [usize; 3],
        out: &mut [f32],
        [sx, sy]: [usize; 2],
    ) -> Result<(), ChunkFailure> {
        let [ci, cj, ck] = [
            self.data.chunks[2],
            self.data.chunks[1],
            self.data.chunks[0],
        ]
        .map(|n| n as usize);
        for k in lo[2]..hi[2] {
            for j in lo[1]..hi[1] {
                let dead = self.live.as_ref().is_some_and(|l| !l[k * dims[1] + j]);
                let row = sx * ((j - lo[1]) + sy * (k - lo[2]));
                let mut i = lo[0];
                while i < hi[0] {
                    let index = [(k / ck) as u64, (j / cj) as u64, (i / ci) as u64];
                    let run = (ci - i % ci).min(hi[0] - i);
                    if dead {
                        out[row + i - lo[0]..][..run].fill(f32::NAN);
                    } else {
                        let chunk = self.chunk(&index)?;
                        let at = (i % ci) + ci * ((j % cj) + cj * (k % ck));
                        out[row + i - lo[0]..][..run].copy_from_slice(&chunk[at..at + run]);
                    }
                    i += run;
                }
            }
        }
        Ok(())
    }

    /// Brick `c` (`[i, j, k]` in bricks of `b`): `b³` values, i fastest, from the chunks
    /// it overlaps; dead traces NaN; beyond the survey 0.
    pub fn brick(
        &self,
        dims: [usize; 3],
        b: usize,
        c: [usize; 3],
    ) -> Result<Vec<f32>, ChunkFailure> {
        let lo = c.map(|x| x * b);
        let hi: [usize; 3] = std::array::from_fn(|a| ((c[a] + 1) * b).min(dims[a]));
        let mut out = vec![0f32; b * b * b];
        self.read_box(dims, lo, hi, &mut out, [b, b])?;
        Ok(out)
    }

    /// Every sample of crosslines `j` and inlines `k` (a column of traces), sample fastest,
    /// into `out`.
    pub fn column(
        &self,
        dims: [usize; 3],
        j: std::ops::Range<usize>,
        k: std::ops::Range<usize>,
        out: &mut [f32],
    ) -> Result<(), ChunkFailure> {
        let sy = j.len();
        self.prefetch_box([0, j.start, k.start], [dims[0], j.end, k.end]);
        self.read_box(
            dims,
            [0, j.start, k.start],
            [dims[0], j.end, k.end],
            out,
            [dims[0], sy],
        )
    }

    /// Start fetching the chunks under voxels `lo..hi` (i, j, k), where the dataset is
    /// remote: a column's chunks all at once rather than one after the other.
    fn prefetch_box(&self, lo: [usize; 3], hi: [usize; 3]) {
        if crate::fetch::url_of(&self.data.folder).is_none() || (0..3).any(|a| hi[a] <= lo[a]) {
            return;
        }
        let per = [2, 1, 0].map(|a| self.data.chunks[a] as usize);
        let span = |a: usize| (lo[a] / per[a])..=((hi[a] - 1) / per[a]);
        let mut files = Vec::new();
        for k in span(2) {
            for j in span(1) {
                for i in span(0) {
                    files.push(self.data.chunk_file(&[k as u64, j as u64, i as u64]));
                }
            }
        }
        crate::fetch::prefetch(files);
    }

    /// Bytes the chunk cache may hold at most.
    pub fn cache_bytes(&self) -> u64 {
        (self.capacity * self.data.chunk_elements() * 4) as u64
    }

    /// How many bricks of side `b` a chunk spans across the traces (at least 1): columns
    /// of bricks converted in tiles of this side share their chunks.
    pub fn tile(&self, b: usize) -> usize {
        (self.data.chunks[0].max(self.data.chunks[1]) as usize)
            .div_ceil(b)
            .max(1)
    }

    /// The chunk file holding brick `c`'s first voxel.
    pub fn chunk_file(&self, b: usize, c: [usize; 3]) -> std::path::PathBuf {
        let ch = &self.data.chunks;
        self.data.chunk_file(&[
            (c[2] * b) as u64 / ch[0],
            (c[1] * b) as u64 / ch[1],
            (c[0] * b) as u64 / ch[2],
        ])
    }
}
