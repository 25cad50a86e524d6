//! The f64 reference of cell projection: one ray per pixel through the mesh, the exact
//! first isovalue crossing of the piecewise-linear field, found tetrahedron by
//! tetrahedron with a bounding-volume hierarchy; and the scores that compare a render
//! with it (agreement of isovalue colours, silhouette pixels apart, depth error).
//!
//! In each tetrahedron the ray's interval `[t_in, t_out]` comes from clipping against
//! the four face planes; the scalar is linear along it, `sf` at entry and `sb` at exit,
//! and the crossing of isovalue `v` is at `t_in + (t_out - t_in)(v - sf)/(sb - sf)` for
//! the first `v` crossed ([`super::first_crossed`]). The nearest crossing over all
//! tetrahedra the ray meets is the pixel's.

use glam::{DMat4, DVec3, DVec4};

use super::prepare::{gradient, normal, Prepared, FACES};
use super::{first_crossed, Isovalue, REFERENCE_SLACK};
use crate::techniques::rays::trace_rays;
use arbvis_core::camera::Camera;

/// What a pixel's ray finds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Index into the sorted isovalues of the first crossing.
    pub iso: usize,
    /// Window depth of the crossing, in [0, 1].
    pub depth: f64,
    /// The crossing in object space.
    pub point: DVec3,
    /// The tetrahedron it is in.
    pub tet: usize,
}

/// A node of the hierarchy: a box, and either two children or a run of tetrahedra.
#[derive(Debug, Clone)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: `order[first..first + count]`; inner: children `first` and `first + 1`.
    first: usize,
    count: usize,
}

/// A bounding-volume hierarchy over the tetrahedra (median split on the longest axis of
/// the centroids' box, four tetrahedra per leaf).
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<usize>,
}

const LEAF: usize = 4;

impl Bvh {
    /// Build over `prepared`'s tetrahedra.
    pub fn build(prepared: &Prepared) -> Bvh {
        let n = prepared.tets.len();
        let boxes: Vec<(DVec3, DVec3, DVec3)> = (0..n)
            .map(|t| {
                let (p, _) = prepared.tet(t);
                let lo = p[0].min(p[1]).min(p[2]).min(p[3]);
                let hi = p[0].max(p[1]).max(p[2]).max(p[3]);
                (lo, hi, (lo + hi) / 2.0)
            })
            .collect();
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * n / LEAF + 1),
            order: (0..n).collect(),
        };
        bvh.nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        let mut stack = vec![(0usize, 0usize, n)];
        while let Some((node, start, end)) = stack.pop() {
            let items = &mut bvh.order[start..end];
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for &t in items.iter() {
                lo = lo.min(boxes[t].0);
                hi = hi.max(boxes[t].1);
                clo = clo.min(boxes[t].2);
                chi = chi.max(boxes[t].2);
            }
            bvh.nodes[node].lo = lo;
            bvh.nodes[node].hi = hi;
            if end - start <= LEAF {
                bvh.nodes[node].first = start;
                bvh.nodes[node].count = end - start;
                continue;
            }
            let axis = (chi - clo).max_position();
            let mid = (end - start) / 2;
            items.select_nth_unstable_by(mid, |&a, &b| {
                boxes[a].2[axis].total_cmp(&boxes[b].2[axis])
            });
            let left = bvh.nodes.len();
            for _ in 0..2 {
                bvh.nodes.push(Node {
                    lo: DVec3::ZERO,
                    hi: DVec3::ZERO,
                    first: 0,
                    count: 0,
                });
            }
            bvh.nodes[node].first = left;
            stack.push((left, start, start + mid));
            stack.push((left + 1, start + mid, end));
        }
        bvh
    }

    /// Call `visit(tet)` for every tetrahedron whose box the ray `o + t d`, `t` in
    /// `[0, t_max]`, meets.
    pub fn visit(&self, o: DVec3, d: DVec3, t_max: f64, mut visit: impl FnMut(usize)) {
        let inv = d.recip();
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i];
            let t0 = (n.lo - o) * inv;
            let t1 = (n.hi - o) * inv;
            let near = t0.min(t1).max_element().max(0.0);
            let far = t0.max(t1).min_element().min(t_max);
            // NaN (a zero direction component on the box's plane) counts as a hit.
            if near > far {
                continue;
            }
            if n.count > 0 {
                self.order[n.first..n.first + n.count]
                    .iter()
                    .for_each(|&t| visit(t));
            } else {
                stack.push(n.first);
                stack.push(n.first + 1);
            }
        }
    }
}

