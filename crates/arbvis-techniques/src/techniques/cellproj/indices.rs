//! The index buffers of one view: which faces of each tetrahedron the volume draws, in
//! the order of its visibility sort.

use glam::DVec3;
use rayon::prelude::*;

use super::prepare::{Prepared, Viewer, FACES, FACING_MARGIN};
use crate::techniques::Frame;
use arbvis_core::camera::Projection;

/// Per face of a tetrahedron with corners `p`: the cosine between its outward normal
/// and the direction from `viewer` (below 0: it faces the viewer; NaN: no area).
fn facing(p: &[DVec3; 4], viewer: Viewer) -> [f64; 4] {
    FACES.map(|(f, _)| {
        let n = (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]);
        let toward = match viewer {
            Viewer::Parallel(d) => d,
            Viewer::Eye(e) => (p[f[0]] - e).normalize_or_zero(),
        };
        n.dot(toward) / n.length()
    })
}

/// Indices into the face vertices (12 per tetrahedron) of the faces of `order`'s
/// tetrahedra that may face `viewer` (within [`FACING_MARGIN`]), in that order.
pub fn front_face_indices(prepared: &Prepared, order: &[u32], viewer: Viewer) -> Vec<u32> {
    in_order(order, |t, out| {
        let cosines = facing(&prepared.tet(t as usize).0, viewer);
        for (k, c) in cosines.into_iter().enumerate() {
            if c < FACING_MARGIN {
                let base = t * 12 + k as u32 * 3;
                out.extend([base, base + 1, base + 2]);
            }
        }
    })
}

/// Indices into the corner vertices (4 per tetrahedron, [`Prepared::corner_vertices`])
/// covering each of `order`'s tetrahedra once, in that order: the faces that may face
/// `viewer`, as [`front_face_indices`], except that with `merge`, where three faces
/// clearly face it (each beyond [`FACING_MARGIN`]), the fourth, wound to face the
/// viewer: it covers the same pixels in one triangle instead of three (about a fifth of
/// a mesh's cells). Its fragments lie at the back of the cell, so `merge` only where
/// nothing tests their depth.
pub fn cell_indices(prepared: &Prepared, order: &[u32], viewer: Viewer, merge: bool) -> Vec<u32> {
    in_order(order, |t, out| {
        let cosines = facing(&prepared.tet(t as usize).0, viewer);
        let corner = |i: usize| t * 4 + i as u32;
        let clear = cosines.iter().filter(|&&c| c < -FACING_MARGIN).count();
        match cosines.iter().position(|&c| c > FACING_MARGIN) {
            Some(back) if merge && clear == 3 => {
                let f = FACES[back].0;
                out.extend([corner(f[0]), corner(f[2]), corner(f[1])]);
            }
            _ => {
                for (k, c) in cosines.into_iter().enumerate() {
                    if c < FACING_MARGIN {
                        out.extend(FACES[k].0.map(corner));
                    }
                }
            }
        }
    })
}

/// What `emit` appends for each of `order`'s tetrahedra, in that order (in parallel).
fn in_order(order: &[u32], emit: impl Fn(u32, &mut Vec<u32>) + Sync) -> Vec<u32> {
    order
        .par_chunks(4096)
        .flat_map_iter(|chunk| {
            let mut out = Vec::with_capacity(chunk.len() * 6);
            for &t in chunk {
                emit(t, &mut out);
            }
            out
        })
        .collect()
}

/// The eye in object space (perspective) and the unit view direction (both cameras).
pub fn eye_and_direction(frame: &Frame) -> (DVec3, DVec3) {
    let inverse = frame.camera.view().inverse();
    let eye = inverse.transform_point3(DVec3::ZERO);
    let dir = inverse.transform_vector3(DVec3::NEG_Z).normalize();
    (eye, dir)
}

