//! CPU preparation for cell projection (no GL): the mesh in the object box, what the
//! seed's vertex program takes for every face vertex, and the `(sf, sb)` table.

use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use super::{first_crossed, CellprojScene, Isovalue};
use crate::error::RenderResult;
use arbvis_data::mesh::quality::{self, Quality};
use arbvis_data::mesh::{Mesh, MeshError};

/// Floats per face vertex: position 3, scalar 1, opposite vertex 3, three normals 3
/// each, gradient 3 (generic attributes 0..6, in this order).
pub const VERTEX_COMPONENTS: [usize; 7] = [3, 1, 3, 3, 3, 3, 3];
/// Sum of [`VERTEX_COMPONENTS`].
pub const FLOATS_PER_VERTEX: usize = 19;

/// Floats per corner vertex (precise `table` drawn per fragment, [`Prepared::corner_vertices`]):
/// position 3, scalar 1, the four face planes `(outward unit normal, offset)` 4 each, the
/// scalar's gradient 3 (generic attributes 0..6).
pub const CORNER_COMPONENTS: [usize; 7] = [3, 1, 4, 4, 4, 4, 3];

/// The faces of a positively oriented tetrahedron `[0, 1, 2, 3]`, each listed
/// counter-clockwise seen from outside, with the vertex opposite it.
pub const FACES: [([usize; 3], usize); 4] = [
    ([1, 2, 3], 0),
    ([0, 3, 2], 1),
    ([0, 1, 3], 2),
    ([0, 2, 1], 3),
];

/// Where the viewer is, in object space, for ordering and culling faces on the CPU.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Viewer {
    /// A parallel view along this unit direction (into the scene).
    Parallel(DVec3),
    /// A perspective eye at this point.
    Eye(DVec3),
}

/// Cosine between a face's outward normal and the direction from the viewer up to which
/// [`Prepared::view_faces`] keeps the face (0 would keep exactly the front faces).
/// Culling happens in the GL from window coordinates in f32 (a few 1e-5 pixels off); a
/// face turned 1e-3 away projects to 1/1000 of its area, far beyond that.
pub const FACING_MARGIN: f64 = 1e-3;

/// A mesh ready to draw and to trace.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Points in object space: centred on the bounding box, longest side spanning
    /// [-1, 1] (computed in f64 from the file's coordinates, halves first, so that
    /// coordinates near ±1.7e308 neither overflow nor lose the box).
    pub points: Vec<DVec3>,
    /// Normalized scalar per point.
    pub scalars: Vec<f64>,
    /// Tetrahedra that are drawn (positively oriented; those touching a NaN scalar, flat
    /// ones and repeats are left out and counted).
    pub tets: Vec<[u32; 4]>,
    /// Half-extents of the object box.
    pub half: DVec3,
    /// Tetrahedra left out for non-finite scalars.
    pub dropped: usize,
    /// Flat (degenerate) tetrahedra left out: their gradient is zero, so `sf = sb` on
    /// every ray and they can cross no isovalue, but each would still be rasterized.
    pub flat_dropped: usize,
    /// Tetrahedra left out because an earlier one has the same corners and scalars: the
    /// same picture, drawn once.
    pub repeats_dropped: usize,
    /// Flat and sliver counts of the mesh.
    pub quality: Quality,
    /// Which array the scalars came from, and its range.
    pub scalar_name: String,
    /// Range mapped to [0, 1].
    pub scalar_range: [f64; 2],
    /// Object units per mesh-file unit (the box's scale: lengths in the file times this).
    pub scale: f64,
    /// The mesh's bounding box in the file's coordinates (low corner, high corner).
    pub bounds: [[f64; 3]; 2],
}

