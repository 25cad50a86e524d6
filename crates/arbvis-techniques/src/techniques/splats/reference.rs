//! The f64 CPU reference of splat compositing, for the renderer to be scored against:
//! the same splats (position, RGBA, size rule, footprint), rasterized as GL rasterizes
//! points and blended back to front with `SRC_ALPHA, ONE_MINUS_SRC_ALPHA` in f64; and
//! the weighted blended order-independent composite (McGuire & Bavoil 2013) of the same
//! splats, with [`rmse_rgb`] to measure one against the other.
//!
//! # A splat, as GL draws a `GL_POINT` with `gl_PointSize`
//!
//! 1. The vertex is transformed by the camera's `projection * view`; a point whose clip
//!    position lies outside `-w ≤ x, y, z ≤ w` (or `w ≤ 0`: at or behind the eye) is
//!    discarded whole, as the GL spec clips points by their vertex (some drivers keep
//!    wide points whose centre is just off-screen, NVIDIA's among them: the precise
//!    programs drop those themselves; the seed's, run as written, do not).
//! 2. Its size in pixels ([`splat_size`]): `point_size / distance(p, eye) * factor` in
//!    perspective, as the seed's vertex shader; `point_size * factor` in orthographic
//!    (no distance there); clamped to `size_range` (GL's `POINT_SIZE_RANGE`, default
//!    `[1, 255]` as llvmpipe reports); a NaN size draws nothing. (A COPC cut's precise
//!    splats are further scaled per point by their level's spacing, before the clamp; the
//!    reference draws clouds without scales, and the tiles mirror the scaled rule.)
//! 3. Point-sprite rasterization: fragments for the pixels whose centres lie in the
//!    square of side `size` centred on the window position, half-open
//!    (`x_w - size/2 ≤ x + 0.5 < x_w + size/2`, the same in y).
//! 4. The fragment shader's `n_dist = 2 |gl_PointCoord - 0.5|`, here `|d| / (size / 2)`
//!    with `d` from the splat's window position to the pixel centre: 0 at the centre, 1
//!    on the inscribed circle; fragments with `n_dist > 1` are discarded. Alpha is the
//!    point's alpha times the [`Footprint`] at `n_dist`; colour and alpha are clamped
//!    to [0, 1] (a fixed-point target clamps them) and a NaN alpha counts as 0.
//!
//! The precise programs compute steps 3 and 4 as written here, in f32, from the
//! fragment's window position (`precise.frag`; the tiles' gather likewise), so they
//! differ from this reference by f32 rounding except at pixel centres within that
//! rounding of a splat's rim, where a fragment can fall on either side of `n_dist = 1`
//! and the pixel moves by up to the footprint's rim value ([`rim_allowance`] marks those
//! pixels). The faithful programs use `gl_PointCoord`, which llvmpipe computes from the
//! rasterizer's fixed-point position, about 2e-3 px off: their rim pixels move more.
//! 5. Blending: colour `SRC_ALPHA, ONE_MINUS_SRC_ALPHA` as the seed's `glBlendFunc`;
//!    alpha `ONE, ONE_MINUS_SRC_ALPHA` (arbvis's `Blend::Over`), so the alpha channel is
//!    coverage, `a + dst.a (1 - a)`.
//!
//! # The seed's footprints and their quirks
//!
//! The seed writes `alpha = smoothstep(0.0, 1.0, n_dist)` or `alpha = gauss(n_dist, 1.0,
//! gauss_factor)` with `gauss(x, x0, sx) = exp(-(x - x0)² / (2 sx)) / sqrt(2π sx)`, and
//! describes splats opaque at the centre and more transparent outward. Its report does
//! not define `n_dist`. Taken as a normalized distance (as here), both formulas as
//! written do the opposite: smoothstep is 0 at the centre and 1 on the rim (a ring),
//! and the Gaussian peaks at `x0 = 1`, the rim. They give the described splats only if
//! the seed's `n_dist` was `1 - distance`, which the precise variants use. The Gaussian
//! has two more quirks: `sx` is a variance, and the factor `1/sqrt(2π sx)` makes the
//! peak exceed 1 for `sx < 1/(2π)` (clamped by the target: a flat-topped splat) and stay
//! below 1 above it (0.40 at `sx = 1`); `sx ≤ 0` gives NaN or infinities. Precise:
//! [`Footprint::Smoothstep`] = `smoothstep(0, 1, 1 - n_dist)`, and
//! [`Footprint::Gaussian`] = `exp(-n_dist² / (2 width))`, peak 1 at the centre (width
//! 0 is its limit: the centre pixel only).
//!
//! # Order
//!
//! [`composite`] draws in [`key_order`]: the renderer's order, computed as the renderer
//! computes it: [`View::key`] in f32 (squared distance to the f32 eye in perspective,
//! `p·v` along the f32 viewing direction in orthographic), farthest first, equal keys
//! in point index order (the rule of [`super::sort`]'s `Keys` and `Radix` methods and
//! of every tile list). So the reference and the renderer composite the same fragments
//! in the same sequence, and what they are scored on is placement, footprint and
//! blending. The key is exact to its f32 rounding only: where the true depths of two
//! overlapping splats differ by less than the rounding of their keys (about 2^-23 of the
//! key: 1e-7 of the depth, more in perspective where the key is a sum of squares), the
//! key's order, not the true order, is drawn, by both. [`exact_order`] gives the true
//! order in f64 and [`composite_in_order`] any order, to measure what that costs
//! (single pixels by up to the difference of the two splats' colours, times their
//! alphas, in a cloud built to have such pairs).
//!
//! # Weighted blended OIT
//!
//! Every fragment adds `(c a w, a w)` to an accumulator and multiplies a revealage by
//! `1 - a`; the result is `avg (1 - R) + background R` with `avg = accum.rgb /
//! max(accum.a, 1e-5)`, and alpha `1 - (1 - bg.a) R`. Weights `w(z, a)` are the paper's
//! equations 7 to 10 ([`OitWeight`]); `z` is the distance along the view axis from the
//! eye (perspective) or from the near plane (orthographic), `d` the window depth.
//!
//! Images are [`Image`]s (`Rgba32f`, top row first) computed in f64; rows are drawn in
//! parallel bands, each band walking all splats in order.

