//! Section layers (issue 57): an inline, crossline or time section of a survey against its
//! f64 reference and against the survey's own samples, ARB and GLSL, faithful and
//! precise; its errors; its place beside a 3D-opacity layer of the same survey; and
//! moved by a frame, not a build.

use crate::common;

use arbvis::gl::{Backend, ProgramChoice, TargetFormat};
use arbvis::render::render_on;
use arbvis::scene::{Fidelity, Scene};
use arbvis::techniques::section::{prepare, reference, SectionScene};
use common::headless;

/// An uneven survey of odd size (samples fastest), some samples without data.
const DIMS: [usize; 3] = [23, 17, 11];

fn sample(i: usize, j: usize, k: usize) -> f32 {
    let (x, y, z) = (i as f64, j as f64, k as f64);
    let v = (x * 0.9 + y * 0.31).sin() * 60.0
        + (z * 1.7 - x * 0.2).cos() * 25.0
        + ((i * 7 + j * 13 + k * 29) % 11) as f64 * 3.0;
    v as f32
}

/// The survey as raw f32 in `dir`, with NaN at two samples; a scene's volume table for it.
fn survey(dir: &std::path::Path) -> (Vec<f32>, String) {
    let mut values = Vec::new();
    for k in 0..DIMS[2] {
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                values.push(sample(i, j, k));
            }
        }
    }
    let index = |i: usize, j: usize, k: usize| i + DIMS[0] * (j + DIMS[1] * k);
    values[index(9, 5, 6)] = f32::NAN;
    values[index(14, 11, 3)] = f32::NAN;
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(dir.join("survey.raw"), bytes).unwrap();
    let volume = format!(
        "{{ raw = {{ path = \"{}\", dims = [{}, {}, {}], type = \"f32\", spacing = [1.0, 1.3, 1.7] }} }}",
        dir.join("survey.raw").display(),
        DIMS[0],
        DIMS[1],
        DIMS[2]
    );
    (values, volume)
}

/// A random table (no smooth run between entries: a wrong entry or an off-by-half lookup
/// shows), written as 64 colours spread over the 256 entries.
fn random_table() -> String {
    let mut state = 0x9e37_79b9u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state % 1000) as f64 / 999.0
    };
    let colours: Vec<String> = (0..64)
        .map(|_| format!("[{:.3}, {:.3}, {:.3}, 1.0]", next(), next(), next()))
        .collect();
    format!("{{ colors = [{}] }}", colours.join(", "))
}

fn section_scene(volume: &str, cut: &str, extra: &str) -> Scene {
    let text = format!(
        "size = [67, 53]\n[camera]\nprojection = \"perspective\"\nrotation = [0.28, -0.17, -0.61, 0.72]\nzoom = 1.5\n[technique.section]\nvolume = {volume}\n{cut}\nquantize = {{ range = [-70.0, 110.0] }}\n{extra}\n"
    );
    Scene::parse(&text, "section.toml").unwrap()
}

fn prepared(scene: &Scene) -> prepare::Prepared {
    let technique = scene.layers().next().unwrap().1;
    let limits = arbvis::volume::Limits::for_max_side(2048);
    let data = arbvis::catalog::prepare(technique, &scene.settings(), &limits).unwrap();
    data.downcast::<prepare::Prepared>().map(|b| *b).unwrap()
}

/// Precise, ARB and GLSL, at an inline, a crossline and a time between samples, against the
/// f64 reference: every pixel both cover within the f32 arithmetic's reach, and the pixels
/// only one covers (the plane's rim, the samples without data) few.
#[test]
fn a_precise_section_matches_its_reference_at_every_cut() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("section-reference");
    let (_, volume) = survey(&dir);
    let table = format!("table = {}", random_table());
    for cut in ["inline = 6", "crossline = 11", "time = 13.37"] {
        for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
            let mut scene = section_scene(&volume, cut, &table);
            (scene.fidelity, scene.programs) = (Fidelity::Precise, programs);
            scene.target = Some(TargetFormat::Rgba32f);
            scene.background = [0.0; 4];
            let p = prepared(&scene);
            let gpu = render_on(&h, &scene).unwrap().image;
            let cpu = reference::reference(&p, 1.0, &scene.camera, scene.size, [0.0; 4]);
            let (mut both, mut one, mut worst) = (0, 0, 0.0f32);
            for y in 0..scene.size[1] {
                for x in 0..scene.size[0] {
                    let (a, b) = (gpu.pixel(x, y), cpu.pixel(x, y));
                    match (a[3] > 0.5, b[3] > 0.5) {
                        (true, true) => {
                            both += 1;
                            for c in 0..3 {
                                worst = worst.max((a[c] - b[c]).abs());
                            }
                        }
                        (false, false) => {}
                        _ => one += 1,
                    }
                }
            }
            // The texture coordinates reach the program interpolated in f32 (~1e-7 of the
            // plane, 3e-6 of a sample over 23), times this survey's steepest change per
            // sample (~130), times 255/180 levels per unit of value and the random table's
            // steepest step (up to 1 per level): ~5e-4; the level arithmetic in f32 adds
            // ~1e-5. Measured: under 1e-4.
            assert!(worst < 2e-3, "{cut} {programs:?}: {worst}");
            // A pixel whose centre lies within f32 rounding of the plane's rim or of the
            // edge of a no-data sample's reach may fall either side: a rim's worth at most.
            let rim = 2 * (scene.size[0] + scene.size[1]) as usize;
            assert!(
                one < rim / 4,
                "{cut} {programs:?}: {one} pixels covered by one"
            );
            // In view at this camera: the time slice nearly edge on (~250 pixels), the
            // others over a thousand.
            assert!(
                both > 200,
                "{cut} {programs:?}: the plane is in view ({both})"
            );
        }
    }
}

