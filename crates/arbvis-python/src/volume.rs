//! `arbvis.Volume`: a survey handed over in memory, from a numpy array or an xarray
//! DataArray, put in a scene wherever a volume file is named
//! (`scene["technique.opacity3d.primary.volume"] = arbvis.Volume(cube)`). The samples are
//! copied once into a shared volume registered under a name
//! ([`arbvis_data::volume::memory`]); the scene names it, and keeps it alive.
//!
//! The array's conversion (its dtype, its order, an xarray's dimensions and coordinates)
//! is done in Python (`arbvis._memory.volume_parts`); the proportions are measured here,
//! as an MDIO dataset's are (`survey_spacing`: the trace steps from `cdp_x`/`cdp_y`, a
//! time axis at 2000 m/s).

use std::sync::Arc;

use numpy::{PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use arbvis_data::volume::segy::geometry::{survey_spacing, MapFrame};
use arbvis_data::volume::{memory, Volume};

use crate::errors;

/// A survey in memory: samples indexed `[inline, crossline, sample]` (as `segyio.tools.cube`
/// and mdio give them; C or Fortran order; float32, float64, int8 to int32, uint8 or
/// uint16), with `spacing` `(inline, crossline, sample)` in metres (a time axis in
/// milliseconds: one millisecond of two-way time as one metre, as a SEG-Y is drawn). An
/// `xarray.DataArray` with dimensions `inline`/`iline`, `crossline`/`xline` and
/// `time`/`twt`/`depth`/`sample` gives its own proportions: the sample step from its
/// coordinate, the trace steps from `cdp_x`/`cdp_y` where it has them (else 25 m bins, as
/// a SEG-Y without coordinates). A `spacing` given overrides them.
#[pyclass(name = "Volume", module = "arbvis", frozen)]
pub struct PyVolume {
    /// The samples, shared with the scenes that name it.
    pub volume: Arc<Volume>,
    /// Its name in scenes (`{ memory = NAME }`).
    pub name: String,
}

/// What `arbvis._memory.volume_parts` hands over: the samples as float32 in C order,
/// the spacing given, the map coordinates of the traces and the sample axis.
type Parts<'py> = (
    PyReadonlyArray3<'py, f32>,
    Option<(f64, f64, f64)>,
    Option<(Vec<f64>, Vec<f64>)>,
    Option<(String, f64)>,
);

#[pymethods]
impl PyVolume {
    #[new]
    #[pyo3(signature = (data, spacing = None))]
    fn new(
        py: Python<'_>,
        data: &Bound<'_, PyAny>,
        spacing: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyVolume> {
        let parts = py
            .import("arbvis._memory")?
            .call_method1("volume_parts", (data, spacing))?;
        let (values, spacing, cdp, axis): Parts<'_> = parts.extract()?;
        let [nk, nj, ni] = <[usize; 3]>::try_from(values.shape()).expect("a 3D array");
        let cdp = cdp.map(|(x, y)| [x, y]);
        let spacing = match spacing {
            Some((inline, crossline, sample)) => [sample, crossline, inline],
            None => {
                let axis = axis.as_ref().map(|(domain, step)| (domain.as_str(), *step));
                survey_spacing(cdp.as_ref(), None, [nj, nk], axis)
            }
        };
        let samples = values.as_slice().map_err(errors::input_error)?.to_vec();
        let mut volume = Volume::new([ni, nj, nk], spacing, samples)
            .map_err(|e| errors::input_error(format!("volume: {e}")))?;
        // Placed on the map by its corner traces' cdp_x/cdp_y, as a SEG-Y is.
        volume.map = cdp.as_ref().and_then(|[x, y]| {
            MapFrame::of_corners(nj, nk, |k, j| {
                let t = k * nj + j;
                Some([*x.get(t)?, *y.get(t)?]).filter(|p| p.iter().all(|v| v.is_finite()))
            })
        });
        let volume = Arc::new(volume);
        let name = memory::register(&volume);
        Ok(PyVolume { volume, name })
    }

    /// Its name in a scene's TOML (`volume = { memory = "volume-1" }`).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// `(inlines, crosslines, samples)`.
    #[getter]
    fn shape(&self) -> (usize, usize, usize) {
        let [ni, nj, nk] = self.volume.dims;
        (nk, nj, ni)
    }

    /// Metres per inline, crossline and sample step.
    #[getter]
    fn spacing(&self) -> (f64, f64, f64) {
        let [s, x, i] = self.volume.spacing;
        (i, x, s)
    }

    fn __repr__(&self) -> String {
        let (i, x, s) = self.shape();
        let (di, dx, ds) = self.spacing();
        format!(
            "<arbvis.Volume {} {i}x{x}x{s} (inline, crossline, sample), spacing {di} {dx} {ds} m>",
            self.name
        )
    }
}