/// The viewer of a frame, in object space (what [`Order::View`] sorts and culls for).
pub fn viewer(frame: &Frame) -> Viewer {
    let (eye, dir) = eye_and_direction(frame);
    match frame.camera.projection {
        Projection::Orthographic => Viewer::Parallel(dir),
        Projection::Perspective => Viewer::Eye(eye),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use arbvis_data::mesh::Mesh;

    /// `count` random tetrahedra (positively oriented, some slivers) in the unit box.
    pub(crate) fn random_cells(count: usize, seed: u64) -> Prepared {
        let mut state = seed;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut mesh = Mesh::default();
        for t in 0..count {
            let centre = DVec3::new(next(), next(), next()) * 0.8;
            let size = if t % 5 == 0 { 0.02 } else { 0.2 };
            let mut p: Vec<DVec3> = (0..4)
                .map(|_| centre + DVec3::new(next(), next(), next()) * size)
                .collect();
            if t % 7 == 0 {
                // A sliver: the fourth corner nearly on the first face.
                p[3] = (p[0] + p[1] + p[2]) / 3.0 + (p[3] - p[0]) * 0.01;
            }
            if (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) < 0.0 {
                p.swap(1, 2);
            }
            let base = mesh.points.len() as u32;
            mesh.points.extend(p.iter().map(|q| q.to_array()));
            mesh.tets.push([base, base + 1, base + 2, base + 3]);
        }
        let scalars: Vec<f64> = (0..mesh.points.len()).map(|i| i as f64 % 3.0).collect();
        super::super::prepare::from_mesh(&mesh, &scalars, "s".into(), [0.0, 2.0]).unwrap()
    }

    /// Twice the signed area of triangle `abc` projected for `viewer` (looking at the
    /// origin), positive when it faces the viewer.
    fn projected_area(viewer: Viewer, [a, b, c]: [DVec3; 3]) -> f64 {
        let (w, project): (DVec3, Box<dyn Fn(DVec3) -> DVec3>) = match viewer {
            Viewer::Parallel(d) => (d, Box::new(|p| p)),
            Viewer::Eye(e) => {
                let w = (-e).normalize();
                (w, Box::new(move |p: DVec3| e + (p - e) / (p - e).dot(w)))
            }
        };
        // Outward normals face the viewer when n.w < 0: the area along -w.
        -(project(b) - project(a))
            .cross(project(c) - project(a))
            .dot(w)
    }

    fn viewers() -> Vec<Viewer> {
        let dirs = [
            DVec3::new(0.3, -0.8, 0.52),
            DVec3::new(-0.9, 0.1, -0.42),
            DVec3::new(0.05, 0.2, 0.98),
        ];
        dirs.iter()
            .flat_map(|d| {
                [
                    Viewer::Parallel(d.normalize()),
                    Viewer::Eye(-d.normalize() * 4.0),
                ]
            })
            .collect()
    }

    #[test]
    fn merged_cells_cover_what_their_front_faces_cover_in_fewer_triangles() {
        let prepared = random_cells(400, 0x9e37_79b9_7f4a_7c15);
        let order: Vec<u32> = (0..prepared.tets.len() as u32).rev().collect();
        for viewer in viewers() {
            let faces = front_face_indices(&prepared, &order, viewer);
            let unmerged = cell_indices(&prepared, &order, viewer, false);
            // Without merging, the same faces: face vertex t*12 + 3k + j is corner
            // FACES[k].0[j] of tetrahedron t.
            let as_corners: Vec<u32> = faces
                .iter()
                .map(|&i| (i / 12) * 4 + FACES[(i % 12 / 3) as usize].0[(i % 3) as usize] as u32)
                .collect();
            assert_eq!(as_corners, unmerged, "{viewer:?}");
            let merged = cell_indices(&prepared, &order, viewer, true);
            assert!(merged.len() < unmerged.len(), "{viewer:?}: nothing merged");
            // Per cell, in order: the same projected area (the silhouette), every merged
            // triangle facing the viewer; the cells keep the sort's order.
            let area = |indices: &[u32]| {
                let mut per_cell = vec![0.0; prepared.tets.len()];
                let mut cells: Vec<usize> = Vec::new();
                for tri in indices.chunks(3) {
                    let t = (tri[0] / 4) as usize;
                    assert!(tri.iter().all(|&i| (i / 4) as usize == t), "{tri:?}");
                    let (p, _) = prepared.tet(t);
                    let corners = [0, 1, 2].map(|k| p[(tri[k] % 4) as usize]);
                    per_cell[t] += projected_area(viewer, corners);
                    if cells.last() != Some(&t) {
                        cells.push(t);
                    }
                }
                (per_cell, cells)
            };
            let (before, cells_before) = area(&unmerged);
            let (after, cells_after) = area(&merged);
            assert_eq!(cells_before, cells_after, "{viewer:?}: order");
            for t in 0..prepared.tets.len() {
                // f64 rounding of areas up to ~0.1: 1e-12 relative.
                assert!(
                    (before[t] - after[t]).abs() <= 1e-12 * before[t].abs().max(1e-3),
                    "{viewer:?} cell {t}: {} -> {}",
                    before[t],
                    after[t]
                );
            }
            for tri in merged.chunks(3) {
                let (p, _) = prepared.tet((tri[0] / 4) as usize);
                let [a, b, c] = [0, 1, 2].map(|k| p[(tri[k] % 4) as usize]);
                let projected = projected_area(viewer, [a, b, c]);
                // Faces kept within FACING_MARGIN of edge-on may face away by up to 1e-3
                // of their area (and the GL culls them); every other triangle faces the
                // viewer.
                let area = (b - a).cross(c - a).length();
                assert!(
                    projected > -1.01e-3 * area,
                    "{viewer:?}: {tri:?} {projected}"
                );
            }
        }
    }
}
