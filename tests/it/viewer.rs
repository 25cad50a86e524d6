//! The desktop viewer under Xvfb: screenshots equal to offscreen renders of the saved
//! scene, framing at two window aspects, an idle viewer that draws nothing, every control
//! of the lut 3D editor reached by `--script` (clicks, drags and values injected through
//! egui's input path), the isovalue, splat and clip editors reaching the saved scene (the
//! clip's cost line read with `print`), and script steps that do nothing failing with
//! their line. (The screen sizes, screenshots' names and overlays, and legends are
//! in `viewer_screen.rs`; the harness that runs the viewer is `common/viewer.rs`.)
//!
//! Needs an X server: `DISPLAY`, or `Xvfb` on PATH (started here). Without either the
//! tests say so and pass, unless `ARBVIS_NO_SKIP=1` (set by `.ci/run`) makes that a failure.
#![cfg(feature = "viewer")]

use crate::common;

use std::path::Path;

use common::viewer::{failing_scripts, run_script};
use common::{opacity3d, temp_dir};

use arbvis::colortable::ColorTable;
use arbvis::gl::{Backend, Surface, Target, TargetFormat};
use arbvis::image::Image;
use arbvis::png_io::read_png;
use arbvis::render::render;
use arbvis::scene::{Scene, TechniqueScene};
use arbvis::techniques::cellproj::transfer::{Precise, Sort};
use arbvis::techniques::cellproj::Mode;
use arbvis::techniques::clip::stats::ClipStats;
use arbvis::techniques::clip::{ClipSpec, ShapeSpec};
use arbvis::techniques::opacity3d::Combine;
use arbvis::techniques::quad::{reference_image, QuadScene};

/// The scene the viewer saved in `dir` (`Save scene`).
fn saved_scene(dir: &Path) -> Scene {
    Scene::load(&dir.join("arbvis-scene.toml")).unwrap()
}

/// The viewer's first screenshot in `dir` is `saved` drawn offscreen.
fn assert_first_screenshot_is(dir: &Path, saved: &Scene) {
    let (shot, _) = read_png(&dir.join("arbvis-screenshot-001.png")).unwrap();
    assert_screenshot_is_the_scene(&shot, saved);
}

/// Layer `index` of `saved`, as technique `T`'s parameters.
fn saved_layer<T: arbvis::techniques::Technique + Clone>(saved: &Scene, index: usize) -> T {
    let (_, technique) = saved.layers().nth(index).expect("the layer");
    technique.get::<T>().expect("the layer's technique").clone()
}

/// The scene `text`, written into `dir` as `NAME.toml`, opened in the viewer (a 900 x 640
/// window, a 200 x 150 picture), `steps` run, a screenshot taken and the scene saved: the
/// saved scene, once the screenshot is checked to be it drawn offscreen. None without a
/// display.
fn saved_after(name: &str, dir: &Path, text: &str, steps: &str) -> Option<Scene> {
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let script =
        format!("resize 900 640\nwait 2\n{steps}wait 2\nclick Screenshot\nclick Save scene\n");
    let (out, _) = run_script(name, scene.to_str().unwrap(), "200x150", &script)?;
    let saved = saved_scene(&out);
    assert_first_screenshot_is(&out, &saved);
    let _ = std::fs::remove_dir_all(&out);
    Some(saved)
}

/// The screenshot equals an offscreen render of the saved scene at its size, within one
/// 8-bit level (same driver, same program).
fn assert_screenshot_is_the_scene(shot: &Image, saved: &Scene) {
    assert_eq!(
        saved.size,
        [shot.width, shot.height],
        "the saved scene's size is the screenshot's"
    );
    let offscreen = saved.picture(&render(saved, Backend::Egl).unwrap().image);
    let d = shot.compare(&offscreen, common::LEVEL).unwrap();
    assert!(d.max_abs <= common::LEVEL as f64 * 1.01, "{d:?}");
}