/// Seen face on, orthographic, one pixel per sample: each pixel is the colour of the
/// survey's own sample there (read from the file's values, not from the prepared plane),
/// precise within f32, faithful within its 8-bit steps; ARB and GLSL agree exactly.
#[test]
fn a_section_seen_face_on_shows_the_surveys_samples() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("section-samples");
    let (values, volume) = survey(&dir);
    // Time along x (23 samples), crosslines along y (17): an inline section, looked at down
    // the inline axis; spacing 1 so that the picture's pixels are the samples.
    let volume = volume.replace("spacing = [1.0, 1.3, 1.7]", "spacing = [1.0, 1.0, 1.0]");
    let inline = 4;
    let text = format!(
        "size = [{}, {}]\n[camera]\nprojection = \"orthographic\"\nzoom = {}\n[technique.section]\nvolume = {volume}\ninline = {inline}\nquantize = {{ range = [-70.0, 110.0] }}\n",
        DIMS[0],
        DIMS[1],
        // The camera frames [-1, 1] on the shorter side at zoom 1; the longest half side
        // is 1, so the 17 crosslines span 17/23 of 2: zoom 23/17 frames them exactly.
        DIMS[0] as f64 / DIMS[1] as f64
    );
    let table = arbvis::colortable::ColorTable::builtin("seismic").unwrap();
    let mut pictures = Vec::new();
    for fidelity in [Fidelity::Precise, Fidelity::Faithful] {
        for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
            let mut scene = Scene::parse(&text, "section.toml").unwrap();
            (scene.fidelity, scene.programs) = (fidelity, programs);
            scene.target = Some(TargetFormat::Rgba32f);
            scene.background = [0.0; 4];
            let image = render_on(&h, &scene).unwrap().image;
            let mut checked = 0;
            for j in 0..DIMS[1] {
                for i in 0..DIMS[0] {
                    let v = values[i + DIMS[0] * (j + DIMS[1] * inline)];
                    // Row 0 is the top: crosslines grow upwards.
                    let got = image.pixel(i as u32, (DIMS[1] - 1 - j) as u32);
                    if v.is_nan() {
                        assert_eq!(got[3], 0.0, "no data at sample {i}, crossline {j}");
                        continue;
                    }
                    let want = reference::colour_of(&table, (-70.0, 110.0), v as f64);
                    // Precise: the sample's own value at its centre, f32 arithmetic (1e-4).
                    // Faithful: the value quantized to one of 256 levels (half a level),
                    // the table's nearest entry (half a level more); the seismic table
                    // changes by at most 2/255 per level: 2.5 levels' worth.
                    let tolerance = match fidelity {
                        Fidelity::Precise => 1e-4,
                        Fidelity::Faithful => 2.5 * 2.0 / 255.0,
                    };
                    for c in 0..3 {
                        assert!(
                            (got[c] as f64 - want[c]).abs() <= tolerance,
                            "{fidelity:?} {programs:?} sample {i}, crossline {j}: {got:?} against {want:?}"
                        );
                    }
                    checked += 1;
                }
            }
            assert!(checked >= DIMS[0] * DIMS[1] - 1);
            pictures.push(image);
        }
    }
    for pair in pictures.chunks(2) {
        assert_eq!(
            pair[0].compare(&pair[1], 0.0).unwrap().pixels_over,
            0,
            "ARB = GLSL"
        );
    }
}

