//! `arbvis.inspect(path)` and `arbvis.convert(src, dst, ...)`: the command line's
//! `inspect` and `convert` (a SEG-Y, raw or MDIO survey into a bricked store), with a
//! progress callback that can stop a conversion (it resumes when run again).

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use arbvis_data::store::compression::UnknownCompression;
use arbvis_data::store::convert::{convert as convert_store, ConvertOptions, Watch};
use arbvis_data::store::StoreError;
use arbvis_data::volume::attributes::{by_name, Attribute};
use arbvis_techniques::inspect::inspect as inspect_file;

use crate::errors::Cancelled;

/// What `arbvis inspect PATH` says of a file or store, as a dict: `path`, each
/// `name: value` line's value under its name (a name said twice: a list), and the whole
/// text under `text`.
#[pyfunction]
pub fn inspect(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let text = py
        .detach(|| inspect_file(&path))
        .map_err(crate::errors::input_error)?;
    let out = PyDict::new(py);
    out.set_item(
        "path",
        arbvis_core::secrets::redact(&path.display().to_string()),
    )?;
    for line in text.lines() {
        let Some((name, value)) = line.split_once(": ") else {
            continue;
        };
        let (name, value) = (name.trim(), value.trim());
        match out.get_item(name)? {
            Some(old) if old.is_instance_of::<PyList>() => {
                old.cast::<PyList>()?.append(value)?;
            }
            Some(old) => out.set_item(
                name,
                PyList::new(py, [old, value.into_pyobject(py)?.into_any()])?,
            )?,
            None => out.set_item(name, value)?,
        }
    }
    out.set_item("text", text)?;
    Ok(out)
}

/// What this process has fetched from remote stores and clouds (`s3://`, `http(s)://`):
/// `requests` sent, `bytes` received, `from_disk` (bytes the disk cache served),
/// `in_flight` (requests under way now) and `loading` (a status line while any are in
/// flight, else None).
#[pyfunction]
pub fn fetch_stats(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let s = arbvis_data::fetch::stats();
    let out = PyDict::new(py);
    out.set_item("requests", s.requests)?;
    out.set_item("bytes", s.bytes)?;
    out.set_item("from_disk", s.from_disk)?;
    out.set_item("in_flight", s.in_flight)?;
    out.set_item("loading", arbvis_data::fetch::status())?;
    Ok(out)
}

/// Convert the survey `src` (SEG-Y, or an MDIO dataset) into the store `dst` (or resume
/// an interrupted conversion there), as `arbvis convert` does: bricks of `brick` voxels,
/// the derived `attributes`, `compression` (`lz4`, `zstd`, `zstd:LEVEL`, `none`).
/// `progress(done, total)` is called after each column of bricks (from the conversion's
/// threads, holding the GIL while it runs); a false return stops the conversion with
/// `arbvis.Cancelled`, and Ctrl-C or an exception the callback raises stops it with that
/// exception (running it again resumes either way). A dict of what was done.
/// A `dst` whose name ends in `.copc.laz` writes the point cloud `src` (LAS, LAZ, PLY) as
/// COPC instead, in nodes of about `node_points` points, as `arbvis convert` does.
#[pyfunction]
#[pyo3(signature = (src, dst, brick = 64, attributes = vec!["envelope".to_string()], compression = "lz4", progress = None, node_points = 100_000))]
#[allow(clippy::too_many_arguments)]
pub fn convert<'py>(
    py: Python<'py>,
    src: PathBuf,
    dst: PathBuf,
    brick: usize,
    attributes: Vec<String>,
    compression: &str,
    progress: Option<Py<PyAny>>,
    node_points: usize,
) -> PyResult<Bound<'py, PyDict>> {
    if dst.to_string_lossy().to_lowercase().ends_with(".copc.laz") {
        return convert_to_copc(py, &src, &dst, node_points);
    }
    let mut derived = Vec::new();
    for name in &attributes {
        match by_name(name) {
            Some(Attribute::Amplitude) | None => {
                return Err(PyValueError::new_err(format!(
                    "attribute {name:?}: derived attributes are envelope, phase, cosine-phase, frequency"
                )))
            }
            Some(a) => derived.push(a),
        }
    }
    let compression = compression
        .parse()
        .map_err(|e: UnknownCompression| PyValueError::new_err(e.to_string()))?;
    // What the callback raised (on a conversion thread), raised here afterwards.
    let raised: Arc<Mutex<Option<PyErr>>> = Arc::default();
    let watch = progress.map(|callback| {
        let raised = raised.clone();
        Watch(Arc::new(move |done, total| {
            Python::attach(|py| {
                let answer = py
                    .check_signals()
                    .and_then(|()| callback.call1(py, (done, total)))
                    .and_then(|a| Ok(a.is_none(py) || a.is_truthy(py)?));
                answer.unwrap_or_else(|e| {
                    raised.lock().expect("one error").get_or_insert(e);
                    false
                })
            })
        }))
    });
    let options = ConvertOptions {
        brick,
        derived,
        compression,
        progress: false,
        watch,
        ..Default::default()
    };
    let report = py.detach(|| convert_store(&src, &dst, &options));
    // A callback that raised (or Ctrl-C): its exception, the store left resumable.
    if let Some(e) = raised.lock().expect("one error").take() {
        return Err(e);
    }
    let report = report.map_err(|e| match e {
        StoreError::Interrupted(m) => Cancelled::new_err(arbvis_core::secrets::redact(&m)),
        e => crate::errors::input_error(e),
    })?;
    let out = PyDict::new(py);
    out.set_item("store", dst.display().to_string())?;
    out.set_item("written", report.written)?;
    out.set_item("resumed", report.resumed)?;
    out.set_item("bytes_read", report.bytes_read)?;
    out.set_item("seconds", report.seconds)?;
    out.set_item("dims", report.meta.dims.to_vec())?;
    out.set_item("levels", report.meta.levels)?;
    Ok(out)
}

/// `convert(cloud, "x.copc.laz")`: the cloud written as COPC; a dict of what was written.
fn convert_to_copc<'py>(
    py: Python<'py>,
    src: &std::path::Path,
    dst: &std::path::Path,
    node_points: usize,
) -> PyResult<Bound<'py, PyDict>> {
    use arbvis_data::points::copc_write::{write_copc, CopcWriteOptions};
    let options = CopcWriteOptions {
        node_points: node_points.max(1),
        ..Default::default()
    };
    let report = py
        .detach(|| write_copc(src, dst, &options))
        .map_err(crate::errors::input_error)?;
    let out = PyDict::new(py);
    out.set_item("copc", dst.display().to_string())?;
    out.set_item("points", report.points)?;
    out.set_item("nodes", report.nodes)?;
    out.set_item("levels", report.depth + 1)?;
    out.set_item("bytes", report.bytes)?;
    Ok(out)
}