#[test]
fn frame_screenshot_and_program_switch() {
    let Some((dir, _)) = run_script(
        "switch",
        "quad",
        "160x160",
        "resize 410 480\nwait 2\nclick Screenshot\nwait 1\nclick GLSL\nwait 2\nclick Screenshot\nwait 1\nclick Save scene\nwait 1\n",
    ) else {
        return;
    };

    let (arb, arb_text) = read_png(&dir.join("arbvis-screenshot-001.png")).unwrap();
    let (glsl, glsl_text) = read_png(&dir.join("arbvis-screenshot-002.png")).unwrap();
    let programs = |t: &[(String, String)]| {
        t.iter()
            .find(|(k, _)| k == "arbvis:programs")
            .map(|(_, v)| v.clone())
    };
    // The click on "GLSL" took effect: the second screenshot was drawn by the GLSL twin.
    assert_eq!(programs(&arb_text).as_deref(), Some("arb"));
    assert_eq!(programs(&glsl_text).as_deref(), Some("glsl"));

    // The view is the window (410 wide) minus the 250-point side panel; the quad fills it
    // (it has no box or legends). Both screenshots match the CPU reference at the
    // view's size within one 8-bit level.
    assert_eq!(arb.width, 160, "view width = window width - panel");
    let want = reference_image(
        &QuadScene::default(),
        arb.width,
        arb.height,
        TargetFormat::Rgba8,
    );
    for (name, img) in [("arb", &arb), ("glsl", &glsl)] {
        let d = img.compare(&want, common::LEVEL).unwrap();
        assert!(
            d.max_abs <= common::LEVEL as f64 + 1e-6,
            "{name} screenshot vs reference: {d:?}"
        );
    }

    // "Save scene" wrote a scene that parses, records the switch and has the view's size.
    let saved = saved_scene(&dir);
    assert_eq!(saved.programs, arbvis::gl::ProgramChoice::Glsl);
    assert_eq!(saved.size, [glsl.width, glsl.height]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn drag_rotates_the_camera() {
    let Some((dir, _)) = run_script(
        "drag",
        "quad",
        "160x160",
        "wait 2\ndrag 60 0\nwait 1\nclick Save scene\nwait 1\n",
    ) else {
        return;
    };
    let saved = saved_scene(&dir);
    // A horizontal drag rotates about the vertical axis only.
    let q = saved.camera.quat();
    let (axis, angle) = q.to_axis_angle();
    assert!(angle > 0.1, "rotation angle {angle}");
    assert!((axis - glam::DVec3::Y).length() < 1e-6, "axis {axis}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_idle_viewer_draws_nothing() {
    // After a drag the volume is refined (the full-quality picture, in parts if slow);
    // then, with no input, the event loop waits and draws nothing.
    let Some((dir, stdout)) = run_script(
        "idle",
        "v3o2-sum",
        "160x160",
        "resize 880 460\nwait 3\ndrag 30 0\nidle 1500\nidle 1000\n",
    ) else {
        return;
    };
    let counts: Vec<u64> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("idle: "))
        .map(|l| l.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(counts.len(), 2, "{stdout}");
    assert!(counts[0] >= 1, "no refinement after the drag: {stdout}");
    assert!(counts[1] <= 2, "an idle second drew frames: {stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The border rows and columns of `img` are all `background`; some pixel inside is not.
fn assert_framed(img: &Image, background: [u8; 4], what: &str) {
    let (w, h) = (img.width, img.height);
    for x in 0..w {
        for y in [0, h - 1] {
            assert_eq!(
                img.pixel_u8(x, y),
                background,
                "{what}: ({x}, {y}) on the border"
            );
        }
    }
    for y in 0..h {
        for x in [0, w - 1] {
            assert_eq!(
                img.pixel_u8(x, y),
                background,
                "{what}: ({x}, {y}) on the border"
            );
        }
    }
    let shown = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| img.pixel_u8(x, y) != background)
        .count();
    assert!(
        shown > (w * h / 20) as usize,
        "{what}: only {shown} pixels show the volume"
    );
}

#[test]
fn the_volume_stays_framed_at_two_window_aspects() {
    // A tall view and a wide one, each turned by a drag; then Home resets the camera.
    let Some((dir, _)) = run_script(
        "framing",
        "v3o2-sum",
        "160x160",
        "resize 880 640\nset Box and labels false\nwait 2\ndrag 50 30\nclick Screenshot\n\
         resize 1200 460\nwait 2\ndrag -40 60\nclick Screenshot\nclick Save scene\n\
         key Home\nclick Save scene\n",
    ) else {
        return;
    };
    let (tall, _) = read_png(&dir.join("arbvis-screenshot-001.png")).unwrap();
    let (wide, _) = read_png(&dir.join("arbvis-screenshot-002.png")).unwrap();
    assert!(tall.height > tall.width, "{}x{}", tall.width, tall.height);
    assert!(wide.width > wide.height, "{}x{}", wide.width, wide.height);
    let black = [0, 0, 0, 255];
    assert_framed(&tall, black, "tall view");
    assert_framed(&wide, black, "wide view");
    // Home reset the rotation and framed the volume: a unit cube's bounding sphere fits.
    let home = saved_scene(&dir);
    assert_eq!(home.camera.rotation, [0.0, 0.0, 0.0, 1.0]);
    let fit = arbvis::viewer::fit_zoom(&home.camera, glam::DVec3::ONE);
    assert!(
        (home.camera.zoom - fit).abs() < 1e-12,
        "{}",
        home.camera.zoom
    );
    assert!((fit - 0.9 / 3f64.sqrt()).abs() < 1e-12, "{fit}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_lut3d_control_reaches_the_saved_scene() {
    // The demo: primary seismic [1, 1, 1, 0.8] with alpha [[0, .6], [.35, 0], [.65, 0],
    // [1, .6]]; secondary magma [1; 4] with alpha [[0, 0], [.6, 0], [1, .8]]; tertiary grey
    // [.5; 4] with alpha [[0, 0], [1, .1]]; sum, 128 slices.
    let script = "\
resize 880 560
wait 2
set primary Cr 0.25
set primary Cg 0.5
set primary Cb 0.75
set primary Ca 0.125
set secondary Cr 0.1
set secondary Cg 0.2
set secondary Cb 0.3
set secondary Ca 0.4
click Lock tertiary
set tertiary Cb 0.625
set secondary table viridis
click Product
set slices 48
click-at primary alpha 0.5 0.25
drag-on primary alpha 0.65 1 20 -30
right-click-at primary alpha 0 0.4
double-click-at secondary alpha 0.6 1
set Interactive quality quarter
set Section attribute secondary
set inline section 10
click Sections
click Sections
measure 2 interactive
set Box and labels false
click Screenshot
click Save scene
";
    let Some((dir, stdout)) = run_script("lut3d", "v3o2-sum", "160x160", script) else {
        return;
    };
    let saved = saved_scene(&dir);
    let o = opacity3d(&saved);
    assert_eq!(o.combine, Combine::Product);
    assert_eq!(o.slices, 48);
    assert_eq!(o.primary.coefficients, [0.25, 0.5, 0.75, 0.125]);
    let secondary = o.secondary.as_ref().unwrap();
    assert_eq!(secondary.coefficients, [0.1, 0.2, 0.3, 0.4]);
    assert_eq!(secondary.table.builtin, "viridis");
    // The lock took Cr (0.5) for all four, then one edit set all four.
    assert_eq!(o.tertiary.as_ref().unwrap().coefficients, [0.625; 4]);
    // Primary: a point added at (0.5, 0.75); the point at (0.65, 0) dragged right and up
    // (20 and 30 points on a plot about 410 x 82 points); (0, 0.6) removed.
    let alpha = &o.primary.table.alpha;
    assert_eq!(alpha.len(), 4, "{alpha:?}");
    assert_eq!(alpha[0], [0.35, 0.0]);
    assert_eq!(alpha[1], [0.5, 0.75]);
    assert!(alpha[2][0] > 0.65 && alpha[2][0] < 0.75, "{alpha:?}");
    assert!(alpha[2][1] > 0.2 && alpha[2][1] < 0.5, "{alpha:?}");
    assert_eq!(alpha[3], [1.0, 0.6]);
    // Secondary: the double click removed (0.6, 0).
    assert_eq!(secondary.table.alpha, vec![[0.0, 0.0], [1.0, 0.8]]);
    // The interactive quality is a viewer setting (not in the scene): `measure` shows it.
    assert!(stdout.contains("interactive quality quarter"), "{stdout}");
    assert_first_screenshot_is(&dir, &saved);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_isovalue_editor_reaches_the_saved_scene() {
    let script = "\
resize 900 600
wait 2
set Isovalue 1 0.35
click Remove isovalue 3
click Add isovalue
click Precise
click Shading
set Box and labels false
click Screenshot
click Save scene
";
    let Some((dir, _)) = run_script("isovalues", "cellproj-spherical", "160x120", script) else {
        return;
    };
    let saved = saved_scene(&dir);
    let TechniqueScene::Cellproj(c) = &saved.technique else {
        panic!("saved scene is not cellproj");
    };
    let values: Vec<f64> = c.isovalues.iter().map(|i| i.value).collect();
    // 0.3 set to 0.35, 0.9 removed, one added after 0.5 (at 0.6).
    assert_eq!(values.len(), 3, "{values:?}");
    assert_eq!(values[0], 0.35);
    assert_eq!(values[1], 0.5);
    assert!((values[2] - 0.6).abs() < 1e-12, "{values:?}");
    assert!(c.shading);
    assert_eq!(saved.fidelity, arbvis::scene::Fidelity::Precise);
    assert_first_screenshot_is(&dir, &saved);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_transfer_function_editor_reaches_the_saved_scene() {
    // The spherical demo draws isosurfaces; switch to both, add a control point on the
    // opacity curve (the table's alpha becomes points first), and set the unit distance,
    // the faithful order and the table's length.
    let script = "\
resize 900 700
wait 2
click Mode both
click-at TF opacity 0.5 0.25
set Unit distance 0.25
click Order centroid
click Precise projected
set Volume table length 32
check layout
set Box and labels false
click Screenshot
click Save scene
";
    let Some((dir, stdout)) = run_script("transfer", "cellproj-spherical", "160x120", script)
    else {
        return;
    };
    // The legends show the volume's colours and the isovalues, as both are drawn.
    for want in ["overlay \"legend volume: ", "overlay \"legend isovalues"] {
        assert!(stdout.contains(want), "{want} not in {stdout}");
    }
    let saved = saved_scene(&dir);
    let TechniqueScene::Cellproj(c) = &saved.technique else {
        panic!("saved scene is not cellproj");
    };
    assert_eq!(c.mode, Mode::Both);
    let v = c.volume.as_ref().expect("the volume's settings are saved");
    assert_eq!(v.unit_distance, 0.25);
    assert_eq!(v.sort, Sort::Centroid);
    assert_eq!(v.precise, Precise::Projected);
    assert_eq!(v.table_size, [128, 32]);
    // viridis' alpha ramps 0..1: the table became the points (0, 0) and (1, 1), and the
    // click at x 0.5, y 0.25 (from the top) added (0.5, 0.75) between them.
    let sa: Vec<[f64; 2]> = v.points.iter().map(|p| [p[0], p[4]]).collect();
    assert_eq!(
        sa,
        vec![[0.0, 0.0], [0.5, 0.75], [1.0, 1.0]],
        "{:?}",
        v.points
    );
    // Each point has viridis' colour where it lies: s = 0.5 is halfway between entries
    // 127 and 128; within 1e-3, the rounding of the written colours.
    let viridis = ColorTable::builtin("viridis").unwrap().entries;
    for (p, want) in v.points.iter().zip([
        viridis[0].map(|e| e as f64 / 255.0),
        std::array::from_fn(|c| (viridis[127][c] as f64 + viridis[128][c] as f64) / 510.0),
        viridis[255].map(|e| e as f64 / 255.0),
    ]) {
        for c in 0..3 {
            assert!((p[c + 1] - want[c]).abs() <= 1e-3, "{p:?} vs {want:?}");
        }
    }
    assert_first_screenshot_is(&dir, &saved);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_splat_editor_reaches_the_saved_scene() {
    let dir = temp_dir("splat-scene");
    let scene = dir.join("splats.toml");
    std::fs::write(
        &scene,
        "fidelity = \"precise\"\nbackground = [1.0, 1.0, 1.0, 1.0]\n[camera]\nprojection = \"perspective\"\nrotation = [-0.5703, -0.1422, -0.1957, 0.785]\nzoom = 1.5\n[technique.splats]\ncloud = { section = { points = 20000, seed = 3 } }\n",
    )
    .unwrap();
    let script = "\
resize 900 640
wait 2
click Layer 7
click Faults in white
set Colour layer
set Point size 6
click Sort seed
click Draw tiles
set Tile size 3
click Volume mode
set Threshold 0.01
set Box and labels false
click Screenshot
click Save scene
";
    let Some((out, _)) = run_script("splats", scene.to_str().unwrap(), "200x150", script) else {
        return;
    };
    let saved = saved_scene(&out);
    let TechniqueScene::Splats(s) = &saved.technique else {
        panic!("saved scene is not splats");
    };
    assert_eq!(s.hide_layers, vec![7]);
    assert!(s.faults_white);
    assert_eq!(
        s.colour,
        arbvis::techniques::splats::scene::ColourMode::Layer
    );
    assert_eq!(s.point_size, 6.0);
    assert_eq!(s.sort, arbvis::techniques::splats::scene::SortChoice::Seed);
    assert_eq!(s.draw, arbvis::techniques::splats::scene::DrawChoice::Tiles);
    assert_eq!(s.tile, 3);
    assert_eq!(s.mode, arbvis::techniques::splats::scene::Mode::Volume);
    assert_eq!(s.volume.threshold, 0.01);
    assert_first_screenshot_is(&out, &saved);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A lidar cloud's editor: a classification code hidden, colour by elevation, and the
/// property list offering the file's own attributes (GPS time).
#[test]
fn the_splat_editor_hides_classes_and_offers_the_clouds_attributes() {
    let dir = temp_dir("splat-classes-scene");
    let scene = dir.join("lidar.toml");
    let cloud =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/points/autzen_trim.laz");
    std::fs::write(
        &scene,
        format!(
            "fidelity = \"precise\"\n[camera]\nrotation = [0.2, 0.1, 0.0, 0.97]\nzoom = 1.8\n[technique.splats]\ncloud = {{ las = {:?} }}\ncolour = \"rgb\"\npoint_size = 6.0\n",
            cloud.display().to_string()
        ),
    )
    .unwrap();
    let script = "\
resize 900 640
wait 2
click Class 2
set Colour elevation
set Property gps_time
set Box and labels false
click Screenshot
click Save scene
";
    let Some((out, _)) = run_script("splat-classes", scene.to_str().unwrap(), "200x150", script)
    else {
        return;
    };
    let saved = saved_scene(&out);
    let TechniqueScene::Splats(s) = &saved.technique else {
        panic!("saved scene is not splats");
    };
    // autzen_trim holds classes 1 and 2; the second is hidden.
    assert_eq!(s.hide_classes, vec![2]);
    assert_eq!(
        s.colour,
        arbvis::techniques::splats::scene::ColourMode::Elevation
    );
    assert_eq!(s.property, "gps_time");
    assert_first_screenshot_is(&out, &saved);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

/// What a script's `print Clip stats` steps wrote (`print LABEL: TEXT (script line N)`).
fn clip_stats_lines(stdout: &str) -> Vec<&str> {
    stdout
        .lines()
        .filter_map(|l| l.strip_prefix("print Clip stats: "))
        .filter_map(|l| l.rsplit_once(" (script line ").map(|(text, _)| text))
        .collect()
}

#[test]
fn the_clip_editor_reaches_the_saved_scene() {
    // The demo: an inverted sphere at [-1, -1, 1], radius 1.3, B = 8, INDEX-DATA. The
    // clip is switched off and on again (restored), made a torus, moved, resized and
    // turned, no longer inverted, B = 16, then the single texture.
    let script = "\
resize 1000 720
wait 2
print Clip stats
click Clip enabled
click Clip enabled
set Clip shape torus-mesh
set Clip minor radius 0.2
set Clip major radius 0.7
set Clip x 0.25
set Clip y -0.5
set Clip z 0
set Clip rotation x 30
set Clip invert false
set Clip block 16
print Clip stats
set Clip multires false
print Clip stats
set Box and labels false
click Screenshot
click Save scene
";
    let Some((dir, stdout)) = run_script("clip", "clip-sphere", "200x200", script) else {
        return;
    };
    let saved = saved_scene(&dir);
    let clip = opacity3d(&saved)
        .clip
        .clone()
        .expect("the saved scene has a clip");
    let mut want = ClipSpec {
        shape: ShapeSpec::TorusMesh {
            center: [0.25, -0.5, 0.0],
            major_radius: 0.7,
            minor_radius: 0.2,
            rotation: [30.0, 0.0, 0.0],
            segments: [48, 24],
        },
        invert: false,
        block: 16,
        multires: false,
        resolution: None,
    };
    assert_eq!(clip, want);
    let text = std::fs::read_to_string(dir.join("arbvis-scene.toml")).unwrap();
    assert!(text.contains("[technique.opacity3d.clip]"), "{text}");

    // The stats line after each rebuild: the demo's (B = 8: INDEX 8^3 x 16 bytes), the
    // torus at B = 16 (INDEX 4^3 x 16 bytes) and the single texture (64^3 x 1 byte,
    // faithful).
    let lines = clip_stats_lines(&stdout);
    assert_eq!(lines.len(), 3, "{stdout}");
    assert!(
        lines[0].starts_with("INDEX-DATA (B = 8): built in "),
        "{}",
        lines[0]
    );
    assert!(
        lines[0].contains("ms; INDEX 8.0 KiB + DATA "),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].starts_with("INDEX-DATA (B = 16): built in "),
        "{}",
        lines[1]
    );
    assert_eq!(
        lines[2].split_once(" ms; ").unwrap().1,
        "256.0 KiB, ratio 1 (uncompressed)",
        "{}",
        lines[2]
    );
    // The torus's bytes and ratio equal a CPU build of the same clip over the demo's
    // 64^3 volume (its box [-1, 1]^3).
    want.multires = true;
    let built = want.build(Path::new("."), [64; 3], [1.0; 3], 2048).unwrap();
    let stats = ClipStats::of(&built, arbvis::scene::Fidelity::Faithful, 0.0);
    assert_eq!(
        lines[1].split_once(" ms; ").unwrap().1,
        stats.line().split_once(" ms; ").unwrap().1
    );
    assert!(stats.ratio > 0.0 && stats.ratio < 1.0, "{stats:?}");

    assert_first_screenshot_is(&dir, &saved);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_clip_the_editor_cannot_edit_is_kept() {
    // The clip-sphere demo with a CSG clip: shown read-only, and chosen again after a
    // sphere was tried.
    let dir = temp_dir("clip-csg-scene");
    let scene = dir.join("csg.toml");
    let demo = include_str!("../../scenes/demo/clip-sphere.toml");
    let csg = "shape = { difference = [{ sphere = { center = [0.0, 0.0, 0.0], radius = 0.9 } }, { box = { center = [0.5, 0.5, 0.5], half_size = [0.5, 0.5, 0.5] } }] }";
    let text = demo.replace(
        "shape = { sphere = { center = [-1.0, -1.0, 1.0], radius = 1.3 } }",
        csg,
    );
    assert_ne!(text, demo);
    std::fs::write(&scene, &text).unwrap();
    let script = "\
resize 1000 720
wait 2
print Clip shape details
set Clip shape sphere
set Clip radius 0.3
set Clip shape scene-difference
set Clip block 16
click Save scene
";
    let Some((out, stdout)) = run_script("clip-csg", scene.to_str().unwrap(), "160x160", script)
    else {
        return;
    };
    assert!(
        stdout.contains("print Clip shape details: difference (read-only)"),
        "{stdout}"
    );
    let saved = saved_scene(&out);
    let clip = opacity3d(&saved).clip.clone().unwrap();
    let original = Scene::load(&scene).unwrap();
    let mut want = opacity3d(&original).clip.clone().unwrap();
    assert_eq!(want.shape.kind(), "difference");
    want.block = 16;
    assert_eq!(clip, want);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn save_tables_writes_them_and_the_scene_uses_them() {
    let Some((dir, _)) = run_script(
        "tables",
        "v3o2-product",
        "160x160",
        "wait 2\nset Box and labels false\nclick-at primary alpha 0.25 0.5\nclick Save tables\nclick Screenshot\nclick Save scene\nclick Transparent screenshots\nclick Screenshot\n",
    ) else {
        return;
    };
    let saved = saved_scene(&dir);
    let o = opacity3d(&saved);
    for (role, attr) in ["primary", "secondary", "tertiary"]
        .iter()
        .zip(o.attributes())
    {
        let Some(attr) = attr else { continue };
        let file = dir.join(format!("arbvis-table-{role}.table"));
        assert!(file.exists(), "{}", file.display());
        assert_eq!(
            attr.table.file.as_deref(),
            Some(std::fs::canonicalize(&file).unwrap().as_path())
        );
        assert!(attr.table.alpha.is_empty(), "the curve is in the file");
    }
    // The table written holds the edited curve [[0, 0], [0.25, 0.5], [0.55, 0], [0.8, 1]].
    let table =
        arbvis::colortable::ColorTable::load(&dir.join("arbvis-table-primary.table")).unwrap();
    assert_eq!(
        table.entries[100][3], 67,
        "(0.55 - 100/255) / 0.3 * 0.5 * 255"
    );
    assert_first_screenshot_is(&dir, &saved);
    // The transparent switch: the second screenshot is the transparent render.
    let (clear, text) = read_png(&dir.join("arbvis-screenshot-002.png")).unwrap();
    let scene_text = &text.iter().find(|(k, _)| k == "arbvis:scene").unwrap().1;
    let mut transparent = Scene::parse(scene_text, "screenshot").unwrap();
    assert!(transparent.transparent);
    transparent.base = saved.base.clone();
    transparent.technique = saved.technique.clone();
    // As `arbvis render --transparent` writes it: straight colour, coverage alpha.
    let offscreen = transparent.picture(&render(&transparent, Backend::Egl).unwrap().image);
    let d = clear.compare(&offscreen, common::LEVEL).unwrap();
    assert!(d.max_abs <= common::LEVEL as f64 * 1.01, "{d:?}");
    assert!(clear.pixel_u8(0, 0)[3] == 0, "the background is clear");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn script_steps_that_do_nothing_fail_with_their_line() {
    let Some(errors) = failing_scripts(
        "failing",
        "v3o2-sum",
        &[
            "wait 1\nclick No such button\n",
            "wait 1\n\nset primary Cr 7\n",
            "wait 1\nset primary table rainbow\n",
            "wait 1\nset Lock primary maybe\n",
            // A click on an existing curve point ((1, 0.3): 0.7 from the top) neither adds nor
            // removes one.
            "wait 1\nclick-at tertiary alpha 1 0.7\n",
            "wait 1\nwait 1\nkey F5\n",
            "wait 1\nset slices 2.5\n",
            // No clip in this demo: the section opens, the clip is added, B is disabled
            // once INDEX-DATA is off.
            "wait 1\nclick Clip\nclick Clip enabled\nset Clip multires false\nset Clip block 16\n",
            // A half-space's normal cannot become zero.
            "wait 1\nclick Clip\nclick Clip enabled\nset Clip shape half-space\nset Clip normal z 0\n",
        ],
    ) else {
        return;
    };
    let expect = [
        (
            "line 2 (click No such button)",
            "no widget labelled \"No such button\"",
        ),
        ("line 3 (set primary Cr 7)", "7 is outside 0..=4"),
        (
            "line 2 (set primary table rainbow)",
            "no option \"rainbow\"",
        ),
        ("line 2 (set Lock primary maybe)", "takes true or false"),
        ("line 2 (click-at tertiary alpha 1 0.7)", "did nothing"),
        ("line 3 (key F5)", "did nothing"),
        ("line 2 (set slices 2.5)", "not a whole number"),
        ("line 5 (set Clip block 16)", "Clip block is disabled"),
        (
            "line 5 (set Clip normal z 0)",
            "the clip normal must not be zero",
        ),
    ];
    for (e, (line, message)) in errors.iter().zip(expect) {
        assert!(e.contains(line) && e.contains(message), "{e}");
    }
    // The missing widget's error lists the widgets there are.
    assert!(
        errors[0].contains("Save tables") && errors[0].contains("Lock secondary"),
        "{}",
        errors[0]
    );
}

#[test]
fn drawing_in_parts_equals_one_draw() {
    // The viewer spreads a slow frame over UI frames with Renderer::draw_part.
    let mut scene = Scene::demo("v3o2-sum").unwrap();
    scene.size = [64, 48];
    if let TechniqueScene::Opacity3d(o) = &mut scene.technique {
        o.slices = 37;
    }
    let headless = common::headless(Backend::Egl);
    let gpu = headless.gpu();
    let kind = scene.programs.resolve(gpu);
    for fidelity in [
        arbvis::scene::Fidelity::Faithful,
        arbvis::scene::Fidelity::Precise,
    ] {
        scene.fidelity = fidelity;
        let mut renderer = arbvis::render::build(gpu, &scene, kind).unwrap();
        let frame = arbvis::techniques::Frame {
            camera: scene.camera,
            width: 64,
            height: 48,
        };
        let draw = |parts: Option<usize>, renderer: &mut Box<dyn arbvis::techniques::Renderer>| {
            let t = Target::new(gpu, 64, 48, scene.target_format()).unwrap();
            t.clear(gpu, scene.background).unwrap();
            match parts {
                None => renderer.draw(gpu, Surface::Target(&t), &frame).unwrap(),
                Some(n) => {
                    for p in 0..n {
                        renderer
                            .draw_part(gpu, Surface::Target(&t), &frame, p, n)
                            .unwrap();
                    }
                }
            }
            t.read(gpu).unwrap()
        };
        let whole = draw(None, &mut renderer);
        for parts in [1, 5, 37, 100] {
            let pieces = draw(Some(parts), &mut renderer);
            assert_eq!(whole.data, pieces.data, "{fidelity:?} in {parts} parts");
        }
    }
}

/// A layered scene's panel: a layer hidden and moved up through its controls, drawn as
/// the saved scene draws offscreen.
#[test]
fn the_layer_list_hides_and_orders_layers_and_reaches_the_saved_scene() {
    let dir = temp_dir("layers-scene");
    let text = "[[layer]]\nname = \"horizon\"\n[layer.surface]\nsynthetic = { size = [17, 11], seed = 2 }\ncolour_by = \"elevation\"\n[[layer]]\nname = \"cube\"\n[layer.opacity3d.primary]\nvolume = { synthetic = { size = [19, 13, 17], seed = 4 } }\nattribute = \"amplitude\"\n";
    let steps =
        "click layer 1: cube (opacity3d) visible\nwait 1\nclick layer 1: cube (opacity3d) up\n";
    let Some(saved) = saved_after("layers", &dir, text, steps) else {
        return;
    };
    let layers: Vec<_> = saved.layers().collect();
    assert_eq!(layers.len(), 2);
    assert_eq!(
        (layers[0].0.name.as_str(), layers[0].0.visible),
        ("cube", false)
    );
    assert_eq!(
        (layers[1].0.name.as_str(), layers[1].0.visible),
        ("horizon", true)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A surface layer's colour from its panel (issue 57 item 6): its settings opened, the
/// drop-down offers its file's property and the other layer; seismic from the cube
/// switched on, then the property instead: the saved scene follows, and the screenshot
/// is the saved scene drawn offscreen.
#[test]
fn a_surface_layers_colour_is_switched_between_a_layer_and_its_property() {
    let dir = temp_dir("surface-colour-scene");
    let ts = "GOCAD TSurf 1\nPROPERTIES throw\nPVRTX 1 0 0 5 0\nPVRTX 2 19 0 6 4\nPVRTX 3 19 13 8 9\nPVRTX 4 0 13 7 2\nTRGL 1 2 3\nTRGL 1 3 4\nEND\n";
    std::fs::write(dir.join("f.ts"), ts).unwrap();
    let text = format!("[[layer]]\nname = \"fault\"\n[layer.surface]\nfile = \"{}\"\n[[layer]]\nname = \"cube\"\n[layer.opacity3d.primary]\nvolume = {{ synthetic = {{ size = [19, 13, 17], seed = 4 }} }}\nattribute = \"amplitude\"\n", dir.join("f.ts").display());
    let steps = "click layer 0: fault (surface) settings\nwait 1\nset layer 0 colour = layer cube\nwait 2\nset layer 0 colour = property throw\n";
    let Some(saved) = saved_after("surface-colour", &dir, &text, steps) else {
        return;
    };
    let surface: arbvis::techniques::surface::SurfaceScene = saved_layer(&saved, 0);
    assert_eq!(
        surface.colour_by,
        Some(arbvis::techniques::surface::ColourBy::Property(
            "throw".into()
        ))
    );
    assert_eq!(surface.colour_from, None);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A lines layer's panel (issue 57 items 3 and 6): the F3 well switched to a ribbon 6
/// pixels wide; the saved scene follows, and the screenshot (the ribbon shaped for the
/// viewer's picture) is the saved scene drawn offscreen.
#[test]
fn a_wells_panel_makes_it_a_ribbon_in_pixels() {
    let dir = temp_dir("lines-ribbon-scene");
    let text = format!(
        "[camera]\nprojection = \"perspective\"\nrotation = [-0.35, 0.12, 0.2, 0.906]\n[[layer]]\nname = \"well\"\n[layer.lines]\nwell = {{ survey = \"{}\", head = [620420.0, 6074520.0], log = \"{}\" }}\nradius = 7.0\n",
        common::data_file("seismic/f3-well-survey.csv").display(),
        common::data_file("seismic/f3-well-log.csv").display()
    );
    let steps = "click layer 0: well (lines) settings\nwait 1\nset Lines style ribbon\nwait 1\nset Width in pixels true\nwait 1\nset Lines width 6\n";
    let Some(saved) = saved_after("lines-ribbon", &dir, &text, steps) else {
        return;
    };
    let lines: arbvis::techniques::lines::LinesScene = saved_layer(&saved, 0);
    assert_eq!(lines.style, arbvis::techniques::lines::LineStyle::Ribbon);
    assert_eq!(
        lines.width,
        Some(arbvis::techniques::lines::Width::Pixels(6.0))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A section layer's slider (issue 57 item 6): over F3's inlines 111..=133, a typed
/// 125.4 lands on inline 125 (the survey's step), the saved scene and the screenshot
/// follow; a number outside the survey is refused by the slider with its range.
#[test]
fn a_sections_slider_moves_it_over_the_surveys_numbers() {
    let dir = temp_dir("section-slider-scene");
    let text = format!(
        "[[layer]]\nname = \"inline\"\n[layer.section]\nvolume = {{ segy = \"{}\" }}\ninline = 120\n",
        common::data_file("seismic/f3.sgy").display()
    );
    let opening = "click layer 0: inline (section) settings\nwait 1\n";
    let steps = format!("{opening}set Inline 125.4\n");
    let Some(saved) = saved_after("section-slider", &dir, &text, &steps) else {
        return;
    };
    let section: arbvis::techniques::section::SectionScene = saved_layer(&saved, 0);
    assert_eq!(section.inline, Some(125.0));
    let outside = format!("resize 900 640\nwait 2\n{opening}set Inline 200\n");
    let scene = dir.join("section-slider.toml");
    let Some(errors) = failing_scripts("section-outside", scene.to_str().unwrap(), &[&outside])
    else {
        return;
    };
    assert!(
        errors[0].contains("Inline: 200 is outside 111..=133"),
        "{}",
        errors[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