/// A cut that is not in the survey, two cuts and none are refused by their key and line,
/// saying what the survey holds; a store that is not there by its path.
#[test]
fn a_section_outside_the_survey_is_refused_by_its_key() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("section-errors");
    let (_, volume) = survey(&dir);
    let scene = section_scene(&volume, "time = 22.5", "");
    let e = render_on(&h, &scene).err().unwrap().to_string();
    assert!(e.contains("time") && e.contains("runs from 0 to 22"), "{e}");
    // A raw volume numbers its axes in its spacing (k every 1.7): 20 lies past 10 x 1.7.
    let scene = section_scene(&volume, "inline = 20", "");
    let e = render_on(&h, &scene).err().unwrap().to_string();
    assert!(
        e.contains("inline 20") && e.contains("runs from 0 to 17"),
        "{e}"
    );
    // A SEG-Y file's inlines are its trace headers' numbers (F3's crop: 111 to 133).
    let f3 = common::data_file("seismic/f3.sgy");
    let text = format!(
        "[technique.section]\nvolume = {{ segy = \"{}\" }}\ninline = 110\n",
        f3.display()
    );
    let scene = Scene::parse(&text, "s.toml").unwrap();
    let e = render_on(&h, &scene).err().unwrap().to_string();
    assert!(
        e.contains("inline 110 is not one of the survey's inlines (111 to 133, 23 of them)"),
        "{e}"
    );
    for cut in ["inline = 2\ncrossline = 3", ""] {
        let text = format!("[technique.section]\nvolume = {volume}\n{cut}\n");
        let e = Scene::parse(&text, "s.toml").unwrap_err().to_string();
        assert!(e.contains("technique.section.inline"), "{e}");
        assert!(e.contains("one of inline = N, crossline = N"), "{e}");
    }
    let missing = dir.join("missing.zarr");
    let text = format!(
        "[technique.section]\nvolume = {{ store = \"{}\" }}\ninline = 3\n",
        missing.display()
    );
    let scene = Scene::parse(&text, "s.toml").unwrap();
    let e = render_on(&h, &scene).err().unwrap().to_string();
    assert!(e.contains("missing.zarr"), "{e}");
}

/// Beside a 3D-opacity layer of the same survey the section lies in the same world frame;
/// moving it (and recolouring it) in a layered session costs an upload, not a build: the
/// survey's file is gone by then, and the picture equals a fresh build's.
#[test]
fn a_section_moves_in_a_layered_scene_without_a_build() {
    use arbvis::session::{Mode, Session};
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("section-layered");
    let (_, volume) = survey(&dir);
    let text = format!(
        "size = [59, 47]\nfidelity = \"precise\"\n[[layer]]\nname = \"volume\"\n[layer.opacity3d.primary]\nvolume = {volume}\ntable = {{ builtin = \"grey\", alpha = [[0.0, 0.0], [1.0, 0.1]] }}\n[[layer]]\nname = \"inline 3\"\n[layer.section]\nvolume = {volume}\ninline = 3\n"
    );
    let scene = Scene::parse(&text, "layered.toml").unwrap();
    let limits = arbvis::volume::Limits::for_max_side(2048);
    let worlds: Vec<_> = scene
        .layers()
        .map(|(_, t)| {
            let data = arbvis::catalog::prepare(t, &scene.settings(), &limits).unwrap();
            arbvis::catalog::world(t, &data).unwrap()
        })
        .collect();
    assert_eq!(worlds[0], worlds[1], "one survey, one place");

    let gpu = h.gpu();
    let kind = scene.programs.resolve(gpu);
    let mut session = Session::build(gpu, &scene, kind, true).unwrap();
    session.frame(gpu, &scene, Mode::Now).unwrap();
    let copy = dir.join("copy.raw");
    std::fs::rename(dir.join("survey.raw"), &copy).unwrap();
    let mut moved = scene.clone();
    let section = moved.more_layers[0].1.get_mut::<SectionScene>().unwrap();
    section.inline = Some(7.0);
    section.table = arbvis::colortable::TableSpec::builtin("viridis");
    session.apply(gpu, &moved).unwrap();
    session.frame(gpu, &moved, Mode::Now).unwrap();
    let kept = session.read(gpu, &moved).unwrap();
    std::fs::rename(&copy, dir.join("survey.raw")).unwrap();
    let fresh = render_on(&h, &moved).unwrap().image;
    let d = kept.compare(&fresh, 0.0).unwrap();
    assert_eq!(d.pixels_over, 0, "moved in place = built afresh: {d:?}");
    let before = render_on(&h, &scene).unwrap().image;
    assert!(
        before.compare(&fresh, 0.0).unwrap().pixels_over > 100,
        "it moved"
    );
}

