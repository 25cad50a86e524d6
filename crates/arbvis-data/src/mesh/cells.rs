//! Cell types and their conversion to positively oriented tetrahedra.
//!
//! - **Tetrahedra** (VTK 10) are kept; one with a negative signed volume gets its last two
//!   vertices swapped, and is counted in [`MeshInfo::flipped`](super::MeshInfo).
//! - **Hexahedra, voxels, wedges (prisms) and pyramids** (VTK 12, 11, 13, 14) are split
//!   so that neighbouring cells agree on their shared faces in any unstructured mesh.
//!   The rule is the one of Dompierre, Labbé, Vallet and Camarero, "How to subdivide
//!   pyramids, prisms and hexahedra into tetrahedra" (IMR 1999): *every quadrilateral face
//!   is cut along the diagonal through its vertex of smallest global index*. Since that
//!   choice depends only on the face's own four indices, the two cells sharing a face cut
//!   it the same way. The tetrahedra are built by the pulling construction from the
//!   cell's vertex `v` of smallest global index: every face not containing `v` is
//!   triangulated by the rule (a triangle stays, a quadrilateral is cut along its
//!   diagonal through its smallest vertex) and each triangle is joined to `v`. On the
//!   faces that do contain `v` this induces exactly the diagonals through `v`, which is
//!   the rule again. A hexahedron gives 6 tetrahedra (Dompierre's tables give 5 in one of
//!   their cases; 6 is as conforming and needs no table), a wedge 3, a pyramid 2. Split
//!   tetrahedra are oriented positively without being counted as flipped; one with a
//!   repeated vertex (a collapsed cell) is dropped and counted in `degenerate_dropped`.
//! - **Quadratic and higher 3D cells** whose first nodes are the corners of a linear cell
//!   (VTK 24 quadratic tetra, 25 quadratic hexahedron, 26 quadratic wedge, 27 quadratic
//!   pyramid, 29 triquadratic hexahedron, 32 biquadratic-quadratic wedge; gmsh 11, 12,
//!   13, 14, 17, 18, 19) use their corner nodes only.
//! - **Vertices, lines, triangles, quadrilaterals** and their quadratic forms (VTK 0–9,
//!   21–23, 28, 30, 34, 35) are skipped and counted.
//! - **Every other type** (polyhedra, Lagrange and Bézier cells, ...) is refused, naming
//!   its number, its VTK name and the cell.

use super::{CellCount, MeshError};

/// What a cell becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// Not a volume cell: skipped and counted.
    Skip,
    /// A tetrahedron (first 4 nodes).
    Tet,
    /// A hexahedron (first 8 nodes, VTK order).
    Hex,
    /// A VTK voxel (8 nodes in x-fastest order).
    Voxel,
    /// A wedge / prism (first 6 nodes: two triangles, node i above node i-3).
    Wedge,
    /// A pyramid (first 5 nodes: the base quadrilateral, then the apex).
    Pyramid,
}

/// A cell type as read from a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Kind {
    /// Its name (the VTK name; gmsh types without a VTK twin are named by gmsh).
    pub name: &'static str,
    /// What it becomes.
    pub shape: Shape,
    /// Nodes it must have (`None`: any number, for poly-vertices, polylines, polygons).
    pub nodes: Option<usize>,
    /// A quadratic or higher cell reduced to its corners.
    pub higher_order: bool,
}

const fn kind(name: &'static str, shape: Shape, nodes: usize, higher_order: bool) -> Kind {
    Kind {
        name,
        shape,
        nodes: Some(nodes),
        higher_order,
    }
}

const fn var(name: &'static str) -> Kind {
    Kind {
        name,
        shape: Shape::Skip,
        nodes: None,
        higher_order: false,
    }
}

