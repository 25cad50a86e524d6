//! What is wrong with a surface, counted (not refused): open and non-manifold edges,
//! edges whose two triangles disagree on orientation, degenerate triangles, the signed
//! volume, and an approximate count of self-intersecting triangle pairs.
//!
//! Self-intersections are found approximately: triangle pairs whose bounding boxes meet
//! in a uniform grid are tested edge-against-triangle (Möller-Trumbore, strict interior);
//! pairs sharing a vertex and coplanar overlaps are not tested, and the search stops after
//! [`MAX_PAIR_TESTS`] pair tests (the report says so). A count of 0 is therefore "none
//! found", not a proof.

use std::collections::HashMap;
use std::fmt;

use glam::DVec3;

use super::TriangleMesh;

/// Pair tests after which the self-intersection search stops.
pub const MAX_PAIR_TESTS: usize = 20_000_000;

/// Counts describing a surface's soundness.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshReport {
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Smallest corner of the bounding box.
    pub min: [f64; 3],
    /// Largest corner of the bounding box.
    pub max: [f64; 3],
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges used by exactly one triangle (holes' borders).
    pub open_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Edges of two triangles that run the same way in both (one of them is flipped).
    pub misoriented_edges: usize,
    /// Triangles with a repeated vertex or zero area.
    pub degenerate_triangles: usize,
    /// Sum of the signed tetrahedron volumes (positive for an outward orientation).
    pub signed_volume: f64,
    /// Self-intersecting triangle pairs found (approximate, see the module doc).
    pub self_intersections: usize,
    /// False when the self-intersection search stopped early.
    pub self_intersection_search_complete: bool,
}

impl MeshReport {
    /// Closed and consistently oriented: every edge shared by exactly two triangles that
    /// traverse it in opposite directions.
    pub fn is_closed(&self) -> bool {
        self.open_edges == 0 && self.non_manifold_edges == 0 && self.misoriented_edges == 0
    }
}

impl fmt::Display for MeshReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "vertices: {}", self.vertices)?;
        writeln!(f, "triangles: {}", self.triangles)?;
        writeln!(f, "bounds: {:?} .. {:?}", self.min, self.max)?;
        writeln!(f, "edges: {}", self.edges)?;
        writeln!(f, "open edges (one triangle): {}", self.open_edges)?;
        writeln!(
            f,
            "non-manifold edges (3+ triangles): {}",
            self.non_manifold_edges
        )?;
        writeln!(f, "misoriented edges: {}", self.misoriented_edges)?;
        writeln!(f, "degenerate triangles: {}", self.degenerate_triangles)?;
        writeln!(f, "signed volume: {:.6}", self.signed_volume)?;
        writeln!(
            f,
            "self-intersecting pairs (approximate): {}{}",
            self.self_intersections,
            if self.self_intersection_search_complete {
                ""
            } else {
                " (search stopped early: at least this many)"
            }
        )?;
        write!(
            f,
            "closed: {}",
            if self.is_closed() {
                "yes"
            } else {
                "no (the winding number still defines inside; see techniques::clip)"
            }
        )
    }
}

fn v(m: &TriangleMesh, i: u32) -> DVec3 {
    DVec3::from_array(m.vertices[i as usize])
}

/// Count what [`MeshReport`] lists.
pub fn inspect(mesh: &TriangleMesh) -> MeshReport {
    // Per undirected edge: (uses a->b with a < b, uses b->a).
    let mut edges: HashMap<(u32, u32), (u32, u32)> =
        HashMap::with_capacity(mesh.triangles.len() * 2);
    let mut degenerate = 0;
    let mut volume = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| v(mesh, i));
        volume += a.dot(b.cross(c)) / 6.0;
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (b - a).cross(c - a) == DVec3::ZERO {
            degenerate += 1;
        }
        for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if p == q {
                continue;
            }
            let e = edges.entry((p.min(q), p.max(q))).or_default();
            if p < q {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
        }
    }
    let mut report = MeshReport {
        vertices: mesh.vertices.len(),
        triangles: mesh.triangles.len(),
        min: mesh.bounds().0,
        max: mesh.bounds().1,
        edges: edges.len(),
        open_edges: 0,
        non_manifold_edges: 0,
        misoriented_edges: 0,
        degenerate_triangles: degenerate,
        signed_volume: volume,
        self_intersections: 0,
        self_intersection_search_complete: true,
    };
    for &(forward, backward) in edges.values() {
        match forward + backward {
            1 => report.open_edges += 1,
            2 if forward != 1 => report.misoriented_edges += 1,
            2 => {}
            _ => report.non_manifold_edges += 1,
        }
    }
    let (count, complete) = self_intersections(mesh);
    report.self_intersections = count;
    report.self_intersection_search_complete = complete;
    report
}

