//! Generated meshes: a regular grid of `nx x ny x nz` points whose cubes are each split
//! into 6 tetrahedra, with an analytic point field. The seed's test mesh is the default,
//! 17 x 17 x 17 points = 16^3 cubes = 24,576 tetrahedra.
//!
//! Decisions:
//! - Points sit at integer steps scaled so that the longest side spans [0, 1]; the cubes
//!   stay cubes on non-cubic grids. Point `(i, j, k)` has index `i + nx * (j + ny * k)`.
//! - Each cube is split by the Kuhn (Freudenthal) rule: one tetrahedron per ordering of
//!   the three axes, walking from the cube's corner (0,0,0) to (1,1,1) one axis at a time.
//!   Every cube is split the same way, so every face diagonal runs from the face's
//!   (0,0) corner to its (1,1) corner in both cubes that share it: the mesh conforms.
//! - Sizes: at least 2 points per axis, at most [`MAX_GRID_TETS`] tetrahedra.
//! - Fields, each normalized to [0, 1] over the mesh's points (`(f - min) / (max - min)`)
//!   and stored as the mesh's one point array, named after the field. With `c` the box
//!   centre and `(x, y, z)` the point:
//!   - `planar`: `x`. The seed's "planar symmetry" field: the isosurfaces are planes
//!     parallel to the grid's yz faces. On the 17-point grid the isovalue 0.5 lies exactly
//!     on the vertex plane `i = 8` (the degenerate case of isovalues at vertex values).
//!   - `oblique`: `(x + 2y + 3z) / sqrt(14)`: planar symmetry about an oblique normal, so
//!     the planes cut the tetrahedra in general position.
//!   - `spherical`: distance from `c` (the seed's "spherical symmetry").
//!   - `cylindrical`: distance from the axis through `c` parallel to z.
//!   - `saddle`: `(x - cx)^2 - (y - cy)^2`.
//!   - `waves`: `sin(3 pi x) sin(2 pi y) cos(pi z)` (several disjoint isosurface pieces).

use serde::{Deserialize, Serialize};

use super::{CellCount, DataArray, Mesh, MeshError, MeshInfo};

/// Largest generated mesh: 2^24 (16.7 million) tetrahedra, 256 MiB of indices.
pub const MAX_GRID_TETS: u64 = 1 << 24;

/// The analytic fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Field {
    /// `x`: isosurfaces parallel to the grid's yz faces.
    Planar,
    /// A linear function along the oblique normal (1, 2, 3).
    Oblique,
    /// Distance from the box centre.
    #[default]
    Spherical,
    /// Distance from the box's z axis.
    Cylindrical,
    /// `(x - cx)^2 - (y - cy)^2`.
    Saddle,
    /// `sin(3 pi x) sin(2 pi y) cos(pi z)`.
    Waves,
}

impl Field {
    /// Every field, for listings.
    pub const ALL: [Field; 6] = [
        Field::Planar,
        Field::Oblique,
        Field::Spherical,
        Field::Cylindrical,
        Field::Saddle,
        Field::Waves,
    ];

    /// Its lower-case name (also the point array's name).
    pub fn name(self) -> &'static str {
        match self {
            Field::Planar => "planar",
            Field::Oblique => "oblique",
            Field::Spherical => "spherical",
            Field::Cylindrical => "cylindrical",
            Field::Saddle => "saddle",
            Field::Waves => "waves",
        }
    }

    /// The raw (not normalized) value at `p` in a box centred on `c`.
    pub fn value(self, p: [f64; 3], c: [f64; 3]) -> f64 {
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let pi = std::f64::consts::PI;
        match self {
            Field::Planar => p[0],
            Field::Oblique => (p[0] + 2.0 * p[1] + 3.0 * p[2]) / 14f64.sqrt(),
            Field::Spherical => (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(),
            Field::Cylindrical => (d[0] * d[0] + d[1] * d[1]).sqrt(),
            Field::Saddle => d[0] * d[0] - d[1] * d[1],
            Field::Waves => (3.0 * pi * p[0]).sin() * (2.0 * pi * p[1]).sin() * (pi * p[2]).cos(),
        }
    }
}