/// The VTK name of cell type `t`, for messages (`None` for numbers VTK does not use).
pub fn vtk_name(t: i64) -> Option<&'static str> {
    Some(match t {
        0 => "VTK_EMPTY_CELL",
        1 => "VTK_VERTEX",
        2 => "VTK_POLY_VERTEX",
        3 => "VTK_LINE",
        4 => "VTK_POLY_LINE",
        5 => "VTK_TRIANGLE",
        6 => "VTK_TRIANGLE_STRIP",
        7 => "VTK_POLYGON",
        8 => "VTK_PIXEL",
        9 => "VTK_QUAD",
        10 => "VTK_TETRA",
        11 => "VTK_VOXEL",
        12 => "VTK_HEXAHEDRON",
        13 => "VTK_WEDGE",
        14 => "VTK_PYRAMID",
        15 => "VTK_PENTAGONAL_PRISM",
        16 => "VTK_HEXAGONAL_PRISM",
        21 => "VTK_QUADRATIC_EDGE",
        22 => "VTK_QUADRATIC_TRIANGLE",
        23 => "VTK_QUADRATIC_QUAD",
        24 => "VTK_QUADRATIC_TETRA",
        25 => "VTK_QUADRATIC_HEXAHEDRON",
        26 => "VTK_QUADRATIC_WEDGE",
        27 => "VTK_QUADRATIC_PYRAMID",
        28 => "VTK_BIQUADRATIC_QUAD",
        29 => "VTK_TRIQUADRATIC_HEXAHEDRON",
        30 => "VTK_QUADRATIC_LINEAR_QUAD",
        31 => "VTK_QUADRATIC_LINEAR_WEDGE",
        32 => "VTK_BIQUADRATIC_QUADRATIC_WEDGE",
        33 => "VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON",
        34 => "VTK_BIQUADRATIC_TRIANGLE",
        35 => "VTK_CUBIC_LINE",
        36 => "VTK_QUADRATIC_POLYGON",
        37 => "VTK_TRIQUADRATIC_PYRAMID",
        41 => "VTK_CONVEX_POINT_SET",
        42 => "VTK_POLYHEDRON",
        51 => "VTK_PARAMETRIC_CURVE",
        52 => "VTK_PARAMETRIC_SURFACE",
        53 => "VTK_PARAMETRIC_TRI_SURFACE",
        54 => "VTK_PARAMETRIC_QUAD_SURFACE",
        55 => "VTK_PARAMETRIC_TETRA_REGION",
        56 => "VTK_PARAMETRIC_HEX_REGION",
        60 => "VTK_HIGHER_ORDER_EDGE",
        61 => "VTK_HIGHER_ORDER_TRIANGLE",
        62 => "VTK_HIGHER_ORDER_QUAD",
        63 => "VTK_HIGHER_ORDER_POLYGON",
        64 => "VTK_HIGHER_ORDER_TETRAHEDRON",
        65 => "VTK_HIGHER_ORDER_WEDGE",
        66 => "VTK_HIGHER_ORDER_PYRAMID",
        67 => "VTK_HIGHER_ORDER_HEXAHEDRON",
        68 => "VTK_LAGRANGE_CURVE",
        69 => "VTK_LAGRANGE_TRIANGLE",
        70 => "VTK_LAGRANGE_QUADRILATERAL",
        71 => "VTK_LAGRANGE_TETRAHEDRON",
        72 => "VTK_LAGRANGE_HEXAHEDRON",
        73 => "VTK_LAGRANGE_WEDGE",
        74 => "VTK_LAGRANGE_PYRAMID",
        75 => "VTK_BEZIER_CURVE",
        76 => "VTK_BEZIER_TRIANGLE",
        77 => "VTK_BEZIER_QUADRILATERAL",
        78 => "VTK_BEZIER_TETRAHEDRON",
        79 => "VTK_BEZIER_HEXAHEDRON",
        80 => "VTK_BEZIER_WEDGE",
        81 => "VTK_BEZIER_PYRAMID",
        _ => return None,
    })
}

/// A cell type arbvis does not read, as a file's reader reports it (with the cell's
/// position).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum UnsupportedCell {
    /// A VTK cell type (legacy `.vtk`, `.vtu`).
    #[error(
        "cell type {0} ({name}) is not supported: arbvis reads tetrahedra, hexahedra, voxels, \
         wedges, pyramids and their quadratic forms, and skips points, lines and faces",
        name = vtk_name(*.0).unwrap_or("not a VTK cell type")
    )]
    Vtk(i64),
    /// A gmsh element type (`.msh`).
    #[error(
        "gmsh element type {0} ({name}) is not supported: arbvis reads tetrahedra (4, 11), \
         hexahedra (5, 12, 17), prisms (6, 13, 18), pyramids (7, 14, 19) and skips points, \
         lines and faces",
        name = gmsh_name(*.0)
    )]
    Gmsh(i64),
}

