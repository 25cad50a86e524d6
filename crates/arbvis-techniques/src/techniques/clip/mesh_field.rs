//! Closed triangle meshes as clip objects: the signed distance on a grid, and the f64
//! membership reference.
//!
//! # Inside and outside
//! The reference ([`MeshShape::inside`]) is the *generalized winding number* (Jacobson et
//! al. 2013): the sum of the signed solid angles of the triangles seen from the point,
//! over 4π; inside when `|w| >= 0.5` (non-zero rule: an inward-oriented mesh still has an
//! inside). For a closed mesh it is exactly 1 inside and 0 outside; with small holes,
//! cracks or a few flipped triangles it degrades smoothly and only near the defect, which
//! is why it was chosen over ray parity (one ray through a hole flips a whole streak).
//! Its cost is one `atan2` per triangle per point: fine for the reference, far too slow
//! for every voxel of a 256³ grid (16.7 M points x 11,036 triangles). The grid's rows
//! that need it use the fast winding number instead ([`super::fast_winding`]: a tree of
//! Taylor expansions, within [`super::fast_winding::ERROR_BOUND`] of the exact sum).
//!
//! # Placement
//! [`MeshShape::placed`] refuses a mesh whose placed vertices are not finite or lie
//! beyond [`MAX_PLACED`] of the grid's centre (scale is applied first, so a file's
//! coordinates near ±1.7e308 with a small scale are fine): every length, cross product
//! and expansion term the field forms then stays finite.
//!
//! # The grid
//! The texture clamps at one voxel diagonal, so exact distances are needed only within
//! one diagonal of the surface, and elsewhere only the sign. Per k-slice (in parallel):
//! - distances: each triangle whose bounding box, grown by one diagonal, meets the slice
//!   writes the exact point-triangle distance (Ericson's closest point) to the voxel
//!   centres of that grown box that lie within one diagonal of its plane (an x-interval
//!   per row, so the work follows the surface's area, not its triangles' boxes); the
//!   minimum is kept. Voxels no triangle reached are more
//!   than one diagonal away and get `±2 diag`.
//! - signs: each row `(j, k)` along x collects its crossings with the triangles, found
//!   with a watertight 2D point-in-triangle test in the yz-plane (exact orientation sign
//!   with a symbolic tie-break, after Batty's SDFGen), so a row through a shared edge or
//!   vertex counts exactly one crossing. Each crossing carries the sign of the triangle's
//!   facing; the winding number of a voxel centre is the sum of the crossings to its left.
//!   For a closed mesh the row's crossings sum to zero. A row whose sum is not zero
//!   passed through a hole: there the generalized winding number decides, evaluated at
//!   both ends of each run of voxels between crossings, and runs whose ends disagree are
//!   bisected to find the change (a few evaluations per damaged row, not one per voxel;
//!   a run whose ends agree is taken as uniform, which misses a hole crossed twice). [`MeshShape::field`] counts such rows in [`MeshShape::repaired_rows`].

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::error::ClipError;
use super::fast_winding::{solid_angle, WindingTree};
use super::grid::ClipGrid;
use arbvis_data::surface::{Position, SurfaceError, TriangleMesh};

/// Largest coordinate of a placed clip mesh (the grid spans at most [-1, 1]³: 1e15 is
/// as far as infinity for it, and keeps every product the field forms, up to seventh
/// powers of distances in the expansions, far from overflow).
pub const MAX_PLACED: f64 = 1e15;

/// Bytes a triangle costs once placed: its corners (72), the tree's copy (72) and its
/// share of the tree's nodes (about 40), its box while the field is made (48).
const TRIANGLE_BYTES: u64 = 72 + 72 + 40 + 48;

/// Largest number of (triangle, slice) pairs binned before slices scan all triangles.
pub const MAX_BIN_ENTRIES: usize = 1 << 26;

/// How [`MeshShape::field_with`] evaluates winding numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Winding {
    /// The tree of expansions ([`super::fast_winding`]).
    Fast,
    /// Every triangle (the reference; slow on large grids).
    Exact,
}

/// A mesh placed in object space, ready to evaluate.
#[derive(Debug)]
pub struct MeshShape {
    /// Triangles' corners in object space.
    pub triangles: Vec<[DVec3; 3]>,
    tree: WindingTree,
    repaired: AtomicUsize,
}

impl Clone for MeshShape {
    fn clone(&self) -> Self {
        MeshShape {
            triangles: self.triangles.clone(),
            tree: self.tree.clone(),
            repaired: AtomicUsize::new(self.repaired_rows()),
        }
    }
}

