//! Splat helpers shared by the splat tests: a generated section, scenes from TOML
//! lines, a rotated camera, a GPU draw into a float target and the f64 reference of the
//! same splats.

use arbvis::camera::{Camera, Projection};
use arbvis::gl::{Headless, ProgramKind, TargetFormat};
use arbvis::image::Image;
use arbvis::points::section::{generate, SectionSpec};
use arbvis::points::PointCloud;
use arbvis::scene::Fidelity;
use arbvis::techniques::splats::oit::OIT_WEIGHT;
use arbvis::techniques::splats::prepare::{footprint, from_cloud, normals_for, point_rgba};
use arbvis::techniques::splats::reference::{
    composite, eye_position, view_direction, weighted_blended, SplatParams, SplatScene,
};
use arbvis::techniques::splats::{SplatsRenderer, SplatsScene};
use arbvis::techniques::Renderer;

use super::frame::Shot;

pub const BACKGROUND: [f32; 4] = [0.1, 0.1, 0.15, 1.0];
pub const SIZE: [u32; 2] = [96, 72];

pub fn cloud(points: usize) -> PointCloud {
    generate(&SectionSpec { points, seed: 7 }).unwrap()
}

pub fn params(text: &str) -> SplatsScene {
    toml::from_str(&format!(
        "cloud = {{ section = {{ points = 1500, seed = 7 }} }}\n{text}"
    ))
    .unwrap()
}

pub fn camera(projection: Projection) -> Camera {
    Camera {
        projection,
        rotation: [-0.5703, -0.1422, -0.1957, 0.785],
        zoom: 1.6,
        ..Camera::default()
    }
}

/// The camera of a comparison of `fidelity`. Precise programs drop a point whose centre
/// lies outside the view, as GL's spec and the reference do, so their comparisons keep
/// the section cut by the image's edges ([`camera`]). The seed's programs, run as
/// written, draw what the driver draws there: llvmpipe drops such points, NVIDIA draws
/// the wide ones whose centre is just off-screen (its pixels at the edge then differ
/// from the reference by up to 0.8, measured on an H100 and an H200). Faithful
/// comparisons use a view that holds every centre (zoom 0.55; [`all_centres_inside`]).
pub fn camera_for(projection: Projection, fidelity: Fidelity) -> Camera {
    match fidelity {
        Fidelity::Precise => camera(projection),
        Fidelity::Faithful => Camera {
            zoom: 0.55,
            ..camera(projection)
        },
    }
}

/// Whether every point's centre lies inside `camera`'s clip volume at [`SIZE`].
pub fn all_centres_inside(cloud: &PointCloud, camera: &Camera) -> bool {
    let m = camera.view_projection(SIZE[0] as f64 / SIZE[1] as f64);
    cloud.positions.iter().all(|p| {
        let q = m * glam::DVec4::new(p[0] as f64, p[1] as f64, p[2] as f64, 1.0);
        q.w > 0.0 && q.x.abs() <= q.w && q.y.abs() <= q.w && q.z.abs() <= q.w
    })
}

/// Draw `cloud` with `params` into a float target (no 8-bit blending drift), GLSL.
pub fn draw(
    h: &Headless,
    cloud: &PointCloud,
    params: &SplatsScene,
    fidelity: Fidelity,
    camera: Camera,
) -> Image {
    draw_with(h, ProgramKind::Glsl, cloud, params, fidelity, camera)
}

/// [`draw`] with programs of `kind`.
pub fn draw_with(
    h: &Headless,
    kind: ProgramKind,
    cloud: &PointCloud,
    params: &SplatsScene,
    fidelity: Fidelity,
    camera: Camera,
) -> Image {
    draw_sized(h, kind, cloud, params, fidelity, camera, SIZE)
}