/// The cell kind of VTK type `t`, or the refused type.
pub fn vtk_kind(t: i64) -> Result<Kind, UnsupportedCell> {
    use Shape::*;
    Ok(match t {
        0 => kind("VTK_EMPTY_CELL", Skip, 0, false),
        1 => kind("VTK_VERTEX", Skip, 1, false),
        2 => var("VTK_POLY_VERTEX"),
        3 => kind("VTK_LINE", Skip, 2, false),
        4 => var("VTK_POLY_LINE"),
        5 => kind("VTK_TRIANGLE", Skip, 3, false),
        6 => var("VTK_TRIANGLE_STRIP"),
        7 => var("VTK_POLYGON"),
        8 => kind("VTK_PIXEL", Skip, 4, false),
        9 => kind("VTK_QUAD", Skip, 4, false),
        10 => kind("VTK_TETRA", Tet, 4, false),
        11 => kind("VTK_VOXEL", Voxel, 8, false),
        12 => kind("VTK_HEXAHEDRON", Hex, 8, false),
        13 => kind("VTK_WEDGE", Wedge, 6, false),
        14 => kind("VTK_PYRAMID", Pyramid, 5, false),
        21 => kind("VTK_QUADRATIC_EDGE", Skip, 3, false),
        22 => kind("VTK_QUADRATIC_TRIANGLE", Skip, 6, false),
        23 => kind("VTK_QUADRATIC_QUAD", Skip, 8, false),
        24 => kind("VTK_QUADRATIC_TETRA", Tet, 10, true),
        25 => kind("VTK_QUADRATIC_HEXAHEDRON", Hex, 20, true),
        26 => kind("VTK_QUADRATIC_WEDGE", Wedge, 15, true),
        27 => kind("VTK_QUADRATIC_PYRAMID", Pyramid, 13, true),
        28 => kind("VTK_BIQUADRATIC_QUAD", Skip, 9, false),
        29 => kind("VTK_TRIQUADRATIC_HEXAHEDRON", Hex, 27, true),
        30 => kind("VTK_QUADRATIC_LINEAR_QUAD", Skip, 6, false),
        32 => kind("VTK_BIQUADRATIC_QUADRATIC_WEDGE", Wedge, 18, true),
        34 => kind("VTK_BIQUADRATIC_TRIANGLE", Skip, 7, false),
        35 => kind("VTK_CUBIC_LINE", Skip, 4, false),
        _ => return Err(UnsupportedCell::Vtk(t)),
    })
}

/// The cell kind of gmsh element type `t`, or the refused type.
pub fn gmsh_kind(t: i64) -> Result<Kind, UnsupportedCell> {
    use Shape::*;
    Ok(match t {
        1 => kind("VTK_LINE", Skip, 2, false),
        2 => kind("VTK_TRIANGLE", Skip, 3, false),
        3 => kind("VTK_QUAD", Skip, 4, false),
        4 => kind("VTK_TETRA", Tet, 4, false),
        5 => kind("VTK_HEXAHEDRON", Hex, 8, false),
        6 => kind("VTK_WEDGE", Wedge, 6, false),
        7 => kind("VTK_PYRAMID", Pyramid, 5, false),
        8 => kind("VTK_QUADRATIC_EDGE", Skip, 3, false),
        9 => kind("VTK_QUADRATIC_TRIANGLE", Skip, 6, false),
        10 => kind("VTK_BIQUADRATIC_QUAD", Skip, 9, false),
        11 => kind("VTK_QUADRATIC_TETRA", Tet, 10, true),
        12 => kind("VTK_TRIQUADRATIC_HEXAHEDRON", Hex, 27, true),
        13 => kind("VTK_BIQUADRATIC_QUADRATIC_WEDGE", Wedge, 18, true),
        14 => kind("gmsh 14-node pyramid", Pyramid, 14, true),
        15 => kind("VTK_VERTEX", Skip, 1, false),
        16 => kind("VTK_QUADRATIC_QUAD", Skip, 8, false),
        17 => kind("VTK_QUADRATIC_HEXAHEDRON", Hex, 20, true),
        18 => kind("VTK_QUADRATIC_WEDGE", Wedge, 15, true),
        19 => kind("VTK_QUADRATIC_PYRAMID", Pyramid, 13, true),
        20 => kind("gmsh 9-node triangle", Skip, 9, false),
        21 => kind("gmsh 10-node triangle", Skip, 10, false),
        26 => kind("VTK_CUBIC_LINE", Skip, 4, false),
        _ => return Err(UnsupportedCell::Gmsh(t)),
    })
}