impl MeshShape {
    /// Place `mesh`: each vertex `v` goes to `position + rotation * (scale * v)`.
    pub fn new(
        mesh: &TriangleMesh,
        position: DVec3,
        scale: DVec3,
        rotation: glam::DQuat,
    ) -> MeshShape {
        let place = |p: [f64; 3]| position + rotation * (scale * DVec3::from_array(p));
        let triangles: Vec<[DVec3; 3]> = (0..mesh.triangles.len())
            .map(|t| mesh.corners(t).map(place))
            .collect();
        MeshShape {
            tree: WindingTree::new(&triangles),
            triangles,
            repaired: AtomicUsize::new(0),
        }
    }

    /// [`MeshShape::new`] for a mesh read from `name`, refused (naming the vertex) when a
    /// placed vertex is not finite or lies beyond [`MAX_PLACED`], or when the placed
    /// triangles and their tree would pass the memory budget.
    pub fn placed(
        name: &std::path::Path,
        mesh: &TriangleMesh,
        position: DVec3,
        scale: DVec3,
        rotation: glam::DQuat,
    ) -> Result<MeshShape, ClipError> {
        let fail = |position: Position, message: String| {
            ClipError::Surface(SurfaceError::format(name, position, message))
        };
        let triangles = mesh.triangles.len() as u64;
        arbvis_core::budget::check(
            format!("placing a clip mesh of {triangles} triangles"),
            arbvis_core::budget::times(triangles, TRIANGLE_BYTES),
        )
        .map_err(|e| fail(Position::Item("triangle", 0), e.to_string()))?;
        for (i, p) in mesh.vertices.iter().enumerate() {
            let q = position + rotation * (scale * DVec3::from_array(*p));
            if !q.is_finite() || q.abs().max_element() > MAX_PLACED {
                return Err(fail(
                    Position::Item("vertex", i),
                    format!(
                        "[{:.3e}, {:.3e}, {:.3e}] placed with scale {} at [{:.3e}, {:.3e}, {:.3e}]: a clip mesh must lie within ±{MAX_PLACED:e} of the volume's centre (the volume spans at most ±1); scale it down or move it",
                        p[0], p[1], p[2], scale.x, q.x, q.y, q.z
                    ),
                ));
            }
        }
        Ok(MeshShape::new(mesh, position, scale, rotation))
    }

    /// Rows of the last [`MeshShape::field`] whose crossings did not sum to zero (holes,
    /// non-manifold or flipped parts) and were decided by the winding number.
    pub fn repaired_rows(&self) -> usize {
        self.repaired.load(Ordering::Relaxed)
    }

    /// Generalized winding number at `p` (van Oosterom-Strackee solid angles, every
    /// triangle: the exact sum).
    pub fn winding_number(&self, p: DVec3) -> f64 {
        let sum: f64 = self.triangles.iter().map(|t| solid_angle(t, p)).sum();
        sum / (4.0 * std::f64::consts::PI)
    }

    /// The fast winding number at `p` (within [`super::fast_winding::ERROR_BOUND`] of
    /// [`MeshShape::winding_number`]).
    pub fn fast_winding_number(&self, p: DVec3) -> f64 {
        self.tree.winding_number(p)
    }

    /// The f64 reference: inside when `|winding number| >= 0.5`.
    pub fn inside(&self, p: DVec3) -> bool {
        self.winding_number(p).abs() >= 0.5
    }

    /// Exact unsigned distance to the surface (every triangle; for tests and references).
    pub fn unsigned_distance(&self, p: DVec3) -> f64 {
        self.triangles
            .iter()
            .map(|t| (closest_point(p, *t) - p).length())
            .fold(f64::INFINITY, f64::min)
    }

    /// Clip distance at every voxel centre (see the module doc), i fastest.
    pub fn field(&self, grid: &ClipGrid) -> Vec<f32> {
        self.field_binned(grid, MAX_BIN_ENTRIES)
    }

    /// [`MeshShape::field`] binning at most `max_bin_entries` (triangle, slice) pairs.
    pub(crate) fn field_binned(&self, grid: &ClipGrid, max_bin_entries: usize) -> Vec<f32> {
        self.field_with(grid, max_bin_entries, Winding::Fast)
    }

