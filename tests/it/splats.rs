//! Splats end to end: GPU vs the f64 compositing reference (same footprints, same
//! order), every sort method drawing the same picture, the seed's formulas as written vs
//! corrected, hidden layers, lighting, volume mode, the extremes, and what gets built.

use crate::common;

use arbvis::camera::{Camera, Projection};
use arbvis::gl::{Backend, ProgramChoice, ProgramKind};
use arbvis::image::Image;
use arbvis::points::section::SectionSpec;
use arbvis::render::render_on;
use arbvis::scene::{Fidelity, Scene, TechniqueScene};
use arbvis::techniques::splats::reference::rmse_rgb;
use arbvis::techniques::splats::scene::{ColourMode, Kernel, Mode, SortChoice};
use common::headless;
use common::splats::*;

#[test]
fn gpu_matches_the_f64_reference() {
    let h = headless(Backend::Egl);
    let c = cloud(1500);
    for (fidelity, text) in [
        (
            Fidelity::Precise,
            "kernel = \"gaussian\"\ngauss_width = 0.15\npoint_size = 7.0",
        ),
        (
            Fidelity::Precise,
            "kernel = \"smoothstep\"\ncolour = \"property\"\npoint_size = 6.0",
        ),
        (
            Fidelity::Faithful,
            "kernel = \"gaussian\"\ngauss_width = 0.3\npoint_size = 7.0\ncolour = \"layer\"",
        ),
        (
            Fidelity::Faithful,
            "kernel = \"smoothstep\"\nfaults_white = true\npoint_size = 5.0",
        ),
        (Fidelity::Precise, "lighting = true\npoint_size = 6.0"),
        (
            Fidelity::Precise,
            "mode = \"volume\"\ncolour = \"property\"\npoint_size = 9.0",
        ),
    ] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let p = params(text);
            let cam = camera_for(projection, fidelity);
            assert!(fidelity == Fidelity::Precise || all_centres_inside(&c, &cam));
            let gpu = rgb_only(&draw(&h, &c, &p, fidelity, cam));
            let cpu = rgb_only(&reference(&c, &p, fidelity, &cam));
            let d = gpu.compare(&cpu, 0.0).unwrap();
            let errs = errors(&gpu, &cpu);
            let q = |f: f64| quantile(&errs, f);
            eprintln!(
                "{fidelity:?} {projection:?} [{}]: rmse {:.5} max {:.4} p99 {:.5} p999 {:.5}",
                text.replace('\n', " "),
                d.rmse,
                d.max_abs,
                q(0.99),
                q(0.999)
            );
            // Precise: f32 rounding only (the programs place the splat and take its
            // footprint as the reference does): measured max 2e-5; a pixel centre within
            // 1e-3 px of a rim could take or lose the rim's alpha (bounded by
            // precise_points_match_the_reference_but_for_rim_flips), none here.
            // Faithful (gl_PointCoord, from the rasterizer's fixed point): orthographic
            // views agree to 2e-3 everywhere (measured: exact but for f32 rounding). In
            // perspective the size is pointSize / distance * factor in f32 against f64,
            // so a pixel centre on a splat's rim (n_dist = 1) can fall on either side:
            // such flips cost the rim's alpha, up to 0.73 with the seed's rim-heavy
            // Gaussian (measured 0.51). 99.9 % of values agree within 2e-3 (measured 8e-4).
            // Another rasterizer snaps sprite centres its own way (NVIDIA: 8 bits of
            // sub-pixel), so rim pixels can flip in orthographic views too (measured on an
            // H100: max 0.108, 99.9 % within 1.6e-4): there the perspective bound.
            let snaps_as_measured = h.gpu().caps().renderer.contains("llvmpipe");
            let bound = if fidelity == Fidelity::Precise {
                1e-4
            } else if projection == Projection::Orthographic && snaps_as_measured {
                2e-3
            } else {
                0.75
            };
            assert!(
                q(0.999) < 2e-3 && d.max_abs < bound,
                "{fidelity:?} {projection:?} [{text}]: {d:?}"
            );
        }
    }
}

