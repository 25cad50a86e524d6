//! What is wrong with a surface, counted (not refused): open and non-manifold edges,
//! edges whose two triangles disagree on orientation, degenerate triangles, the signed
//! volume, and an approximate count of self-intersecting triangle pairs.
//!
//! Everything is computed on the vertices scaled by a power of two into [-2, 2]³ (exact:
//! the same bits of mantissa), so coordinates anywhere in f64's range (±1.7e308, or
//! 1e-300) give finite products; the signed volume is scaled back, and where it is beyond
//! f64's range the report says so and gives its power of ten.
//!
//! Self-intersections are found approximately: triangle pairs whose bounding boxes meet
//! in a uniform grid are tested edge-against-triangle (Möller-Trumbore, strict interior);
//! pairs sharing a vertex and coplanar overlaps are not tested. The search's whole work
//! is bounded by [`MAX_WORK`]: every triangle-cell insertion and every pair considered in
//! a cell costs one unit (pairs skipped for sharing a vertex or for boxes that do not
//! meet included), every exact pair test [`PAIR_TEST_COST`] more. The grid is chosen
//! among the finest one (about a triangle per cell) and its coarser halvings as the one
//! with the fewest insertions plus pairs, counting each candidate's insertions against a
//! quarter of the work: long triangles spanning the grid, which a fine grid would insert
//! into every cell and pair in every cell, choose a coarse one. When the work runs out
//! the search stops and the report says "search stopped early after N units of work".
//! A count of 0 is therefore "none found", not a proof.

use std::fmt;

use glam::DVec3;

use super::TriangleMesh;

/// Units of work after which the self-intersection search stops, sized to keep the
/// search short on one core (measured: docs/benchmarks.md, "Memory estimates and work
/// limits"; see the module doc for what a unit is).
pub const MAX_WORK: u64 = 40_000_000;

/// Units an exact triangle-pair test costs on top of considering the pair (six segment
/// tests, each a few dozen flops).
pub const PAIR_TEST_COST: u64 = 16;

