//! Pictures as numpy arrays, for image regression (the pytest plugin): read and write
//! PNGs as arbvis writes them, and compare two pictures with the metric the Rust tests use
//! ([`Image::compare`]: the largest channel difference, RMSE, PSNR, pixels over the
//! tolerance, on 8-bit levels when either side is 8-bit).

use std::path::PathBuf;

use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use arbvis_core::image::Image;
use arbvis_core::png_io;
use arbvis_core::vocab::TargetFormat;

/// An `(height, width, 4)` array (uint8, or float32 in 0..1) as an image.
fn image_of(array: &Bound<'_, PyAny>) -> PyResult<Image> {
    let (format, data, shape) = if let Ok(a) = array.extract::<PyReadonlyArray3<'_, u8>>() {
        let data = a.as_array().iter().map(|&b| b as f32 / 255.0).collect();
        (TargetFormat::Rgba8, data, a.shape().to_vec())
    } else if let Ok(a) = array.extract::<PyReadonlyArray3<'_, f32>>() {
        let data = a.as_array().iter().copied().collect();
        (TargetFormat::Rgba32f, data, a.shape().to_vec())
    } else {
        return Err(PyValueError::new_err(
            "expected a (height, width, 4) numpy array of uint8 or float32",
        ));
    };
    if shape.len() != 3 || shape[2] != 4 {
        return Err(PyValueError::new_err(format!(
            "expected a (height, width, 4) array, got the shape {shape:?}"
        )));
    }
    Ok(Image {
        width: shape[1] as u32,
        height: shape[0] as u32,
        format,
        data,
    })
}

/// An image as 8-bit levels (what a PNG holds), in an RGBA8 array.
fn to_u8_array<'py>(py: Python<'py>, image: &Image) -> Bound<'py, PyAny> {
    let shape = (image.height as usize, image.width as usize, 4);
    Array3::from_shape_vec(shape, image.to_rgba8())
        .expect("4 values a pixel")
        .into_pyarray(py)
        .into_any()
}

/// `image` rounded to 8-bit levels.
fn levels(image: Image) -> Image {
    let data = image.to_rgba8().iter().map(|&b| b as f32 / 255.0).collect();
    Image {
        format: TargetFormat::Rgba8,
        data,
        ..image
    }
}

/// Read a PNG as an `(height, width, 4)` uint8 array.
#[pyfunction]
pub fn read_png(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let (image, _) = png_io::read_png(&path).map_err(crate::errors::input_error)?;
    Ok(to_u8_array(py, &image))
}

/// An `(height, width, 4)` array (uint8, or float32 in 0..1) as the bytes of an 8-bit PNG
/// (what a notebook view sends to the page).
#[pyfunction]
pub fn png_bytes<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, pyo3::types::PyBytes>> {
    let image = levels(image_of(array)?);
    let bytes = png_io::encode_png("picture", &image, &[]).map_err(crate::errors::input_error)?;
    Ok(pyo3::types::PyBytes::new(py, &bytes))
}

/// Write an `(height, width, 4)` array (uint8, or float32 in 0..1) as an 8-bit PNG,
/// atomically.
#[pyfunction]
pub fn write_png(path: PathBuf, array: &Bound<'_, PyAny>) -> PyResult<()> {
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        return Err(PyValueError::new_err(format!(
            "{}: write_png writes PNG files; name it .png",
            path.display()
        )));
    }
    let image = levels(image_of(array)?);
    png_io::write_png(&path, &image, &[]).map_err(crate::errors::input_error)
}

/// How `actual` differs from `expected`, on 8-bit levels (what a PNG holds): a dict of
/// `max_abs`, `rmse`, `psnr`, `pixels_over` (pixels with a channel more than `tolerance`
/// off) and `worst` (x, y). Pictures of different sizes, and a tolerance that is negative
/// or not a number, are a `ValueError`.
#[pyfunction]
#[pyo3(signature = (actual, expected, tolerance = 1.0 / 255.0))]
pub fn compare<'py>(
    py: Python<'py>,
    actual: &Bound<'py, PyAny>,
    expected: &Bound<'py, PyAny>,
    tolerance: f32,
) -> PyResult<Bound<'py, PyDict>> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "tolerance {tolerance}: a difference of 0 or more (1/255 is one 8-bit level)"
        )));
    }
    let (a, e) = (levels(image_of(actual)?), levels(image_of(expected)?));
    let d = a.compare(&e, tolerance).ok_or_else(|| {
        PyValueError::new_err(format!(
            "the pictures' sizes differ: {}x{} and {}x{}",
            a.width, a.height, e.width, e.height
        ))
    })?;
    let out = PyDict::new(py);
    out.set_item("max_abs", d.max_abs)?;
    out.set_item("rmse", d.rmse)?;
    out.set_item("psnr", d.psnr)?;
    out.set_item("pixels_over", d.pixels_over)?;
    out.set_item("worst", d.worst)?;
    Ok(out)
}

/// A diff image of `actual` against `expected`: each pixel's largest channel difference
/// times `gain` as grey, pixels over `tolerance` in red (uint8, opaque).
#[pyfunction]
#[pyo3(signature = (actual, expected, tolerance = 1.0 / 255.0, gain = 16.0))]
pub fn diff_image<'py>(
    py: Python<'py>,
    actual: &Bound<'py, PyAny>,
    expected: &Bound<'py, PyAny>,
    tolerance: f32,
    gain: f32,
) -> PyResult<Bound<'py, PyAny>> {
    let (a, e) = (levels(image_of(actual)?), levels(image_of(expected)?));
    let diff = a
        .diff_image(&e, tolerance, gain)
        .ok_or_else(|| PyValueError::new_err("the images' sizes differ"))?;
    Ok(to_u8_array(py, &diff))
}