#[test]
fn every_sort_method_draws_the_same_picture_and_order_matters() {
    let h = headless(Backend::Egl);
    let c = cloud(1500);
    let cam = camera(Projection::Perspective);
    let pictures: Vec<Image> = ["radix", "keys", "seed"]
        .iter()
        .map(|m| {
            draw(
                &h,
                &c,
                &params(&format!("sort = \"{m}\"\npoint_size = 8.0")),
                Fidelity::Precise,
                cam,
            )
        })
        .collect();
    for (i, p) in pictures.iter().enumerate().skip(1) {
        let d = p.compare(&pictures[0], 0.0).unwrap();
        // Same order, same fragments: bit-identical.
        assert_eq!(d.max_abs, 0.0, "method {i}: {d:?}");
    }
    let unsorted = draw(
        &h,
        &c,
        &params("sort = \"none\"\npoint_size = 8.0"),
        Fidelity::Precise,
        cam,
    );
    let d = unsorted.compare(&pictures[0], 0.0).unwrap();
    assert!(
        d.max_abs > 0.05,
        "file order is visibly wrong where splats overlap: {d:?}"
    );
}

#[test]
fn the_seed_footprints_as_written_differ_from_the_corrected_ones() {
    // The seed's smoothstep(0, 1, n_dist) is 0 at the centre: a lone splat is a ring.
    let h = headless(Backend::Egl);
    let mut one = cloud(1);
    one.positions = vec![[0.0, 0.0, 0.0]];
    let p = params("kernel = \"smoothstep\"\npoint_size = 21.0\ncolour = \"layer\"");
    let cam = Camera::default();
    for (fidelity, centre_alpha_is_high) in [(Fidelity::Faithful, false), (Fidelity::Precise, true)]
    {
        let img = draw(&h, &one, &p, fidelity, cam);
        let centre = img.pixel(SIZE[0] / 2, SIZE[1] / 2);
        let rim = img.pixel(SIZE[0] / 2 + 8, SIZE[1] / 2);
        let dist = |px: [f32; 4]| (0..3).map(|i| (px[i] - BACKGROUND[i]).abs()).sum::<f32>();
        assert_eq!(
            dist(centre) > dist(rim),
            centre_alpha_is_high,
            "{fidelity:?}: centre {centre:?} rim {rim:?}"
        );
    }
}

#[test]
fn hidden_layers_and_undefined_facies_are_not_drawn() {
    let h = headless(Backend::Egl);
    let c = cloud(3000);
    let cam = camera(Projection::Orthographic);
    let all = draw(&h, &c, &params("point_size = 4.0"), Fidelity::Precise, cam);
    let hidden_text = "point_size = 4.0\nhide_layers = [0, 1, 2, 3, 4, 5, 6, 7]";
    let none = draw(&h, &c, &params(hidden_text), Fidelity::Precise, cam);
    assert!(
        none.data.chunks_exact(4).all(|p| p[..3] == BACKGROUND[..3]),
        "every layer hidden"
    );
    let some = draw(
        &h,
        &c,
        &params("point_size = 4.0\nhide_layers = [7]\nhide_undefined = true"),
        Fidelity::Precise,
        cam,
    );
    let lit = |img: &Image| {
        img.data
            .chunks_exact(4)
            .filter(|p| p[..3] != BACKGROUND[..3])
            .count()
    };
    assert!(lit(&some) < lit(&all) && lit(&some) > 0);
    // The reference agrees on which points are left out.
    let p = params("point_size = 4.0\nhide_layers = [7]\nhide_undefined = true");
    let d = rgb_only(&some)
        .compare(&rgb_only(&reference(&c, &p, Fidelity::Precise, &cam)), 0.0)
        .unwrap();
    assert!(d.rmse < 2e-3, "{d:?}");
}