/// Most grid cells along an axis.
const MAX_CELLS: u32 = 128;

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
    /// Sum of the signed tetrahedron volumes (positive for an outward orientation);
    /// ±infinity (or 0) where it is beyond f64's range (see [`MeshReport::volume_log10`]).
    pub signed_volume: f64,
    /// log10 of the signed volume's magnitude (finite whenever the volume is not 0).
    pub volume_log10: f64,
    /// Self-intersecting triangle pairs found (approximate, see the module doc).
    pub self_intersections: usize,
    /// False when the self-intersection search stopped early.
    pub self_intersection_search_complete: bool,
    /// Units of work the search spent (at most [`MAX_WORK`] and one pair test).
    pub self_intersection_work: u64,
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
        let beyond = !self.signed_volume.is_finite()
            || (self.signed_volume == 0.0 && self.volume_log10.is_finite());
        if !beyond {
            writeln!(f, "signed volume: {:.6}", self.signed_volume)?;
        } else {
            let sign = if self.signed_volume < 0.0 { "-" } else { "" };
            let exponent = self.volume_log10.floor();
            writeln!(
                f,
                "signed volume: {sign}{:.6}e{exponent} (beyond f64's range)",
                10f64.powf(self.volume_log10 - exponent)
            )?;
        }
        writeln!(
            f,
            "self-intersecting pairs (approximate): {}{}",
            self.self_intersections,
            if self.self_intersection_search_complete {
                String::new()
            } else {
                format!(
                    " (search stopped early after {} units of work: at least this many)",
                    self.self_intersection_work
                )
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

/// The vertices scaled by the power of two `2^-k` that brings the largest coordinate
/// magnitude into [0.5, 2] (exact), and `k`.
fn scaled(mesh: &TriangleMesh) -> (Vec<DVec3>, i32) {
    let largest = mesh
        .vertices
        .iter()
        .flatten()
        .fold(0f64, |m, c| m.max(c.abs()));
    let k = if largest > 0.0 && largest.is_finite() {
        (largest.log2().ceil() as i32).clamp(-1022, 1023)
    } else {
        0
    };
    let s = 2f64.powi(-k);
    let vertices = mesh
        .vertices
        .iter()
        .map(|p| DVec3::from_array(*p) * s)
        .collect();
    (vertices, k)
}

/// `v * 2^e` for any `e`, in steps that each stay within f64's exponents (the result is
/// ±infinity or 0 only where `v * 2^e` is beyond f64's range).
fn times_power_of_two(mut v: f64, mut e: i32) -> f64 {
    while e != 0 && v.is_finite() && v != 0.0 {
        let step = e.clamp(-1000, 1000);
        v *= 2f64.powi(step);
        e -= step;
    }
    v
}

/// Count what [`MeshReport`] lists.
pub fn inspect(mesh: &TriangleMesh) -> MeshReport {
    let (vertices, k) = scaled(mesh);
    let v = |i: u32| vertices[i as usize];
    // Per undirected edge: (uses a->b with a < b, uses b->a).
    let mut edges: std::collections::HashMap<(u32, u32), (u32, u32)> =
        std::collections::HashMap::with_capacity(mesh.triangles.len() * 2);
    let mut degenerate = 0;
    let mut volume = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(v);
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
    let signed_volume = times_power_of_two(volume, 3 * k);
    let volume_log10 = volume.abs().log10() + 3.0 * k as f64 * std::f64::consts::LOG10_2;
    let (lo, hi) = mesh.bounds();
    let mut report = MeshReport {
        vertices: mesh.vertices.len(),
        triangles: mesh.triangles.len(),
        min: lo,
        max: hi,
        edges: edges.len(),
        open_edges: 0,
        non_manifold_edges: 0,
        misoriented_edges: 0,
        degenerate_triangles: degenerate,
        signed_volume,
        volume_log10,
        self_intersections: 0,
        self_intersection_search_complete: true,
        self_intersection_work: 0,
    };
    for &(forward, backward) in edges.values() {
        match forward + backward {
            1 => report.open_edges += 1,
            2 if forward != 1 => report.misoriented_edges += 1,
            2 => {}
            _ => report.non_manifold_edges += 1,
        }
    }
    let search = search(&vertices, &mesh.triangles, MAX_WORK);
    report.self_intersections = search.found;
    report.self_intersection_search_complete = search.complete;
    report.self_intersection_work = search.work;
    report
}

/// What a self-intersection search found and spent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Search {
    /// Intersecting pairs found.
    pub found: usize,
    /// False when the work ran out.
    pub complete: bool,
    /// Units of work spent.
    pub work: u64,
}

/// Approximate count of intersecting triangle pairs (see the module doc) and whether the
/// search finished within [`MAX_WORK`].
pub fn self_intersections(mesh: &TriangleMesh) -> (usize, bool) {
    let (vertices, _) = scaled(mesh);
    let s = search(&vertices, &mesh.triangles, MAX_WORK);
    (s.found, s.complete)
}

/// The uniform grid of the search: cells along each axis over `[lo, lo + extent]`.
struct Grid {
    lo: DVec3,
    extent: DVec3,
    cells: glam::UVec3,
}

impl Grid {
    fn cell_of(&self, p: DVec3) -> glam::UVec3 {
        let c = ((p - self.lo) / self.extent * self.cells.as_dvec3()).floor();
        // NaN (a zero extent) and out-of-range values clamp into the grid.
        let c = c.max(DVec3::ZERO).min((self.cells - 1).as_dvec3());
        c.as_uvec3()
    }

    fn index(&self, c: glam::UVec3) -> usize {
        (c.x + self.cells.x * (c.y + self.cells.y * c.z)) as usize
    }

    /// The start of each cell's list in an array of every (cell, triangle) insertion of
    /// `boxes`, and its end (one more entry than cells).
    fn starts(&self, boxes: &[(DVec3, DVec3)]) -> Vec<u32> {
        let cells = (self.cells.x * self.cells.y * self.cells.z) as usize;
        let mut start = vec![0u32; cells + 1];
        for b in boxes {
            let (c0, c1) = (self.cell_of(b.0), self.cell_of(b.1));
            for z in c0.z..=c1.z {
                for y in c0.y..=c1.y {
                    let row = self.index(glam::UVec3::new(c0.x, y, z));
                    for x in 0..=(c1.x - c0.x) as usize {
                        start[row + x + 1] += 1;
                    }
                }
            }
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        start
    }

    /// Cells the box `(bmin, bmax)` covers.
    fn covered(&self, bmin: DVec3, bmax: DVec3) -> u64 {
        let (c0, c1) = (self.cell_of(bmin), self.cell_of(bmax));
        let d = (c1 - c0 + 1).as_u64vec3();
        d.x * d.y * d.z
    }
}

/// The search over `triangles` of `vertices` (scaled into [-2, 2]³), spending at most
/// about `max_work` units (see the module doc).
pub(crate) fn search(vertices: &[DVec3], triangles: &[[u32; 3]], max_work: u64) -> Search {
    let n = triangles.len();
    let boxes: Vec<(DVec3, DVec3)> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            (a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    let (lo, hi) = boxes
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), b| {
            (lo.min(b.0), hi.max(b.1))
        });
    if n < 2 {
        return Search {
            found: 0,
            complete: true,
            work: 0,
        };
    }
    let extent = (hi - lo).max(DVec3::splat(1e-300));
    // About one cell per triangle, cubic cells, at most MAX_CELLS along an axis; then
    // coarser grids, each costing its insertions to count, while that stays within a
    // quarter of the work: the grid with the fewest insertions plus pairs is searched.
    let cell = (extent.x * extent.y * extent.z / n as f64)
        .cbrt()
        .max(extent.max_element() / MAX_CELLS as f64);
    let mut cells = (extent / cell)
        .ceil()
        .as_uvec3()
        .clamp(glam::UVec3::ONE, glam::UVec3::splat(MAX_CELLS));
    let mut work = 0u64;
    let mut best: Option<(u64, Grid, Vec<u32>)> = None;
    loop {
        let grid = Grid { lo, extent, cells };
        let fits = boxes.iter().try_fold(0u64, |sum, b| {
            let s = sum + grid.covered(b.0, b.1);
            (s <= max_work / 4).then_some(s)
        });
        if let Some(insertions) = fits {
            work += insertions;
            let start = grid.starts(&boxes);
            let pairs = start.windows(2).fold(0u64, |sum, w| {
                let k = (w[1] - w[0]) as u64;
                sum.saturating_add(k * k.saturating_sub(1) / 2)
            });
            let cost = insertions.saturating_add(pairs);
            if best.as_ref().is_none_or(|b| cost < b.0) {
                best = Some((cost, grid, start));
            }
        }
        if cells == glam::UVec3::ONE || work > max_work / 4 {
            break;
        }
        cells = (cells / 2).max(glam::UVec3::ONE);
    }
    let Some((_, grid, start)) = best else {
        // Even one cell holds more insertions than a quarter of the work (n is larger).
        return Search {
            found: 0,
            complete: false,
            work,
        };
    };
    // Cell lists as one array (a counting sort): `start[c]..start[c + 1]` in `entries`.
    let total_cells = start.len() - 1;
    let mut fill = start.clone();
    let mut entries = vec![0u32; start[total_cells] as usize];
    work += entries.len() as u64;
    for (t, b) in boxes.iter().enumerate() {
        let (c0, c1) = (grid.cell_of(b.0), grid.cell_of(b.1));
        for z in c0.z..=c1.z {
            for y in c0.y..=c1.y {
                let row = grid.index(glam::UVec3::new(c0.x, y, z));
                for x in 0..=(c1.x - c0.x) as usize {
                    entries[fill[row + x] as usize] = t as u32;
                    fill[row + x] += 1;
                }
            }
        }
    }
    drop(fill);
    let mut found = 0;
    for c in 0..total_cells {
        let list = &entries[start[c] as usize..start[c + 1] as usize];
        for (i, &a) in list.iter().enumerate() {
            for &b in &list[i + 1..] {
                work += 1;
                if work > max_work {
                    return Search {
                        found,
                        complete: false,
                        work,
                    };
                }
                let (amin, amax) = boxes[a as usize];
                let (bmin, bmax) = boxes[b as usize];
                let (omin, omax) = (amin.max(bmin), amax.min(bmax));
                // Test each pair once: in the cell holding the overlap's low corner.
                if omin.cmpgt(omax).any() || grid.index(grid.cell_of(omin)) != c {
                    continue;
                }
                let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
                if ta.iter().any(|x| tb.contains(x)) {
                    continue;
                }
                work += PAIR_TEST_COST;
                let pa = ta.map(|i| vertices[i as usize]);
                let pb = tb.map(|i| vertices[i as usize]);
                if triangles_cross(pa, pb) || triangles_cross(pb, pa) {
                    found += 1;
                }
            }
        }
    }
    Search {
        found,
        complete: true,
        work,
    }
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
    // --- issue 17: clouds and surfaces ---

    /// `copies` copies of one face, each with its own three vertices (`shared` false:
    /// nothing skips them) or all on the same three (`shared` true).
    fn copies_of_one_face(copies: usize, shared: bool) -> TriangleMesh {
        let face = [[0.0, 0.0, 0.0], [1.0, 0.25, 0.0], [0.1, 1.0, 0.3]];
        let mut m = TriangleMesh {
            vertices: face.to_vec(),
            triangles: Vec::new(),
            properties: Vec::new(),
        };
        for c in 0..copies as u32 {
            if shared {
                m.triangles.push([0, 1, 2]);
            } else {
                m.vertices.extend(face);
                m.triangles.push([3 * c + 3, 3 * c + 4, 3 * c + 5]);
            }
        }
        m
    }

    #[test]
    fn copies_of_one_face_stop_the_search_within_its_work() {
        for shared in [false, true] {
            let m = copies_of_one_face(3000, shared);
            let t = std::time::Instant::now();
            let r = inspect(&m);
            let took = t.elapsed();
            // 4.5 million pairs: on their own vertices each is tested (17 units), far over
            // the work; on shared ones each is skipped (1 unit) and the search finishes.
            assert_eq!(r.self_intersection_search_complete, shared, "{r}");
            assert!(
                r.self_intersection_work <= MAX_WORK + PAIR_TEST_COST,
                "{}",
                r.self_intersection_work
            );
            assert_eq!(
                r.to_string().contains("search stopped early after"),
                !shared,
                "{r}"
            );
            assert_eq!(
                r.self_intersections, 0,
                "coplanar copies are not tested as crossing"
            );
            // MAX_WORK keeps the search short in release (docs/benchmarks.md, "Memory
            // estimates and work limits"); the bound leaves room for a debug build on a
            // busy machine. Minutes before the work was bounded.
            assert!(took.as_secs_f64() < 30.0, "{took:?}");
        }
    }

    #[test]
    fn long_triangles_spanning_the_grid_coarsen_it() {
        // 20,000 small triangles on a 100x200 lattice, and 200 slivers from one corner of
        // the box to the other, each covering every cell of the fine grid (22,000 cells:
        // 20,000 sliver pairs in each, 440 million pairs, far over the work; a grid of
        // 6x6x8 cells holds them in about 16 million).
        let mut m = TriangleMesh {
            vertices: Vec::new(),
            triangles: Vec::new(),
            properties: Vec::new(),
        };
        for i in 0..100 {
            for j in 0..200 {
                let (x, y) = (i as f64 * 0.01, j as f64 * 0.005);
                let v = m.vertices.len() as u32;
                m.vertices
                    .extend([[x, y, 0.0], [x + 0.004, y, 0.0], [x, y + 0.002, 0.001]]);
                m.triangles.push([v, v + 1, v + 2]);
            }
        }
        for k in 0..200 {
            let z = 0.5 + k as f64 * 2e-3;
            let v = m.vertices.len() as u32;
            m.vertices
                .extend([[0.0, 0.0, z], [1.0, 1.0, z + 0.5], [1.0, 0.999, z + 0.5]]);
            m.triangles.push([v, v + 1, v + 2]);
        }
        // One real crossing: a triangle through the first lattice triangle's interior.
        let v = m.vertices.len() as u32;
        m.vertices.extend([
            [0.001, 0.0005, -0.5],
            [0.0015, 0.0005, 0.5],
            [0.5, 0.7, 0.3],
        ]);
        m.triangles.push([v, v + 1, v + 2]);
        let (vertices, _) = scaled(&m);
        let s = search(&vertices, &m.triangles, MAX_WORK);
        assert!(s.work <= MAX_WORK + PAIR_TEST_COST, "{s:?}");
        assert!(s.complete, "{s:?}");
        assert!(s.found >= 1, "{s:?}");
        // The same search, deterministic (cells in index order).
        assert_eq!(search(&vertices, &m.triangles, MAX_WORK), s);
        // With a tenth of the work it stops, saying so, never over the bound.
        let short = search(&vertices, &m.triangles, MAX_WORK / 10);
        assert!(
            !short.complete && short.work <= MAX_WORK / 10 + PAIR_TEST_COST,
            "{short:?}"
        );
    }
}
