//! Tetrahedral meshes for the cell-projection isosurfaces (seed 001): read from VTK legacy
//! (`.vtk`), VTK XML (`.vtu`) and gmsh (`.msh`) files, or generated (the seed's 17x17x17
//! grid of 24,576 tetrahedra with analytic fields); scalars chosen and normalized per
//! point; tetrahedron quality. No GL here: the renderer builds on [`Mesh`].
//!
//! Decisions taken once for every format:
//! - Points are f64; tetrahedra are `[u32; 4]` point indices, all with a positive signed
//!   volume `det(p1-p0, p2-p0, p3-p0) / 6` (VTK's and gmsh's convention). A file
//!   tetrahedron with a negative volume has its last two vertices swapped and is counted
//!   in [`MeshInfo::flipped`]. Other cells are converted as [`cells`] explains.
//! - Point arrays hold one tuple per point. Cell arrays hold one tuple per *tetrahedron*:
//!   each tetrahedron carries the values of the file cell it came from
//!   ([`Mesh::source_cell`]); values of skipped cells (points, lines, faces) are dropped.
//! - Arrays keep their values as f64, NaN and infinities included; coordinates must be
//!   finite (an error names the point and its position otherwise).
//! - The format is chosen from the content, not the extension: `# vtk DataFile` starts a
//!   legacy file, `<VTKFile` (after an optional XML declaration) an XML file, and
//!   `$MeshFormat` a gmsh file.
//! - Files are read whole through [`arbvis_core::input`], at most [`MAX_MESH_BYTES`].
//! - Sections may come in any order the format allows (gmsh data before `$Nodes`, VTK
//!   `POINT_DATA` before `POINTS`); what refers to another section is checked against it
//!   once both are read, with the file and the position of the one that disagrees, and
//!   [`Mesh::assemble`] refuses any array whose tuple count is not the point or cell
//!   count (it never indexes past one). A section a file may hold once (`POINTS`) is
//!   refused the second time.
//! - Memory: every allocation whose size comes from the file is checked against the
//!   memory budget ([`arbvis_core::budget`]) before it is made, and made fallibly; compressed
//!   `.vtu` arrays are checked against what the piece declares, and the total against
//!   the budget, before anything is inflated. A refusal names the file, the place that
//!   declared the size, the estimate, the budget and how to raise it.
//! - Geometry is computed on coordinates scaled by an exact power of two
//!   ([`cells::unit_scale`]), so coordinates near ±1.7e308 orient, measure and draw.

pub mod cells;
pub mod gmsh;
pub mod grid;
pub mod legacy;
pub mod memory;
pub mod quality;
pub mod read;
pub mod scalars;
pub mod vtu;

#[cfg(test)]
mod tests;

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use arbvis_core::budget;

/// Largest mesh file read (1 GiB).
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// A tetrahedral mesh with named point and cell arrays.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Point coordinates, all finite.
    pub points: Vec<[f64; 3]>,
    /// Tetrahedra as point indices, each with a positive (or zero) signed volume.
    pub tets: Vec<[u32; 4]>,
    /// For each tetrahedron, the index of the file cell it came from.
    pub source_cell: Vec<u32>,
    /// Arrays with one tuple per point.
    pub point_arrays: Vec<DataArray>,
    /// Arrays with one tuple per tetrahedron (copied from the source cell).
    pub cell_arrays: Vec<DataArray>,
    /// Where the mesh came from and what was converted.
    pub info: MeshInfo,
}

/// A named array of `components` values per tuple.
#[derive(Debug, Clone, PartialEq)]
pub struct DataArray {
    /// Its name in the file.
    pub name: String,
    /// Values per tuple (1 for scalars, 3 for vectors, ...).
    pub components: usize,
    /// `tuples * components` values, tuple-major.
    pub values: Vec<f64>,
}

impl DataArray {
    /// Number of tuples.
    pub fn tuples(&self) -> usize {
        self.values.len() / self.components.max(1)
    }
}

/// How many cells of one type were read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CellCount {
    /// The VTK type name (e.g. `VTK_TETRA`; gmsh types without a VTK twin are named by gmsh).
    pub name: String,
    /// How many.
    pub count: usize,
}