fn gmsh_name(t: i64) -> &'static str {
    match t {
        22..=25 => "a higher-order triangle",
        27 | 28 => "a higher-order line",
        29..=31 => "a higher-order tetrahedron",
        32..=91 => "a higher-order or incomplete element",
        92 | 93 => "a higher-order hexahedron",
        _ => "not a gmsh element type",
    }
}

/// Cells as read, before conversion: kind, node indices and where each cell was read.
#[derive(Debug, Default)]
pub struct RawCells {
    /// Each cell's kind.
    pub kinds: Vec<Kind>,
    /// Start of each cell's nodes in `nodes`, plus the end (`kinds.len() + 1` entries).
    pub offsets: Vec<usize>,
    /// Point indices (0-based, not yet checked against the point count).
    pub nodes: Vec<u32>,
    /// Where each cell's node list was read (for errors): a byte offset, or with
    /// `token_base` the index of its first token counted from that byte.
    pub at: Vec<usize>,
    /// For ASCII lists: the byte where the token counting of `at` starts.
    pub token_base: Option<usize>,
    /// Whether those offsets lie in text (line and column are given) or binary data.
    pub text: bool,
    /// Whether `at` holds cell indices (cells handed over in memory, no file).
    pub indexed: bool,
}

/// Tetrahedra built from cells.
#[derive(Debug, Default)]
pub struct Converted {
    /// Positively oriented tetrahedra.
    pub tets: Vec<[u32; 4]>,
    /// The cell each tetrahedron came from.
    pub source_cell: Vec<u32>,
    /// Cells read, by kind name, in order of first appearance.
    pub cells: Vec<CellCount>,
    /// Cells split into tetrahedra.
    pub split: usize,
    /// Points, lines and faces skipped.
    pub skipped: usize,
    /// Quadratic or higher cells reduced to their corners.
    pub reduced: usize,
    /// File tetrahedra whose vertex order was reversed.
    pub flipped: usize,
    /// Split tetrahedra dropped because a collapsed cell repeated a vertex.
    pub degenerate_dropped: usize,
}

/// Six times the signed volume of tetrahedron `t` (in the file's units; infinite or NaN
/// when that overflows: [`det_scaled`] does not).
pub fn det(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    det_scaled(points, t, 1.0)
}