use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

use super::sort::{keys_order, View};
use arbvis_core::camera::{Camera, Projection};
use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;

/// How a splat's alpha falls off with `n_dist` (0 at the centre, 1 on the rim).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Footprint {
    /// The seed as written: `smoothstep(0, 1, n_dist)` (0 at the centre, 1 on the rim).
    SeedSmoothstep,
    /// The seed as written: `gauss(n_dist, 1.0, width)` (peak `1/sqrt(2π width)` on the rim).
    SeedGaussian {
        /// The seed's `gauss_factor` (a variance).
        width: f64,
    },
    /// Precise: `smoothstep(0, 1, 1 - n_dist)` (1 at the centre, 0 on the rim).
    Smoothstep,
    /// Precise: `exp(-n_dist² / (2 width))` (1 at the centre).
    Gaussian {
        /// Variance, in units of the splat radius squared.
        width: f64,
    },
    /// An opaque disc.
    Disc,
}

impl Footprint {
    /// The footprint's alpha at `n_dist` in [0, 1] (may exceed 1 or be NaN for the
    /// seed's Gaussian, see the module doc).
    pub fn alpha(&self, n_dist: f64) -> f64 {
        match *self {
            Footprint::SeedSmoothstep => smoothstep(0.0, 1.0, n_dist),
            Footprint::SeedGaussian { width } => seed_gauss(n_dist, 1.0, width),
            Footprint::Smoothstep => smoothstep(0.0, 1.0, 1.0 - n_dist),
            Footprint::Gaussian { width } => {
                if width > 0.0 {
                    (-n_dist * n_dist / (2.0 * width)).exp()
                } else if n_dist == 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
            Footprint::Disc => 1.0,
        }
    }
}

/// GLSL's `smoothstep`.
pub fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The seed's `gauss(x, x0, sx)` as written.
pub fn seed_gauss(x: f64, x0: f64, sx: f64) -> f64 {
    let d = x - x0;
    let e = -1.0 / 2.0 * d * d / sx;
    let a = 1.0 / (2.0 * std::f64::consts::PI * sx).powf(0.5);
    a * e.exp()
}

/// The splat rules shared by the renderer and this reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplatParams {
    /// The seed's `pointSize` uniform.
    pub point_size: f64,
    /// The seed's `factor`.
    pub factor: f64,
    /// Alpha fall-off.
    pub footprint: Footprint,
    /// Sizes are clamped to this range (GL's `POINT_SIZE_RANGE`).
    pub size_range: [f64; 2],
}

