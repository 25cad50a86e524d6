//! `arbvis.Surface`: a triangle surface handed over in memory, from numpy arrays of
//! vertices and triangles or a 2D grid of heights (a horizon as interpretation tools hold
//! it), put in a scene wherever a surface file is named
//! (`scene["layer.1.surface.file"] = arbvis.Surface(vertices, triangles)`). The arrays'
//! checks and the grid's triangles are made in Python (`arbvis._memory`).

use std::sync::Arc;

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use arbvis_data::surface::{TriangleMesh, VertexProperty, SURFACES};

use crate::errors;

/// A triangle surface in memory: `vertices` an (N, 3) array (x, y, z up, the data's own
/// coordinates), `triangles` an (M, 3) array of vertex indices, `properties` a dict of
/// values per vertex (N each, NaN for none) that `colour_by = { property = NAME }` reads.
/// Copied once.
#[pyclass(name = "Surface", module = "arbvis", frozen)]
pub struct PySurface {
    /// The surface, shared with the scenes that name it.
    pub surface: Arc<TriangleMesh>,
    /// Its name in scenes (`{ memory = NAME }`).
    pub name: String,
}

impl PySurface {
    fn of(parts: &Bound<'_, PyAny>, properties: &Bound<'_, PyAny>) -> PyResult<PySurface> {
        let (vertices, triangles): (PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, u32>) =
            parts.extract()?;
        let xyz = vertices.as_slice().map_err(errors::input_error)?;
        let tri = triangles.as_slice().map_err(errors::input_error)?;
        let vertices: Vec<[f64; 3]> = xyz.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        let polygons = tri.chunks_exact(3);
        let named: Vec<(String, PyReadonlyArray1<'_, f64>)> = properties.extract()?;
        let mut properties = Vec::with_capacity(named.len());
        for (name, values) in named {
            let values = values.as_slice().map_err(errors::input_error)?.to_vec();
            properties.push(VertexProperty { name, values });
        }
        let name = std::path::Path::new("surface");
        let mesh = TriangleMesh::from_indexed(name, vertices, polygons)
            .and_then(|mesh| mesh.with_properties(name, properties))
            .map_err(|e| errors::input_error(format!("surface: {e}")))?;
        let surface = Arc::new(mesh);
        let name = SURFACES.register(&surface);
        Ok(PySurface { surface, name })
    }
}

#[pymethods]
impl PySurface {
    #[new]
    #[pyo3(signature = (vertices, triangles, properties = None))]
    fn new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        properties: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PySurface> {
        let memory = py.import("arbvis._memory")?;
        let parts = memory.call_method1("surface_parts", (vertices, triangles))?;
        let n = parts.get_item(0)?.len()?;
        let properties = memory.call_method1("surface_properties", (properties, n))?;
        PySurface::of(&parts, &properties)
    }

    /// A surface from a 2D grid of heights `z[i, j]` at (`x[i]`, `y[j]`) (index numbers
    /// where not given): two triangles a cell, where its corners are defined (NaN leaves
    /// a node out). A horizon in time is given as `-time` (z up, time down).
    /// `properties`: a dict of arrays of `z`'s shape, values at the nodes.
    #[staticmethod]
    #[pyo3(signature = (z, x = None, y = None, properties = None))]
    fn grid(
        py: Python<'_>,
        z: &Bound<'_, PyAny>,
        x: Option<&Bound<'_, PyAny>>,
        y: Option<&Bound<'_, PyAny>>,
        properties: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PySurface> {
        let memory = py.import("arbvis._memory")?;
        let (vertices, triangles, kept) = memory
            .call_method1("grid_surface", (z, x, y))?
            .extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyAny>)>()?;
        let parts = memory.call_method1("surface_parts", (vertices, triangles))?;
        let properties = memory.call_method1("grid_properties", (properties, z, kept))?;
        PySurface::of(&parts, &properties)
    }

    /// The names of its vertex properties.
    #[getter]
    fn properties(&self) -> Vec<String> {
        self.surface
            .properties
            .iter()
            .map(|p| p.name.clone())
            .collect()
    }

    /// Its name in scenes.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// Vertices and triangles.
    fn __len__(&self) -> usize {
        self.surface.triangles.len()
    }
}
