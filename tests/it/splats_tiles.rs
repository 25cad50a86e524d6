//! Splats drawn as tiles (`draw = "tiles"`): the gather program against the f64
//! reference and against the same splats drawn as points, lighting recomputed as the view
//! turns, the fallback to points past the bound on list entries, and the scene's rules.

use crate::common;

use arbvis::camera::{Camera, Projection};
use arbvis::gl::{Backend, ProgramKind, Surface, Target, TargetFormat};
use arbvis::image::Image;
use arbvis::points::PointCloud;
use arbvis::scene::{Fidelity, Scene};
use arbvis::techniques::splats::prepare::{from_cloud, normals_for};
use arbvis::techniques::splats::SplatsRenderer;
use arbvis::techniques::{Frame, Renderer};
use common::headless;
use common::splats::*;

/// Scenes that differ in every way the gather program branches: kernels, colour modes,
/// lighting, volume mode's alpha, sizes, and file order.
const SCENES: [&str; 6] = [
    "kernel = \"gaussian\"\ngauss_width = 0.15\npoint_size = 7.0",
    "kernel = \"smoothstep\"\ncolour = \"property\"\npoint_size = 6.0",
    "kernel = \"gaussian\"\ngauss_width = 0.02\npoint_size = 5.0\ncolour = \"layer\"",
    "lighting = true\npoint_size = 6.0\ntile = 3",
    "mode = \"volume\"\ncolour = \"property\"\npoint_size = 9.0\ntile = 1",
    "sort = \"none\"\npoint_size = 8.0\ntile = 5",
];

fn tiles(text: &str) -> String {
    format!("{text}\ndraw = \"tiles\"")
}

#[test]
fn tiles_match_the_f64_reference_and_the_points() {
    let h = headless(Backend::Egl);
    let c = cloud(1500);
    for text in SCENES {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let cam = camera(projection);
            let p = params(&tiles(text));
            let gathered = rgb_only(&draw(&h, &c, &p, Fidelity::Precise, cam));
            let exact = rgb_only(&reference(&c, &p, Fidelity::Precise, &cam));
            let points = rgb_only(&draw(&h, &c, &params(text), Fidelity::Precise, cam));
            let e = errors(&gathered, &exact);
            let covered = gathered
                .data
                .chunks_exact(4)
                .filter(|px| px[..3] != BACKGROUND[..3])
                .count();
            eprintln!(
                "{projection:?} [{}]: {covered} pixels drawn, against f64: max {:.2e} p999 {:.2e}; \
                 against points: max {:.2e}",
                text.replace('\n', " "),
                e.last().unwrap(),
                quantile(&e, 0.999),
                errors(&gathered, &points).last().unwrap()
            );
            assert!(covered > 500, "{text}: {covered} pixels drawn");
            if text.contains("sort = \"none\"") {
                // File order: visibly not the exact order (the points' order, below).
                assert!(*e.last().unwrap() > 0.05, "{text}");
            } else {
                // Positions, sizes and colours in f32 (as the vertex program computes
                // them), compositing in f32, the walk stopped at a transmittance of 2^-16:
                // measured at most 2.7e-5 from the f64 reference (a pixel centre within
                // 1e-3 px of a rim could take or lose the rim's alpha: none here).
                assert!(*e.last().unwrap() < 1e-4, "{projection:?} [{text}]");
            }
            // Against the same splats drawn as points, whose programs place them and
            // take the footprint as the gather does (in the vertex stage rather than on
            // the CPU): f32 rounding, measured max 4.2e-5, 99.9 % within 1.3e-5; the max
            // is left free, as a rim within rounding of a pixel centre could flip.
            let vs_points = errors(&gathered, &points);
            assert!(
                quantile(&vs_points, 0.999) < 1e-4,
                "{projection:?} [{text}]"
            );
        }
    }
}

/// A renderer of the scene `text` on a 96 x 72 float target.
fn renderer(h: &arbvis::gl::Headless, text: &str) -> (SplatsRenderer, Target) {
    let c = cloud(1500);
    let p = params(text);
    let normals = normals_for(&c, &p);
    let prepared = from_cloud(&c, &p, normals).unwrap();
    let gpu = h.gpu();
    let r = SplatsRenderer::from_prepared(
        gpu,
        ProgramKind::Glsl,
        Fidelity::Precise,
        &p,
        std::path::Path::new("."),
        c,
        prepared,
    )
    .unwrap();
    let target = Target::new(gpu, SIZE[0], SIZE[1], TargetFormat::Rgba32f).unwrap();
    (r, target)
}