impl Default for SplatParams {
    fn default() -> Self {
        SplatParams {
            point_size: 10.0,
            factor: 1.0,
            footprint: Footprint::Smoothstep,
            size_range: [1.0, 255.0],
        }
    }
}

impl SplatParams {
    /// Splats of `point_size` (factor 1, GL's default size range) with `footprint`.
    pub fn sized(footprint: Footprint, point_size: f64) -> SplatParams {
        SplatParams {
            point_size,
            footprint,
            ..SplatParams::default()
        }
    }
}

/// The eye in object space (perspective), [`Camera::eye`].
pub fn eye_position(camera: &Camera) -> Option<DVec3> {
    (camera.projection == Projection::Perspective).then(|| camera.eye())
}

/// The viewing direction in object space (into the scene), `R⁻¹ (0, 0, -1)`.
pub fn view_direction(camera: &Camera) -> DVec3 {
    -camera.toward_viewer()
}

/// A splat's size in pixels (see the module doc), unclamped NaN when undefined.
pub fn splat_size(params: &SplatParams, camera: &Camera, p: DVec3) -> f64 {
    size_from(params, eye_position(camera), p)
}

fn size_from(params: &SplatParams, eye: Option<DVec3>, p: DVec3) -> f64 {
    let size = match eye {
        Some(eye) => params.point_size / p.distance(eye) * params.factor,
        None => params.point_size * params.factor,
    };
    if size.is_nan() {
        return f64::NAN;
    }
    size.max(params.size_range[0]).min(params.size_range[1])
}

/// What is drawn: points (object space, as the GPU gets them), one RGBA each (points
/// past the shorter of the two are not drawn), the splat rules, the clear colour.
#[derive(Debug, Clone, Copy)]
pub struct SplatScene<'a> {
    /// Positions.
    pub positions: &'a [[f32; 3]],
    /// Colour and alpha per point.
    pub rgba: &'a [[f64; 4]],
    /// Size and footprint rules.
    pub params: SplatParams,
    /// The clear colour.
    pub background: [f64; 4],
}

impl SplatScene<'_> {
    fn len(&self) -> usize {
        self.positions.len().min(self.rgba.len())
    }

    fn position(&self, i: usize) -> DVec3 {
        DVec3::from_array(self.positions[i].map(f64::from))
    }
}

/// A splat on screen (GL window coordinates, y up).
#[derive(Debug, Clone, Copy)]
struct Screen {
    x: f64,
    y: f64,
    size: f64,
    rgb: [f64; 3],
    alpha: f64,
    /// Distance along the view axis (see the module doc) and window depth, for OIT.
    z: f64,
    depth: f64,
}

/// Where GL draws a point: the camera's matrices and eye, computed once per image.
pub struct Projector {
    mvp: DMat4,
    view: DMat4,
    eye: Option<DVec3>,
    size: [f64; 2],
}

impl Projector {
    /// The projector of `camera` onto a `size` image.
    pub fn new(camera: &Camera, size: [u32; 2]) -> Projector {
        Projector {
            mvp: camera.view_projection(size[0] as f64 / size[1].max(1) as f64),
            view: camera.view(),
            eye: eye_position(camera),
            size: [size[0] as f64, size[1] as f64],
        }
    }

