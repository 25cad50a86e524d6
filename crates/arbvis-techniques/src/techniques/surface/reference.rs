//! The f64 CPU twin of a surface's picture: at each pixel centre the triangles the ray
//! meets, their barycentric weights corrected for perspective as the GL interpolates, and
//! the headlight evaluated as `fidelity` evaluates it (per vertex and interpolated, or per
//! pixel on the interpolated normal). Opaque: the nearest hit (the GL's depth test).
//! Translucent: every hit composited in depth order, premultiplied, over the background
//! (the renderer sorts triangles by their centroids, which orders every pixel alike where
//! no two triangles overlap out of that order).

use glam::{DVec3, DVec4};

use super::prepare::{Corner, Prepared};
use super::SurfaceScene;
use arbvis_core::camera::Camera;
use arbvis_core::image::Image;
use arbvis_core::vocab::Fidelity;

/// The nearest hit at a pixel: the triangle and its perspective-correct weights.
#[derive(Debug, Clone, Copy)]
struct Hit {
    depth: f64,
    triangle: usize,
    weights: DVec3,
}

/// The picture of `prepared` seen by `camera` on `size` pixels over `background`
/// (RGBA32F, top row first, alpha the coverage).
pub fn reference(
    prepared: &Prepared,
    scene: &SurfaceScene,
    fidelity: Fidelity,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    let translucent = scene.opacity < 1.0;
    let hits = all_hits(prepared, camera, size, !translucent);
    let light = camera.toward_viewer().normalize();
    let terms = scene.light_terms();
    let a = terms[2];
    let pixels = hits.into_iter().map(|mut hits| {
        // Front to back: each hit's colour weighted by what the nearer ones let through.
        hits.sort_by(|x, y| x.depth.total_cmp(&y.depth));
        let (mut colour, mut alpha) = (DVec3::ZERO, 0.0);
        for hit in hits {
            let c = &prepared.corners[hit.triangle * 3..hit.triangle * 3 + 3];
            colour += shade(c, hit.weights, light, terms, fidelity) * a * (1.0 - alpha);
            alpha += a * (1.0 - alpha);
        }
        std::array::from_fn(|i| match i {
            3 => alpha + background[3] * (1.0 - alpha),
            _ => colour[i] + background[i] * (1.0 - alpha),
        })
    });
    Image::from_f64_pixels(
        size[0],
        size[1],
        arbvis_gl::TargetFormat::Rgba32f,
        pixels.collect::<Vec<_>>(),
    )
}

/// The headlight on one corner's normal: ambient plus two-sided diffuse.
fn lit(normal: DVec3, light: DVec3, terms: [f64; 4]) -> f64 {
    normal.normalize_or_zero().dot(light).abs() * terms[1] + terms[0]
}

/// The colour at weights `w` of triangle `c`.
fn shade(c: &[Corner], w: DVec3, light: DVec3, terms: [f64; 4], fidelity: Fidelity) -> DVec3 {
    match fidelity {
        Fidelity::Faithful => (0..3)
            .map(|i| c[i].colour * lit(c[i].normal, light, terms) * w[i])
            .sum(),
        Fidelity::Precise => {
            let normal: DVec3 = (0..3).map(|i| c[i].normal * w[i]).sum();
            let colour: DVec3 = (0..3).map(|i| c[i].colour * w[i]).sum();
            colour * lit(normal, light, terms)
        }
    }
}

/// The triangles met at each pixel centre, top row first: every one, or the nearest only.
fn all_hits(prepared: &Prepared, camera: &Camera, size: [u32; 2], nearest: bool) -> Vec<Vec<Hit>> {
    let [w, h] = size.map(|s| s.max(1) as usize);
    let mvp = camera.view_projection(w as f64 / h as f64);
    let mut hits: Vec<Vec<Hit>> = vec![Vec::new(); w * h];
    for (t, corners) in prepared.corners.chunks_exact(3).enumerate() {
        let clip: [DVec4; 3] = std::array::from_fn(|i| mvp * corners[i].position.extend(1.0));
        // Every corner in front of the eye (the scene's frame lies within the depth range).
        if clip.iter().any(|c| c.w <= 0.0) {
            continue;
        }
        // Window coordinates, y down (row 0 at the top), and depth in [-1, 1].
        let win = clip.map(|c| {
            let n = c.truncate() / c.w;
            DVec3::new(
                (n.x + 1.0) / 2.0 * w as f64,
                (1.0 - n.y) / 2.0 * h as f64,
                n.z,
            )
        });
        let area = edge(win[0], win[1], win[2]);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        let lo = win.iter().fold(DVec3::INFINITY, |a, p| a.min(*p));
        let hi = win.iter().fold(DVec3::NEG_INFINITY, |a, p| a.max(*p));
        let x0 = (lo.x - 0.5).ceil().max(0.0) as usize;
        let y0 = (lo.y - 0.5).ceil().max(0.0) as usize;
        let x1 = ((hi.x - 0.5).floor().min(w as f64 - 1.0)).max(-1.0);
        let y1 = ((hi.y - 0.5).floor().min(h as f64 - 1.0)).max(-1.0);
        for y in y0..=(y1 as i64).max(-1) as usize {
            if y1 < 0.0 {
                break;
            }
            for x in x0..=(x1 as i64).max(-1) as usize {
                if x1 < 0.0 {
                    break;
                }
                let p = DVec3::new(x as f64 + 0.5, y as f64 + 0.5, 0.0);
                let b = DVec3::new(
                    edge(win[1], win[2], p),
                    edge(win[2], win[0], p),
                    edge(win[0], win[1], p),
                ) / area;
                if b.min_element() < 0.0 {
                    continue;
                }
                let depth = b.x * win[0].z + b.y * win[1].z + b.z * win[2].z;
                if !(-1.0..=1.0).contains(&depth) {
                    continue;
                }
                let slot = &mut hits[y * w + x];
                if nearest && slot.first().is_some_and(|s| s.depth <= depth) {
                    continue;
                }
                // Perspective-correct weights: b_i / w_i, normalized.
                let q = DVec3::new(b.x / clip[0].w, b.y / clip[1].w, b.z / clip[2].w);
                let hit = Hit {
                    depth,
                    triangle: t,
                    weights: q / q.element_sum(),
                };
                match nearest {
                    true => *slot = vec![hit],
                    false => slot.push(hit),
                }
            }
        }
    }
    hits
}

/// Twice the signed area of (a, b, p) in the window's x-y plane.
fn edge(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
}