/// Most layers cell projection draws: the mean number of tetrahedra a line through the
/// mesh's box crosses ([`Quality::depth`](arbvis_data::mesh::quality::Quality), counted over
/// the tetrahedra that are drawn). Every layer is a face rasterized at a pixel, so this
/// bounds the rasterizer's work at about this many fragments per pixel: near this depth
/// a frame of thin plates stacked across a whole mesh is already far from interactive
/// on llvmpipe (measured: docs/benchmarks.md, "Figures behind cell projection's
/// settings"). Meshes whose cells do not overlap stay far below: a grid of
/// 16³ hexahedra (24,576 tetrahedra, the seed's size) is at 39, one of 60³ (1.3 million
/// tetrahedra) at 145, and the depth of such grids grows with the cube root of their
/// size. Cells stacked on each other with different scalars, or plates across the whole
/// mesh, reach it.
pub const MAX_DEPTH: f64 = 1024.0;

/// Bytes of vertex data per drawn tetrahedron: 4 faces x 3 vertices x
/// [`FLOATS_PER_VERTEX`] f32.
pub const VERTEX_BYTES_PER_TET: u64 = 12 * FLOATS_PER_VERTEX as u64 * 4;

/// Load and prepare a scene's mesh; relative paths from `base`. What was left out is
/// told on stderr (one line).
pub fn prepare(scene: &CellprojScene, base: &Path) -> RenderResult<Prepared> {
    let mesh = scene.mesh.load(base)?;
    let scalars = scene.scalars.evaluate(&mesh)?;
    let p = from_mesh(&mesh, &scalars.values, scalars.name, scalars.range)?;
    if let Some(note) = p.left_out(&mesh) {
        eprintln!("arbvis: note: {note}");
    }
    if scene.mode.isosurfaces() {
        for warning in scene.range_warnings(p.scalar_range) {
            eprintln!("arbvis: warning: {warning}");
        }
    }
    Ok(p)
}

/// Prepare a mesh with one normalized scalar per point.
pub fn from_mesh(
    mesh: &Mesh,
    scalars: &[f64],
    scalar_name: String,
    scalar_range: [f64; 2],
) -> RenderResult<Prepared> {
    if scalars.len() != mesh.points.len() {
        return Err(MeshError::Invalid(format!(
            "{} scalars for {} points",
            scalars.len(),
            mesh.points.len()
        ))
        .into());
    }
    if mesh.tets.is_empty() {
        return Err(MeshError::Invalid(format!(
            "{}: the mesh has no tetrahedra",
            mesh.info.source
        ))
        .into());
    }
    let (lo, hi) = mesh
        .bounds()
        .ok_or_else(|| MeshError::Invalid("the mesh has no points".into()))?;
    let bounds = [lo, hi];
    let (lo, hi) = (DVec3::from_array(lo), DVec3::from_array(hi));
    // Halves first: `hi - lo` and `lo + hi` overflow near ±1.7e308, their halves do not.
    let centre = lo / 2.0 + hi / 2.0;
    let half_extent = hi / 2.0 - lo / 2.0;
    let longest = half_extent.max_element();
    let scale = if longest > 0.0 && (1.0 / longest).is_finite() {
        1.0 / longest
    } else {
        1.0
    };
    let points: Vec<DVec3> = mesh
        .points
        .iter()
        .map(|p| (DVec3::from_array(*p) - centre) * scale)
        .collect();
    let half = (half_extent * scale).max(DVec3::splat(1e-9));
    let (quality, flat) = Quality::classify(mesh);
    let finite = |t: &[u32; 4]| t.iter().all(|&v| scalars[v as usize].is_finite());
    let unit = quality::mesh_scale(&mesh.points);
    let again = quality::repeats(mesh.tets.len(), |i| {
        let t = mesh.tets[i];
        let mut k = t.map(|v| {
            let p = mesh.points[v as usize].map(|c| (c + 0.0).to_bits());
            (p, (scalars[v as usize] + 0.0).to_bits())
        });
        k.sort_unstable();
        k
    });
    let (mut dropped, mut flat_dropped, mut repeats_dropped) = (0, 0, 0);
    let mut tets = Vec::new();
    let mut area = 0.0;
    for (i, t) in mesh.tets.iter().enumerate() {
        if !finite(t) {
            dropped += 1;
        } else if flat[i] {
            flat_dropped += 1;
        } else if again[i].is_some() {
            repeats_dropped += 1;
        } else {
            tets.push(*t);
            area += quality::surface_area_scaled(&mesh.points, *t, unit);
        }
    }
    let box_area = quality::box_area_scaled(&mesh.points, unit);
    let depth = if box_area > 0.0 { area / box_area } else { 0.0 };
    if depth > MAX_DEPTH {
        return Err(MeshError::Invalid(format!(
            "{}: a line through the mesh crosses {depth:.0} of its {} drawn tetrahedra on average (the sum of their surface areas over the bounding box's), more than the {MAX_DEPTH} layers cell projection draws: its cells overlap or are plates across the whole mesh{}",
            mesh.info.source,
            tets.len(),
            quality
                .first_repeat
                .map_or(String::new(), |(t, e)| format!(
                    " (tetrahedron {t} of file cell {} is at the place of tetrahedron {e} of cell {})",
                    mesh.source_cell.get(t).copied().unwrap_or(0),
                    mesh.source_cell.get(e).copied().unwrap_or(0)
                ))
        ))
        .into());
    }
    arbvis_core::budget::check(
        format!(
            "{}: the cell-projection vertex data of {} tetrahedra",
            mesh.info.source,
            tets.len()
        ),
        arbvis_core::budget::times(tets.len() as u64, VERTEX_BYTES_PER_TET),
    )?;
    if tets.is_empty() {
        return Err(MeshError::Invalid(format!(
            "{}: no tetrahedron to draw: of {}, {flat_dropped} are flat (degenerate: zero volume{}) and {dropped} touch a NaN or infinite scalar",
            mesh.info.source,
            mesh.tets.len(),
            quality.first_flat.map_or(String::new(), |t| format!(
                ", the first is tetrahedron {t} of file cell {}",
                mesh.source_cell.get(t).copied().unwrap_or(0)
            ))
        ))
        .into());
    }
    Ok(Prepared {
        dropped,
        flat_dropped,
        repeats_dropped,
        points,
        scalars: scalars.to_vec(),
        tets,
        half,
        quality,
        scalar_name,
        scalar_range,
        scale,
        bounds,
    })
}

