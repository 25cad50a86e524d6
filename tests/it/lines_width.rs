//! Lines as wide as a number of pixels or metres, as tubes or ribbons (issue 57 item 3):
//! the band a line covers on the picture, measured column by column, at several zooms,
//! both projections and turned cameras; ribbons against their f64 reference; a session
//! turned through views reshapes them as a fresh render would.

use crate::common;

use arbvis::gl::{Backend, ProgramChoice};
use arbvis::image::Image;
use arbvis::render::render_on;
use arbvis::scene::{Fidelity, Scene};
use common::{headless, LEVEL};
use glam::DQuat;

/// A straight line 1000 m long along x (three points, unevenly spaced), through the
/// frame's centre, drawn in the constant colour on black.
fn straight_line(camera: &str, style: &str, width: &str) -> Scene {
    let text = format!(
        "size = [97, 61]\nfidelity = \"precise\"\n[camera]\n{camera}\n[technique.lines]\npolylines = [[[0.0, 0.0, 0.0], [380.0, 0.0, 0.0], [1000.0, 0.0, 0.0]]]\nstyle = \"{style}\"\nwidth = {width}\nsides = 32\n"
    );
    let mut scene = Scene::parse(&text, "w.toml").unwrap();
    scene.background = [0.0; 4];
    scene
}

/// The lit pixels of each column from `x0` to `x1`.
fn column_counts(image: &Image, x0: u32, x1: u32) -> Vec<usize> {
    (x0..x1)
        .map(|x| {
            (0..image.height)
                .filter(|&y| image.pixel(x, y)[..3].iter().sum::<f32>() > 0.05)
                .count()
        })
        .collect()
}

/// `[x, y, z, w]` of a turn of `degrees` about `axis`.
fn turn(axis: glam::DVec3, degrees: f64) -> String {
    let q = DQuat::from_axis_angle(axis, degrees.to_radians()).to_array();
    format!("rotation = {q:?}")
}

/// A band of width w (pixels) covers, in a column it crosses at angle a to the
/// horizontal, the pixel centres of an interval w / cos a long: the floor or the ceiling
/// of that count (a tube's silhouette of 32 sides spans w cos(pi/32) to w). Zooms 0.6 to
/// 2.5 (the line from 37 to 97 pixels long), orthographic turned about x and z, and
/// perspective turned about y (the line recedes: its far end deeper than its near).
#[test]
fn a_width_in_pixels_holds_at_every_zoom_and_along_the_line() {
    let h = headless(Backend::Egl);
    let cameras = [
        (turn(glam::DVec3::X, 40.0), 0.0, "orthographic"),
        (turn(glam::DVec3::Z, 25.0), 25.0, "orthographic"),
        (turn(glam::DVec3::Y, 50.0), 0.0, "perspective"),
    ];
    for (rotation, tilt, projection) in &cameras {
        for zoom in [0.6, 1.0, 2.5] {
            for (style, width) in [("ribbon", 5.0), ("ribbon", 7.5), ("tube", 6.0)] {
                let camera = format!("projection = \"{projection}\"\n{rotation}\nzoom = {zoom}");
                let scene = straight_line(&camera, style, &format!("{{ pixels = {width} }}"));
                let image = render_on(&h, &scene).unwrap().image;
                let across = width / f64::cos(f64::to_radians(*tilt));
                let low = match style {
                    "tube" => across * (std::f64::consts::PI / 32.0).cos(),
                    _ => across,
                };
                // Columns within 5 pixels of the centre: on the line at every zoom (23
                // pixels long at zoom 0.6 in perspective, turned 50 degrees).
                for (k, &count) in column_counts(&image, 43, 54).iter().enumerate() {
                    assert!(
                        (low.floor() as usize..=across.ceil() as usize).contains(&count),
                        "{projection} {rotation} zoom {zoom} {style} {width} px: column {} covers {count}, want {low:.2} to {across:.2}",
                        43 + k
                    );
                }
            }
        }
    }
}

