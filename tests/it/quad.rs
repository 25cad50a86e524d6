//! The quad demo end to end: ARB and GLSL twins agree, GPU agrees with the CPU reference
//! on every target precision, EGL and OSMesa give the same pixels, and the image matches
//! its golden file.

use crate::common;

use arbvis::gl::{Backend, ProgramChoice, ProgramKind, TargetFormat};
use arbvis::render::render_on;
use arbvis::scene::Scene;
use arbvis::techniques::quad::{reference_image, QuadScene};
use common::{headless, LEVEL};

fn quad_scene(programs: ProgramChoice, target: TargetFormat, size: u32) -> Scene {
    let mut scene = Scene::demo("quad").unwrap();
    scene.programs = programs;
    scene.target = Some(target);
    scene.size = [size, size];
    scene
}

fn params(scene: &Scene) -> QuadScene {
    let arbvis::scene::TechniqueScene::Quad(p) = &scene.technique else {
        panic!("the quad demo is a quad scene")
    };
    (**p).clone()
}

#[test]
fn arb_and_glsl_agree_within_one_level() {
    let h = headless(Backend::Egl);
    let arb = render_on(
        &h,
        &quad_scene(ProgramChoice::Arb, TargetFormat::Rgba8, 128),
    )
    .unwrap();
    let glsl = render_on(
        &h,
        &quad_scene(ProgramChoice::Glsl, TargetFormat::Rgba8, 128),
    )
    .unwrap();
    assert_eq!(arb.program_kind, ProgramKind::Arb);
    assert_eq!(glsl.program_kind, ProgramKind::Glsl);
    // Both compute the same f32 expression; each stores round(255 v), so they may differ
    // by one 8-bit level where v sits on a rounding boundary, never more.
    let d = arb.image.compare(&glsl.image, LEVEL).unwrap();
    assert!(d.max_abs <= LEVEL as f64 + 1e-6, "ARB vs GLSL: {d:?}");
}

#[test]
fn gpu_matches_cpu_reference_on_every_target() {
    let h = headless(Backend::Egl);
    // Tolerances: RGBA8 stores round(255 v): half a level of quantization, plus f32
    // attribute interpolation (~1e-6), within one level. RGBA16F has a 10-bit mantissa:
    // for v <= 1 the step is at most 2^-11 and rounding errs by half that, ~5e-4, so
    // 1/1024 bounds it. RGBA32F: only interpolation and arithmetic in f32, relative
    // ~1e-6 on values <= 1; 1e-5 leaves margin for the rasterizer's barycentrics.
    for (target, tolerance) in [
        (TargetFormat::Rgba8, LEVEL),
        (TargetFormat::Rgba16f, 1.0 / 1024.0),
        (TargetFormat::Rgba32f, 1e-5),
    ] {
        for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
            let scene = quad_scene(programs, target, 64);
            let got = render_on(&h, &scene).unwrap().image;
            let want = reference_image(&params(&scene), 64, 64, target);
            let d = got.compare(&want, tolerance).unwrap();
            assert!(
                d.max_abs <= tolerance as f64,
                "{target:?} {programs:?}: {d:?} (tolerance {tolerance})"
            );
        }
    }
}

#[test]
fn float_target_keeps_values_above_one() {
    // RGBA8 clamps to 1; a float target does not (precise mode relies on it).
    let h = headless(Backend::Egl);
    let mut scene = quad_scene(ProgramChoice::Auto, TargetFormat::Rgba32f, 16);
    scene.technique = QuadScene {
        left: [2.0, 2.0, 2.0, 2.0],
        right: [2.0, 2.0, 2.0, 2.0],
    }
    .into();
    let img = render_on(&h, &scene).unwrap().image;
    assert!(img.pixel(8, 0)[3] > 1.99, "{:?}", img.pixel(8, 0));
    scene.target = Some(TargetFormat::Rgba8);
    let img = render_on(&h, &scene).unwrap().image;
    assert_eq!(img.pixel(8, 0)[3], 1.0);
}

#[test]
fn egl_and_osmesa_give_identical_pixels() {
    // Both are llvmpipe here (DESIGN.md §8): identical, bit for bit. On a machine where EGL
    // is a real GPU the two differ by design; then the bound is the CPU reference's.
    let egl = headless(Backend::Egl);
    let osmesa = headless(Backend::Osmesa);
    for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
        let scene = quad_scene(programs, TargetFormat::Rgba8, 128);
        let a = render_on(&egl, &scene).unwrap();
        let b = render_on(&osmesa, &scene).unwrap();
        let d = a.image.compare(&b.image, 0.0).unwrap();
        if a.caps.renderer == b.caps.renderer {
            assert_eq!(d.max_abs, 0.0, "{programs:?}: {d:?}");
        } else {
            assert!(d.max_abs <= 2.0 * LEVEL as f64, "{programs:?}: {d:?}");
        }
    }
}

#[test]
fn golden_quad() {
    let h = headless(Backend::Egl);
    let img = render_on(
        &h,
        &quad_scene(ProgramChoice::Arb, TargetFormat::Rgba8, 128),
    )
    .unwrap()
    .image;
    // Golden made on llvmpipe (Mesa 22.3.6); one level covers other drivers' rounding.
    common::assert_snapshot("quad/quad_arb_128", &img, LEVEL);
}

#[test]
fn stats_list_only_what_the_scene_names() {
    let h = headless(Backend::Egl);
    let r = render_on(
        &h,
        &quad_scene(ProgramChoice::Arb, TargetFormat::Rgba16f, 32),
    )
    .unwrap();
    let kinds: Vec<&str> = r.resources.iter().map(|r| r.kind).collect();
    assert_eq!(
        kinds,
        ["program", "buffer", "framebuffer"],
        "{:?}",
        r.resources
    );
    assert_eq!(r.resources[2].bytes, 32 * 32 * 8, "RGBA16F target bytes");
    assert_eq!(
        r.resources[1].bytes,
        6 * 8 * 4,
        "six vertices of eight floats"
    );
}
