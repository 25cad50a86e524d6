//! Legends and axes in offscreen pictures (`render --legend --axes`, a scene's `legend`
//! and `axes`): the colour bar holds the table's own colours, labels and axes are drawn,
//! untouched pixels keep a float target's precision, and nothing is drawn unless asked.

use std::process::Command;

use arbvis::annotate::first_bar;
use arbvis::gl::Backend;
use arbvis::png_io::read_png;
use arbvis::render::{build, render_on};
use arbvis::scene::{Fidelity, Scene};
use arbvis::techniques::annotations::Legend;

use crate::common::{headless, opacity3d, stdout_of, temp_dir};

fn pixel(image: &arbvis::image::Image, x: i32, y: i32) -> [f32; 4] {
    let i = 4 * (y as usize * image.width as usize + x as usize);
    image.data[i..i + 4].try_into().unwrap()
}

#[test]
fn the_legend_bar_holds_the_tables_colours_and_the_axes_are_drawn() {
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("v3o2-sum").unwrap();
    scene.size = [330, 250];
    let plain = render_on(&h, &scene).unwrap().image;
    scene.legend = true;
    scene.axes = true;
    let annotated = render_on(&h, &scene).unwrap().image;
    // The first bar is the primary's table: column x shows entry x * 256 / width, exactly
    // (an 8-bit target holds k / 255; the overlay writes the table's bytes).
    let table = opacity3d(&scene).primary.table.build(&scene.base).unwrap();
    let [left, top, width, height] = first_bar(330, 250);
    for x in 0..width {
        let e = table.entries[(x * 256 / width) as usize];
        let got = pixel(&annotated, left + x, top + height / 2);
        let want = [e[0], e[1], e[2]].map(|c| c as f32 / 255.0);
        assert_eq!(&got[..3], &want, "bar column {x}");
        assert_eq!(got[3], 1.0);
    }
    // Titles, range labels and three axes with their ticks: many pixels changed, most
    // of the picture not.
    let changed = (0..annotated.data.len() / 4)
        .filter(|&p| annotated.data[4 * p..4 * p + 4] != plain.data[4 * p..4 * p + 4])
        .count();
    let all = 330 * 250;
    assert!(
        changed > all / 50 && changed < all / 3,
        "{changed} of {all}"
    );
    // Outside the legends' column, the axes changed pixels too.
    let axes = (0..all)
        .filter(|&p| (p % 330) < left as usize - 20)
        .filter(|&p| annotated.data[4 * p..4 * p + 4] != plain.data[4 * p..4 * p + 4])
        .count();
    assert!(axes > 300, "{axes} pixels of axes");
}

#[test]
fn a_float_picture_keeps_its_precision_where_nothing_is_drawn() {
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("v3o2-sum").unwrap();
    scene.size = [200, 160];
    scene.fidelity = Fidelity::Precise;
    let plain = render_on(&h, &scene).unwrap().image;
    scene.legend = true;
    let annotated = render_on(&h, &scene).unwrap().image;
    let n = plain.data.len() / 4;
    let mut fractional = 0;
    for p in 0..n {
        let (a, b) = (
            &annotated.data[4 * p..4 * p + 4],
            &plain.data[4 * p..4 * p + 4],
        );
        if a != b {
            // A drawn pixel: opaque.
            assert_eq!(a[3], 1.0);
        } else if b[..3].iter().any(|v| (v * 255.0).fract().abs() > 1e-3) {
            fractional += 1;
        }
    }
    // The untouched pixels are the float target's own, not rounded to 8 bits.
    assert!(fractional > n / 4, "{fractional} of {n}");
}

#[test]
fn each_technique_says_its_tables_and_keys() {
    let h = headless(Backend::Egl);
    let load = |name: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
        Scene::load(&path).unwrap()
    };
    let kind = arbvis::gl::ProgramKind::Glsl;
    // The oxygen post: its isovalues in Pressure's units, with their colours.
    let post = load("scenes/data/post.toml");
    let a = build(h.gpu(), &post, kind).unwrap().annotations();
    let Legend::Keys { title, keys } = &a.legends[0] else {
        panic!("{a:?}")
    };
    assert_eq!(title, "isovalues: Pressure");
    let labels: Vec<&str> = keys.iter().map(|k| k.1.as_str()).collect();
    assert_eq!(labels, ["0.7", "1", "1.3"]);
    assert_eq!(keys[0].0, [51, 102, 255]);
    // Its axes in the file's coordinates: x, y, z over the mesh's bounds.
    let axes = &a.axes.as_ref().unwrap().axes;
    let names: Vec<&str> = axes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["x", "y", "z"]);
    // F3: amplitude over its 1-99 % range, and inline / crossline / time axes.
    let f3 = load("scenes/data/f3.toml");
    let a = build(h.gpu(), &f3, kind).unwrap().annotations();
    let Legend::Bar {
        title, low, high, ..
    } = &a.legends[0]
    else {
        panic!("{a:?}")
    };
    assert_eq!(title, "primary: amplitude");
    assert!(
        *low < 0.0 && *high > 0.0 && low.abs() < 10239.0,
        "{low} {high}"
    );
    let axes = &a.axes.as_ref().unwrap().axes;
    let names: Vec<&str> = axes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["time (ms)", "crossline", "inline"]);
    assert_eq!(axes[2].label(0), "111");
    // A lidar tile coloured by elevation: a bar over its z range, x/y/z axes.
    let mut autzen = load("scenes/data/autzen.toml");
    if let arbvis::scene::TechniqueScene::Splats(s) = &mut autzen.technique {
        s.colour = arbvis::techniques::splats::scene::ColourMode::Elevation;
    }
    let a = build(h.gpu(), &autzen, kind).unwrap().annotations();
    let Legend::Bar {
        title, low, high, ..
    } = &a.legends[0]
    else {
        panic!("{a:?}")
    };
    assert_eq!(title, "elevation");
    assert!(high > low);
}