#[test]
fn extremes_stay_finite() {
    let h = headless(Backend::Egl);
    let cam = camera(Projection::Perspective);
    // No points, and one point.
    for n in [0usize, 1] {
        let mut c = cloud(1);
        c.positions.truncate(n);
        for a in &mut c.attributes {
            match &mut a.values {
                arbvis::points::Values::Int(v) => v.truncate(n),
                arbvis::points::Values::Float(v) => v.truncate(n),
            }
        }
        let img = draw(&h, &c, &params(""), Fidelity::Precise, cam);
        assert!(img.data.iter().all(|v| v.is_finite()), "{n} points");
    }
    // Coincident points: a stable order gives the same picture every time.
    let mut c = cloud(50);
    c.positions.iter_mut().for_each(|p| *p = [0.1, 0.0, 0.0]);
    let a = draw(&h, &c, &params("point_size = 12.0"), Fidelity::Precise, cam);
    let b = draw(&h, &c, &params("point_size = 12.0"), Fidelity::Precise, cam);
    assert_eq!(a.compare(&b, 0.0).unwrap().max_abs, 0.0);
    // The camera inside the cloud (points behind it are not drawn), a zero Gaussian
    // width, and a property of zero range (the seed's division gives NaN: alpha 0).
    let c = cloud(1500);
    let inside = Camera {
        projection: Projection::Perspective,
        zoom: 12.0,
        ..Camera::default()
    };
    for (text, fidelity) in [
        ("point_size = 30.0", Fidelity::Precise),
        ("gauss_width = 0.0", Fidelity::Precise),
        ("gauss_width = 0.0", Fidelity::Faithful),
    ] {
        let img = draw(&h, &c, &params(text), fidelity, inside);
        assert!(
            img.data.iter().all(|v| v.is_finite()),
            "{text} {fidelity:?}"
        );
    }
    let mut flat = cloud(400);
    for a in &mut flat.attributes {
        if a.name == "porosity" {
            if let arbvis::points::Values::Float(v) = &mut a.values {
                v.iter_mut().for_each(|x| *x = 0.004);
            }
        }
    }
    // Precise normalizes a zero range to 0: finite. The seed's `value / (max - min)` is
    // infinite there and its gradient's sin() NaN, as written: the faithful colours are
    // NaN in a float target, and 0 in a fixed-point one (as the reference clamps them).
    let p = params(
        "colour = \"property\"\nmode = \"volume\"\nvolume = { threshold = 0.004, range = 0.001 }",
    );
    let img = draw(&h, &flat, &p, Fidelity::Precise, cam);
    assert!(img.data.iter().all(|v| v.is_finite()));
    let faithful = draw(&h, &flat, &p, Fidelity::Faithful, cam);
    let expected = reference(&flat, &p, Fidelity::Faithful, &cam);
    let nan = |img: &Image| img.data.iter().filter(|v| v.is_nan()).count();
    assert!(nan(&faithful) > 0 && nan(&expected) == 0);
}

#[test]
fn the_demo_builds_what_it_draws() {
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("splats-section").unwrap();
    scene.size = [160, 90];
    if let TechniqueScene::Splats(s) = &mut scene.technique {
        s.cloud = arbvis::points::PointSource::Section(SectionSpec {
            points: 20_000,
            seed: 1,
        });
    }
    let r = render_on(&h, &scene).unwrap();
    let kinds: Vec<&str> = r.resources.iter().map(|r| r.kind).collect();
    // The index buffer of the order comes with the first frame.
    assert_eq!(
        kinds,
        ["program", "buffer", "framebuffer", "buffer"],
        "{:?}",
        r.resources
    );
    assert_eq!(
        r.resources[1].bytes,
        20_000 * 11 * 4,
        "11 floats per point: position, colour, value, normal, size scale"
    );
    let lit = r
        .image
        .data
        .chunks_exact(4)
        .filter(|p| p[..3] != [1.0, 1.0, 1.0])
        .count();
    assert!(lit > 160 * 90 / 10, "the section is drawn: {lit} pixels");
    let _ = (
        ColourMode::Facies,
        Kernel::Gaussian,
        Mode::Surface,
        SortChoice::Radix,
    );
}

