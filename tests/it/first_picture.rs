//! A user's own survey in a minimal scene (`segy`, `amplitude`, a built-in table) gives a
//! usable first picture: the survey's proportions from its CDP coordinates and sample
//! interval, a three-quarter view with time running down, one attribute undimmed, the
//! 1-99 % range, and an alpha from the data's own distribution; every default gives way
//! to a key the scene writes.

use std::path::Path;

use glam::DVec3;

use arbvis::colortable::alpha_from_histogram;
use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::Scene;
use arbvis::techniques::opacity3d::{Combine, SURVEY_VIEW};
use arbvis::volume::quantize::Quantization;
use arbvis::volume::segy;

use crate::common::{data_file, headless, opacity3d, temp_dir};

fn minimal(segy: &Path, extra: &str) -> String {
    format!(
        "{extra}[technique.opacity3d.primary]\nvolume = {{ segy = {:?} }}\nattribute = \"amplitude\"\ntable = {{ builtin = \"seismic\" }}\n",
        segy.display().to_string()
    )
}

#[test]
fn a_minimal_survey_scene_gets_the_surveys_shape_and_a_three_quarter_view() {
    let f3 = data_file("seismic/f3.sgy");
    let cube = segy::read(&f3, &Default::default()).unwrap();
    // F3's corner traces are 17 crossline steps of 25.004 m and 22 inline steps of
    // 24.996 m apart (its CDP coordinates, scalar -10); 4 ms shown as 4 m.
    let [s, x, i] = cube.volume.spacing;
    assert_eq!(s, 4.0);
    assert!(
        (x - 25.004).abs() < 1e-3 && (i - 24.996).abs() < 1e-3,
        "{:?}",
        cube.volume.spacing
    );

    let scene = Scene::parse(&minimal(&f3, ""), "minimal").unwrap();
    let o = opacity3d(&scene);
    assert_eq!(scene.camera.rotation, SURVEY_VIEW);
    // The viewer's Reset camera returns to the same view.
    assert_eq!(scene.technique.default_camera(), Some(scene.camera));
    assert_eq!(o.combine, Combine::Product);
    assert_eq!(o.primary.quantize, Quantization::Percentile([1.0, 99.0]));
    // Time (the volume's i, object x) runs down the screen; inline and crossline lie
    // across it, both seen (a three-quarter view, no face edge-on).
    let q = scene.camera.quat();
    let [time, crossline, inline] = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| q * a);
    assert!(time.y < -0.9, "time on screen: {time:?}");
    for a in [crossline, inline] {
        assert!(a.x.abs() > 0.3 && a.z.abs() > 0.2, "{a:?}");
    }
    // The whole box in view: no pixel of the border is drawn.
    let h = headless(Backend::Egl);
    let mut small = scene.clone();
    small.size = [96, 80];
    let image = render_on(&h, &small).unwrap().image;
    let lit = |x: u32, y: u32| {
        let p = &image.data[4 * (y * image.width + x) as usize..][..3];
        p.iter().any(|&c| c > 0.02)
    };
    let (w, hgt) = (image.width, image.height);
    for x in 0..w {
        assert!(
            !lit(x, 0) && !lit(x, hgt - 1),
            "column {x} touches the border"
        );
    }
    for y in 0..hgt {
        assert!(!lit(0, y) && !lit(w - 1, y), "row {y} touches the border");
    }
    // And the survey is drawn, not a strip: F3's flat box (300 x 450 x 575 m) at the
    // zoom that fits any box draws 16 % of the pixels (its clear amplitudes leave holes).
    let covered = (0..w * hgt).filter(|&p| lit(p % w, p / w)).count();
    assert!(
        covered as f64 > 0.1 * (w * hgt) as f64,
        "{covered} pixels drawn"
    );

    // Keys the scene writes win.
    let written = "[camera]\nzoom = 0.8\n[technique.opacity3d]\ncombine = \"sum\"\nvertical_exaggeration = 3.0\n";
    let text = minimal(&f3, written).replace(
        "attribute = \"amplitude\"\n",
        "attribute = \"amplitude\"\nquantize = \"min-max\"\n",
    );
    let scene = Scene::parse(&text, "written").unwrap();
    let o = opacity3d(&scene);
    assert_eq!(
        (scene.camera.rotation, scene.camera.zoom),
        ([0.0, 0.0, 0.0, 1.0], 0.8)
    );
    assert_eq!(o.combine, Combine::Sum);
    assert_eq!(o.primary.quantize, Quantization::MinMax);
    assert_eq!(o.spacing_for(cube.volume.spacing)[0], 12.0, "4 m times 3");
    let e = Scene::parse(
        &minimal(&f3, "[technique.opacity3d]\nvertical_exaggeration = 0.0\n"),
        "zero",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("technique.opacity3d.vertical_exaggeration"),
        "{e}"
    );
    // A synthetic volume keeps the plain defaults (the demos' pictures).
    let scene = Scene::demo("v3o2-sum").unwrap();
    assert_eq!(opacity3d(&scene).primary.quantize, Quantization::MinMax);
}