/// Approximate count of intersecting triangle pairs (see the module doc) and whether the
/// search finished.
pub fn self_intersections(mesh: &TriangleMesh) -> (usize, bool) {
    let n = mesh.triangles.len();
    let (lo, hi) = mesh.bounds();
    let (lo, hi) = (DVec3::from_array(lo), DVec3::from_array(hi));
    let extent = (hi - lo).max(DVec3::splat(1e-300));
    // About one cell per triangle, cubic cells.
    let cell = (extent.x * extent.y * extent.z / n as f64)
        .cbrt()
        .max(extent.max_element() / 256.0);
    let cells =
        ((extent / cell).ceil().as_uvec3().max(glam::UVec3::ONE)).min(glam::UVec3::splat(256));
    let cell_of = |p: DVec3| {
        let c = ((p - lo) / extent * cells.as_dvec3()).floor().as_ivec3();
        c.clamp(glam::IVec3::ZERO, cells.as_ivec3() - 1)
    };
    let boxes: Vec<(DVec3, DVec3)> = (0..n)
        .map(|t| {
            let [a, b, c] = mesh.triangles[t].map(|i| v(mesh, i));
            (a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    for (t, &(bmin, bmax)) in boxes.iter().enumerate() {
        let (c0, c1) = (cell_of(bmin), cell_of(bmax));
        for z in c0.z..=c1.z {
            for y in c0.y..=c1.y {
                for x in c0.x..=c1.x {
                    grid.entry(glam::IVec3::new(x, y, z))
                        .or_default()
                        .push(t as u32);
                }
            }
        }
    }
    let mut found = 0;
    let mut tests = 0usize;
    for (&key, list) in &grid {
        for (i, &a) in list.iter().enumerate() {
            for &b in &list[i + 1..] {
                let (amin, amax) = boxes[a as usize];
                let (bmin, bmax) = boxes[b as usize];
                let (omin, omax) = (amin.max(bmin), amax.min(bmax));
                // Test each pair once: in the cell holding the overlap's low corner.
                if omin.cmpgt(omax).any() || cell_of(omin) != key {
                    continue;
                }
                let (ta, tb) = (mesh.triangles[a as usize], mesh.triangles[b as usize]);
                if ta.iter().any(|x| tb.contains(x)) {
                    continue;
                }
                tests += 1;
                if tests > MAX_PAIR_TESTS {
                    return (found, false);
                }
                let pa = ta.map(|i| v(mesh, i));
                let pb = tb.map(|i| v(mesh, i));
                if triangles_cross(pa, pb) || triangles_cross(pb, pa) {
                    found += 1;
                }
            }
        }
    }
    (found, true)
}

/// True when an edge of `a` passes through the interior of triangle `b`.
fn triangles_cross(a: [DVec3; 3], b: [DVec3; 3]) -> bool {
    (0..3).any(|e| segment_hits_triangle(a[e], a[(e + 1) % 3], b))
}

/// Möller-Trumbore on a segment, strict: the hit must lie inside the segment and the
/// triangle by a relative margin (touching contacts are not counted).
fn segment_hits_triangle(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    const EPS: f64 = 1e-9;
    let d = q - p;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() <= EPS * d.length() * e1.length() * e2.length() {
        return false; // parallel or coplanar: not tested
    }
    let s = p - t[0];
    let u = s.dot(h) / det;
    let qv = s.cross(e1);
    let w = d.dot(qv) / det;
    let r = e2.dot(qv) / det;
    u > EPS && w > EPS && u + w < 1.0 - EPS && r > EPS && r < 1.0 - EPS
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// An axis-aligned box [0,2]x[0,1]x[0,3] as 12 outward triangles.
    pub(crate) fn box_mesh() -> TriangleMesh {
        let s = [2.0, 1.0, 3.0];
        let vertices = (0..8)
            .map(|i| {
                [
                    (i & 1) as f64 * s[0],
                    ((i >> 1) & 1) as f64 * s[1],
                    ((i >> 2) & 1) as f64 * s[2],
                ]
            })
            .collect();
        let quads: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        TriangleMesh::from_indexed(Path::new("box"), vertices, quads).unwrap()
    }

    #[test]
    fn a_closed_box() {
        let r = inspect(&box_mesh());
        assert_eq!((r.triangles, r.edges), (12, 18));
        assert!(r.is_closed(), "{r}");
        assert!((r.signed_volume - 6.0).abs() < 1e-12);
        assert_eq!((r.degenerate_triangles, r.self_intersections), (0, 0));
    }

    #[test]
    fn defects_are_counted() {
        let mut m = box_mesh();
        m.triangles.pop();
        let r = inspect(&m);
        assert_eq!(r.open_edges, 3, "{r}");
        let mut m = box_mesh();
        m.triangles[0].swap(1, 2);
        let r = inspect(&m);
        assert_eq!((r.open_edges, r.misoriented_edges), (0, 3), "{r}");
        let mut m = box_mesh();
        let t = m.triangles[0];
        m.triangles.push(t);
        m.triangles.push([0, 0, 1]);
        let r = inspect(&m);
        assert_eq!(r.non_manifold_edges, 3 + 1, "{r}"); // and edge 0-1 of [0, 0, 1]
        assert_eq!(r.degenerate_triangles, 1);
        assert!(r.to_string().contains("closed: no"));
    }

    #[test]
    fn two_crossing_boxes_intersect() {
        let a = box_mesh();
        let b = a.map_vertices(|p| [p[0] + 1.0, p[1] + 0.5, p[2] + 1.2]);
        let mut m = a.clone();
        let off = m.vertices.len() as u32;
        m.vertices.extend(b.vertices);
        m.triangles
            .extend(b.triangles.iter().map(|t| t.map(|i| i + off)));
        let r = inspect(&m);
        assert!(r.self_intersections >= 4, "{r}");
        assert!(r.is_closed());
        let c = box_mesh().map_vertices(|p| [p[0] + 5.0, p[1], p[2]]);
        let mut m = box_mesh();
        m.vertices.extend(c.vertices);
        m.triangles
            .extend(c.triangles.iter().map(|t| t.map(|i| i + 8)));
        assert_eq!(inspect(&m).self_intersections, 0);
    }
}
