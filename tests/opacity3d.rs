//! v3o2's 3D opacity end to end: ARB vs GLSL, faithful vs an independent CPU emulation of
//! the 8-bit pipeline, precise vs the f64 reference integral, Figure 15's union and
//! intersection, the extremes of DESIGN §4, and what gets built.

mod common;

use std::path::{Path, PathBuf};

use arbvis::gl::{Backend, Filter, Headless, ProgramChoice, ProgramKind, TargetFormat};
use arbvis::image::Image;
use arbvis::render::{render_on, Rendered};
use arbvis::scene::{Fidelity, Scene, TechniqueScene};
use arbvis::techniques::opacity3d::prepare::prepare;
use arbvis::techniques::opacity3d::reference::{emulate_faithful, reference};
use arbvis::techniques::opacity3d::Opacity3dScene;
use common::{headless, temp_dir, LEVEL};

/// Write `n³` u8 samples from `f(i, j, k)` as a raw file.
fn write_raw(dir: &Path, file: &str, n: usize, f: impl Fn(usize, usize, usize) -> u8) {
    let mut bytes = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                bytes.push(f(i, j, k));
            }
        }
    }
    std::fs::write(dir.join(file), bytes).unwrap();
}

/// A scene over raw u8 files `a.raw`, `b.raw`, `c.raw` (those named) of `n³` voxels,
/// quantized over the fixed range 0..255 so quantized value = sample.
fn raw_scene(
    dir: &Path,
    n: usize,
    files: &[(&str, &str, [f64; 4])],
    combine: &str,
    slices: usize,
) -> Scene {
    let mut text = format!(
        "size = [64, 64]\nbackground = [0.0, 0.0, 0.0, 1.0]\n[technique.opacity3d]\ncombine = \"{combine}\"\nslices = {slices}\n"
    );
    for (role, (file, table, coefficients)) in
        ["primary", "secondary", "tertiary"].iter().zip(files)
    {
        text += &format!(
            "[technique.opacity3d.{role}]\nvolume = {{ raw = {{ path = \"{file}\", dims = [{n}, {n}, {n}], type = \"u8\" }} }}\nquantize = {{ range = [0.0, 255.0] }}\ntable = {table}\ncoefficients = {coefficients:?}\n"
        );
    }
    let mut scene = Scene::parse(&text, "test").unwrap();
    scene.base = dir.to_path_buf();
    scene
}

fn params(scene: &Scene) -> &Opacity3dScene {
    match &scene.technique {
        TechniqueScene::Opacity3d(p) => p,
        _ => panic!("not an opacity3d scene"),
    }
}

fn params_mut(scene: &mut Scene) -> &mut Opacity3dScene {
    match &mut scene.technique {
        TechniqueScene::Opacity3d(p) => p,
        _ => panic!("not an opacity3d scene"),
    }
}

fn render(h: &Headless, scene: &Scene) -> Rendered {
    render_on(h, scene).unwrap_or_else(|e| panic!("render failed: {e}"))
}

/// The image with alpha zeroed: SRC_ALPHA blending makes target alpha a by-product, not
/// a quantity the references define the same way (module doc of `reference`).
fn rgb(image: &Image) -> Image {
    let mut out = image.clone();
    out.data.chunks_exact_mut(4).for_each(|p| p[3] = 0.0);
    out
}

fn background(scene: &Scene) -> [f64; 4] {
    scene.background.map(|v| v as f64)
}

/// Three overlapping gradient volumes: primary ramps along i, secondary along j,
/// tertiary is a ball.
fn gradient_fixture(name: &str, n: usize) -> PathBuf {
    let dir = temp_dir(name);
    let scale = 255.0 / (n - 1) as f64;
    write_raw(&dir, "a.raw", n, |i, _, _| (i as f64 * scale).round() as u8);
    write_raw(&dir, "b.raw", n, |_, j, _| (j as f64 * scale).round() as u8);
    let c = (n - 1) as f64 / 2.0;
    write_raw(&dir, "c.raw", n, |i, j, k| {
        let r = ((i as f64 - c).powi(2) + (j as f64 - c).powi(2) + (k as f64 - c).powi(2)).sqrt();
        (255.0 * (1.0 - r / c).clamp(0.0, 1.0)).round() as u8
    });
    dir
}