    /// Window position (x, y: GL's, y up) and size in pixels of the splat at `p`, with
    /// its clip position; `None` when GL would not draw it (steps 1 and 2 of the module
    /// doc).
    pub fn place(&self, params: &SplatParams, p: DVec3) -> Option<([f64; 3], DVec4)> {
        let c = self.mvp * DVec4::new(p.x, p.y, p.z, 1.0);
        // Written so that NaN fails every test.
        let inside = c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z.abs() <= c.w;
        let s = size_from(params, self.eye, p);
        let drawn = s > 0.0;
        if !inside || !drawn {
            return None;
        }
        let x = (c.x / c.w + 1.0) / 2.0 * self.size[0];
        let y = (c.y / c.w + 1.0) / 2.0 * self.size[1];
        Some(([x, y, s], c))
    }

    /// Splat `i` on screen, or `None` when GL would not draw it.
    fn project(&self, scene: &SplatScene, i: usize) -> Option<Screen> {
        let p = scene.position(i);
        let ([x, y, size], c) = self.place(&scene.params, p)?;
        let eye_z = (self.view * DVec4::new(p.x, p.y, p.z, 1.0)).z;
        let rgba = scene.rgba[i];
        Some(Screen {
            x,
            y,
            size,
            rgb: [0, 1, 2].map(|k| clamp01(rgba[k])),
            alpha: rgba[3],
            z: match self.eye {
                Some(_) => -eye_z,
                None => 2.0 - eye_z,
            },
            depth: (c.z / c.w + 1.0) / 2.0,
        })
    }
}

/// Clamp to [0, 1] with NaN → 0.
fn clamp01(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0)
    }
}

/// Pixel index range `[lo, hi)` whose centres `k + 0.5` lie in `[c - h, c + h)`.
pub fn covered(c: f64, h: f64, limit: u32) -> (i64, i64) {
    let lo = (c - h - 0.5).ceil().max(0.0);
    let hi = (c + h - 0.5).ceil().min(limit as f64);
    (lo as i64, hi as i64)
}

/// Call `fragment(pixel, screen, alpha)` for every fragment of `splats` (in order) in
/// parallel bands of rows; `pixels` holds `width` entries per GL row, bottom row first.
fn rasterize<T: Send>(
    splats: &[Screen],
    footprint: Footprint,
    size: [u32; 2],
    pixels: &mut [T],
    fragment: impl Fn(&mut T, &Screen, f64) + Sync,
) {
    let [width, height] = size;
    let band = 16usize;
    // A bar (bands of rows done, time left) when a reference runs past a couple of seconds.
    let bar = arbvis_core::progress::Bar::delayed(
        height.div_ceil(band as u32) as u64,
        "f64 splat reference (bands of 16 rows)",
        arbvis_core::progress::Unit::Rows,
        std::time::Duration::from_secs(2),
    );
    pixels
        .par_chunks_mut(width.max(1) as usize * band)
        .enumerate()
        .for_each(|(b, rows)| {
            let first = (b * band) as i64;
            let last = (first + band as i64).min(height as i64);
            for s in splats {
                let h = s.size / 2.0;
                let (y0, y1) = covered(s.y, h, height);
                let (y0, y1) = (y0.max(first), y1.min(last));
                if y0 >= y1 {
                    continue;
                }
                let (x0, x1) = covered(s.x, h, width);
                for j in y0..y1 {
                    let dy = j as f64 + 0.5 - s.y;
                    for i in x0..x1 {
                        let dx = i as f64 + 0.5 - s.x;
                        let n_dist = 2.0 * (dx * dx + dy * dy).sqrt() / s.size;
                        if n_dist > 1.0 {
                            continue;
                        }
                        let a = clamp01(s.alpha * footprint.alpha(n_dist));
                        let k = (j - first) as usize * width as usize + i as usize;
                        fragment(&mut rows[k], s, a);
                    }
                }
            }
            bar.inc(1);
        });
}