impl Prepared {
    /// One line saying which tetrahedra are not drawn and why (`None` when all are).
    pub fn left_out(&self, mesh: &Mesh) -> Option<String> {
        if self.dropped + self.flat_dropped + self.repeats_dropped == 0 {
            return None;
        }
        let cell = |t: usize| mesh.source_cell.get(t).copied().unwrap_or(0);
        let mut parts = Vec::new();
        if self.flat_dropped > 0 {
            parts.push(format!(
                "{} flat (degenerate){}",
                self.flat_dropped,
                self.quality.first_flat.map_or(String::new(), |t| format!(
                    ", the first is tetrahedron {t} of file cell {}",
                    cell(t)
                ))
            ));
        }
        if self.repeats_dropped > 0 {
            parts.push(format!(
                "{} repeating an earlier one's corners and scalars",
                self.repeats_dropped
            ));
        }
        if self.dropped > 0 {
            parts.push(format!(
                "{} touching a NaN or infinite scalar",
                self.dropped
            ));
        }
        Some(format!(
            "{}: {} of {} tetrahedra are not drawn: {}",
            mesh.info.source,
            self.dropped + self.flat_dropped + self.repeats_dropped,
            mesh.tets.len(),
            parts.join("; ")
        ))
    }
}

/// The gradient of the linear scalar in a tetrahedron (zero when it is flat: a
/// determinant within 1e-12 of its longest edge cubed, the mesh module's flatness).
pub fn gradient(p: [DVec3; 4], s: [f64; 4]) -> DVec3 {
    let (e1, e2, e3) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    let det = e1.dot(e2.cross(e3));
    let longest = [e1, e2, e3, p[2] - p[1], p[3] - p[1], p[3] - p[2]]
        .iter()
        .map(|e| e.length())
        .fold(0.0, f64::max);
    if det.abs() <= 1e-12 * longest.powi(3) || !det.is_finite() {
        return DVec3::ZERO;
    }
    // Solve [e1; e2; e3] g = ds by Cramer's rule with the cofactor vectors.
    let ds = DVec3::new(s[1] - s[0], s[2] - s[0], s[3] - s[0]);
    (e2.cross(e3) * ds.x + e3.cross(e1) * ds.y + e1.cross(e2) * ds.z) / det
}