/// The ray's parameter interval inside tetrahedron `p` (outward faces), if any.
pub fn tet_interval(p: [DVec3; 4], o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for (f, _) in FACES {
        let n = normal(p[f[0]], p[f[1]], p[f[2]]);
        if n == DVec3::ZERO {
            return None;
        }
        let dist = n.dot(o - p[f[0]]);
        let rate = n.dot(d);
        if rate.abs() < 1e-300 {
            if dist > 0.0 {
                return None;
            }
        } else if rate > 0.0 {
            hi = hi.min(-dist / rate);
        } else {
            lo = lo.max(-dist / rate);
        }
    }
    (lo < hi).then_some((lo, hi))
}

/// The nearest first crossing along `o + t d`, `t` in [0, 1].
pub fn first_hit(
    prepared: &Prepared,
    bvh: &Bvh,
    sorted: &[Isovalue],
    o: DVec3,
    d: DVec3,
) -> Option<(usize, f64, usize)> {
    let mut best: Option<(usize, f64, usize)> = None;
    bvh.visit(o, d, 1.0, |t| {
        let (p, s) = prepared.tet(t);
        let Some((t_in, t_out)) = tet_interval(p, o, d) else {
            return;
        };
        if t_out < 0.0 || t_in > 1.0 || best.is_some_and(|b| b.1 < t_in) {
            return;
        }
        let g = gradient(p, s);
        let at = |t: f64| s[0] + g.dot(o + d * t - p[0]);
        let (sf, sb) = (at(t_in), at(t_out));
        if let Some(k) = first_crossed(sorted, sf, sb, REFERENCE_SLACK) {
            let f = (sorted[k].value - sf) / (sb - sf);
            let t_iso = t_in + (t_out - t_in) * f;
            if best.is_none_or(|b| t_iso < b.1) {
                best = Some((k, t_iso, t));
            }
        }
    });
    best
}

/// The reference: the hit of every pixel of a `size` image, top row first.
pub fn reference(
    prepared: &Prepared,
    isovalues: &[Isovalue],
    camera: &Camera,
    size: [u32; 2],
) -> Vec<Option<Hit>> {
    let bvh = Bvh::build(prepared);
    let mut sorted = isovalues.to_vec();
    sorted.sort_by(|a, b| a.value.total_cmp(&b.value));
    let mvp = camera.view_projection(size[0] as f64 / size[1].max(1) as f64);
    trace_rays(camera, size, |o, d| {
        first_hit(prepared, &bvh, &sorted, o, d).map(|(iso, t, tet)| {
            let point = o + d * t;
            Hit {
                iso,
                depth: window_depth(&mvp, point),
                point,
                tet,
            }
        })
    })
}

/// Window depth (GL's default range) of an object-space point.
pub fn window_depth(mvp: &DMat4, p: DVec3) -> f64 {
    let c = *mvp * DVec4::new(p.x, p.y, p.z, 1.0);
    (0.5 * c.z / c.w + 0.5).clamp(0.0, 1.0)
}