/// Six times the signed volume of tetrahedron `t` with every coordinate multiplied by
/// `scale` first. With a power of two (see [`unit_scale`]) the products are exact, so
/// this is the file's determinant times `scale³`, without overflow when the scaled
/// coordinates are at most 1 in magnitude.
pub fn det_scaled(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> f64 {
    let p = t.map(|i| points[i as usize].map(|c| c * scale));
    let a = sub(p[1], p[0]);
    let b = sub(p[2], p[0]);
    let c = sub(p[3], p[0]);
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The power of two `2^-e` that brings `largest` (a largest coordinate magnitude) into
/// `[0.5, 1)`; 1 for 0 and for values that are not finite. Multiplying by it is exact
/// (for normal numbers), so volumes, extents and orientations can be computed on scaled
/// coordinates without overflow near 1.7e308 or underflow near 1e-308.
pub fn unit_scale(largest: f64) -> f64 {
    if !(largest.is_finite() && largest > 0.0) {
        return 1.0;
    }
    // largest = m 2^e with m in [0.5, 1): e - 1 is the biased exponent field minus 1022.
    let field = ((largest.to_bits() >> 52) & 0x7ff) as i32;
    let e = if field == 0 {
        // Subnormal: the scale 2^1022 brings it to at least 2^-52, far from underflow.
        -1021
    } else {
        field - 1022
    };
    let exp = (-e).clamp(-1022, 1023);
    f64::from_bits(((exp + 1023) as u64) << 52)
}

/// The base-2 logarithm of a [`unit_scale`] (an exact integer).
pub fn scale_log2(scale: f64) -> i32 {
    ((scale.to_bits() >> 52) & 0x7ff) as i32 - 1023
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `t` with a positive volume (last two vertices swapped when negative); true if swapped.
/// The sign comes from coordinates scaled by the tetrahedron's own [`unit_scale`], so it
/// is right for coordinates near ±1.7e308 too.
pub fn orient(points: &[[f64; 3]], t: [u32; 4]) -> ([u32; 4], bool) {
    let largest = t
        .iter()
        .flat_map(|&i| points[i as usize])
        .fold(0.0f64, |m, c| m.max(c.abs()));
    if det_scaled(points, t, unit_scale(largest)) < 0.0 {
        ([t[0], t[1], t[3], t[2]], true)
    } else {
        (t, false)
    }
}

/// Faces of the linear cells, local node numbers in cyclic order.
const HEX_FACES: [&[usize]; 6] = [
    &[0, 1, 2, 3],
    &[4, 5, 6, 7],
    &[0, 1, 5, 4],
    &[1, 2, 6, 5],
    &[2, 3, 7, 6],
    &[3, 0, 4, 7],
];
const WEDGE_FACES: [&[usize]; 5] = [
    &[0, 1, 2],
    &[3, 4, 5],
    &[0, 1, 4, 3],
    &[1, 2, 5, 4],
    &[2, 0, 3, 5],
];
const PYRAMID_FACES: [&[usize]; 5] = [
    &[0, 1, 2, 3],
    &[0, 1, 4],
    &[1, 2, 4],
    &[2, 3, 4],
    &[3, 0, 4],
];

/// Split a cell with corner nodes `v` (global indices) and faces `faces` into
/// tetrahedra by the smallest-index rule (see the module doc); unoriented.
pub fn split(v: &[u32], faces: &[&[usize]], out: &mut Vec<[u32; 4]>) {
    let apex = (0..v.len()).min_by_key(|&i| v[i]).unwrap_or(0);
    for f in faces {
        if f.contains(&apex) {
            continue;
        }
        let g: Vec<u32> = f.iter().map(|&i| v[i]).collect();
        if g.len() == 3 {
            out.push([v[apex], g[0], g[1], g[2]]);
        } else {
            let m = (0..4).min_by_key(|&i| g[i]).unwrap_or(0);
            let q = |k: usize| g[(m + k) % 4];
            out.push([v[apex], q(0), q(1), q(2)]);
            out.push([v[apex], q(0), q(2), q(3)]);
        }
    }
}

/// Faces of a shape (None for tetrahedra and skipped cells).
pub fn faces(shape: Shape) -> Option<&'static [&'static [usize]]> {
    match shape {
        Shape::Hex | Shape::Voxel => Some(&HEX_FACES),
        Shape::Wedge => Some(&WEDGE_FACES),
        Shape::Pyramid => Some(&PYRAMID_FACES),
        Shape::Tet | Shape::Skip => None,
    }
}

impl RawCells {
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.kinds.len()
    }

    /// True when there are no cells.
    pub fn is_empty(&self) -> bool {
        self.kinds.is_empty()
    }

    /// The most tetrahedra the cells can become (hexahedra and voxels 6, wedges 3,
    /// pyramids 2, tetrahedra 1), to check the memory before converting.
    pub fn most_tets(&self) -> usize {
        self.kinds
            .iter()
            .map(|k| match k.shape {
                Shape::Tet => 1,
                Shape::Hex | Shape::Voxel => 6,
                Shape::Wedge => 3,
                Shape::Pyramid => 2,
                Shape::Skip => 0,
            })
            .sum()
    }

    /// Convert to tetrahedra over `points`, checking node counts and indices. A file with
    /// no tetrahedra left (no volume cells, or only collapsed ones) is an error that names
    /// the first collapsed cell.
    pub fn convert(
        &self,
        name: &std::path::Path,
        bytes: &[u8],
        points: &[[f64; 3]],
    ) -> Result<Converted, MeshError> {
        let err = |i: usize, m: String| {
            let mut at = self.at.get(i).copied().unwrap_or(0);
            if let Some(base) = self.token_base {
                at = super::read::nth_token(bytes, base, at);
            }
            if self.indexed {
                super::MeshError::Format {
                    path: name.to_path_buf(),
                    at: super::Position::Cell(at as u64),
                    message: m,
                }
            } else if self.text {
                super::read::text_error(name, bytes, at, m)
            } else {
                super::read::binary_error(name, at, m)
            }
        };
        let most = self.most_tets();
        let what = format!(
            "making the tetrahedra of {} cells (at most {most})",
            self.len()
        );
        let budget_err = |e: arbvis_core::budget::OverBudget| err(0, e.to_string());
        let mut out = Converted {
            tets: arbvis_core::budget::vec_for(most, &what).map_err(budget_err)?,
            source_cell: arbvis_core::budget::vec_for(most, &what).map_err(budget_err)?,
            ..Converted::default()
        };
        let mut names: Vec<(&'static str, usize)> = Vec::new();
        let mut scratch = Vec::with_capacity(6);
        let mut volume_cells = 0usize;
        let mut first_collapsed = None;
        for (i, k) in self.kinds.iter().enumerate() {
            let (s, e) = (self.offsets[i], self.offsets[i + 1]);
            let nodes = &self.nodes[s..e];
            if let Some(n) = k.nodes {
                if nodes.len() != n {
                    return Err(err(
                        i,
                        format!(
                            "cell {i} is a {} and needs {n} points, but the file gives {}",
                            k.name,
                            nodes.len()
                        ),
                    ));
                }
            }
            if let Some(&bad) = nodes.iter().find(|&&p| p as usize >= points.len()) {
                return Err(err(
                    i,
                    format!(
                        "cell {i} ({}) refers to point {bad}, but there are only {} points (0 to {})",
                        k.name,
                        points.len(),
                        points.len() as i64 - 1
                    ),
                ));
            }
            match names.iter_mut().find(|(n, _)| *n == k.name) {
                Some(c) => c.1 += 1,
                None => names.push((k.name, 1)),
            }
            if k.higher_order {
                out.reduced += 1;
            }
            let cell = i as u32;
            scratch.clear();
            let corners: Vec<u32> = match k.shape {
                Shape::Skip => {
                    out.skipped += 1;
                    continue;
                }
                Shape::Tet => {
                    scratch.push([nodes[0], nodes[1], nodes[2], nodes[3]]);
                    nodes[..4].to_vec()
                }
                Shape::Voxel => [0, 1, 3, 2, 4, 5, 7, 6].iter().map(|&j| nodes[j]).collect(),
                Shape::Hex => nodes[..8].to_vec(),
                Shape::Wedge => nodes[..6].to_vec(),
                Shape::Pyramid => nodes[..5].to_vec(),
            };
            volume_cells += 1;
            if k.shape != Shape::Tet {
                out.split += 1;
                split(&corners, faces(k.shape).unwrap_or(&[]), &mut scratch);
            }
            let before = out.tets.len();
            for &t in &scratch {
                if (0..4).any(|a| (a + 1..4).any(|b| t[a] == t[b])) {
                    out.degenerate_dropped += 1;
                    continue;
                }
                let (t, flipped) = orient(points, t);
                if k.shape == Shape::Tet {
                    out.flipped += usize::from(flipped);
                }
                out.tets.push(t);
                out.source_cell.push(cell);
            }
            if out.tets.len() == before && first_collapsed.is_none() {
                first_collapsed = Some((i, corners));
            }
        }
        out.cells = names
            .into_iter()
            .map(|(name, count)| CellCount {
                name: name.to_string(),
                count,
            })
            .collect();
        if out.tets.is_empty() {
            let held: Vec<String> = out
                .cells
                .iter()
                .map(|k| format!("{}: {}", k.name, k.count))
                .collect();
            return Err(match first_collapsed {
                Some((i, corners)) => err(
                    i,
                    format!(
                        "no tetrahedra: all {volume_cells} volume cells are collapsed (degenerate): each repeats points so that every tetrahedron it splits into has a repeated corner; the first is cell {i} ({}) with points {corners:?}",
                        self.kinds[i].name
                    ),
                ),
                None => err(
                    0,
                    format!(
                        "no volume cells (tetrahedra, hexahedra, voxels, wedges, pyramids): the file holds {}",
                        if held.is_empty() {
                            "no cells".to_string()
                        } else {
                            held.join(", ")
                        }
                    ),
                ),
            });
        }
        Ok(out)
    }
}