#[test]
fn alpha_from_the_distribution_clears_the_common_values() {
    // A skewed histogram: most values at level 140, a tail down to 0 and up to 255.
    let mut counts = [0u64; 256];
    for (k, c) in counts.iter_mut().enumerate() {
        let d = (k as f64 - 140.0).abs();
        *c = (10_000.0 * (-d / 12.0).exp()).round() as u64 + 1;
    }
    let alpha = alpha_from_histogram(&counts);
    assert_eq!(alpha[140], 0, "the median level is clear");
    assert_eq!(alpha[0], 255, "the farthest level is opaque");
    // Clear over the closer half of the values, then rising with the distance.
    let within = |d: i32| -> u64 {
        (0..256)
            .filter(|&k| (k - 140i32).abs() < d)
            .map(|k| counts[k as usize])
            .sum()
    };
    let total: u64 = counts.iter().sum();
    for k in 0..256i32 {
        let d = (k - 140).abs();
        let share = within(d) as f64 / total as f64;
        let want = (((share - 0.5) / 0.5).max(0.0).powi(2) * 255.0).round() as u8;
        assert_eq!(alpha[k as usize], want, "level {k}");
        if k > 140 {
            assert!(alpha[k as usize] >= alpha[k as usize - 1]);
        }
    }
    assert_eq!(alpha_from_histogram(&[0; 256]), [0; 256]);
}

#[test]
fn alpha_from_data_false_keeps_the_tables_alpha() {
    let dir = temp_dir("alpha-from-data");
    let f3 = data_file("seismic/f3.sgy");
    let h = headless(Backend::Egl);
    let render = |text: String| {
        let mut scene = Scene::parse(&text, "s").unwrap();
        scene.size = [48, 40];
        render_on(&h, &scene).unwrap().image
    };
    let auto = render(minimal(&f3, ""));
    let own = render(minimal(&f3, "").replace(
        "table = { builtin = \"seismic\" }",
        "table = { builtin = \"seismic\", alpha_from_data = false }",
    ));
    let d = auto.compare(&own, crate::common::LEVEL).unwrap();
    // seismic's own alpha (|2t - 1|) is another picture than the distribution's.
    assert!(d.pixels_over > 100, "{d:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_lidar_cloud_gets_precise_lit_splats_coloured_by_height() {
    use arbvis::scene::{Fidelity, TechniqueScene};
    use arbvis::techniques::splats::scene::ColourMode;
    let laz = data_file("points/autzen_trim.laz");
    let text = |extra: &str| {
        format!(
            "{extra}[technique.splats]\ncloud = {{ las = {:?} }}\n",
            laz.display().to_string()
        )
    };
    let splats = |scene: &Scene| match &scene.technique {
        TechniqueScene::Splats(s) => (**s).clone(),
        _ => panic!("not splats"),
    };
    let scene = Scene::parse(&text(""), "laz").unwrap();
    let s = splats(&scene);
    assert_eq!(scene.fidelity, Fidelity::Precise);
    assert_eq!((s.edl, s.colour), (1.0, ColourMode::Elevation));
    // It draws, with the eye-dome lighting pass (a GLSL pass after the splats).
    let h = headless(Backend::Egl);
    let mut small = scene.clone();
    small.size = [64, 48];
    let r = render_on(&h, &small).unwrap();
    assert!(
        r.resources.iter().any(|x| x.label.contains("EDL")),
        "{:?}",
        r.resources
    );
    // Written keys win; the seed's generated section keeps the seed's defaults.
    let scene = Scene::parse(&text("fidelity = \"faithful\"\n"), "faithful").unwrap();
    assert_eq!(
        (scene.fidelity, splats(&scene).edl),
        (Fidelity::Faithful, 0.0)
    );
    let scene = Scene::parse(&text("programs = \"arb\"\n"), "arb").unwrap();
    assert_eq!(splats(&scene).edl, 0.0, "eye-dome lighting needs GLSL");
    let scene = Scene::parse(
        "[technique.splats]\ncloud = { section = { points = 1000, seed = 1 } }\n",
        "section",
    )
    .unwrap();
    assert_eq!(scene.fidelity, Fidelity::Faithful);
    assert_eq!(splats(&scene).colour, ColourMode::Facies);
}
