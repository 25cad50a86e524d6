//! Face neighbours and the visibility orders of the volume's faithful projection (CPU, no
//! GL): the era's two sorts, both back to front.
//!
//! - [`centroid_order`]: the tetrahedra by the depth of their centroids, farthest first,
//!   as VTK's projected tetrahedra sorts them (`vtkCellCenterDepthSort`). Wrong wherever a
//!   large tetrahedron's centroid lies behind a small one it covers, which on meshes of
//!   mixed sizes and non-convex meshes happens from most views.
//! - [`mpvonc_order`]: after Williams' MPVONC (1992). Each interior face between `a` and
//!   `b` says which of the two is behind for this viewer (the one on the far side of the
//!   face's plane); a topological sort of that relation (Kahn's algorithm) draws a
//!   tetrahedron only after every neighbour behind it. Exact for convex meshes without
//!   cycles; a non-convex mesh gives tetrahedra that are unrelated through faces (across
//!   a hole), which Williams orders by heuristics: here the ready tetrahedra wait in a
//!   priority queue, farthest centroid first, and a cycle (possible in perspective, and
//!   on some meshes in parallel views) is broken by taking the farthest remaining
//!   tetrahedron. Non-convex meshes can still be misordered where a tetrahedron behind
//!   a hole is ready before one in front of it that it does not touch.

use std::collections::BinaryHeap;

use glam::DVec3;
use rayon::prelude::*;

use super::prepare::{normal, Prepared, Viewer, FACES};

/// No neighbour across this face: it is on the mesh's boundary.
pub const BOUNDARY: u32 = u32::MAX;

/// For every tetrahedron, the tetrahedron across each of its four faces ([`FACES`]
/// order), or [`BOUNDARY`]. Faces are matched by their sorted vertex triple; a face
/// shared by more than two tetrahedra (a broken mesh) keeps the first pair.
pub fn neighbours(tets: &[[u32; 4]]) -> Vec<[u32; 4]> {
    let mut faces: Vec<([u32; 3], u32)> = tets
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, tet)| {
            FACES.iter().enumerate().map(move |(k, (f, _))| {
                let mut key = f.map(|i| tet[i]);
                key.sort_unstable();
                (key, (t * 4 + k) as u32)
            })
        })
        .collect();
    faces.par_sort_unstable();
    let mut out = vec![[BOUNDARY; 4]; tets.len()];
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j - i >= 2 {
            let (a, b) = (faces[i].1 as usize, faces[i + 1].1 as usize);
            out[a / 4][a % 4] = (b / 4) as u32;
            out[b / 4][b % 4] = (a / 4) as u32;
        }
        i = j;
    }
    out
}

/// Depth of point `p` for `viewer`: larger is farther.
pub fn depth(viewer: Viewer, p: DVec3) -> f64 {
    match viewer {
        Viewer::Parallel(d) => p.dot(d),
        Viewer::Eye(e) => (p - e).length_squared(),
    }
}

/// `tets` (indices into `prepared`) by centroid depth, farthest first (ties by index).
pub fn centroid_order(prepared: &Prepared, tets: &[u32], viewer: Viewer) -> Vec<u32> {
    let mut keyed: Vec<(f64, u32)> = tets
        .par_iter()
        .map(|&t| (depth(viewer, prepared.centroid(t as usize)), t))
        .collect();
    keyed.par_sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    keyed.into_iter().map(|(_, t)| t).collect()
}

/// A max-heap key: the depth's bits ordered as the depth, then the index (lower first).
fn heap_key(depth: f64, t: u32) -> (u64, std::cmp::Reverse<u32>) {
    let b = depth.to_bits();
    let ordered = if depth.is_sign_negative() {
        !b
    } else {
        b | (1 << 63)
    };
    (ordered, std::cmp::Reverse(t))
}

/// What [`mpvonc_order`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MpvoncStats {
    /// Cycles broken (tetrahedra taken before all their behind-neighbours).
    pub cycles_broken: usize,
}