/// What was read and converted.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MeshInfo {
    /// The file (or `generated grid`).
    pub source: String,
    /// Format name: `VTK legacy`, `VTK XML UnstructuredGrid`, `gmsh MSH`, `generated grid`.
    pub format: String,
    /// The format version as written in the file (`3.0`, `5.1`, `1.0`, `4.1`, ...).
    pub version: String,
    /// How the data were stored (`ascii`, `binary`, `appended raw, zlib`, ...).
    pub encoding: String,
    /// Cells read, by type, in order of first appearance.
    pub cells: Vec<CellCount>,
    /// Hexahedra, voxels, wedges and pyramids split into tetrahedra.
    pub split_cells: usize,
    /// Points, lines and faces skipped.
    pub skipped_cells: usize,
    /// Quadratic or higher cells reduced to their corner nodes.
    pub reduced_to_corners: usize,
    /// File tetrahedra whose vertex order was reversed to make their volume positive.
    pub flipped: usize,
    /// Tetrahedra dropped because their cell repeated a point (a collapsed cell).
    pub degenerate_dropped: usize,
}

/// Where in a file a problem is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Position {
    /// In text: line and column (1-based; the column counts bytes) and byte offset.
    Text {
        /// Line.
        line: usize,
        /// Column.
        column: usize,
        /// Byte offset from the start of the file.
        byte: u64,
    },
    /// In binary data: byte offset from the start of the file.
    Byte(u64),
    /// The cell of that index (0-based), in cells handed over in memory.
    Cell(u64),
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Text { line, column, byte } => {
                write!(f, "line {line}, column {column} (byte {byte})")
            }
            Position::Byte(b) => write!(f, "at byte {b}"),
            Position::Cell(c) => write!(f, "cell {c}"),
        }
    }
}

/// Errors reading, generating or using meshes.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// The content is not what the format requires.
    #[error("{path}: {at}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// Where.
        at: Position,
        /// What was expected and what was found.
        message: String,
    },
    /// Parameters (a grid size, a field or array name, a range) that cannot be used.
    #[error("{0}")]
    Invalid(String),
}

impl MeshError {
    fn whole_file(path: &Path, message: impl Into<String>) -> MeshError {
        MeshError::Format {
            path: path.to_path_buf(),
            at: Position::Byte(0),
            message: message.into(),
        }
    }
}

/// Where a mesh comes from, as written in a scene:
/// `{ file = "post.vtk" }` or `{ grid = { points = [17, 17, 17], field = "spherical" } }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum MeshSource {
    /// A `.vtk`, `.vtu` or `.msh` file (relative to the scene's folder).
    File(PathBuf),
    /// A generated grid with an analytic field.
    Grid(grid::GridSpec),
    /// A mesh handed over in memory (an `arbvis.Mesh`), by its name ([`memory`]).
    Memory(String),
}

impl MeshSource {
    /// Read or generate the mesh; relative paths are taken from `base`.
    pub fn load(&self, base: &Path) -> Result<Mesh, MeshError> {
        match self {
            MeshSource::File(p) => read(&base.join(p)),
            MeshSource::Grid(spec) => grid::generate(spec),
            MeshSource::Memory(name) => memory::load(name),
        }
    }

    /// The file it names, if any.
    pub fn path(&self) -> Option<&Path> {
        match self {
            MeshSource::File(p) => Some(p),
            MeshSource::Grid(_) | MeshSource::Memory(_) => None,
        }
    }

    /// The file it names, if any, for rewriting.
    pub fn path_mut(&mut self) -> Option<&mut PathBuf> {
        match self {
            MeshSource::File(p) => Some(p),
            MeshSource::Grid(_) | MeshSource::Memory(_) => None,
        }
    }
}

/// Read a mesh file (format from its content).
pub fn read(path: &Path) -> Result<Mesh, MeshError> {
    let bytes =
        arbvis_core::input::read_regular(path, MAX_MESH_BYTES).map_err(|source| MeshError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    parse(path, &bytes)
}

/// Parse a mesh file held in memory; `name` is used in errors. What it may make is
/// bounded by the memory budget, and by default also by the file's size
/// ([`budget::for_input`]).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    budget::for_input(bytes.len() as u64, || parse_format(name, bytes))
}

fn parse_format(name: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    let head = &bytes[..bytes.len().min(4096)];
    let trimmed = head.trim_ascii_start();
    if trimmed.len() >= 14 && trimmed[..14].eq_ignore_ascii_case(b"# vtk DataFile") {
        legacy::parse(name, bytes)
    } else if trimmed.starts_with(b"$MeshFormat") {
        gmsh::parse(name, bytes)
    } else if head.windows(8).any(|w| w == b"<VTKFile") {
        vtu::parse(name, bytes)
    } else {
        Err(MeshError::whole_file(
            name,
            format!(
                "not a mesh file arbvis reads: expected \"# vtk DataFile Version\" (VTK legacy), \"<VTKFile\" (VTK XML .vtu) or \"$MeshFormat\" (gmsh .msh) at the start, found {}",
                read::quote(&trimmed[..trimmed.len().min(30)])
            ),
        ))
    }
}

