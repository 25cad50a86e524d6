//! `arbvis.Cloud`: a point cloud handed over in memory, from numpy arrays or a
//! `laspy.LasData`, put in a scene wherever a cloud file is named
//! (`scene["technique.splats.cloud"] = arbvis.Cloud(xyz, {"intensity": i})`). The points
//! are copied once into a shared cloud shelved under a name
//! ([`arbvis_data::points::memory`]); the scene names it, and keeps it alive. The arrays'
//! conversion is done in Python (`arbvis._memory.cloud_parts`).

use std::sync::Arc;

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use arbvis_data::points::{memory, CloudParts, PointCloud, Values};

use crate::errors;

/// A point cloud in memory: `positions` an N x 3 array of x, y, z (z up, the file's
/// coordinates), `attributes` a dict of N values each (integers stay integers: facies,
/// classes; the rest are floats), `rgb` an N x 3 array of 16-bit colours (8-bit ones
/// are scaled as LAS scales them); or a `laspy.LasData`, read as arbvis reads its LAS file
/// (intensity, classification, returns, GPS time, extra dimensions, colours).
#[pyclass(name = "Cloud", module = "arbvis", frozen)]
pub struct PyCloud {
    /// The points, shared with the scenes that name them.
    pub cloud: Arc<PointCloud>,
    /// Its name in scenes (`{ memory = NAME }`).
    pub name: String,
}

/// What `arbvis._memory.cloud_parts` hands over: positions (N x 3, float64, C order),
/// each attribute's name, whether it holds integers, and its values as float64; colours.
type Parts<'py> = (
    PyReadonlyArray2<'py, f64>,
    Vec<(String, bool, PyReadonlyArray1<'py, f64>)>,
    Option<PyReadonlyArray2<'py, u16>>,
);

#[pymethods]
impl PyCloud {
    #[new]
    #[pyo3(signature = (positions, attributes = None, rgb = None))]
    fn new(
        py: Python<'_>,
        positions: &Bound<'_, PyAny>,
        attributes: Option<&Bound<'_, PyAny>>,
        rgb: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyCloud> {
        let parts = py
            .import("arbvis._memory")?
            .call_method1("cloud_parts", (positions, attributes, rgb))?;
        let (positions, attributes, rgb): Parts<'_> = parts.extract()?;
        let bad = |e: &dyn std::fmt::Display| errors::input_error(format!("cloud: {e}"));
        let xyz = positions.as_slice().map_err(|e| bad(&e))?;
        let positions: Vec<[f64; 3]> = xyz.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        let mut named = Vec::with_capacity(attributes.len());
        for (name, integral, values) in attributes {
            let v = values.as_slice().map_err(|e| bad(&e))?;
            let values = match integral {
                true => Values::Int(v.iter().map(|&x| x as i32).collect()),
                false => Values::Float(v.iter().map(|&x| x as f32).collect()),
            };
            named.push((name, values));
        }
        let rgb = match rgb {
            Some(c) => {
                let c = c.as_slice().map_err(|e| bad(&e))?;
                Some(c.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
            }
            None => None,
        };
        let cloud = PointCloud::from_parts(CloudParts {
            positions,
            attributes: named,
            rgb,
            normals: None,
        })
        .map_err(|e| bad(&e))?;
        let cloud = Arc::new(cloud);
        let name = memory::register(&cloud);
        Ok(PyCloud { cloud, name })
    }

    /// Its name in a scene's TOML (`cloud = { memory = "cloud-1" }`).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The number of points.
    fn __len__(&self) -> usize {
        self.cloud.len()
    }

    /// The attributes' names, in order.
    #[getter]
    fn attributes(&self) -> Vec<String> {
        self.cloud
            .attributes
            .iter()
            .map(|a| a.name.clone())
            .collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "<arbvis.Cloud {} {} points, attributes {:?}>",
            self.name,
            self.cloud.len(),
            self.attributes()
        )
    }
}