/// All of `prepared`'s tetrahedra back to front by MPVONC (see the module doc).
pub fn mpvonc_order(
    prepared: &Prepared,
    neighbours: &[[u32; 4]],
    viewer: Viewer,
) -> (Vec<u32>, MpvoncStats) {
    let n = prepared.tets.len();
    // behind[t] bit k: the neighbour across face k is behind t (drawn before it).
    let behind: Vec<u8> = (0..n)
        .into_par_iter()
        .map(|t| {
            let (p, _) = prepared.tet(t);
            let mut bits = 0u8;
            for (k, (f, _)) in FACES.iter().enumerate() {
                if neighbours[t][k] == BOUNDARY {
                    continue;
                }
                let nrm = normal(p[f[0]], p[f[1]], p[f[2]]);
                let toward_viewer = match viewer {
                    Viewer::Parallel(d) => -d,
                    Viewer::Eye(e) => e - p[f[0]],
                };
                // The viewer on t's inner side of the face: the neighbour, on the
                // outer side, is behind t.
                if nrm.dot(toward_viewer) < 0.0 {
                    bits |= 1 << k;
                }
            }
            bits
        })
        .collect();
    let mut waiting: Vec<u8> = behind.iter().map(|b| b.count_ones() as u8).collect();
    let depths: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|t| depth(viewer, prepared.centroid(t)))
        .collect();
    let mut heap: BinaryHeap<(u64, std::cmp::Reverse<u32>)> = (0..n)
        .filter(|&t| waiting[t] == 0)
        .map(|t| heap_key(depths[t], t as u32))
        .collect();
    let mut done = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut stats = MpvoncStats::default();
    // For breaking cycles: every tetrahedron, farthest first.
    let mut fallback: Vec<u32> = (0..n as u32).collect();
    let mut fallback_sorted = false;
    let mut cursor = 0;
    while order.len() < n {
        let t = match heap.pop() {
            Some((_, std::cmp::Reverse(t))) => t as usize,
            None => {
                if !fallback_sorted {
                    fallback.par_sort_unstable_by(|&a, &b| {
                        depths[b as usize].total_cmp(&depths[a as usize])
                    });
                    fallback_sorted = true;
                }
                while done[fallback[cursor] as usize] {
                    cursor += 1;
                }
                stats.cycles_broken += 1;
                fallback[cursor] as usize
            }
        };
        if done[t] {
            continue;
        }
        done[t] = true;
        order.push(t as u32);
        // Every neighbour in front of t (t is behind it) waits for one fewer.
        for (k, &m) in neighbours[t].iter().enumerate() {
            if m == BOUNDARY || behind[t] & (1 << k) != 0 {
                continue;
            }
            let m = m as usize;
            if !done[m] && waiting[m] > 0 {
                waiting[m] -= 1;
                if waiting[m] == 0 {
                    heap.push(heap_key(depths[m], m as u32));
                }
            }
        }
    }
    (order, stats)
}

/// Whether every tetrahedron reaches every other across shared faces (one body).
pub fn one_body(neighbours: &[[u32; 4]]) -> bool {
    if neighbours.is_empty() {
        return true;
    }
    let mut seen = vec![false; neighbours.len()];
    let mut stack = vec![0u32];
    seen[0] = true;
    let mut reached = 1;
    while let Some(t) = stack.pop() {
        for &m in &neighbours[t as usize] {
            if m != BOUNDARY && !seen[m as usize] {
                seen[m as usize] = true;
                reached += 1;
                stack.push(m);
            }
        }
    }
    reached == neighbours.len()
}