/// The unit normal of triangle `a, b, c` (zero when degenerate).
pub fn normal(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a).normalize_or_zero()
}

impl Prepared {
    /// Corners and scalars of tetrahedron `t`.
    pub fn tet(&self, t: usize) -> ([DVec3; 4], [f64; 4]) {
        let v = self.tets[t];
        (
            v.map(|i| self.points[i as usize]),
            v.map(|i| self.scalars[i as usize]),
        )
    }

    /// Vertex data of every face of every tetrahedron: 4 faces x 3 vertices x
    /// [`FLOATS_PER_VERTEX`], in parallel.
    pub fn face_vertices(&self) -> Vec<f32> {
        (0..self.tets.len())
            .into_par_iter()
            .flat_map_iter(|t| self.tet_vertices(t))
            .collect()
    }

    fn tet_vertices(&self, t: usize) -> Vec<f32> {
        let (p, s) = self.tet(t);
        let g = gradient(p, s);
        let mut out = Vec::with_capacity(12 * FLOATS_PER_VERTEX);
        for (face, opposite) in FACES {
            let v3 = p[opposite];
            // The three other faces all contain the opposite vertex.
            let others: Vec<DVec3> = FACES
                .iter()
                .filter(|(_, o)| *o != opposite)
                .map(|(f, _)| normal(p[f[0]], p[f[1]], p[f[2]]))
                .collect();
            for &corner in &face {
                let mut v = vec![p[corner].x, p[corner].y, p[corner].z, s[corner]];
                v.extend(v3.to_array());
                for n in &others {
                    v.extend(n.to_array());
                }
                v.extend(g.to_array());
                out.extend(v.iter().map(|&x| x as f32));
            }
        }
        out
    }

    /// Vertex data of every tetrahedron's four corners: [`CORNER_COMPONENTS`], the planes
    /// and gradient repeated at each corner (they are the cell's, read `flat`), in
    /// parallel. A plane `(n, d)` holds the points `x` with `n·x = d`, `n` outward.
    pub fn corner_vertices(&self) -> Vec<f32> {
        const FLOATS: usize = 23;
        (0..self.tets.len())
            .into_par_iter()
            .flat_map_iter(|t| {
                let (p, s) = self.tet(t);
                let mut cell = [0.0; FLOATS - 4];
                for (k, (f, _)) in FACES.iter().enumerate() {
                    let n = normal(p[f[0]], p[f[1]], p[f[2]]);
                    cell[4 * k..4 * k + 4].copy_from_slice(&[n.x, n.y, n.z, n.dot(p[f[0]])]);
                }
                cell[16..].copy_from_slice(&gradient(p, s).to_array());
                let mut out = [0f32; 4 * FLOATS];
                for (k, corner) in out.chunks_exact_mut(FLOATS).enumerate() {
                    let own = [p[k].x, p[k].y, p[k].z, s[k]];
                    for (o, v) in corner.iter_mut().zip(own.iter().chain(&cell)) {
                        *o = *v as f32;
                    }
                }
                out
            })
            .collect()
    }

    /// The scalar range `[min, max]` over each tetrahedron's corners.
    pub fn ranges(&self) -> Vec<[f64; 2]> {
        self.tets
            .iter()
            .map(|t| {
                let s = t.map(|v| self.scalars[v as usize]);
                [
                    s.iter().copied().fold(f64::INFINITY, f64::min),
                    s.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                ]
            })
            .collect()
    }

    /// The tetrahedra whose range, widened by `slack`, holds one of `isovalues`.
    pub fn active_tets(ranges: &[[f64; 2]], isovalues: &[Isovalue], slack: f64) -> Vec<u32> {
        let mut values: Vec<f64> = isovalues.iter().map(|i| i.value).collect();
        values.sort_by(f64::total_cmp);
        let mut out = Vec::new();
        for (t, [lo, hi]) in ranges.iter().enumerate() {
            // The first isovalue at or above lo - slack: active when it is <= hi + slack.
            let k = values.partition_point(|&v| v < lo - slack);
            if values.get(k).is_some_and(|&v| v <= hi + slack) {
                out.push(t as u32);
            }
        }
        out
    }

