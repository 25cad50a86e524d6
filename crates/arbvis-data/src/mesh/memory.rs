//! Meshes handed over in memory (`arbvis.Mesh`, from numpy arrays or a `meshio.Mesh`),
//! assembled as a file's cells are (each VTK cell kind split into tetrahedra the same
//! way, the same checks, errors naming the cell by index) and shelved by name
//! ([`crate::memory`]): `mesh = { memory = "mesh-1" }`.

use std::path::Path;
use std::sync::Arc;

use super::cells::{vtk_kind, RawCells};
use super::{DataArray, Mesh, MeshError, MeshInfo, ReadArray};
use crate::memory::Shelf;

/// The meshes handed over, by name.
pub static MESHES: Shelf<Mesh> = Shelf::new("mesh");

/// One kind of cell: its VTK type number and the point indices of its cells, `nodes`
/// to a cell.
pub struct CellBlock {
    /// VTK cell type (10 tetrahedron, 12 hexahedron, 13 wedge, 14 pyramid, 11 voxel;
    /// surface, line and vertex cells are skipped as in files).
    pub vtk_type: i64,
    /// Points per cell.
    pub nodes: usize,
    /// `nodes` point indices per cell.
    pub connectivity: Vec<u32>,
}

/// The mesh of `points` and the cells of `blocks` (in order), with arrays of one tuple
/// per point and per cell (the cells of all blocks, in order).
pub fn assemble(
    points: Vec<[f64; 3]>,
    blocks: &[CellBlock],
    point_arrays: Vec<DataArray>,
    cell_arrays: Vec<DataArray>,
) -> Result<Mesh, MeshError> {
    let name = Path::new("mesh");
    let mut raw = RawCells {
        offsets: vec![0],
        indexed: true,
        ..RawCells::default()
    };
    for b in blocks {
        let kind = vtk_kind(b.vtk_type).map_err(|e| {
            MeshError::Invalid(format!("mesh: cells of VTK type {}: {e}", b.vtk_type))
        })?;
        if b.nodes == 0 || !b.connectivity.len().is_multiple_of(b.nodes) {
            return Err(MeshError::Invalid(format!(
                "mesh: {} point indices are no whole cells of {} points",
                b.connectivity.len(),
                b.nodes
            )));
        }
        for cell in b.connectivity.chunks_exact(b.nodes) {
            raw.at.push(raw.kinds.len());
            raw.kinds.push(kind);
            raw.nodes.extend_from_slice(cell);
            raw.offsets.push(raw.nodes.len());
        }
    }
    let read = |arrays: Vec<DataArray>| -> Vec<ReadArray> {
        arrays
            .into_iter()
            .map(|array| ReadArray { array, at: 0 })
            .collect()
    };
    let info = MeshInfo {
        format: "in memory".into(),
        ..MeshInfo::default()
    };
    Mesh::assemble(
        name,
        b"",
        points,
        &raw,
        read(point_arrays),
        read(cell_arrays),
        info,
    )
}

/// Shelve `mesh`; its name.
pub fn register(mesh: &Arc<Mesh>) -> String {
    MESHES.register(mesh)
}

/// The mesh named `name`, a copy.
pub fn load(name: &str) -> Result<Mesh, MeshError> {
    MESHES
        .copy(name)
        .map_err(|e| MeshError::Invalid(e.to_string()))
}
