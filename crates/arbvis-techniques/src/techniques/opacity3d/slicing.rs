//! View-aligned slicing (pure Rust, no GL): planes perpendicular to the view direction cut
//! the volume's box into convex polygons of 3 to 6 vertices, ordered back to front, each
//! vertex carrying its exact 3D texture coordinate.
//!
//! The box spans `[-half, half]` in object space and the whole texture `[0, 1]³`, so
//! texture coordinate = `(p + half) / (2 half)` — an affine map, exact at every vertex, and
//! linear interpolation over a triangle reproduces it at every fragment.
//!
//! Slice `i` of `n` lies at depth `t_i = t_min + (i + 0.5) (t_max - t_min) / n` along the
//! view direction, where `[t_min, t_max]` is the box's extent along it: slices sample the
//! centres of `n` equal layers, and the spacing `(t_max - t_min) / n` is what opacity
//! correction needs. One slice lies through the centre.

use glam::DVec3;

/// One slice polygon, convex, counter-clockwise seen from the viewer.
#[derive(Debug, Clone, PartialEq)]
pub struct SlicePolygon {
    /// Object-space vertices (3 to 6).
    pub positions: Vec<DVec3>,
    /// 3D texture coordinates of the same vertices.
    pub texcoords: Vec<DVec3>,
}

/// The slices of a box for one view direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Slices {
    /// Polygons, farthest first (draw in this order with "over" blending).
    pub polygons: Vec<SlicePolygon>,
    /// Distance between consecutive slice planes, in object units.
    pub spacing: f64,
}

/// The 12 edges of a box, as pairs of corner indices (bit 0 = x, 1 = y, 2 = z), lower
/// corner first.
pub(super) const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7), // along x
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7), // along y
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7), // along z
];

fn corner(half: DVec3, i: usize) -> DVec3 {
    DVec3::new(
        if i & 1 == 0 { -half.x } else { half.x },
        if i & 2 == 0 { -half.y } else { half.y },
        if i & 4 == 0 { -half.z } else { half.z },
    )
}

/// Texture coordinate of object-space point `p` in a box of half-extent `half`.
pub fn texcoord(p: DVec3, half: DVec3) -> DVec3 {
    (p + half) / (2.0 * half)
}

/// Slice the box `[-half, half]` with `count` planes perpendicular to `toward_viewer`
/// (the direction from the volume toward the eye, object space; need not be unit).
/// Returns no polygons for a zero or non-finite direction, a degenerate box, or
/// `count == 0`.
pub fn slice_box(half: DVec3, toward_viewer: DVec3, count: usize) -> Slices {
    let empty = Slices {
        polygons: Vec::new(),
        spacing: 0.0,
    };
    let n = toward_viewer.normalize_or_zero();
    if count == 0 || n == DVec3::ZERO || !half.is_finite() || half.min_element() <= 0.0 {
        return empty;
    }
    let depths: Vec<f64> = (0..8).map(|i| corner(half, i).dot(n)).collect();
    let t_min = depths.iter().copied().fold(f64::INFINITY, f64::min);
    let t_max = depths.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let spacing = (t_max - t_min) / count as f64;
    // An in-plane basis (u, v, n) is right-handed, so sorting by angle about n gives
    // counter-clockwise order seen from the viewer.
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let polygons = (0..count)
        .filter_map(|i| {
            let t = t_min + (i as f64 + 0.5) * spacing;
            let positions = cut(half, t, &depths, u, v);
            (positions.len() >= 3).then(|| SlicePolygon {
                texcoords: positions.iter().map(|&p| texcoord(p, half)).collect(),
                positions,
            })
        })
        .collect();
    Slices { polygons, spacing }
}

/// The polygon where plane `n·p = t` meets the box (`depths` = `n·corner`), sorted
/// counter-clockwise about `n = u × v`.
fn cut(half: DVec3, t: f64, depths: &[f64], u: DVec3, v: DVec3) -> Vec<DVec3> {
    let mut points: Vec<DVec3> = Vec::with_capacity(6);
    for &(a, b) in &EDGES {
        let (da, db) = (depths[a] - t, depths[b] - t);
        // The edge crosses the plane (an endpoint on it counts once, from the edge where
        // it is the lower end, via the half-open test).
        if (da < 0.0) != (db < 0.0) {
            let s = da / (da - db);
            let p = corner(half, a).lerp(corner(half, b), s);
            // Clamp rounding so vertices stay inside the box (texcoords in [0, 1]).
            points.push(p.clamp(-half, half));
        }
    }
    polygon(points, 1e-12 * half.max_element(), u, v)
}

/// The convex polygon through `points` (a plane's crossings of a box's edges): points
/// closer than `eps` merged (a plane through a corner), sorted counter-clockwise about
/// `u × v`; empty when fewer than three remain.
pub(super) fn polygon(points: Vec<DVec3>, eps: f64, u: DVec3, v: DVec3) -> Vec<DVec3> {
    let mut unique: Vec<DVec3> = Vec::with_capacity(points.len());
    for p in points {
        if unique.iter().all(|q| q.distance(p) > eps) {
            unique.push(p);
        }
    }
    if unique.len() < 3 {
        return Vec::new();
    }
    let centre = unique.iter().copied().sum::<DVec3>() / unique.len() as f64;
    unique.sort_by(|a, b| {
        let angle = |p: &DVec3| (p - centre).dot(v).atan2((p - centre).dot(u));
        angle(a).total_cmp(&angle(b))
    });
    unique
}