/// Sorted quantiles of the absolute channel differences (alpha left out).
fn error_quantiles(a: &Image, b: &Image) -> (f32, impl Fn(f64) -> f32) {
    let mut errs: Vec<f32> = a
        .data
        .chunks_exact(4)
        .zip(b.data.chunks_exact(4))
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .collect();
    errs.sort_by(f32::total_cmp);
    let max = *errs.last().unwrap();
    (max, move |f: f64| {
        errs[((errs.len() - 1) as f64 * f) as usize]
    })
}

const CASES: [(Fidelity, &str); 8] = [
    (
        Fidelity::Precise,
        "kernel = \"gaussian\"\ngauss_width = 0.15\npoint_size = 7.0",
    ),
    (
        Fidelity::Precise,
        "kernel = \"smoothstep\"\ncolour = \"property\"\npoint_size = 6.0",
    ),
    (
        Fidelity::Faithful,
        "kernel = \"gaussian\"\ngauss_width = 0.3\npoint_size = 7.0\ncolour = \"property\"",
    ),
    (
        Fidelity::Faithful,
        "kernel = \"smoothstep\"\nfaults_white = true\npoint_size = 5.0",
    ),
    (Fidelity::Precise, "lighting = true\npoint_size = 6.0"),
    (Fidelity::Faithful, "lighting = true\npoint_size = 6.0"),
    (
        Fidelity::Precise,
        "mode = \"volume\"\ncolour = \"property\"\npoint_size = 9.0",
    ),
    (
        Fidelity::Faithful,
        "mode = \"volume\"\ncolour = \"property\"\npoint_size = 9.0\nvolume = { threshold = 0.01, range = 0.008 }",
    ),
];

#[test]
fn arb_programs_match_their_glsl_twins() {
    let h = headless(Backend::Egl);
    if !h.gpu().caps().has_arb() {
        eprintln!("SKIPPED: the driver has no ARB programs");
        return;
    }
    let c = cloud(1500);
    for (fidelity, text) in CASES {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let p = params(text);
            let cam = camera(projection);
            let arb = draw_with(&h, ProgramKind::Arb, &c, &p, fidelity, cam);
            let glsl = draw_with(&h, ProgramKind::Glsl, &c, &p, fidelity, cam);
            let (max, q) = error_quantiles(&arb, &glsl);
            eprintln!(
                "{fidelity:?} {projection:?} [{}]: max {max:.2e} p99 {:.2e} p999 {:.2e}",
                text.replace('\n', " "),
                q(0.99),
                q(0.999)
            );
            // Mesa compiles both kinds to the same IR: on llvmpipe they differ only by
            // the order of f32 operations (x * RCP(y) for x / y, RCP(RSQ(x)) for
            // sqrt, EX2(x log2 e) for exp, 0.2 z for z / 5), a few ulps: measured max
            // 2.4e-7, bound 1e-6 (8 ulps of 1.0). A hardware driver may implement the
            // ARB instructions with its own approximations, which can move a rim pixel
            // across n_dist = 1: there, 99.9 % of values within 2e-3 as the reference
            // test asks. The precise programs also place the splat themselves (1 / w,
            // the inverse square root of the eye distance), which the two compilations
            // round apart by about an ulp of the window position in perspective (7.6e-6
            // px at 96 px): alpha moves by up to f' x 2 ulp / size, measured 8.6e-6,
            // bound 3e-5.
            let software = arbvis::gl::renderer_is_software(&h.gpu().caps().renderer);
            let placed = fidelity == Fidelity::Precise && projection == Projection::Perspective;
            let ok = if software {
                max < if placed { 3e-5 } else { 1e-6 }
            } else {
                q(0.999) < 2e-3
            };
            assert!(ok, "{fidelity:?} {projection:?} [{text}]: max {max:e}");
        }
    }
}