const THREE: [(&str, &str, [f64; 4]); 3] = [
    ("a.raw", "{ builtin = \"viridis\" }", [1.0, 1.0, 1.0, 0.5]),
    ("b.raw", "{ builtin = \"seismic\" }", [1.0, 0.5, 1.0, 0.5]),
    ("c.raw", "{ builtin = \"red\" }", [1.0, 1.0, 1.0, 1.0]),
];

#[test]
fn arb_and_glsl_agree_within_one_level_in_both_modes() {
    let h = headless(Backend::Egl);
    for demo in ["v3o2-sum", "v3o2-product"] {
        for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
            let mut scene = Scene::demo(demo).unwrap();
            scene.size = [128, 128];
            scene.fidelity = fidelity;
            scene.target = Some(TargetFormat::Rgba8);
            scene.programs = ProgramChoice::Arb;
            let arb = render(&h, &scene);
            scene.programs = ProgramChoice::Glsl;
            let glsl = render(&h, &scene);
            assert_eq!(arb.program_kind, ProgramKind::Arb);
            assert_eq!(glsl.program_kind, ProgramKind::Glsl);
            // Same instructions in both languages, both rounded to an 8-bit target each
            // slice: one level. (A single rounding flip early in the stack decays under
            // later slices, it does not grow.)
            let d = arb.image.compare(&glsl.image, LEVEL).unwrap();
            assert!(
                d.max_abs <= LEVEL as f64 * 1.01,
                "{demo} {fidelity:?}: {d:?}"
            );
        }
    }
}

#[test]
fn faithful_equals_the_cpu_emulation_of_the_8_bit_pipeline() {
    let h = headless(Backend::Egl);
    let dir = gradient_fixture("emulation", 12);
    for volume_filter in [Filter::Nearest, Filter::Linear] {
        for table_filter in [Filter::Nearest, Filter::Linear] {
            for combine in ["sum", "product"] {
                for slices in [1, 16, 64] {
                    let mut scene = raw_scene(&dir, 12, &THREE, combine, slices);
                    params_mut(&mut scene).table_filter = table_filter;
                    params_mut(&mut scene).volume_filter = volume_filter;
                    let gpu = render(&h, &scene);
                    let p = params(&scene);
                    let prepared = prepare(p, &dir).unwrap();
                    let cpu = emulate_faithful(
                        &prepared,
                        p,
                        &scene.camera,
                        scene.size,
                        background(&scene),
                    );
                    let what = format!("{volume_filter:?} volume, {table_filter:?} tables, {combine}, {slices} slices");
                    let d = gpu.image.compare(&cpu, LEVEL * 1.01).unwrap();
                    if volume_filter == Filter::Nearest {
                        // No filtering arithmetic to model: every fetch is an exact 8-bit
                        // value, so the only freedom left is float rounding of 0.3333 x
                        // coefficient at a .5 boundary: one level.
                        assert!(d.max_abs <= LEVEL as f64 * 1.01, "{what}: {d:?}");
                    } else {
                        // Trilinear filtering rounds to 8 bits after each lerp; the order of
                        // llvmpipe's lerps is not modelled exactly, so a fetch can land one
                        // level off, and the 8-bit blend carries it: 2 levels, on under 1%
                        // of the pixels more than one.
                        assert!(d.max_abs <= 2.0 * LEVEL as f64 * 1.01, "{what}: {d:?}");
                        assert!(d.pixels_over * 100 <= 64 * 64, "{what}: {d:?}");
                    }
                }
            }
        }
    }
}

#[test]
fn precise_agrees_with_the_reference_integral() {
    let h = headless(Backend::Egl);
    let dir = gradient_fixture("precise", 12);
    for combine in ["sum", "product"] {
        for slices in [64, 256, 1024] {
            let mut scene = raw_scene(&dir, 12, &THREE, combine, slices);
            scene.fidelity = Fidelity::Precise;
            let gpu = render(&h, &scene);
            let p = params(&scene);
            let prepared = prepare(p, &dir).unwrap();
            let cpu = reference(
                &prepared,
                p,
                &scene.camera,
                scene.size,
                background(&scene),
                16.0,
            );
            let d = rgb(&gpu.image).compare(&rgb(&cpu), 0.0).unwrap();
            // Measured 4.5e-4 (sum) and 1.1e-4 (product) at every slice count: the
            // volume is stored as RGB16F, so k/255 carries half-float rounding (2^-12
            // relative) into the table lookup; slicing error is already below it on a 12³
            // grid from 64 slices on. 1e-3 is a quarter of an 8-bit level.
            assert!(d.max_abs < 1e-3, "{combine}, {slices} slices: {d:?}");
        }
    }
}
