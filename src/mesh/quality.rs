//! Tetrahedron quality: signed volume, flat and sliver tetrahedra.
//!
//! Definitions (for the extremes of DESIGN §4):
//! - **Signed volume** `det(p1 - p0, p2 - p0, p3 - p0) / 6`; positive for every tetrahedron
//!   of a [`Mesh`](super::Mesh) except flat ones, which may be 0 or round-off negative.
//! - **Flat**: `|volume| <= 1e-12 * L^3`, `L` the longest edge (relative, so the test does
//!   not depend on the mesh's units); a tetrahedron with `L = 0` (all four points equal)
//!   is flat. The renderer cannot get a gradient from a flat tetrahedron.
//! - **Sliver**: not flat, and a radius ratio `rho = 3 r / R` below
//!   [`SLIVER_RADIUS_RATIO`] (`r` the inradius `3 V / (sum of face areas)`, `R` the
//!   circumradius; `rho = 1` for the regular tetrahedron, 0.717 for the cube's Kuhn
//!   tetrahedra). The radius ratio is low for every badly shaped tetrahedron (true
//!   slivers, needles, caps, wedges), which is what makes exit-point and gradient
//!   computations ill-conditioned, so "sliver" here means any of them.

use super::cells::det;
use super::Mesh;

/// Radius ratio below which a non-flat tetrahedron counts as a sliver.
pub const SLIVER_RADIUS_RATIO: f64 = 0.1;

/// Relative volume below which a tetrahedron is flat (times the longest edge cubed).
pub const FLAT_RELATIVE_VOLUME: f64 = 1e-12;

/// Signed volume of tetrahedron `t`.
pub fn signed_volume(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    det(points, t) / 6.0
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm2(a: [f64; 3]) -> f64 {
    a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
}

/// Longest edge of `t`.
pub fn longest_edge(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    let p = t.map(|i| points[i as usize]);
    let mut l: f64 = 0.0;
    for a in 0..4 {
        for b in a + 1..4 {
            l = l.max(norm2(sub(p[a], p[b])));
        }
    }
    l.sqrt()
}

/// True when `t` is flat (see the module doc).
pub fn is_flat(points: &[[f64; 3]], t: [u32; 4]) -> bool {
    let l = longest_edge(points, t);
    signed_volume(points, t).abs() <= FLAT_RELATIVE_VOLUME * l * l * l
}

/// Radius ratio `3 r / R` of `t` (1 for the regular tetrahedron, 0 when flat).
pub fn radius_ratio(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    let p = t.map(|i| points[i as usize]);
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let v6 = det(points, t).abs();
    if v6 == 0.0 {
        return 0.0;
    }
    let area2 = |x: [f64; 3], y: [f64; 3]| norm2(cross(x, y)).sqrt(); // twice a face area
    let faces = area2(a, b) + area2(b, c) + area2(c, a) + area2(sub(b, a), sub(c, a));
    let r = v6 / faces; // 3V / (sum of areas) = (6V) / (2 * sum of areas)
    let (ab, bc, ca) = (cross(a, b), cross(b, c), cross(c, a));
    let num: [f64; 3] =
        std::array::from_fn(|k| norm2(a) * bc[k] + norm2(b) * ca[k] + norm2(c) * ab[k]);
    let big_r = norm2(num).sqrt() / (2.0 * v6); // |...| / (12 V)
    if big_r > 0.0 && big_r.is_finite() {
        (3.0 * r / big_r).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Quality summary of a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quality {
    /// Flat tetrahedra.
    pub flat: usize,
    /// Sliver tetrahedra (not counting flat ones).
    pub slivers: usize,
    /// Sum of the signed volumes.
    pub total_volume: f64,
    /// Smallest signed volume (+inf without tetrahedra).
    pub min_volume: f64,
    /// Smallest radius ratio among the non-flat tetrahedra (1 when there are none).
    pub min_radius_ratio: f64,
}

impl Quality {
    /// Measure every tetrahedron of `mesh`.
    pub fn of(mesh: &Mesh) -> Quality {
        let mut q = Quality {
            flat: 0,
            slivers: 0,
            total_volume: 0.0,
            min_volume: f64::INFINITY,
            min_radius_ratio: 1.0,
        };
        for &t in &mesh.tets {
            let v = signed_volume(&mesh.points, t);
            q.total_volume += v;
            q.min_volume = q.min_volume.min(v);
            if is_flat(&mesh.points, t) {
                q.flat += 1;
                continue;
            }
            let rho = radius_ratio(&mesh.points, t);
            q.min_radius_ratio = q.min_radius_ratio.min(rho);
            if rho < SLIVER_RADIUS_RATIO {
                q.slivers += 1;
            }
        }
        q
    }
}
