//! Tetrahedron quality: signed volume, flat, sliver and repeated tetrahedra, and how many
//! tetrahedra a line through the mesh crosses.
//!
//! Definitions (for the extremes of DESIGN §4):
//! - **Signed volume** `det(p1 - p0, p2 - p0, p3 - p0) / 6`; positive for every tetrahedron
//!   of a [`Mesh`](super::Mesh) except flat ones, which may be 0 or round-off negative.
//! - **Flat** (degenerate): `|volume| <= 1e-12 * L^3`, `L` the longest edge (relative, so
//!   the test does not depend on the mesh's units); a tetrahedron with `L = 0` (all four
//!   points equal) is flat. The renderer cannot get a gradient from a flat tetrahedron.
//! - **Sliver**: not flat, and a radius ratio `rho = 3 r / R` below
//!   [`SLIVER_RADIUS_RATIO`] (`r` the inradius `3 V / (sum of face areas)`, `R` the
//!   circumradius; `rho = 1` for the regular tetrahedron, 0.717 for the cube's Kuhn
//!   tetrahedra). The radius ratio is low for every badly shaped tetrahedron (true
//!   slivers, needles, caps, wedges), which is what makes exit-point and gradient
//!   computations ill-conditioned, so "sliver" here means any of them.
//! - **Repeated**: a tetrahedron with the same four corner coordinates as an earlier one
//!   (in any order; the same points, or other points at the same places): cells that
//!   overlap exactly.
//! - **Depth**: the mean number of tetrahedra that a line through the mesh's bounding box
//!   crosses, over all such lines. By Cauchy and Crofton, the lines meeting a convex body
//!   have a measure proportional to its surface area, so the mean is `sum of the
//!   tetrahedra's surface areas / surface area of the box`, counted over the tetrahedra
//!   that are neither flat nor repeated. In a mesh whose cells do not overlap it grows
//!   like the cube root of the tetrahedron count (about 20 for the seed's 24,576); cells
//!   stacked on each other or thin plates across the whole mesh make it as large as
//!   their number, and cell projection rasterizes about that many layers per pixel.
//!
//! Every measure is computed on the coordinates times the mesh's [`unit_scale`] (a power
//! of two, so exact), which keeps coordinates near ±1.7e308 from overflowing and tiny
//! ones from underflowing; volumes are scaled back with their exponent kept apart
//! ([`Quality::volume_log2`]), so a total beyond the largest f64 is still reported.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

use super::cells::{det_scaled, scale_log2, unit_scale};
use super::Mesh;

/// Radius ratio below which a non-flat tetrahedron counts as a sliver.
pub const SLIVER_RADIUS_RATIO: f64 = 0.1;

/// Relative volume below which a tetrahedron is flat (times the longest edge cubed).
pub const FLAT_RELATIVE_VOLUME: f64 = 1e-12;

/// The [`unit_scale`] of a set of points: the power of two that brings the largest
/// coordinate magnitude into `[0.5, 1)` (at most 4 near the largest f64).
pub fn mesh_scale(points: &[[f64; 3]]) -> f64 {
    unit_scale(points.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs())))
}

/// Signed volume of tetrahedron `t` in the file's units (infinite when that overflows).
pub fn signed_volume(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    signed_volume_scaled(points, t, 1.0)
}