/// A generated grid, as in a scene: `{ points = [17, 17, 17], field = "spherical" }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Points along x, y, z (at least 2 each).
    #[serde(default = "seed_points")]
    pub points: [usize; 3],
    /// The point field.
    #[serde(default)]
    pub field: Field,
}

fn seed_points() -> [usize; 3] {
    [17, 17, 17]
}

impl Default for GridSpec {
    fn default() -> Self {
        GridSpec {
            points: seed_points(),
            field: Field::default(),
        }
    }
}

/// The six Kuhn tetrahedra of the unit cube, corners numbered `x + 2y + 4z`.
pub const KUHN: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Generate the grid mesh of `spec`.
pub fn generate(spec: &GridSpec) -> Result<Mesh, MeshError> {
    let [nx, ny, nz] = spec.points;
    let cubes = (nx.saturating_sub(1) as u64)
        .checked_mul(ny.saturating_sub(1) as u64)
        .and_then(|c| c.checked_mul(nz.saturating_sub(1) as u64));
    let tets = cubes.and_then(|c| c.checked_mul(6));
    if nx < 2 || ny < 2 || nz < 2 || tets.is_none_or(|t| t > MAX_GRID_TETS) {
        return Err(MeshError::Invalid(format!(
            "grid points {:?}: need at least 2 points per axis and at most {MAX_GRID_TETS} tetrahedra (6 per cube){}",
            spec.points,
            tets.map_or(" (the count overflows)".to_string(), |t| format!(", this grid has {t}"))
        )));
    }
    let step = 1.0 / (nx.max(ny).max(nz) - 1) as f64;
    let mut points = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                points.push([i as f64 * step, j as f64 * step, k as f64 * step]);
            }
        }
    }
    let idx = |i: usize, j: usize, k: usize| (i + nx * (j + ny * k)) as u32;
    let n_cubes = (nx - 1) * (ny - 1) * (nz - 1);
    let mut tets = Vec::with_capacity(6 * n_cubes);
    let mut source_cell = Vec::with_capacity(6 * n_cubes);
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let corner = |c: usize| idx(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                for t in KUHN {
                    let (t, _) = super::cells::orient(&points, t.map(corner));
                    tets.push(t);
                    source_cell.push((i + (nx - 1) * (j + (ny - 1) * k)) as u32);
                }
            }
        }
    }
    let c = [
        (nx - 1) as f64 * step / 2.0,
        (ny - 1) as f64 * step / 2.0,
        (nz - 1) as f64 * step / 2.0,
    ];
    let raw: Vec<f64> = points.iter().map(|&p| spec.field.value(p, c)).collect();
    let values = normalize(&raw);
    Ok(Mesh {
        points,
        tets,
        source_cell,
        point_arrays: vec![DataArray {
            name: spec.field.name().to_string(),
            components: 1,
            values,
        }],
        cell_arrays: Vec::new(),
        info: MeshInfo {
            source: format!(
                "generated grid {}x{}x{} ({})",
                nx,
                ny,
                nz,
                spec.field.name()
            ),
            format: "generated grid".into(),
            version: "-".into(),
            encoding: "Kuhn split, 6 tetrahedra per cube".into(),
            cells: vec![CellCount {
                name: "VTK_VOXEL".into(),
                count: n_cubes,
            }],
            split_cells: n_cubes,
            ..MeshInfo::default()
        },
    })
}

/// `(v - min) / (max - min)`, or all 0 when the values are constant.
fn normalize(v: &[f64]) -> Vec<f64> {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = hi - lo;
    v.iter()
        .map(|&x| {
            if span > 0.0 {
                ((x - lo) / span).clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
        .collect()
}
