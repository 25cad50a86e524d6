//! `arbvis.Mesh`: an unstructured mesh handed over in memory, from numpy arrays or a
//! `meshio.Mesh`, put in a scene wherever a mesh file is named
//! (`scene["technique.cellproj.mesh"] = arbvis.Mesh(points, {"tetra": cells}, {"T": t})`).
//! Its cells are assembled as a file's are ([`arbvis_data::mesh::memory::assemble`]: the
//! same split into tetrahedra, the same checks), shelved under a name the scene gives. The
//! arrays' conversion is done in Python (`arbvis._memory.mesh_parts`).

use std::sync::Arc;

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use arbvis_data::mesh::memory::{self, CellBlock};
use arbvis_data::mesh::{DataArray, Mesh};

use crate::errors;

/// An unstructured mesh in memory: `points` an (N, 3) array, `cells` an (M, 4) array of
/// tetrahedra or a dict of meshio's cell names (`tetra`, `hexahedron`, `wedge`,
/// `pyramid`; surface and line cells are skipped, as in files) to (M, k) arrays, and
/// `point_data` / `cell_data` dicts of arrays of one value (or one row) per point / cell;
/// or a `meshio.Mesh`. Hexahedra, wedges and pyramids are split into tetrahedra as
/// arbvis splits a file's.
#[pyclass(name = "Mesh", module = "arbvis", frozen)]
pub struct PyMesh {
    /// The mesh, shared with the scenes that name it.
    pub mesh: Arc<Mesh>,
    /// Its name in scenes (`{ memory = NAME }`).
    pub name: String,
}

/// An array as `mesh_parts` hands it over: name, components, values (float64, row-major).
type Array<'py> = (String, usize, PyReadonlyArray1<'py, f64>);

/// What `arbvis._memory.mesh_parts` hands over: points (N x 3, float64, C order), the cell
/// blocks (VTK type, points per cell, indices), the point arrays and the cell arrays.
type Parts<'py> = (
    PyReadonlyArray2<'py, f64>,
    Vec<(i64, usize, PyReadonlyArray1<'py, u32>)>,
    Vec<Array<'py>>,
    Vec<Array<'py>>,
);

fn arrays(list: Vec<Array<'_>>) -> PyResult<Vec<DataArray>> {
    list.into_iter()
        .map(|(name, components, values)| {
            Ok(DataArray {
                name,
                components,
                values: values.as_slice().map_err(errors::input_error)?.to_vec(),
            })
        })
        .collect()
}

#[pymethods]
impl PyMesh {
    #[new]
    #[pyo3(signature = (points, cells = None, point_data = None, cell_data = None))]
    fn new(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        cells: Option<&Bound<'_, PyAny>>,
        point_data: Option<&Bound<'_, PyAny>>,
        cell_data: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyMesh> {
        let parts = py
            .import("arbvis._memory")?
            .call_method1("mesh_parts", (points, cells, point_data, cell_data))?;
        let (points, blocks, point_arrays, cell_arrays): Parts<'_> = parts.extract()?;
        let xyz = points.as_slice().map_err(errors::input_error)?;
        let points: Vec<[f64; 3]> = xyz.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        let blocks = blocks
            .into_iter()
            .map(|(vtk_type, nodes, connectivity)| {
                Ok(CellBlock {
                    vtk_type,
                    nodes,
                    connectivity: connectivity
                        .as_slice()
                        .map_err(errors::input_error)?
                        .to_vec(),
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        let (point_arrays, cell_arrays) = (arrays(point_arrays)?, arrays(cell_arrays)?);
        let mesh = py
            .detach(|| memory::assemble(points, &blocks, point_arrays, cell_arrays))
            .map_err(errors::input_error)?;
        let mesh = Arc::new(mesh);
        let name = memory::register(&mesh);
        Ok(PyMesh { mesh, name })
    }

    /// Its name in a scene's TOML (`mesh = { memory = "mesh-1" }`).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The number of tetrahedra its cells became.
    #[getter]
    fn tetrahedra(&self) -> usize {
        self.mesh.tets.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<arbvis.Mesh {} {} points, {} tetrahedra>",
            self.name,
            self.mesh.points.len(),
            self.mesh.tets.len()
        )
    }
}