/// Scenes `a` and `b` cut one plane in one place and draw one picture, exactly, with the
/// section in view (over 100 lit pixels).
fn assert_one_section(h: &arbvis::gl::Headless, a: &Scene, b: &Scene, what: &str) {
    let (pa, pb) = (prepared(a), prepared(b));
    assert_eq!(pa.world, pb.world, "{what}: one place");
    assert_eq!(pa.plane, pb.plane, "{what}: one plane");
    let (ia, ib) = (
        render_on(h, a).unwrap().image,
        render_on(h, b).unwrap().image,
    );
    assert_eq!(ia.compare(&ib, 0.0).unwrap().pixels_over, 0, "{what}");
    let lit = common::lit_pixels(&ia, 0.05);
    assert!(lit > 100, "{what}: in view ({lit})");
}

/// A section of F3 converted into a store (bricks of 8: a plane crosses several) draws the
/// SEG-Y's section exactly, at an inline, a crossline and a time between samples, and in
/// the same world frame; the store's plane is read at full resolution as it is needed.
#[test]
fn a_section_of_a_store_draws_the_segys_section() {
    let h = headless(Backend::Egl);
    let (_dir, f3, store) = crate::mdio::f3_store("section-store");
    let scene = |volume: String, cut: &str| {
        // A store's range is its min-max (its percentiles are not computed): the SEG-Y's too.
        let text = format!(
            "size = [61, 45]\nfidelity = \"precise\"\n[technique.section]\nvolume = {volume}\n{cut}\nquantize = \"min-max\"\n"
        );
        Scene::parse(&text, "s.toml").unwrap()
    };
    for cut in ["inline = 127", "crossline = 880", "time = 141"] {
        let a = scene(format!("{{ segy = \"{}\" }}", f3.display()), cut);
        let b = scene(format!("{{ store = \"{}\" }}", store.display()), cut);
        // Each plane seen from the survey's three-quarter view: 144 to 172 of 2,745 pixels.
        assert_one_section(&h, &a, &b, cut);
    }
}

/// A survey in depth (F3's store declared in depth, 4 m a sample, as an MDIO dataset with
/// a depth axis says) is cut by `depth`: the same plane, place and picture as the store in
/// time cut by `time` at the same number (a survey in time lies at 1 m per ms); `time` on
/// the survey in depth, and `depth` on the one in time or on the SEG-Y, are refused by key
/// with the survey's vertical axis named.
#[test]
fn a_survey_in_depth_is_cut_by_depth() {
    let h = headless(Backend::Egl);
    let (dir, f3, timed) = crate::mdio::f3_store("section-depth");
    let deep = dir.join("f3-depth.zarr");
    common::copy_tree(&timed, &deep);
    let root = deep.join("zarr.json");
    let mut meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&root).unwrap()).unwrap();
    meta["attributes"]["arbvis"]["source"]["samples"] =
        serde_json::json!({"domain": "depth", "unit": "m", "first": 0.0, "step": 4.0});
    std::fs::write(&root, serde_json::to_vec(&meta).unwrap()).unwrap();
    let scene = |store: &std::path::Path, cut: &str| {
        let text = format!(
            "size = [61, 45]\nfidelity = \"precise\"\n[technique.section]\nvolume = {{ store = \"{}\" }}\n{cut}\nquantize = \"min-max\"\n",
            store.display()
        );
        Scene::parse(&text, "s.toml").unwrap()
    };
    // On a sample and between two.
    for number in [140.0, 141.0] {
        let a = scene(&timed, &format!("time = {number:?}"));
        let b = scene(&deep, &format!("depth = {number:?}"));
        assert_one_section(&h, &a, &b, &format!("{number}"));
    }
    let segy = format!("{{ segy = \"{}\" }}", f3.display());
    for (text, key, says) in [
        (
            scene(&deep, "time = 140"),
            "time",
            "vertical axis is depth (m)",
        ),
        (
            scene(&timed, "depth = 140"),
            "depth",
            "vertical axis is time (ms)",
        ),
        (
            Scene::parse(
                &format!("[technique.section]\nvolume = {segy}\ndepth = 140\n"),
                "s.toml",
            )
            .unwrap(),
            "depth",
            "use time = N",
        ),
    ] {
        let e = render_on(&h, &text).err().expect("refused").to_string();
        assert!(e.contains(key) && e.contains(says), "{e}");
    }
}