#[test]
fn gpu_oit_matches_the_weighted_blended_reference() {
    let h = headless(Backend::Egl);
    let c = cloud(1500);
    let kinds: &[ProgramKind] = if h.gpu().caps().has_arb() {
        &[ProgramKind::Glsl, ProgramKind::Arb]
    } else {
        &[ProgramKind::Glsl]
    };
    for (fidelity, text) in CASES {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let text = format!("{text}\nsort = \"oit\"");
            let p = params(&text);
            let cam = camera_for(projection, fidelity);
            let expected = reference_of(&c, &p, fidelity, &cam, true);
            let exact = reference_of(&c, &p, fidelity, &cam, false);
            for &kind in kinds {
                let oit = draw_with(&h, kind, &c, &p, fidelity, cam);
                let (max, q) = error_quantiles(&oit, &expected);
                let vs_exact = rmse_rgb(&oit, &exact).unwrap();
                let vs_reference = rmse_rgb(&oit, &expected).unwrap();
                eprintln!(
                    "{kind:?} {fidelity:?} {projection:?} [{}]: vs reference max {max:.2e} p99 {:.2e} p999 {:.2e} rmse {vs_reference:.2e}; vs exact order rmse {vs_exact:.4}",
                    text.replace('\n', " "),
                    q(0.99),
                    q(0.999),
                );
                // Float targets, f32 against f64: 99.9 % of values within 1e-3 (measured
                // up to 8.4e-4, perspective; 1.5e-6 orthographic). A few pixels differ
                // more: llvmpipe snaps a sprite's centre to 1/256 pixel, so a pixel on
                // the sprite's edge can be in one and out of the other, and unlike the
                // sorted blend (where later splats cover it) OIT keeps every fragment's
                // share; the seed's footprints are heaviest on the rim (measured max
                // 0.26, RMSE up to 2.3e-3).
                // Another rasterizer snaps sprite centres its own way: faithful's rims
                // flip on more pixels (measured on an H100: 99.9 % within 5.1e-3).
                let snaps_as_measured = h.gpu().caps().renderer.contains("llvmpipe");
                let q_bound = if fidelity == Fidelity::Faithful && !snaps_as_measured {
                    1e-2
                } else {
                    1e-3
                };
                assert!(
                    q(0.999) < q_bound && vs_reference < 5e-3 && max < 0.5,
                    "{kind:?} {fidelity:?} {projection:?} [{text}]: max {max:e}, rmse {vs_reference:e}"
                );
                // OIT is an approximation: against exact order it errs far more than
                // against its own reference (measured 6e-3 to 8e-2 where splats of
                // different colours overlap, 6 to 3000 times its error against the
                // reference; 4e-4 for the sparse precise volume).
                // (Faithful's rim flips on another rasterizer add to its error against
                // the reference, not to OIT's approximation: not compared there.)
                if fidelity == Fidelity::Precise || snaps_as_measured {
                    assert!(vs_exact > 4.0 * vs_reference, "{text}: {vs_exact}");
                }
                if p.mode == Mode::Surface {
                    assert!(vs_exact > 5e-3, "{text}: {vs_exact}");
                }
            }
        }
    }
}