fn frame(r: &mut SplatsRenderer, h: &arbvis::gl::Headless, t: &Target, cam: Camera) -> Image {
    frame_over(r, h, t, cam, BACKGROUND)
}

/// A frame drawn over `background`.
fn frame_over(
    r: &mut SplatsRenderer,
    h: &arbvis::gl::Headless,
    t: &Target,
    cam: Camera,
    background: [f32; 4],
) -> Image {
    let gpu = h.gpu();
    t.clear(gpu, background).unwrap();
    let f = Frame {
        camera: cam,
        width: SIZE[0],
        height: SIZE[1],
    };
    r.draw(gpu, Surface::Target(t), &f).unwrap();
    t.read(gpu).unwrap()
}

#[test]
fn lists_and_lit_colours_follow_the_camera() {
    let h = headless(Backend::Egl);
    let text = "lighting = true\npoint_size = 6.0";
    let (mut r, target) = renderer(&h, &tiles(text));
    let first = camera(Projection::Perspective);
    let mut turned = first;
    turned.rotation = (first.quat() * glam::DQuat::from_rotation_y(0.5)).to_array();
    let c = cloud(1500);
    let p = params(&tiles(text));
    let a = frame(&mut r, &h, &target, first);
    let b = frame(&mut r, &h, &target, turned);
    // The second frame is the turned view, lit from its own eye: the reference of the
    // turned camera, not the first one's lists or colours.
    let e = errors(
        &rgb_only(&b),
        &rgb_only(&reference(&c, &p, Fidelity::Precise, &turned)),
    );
    assert!(quantile(&e, 0.999) < 2e-3, "{:?}", e.last());
    assert!(errors(&a, &b).last().unwrap() > &0.1, "the view changed");
    // The same camera again draws the same picture without new lists.
    let status = r.status().unwrap();
    let again = frame(&mut r, &h, &target, turned);
    assert_eq!(again.compare(&b, 0.0).unwrap().max_abs, 0.0);
    assert_eq!(r.status().unwrap(), status);
    assert!(status.contains("as tiles of 2 px"), "{status}");
}

#[test]
fn past_the_bound_on_entries_a_frame_is_drawn_as_points() {
    // 2,500 splats of 255 pixels (the clamp) cover all 96 x 72 tiles of 1 pixel:
    // 17 million entries, past the 16 M bound.
    let h = headless(Backend::Egl);
    let c = cloud(2500);
    let text = "point_size = 4000.0\ntile = 1\nkernel = \"gaussian\"";
    let cam = Camera {
        zoom: 0.8,
        ..Camera::default()
    };
    let p = params(&tiles(text));
    let normals = normals_for(&c, &p);
    let prepared = from_cloud(&c, &p, normals).unwrap();
    let gpu = h.gpu();
    let mut r = SplatsRenderer::from_prepared(
        gpu,
        ProgramKind::Glsl,
        Fidelity::Precise,
        &p,
        std::path::Path::new("."),
        c.clone(),
        prepared,
    )
    .unwrap();
    let target = Target::new(gpu, SIZE[0], SIZE[1], TargetFormat::Rgba32f).unwrap();
    let fell_back = frame(&mut r, &h, &target, cam);
    let status = r.status().unwrap();
    assert!(status.contains("drawn as points"), "{status}");
    let as_points = draw(&h, &c, &params(text), Fidelity::Precise, cam);
    assert_eq!(fell_back.compare(&as_points, 0.0).unwrap().max_abs, 0.0);
}