/// [`draw_with`] on a `size` target.
pub fn draw_sized(
    h: &Headless,
    kind: ProgramKind,
    cloud: &PointCloud,
    params: &SplatsScene,
    fidelity: Fidelity,
    camera: Camera,
    size: [u32; 2],
) -> Image {
    let gpu = h.gpu();
    let normals = normals_for(cloud, params);
    let prepared = from_cloud(cloud, params, normals).unwrap();
    let mut r = SplatsRenderer::from_prepared(
        gpu,
        kind,
        fidelity,
        params,
        std::path::Path::new("."),
        cloud.clone(),
        prepared,
    )
    .unwrap();
    let image = Shot::new(size, TargetFormat::Rgba32f)
        .on(BACKGROUND)
        .draw(gpu, &mut r, &camera);
    assert_eq!(r.program_kind(), kind);
    image
}

/// What renderer `r` draws of `camera` into a fresh `size` float target.
pub fn draw_renderer(
    gpu: &arbvis::gl::Gpu,
    r: &mut dyn Renderer,
    camera: &Camera,
    size: [u32; 2],
) -> Image {
    Shot::new(size, TargetFormat::Rgba32f).draw(gpu, r, camera)
}

/// The f64 reference of the same splats.
pub fn reference(
    cloud: &PointCloud,
    params: &SplatsScene,
    fidelity: Fidelity,
    camera: &Camera,
) -> Image {
    reference_of(cloud, params, fidelity, camera, false)
}

/// The f64 reference, in the renderer's order or weighted blended (the GPU's weight).
pub fn reference_of(
    cloud: &PointCloud,
    params: &SplatsScene,
    fidelity: Fidelity,
    camera: &Camera,
    oit: bool,
) -> Image {
    let (positions, rgba) = reference_points(cloud, params, fidelity, camera);
    let scene = reference_scene(&positions, &rgba, params, fidelity);
    if oit {
        weighted_blended(&scene, OIT_WEIGHT, camera, SIZE)
    } else {
        composite(&scene, camera, SIZE)
    }
}

/// The drawn points' positions and f64 RGBA as the reference takes them.
pub fn reference_points(
    cloud: &PointCloud,
    params: &SplatsScene,
    fidelity: Fidelity,
    camera: &Camera,
) -> (Vec<[f32; 3]>, Vec<[f64; 4]>) {
    let normals = normals_for(cloud, params);
    let prepared = from_cloud(cloud, params, normals).unwrap();
    let rgba = point_rgba(
        &prepared,
        params,
        fidelity,
        eye_position(camera),
        view_direction(camera),
    );
    (prepared.positions, rgba)
}

/// The reference's scene of those points.
pub fn reference_scene<'a>(
    positions: &'a [[f32; 3]],
    rgba: &'a [[f64; 4]],
    params: &SplatsScene,
    fidelity: Fidelity,
) -> SplatScene<'a> {
    SplatScene {
        positions,
        rgba,
        params: SplatParams {
            point_size: params.point_size,
            factor: params.factor,
            footprint: footprint(params, fidelity),
            size_range: [1.0, 255.0],
        },
        background: BACKGROUND.map(f64::from),
    }
}

pub fn rgb_only(image: &Image) -> Image {
    let mut out = image.clone();
    out.data.chunks_exact_mut(4).for_each(|p| p[3] = 1.0);
    out
}

/// Per-value absolute differences of two images, sorted (the last is the largest).
pub fn errors(a: &Image, b: &Image) -> Vec<f32> {
    let mut e: Vec<f32> = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| (x - y).abs())
        .collect();
    e.sort_by(f32::total_cmp);
    e
}

/// The `q` quantile of sorted values.
pub fn quantile(sorted: &[f32], q: f64) -> f32 {
    sorted[((sorted.len() - 1) as f64 * q) as usize]
}

/// A camera of `projection` at `zoom`, turned by the quaternion `rotation` (normalized).
pub fn camera_turned(projection: Projection, zoom: f64, rotation: [f64; 4]) -> Camera {
    Camera {
        projection,
        rotation: glam::DQuat::from_array(rotation).normalize().to_array(),
        zoom,
        ..Default::default()
    }
}