/// Pixels within `radius` pixels of the mesh's silhouette: the projected boundary edges
/// (of faces used by one tetrahedron) where a front-facing and a back-facing boundary
/// face meet. There a pixel's colour depends on which side of the outline its centre
/// falls, which rasterization rules decide rather than the method.
pub fn silhouette_pixels(
    prepared: &Prepared,
    camera: &Camera,
    size: [u32; 2],
    radius: f64,
) -> Vec<bool> {
    use std::collections::HashMap;
    let mut faces: HashMap<[u32; 3], (usize, [u32; 3])> = HashMap::new();
    for tet in &prepared.tets {
        for (f, _) in FACES {
            let verts = f.map(|i| tet[i]);
            let mut key = verts;
            key.sort_unstable();
            faces.entry(key).or_insert((0, verts)).0 += 1;
        }
    }
    let [w, h] = size;
    let mvp = camera.view_projection(w as f64 / h.max(1) as f64);
    let inverse = camera.view().inverse();
    let eye = inverse.transform_point3(DVec3::ZERO);
    let view_dir = inverse.transform_vector3(DVec3::NEG_Z);
    let perspective = camera.projection == arbvis_core::camera::Projection::Perspective;
    // Each boundary edge with the facings of the boundary faces around it.
    let mut edges: HashMap<(u32, u32), (bool, bool)> = HashMap::new();
    for (count, v) in faces.values() {
        if *count != 1 {
            continue;
        }
        let p = v.map(|i| prepared.points[i as usize]);
        let to_viewer = if perspective { eye - p[0] } else { -view_dir };
        let front = normal(p[0], p[1], p[2]).dot(to_viewer) > 0.0;
        for e in 0..3 {
            let (a, b) = (v[e], v[(e + 1) % 3]);
            let entry = edges.entry((a.min(b), a.max(b))).or_insert((false, false));
            if front {
                entry.0 = true;
            } else {
                entry.1 = true;
            }
        }
    }
    let screen = |p: DVec3| {
        let c = mvp * DVec4::new(p.x, p.y, p.z, 1.0);
        let n = c.truncate() / c.w;
        ((n.x + 1.0) / 2.0 * w as f64, (1.0 - n.y) / 2.0 * h as f64)
    };
    let mut mask = vec![false; (w * h) as usize];
    for (&(a, b), &(front, back)) in &edges {
        if front && back {
            let (a, b) = (prepared.points[a as usize], prepared.points[b as usize]);
            mark_segment(&mut mask, size, screen(a), screen(b), radius);
        }
    }
    mask
}

/// Mark pixels whose centre lies within `radius` of segment `a`-`b` (screen pixels).
fn mark_segment(mask: &mut [bool], [w, h]: [u32; 2], a: (f64, f64), b: (f64, f64), radius: f64) {
    let (x0, x1) = (a.0.min(b.0) - radius, a.0.max(b.0) + radius);
    let (y0, y1) = (a.1.min(b.1) - radius, a.1.max(b.1) + radius);
    if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
        return;
    }
    let (ab_x, ab_y) = (b.0 - a.0, b.1 - a.1);
    let len2 = ab_x * ab_x + ab_y * ab_y;
    let xs = (x0.floor().max(0.0) as u32)..=(x1.ceil().min(w as f64 - 1.0).max(0.0) as u32);
    for y in (y0.floor().max(0.0) as u32)..=(y1.ceil().min(h as f64 - 1.0).max(0.0) as u32) {
        for x in xs.clone() {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let f = if len2 > 0.0 {
                (((px - a.0) * ab_x + (py - a.1) * ab_y) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (dx, dy) = (px - (a.0 + f * ab_x), py - (a.1 + f * ab_y));
            if dx * dx + dy * dy <= radius * radius {
                mask[(y * w + x) as usize] = true;
            }
        }
    }
}

/// How a render compares with the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Agreement {
    /// Pixels away from the silhouette.
    pub interior: usize,
    /// Of those, the ones with the reference's isovalue colour (or background where the
    /// reference has no crossing).
    pub interior_agree: usize,
    /// Pixels near the silhouette.
    pub silhouette: usize,
    /// Of those, the ones that agree.
    pub silhouette_agree: usize,
    /// Largest depth difference (window units) over interior pixels where both hit the
    /// same isovalue, when depths were given.
    pub max_depth_error: f64,
    /// The 99th percentile of those differences (where a ray grazes an isosurface the
    /// crossing is ill-conditioned: a scalar error of one ulp moves it far along the ray).
    pub depth_error_p99: f64,
}