#[test]
fn tiles_are_precise_and_glsl_and_need_an_order() {
    let scene = |lines: &str, technique: &str| {
        Scene::parse(
            &format!(
                "{lines}\n[technique.splats]\ncloud = {{ section = {{ points = 100 }} }}\n{technique}\n"
            ),
            "tiles.toml",
        )
    };
    for (lines, technique, key, says) in [
        (
            "fidelity = \"faithful\"",
            "draw = \"tiles\"",
            "technique.splats.draw",
            "precise",
        ),
        (
            "fidelity = \"precise\"\nprograms = \"arb\"",
            "draw = \"tiles\"",
            "technique.splats.draw",
            "GLSL",
        ),
        (
            "fidelity = \"precise\"",
            "draw = \"tiles\"\nsort = \"oit\"",
            "technique.splats.draw",
            "oit",
        ),
        (
            "fidelity = \"precise\"",
            "draw = \"tiles\"\ntile = 0",
            "technique.splats.tile",
            "1..=256",
        ),
    ] {
        let e = scene(lines, technique).unwrap_err().to_string();
        assert!(e.contains(key) && e.contains(says), "{technique}: {e}");
        assert!(e.contains("tiles.toml:"), "{e}");
    }
    assert!(scene("fidelity = \"precise\"", "draw = \"tiles\"").is_ok());
    assert!(scene("fidelity = \"faithful\"", "draw = \"points\"").is_ok());
}

#[test]
fn edits_reach_the_tiles() {
    // Point size, kernel and the transfer function change what the lists and colours
    // hold without rebuilding the renderer: the edited renderer draws what a new one does.
    let h = headless(Backend::Egl);
    let cam = camera(Projection::Perspective);
    let base = "mode = \"volume\"\ncolour = \"property\"\npoint_size = 6.0";
    let edited = "mode = \"volume\"\ncolour = \"property\"\npoint_size = 11.0\n\
                  kernel = \"smoothstep\"\nvolume = { threshold = 0.004, range = 0.003 }";
    let (mut r, target) = renderer(&h, &tiles(base));
    let before = frame(&mut r, &h, &target, cam);
    let new = arbvis::scene::TechniqueScene::Splats(Box::new(params(&tiles(edited))));
    r.update(h.gpu(), new.params()).unwrap();
    let after = frame(&mut r, &h, &target, cam);
    let (mut fresh, fresh_target) = renderer(&h, &tiles(edited));
    let expected = frame(&mut fresh, &h, &fresh_target, cam);
    assert_eq!(after.compare(&expected, 0.0).unwrap().max_abs, 0.0);
    let changed = before.compare(&after, 0.0).unwrap();
    assert!(changed.pixels_over > 100, "{changed:?}");
}

#[test]
fn coverage_over_a_transparent_background_is_the_points_alpha() {
    // Volume mode gives partial alphas; the background's alpha is 0, so the frame's alpha
    // is the splats' coverage: a + dst.a (1 - a) per splat for points, 1 - T + T dst.a
    // for the gather, the same number.
    let h = headless(Backend::Egl);
    let text =
        "mode = \"volume\"\ncolour = \"property\"\nkernel = \"smoothstep\"\npoint_size = 7.0";
    let cam = camera(Projection::Orthographic);
    let clear = [0.2, 0.1, 0.0, 0.0];
    let (mut t, target) = renderer(&h, &tiles(text));
    let gathered = frame_over(&mut t, &h, &target, cam, clear);
    let (mut p, target) = renderer(&h, text);
    let points = frame_over(&mut p, &h, &target, cam, clear);
    let alpha = |img: &Image| -> Vec<f32> { img.data.chunks_exact(4).map(|px| px[3]).collect() };
    let (a, b) = (alpha(&gathered), alpha(&points));
    let partial = a.iter().filter(|&&v| v > 0.05 && v < 0.95).count();
    assert!(partial > 100, "{partial} partly covered pixels");
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    // Orthographic: no rim flips; f32 compositing in a different order (measured 1e-6).
    assert!(worst < 1e-4, "alpha differs by {worst}");
}

/// `x` moved by `n` steps of its bit pattern (a few ulps, away from zero for n > 0).
fn nudge(x: f32, n: i32) -> f32 {
    f32::from_bits((x.to_bits() as i32 + n) as u32)
}