#[test]
fn the_scene_picks_the_program_kind_and_oit_builds_its_targets() {
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("splats-section").unwrap();
    scene.size = [160, 90];
    if let TechniqueScene::Splats(s) = &mut scene.technique {
        s.cloud = arbvis::points::PointSource::Section(SectionSpec {
            points: 5_000,
            seed: 3,
        });
        s.sort = SortChoice::Oit;
    }
    let mut choices = vec![(ProgramChoice::Glsl, ProgramKind::Glsl)];
    if h.gpu().caps().has_arb() {
        choices.push((ProgramChoice::Arb, ProgramKind::Arb));
        choices.push((ProgramChoice::Auto, ProgramKind::Arb));
    }
    for (choice, kind) in choices {
        scene.programs = choice;
        // A fresh context each time: its resource list starts empty.
        let r = render_on(&headless(Backend::Egl), &scene).unwrap();
        assert_eq!(r.program_kind, kind);
        let kinds: Vec<&str> = r.resources.iter().map(|r| r.kind).collect();
        // Splat program, points, the file-order index buffer, the surface; at the first
        // frame the composite program, its quad and the two OIT targets.
        assert_eq!(
            kinds,
            [
                "program",
                "buffer",
                "buffer",
                "framebuffer",
                "program",
                "buffer",
                "framebuffer",
                "framebuffer"
            ],
            "{choice:?}"
        );
        assert_eq!(r.resources[6].bytes, 160 * 90 * 16, "RGBA32F accumulation");
        let lit = r
            .image
            .data
            .chunks_exact(4)
            .filter(|p| p[..3] != [1.0, 1.0, 1.0])
            .count();
        assert!(
            lit > 160 * 90 / 10,
            "{choice:?}: the section is drawn: {lit}"
        );
    }
}

#[test]
fn arb_keeps_the_seeds_nan_where_glsl_does() {
    // A property of zero range: the seed's division is infinite, its sin() NaN.
    let h = headless(Backend::Egl);
    if !h.gpu().caps().has_arb() {
        eprintln!("SKIPPED: the driver has no ARB programs");
        return;
    }
    let mut flat = cloud(400);
    for a in &mut flat.attributes {
        if a.name == "porosity" {
            if let arbvis::points::Values::Float(v) = &mut a.values {
                v.iter_mut().for_each(|x| *x = 0.004);
            }
        }
    }
    let cam = camera(Projection::Perspective);
    for text in [
        "colour = \"property\"\nmode = \"volume\"\nvolume = { threshold = 0.004, range = 0.001 }",
        "gauss_width = 0.0",
    ] {
        let p = params(text);
        for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
            let arb = draw_with(&h, ProgramKind::Arb, &flat, &p, fidelity, cam);
            let glsl = draw_with(&h, ProgramKind::Glsl, &flat, &p, fidelity, cam);
            let nan = |img: &Image| img.data.iter().filter(|v| v.is_nan()).count();
            assert_eq!(nan(&arb), nan(&glsl), "{fidelity:?} [{text}]");
            let same = arb
                .data
                .iter()
                .zip(&glsl.data)
                .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()) || (a - b).abs() < 1e-6);
            assert!(same, "{fidelity:?} [{text}]");
            let inf = arb.data.iter().filter(|v| v.is_infinite()).count();
            eprintln!(
                "{fidelity:?} [{}]: {} NaN, {inf} infinite values",
                text.replace('\n', " "),
                nan(&arb)
            );
        }
    }
}

/// Pixels a renderer's f32 placement may be off the f64 reference's: the GPU's window
/// positions go through f32 matrices and a division (a few ulps of values up to 131 px:
/// ulp(128) = 7.6e-6), its sizes through f32 `pointSize / distance`; 1e-3 px is over 100
/// times that. Pixel centres this close to a rim may take or lose the rim fragment.
const RIM_DELTA: f64 = 1e-3;