/// A ribbon 40 m across, orthographic: on the picture its width in the frame (40 m over
/// the frame's 520 m half-side: the points' box widened by half the width) times the zoom
/// times half the picture's height, floor or ceiling; so it widens with the zoom.
#[test]
fn a_width_in_metres_grows_with_the_zoom() {
    let h = headless(Backend::Egl);
    for zoom in [0.9, 1.7, 2.5] {
        let camera = format!(
            "projection = \"orthographic\"\n{}\nzoom = {zoom}",
            turn(glam::DVec3::X, 40.0)
        );
        let scene = straight_line(&camera, "ribbon", "{ metres = 40.0 }");
        let image = render_on(&h, &scene).unwrap().image;
        let want: f64 = 40.0 / 520.0 * zoom * 61.0 / 2.0;
        for count in column_counts(&image, 38, 59) {
            assert!(
                (want.floor() as usize..=want.ceil() as usize).contains(&count),
                "zoom {zoom}: {count} pixels, want {want:.2}"
            );
        }
    }
}

/// The F3 well as a ribbon, in metres and in pixels, at an odd size and a turned
/// perspective camera, against the f64 reference drawing the same band: unlit, so both
/// fidelities draw the colours as given, interpolated along the band.
#[test]
fn ribbons_match_their_reference() {
    let h = headless(Backend::Egl);
    let well = format!(
        "[technique.lines]\nwell = {{ survey = \"{}\", head = [620420.0, 6074520.0], log = \"{}\" }}\nstyle = \"ribbon\"\n",
        common::data_file("seismic/f3-well-survey.csv").display(),
        common::data_file("seismic/f3-well-log.csv").display()
    );
    for width in ["{ metres = 50.0 }", "{ pixels = 6.0 }"] {
        for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
            for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
                let text = format!(
                    "size = [71, 93]\n[camera]\nprojection = \"perspective\"\nrotation = [-0.35, 0.12, 0.2, 0.906]\n{well}width = {width}\n"
                );
                let (gpu, cpu) = crate::lines::drawn_and_reference(&h, &text, fidelity, programs);
                let d = gpu.compare(&cpu, LEVEL).unwrap();
                let pixels = 71 * 93;
                let lit = common::lit_pixels(&gpu, 0.05);
                assert!(
                    lit > 150,
                    "{width} {fidelity:?} {programs:?}: in view ({lit})"
                );
                // The colours are the table's at each point, linear between points in both;
                // a pixel whose centre lies within f32 rounding of the band's edge may be
                // in on one side and out on the other: 1 % of the pixels over a level.
                assert!(
                    d.pixels_over * 100 < pixels && d.rmse < 0.02,
                    "{width} {fidelity:?} {programs:?}: {d:?}"
                );
            }
        }
    }
}

/// One session turned through five views reshapes a ribbon in pixels for each, as a
/// fresh render of that view draws it (exactly: the same shape, the same programs).
#[test]
fn a_ribbon_turned_by_one_session_draws_each_view_as_a_fresh_render() {
    let scene = straight_line(
        "projection = \"perspective\"\nzoom = 1.3",
        "ribbon",
        "{ pixels = 4.0 }",
    );
    let pairs = crate::session::turned_and_fresh(scene);
    crate::session::assert_each_view_equal(&pairs, "ribbon");
}

/// Widths and styles that are not ones are refused by key.
#[test]
fn bad_widths_and_styles_are_refused_by_key() {
    for (line, key, says) in [
        ("width = { pixels = 0.0 }", "width.pixels", "above 0"),
        (
            "width = { pixels = 5000.0 }",
            "width.pixels",
            "at most 1024",
        ),
        ("width = { metres = -3.0 }", "width.metres", "above 0"),
        ("width = { inches = 3.0 }", "inches", "metres` or `pixels"),
        ("style = \"dotted\"", "`tube` or `ribbon`", "dotted"),
    ] {
        let text = format!(
            "[technique.lines]\npolylines = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]]\n{line}\n"
        );
        let e = Scene::parse(&text, "l.toml").unwrap_err().to_string();
        assert!(e.contains(key) && e.contains(says), "{line}: {e}");
    }
}