    /// [`MeshShape::field_binned`] deciding damaged rows with `winding` (the exact sum is
    /// for comparisons: tests, and the study's timing of what the fast one replaced).
    pub fn field_with(
        &self,
        grid: &ClipGrid,
        max_bin_entries: usize,
        winding: Winding,
    ) -> Vec<f32> {
        let [ni, nj, nk] = grid.dims;
        let h = grid.voxel();
        let diag = grid.diagonal();
        let lo = -grid.half;
        // Voxel index range whose centres lie in [a, b] along axis `axis`.
        let range = |a: f64, b: f64, axis: usize, n: usize| -> Option<(usize, usize)> {
            let first = ((a - lo[axis]) / h[axis] - 0.5).ceil().max(0.0);
            let last = ((b - lo[axis]) / h[axis] - 0.5).floor().min(n as f64 - 1.0);
            (first <= last).then_some((first as usize, last as usize))
        };
        let boxes: Vec<(DVec3, DVec3)> = self
            .triangles
            .iter()
            .map(|[a, b, c]| (a.min(*b).min(*c), a.max(*b).max(*c)))
            .collect();
        // Triangles per k-slice; when that list would be huge (many triangles spanning
        // most of the grid), each slice scans all triangles instead.
        let slices_of = |t: usize| range(boxes[t].0.z - diag, boxes[t].1.z + diag, 2, nk);
        let entries: usize = (0..boxes.len())
            .map(|t| slices_of(t).map_or(0, |(k0, k1)| k1 - k0 + 1))
            .fold(0usize, usize::saturating_add);
        let binned = entries <= max_bin_entries;
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); if binned { nk } else { 0 }];
        for t in 0..boxes.len() {
            if let (true, Some((k0, k1))) = (binned, slices_of(t)) {
                for bin in &mut bins[k0..=k1] {
                    bin.push(t as u32);
                }
            }
        }
        self.repaired.store(0, Ordering::Relaxed);
        let mut out = vec![0f32; grid.len()];
        out.par_chunks_mut(ni * nj)
            .enumerate()
            .for_each(|(k, slice)| {
                let z = lo.z + (k as f64 + 0.5) * h.z;
                let mut distance = vec![f64::INFINITY; ni * nj];
                let mut rows: Vec<Vec<(f64, i32)>> = vec![Vec::new(); nj];
                let all: Vec<u32>;
                let list = if binned {
                    &bins[k]
                } else {
                    all = (0..boxes.len() as u32)
                        .filter(|&t| {
                            slices_of(t as usize).is_some_and(|(k0, k1)| (k0..=k1).contains(&k))
                        })
                        .collect();
                    &all
                };
                for &t in list {
                    let tri = self.triangles[t as usize];
                    let (bmin, bmax) = boxes[t as usize];
                    let Some((j0, j1)) = range(bmin.y - diag, bmax.y + diag, 1, nj) else {
                        continue;
                    };
                    // Crossings count even where the triangle lies beyond the grid in x.
                    let i_range = range(bmin.x - diag, bmax.x + diag, 0, ni);
                    let crosses_slice = z >= bmin.z && z <= bmax.z;
                    // Only centres within one diagonal of the triangle's plane can be within
                    // one diagonal of it: along a row that is an x-interval.
                    let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                    let reach = diag * normal.length();
                    for j in j0..=j1 {
                        let y = lo.y + (j as f64 + 0.5) * h.y;
                        let band = i_range.and_then(|(i0, i1)| {
                            let c = normal.dot(DVec3::new(0.0, y, z) - tri[0]);
                            if normal.x.abs() > reach * 1e-12 {
                                let (a, b) = ((-reach - c) / normal.x, (reach - c) / normal.x);
                                let (x0, x1) = (a.min(b), a.max(b));
                                let (b0, b1) = range(x0, x1, 0, ni)?;
                                (b0.max(i0) <= b1.min(i1)).then_some((b0.max(i0), b1.min(i1)))
                            } else {
                                (c.abs() <= reach || reach == 0.0).then_some((i0, i1))
                            }
                        });
                        if let Some((i0, i1)) = band {
                            for i in i0..=i1 {
                                let p = DVec3::new(lo.x + (i as f64 + 0.5) * h.x, y, z);
                                let d = (closest_point(p, tri) - p).length();
                                let cell = &mut distance[i + ni * j];
                                if d < *cell {
                                    *cell = d;
                                }
                            }
                        }
                        if crosses_slice && y >= bmin.y && y <= bmax.y {
                            if let Some(hit) = row_crossing(y, z, tri) {
                                rows[j].push(hit);
                            }
                        }
                    }
                }
                for (j, row) in rows.iter_mut().enumerate() {
                    row.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let y = lo.y + (j as f64 + 0.5) * h.y;
                    let inside = self.row_inside(row, ni, lo.x, h.x, [y, z], winding);
                    for (i, inside) in inside.into_iter().enumerate() {
                        let d = distance[i + ni * j].min(2.0 * diag);
                        slice[i + ni * j] = (if inside { d } else { -d }) as f32;
                    }
                }
            });
        out
    }

    /// Inside flags of the voxel centres of one row from its sorted crossings.
    fn row_inside(
        &self,
        row: &[(f64, i32)],
        ni: usize,
        x0: f64,
        hx: f64,
        [y, z]: [f64; 2],
        winding: Winding,
    ) -> Vec<bool> {
        let x_of = |i: usize| x0 + (i as f64 + 0.5) * hx;
        let total: i32 = row.iter().map(|c| c.1).sum();
        if total == 0 {
            let mut out = Vec::with_capacity(ni);
            let (mut next, mut winding) = (0, 0);
            for i in 0..ni {
                let x = x_of(i);
                while next < row.len() && row[next].0 < x {
                    winding += row[next].1;
                    next += 1;
                }
                out.push(winding != 0);
            }
            return out;
        }
        self.repaired.fetch_add(1, Ordering::Relaxed);
        // The winding number at the two ends of each run of voxels between crossings;
        // runs whose ends disagree (a hole lies across them) are bisected.
        let mut out = vec![false; ni];
        let mut start = 0;
        let mut next = 0;
        while start < ni {
            while next < row.len() && row[next].0 < x_of(start) {
                next += 1;
            }
            let mut end = start;
            while end + 1 < ni && !(next < row.len() && row[next].0 < x_of(end + 1)) {
                end += 1;
            }
            let at = |i: usize| {
                let p = DVec3::new(x_of(i), y, z);
                match winding {
                    Winding::Fast => self.fast_winding_number(p),
                    Winding::Exact => self.winding_number(p),
                }
                .abs()
                    >= 0.5
            };
            let (a, b) = (at(start), at(end));
            self.bisect(&mut out, start, end, a, b, &at);
            start = end + 1;
        }
        out
    }

    /// Fill `out[lo..=hi]` given the flags at both ends, bisecting where they differ.
    fn bisect(
        &self,
        out: &mut [bool],
        lo: usize,
        hi: usize,
        a: bool,
        b: bool,
        at: &dyn Fn(usize) -> bool,
    ) {
        if a == b {
            out[lo..=hi].fill(a);
        } else if hi - lo <= 1 {
            out[lo] = a;
            out[hi] = b;
        } else {
            let mid = (lo + hi) / 2;
            let m = at(mid);
            self.bisect(out, lo, mid, a, m, at);
            self.bisect(out, mid, hi, m, b, at);
        }
    }
}