/// The largest difference (colour channels) of `gpu` from `exact` at pixels no rim passes
/// within [`RIM_DELTA`] of, the largest by which any pixel exceeds its rim allowance
/// (`rim_allowance`), and the number of pixels a rim passes that close to.
fn beside_rims(gpu: &Image, exact: &Image, allowance: &[f64]) -> (f32, f64, usize) {
    let (mut clear, mut excess, mut near) = (0.0f32, f64::NEG_INFINITY, 0);
    for ((g, r), &a) in gpu
        .data
        .chunks_exact(4)
        .zip(exact.data.chunks_exact(4))
        .zip(allowance)
    {
        let d = (0..3).map(|k| (g[k] - r[k]).abs()).fold(0.0f32, f32::max);
        if a == 0.0 {
            clear = clear.max(d);
        } else {
            near += 1;
        }
        excess = excess.max(d as f64 - a);
    }
    (clear, excess, near)
}

#[test]
fn precise_points_match_the_reference_but_for_rim_flips() {
    use arbvis::techniques::splats::reference::{composite, rim_allowance};
    let h = headless(Backend::Egl);
    let c = cloud(1500);
    let kernels = [
        "kernel = \"gaussian\"\ngauss_width = 0.2",
        "kernel = \"gaussian\"\ngauss_width = 0.35",
        "kernel = \"gaussian\"\ngauss_width = 0.6",
        "kernel = \"gaussian\"\ngauss_width = 1.0",
        "kernel = \"smoothstep\"",
    ];
    // Orthographic: the sizes in pixels; perspective: divided by the eye distance (about
    // 3 to 5 here), so 1 (clamped) to 4 pixels.
    let point_sizes = [3.0, 5.5, 8.0, 12.5];
    // Odd sizes, neither a multiple of the other: pixel centres meet rims anywhere.
    let sizes = [[97, 61], [131, 89]];
    let (mut worst_clear, mut rim_pixels) = (0.0f32, 0);
    for (k, kernel) in kernels.iter().enumerate() {
        for (n, point_size) in point_sizes.iter().enumerate() {
            let size = sizes[(k + n) % 2];
            for projection in [Projection::Orthographic, Projection::Perspective] {
                let text = format!("{kernel}\npoint_size = {point_size}\ncolour = \"layer\"");
                let p = params(&text);
                let cam = camera(projection);
                let kind = ProgramKind::Glsl;
                let gpu = draw_sized(&h, kind, &c, &p, Fidelity::Precise, cam, size);
                let (positions, rgba) = reference_points(&c, &p, Fidelity::Precise, &cam);
                let scene = reference_scene(&positions, &rgba, &p, Fidelity::Precise);
                let exact = composite(&scene, &cam, size);
                let allowance = rim_allowance(&scene, &cam, size, RIM_DELTA);
                let (clear, excess, near) = beside_rims(&gpu, &exact, &allowance);
                let drawn = exact
                    .data
                    .chunks_exact(4)
                    .filter(|px| px[..3] != BACKGROUND[..3])
                    .count();
                eprintln!(
                    "{projection:?} {size:?} [{}]: {drawn} pixels drawn, max {clear:.2e} \
                     away from rims; {near} pixels within {RIM_DELTA} px of a rim, \
                     worst excess over their allowance {excess:.2e}",
                    text.replace('\n', " ")
                );
                assert!(drawn > 300, "[{text}] {projection:?}: {drawn} pixels drawn");
                // Away from rims only f32 rounding is left: positions and sizes (n_dist
                // moves by ~1e-6, alpha by at most 5e-6 with the steepest footprint
                // here), colours and the blend in f32 over about 10 layers.
                // Measured at most 2.2e-5 (perspective), 5.7e-6 (orthographic).
                assert!(clear < 1e-4, "[{text}] {projection:?} {size:?}: {clear:e}");
                // Near rims: within the allowance (the rim fragments' alphas) plus the
                // same rounding.
                assert!(
                    excess < 1e-4,
                    "[{text}] {projection:?} {size:?}: {excess:e}"
                );
                worst_clear = worst_clear.max(clear);
                rim_pixels += near;
            }
        }
    }
    eprintln!("worst away from rims {worst_clear:.2e}; {rim_pixels} pixels near rims in all");
}
