//! The f64 reference of the volume (issue 16, item 4): one ray per pixel centre, from the
//! near plane to the far plane, through every tetrahedron it meets (the isosurface
//! reference's bounding-volume hierarchy), the segments sorted along the ray (they do not
//! overlap: the order is exact for any mesh and any view, camera inside included) and
//! each integrated exactly ([`Transfer::segment`]), front to back, without early
//! termination; with isovalues (`mode = "both"`), up to the first crossing, where the
//! opaque isosurface colour ends the ray. Composited over the background.

use glam::DVec3;

use super::prepare::{gradient, Prepared};
use super::reference::{tet_interval, Bvh};
use super::transfer::{over, Rgba, Transfer};
use super::{first_crossed, Isovalue, REFERENCE_SLACK};
use crate::techniques::rays::trace_pixels;
use arbvis_core::camera::Camera;
use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;

/// The segments of one ray, `(t_in, t_out, tet)` with `t` in [0, 1] from near to far,
/// sorted by entry.
pub fn segments(prepared: &Prepared, bvh: &Bvh, o: DVec3, d: DVec3) -> Vec<(f64, f64, usize)> {
    let mut out = Vec::new();
    bvh.visit(o, d, 1.0, |t| {
        let (p, _) = prepared.tet(t);
        if let Some((a, b)) = tet_interval(p, o, d) {
            let (a, b) = (a.max(0.0), b.min(1.0));
            if b > a {
                out.push((a, b, t));
            }
        }
    });
    out.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.2.cmp(&y.2)));
    out
}

/// Premultiplied colour and opacity of one ray (before the background).
pub fn integrate_ray(
    prepared: &Prepared,
    bvh: &Bvh,
    tf: &Transfer,
    sorted_isos: &[Isovalue],
    o: DVec3,
    d: DVec3,
) -> Rgba {
    let mut acc = [0.0; 4];
    let len = d.length();
    for (a, b, t) in segments(prepared, bvh, o, d) {
        let (p, s) = prepared.tet(t);
        let g = gradient(p, s);
        let at = |u: f64| s[0] + g.dot(o + d * u - p[0]);
        let (sf, sb) = (at(a), at(b));
        if let Some(k) = first_crossed(sorted_isos, sf, sb, REFERENCE_SLACK) {
            let f = ((sorted_isos[k].value - sf) / (sb - sf)).clamp(0.0, 1.0);
            over(
                &mut acc,
                tf.segment(sf, sf + (sb - sf) * f, (b - a) * len * f),
            );
            let c = sorted_isos[k].color;
            over(&mut acc, [c[0], c[1], c[2], 1.0]);
            return acc;
        }
        over(&mut acc, tf.segment(sf, sb, (b - a) * len));
    }
    acc
}

/// The reference image (RGBA32F, alpha = coverage) over `background`; `isovalues` only
/// for scenes drawing both.
pub fn reference(
    prepared: &Prepared,
    tf: &Transfer,
    isovalues: &[Isovalue],
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    let bvh = Bvh::build(prepared);
    let mut sorted = isovalues.to_vec();
    sorted.sort_by(|a, b| a.value.total_cmp(&b.value));
    trace_pixels(camera, size, TargetFormat::Rgba32f, |o, d| {
        let c = integrate_ray(prepared, &bvh, tf, &sorted, o, d);
        let t = 1.0 - c[3];
        [
            c[0] + t * background[0],
            c[1] + t * background[1],
            c[2] + t * background[2],
            c[3] + t * background[3],
        ]
    })
}

/// Pixels whose ray meets the mesh away from its silhouette (`silhouette` from
/// [`super::reference::silhouette_pixels`]): the interior the scores single out.
pub fn interior_mask(
    prepared: &Prepared,
    camera: &Camera,
    size: [u32; 2],
    silhouette: &[bool],
) -> Vec<bool> {
    let bvh = Bvh::build(prepared);
    let hits = crate::techniques::rays::trace_rays(camera, size, |o, d| {
        !segments(prepared, &bvh, o, d).is_empty()
    });
    hits.iter()
        .zip(silhouette)
        .map(|(&h, &s)| h && !s)
        .collect()
}

/// RGB RMSE and largest difference between two images, over all pixels and over the
/// `mask`'s: `((rmse, max), (rmse, max))`.
pub fn score(image: &Image, reference: &Image, mask: &[bool]) -> ((f64, f64), (f64, f64)) {
    let (mut all, mut inner) = ((0.0, 0.0, 0usize), (0.0, 0.0, 0usize));
    for (n, (p, q)) in image
        .data
        .chunks_exact(4)
        .zip(reference.data.chunks_exact(4))
        .enumerate()
    {
        for c in 0..3 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            all = (all.0 + d * d, f64::max(all.1, d), all.2 + 1);
            if mask.get(n).copied().unwrap_or(false) {
                inner = (inner.0 + d * d, f64::max(inner.1, d), inner.2 + 1);
            }
        }
    }
    let f = |(s, m, n): (f64, f64, usize)| ((s / n.max(1) as f64).sqrt(), m);
    (f(all), f(inner))
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_data::mesh::Mesh;

    #[test]
    fn one_tetrahedron_matches_the_analytic_integral() {
        // A single tetrahedron with a linear field and a transfer function linear in s
        // (one piece): along each ray the integral is one piece in closed form. The
        // reference (f64 quadrature per piece) lands within 1e-12 of it.
        let mesh = Mesh {
            points: vec![
                [0.1, -0.2, 0.0],
                [1.0, 0.1, 0.2],
                [0.2, 0.9, -0.1],
                [0.3, 0.2, 1.1],
            ],
            tets: vec![[0, 1, 2, 3]],
            ..Default::default()
        };
        let p =
            super::super::prepare::from_mesh(&mesh, &[0.0, 1.0, 0.3, 0.7], "s".into(), [0.0, 1.0])
                .unwrap();
        let tf = Transfer {
            s: vec![0.0, 1.0],
            rgba: vec![[0.9, 0.2, 0.1, 0.3], [0.1, 0.4, 1.0, 0.9]],
            unit: 0.2,
        };
        let bvh = Bvh::build(&p);
        let mut checked = 0;
        for i in 0..40 {
            for j in 0..40 {
                let o = DVec3::new(-1.0 + i as f64 / 20.0, -1.0 + j as f64 / 20.0, -3.0);
                let d = DVec3::new(0.1, -0.05, 6.0);
                let segs = segments(&p, &bvh, o, d);
                if segs.is_empty() {
                    continue;
                }
                let (a, b, _) = segs[0];
                let (q, s) = p.tet(0);
                let g = gradient(q, s);
                let at = |u: f64| s[0] + g.dot(o + d * u - q[0]);
                let (sf, sb) = (at(a), at(b));
                let len = (b - a) * d.length();
                // Closed form for one piece: c and tau linear in s, hence along the ray.
                let (f, bk) = (tf.at(sf), tf.at(sb));
                let want = super::super::transfer::linear_piece(f, bk, tf.unit, len);
                let got = integrate_ray(&p, &bvh, &tf, &[], o, d);
                for c in 0..4 {
                    assert!((got[c] - want[c]).abs() < 1e-12, "{got:?} {want:?}");
                }
                checked += 1;
            }
        }
        assert!(checked > 50, "{checked} rays met the tetrahedron");
    }
}