/// A data array as a loader read it, with the byte where its declaration starts (a
/// section keyword or a tag: always text, in every format), for errors.
#[derive(Debug)]
pub(crate) struct ReadArray {
    /// The array, one tuple per point or per file cell.
    pub array: DataArray,
    /// Where it was declared.
    pub at: usize,
}

impl Mesh {
    /// Assemble a mesh from loader output: checks that every array holds one tuple per
    /// point (per file cell), converts the cells and expands cell arrays to one tuple per
    /// tetrahedron within the memory budget.
    pub(crate) fn assemble(
        name: &Path,
        bytes: &[u8],
        points: Vec<[f64; 3]>,
        raw: &cells::RawCells,
        point_arrays: Vec<ReadArray>,
        cell_arrays: Vec<ReadArray>,
        mut info: MeshInfo,
    ) -> Result<Mesh, MeshError> {
        if points.len() > u32::MAX as usize {
            return Err(MeshError::whole_file(name, "more than 2^32 - 1 points"));
        }
        for (list, want, what) in [
            (&point_arrays, points.len(), "point"),
            (&cell_arrays, raw.len(), "cell"),
        ] {
            for a in list {
                let k = a.array.components;
                if k == 0 || Some(a.array.values.len()) != want.checked_mul(k) {
                    return Err(read::text_error(
                        name,
                        bytes,
                        a.at,
                        format!(
                            "{what} array \"{}\" holds {} values ({} components each), but the mesh has {want} {what}s: one tuple per {what} is needed",
                            a.array.name,
                            a.array.values.len(),
                            k
                        ),
                    ));
                }
            }
        }
        let c = raw.convert(name, bytes, &points)?;
        let per_tet: usize = cell_arrays.iter().map(|a| a.array.components).sum();
        if let Some(first) = cell_arrays.first() {
            let n = c.tets.len();
            let bytes_needed = budget::times(budget::times(n as u64, per_tet as u64), 8);
            budget::check(
                format!(
                    "copying {} cell array{} to each of {n} tetrahedra",
                    cell_arrays.len(),
                    if cell_arrays.len() == 1 { "" } else { "s" }
                ),
                bytes_needed,
            )
            .map_err(|e| read::text_error(name, bytes, first.at, e.to_string()))?;
        }
        let mut expanded = Vec::with_capacity(cell_arrays.len());
        for a in cell_arrays {
            let k = a.array.components;
            let n = c.source_cell.len().saturating_mul(k);
            let mut values = budget::vec_for(n, &format!("cell array \"{}\"", a.array.name))
                .map_err(|e| read::text_error(name, bytes, a.at, e.to_string()))?;
            for &s in &c.source_cell {
                let s = s as usize * k;
                values.extend_from_slice(&a.array.values[s..s + k]);
            }
            expanded.push(DataArray { values, ..a.array });
        }
        info.source = name.display().to_string();
        info.cells = c.cells;
        info.split_cells = c.split;
        info.skipped_cells = c.skipped;
        info.reduced_to_corners = c.reduced;
        info.flipped = c.flipped;
        info.degenerate_dropped = c.degenerate_dropped;
        Ok(Mesh {
            points,
            tets: c.tets,
            source_cell: c.source_cell,
            point_arrays: point_arrays.into_iter().map(|a| a.array).collect(),
            cell_arrays: expanded,
            info,
        })
    }

    /// Smallest and largest coordinates (`None` without points).
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let first = *self.points.first()?;
        Some(self.points.iter().fold((first, first), |(lo, hi), p| {
            (
                std::array::from_fn(|a| lo[a].min(p[a])),
                std::array::from_fn(|a| hi[a].max(p[a])),
            )
        }))
    }

    /// The point array called `name`.
    pub fn point_array(&self, name: &str) -> Option<&DataArray> {
        self.point_arrays.iter().find(|a| a.name == name)
    }

    /// The cell array called `name`.
    pub fn cell_array(&self, name: &str) -> Option<&DataArray> {
        self.cell_arrays.iter().find(|a| a.name == name)
    }
}

/// `arbvis inspect` for a mesh file: format and version, points, cells by type and what
/// was converted, tetrahedra, bounds, each array with its range, orientation and quality.
pub fn inspect(path: &Path) -> Result<String, MeshError> {
    let mesh = read(path)?;
    Ok(describe(&mesh))
}