/// Signed volume of tetrahedron `t` with the coordinates times `scale`.
pub fn signed_volume_scaled(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> f64 {
    det_scaled(points, t, scale) / 6.0
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

fn corners(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> [[f64; 3]; 4] {
    t.map(|i| points[i as usize].map(|c| c * scale))
}

/// Longest edge of `t`.
pub fn longest_edge(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    longest_edge_scaled(points, t, 1.0)
}

fn longest_edge_scaled(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> f64 {
    let p = corners(points, t, scale);
    let mut l: f64 = 0.0;
    for a in 0..4 {
        for b in a + 1..4 {
            l = l.max(norm2(sub(p[a], p[b])));
        }
    }
    l.sqrt()
}

/// What one pass over a tetrahedron measures (coordinates times a scale).
#[derive(Debug, Clone, Copy)]
pub struct Measure {
    /// Signed volume.
    pub volume: f64,
    /// Flat (see the module doc).
    pub flat: bool,
    /// Surface area.
    pub area: f64,
    /// Radius ratio (0 when the volume is 0).
    pub rho: f64,
}

/// Volume, flatness, surface area and radius ratio of `t`, from its corners times
/// `scale` (a power of two: see [`mesh_scale`]), in one pass.
pub fn measure(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> Measure {
    let p = corners(points, t, scale);
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let (ab, bc, ca) = (cross(a, b), cross(b, c), cross(c, a));
    let v6 = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
    let longest2 = [a, b, c, sub(p[2], p[1]), sub(p[3], p[1]), sub(p[3], p[2])]
        .iter()
        .map(|e| norm2(*e))
        .fold(0.0, f64::max);
    let l = longest2.sqrt();
    // NaN (an overflow the scale did not prevent) counts as flat.
    let flat = (v6 / 6.0)
        .abs()
        .partial_cmp(&(FLAT_RELATIVE_VOLUME * l * l * l))
        != Some(std::cmp::Ordering::Greater);
    // Twice the face areas: three around p0, and the one opposite it.
    let twice = [
        norm2(ab).sqrt(),
        norm2(bc).sqrt(),
        norm2(ca).sqrt(),
        norm2(cross(sub(b, a), sub(c, a))).sqrt(),
    ];
    let faces: f64 = twice.iter().sum();
    let rho = if v6 == 0.0 || !v6.is_finite() {
        0.0
    } else {
        let r = v6.abs() / faces; // 3V / (sum of areas) = (6V) / (2 * sum of areas)
        let num: [f64; 3] =
            std::array::from_fn(|k| norm2(a) * bc[k] + norm2(b) * ca[k] + norm2(c) * ab[k]);
        let big_r = norm2(num).sqrt() / (2.0 * v6.abs()); // |...| / (12 V)
        if big_r > 0.0 && big_r.is_finite() {
            (3.0 * r / big_r).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    Measure {
        volume: v6 / 6.0,
        flat,
        area: faces / 2.0,
        rho,
    }
}

/// True when `t` is flat (see the module doc).
pub fn is_flat(points: &[[f64; 3]], t: [u32; 4]) -> bool {
    is_flat_scaled(points, t, unit_scale(largest_of(points, t)))
}

fn largest_of(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    t.iter()
        .flat_map(|&i| points[i as usize])
        .fold(0.0f64, |m, c| m.max(c.abs()))
}

/// [`is_flat`] on coordinates times `scale` (flatness does not depend on the scale, but
/// overflow does).
pub fn is_flat_scaled(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> bool {
    measure(points, t, scale).flat
}

/// Radius ratio `3 r / R` of `t` (1 for the regular tetrahedron, 0 when its volume is 0).
pub fn radius_ratio(points: &[[f64; 3]], t: [u32; 4]) -> f64 {
    measure(points, t, unit_scale(largest_of(points, t))).rho
}

/// Surface area of `t` with the coordinates times `scale`.
pub fn surface_area_scaled(points: &[[f64; 3]], t: [u32; 4], scale: f64) -> f64 {
    measure(points, t, scale).area
}

/// Surface area of the bounding box of `points` times `scale`.
pub fn box_area_scaled(points: &[[f64; 3]], scale: f64) -> f64 {
    let Some(first) = points.first() else {
        return 0.0;
    };
    let (lo, hi) = points.iter().fold((*first, *first), |(lo, hi), p| {
        (
            std::array::from_fn(|a| lo[a].min(p[a])),
            std::array::from_fn(|a| hi[a].max(p[a])),
        )
    });
    let e: [f64; 3] = std::array::from_fn(|a| hi[a] * scale - lo[a] * scale);
    2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
}

/// For each of `n` items, the earlier item with an equal key, if any. Keys are hashed,
/// the hashes sorted, and equal hashes compared by key, so the cost is `n log n` and the
/// memory 16 bytes per item (plus one key at a time).
pub fn repeats<K: Hash + Eq>(n: usize, key: impl Fn(usize) -> K) -> Vec<Option<u32>> {
    let hash = |i: usize| {
        let mut h = DefaultHasher::new();
        key(i).hash(&mut h);
        h.finish()
    };
    let mut order: Vec<(u64, u32)> = (0..n).map(|i| (hash(i), i as u32)).collect();
    order.sort_unstable();
    let mut out = vec![None; n];
    let mut run = 0;
    while run < order.len() {
        let end = run + order[run..].partition_point(|x| x.0 == order[run].0);
        // Within a run of equal hashes (ascending index), each item repeats the first
        // earlier one with an equal key.
        for a in run + 1..end {
            let ia = order[a].1 as usize;
            let ka = key(ia);
            if let Some(b) = (run..a)
                .find(|&b| out[order[b].1 as usize].is_none() && key(order[b].1 as usize) == ka)
            {
                out[ia] = Some(order[b].1);
            }
        }
        run = end;
    }
    out
}

/// The corner coordinates of `t`, sorted, as bits: equal for tetrahedra at the same
/// place whatever their points' indices and order (`-0.0` and `0.0` are made equal).
pub fn place_key(points: &[[f64; 3]], t: [u32; 4]) -> [[u64; 3]; 4] {
    let mut k = t.map(|i| points[i as usize].map(|c| (c + 0.0).to_bits()));
    k.sort_unstable();
    k
}

/// `v` times `2^log2`, saturating to infinity or zero (never NaN from the exponent).
pub fn times_pow2(v: f64, log2: i32) -> f64 {
    let mut v = v;
    let mut e = log2;
    while e != 0 {
        let step = e.clamp(-1000, 1000);
        v *= f64::from_bits(((step + 1023) as u64) << 52);
        e -= step;
    }
    v
}

/// `v * 2^log2` written in decimal scientific notation, also when it is beyond the f64
/// range (e.g. a volume of 1e900 from coordinates near 1e300).
pub fn format_pow2(v: f64, log2: i32) -> String {
    let direct = times_pow2(v, log2);
    if direct.is_finite() && (direct == 0.0) == (v == 0.0) {
        return format!("{direct:.6e}");
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let l = v.abs().log10() + f64::from(log2) * std::f64::consts::LOG10_2;
    let (mut exp, mut mant) = (l.floor(), 10f64.powf(l - l.floor()));
    if mant >= 9.9999995 {
        mant /= 10.0;
        exp += 1.0;
    }
    format!("{}{mant:.6}e{exp}", if v < 0.0 { "-" } else { "" })
}

/// Quality summary of a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quality {
    /// Flat tetrahedra.
    pub flat: usize,
    /// The first flat tetrahedron.
    pub first_flat: Option<usize>,
    /// Sliver tetrahedra (not counting flat ones).
    pub slivers: usize,
    /// Tetrahedra at the place of an earlier one (not counting flat ones).
    pub repeated: usize,
    /// The first repeated tetrahedron and the earlier one it repeats.
    pub first_repeat: Option<(usize, usize)>,
    /// Mean tetrahedra a line through the bounding box crosses (see the module doc).
    pub depth: f64,
    /// Sum of the signed volumes (infinite when beyond the f64 range: see
    /// [`Quality::volume_log2`]).
    pub total_volume: f64,
    /// Smallest signed volume (+inf without tetrahedra).
    pub min_volume: f64,
    /// The volumes on the scaled coordinates: `total, min` times `2^volume_log2` are the
    /// file's.
    pub scaled_volumes: (f64, f64),
    /// Exponent of [`Quality::scaled_volumes`].
    pub volume_log2: i32,
    /// Smallest radius ratio among the non-flat tetrahedra (1 when there are none).
    pub min_radius_ratio: f64,
}

impl Quality {
    /// Measure every tetrahedron of `mesh`.
    pub fn of(mesh: &Mesh) -> Quality {
        Quality::classify(mesh).0
    }

    /// [`Quality::of`], and which tetrahedra are flat.
    pub fn classify(mesh: &Mesh) -> (Quality, Vec<bool>) {
        let scale = mesh_scale(&mesh.points);
        let points = &mesh.points;
        let mut q = Quality {
            flat: 0,
            first_flat: None,
            slivers: 0,
            repeated: 0,
            first_repeat: None,
            depth: 0.0,
            total_volume: 0.0,
            min_volume: f64::INFINITY,
            scaled_volumes: (0.0, f64::INFINITY),
            volume_log2: -3 * scale_log2(scale),
            min_radius_ratio: 1.0,
        };
        let again = repeats(mesh.tets.len(), |t| place_key(points, mesh.tets[t]));
        let mut flat = Vec::with_capacity(mesh.tets.len());
        let mut area = 0.0;
        for (i, &t) in mesh.tets.iter().enumerate() {
            let m = measure(points, t, scale);
            flat.push(m.flat);
            q.scaled_volumes.0 += m.volume;
            q.scaled_volumes.1 = q.scaled_volumes.1.min(m.volume);
            if m.flat {
                q.flat += 1;
                q.first_flat.get_or_insert(i);
                continue;
            }
            if let Some(earlier) = again[i] {
                q.repeated += 1;
                q.first_repeat.get_or_insert((i, earlier as usize));
            } else {
                area += m.area;
            }
            q.min_radius_ratio = q.min_radius_ratio.min(m.rho);
            if m.rho < SLIVER_RADIUS_RATIO {
                q.slivers += 1;
            }
        }
        let box_area = box_area_scaled(points, scale);
        q.depth = if box_area > 0.0 { area / box_area } else { 0.0 };
        q.total_volume = times_pow2(q.scaled_volumes.0, q.volume_log2);
        q.min_volume = times_pow2(q.scaled_volumes.1, q.volume_log2);
        (q, flat)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_scales_are_exact_powers_of_two() {
        assert_eq!(unit_scale(1.0), 0.5);
        assert_eq!(unit_scale(0.75), 1.0);
        assert_eq!(unit_scale(3.0), 0.25);
        assert_eq!(unit_scale(0.0), 1.0);
        assert_eq!(scale_log2(unit_scale(1e300)), -997);
        // Near the largest f64 the scaled value stays below 4 (the scale cannot go below
        // 2^-1022 as a normal number).
        assert!(f64::MAX * unit_scale(f64::MAX) < 4.0);
        assert!(1e-310 * unit_scale(1e-310) >= 2f64.powi(-53));
    }

    #[test]
    fn huge_volumes_are_written_beyond_the_f64_range() {
        assert_eq!(format_pow2(1.5, 1), "3.000000e0");
        // 2^3000 = 1.2302319221611e903 and 2^-3001 = 4.0640...e-904 (exact values by
        // Python's decimal module).
        assert_eq!(format_pow2(1.0, 3000), "1.230232e903");
        assert_eq!(format_pow2(-0.5, -3000), "-4.064274e-904");
        assert_eq!(times_pow2(1.0, 3000), f64::INFINITY);
    }

    #[test]
    fn repeats_find_the_first_earlier_equal_key() {
        let keys = [5, 7, 5, 5, 9, 7];
        assert_eq!(
            repeats(keys.len(), |i| keys[i]),
            [None, None, Some(0), Some(0), None, Some(1)]
        );
    }
}