/// Whether the mesh is one convex body, so that a ray enters it once: one body
/// ([`one_body`]; separate convex plates pass the next test each), and its boundary
/// locally convex: at every boundary edge, the other boundary faces' far vertices lie on
/// the inner side of each face's plane (within 1e-9 of the box).
pub fn boundary_is_convex(prepared: &Prepared, neighbours: &[[u32; 4]]) -> bool {
    use std::collections::HashMap;
    if !one_body(neighbours) {
        return false;
    }
    let mut faces = Vec::new();
    for (t, row) in neighbours.iter().enumerate() {
        for (k, &m) in row.iter().enumerate() {
            if m == BOUNDARY {
                faces.push(FACES[k].0.map(|i| prepared.tets[t][i]));
            }
        }
    }
    let mut by_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for f in &faces {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            by_edge
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push(f[(e + 2) % 3]);
        }
    }
    faces.par_iter().all(|f| {
        let p = f.map(|i| prepared.points[i as usize]);
        let n = normal(p[0], p[1], p[2]);
        let d = n.dot(p[0]);
        (0..3).all(|e| {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            by_edge[&(a.min(b), a.max(b))]
                .iter()
                .all(|&q| n.dot(prepared.points[q as usize]) <= d + 1e-9)
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_data::mesh::grid::{generate, Field, GridSpec};

    fn grid(n: usize) -> Prepared {
        let mesh = generate(&GridSpec {
            points: [n; 3],
            field: Field::Spherical,
        })
        .unwrap();
        let s = arbvis_data::mesh::scalars::ScalarSpec::default()
            .evaluate(&mesh)
            .unwrap();
        super::super::prepare::from_mesh(&mesh, &s.values, s.name, s.range).unwrap()
    }

    #[test]
    fn neighbours_are_symmetric_and_the_grid_boundary_is_its_surface() {
        let p = grid(4);
        let nb = neighbours(&p.tets);
        let boundary = nb.iter().flatten().filter(|&&m| m == BOUNDARY).count();
        // 6 sides of 3x3 squares, 2 triangles each.
        assert_eq!(boundary, 6 * 9 * 2);
        for (t, row) in nb.iter().enumerate() {
            for &m in row.iter().filter(|&&m| m != BOUNDARY) {
                assert!(nb[m as usize].contains(&(t as u32)));
            }
        }
        assert!(boundary_is_convex(&p, &nb));
    }

    #[test]
    fn mpvonc_draws_what_rays_meet_farther_first_on_a_convex_grid() {
        use super::super::reference::Bvh;
        use super::super::volume_reference::segments;
        let p = grid(5);
        let nb = neighbours(&p.tets);
        let bvh = Bvh::build(&p);
        for (viewer, origin) in [
            (
                Viewer::Parallel(DVec3::new(0.3, -0.5, 0.81).normalize()),
                None,
            ),
            (
                Viewer::Eye(DVec3::new(2.5, 1.9, -3.1)),
                Some(DVec3::new(2.5, 1.9, -3.1)),
            ),
        ] {
            let (order, stats) = mpvonc_order(&p, &nb, viewer);
            assert_eq!(order.len(), p.tets.len());
            // A Kuhn grid seen from outside has no cycles.
            assert_eq!(stats.cycles_broken, 0, "{viewer:?}");
            let mut at = vec![0usize; order.len()];
            for (i, &t) in order.iter().enumerate() {
                at[t as usize] = i;
            }
            // Independent truth: rays cast through the mesh meet the tetrahedra in
            // depth order; back to front draws each one met later before the earlier.
            let mut pairs = 0;
            for i in 0..15 {
                for j in 0..15 {
                    let target = DVec3::new(-0.9 + i as f64 * 0.13, -0.85 + j as f64 * 0.12, 0.05);
                    let (o, d) = match (viewer, origin) {
                        (Viewer::Parallel(d), _) => (target - d * 3.0, d * 6.0),
                        (_, Some(e)) => (e, (target - e) * 3.0),
                        _ => unreachable!(),
                    };
                    let segs = segments(&p, &bvh, o, d);
                    for w in segs.windows(2) {
                        if w[1].0 - w[0].1 > 1e-9
                            || w[0].1 - w[0].0 < 1e-9
                            || w[1].1 - w[1].0 < 1e-9
                        {
                            continue;
                        }
                        assert!(
                            at[w[1].2] < at[w[0].2],
                            "{viewer:?}: {:?} then {:?}",
                            w[0],
                            w[1]
                        );
                        pairs += 1;
                    }
                }
            }
            assert!(pairs > 500, "{pairs} pairs checked");
        }
    }
}