/// A number as Rust writes it (shortest round trip), in exponent form beyond 1e16 or
/// below 1e-5, where the plain form runs to hundreds of digits.
fn num(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// The report [`inspect`] prints, one item per line.
pub fn describe(mesh: &Mesh) -> String {
    use std::fmt::Write;
    let i = &mesh.info;
    let mut s = String::new();
    let _ = writeln!(s, "{}", i.source);
    let _ = writeln!(s, "format: {} {} ({})", i.format, i.version, i.encoding);
    let _ = writeln!(s, "points: {}", mesh.points.len());
    let total: usize = i.cells.iter().map(|c| c.count).sum();
    let _ = writeln!(s, "cells: {total}");
    for c in &i.cells {
        let _ = writeln!(s, "  {}: {}", c.name, c.count);
    }
    if i.split_cells > 0 {
        let _ = writeln!(
            s,
            "split into tetrahedra: {} cells (quadrilateral faces cut through their smallest vertex)",
            i.split_cells
        );
    }
    if i.reduced_to_corners > 0 {
        let _ = writeln!(
            s,
            "reduced to corner nodes: {} quadratic cells",
            i.reduced_to_corners
        );
    }
    if i.skipped_cells > 0 {
        let _ = writeln!(s, "skipped (points, lines, faces): {}", i.skipped_cells);
    }
    if i.degenerate_dropped > 0 {
        let _ = writeln!(
            s,
            "dropped (tetrahedra with a repeated point, of collapsed cells): {}",
            i.degenerate_dropped
        );
    }
    let _ = writeln!(s, "tetrahedra: {}", mesh.tets.len());
    if let Some((lo, hi)) = mesh.bounds() {
        let _ = writeln!(
            s,
            "bounds: x [{}, {}] y [{}, {}] z [{}, {}]",
            num(lo[0]),
            num(hi[0]),
            num(lo[1]),
            num(hi[1]),
            num(lo[2]),
            num(hi[2])
        );
    }
    for (kind, arrays) in [("point", &mesh.point_arrays), ("cell", &mesh.cell_arrays)] {
        for a in arrays {
            let r = scalars::finite_range(&a.values);
            let range = match r {
                Some((lo, hi)) => format!("range [{}, {}]", num(lo), num(hi)),
                None => "no finite values".to_string(),
            };
            let bad = a.values.iter().filter(|v| !v.is_finite()).count();
            let _ = writeln!(
                s,
                "{kind} array \"{}\": {} component{}, {range}{}",
                a.name,
                a.components,
                if a.components == 1 { "" } else { "s" },
                if bad > 0 {
                    format!(", {bad} NaN or infinite values")
                } else {
                    String::new()
                }
            );
        }
    }
    let q = quality::Quality::of(mesh);
    let _ = writeln!(s, "flipped to positive orientation: {}", i.flipped);
    let cell_of = |t: usize| {
        mesh.source_cell
            .get(t)
            .map_or(String::new(), |c| format!(" from file cell {c}"))
    };
    let _ = writeln!(
        s,
        "flat (degenerate) tetrahedra (|volume| <= 1e-12 x longest edge^3, not drawn): {}{}",
        q.flat,
        q.first_flat.map_or(String::new(), |t| format!(
            ", the first is tetrahedron {t}{}",
            cell_of(t)
        ))
    );
    let _ = writeln!(
        s,
        "repeated tetrahedra (at the place of an earlier one): {}{}",
        q.repeated,
        q.first_repeat.map_or(String::new(), |(t, e)| format!(
            ", the first is tetrahedron {t}{} repeating {e}{}",
            cell_of(t),
            cell_of(e)
        ))
    );
    let _ = writeln!(
        s,
        "sliver tetrahedra (radius ratio < {}): {}",
        quality::SLIVER_RADIUS_RATIO,
        q.slivers
    );
    let _ = writeln!(
        s,
        "depth: a line through the bounding box crosses {:.1} tetrahedra on average",
        q.depth
    );
    let _ = writeln!(
        s,
        "volume: total {}, smallest tetrahedron {}, radius ratio min {:.4}",
        quality::format_pow2(q.scaled_volumes.0, q.volume_log2),
        if mesh.tets.is_empty() {
            "-".to_string()
        } else {
            quality::format_pow2(q.scaled_volumes.1, q.volume_log2)
        },
        q.min_radius_ratio
    );
    s
}