impl Agreement {
    /// Fraction of interior pixels that agree.
    pub fn interior_fraction(&self) -> f64 {
        self.interior_agree as f64 / self.interior.max(1) as f64
    }
}

/// Classify every pixel of `image` (RGBA, top row first) as the nearest isovalue colour
/// or the background, and compare with `hits`.
pub fn agreement(
    image: &arbvis_core::image::Image,
    depth: Option<&[f32]>,
    hits: &[Option<Hit>],
    sorted: &[Isovalue],
    background: [f32; 4],
    silhouette: &[bool],
) -> Agreement {
    let mut a = Agreement {
        interior: 0,
        interior_agree: 0,
        silhouette: 0,
        silhouette_agree: 0,
        max_depth_error: 0.0,
        depth_error_p99: 0.0,
    };
    let mut depth_errors = Vec::new();
    let colours: Vec<[f32; 3]> = sorted
        .iter()
        .map(|i| [i.color[0] as f32, i.color[1] as f32, i.color[2] as f32])
        .collect();
    for (n, px) in image.data.chunks_exact(4).enumerate() {
        let dist = |c: [f32; 3]| (0..3).map(|i| (px[i] - c[i]).powi(2)).sum::<f32>();
        let bg = dist([background[0], background[1], background[2]]);
        let nearest = colours
            .iter()
            .enumerate()
            .map(|(k, c)| (k, dist(*c)))
            .min_by(|x, y| x.1.total_cmp(&y.1));
        let got = match nearest {
            Some((k, d)) if d < bg => Some(k),
            _ => None,
        };
        let ok = got == hits[n].map(|h| h.iso);
        if silhouette[n] {
            a.silhouette += 1;
            a.silhouette_agree += ok as usize;
        } else {
            a.interior += 1;
            a.interior_agree += ok as usize;
        }
        if let (true, false, Some(d), Some(h)) = (ok, silhouette[n], depth, hits[n]) {
            depth_errors.push((d[n] as f64 - h.depth).abs());
        }
    }
    depth_errors.sort_by(f64::total_cmp);
    a.max_depth_error = depth_errors.last().copied().unwrap_or(0.0);
    a.depth_error_p99 = depth_errors
        .get(depth_errors.len() * 99 / 100)
        .copied()
        .unwrap_or(0.0);
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_through_a_tetrahedron_enters_and_leaves_at_its_faces() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        // Along z through (0.2, 0.2): enters the bottom face z = 0, leaves the slanted
        // face x + y + z = 1 at z = 0.6.
        let (a, b) = tet_interval(p, DVec3::new(0.2, 0.2, -1.0), DVec3::Z).unwrap();
        assert!(
            (a - 1.0).abs() < 1e-12 && (b - 1.6).abs() < 1e-12,
            "{a} {b}"
        );
        assert!(tet_interval(p, DVec3::new(0.8, 0.8, -1.0), DVec3::Z).is_none());
    }

    #[test]
    fn segments_mark_nearby_pixel_centres() {
        let mut mask = vec![false; 100];
        mark_segment(&mut mask, [10, 10], (0.0, 5.0), (10.0, 5.0), 0.6);
        let rows: Vec<usize> = (0..10)
            .filter(|y| (0..10).all(|x| mask[y * 10 + x]))
            .collect();
        assert_eq!(rows, vec![4, 5], "centres at y = 4.5 and 5.5 are 0.5 away");
    }
}