/// Sign of the 2D orientation of `(x1, y1), (x2, y2)` about the origin, with Batty's
/// symbolic tie-break so that exactly collinear cases still get a consistent sign; and
/// the doubled signed area.
fn orientation(x1: f64, y1: f64, x2: f64, y2: f64) -> (i32, f64) {
    let area = y1 * x2 - x1 * y2;
    let sign = if area > 0.0 {
        1
    } else if area < 0.0 {
        -1
    } else if y2 > y1 {
        1
    } else if y2 < y1 {
        -1
    } else if x1 > x2 {
        1
    } else if x1 < x2 {
        -1
    } else {
        0
    };
    (sign, area)
}

/// Where the line `{(t, y, z)}` crosses triangle `tri`, and the crossing's sign (+1 where
/// an outward-oriented surface is entered going +x), or `None`.
fn row_crossing(y: f64, z: f64, tri: [DVec3; 3]) -> Option<(f64, i32)> {
    let [p1, p2, p3] = tri.map(|v| (v.y - y, v.z - z));
    let (sa, a) = orientation(p2.0, p2.1, p3.0, p3.1);
    if sa == 0 {
        return None;
    }
    let (sb, b) = orientation(p3.0, p3.1, p1.0, p1.1);
    if sb != sa {
        return None;
    }
    let (sc, c) = orientation(p1.0, p1.1, p2.0, p2.1);
    if sc != sa {
        return None;
    }
    let sum = a + b + c;
    if sum == 0.0 {
        return None;
    }
    let x = (a * tri[0].x + b * tri[1].x + c * tri[2].x) / sum;
    Some((x, sa))
}

/// Closest point of triangle `t` to `p` (Ericson, Real-Time Collision Detection 5.1.5).
pub fn closest_point(p: DVec3, t: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + v * ab;
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + w * ac;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + w * (c - b);
    }
    let denom = va + vb + vc;
    if denom == 0.0 || !denom.is_finite() {
        // Degenerate (zero-area) triangle: the closest of its three edges.
        return [(a, b), (b, c), (c, a)]
            .iter()
            .map(|&(s, e)| {
                let d = e - s;
                let len2 = d.length_squared();
                let t = if len2 > 0.0 {
                    ((p - s).dot(d) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                s + t * d
            })
            .min_by(|x, y| {
                (*x - p)
                    .length_squared()
                    .total_cmp(&(*y - p).length_squared())
            })
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}