/// A dense cloud built against the f32 depth key: at each of up to `sites` random places
/// a point and a twin a few ulps away, kept only when the renderer's f32 key orders the
/// pair otherwise than their f64 depths (the keys tie with the nearer point first in
/// index order, or round the other way); the first of each pair warm, the second cool.
/// Returns the cloud and the number of pairs.
fn pairs_the_key_cannot_order(camera: &Camera, sites: usize) -> (PointCloud, usize) {
    use arbvis::points::section::SplitMix64;
    use arbvis::techniques::splats::reference::{exact_order, key_order};
    let mut rng = SplitMix64::new(18);
    let (mut positions, mut rgb) = (Vec::new(), Vec::new());
    for _ in 0..sites {
        let p: [f32; 3] = [0, 1, 2].map(|_| rng.range(-0.7, 0.7) as f32);
        for _ in 0..64 {
            let q = p.map(|v| nudge(v, (rng.next_u64() % 7) as i32 - 3));
            let pair = [p, q];
            if q != p && key_order(&pair, camera) != exact_order(&pair, camera) {
                positions.extend(pair);
                let shade = (rng.next_f64() * 30_000.0) as u16;
                rgb.extend([[65_535, shade, 0], [0, shade, 65_535]]);
                break;
            }
        }
    }
    let n = positions.len() / 2;
    let cloud = PointCloud {
        origin: [0.0; 3],
        scale: 1.0,
        positions,
        bounds: [[-0.7; 3], [0.7; 3]],
        frame: [[-0.7; 3], [0.7; 3]],
        attributes: Vec::new(),
        rgb: Some(rgb),
        normals: None,
    };
    (cloud, n)
}

#[test]
fn near_equal_depths_are_drawn_in_the_references_order() {
    use arbvis::techniques::splats::reference::{
        composite, composite_in_order, exact_order, rim_allowance,
    };
    let h = headless(Backend::Egl);
    let splats = "colour = \"rgb\"\nkernel = \"gaussian\"\ngauss_width = 0.35\npoint_size = 6.0";
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let cam = camera(projection);
        let (c, pairs) = pairs_the_key_cannot_order(&cam, 600);
        // Most random places have a twin a few ulps away that the key misorders.
        assert!(pairs > 400, "{projection:?}: {pairs} pairs");
        let p = params(splats);
        let (positions, rgba) = reference_points(&c, &p, Fidelity::Precise, &cam);
        let scene = reference_scene(&positions, &rgba, &p, Fidelity::Precise);
        let reference = rgb_only(&composite(&scene, &cam, SIZE));
        let true_order = exact_order(&positions, &cam);
        let f64_order = rgb_only(&composite_in_order(&scene, &true_order, &cam, SIZE));
        let allowance = rim_allowance(&scene, &cam, SIZE, 1e-3);
        // The cloud is not a friendly one: drawn in the f64 order, the pairs' colours
        // swap (warm over cool) at many pixels.
        let vs_f64 = errors(&f64_order, &reference);
        let swapped = vs_f64.iter().filter(|&&e| e > 0.1).count();
        eprintln!(
            "{projection:?}: {pairs} pairs; f64 order against the key's: max {:.3}, {swapped} \
             values over 0.1",
            vs_f64.last().unwrap()
        );
        assert!(swapped > 100, "{projection:?}: {swapped}");
        for (what, text) in [
            ("tiles", format!("{splats}\ndraw = \"tiles\"")),
            ("points, keys", format!("{splats}\nsort = \"keys\"")),
            ("points, radix", format!("{splats}\nsort = \"radix\"")),
        ] {
            let drawn = rgb_only(&draw(&h, &c, &params(&text), Fidelity::Precise, cam));
            let mut excess = f64::NEG_INFINITY;
            for ((g, r), &a) in drawn
                .data
                .chunks_exact(4)
                .zip(reference.data.chunks_exact(4))
                .zip(&allowance)
            {
                let d = (0..3).map(|k| (g[k] - r[k]).abs()).fold(0.0f32, f32::max);
                excess = excess.max(d as f64 - a);
            }
            let vs_true = errors(&drawn, &f64_order);
            eprintln!(
                "{projection:?} {what}: worst excess over the rim allowance {excess:.2e}; \
                 against the f64 order max {:.3}",
                vs_true.last().unwrap()
            );
            // Same order as the reference, so only f32 placement and blending are left
            // (the bound of precise_points_match_the_reference_but_for_rim_flips and of
            // the tiles' 2.7e-5), plus the alpha of rims within 1e-3 px of a pixel centre.
            assert!(excess < 1e-4, "{projection:?} {what}: {excess:e}");
        }
    }
}