#[test]
fn the_command_line_draws_them_only_when_asked() {
    let dir = temp_dir("annotate-cli");
    let run = |args: &[&str], png: &str| {
        stdout_of(
            Command::new(env!("CARGO_BIN_EXE_arbvis"))
                .args([
                    "render", "--demo", "v3o2-sum", "--size", "160x120", "-o", png,
                ])
                .args(args)
                .current_dir(&dir),
        );
        read_png(&dir.join(png)).unwrap().0
    };
    let plain = run(&[], "plain.png");
    let with = run(&["--legend", "--axes"], "with.png");
    assert_ne!(plain, with);
    // The plain picture is the renderer's own, as before.
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("v3o2-sum").unwrap();
    scene.size = [160, 120];
    let own = scene.picture(&render_on(&h, &scene).unwrap().image);
    assert_eq!(plain, own);
    // A scene asks for them with legend = true and axes = true.
    let text = "legend = true\naxes = true\n".to_string()
        + include_str!("../../scenes/demo/v3o2-sum.toml");
    let scene = Scene::parse(&text, "keys").unwrap();
    assert!(scene.legend && scene.axes);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A layered scene's axes are the first visible layer's box with that layer's placement:
/// a cube moved into the left of a frame it shares with a small horizon (hidden, but in
/// the frame) gets its axes around where it is drawn, not around the frame's middle.
#[test]
fn a_layered_scenes_axes_follow_their_layer() {
    let h = headless(Backend::Egl);
    let text = "size = [240, 180]\n[camera]\nrotation = [-0.483, -0.1294, -0.2241, 0.8365]\n\
                [[layer]]\nname = \"cube\"\n[layer.opacity3d.primary]\n\
                volume = { synthetic = { size = [19, 13, 17], seed = 4 } }\nattribute = \"amplitude\"\n\
                [[layer]]\nname = \"horizon\"\nvisible = false\noffset = [30.0, 0.0, 205.0]\nscale = 0.2\n\
                [layer.surface]\nsynthetic = { size = [3, 3], seed = 1 }\n";
    let mut scene = Scene::parse(text, "axes.toml").unwrap();
    let plain = render_on(&h, &scene).unwrap().image;
    scene.axes = true;
    let annotated = render_on(&h, &scene).unwrap().image;
    let width = plain.width as usize;
    // Bounding boxes (x0, y0, x1, y1) of the pixels a test picks.
    let bbox = |keep: &dyn Fn(usize) -> bool| {
        let mut b = [i64::MAX, i64::MAX, i64::MIN, i64::MIN];
        for p in (0..plain.data.len() / 4).filter(|&p| keep(p)) {
            let (x, y) = ((p % width) as i64, (p / width) as i64);
            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
        }
        b
    };
    let cube = bbox(&|p| plain.data[4 * p..4 * p + 3].iter().any(|&v| v > 0.02));
    let axes = bbox(&|p| annotated.data[4 * p..4 * p + 4] != plain.data[4 * p..4 * p + 4]);
    assert!(
        (cube[0] + cube[2]) / 2 < 90,
        "the cube is drawn in the left of the frame: {cube:?}"
    );
    // The axes run along three of the cube's box edges, their ticks and labels a few text
    // heights (about 10 pixels at 180 rows) outside: within the cube's bounds grown by 30
    // pixels. Drawn for the unplaced box (the cube alone, framed in the middle) they
    // reach the frame's right side, far past it.
    let grown = [cube[0] - 30, cube[1] - 30, cube[2] + 30, cube[3] + 30];
    assert!(
        axes[0] >= grown[0] && axes[1] >= grown[1] && axes[2] <= grown[2] && axes[3] <= grown[3],
        "axes {axes:?} outside the cube's {cube:?} grown by 30"
    );
    assert!(axes[2] - axes[0] > 40, "the axes are drawn: {axes:?}");
}
