//! arbvis from Python (the `arbvis` package's extension module, `arbvis._arbvis`):
//! scenes read and edited as Python values ([`scene`]), renderers that keep their GL
//! context, data and programs between frames and hand back numpy arrays ([`renderer`]),
//! surveys, clouds and meshes handed over in memory ([`volume`], [`cloud`], [`mesh`]), the driver's report ([`info`]), and pictures read, written and compared as the Rust
//! tests compare them ([`images`]). Errors are Python exceptions of arbvis's own types
//! ([`errors`]). The Python side (`python/arbvis/`) adds the pytest plugin and the Dask
//! helper.

#![deny(unsafe_code)]

mod cloud;
mod errors;
mod images;
mod mesh;
mod renderer;
mod scene;
mod surface;
mod tools;
mod volume;

use pyo3::prelude::*;

/// The driver's report as `arbvis info --json` prints it, as a dict: the backend, vendor,
/// renderer, version, limits, and the measured filter and interpolation errors.
#[pyfunction]
#[pyo3(signature = (backend = "egl"))]
fn info<'py>(py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
    let backend = renderer::backend_named(backend)?;
    let report = py
        .detach(|| {
            let headless = arbvis_gl::Headless::new(backend)?;
            let gpu = headless.gpu();
            let filter = gpu.linear_filter_error()?;
            let interpolation = gpu.interpolation_error()?;
            Ok::<_, arbvis_gl::GlError>(arbvis_techniques::info::to_json(
                backend,
                gpu.caps(),
                filter,
                interpolation,
            ))
        })
        .map_err(errors::from_gl)?;
    scene::json_loads(py, &report)
}

/// Refuse, before it is made, a copy of `bytes` that the memory budget does not hold
/// (`what` names it): an `InputError` saying the estimate, the budget and how to raise it.
#[pyfunction]
fn check_budget(what: &str, bytes: u64) -> PyResult<()> {
    arbvis_core::budget::check(what, bytes).map_err(errors::input_error)
}

/// The extension module.
#[pymodule]
fn _arbvis(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<renderer::PyRenderer>()?;
    m.add_class::<volume::PyVolume>()?;
    m.add_class::<cloud::PyCloud>()?;
    m.add_class::<mesh::PyMesh>()?;
    m.add_class::<surface::PySurface>()?;
    m.add_function(wrap_pyfunction!(info, m)?)?;
    m.add_function(wrap_pyfunction!(check_budget, m)?)?;
    m.add_function(wrap_pyfunction!(tools::inspect, m)?)?;
    m.add_function(wrap_pyfunction!(tools::convert, m)?)?;
    m.add_function(wrap_pyfunction!(tools::fetch_stats, m)?)?;
    m.add_function(wrap_pyfunction!(images::read_png, m)?)?;
    m.add_function(wrap_pyfunction!(images::write_png, m)?)?;
    m.add_function(wrap_pyfunction!(images::png_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(images::compare, m)?)?;
    m.add_function(wrap_pyfunction!(images::diff_image, m)?)?;
    Ok(())
}
