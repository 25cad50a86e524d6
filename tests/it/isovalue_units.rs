//! Isovalues in the scalar's own units (the default) and normalized (`isovalue_units =
//! "normalized"`, the seed's habit): the same surfaces either way, and a value outside the
//! scalar's range said on stderr with its key and the range.

use std::path::Path;
use std::process::Command;

use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::{Scene, TechniqueScene};
use arbvis::techniques::cellproj::prepare::prepare;
use arbvis::techniques::cellproj::IsovalueUnits;

use crate::common::{headless, temp_dir};

fn post_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data/post.toml");
    let mut scene = Scene::load(&path).unwrap();
    scene.size = [120, 90];
    scene
}

#[test]
fn data_and_normalized_units_draw_the_same_surfaces() {
    let h = headless(Backend::Egl);
    let mut scene = post_scene();
    let TechniqueScene::Cellproj(c) = &mut scene.technique else {
        panic!("post.toml draws cell projection");
    };
    // Uneven values in Pressure's units (0.3554..1.641), not the scene's round ones.
    let data = [0.83, 1.17, 1.52];
    for (iso, v) in c.isovalues.iter_mut().zip(data) {
        iso.value = v;
    }
    assert_eq!(c.isovalue_units, IsovalueUnits::Data);
    let range = prepare(c, &scene.base).unwrap().scalar_range;
    assert!((range[0] - 0.35537).abs() < 1e-5 && (range[1] - 1.64124).abs() < 1e-5);
    let in_data = render_on(&h, &scene).unwrap().image;

    let mut normalized = scene.clone();
    let TechniqueScene::Cellproj(n) = &mut normalized.technique else {
        unreachable!()
    };
    n.isovalue_units = IsovalueUnits::Normalized;
    for (iso, v) in n.isovalues.iter_mut().zip(data) {
        iso.value = (v - range[0]) / (range[1] - range[0]);
    }
    let in_normalized = render_on(&h, &normalized).unwrap().image;
    // The same normalized numbers reach the programs: the same picture, bit for bit.
    assert_eq!(in_data, in_normalized);

    // And the units matter: the data values read as normalized ones (all above 0.8 of
    // the range or beyond it) draw another picture.
    let TechniqueScene::Cellproj(n) = &mut normalized.technique else {
        unreachable!()
    };
    n.isovalues
        .iter_mut()
        .zip(data)
        .for_each(|(iso, v)| iso.value = v);
    let misread = render_on(&h, &normalized).unwrap().image;
    // Over one 8-bit level counts as a different pixel.
    let d = misread.compare(&in_data, crate::common::LEVEL).unwrap();
    assert!(d.pixels_over > 500, "{d:?}");
}

#[test]
fn a_value_outside_the_range_is_said_with_its_key() {
    let dir = temp_dir("isovalue-outside");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data/post.toml"),
    )
    .unwrap()
    .replace("{ value = 0.7,", "{ value = 1.8,")
    .replace(
        "../../data/",
        &format!("{}/data/", env!("CARGO_MANIFEST_DIR")),
    );
    std::fs::write(dir.join("post.toml"), &text).unwrap();
    let run = |scene: &str| {
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .args(["render", scene, "--size", "48x36", "-o"])
            .arg(dir.join("out.png"))
            .current_dir(&dir)
            .output()
            .unwrap()
    };
    let out = run("post.toml");
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The line docs/cellproj.md shows, word for word.
    let want = "arbvis: warning: technique.cellproj.isovalues.0.value = 1.8 lies outside the scalar's range 0.3554..1.641 (the scalar's units; isovalue_units = \"data\"): it draws nothing";
    assert!(stderr.contains(want), "{stderr}");
    let docs =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/cellproj.md"))
            .unwrap();
    assert!(
        docs.contains(want),
        "docs/cellproj.md shows the warning as printed"
    );
    assert_eq!(stderr.matches("warning").count(), 1, "{stderr}");

    // In range: no warning. Normalized and outside 0..1: said in normalized units.
    std::fs::write(
        dir.join("inside.toml"),
        text.replace("{ value = 1.8,", "{ value = 1.6,"),
    )
    .unwrap();
    let out = run("inside.toml");
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    std::fs::write(
        dir.join("normalized.toml"),
        text.replace(
            "shading = true",
            "shading = true\nisovalue_units = \"normalized\"",
        ),
    )
    .unwrap();
    let stderr = String::from_utf8_lossy(&run("normalized.toml").stderr).into_owned();
    for want in [
        "isovalues.0.value = 1.8 lies outside the scalar's range 0..1 (normalized",
        "isovalues.2.value = 1.3 lies outside",
    ] {
        assert!(stderr.contains(want), "{want} not in {stderr}");
    }
    assert!(
        !stderr.contains("isovalues.1."),
        "1.0 is the range's end: {stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