/// GL rows (bottom first) to an image (top first).
fn to_image(size: [u32; 2], pixels: Vec<[f64; 4]>) -> Image {
    let [width, height] = size;
    let mut rows: Vec<&[[f64; 4]]> = pixels.chunks(width.max(1) as usize).collect();
    rows.truncate(height as usize);
    rows.reverse();
    Image::from_f64_pixels(width, height, TargetFormat::Rgba32f, rows.concat())
}

/// The exact back-to-front order in f64 (farthest first, ties in index order).
pub fn exact_order(positions: &[[f32; 3]], camera: &Camera) -> Vec<u32> {
    let eye = eye_position(camera);
    let dir = view_direction(camera);
    let key = |p: &[f32; 3]| {
        let p = DVec3::from_array(p.map(f64::from));
        let k = match eye {
            Some(e) => p.distance(e),
            None => p.dot(dir),
        };
        if k.is_nan() {
            f64::INFINITY
        } else {
            k + 0.0
        }
    };
    let n = positions.len().min(u32::MAX as usize);
    let mut order: Vec<(f64, u32)> = (0..n).map(|i| (key(&positions[i]), i as u32)).collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0));
    order.into_iter().map(|(_, i)| i).collect()
}

/// The renderer's back-to-front order (see the module doc): the f32 [`View::key`] of
/// `camera`'s view, farthest first, ties in index order.
pub fn key_order(positions: &[[f32; 3]], camera: &Camera) -> Vec<u32> {
    keys_order(positions, View::of_camera(camera))
}

/// The reference image: the splats in the renderer's back-to-front order
/// ([`key_order`]), blended in f64.
pub fn composite(scene: &SplatScene, camera: &Camera, size: [u32; 2]) -> Image {
    let order = key_order(&scene.positions[..scene.len()], camera);
    composite_in_order(scene, &order, camera, size)
}

/// Per pixel (top row first, as an [`Image`]), the most a renderer placing splats in
/// f32 can differ from [`composite`] there by a rim fragment falling on the other side
/// of `n_dist = 1`: the sum, over the splats whose rim passes within `delta` pixels of
/// the pixel's centre, of the alpha of their rim (the point's alpha times the footprint
/// at 1). 0 where no rim passes that close.
pub fn rim_allowance(scene: &SplatScene, camera: &Camera, size: [u32; 2], delta: f64) -> Vec<f64> {
    let projector = Projector::new(camera, size);
    let splats: Vec<Screen> = (0..scene.len())
        .filter_map(|i| projector.project(scene, i))
        .collect();
    let rim = scene.params.footprint.alpha(1.0);
    let [width, height] = size;
    let mut pixels = vec![0.0f64; width as usize * height as usize];
    for s in &splats {
        let h = s.size / 2.0;
        let (y0, y1) = covered(s.y, h + delta, height);
        let (x0, x1) = covered(s.x, h + delta, width);
        for j in y0..y1 {
            let dy = j as f64 + 0.5 - s.y;
            for i in x0..x1 {
                let dx = i as f64 + 0.5 - s.x;
                if ((dx * dx + dy * dy).sqrt() - h).abs() <= delta {
                    // GL rows count up; images count down.
                    let k = (height as i64 - 1 - j) as usize * width as usize + i as usize;
                    pixels[k] += clamp01(s.alpha * rim);
                }
            }
        }
    }
    pixels
}

/// The splats drawn in `order` (indices past the points are skipped), blended in f64.
pub fn composite_in_order(
    scene: &SplatScene,
    order: &[u32],
    camera: &Camera,
    size: [u32; 2],
) -> Image {
    let splats = screen_splats(scene, order.iter().map(|&i| i as usize), camera, size);
    let mut pixels = vec![scene.background; size[0] as usize * size[1] as usize];
    rasterize(
        &splats,
        scene.params.footprint,
        size,
        &mut pixels,
        |dst, s, a| {
            for (d, c) in dst.iter_mut().zip(s.rgb) {
                *d = c * a + *d * (1.0 - a);
            }
            dst[3] = a + dst[3] * (1.0 - a);
        },
    );
    to_image(size, pixels)
}