    /// Vertex indices (12 per tetrahedron, into [`Prepared::face_vertices`]) of the
    /// [`Prepared::active_tets`].
    pub fn active_indices(ranges: &[[f64; 2]], isovalues: &[Isovalue], slack: f64) -> Vec<u32> {
        Self::active_tets(ranges, isovalues, slack)
            .into_iter()
            .flat_map(|t| t * 12..t * 12 + 12)
            .collect()
    }

    /// The centroid of tetrahedron `t`.
    pub fn centroid(&self, t: usize) -> DVec3 {
        let (p, _) = self.tet(t);
        (p[0] + p[1] + p[2] + p[3]) / 4.0
    }

    /// The vertex data of `tets` (slices of `faces`, [`Prepared::face_vertices`]) for one
    /// view: the tetrahedra front to back by centroid, and of each only the faces that
    /// may face `viewer` (outward normal at most [`FACING_MARGIN`] away from the
    /// viewer's side: what back-face culling would drop, with a margin for the GL's f32
    /// rounding of nearly edge-on faces, which are kept). In parallel.
    pub fn view_faces(&self, faces: &[f32], tets: &[u32], viewer: Viewer) -> Vec<f32> {
        // Sort keys and the faces to keep (bit k for face k), in parallel; then one
        // sequential copy of whole faces.
        let mut keyed: Vec<(f64, u32, u8)> = tets
            .par_iter()
            .map(|&t| {
                let (p, _) = self.tet(t as usize);
                let c = (p[0] + p[1] + p[2] + p[3]) / 4.0;
                let key = match viewer {
                    Viewer::Parallel(d) => c.dot(d),
                    Viewer::Eye(e) => (c - e).length_squared(),
                };
                let mut keep = 0u8;
                for (k, (f, _)) in FACES.iter().enumerate() {
                    let n = (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]);
                    let toward = match viewer {
                        Viewer::Parallel(d) => d,
                        Viewer::Eye(e) => (p[f[0]] - e).normalize_or_zero(),
                    };
                    if n.dot(toward) < FACING_MARGIN * n.length() || n == DVec3::ZERO {
                        keep |= 1 << k;
                    }
                }
                (key, t, keep)
            })
            .collect();
        keyed.par_sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let face_floats = 3 * FLOATS_PER_VERTEX;
        let kept: usize = keyed.iter().map(|k| k.2.count_ones() as usize).sum();
        let mut out = Vec::with_capacity(kept * face_floats);
        for &(_, t, keep) in &keyed {
            for k in 0..4 {
                if keep & (1 << k) != 0 {
                    let at = (t as usize * 4 + k) * face_floats;
                    out.extend_from_slice(&faces[at..at + face_floats]);
                }
            }
        }
        out
    }

    /// The longest edge of any tetrahedron (object units).
    pub fn longest_edge(&self) -> f64 {
        (0..self.tets.len())
            .into_par_iter()
            .map(|t| {
                let (p, _) = self.tet(t);
                let mut m = 0f64;
                for i in 0..4 {
                    for j in i + 1..4 {
                        m = m.max((p[i] - p[j]).length());
                    }
                }
                m
            })
            .reduce(|| 0.0, f64::max)
    }

    /// Number of face vertices [`Prepared::face_vertices`] yields.
    pub fn vertex_count(&self) -> usize {
        self.tets.len() * 12
    }
}

/// The faithful `(sf, sb)` table: `size`² RGBA8, texel `(i, j)` (i along s = sf, j
/// along t = sb, row j first) holding the colour of the first isovalue crossed from
/// `sf = (i + ½)/size` to `sb = (j + ½)/size`, alpha 0 where none is.
pub fn iso_table(isovalues: &[Isovalue], size: u32) -> Vec<u8> {
    let mut sorted = isovalues.to_vec();
    sorted.sort_by(|a, b| a.value.total_cmp(&b.value));
    let n = size as usize;
    let centre = |k: usize| (k as f64 + 0.5) / n as f64;
    let byte = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let mut texels = vec![0u8; n * n * 4];
    for j in 0..n {
        for i in 0..n {
            if let Some(k) = first_crossed(&sorted, centre(i), centre(j), 0.0) {
                let c = sorted[k].color;
                let at = (j * n + i) * 4;
                texels[at..at + 4].copy_from_slice(&[byte(c[0]), byte(c[1]), byte(c[2]), 255]);
            }
        }
    }
    texels
}