impl Slices {
    /// Triangles of every polygon as a fan, interleaved for a mesh of attributes
    /// `[position xyzw, texcoord xyzw]` (8 floats per vertex), back to front.
    pub fn triangle_vertices(&self) -> Vec<f32> {
        let mut out = Vec::new();
        for poly in &self.polygons {
            for k in 1..poly.positions.len() - 1 {
                for i in [0, k, k + 1] {
                    let (p, t) = (poly.positions[i], poly.texcoords[i]);
                    out.extend_from_slice(&[
                        p.x as f32, p.y as f32, p.z as f32, 1.0, t.x as f32, t.y as f32,
                        t.z as f32, 1.0,
                    ]);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon_area(poly: &SlicePolygon, n: DVec3) -> f64 {
        let p = &poly.positions;
        let mut twice = 0.0;
        for k in 1..p.len() - 1 {
            twice += (p[k] - p[0]).cross(p[k + 1] - p[0]).dot(n);
        }
        twice / 2.0
    }

    fn check(half: DVec3, dir: DVec3, count: usize) -> Slices {
        let s = slice_box(half, dir, count);
        let n = dir.normalize();
        let tol = 1e-12 * half.max_element();
        let mut last_depth = f64::NEG_INFINITY;
        for poly in &s.polygons {
            assert!(
                (3..=6).contains(&poly.positions.len()),
                "{} vertices",
                poly.positions.len()
            );
            let depth = poly.positions[0].dot(n);
            for (p, t) in poly.positions.iter().zip(&poly.texcoords) {
                // On one plane, inside the box, texcoord exactly the affine map.
                assert!((p.dot(n) - depth).abs() < 1e-9, "not planar");
                assert!(p.abs().cmple(half + tol).all(), "{p} outside {half}");
                assert_eq!(*t, texcoord(*p, half));
                assert!(
                    t.cmpge(DVec3::ZERO).all() && t.cmple(DVec3::ONE).all(),
                    "{t}"
                );
            }
            // Back to front, and counter-clockwise (positive area) seen from the viewer.
            assert!(depth > last_depth, "slices not back to front");
            last_depth = depth;
            assert!(polygon_area(poly, n) > 0.0, "not counter-clockwise");
        }
        s
    }

    #[test]
    fn axis_aligned_view_gives_squares_at_layer_centres() {
        let s = check(DVec3::ONE, DVec3::Z, 4);
        assert_eq!(s.polygons.len(), 4);
        assert!((s.spacing - 0.5).abs() < 1e-15);
        let zs: Vec<f64> = s.polygons.iter().map(|p| p.positions[0].z).collect();
        assert_eq!(zs, [-0.75, -0.25, 0.25, 0.75]);
        for p in &s.polygons {
            assert_eq!(p.positions.len(), 4);
            assert!((polygon_area(p, DVec3::Z) - 4.0).abs() < 1e-12);
        }
        // The z texture coordinate samples layer centres exactly.
        let tz: Vec<f64> = s.polygons.iter().map(|p| p.texcoords[0].z).collect();
        assert_eq!(tz, [0.125, 0.375, 0.625, 0.875]);
    }

    #[test]
    fn diagonal_view_gives_triangles_and_a_hexagon() {
        let s = check(DVec3::ONE, DVec3::ONE, 3);
        let counts: Vec<usize> = s.polygons.iter().map(|p| p.positions.len()).collect();
        assert_eq!(counts, [3, 6, 3]);
    }

    #[test]
    fn slices_fill_the_box_volume() {
        // Sum of area x spacing -> box volume (midpoint rule), for many directions.
        let half = DVec3::new(1.0, 0.5, 0.25);
        let volume = 8.0 * half.x * half.y * half.z;
        for dir in [
            DVec3::new(0.3, -0.7, 0.2),
            DVec3::new(-1.0, 2.0, 3.0),
            DVec3::X,
            DVec3::new(1.0, 1.0, 0.0),
        ] {
            let s = check(half, dir, 2000);
            let n = dir.normalize();
            let sum: f64 = s.polygons.iter().map(|p| polygon_area(p, n)).sum::<f64>() * s.spacing;
            assert!(
                (sum - volume).abs() / volume < 1e-4,
                "{dir}: {sum} vs {volume}"
            );
        }
    }

    #[test]
    fn extremes() {
        // One slice: through the centre.
        let s = check(DVec3::ONE, DVec3::new(0.2, 0.1, 1.0), 1);
        assert_eq!(s.polygons.len(), 1);
        let c: DVec3 = s.polygons[0].positions.iter().copied().sum::<DVec3>()
            / s.polygons[0].positions.len() as f64;
        assert!(c.dot(DVec3::new(0.2, 0.1, 1.0)).abs() < 1e-12);
        // Thousands of slices: all valid.
        assert_eq!(
            check(DVec3::ONE, DVec3::new(1.0, -2.0, 0.5), 4096)
                .polygons
                .len(),
            4096
        );
        // Degenerate inputs give nothing rather than NaN vertices.
        assert!(slice_box(DVec3::ONE, DVec3::ZERO, 10).polygons.is_empty());
        assert!(slice_box(DVec3::ONE, DVec3::new(f64::NAN, 0.0, 1.0), 10)
            .polygons
            .is_empty());
        assert!(slice_box(DVec3::new(1.0, 0.0, 1.0), DVec3::Z, 10)
            .polygons
            .is_empty());
        assert!(slice_box(DVec3::ONE, DVec3::Z, 0).polygons.is_empty());
        // A 1-voxel-thick box (1 x N volume) still slices.
        check(DVec3::new(1e-3, 1.0, 1.0), DVec3::new(1.0, 0.3, 0.2), 16);
    }

    #[test]
    fn triangle_fan_vertex_layout() {
        let s = slice_box(DVec3::ONE, DVec3::ONE, 3);
        // 3 + 6 + 3 vertices -> 1 + 4 + 1 triangles -> 18 vertices of 8 floats.
        assert_eq!(s.triangle_vertices().len(), 18 * 8);
    }
}