fn screen_splats(
    scene: &SplatScene,
    indices: impl Iterator<Item = usize>,
    camera: &Camera,
    size: [u32; 2],
) -> Vec<Screen> {
    let projector = Projector::new(camera, size);
    indices
        .filter(|&i| i < scene.len())
        .filter_map(|i| projector.project(scene, i))
        .collect()
}

/// McGuire & Bavoil's depth weights `w(z, a)` (equations 7 to 10 of the paper).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OitWeight {
    /// `a` alone (no depth term).
    Alpha,
    /// Eq. 7: `a · max(1e-2, min(3e3, 10 / (1e-5 + (z/5)² + (z/200)⁶)))`.
    Eq7,
    /// Eq. 8: `a · max(1e-2, min(3e3, 10 / (1e-5 + (z/10)³ + (z/200)⁶)))`.
    Eq8,
    /// Eq. 9: `a · max(1e-2, min(3e3, 0.03 / (1e-5 + (z/200)⁴)))`.
    Eq9,
    /// Eq. 10: `a · max(1e-2, 3e3 (1 - d)³)`, `d` the window depth.
    Eq10,
}

impl OitWeight {
    /// The weight of a fragment of alpha `a` at view distance `z` and window depth `d`.
    pub fn weight(self, a: f64, z: f64, d: f64) -> f64 {
        let z = z.abs();
        let w = match self {
            OitWeight::Alpha => 1.0,
            OitWeight::Eq7 => 10.0 / (1e-5 + (z / 5.0).powi(2) + (z / 200.0).powi(6)),
            OitWeight::Eq8 => 10.0 / (1e-5 + (z / 10.0).powi(3) + (z / 200.0).powi(6)),
            OitWeight::Eq9 => 0.03 / (1e-5 + (z / 200.0).powi(4)),
            OitWeight::Eq10 => return a * (3e3 * (1.0 - d).powi(3)).max(1e-2),
        };
        if self == OitWeight::Alpha {
            a
        } else {
            a * w.clamp(1e-2, 3e3)
        }
    }
}

/// The weighted blended order-independent composite of the same splats (no sorting).
pub fn weighted_blended(
    scene: &SplatScene,
    weight: OitWeight,
    camera: &Camera,
    size: [u32; 2],
) -> Image {
    let splats = screen_splats(scene, 0..scene.len(), camera, size);
    // Accumulated (c a w, a w) and revealage.
    let mut pixels = vec![([0.0f64; 4], 1.0f64); size[0] as usize * size[1] as usize];
    rasterize(
        &splats,
        scene.params.footprint,
        size,
        &mut pixels,
        |(acc, reveal), s, a| {
            let w = weight.weight(a, s.z, s.depth);
            for (sum, c) in acc.iter_mut().zip(s.rgb) {
                *sum += c * a * w;
            }
            acc[3] += a * w;
            *reveal *= 1.0 - a;
        },
    );
    let bg = scene.background;
    let resolved = pixels
        .into_iter()
        .map(|(acc, r)| {
            let avg = [0, 1, 2].map(|k| acc[k] / acc[3].max(1e-5));
            [
                avg[0] * (1.0 - r) + bg[0] * r,
                avg[1] * (1.0 - r) + bg[1] * r,
                avg[2] * (1.0 - r) + bg[2] * r,
                1.0 - (1.0 - bg[3]) * r,
            ]
        })
        .collect();
    to_image(size, resolved)
}

/// Root mean square difference of the colour channels (alpha left out: the seed's
/// blend makes it `a² + ...`, see the module doc); `None` when the sizes differ.
pub fn rmse_rgb(a: &Image, b: &Image) -> Option<f64> {
    if (a.width, a.height) != (b.width, b.height) {
        return None;
    }
    let (mut sum, mut count) = (0.0f64, 0usize);
    for (p, q) in a.data.chunks_exact(4).zip(b.data.chunks_exact(4)) {
        for k in 0..3 {
            let d = p[k] as f64 - q[k] as f64;
            sum += if d.is_finite() { d * d } else { 1.0 };
            count += 1;
        }
    }
    Some((sum / count.max(1) as f64).sqrt())
}

#[cfg(test)]
mod tests;