/// The precise programs' isovalue list: a `count` x 2 RGBA32F texture, row 0 the
/// colours, row 1 the values (sorted ascending).
pub fn iso_list(isovalues: &[Isovalue]) -> Vec<f32> {
    let mut sorted = isovalues.to_vec();
    sorted.sort_by(|a, b| a.value.total_cmp(&b.value));
    let mut texels: Vec<f32> = sorted
        .iter()
        .flat_map(|i| i.color.map(|c| c as f32))
        .collect();
    texels.extend(sorted.iter().flat_map(|i| [i.value as f32, 0.0, 0.0, 0.0]));
    texels
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_data::mesh::grid::{generate, Field, GridSpec};

    #[test]
    fn faces_are_outward_and_counter_clockwise() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let centre = (p[0] + p[1] + p[2] + p[3]) / 4.0;
        for (f, o) in FACES {
            let n = normal(p[f[0]], p[f[1]], p[f[2]]);
            assert!(n.dot(p[f[0]] - centre) > 0.0, "face {f:?} points out");
            assert!(!f.contains(&o));
        }
    }

    /// A tetrahedron with no symmetry, and a linear field's gradient over it.
    fn skewed_cell() -> ([DVec3; 4], DVec3) {
        let p = [
            DVec3::new(0.3, -0.2, 0.1),
            DVec3::new(1.1, 0.0, 0.2),
            DVec3::new(0.2, 0.9, -0.1),
            DVec3::new(0.1, 0.3, 1.3),
        ];
        (p, DVec3::new(0.7, -1.9, 0.25))
    }

    #[test]
    fn corners_carry_their_cell_planes_and_gradient() {
        let (p, g) = skewed_cell();
        let mesh = arbvis_data::mesh::Mesh {
            points: p.iter().map(|q| q.to_array()).collect(),
            tets: vec![[0, 1, 2, 3]],
            ..Default::default()
        };
        let s: Vec<f64> = p.iter().map(|q| 0.4 + g.dot(*q)).collect();
        let prepared = from_mesh(&mesh, &s, "s".into(), [-3.0, 3.0]).unwrap();
        let (q, sq) = prepared.tet(0);
        let v = prepared.corner_vertices();
        let floats: usize = CORNER_COMPONENTS.iter().sum();
        assert_eq!(v.len(), 4 * floats);
        let at = |i: usize| v[i] as f64;
        for (k, corner) in (0..4).map(|k| (k, k * floats)) {
            let own = DVec3::new(at(corner), at(corner + 1), at(corner + 2));
            assert!((own - q[k]).length() < 1e-6 && (at(corner + 3) - sq[k]).abs() < 1e-6);
            // f32 storage: each plane holds its face's corners and has the fourth inside.
            for (f, (face, opposite)) in FACES.iter().enumerate() {
                let n = DVec3::new(
                    at(corner + 4 + 4 * f),
                    at(corner + 5 + 4 * f),
                    at(corner + 6 + 4 * f),
                );
                let d = at(corner + 7 + 4 * f);
                assert!((n.length() - 1.0).abs() < 1e-6);
                for &c in face {
                    assert!((n.dot(q[c]) - d).abs() < 1e-6, "corner {k} face {f}");
                }
                assert!(
                    n.dot(q[*opposite]) < d - 0.1,
                    "corner {k} face {f} points in"
                );
            }
            let grad = DVec3::new(at(corner + 20), at(corner + 21), at(corner + 22));
            assert!((grad - gradient(q, sq)).length() < 1e-5, "{grad}");
        }
    }

    #[test]
    fn gradient_of_a_linear_field_is_exact() {
        let (p, g) = skewed_cell();
        let s = p.map(|q| 0.4 + g.dot(q));
        assert!((gradient(p, s) - g).length() < 1e-12);
        let flat = [p[0], p[1], p[2], (p[1] + p[2]) / 2.0];
        assert_eq!(gradient(flat, s), DVec3::ZERO);
    }

    #[test]
    fn the_seed_grid_prepares_into_the_object_box() {
        let mesh = generate(&GridSpec {
            points: [17, 17, 17],
            field: Field::Spherical,
        })
        .unwrap();
        let s = arbvis_data::mesh::scalars::ScalarSpec::default()
            .evaluate(&mesh)
            .unwrap();
        let p = from_mesh(&mesh, &s.values, s.name, s.range).unwrap();
        assert_eq!(p.tets.len(), 24_576);
        assert_eq!(p.vertex_count(), 24_576 * 12);
        assert!((p.half - DVec3::ONE).length() < 1e-12);
        let v = p.face_vertices();
        assert_eq!(v.len(), 24_576 * 12 * FLOATS_PER_VERTEX);
        // The first vertex: position, scalar, opposite vertex, then unit normals.
        let n0 = DVec3::new(v[7] as f64, v[8] as f64, v[9] as f64);
        assert!((n0.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn far_from_the_origin_keeps_millimetres() {
        // A tetrahedron 1e6 from the origin with millimetre edges: in f32 directly its
        // corners would collapse (f32 spacing at 1e6 is 0.0625); re-centred in f64 they
        // keep their shape.
        let o = 1.0e6;
        let mesh = arbvis_data::mesh::Mesh {
            points: vec![
                [o, o, o],
                [o + 0.001, o, o],
                [o, o + 0.001, o],
                [o, o, o + 0.001],
            ],
            tets: vec![[0, 1, 2, 3]],
            ..Default::default()
        };
        let p = from_mesh(&mesh, &[0.0, 1.0, 0.0, 0.0], "s".into(), [0.0, 1.0]).unwrap();
        let (q, s) = p.tet(0);
        let g = gradient(q, s);
        // s = x / 1 mm; the box maps 1 mm to 2 units: the gradient is 0.5 per unit.
        assert!((g - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-9, "{g}");
    }

    #[test]
    fn active_tetrahedra_are_those_whose_range_holds_an_isovalue() {
        let ranges = [[0.0, 0.2], [0.25, 0.35], [0.5, 0.5], [0.6, 1.0]];
        let iso = |value| Isovalue {
            value,
            color: [1.0; 4],
        };
        let active = Prepared::active_indices(&ranges, &[iso(0.3), iso(0.5)], 0.0);
        let tets: Vec<u32> = active.chunks(12).map(|c| c[0] / 12).collect();
        assert_eq!(tets, vec![1, 2]);
        assert!(active.chunks(12).all(|c| c[11] == c[0] + 11));
        assert!(Prepared::active_indices(&ranges, &[iso(0.21)], 0.0).is_empty());
        assert_eq!(
            Prepared::active_indices(&ranges, &[iso(0.21)], 0.02).len(),
            12
        );
    }

    #[test]
    fn table_holds_the_first_crossing_and_nothing_elsewhere() {
        let isos = [
            Isovalue {
                value: 0.5,
                color: [0.0, 1.0, 0.0, 1.0],
            },
            Isovalue {
                value: 0.3,
                color: [1.0, 0.0, 0.0, 1.0],
            },
        ];
        let t = iso_table(&isos, 10);
        let at = |i: usize, j: usize| &t[(j * 10 + i) * 4..][..4];
        assert_eq!(
            at(1, 8),
            &[255, 0, 0, 255],
            "0.15 -> 0.85 crosses 0.3 first"
        );
        assert_eq!(
            at(8, 1),
            &[0, 255, 0, 255],
            "0.85 -> 0.15 crosses 0.5 first"
        );
        assert_eq!(at(3, 4), &[0, 0, 0, 0], "0.35 -> 0.45: nothing");
        assert_eq!(
            iso_list(&isos)[..4],
            [1.0, 0.0, 0.0, 1.0],
            "sorted: 0.3 first"
        );
    }
}
