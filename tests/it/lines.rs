//! Lines and wells (issue 57 item 3): a well's tube follows its minimum-curvature path and
//! is coloured by its log; tubes drawn against their f64 reference, ARB and GLSL,
//! faithful and precise; a well lies in a survey's world frame; bad files named by line.

use crate::common;

use arbvis::gl::{Backend, ProgramChoice, TargetFormat};
use arbvis::render::render_on;
use arbvis::scene::{Fidelity, Scene};
use arbvis::techniques::lines::{polylines, tubes, LinesScene};
use common::{headless, LEVEL};

/// The repository's synthetic well through F3 (`scripts/make_well.py`).
fn f3_well(extra: &str) -> String {
    format!(
        "[technique.lines]\nwell = {{ survey = \"{}\", head = [620420.0, 6074520.0], log = \"{}\" }}\nradius = 7.0\n{extra}",
        common::data_file("seismic/f3-well-survey.csv").display(),
        common::data_file("seismic/f3-well-log.csv").display()
    )
}

/// Each ring of the tube is centred on the well's path (every 2 m and at every station),
/// the path goes through the survey's stations where minimum curvature puts them, and
/// each ring's colour is the log's value there through the table.
#[test]
fn a_wells_tube_follows_its_path_and_its_log() {
    let scene = Scene::parse(&f3_well(""), "w.toml").unwrap();
    let params = scene.technique.get::<LinesScene>().unwrap();
    let lines = polylines(params, std::path::Path::new("")).unwrap();
    let path = &lines[0].points;
    // 0 to 330 m every 2 m, and the stations at odd multiples of 15 m: 166 + 11.
    assert_eq!(path.len(), 177);
    assert_eq!(path[0], [620420.0, 6074520.0, 0.0]);
    // Vertical to 60 m, then a build of 0.2 degrees per metre toward azimuth 125 to 36
    // degrees at 240 m: the arc's end lies R (1 - cos 36) across and R sin 36 down,
    // R = 1 / 0.2 degrees per metre.
    let r = 1.0 / 0.2f64.to_radians();
    let (across, down) = (
        r * (1.0 - 36f64.to_radians().cos()),
        r * 36f64.to_radians().sin(),
    );
    let at_240 = path.iter().find(|p| (p[2] + 60.0 + down).abs() < 1e-6);
    let p = at_240.expect("a point at the end of the build");
    let (east, north) = (p[0] - 620420.0, p[1] - 6074520.0);
    assert!((east.hypot(north) - across).abs() < 1e-6, "{east} {north}");
    assert!((north.atan2(east).to_degrees() - (90.0 - 125.0)).abs() < 1e-9);
    let (mesh, values) = tubes(&lines, 7.0, 8);
    for (i, point) in path.iter().enumerate() {
        let ring = &mesh.vertices[i * 8..i * 8 + 8];
        let centre: [f64; 3] =
            std::array::from_fn(|k| ring.iter().map(|v| v[k]).sum::<f64>() / 8.0);
        for k in 0..3 {
            // Eight points evenly round a circle average to its centre (f64, UTM: 1e-7).
            assert!((centre[k] - point[k]).abs() < 1e-7, "ring {i}");
        }
        assert!(ring.iter().all(|v| {
            let d = (0..3)
                .map(|k| (v[k] - point[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            (d - 7.0).abs() < 1e-7
        }));
        assert_eq!(values[i * 8], lines[0].values.as_ref().unwrap()[i]);
    }
}

/// The lines scene `text` drawn at `fidelity` with `programs` into a float target on
/// black, and its f64 reference.
pub fn drawn_and_reference(
    h: &arbvis::gl::Headless,
    text: &str,
    fidelity: Fidelity,
    programs: ProgramChoice,
) -> (arbvis::image::Image, arbvis::image::Image) {
    let mut scene = Scene::parse(text, "w.toml").unwrap();
    (scene.fidelity, scene.programs) = (fidelity, programs);
    scene.target = Some(TargetFormat::Rgba32f);
    scene.background = [0.0; 4];
    let gpu = render_on(h, &scene).unwrap().image;
    let limits = arbvis::volume::Limits::for_max_side(2048);
    let view = arbvis::techniques::ReferenceView {
        camera: scene.camera,
        size: scene.size,
        background: [0.0; 4],
        base: std::path::Path::new(""),
    };
    let cpu = arbvis::catalog::reference(&scene.technique, &scene.settings(), &limits, &view)
        .unwrap()
        .unwrap();
    (gpu, cpu)
}

/// A well's tube drawn on the GPU against the surface reference it is drawn as, at an odd
/// size and a rotated perspective camera: as the surface test bounds it.
#[test]
fn a_wells_tube_matches_its_reference() {
    let h = headless(Backend::Egl);
    for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
        for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
            let text = format!(
                "size = [71, 93]\n[camera]\nprojection = \"perspective\"\nrotation = [-0.35, 0.12, 0.2, 0.906]\n{}",
                // A thick tube: 60 m across a frame of the well's 300 m depth.
                f3_well("").replace("radius = 7.0", "radius = 30.0")
            );
            let (gpu, cpu) = drawn_and_reference(&h, &text, fidelity, programs);
            // Precise: the surface programs' per-pixel headlight in f32 against f64 (measured
            // 1.2e-4 at most); a pixel whose centre lies within f32 rounding of a triangle's
            // edge may take the other triangle or the background: 1 % of the pixels over a
            // level at most. Faithful lights each vertex and interpolates, against the
            // per-pixel reference: the RMSE the ring's 8 sides allow (measured 0.0026).
            let d = gpu.compare(&cpu, LEVEL).unwrap();
            let pixels = (71 * 93) as usize;
            let lit = common::lit_pixels(&gpu, 0.05);
            // A tube 60 m across and 300 m long in perspective: about 4 % of the picture.
            assert!(
                lit > pixels / 40,
                "{fidelity:?} {programs:?}: the well is in view ({lit})"
            );
            match fidelity {
                Fidelity::Precise => assert!(
                    d.pixels_over * 50 < pixels && d.rmse < 0.01,
                    "{programs:?}: {d:?}"
                ),
                Fidelity::Faithful => assert!(d.rmse < 0.05, "{programs:?}: {d:?}"),
            }
        }
    }
}

/// In a layered scene with F3, the well starts at the survey's top, in its map area, and
/// reaches the depth its survey says (z = -301 m at 330 m, lined up with 301 ms).
#[test]
fn a_well_lies_in_the_surveys_world() {
    let text = format!(
        "[[layer]]\nname = \"F3\"\n[layer.opacity3d.primary]\nvolume = {{ segy = \"{}\" }}\n[[layer]]\nname = \"well\"\n{}",
        common::data_file("seismic/f3.sgy").display(),
        f3_well("").replace("[technique.lines]", "[layer.lines]")
    );
    let scene = Scene::parse(&text, "w.toml").unwrap();
    let limits = arbvis::volume::Limits::for_max_side(2048);
    let bounds: Vec<_> = scene
        .layers()
        .map(|(_, t)| {
            let data = arbvis::catalog::prepare(t, &scene.settings(), &limits).unwrap();
            arbvis::catalog::world(t, &data).unwrap().bounds()
        })
        .collect();
    let ([slo, shi], [wlo, whi]) = (bounds[0], bounds[1]);
    for k in 0..2 {
        assert!(
            wlo[k] > slo[k] && whi[k] < shi[k],
            "inside the survey's map area"
        );
    }
    // The tube's top ring at z = 0 and radius 7 (its ends are open rings).
    assert!((whi.z - 0.0).abs() < 7.0 + 1e-6);
    let tvd =
        60.0 + 36f64.to_radians().sin() / 0.2f64.to_radians() + 90.0 * 36f64.to_radians().cos();
    assert!((wlo.z + tvd).abs() < 7.0 + 1e-6, "{} {tvd}", wlo.z);
}

/// A survey or a log that is not one is named by its file, line and column; a scene
/// with both a file and a well, or neither, by its key.
#[test]
fn bad_lines_are_refused_where_they_are() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("lines-bad");
    std::fs::write(dir.join("s.csv"), "MD,INC,AZI\n0,0,0\n10,5,0\n20,4\n").unwrap();
    std::fs::write(dir.join("p.csv"), "0 0 0 1\n1 1 1 2\n").unwrap();
    let text = format!(
        "[technique.lines]\nwell = {{ survey = \"{}\", head = [0.0, 0.0] }}\n",
        dir.join("s.csv").display()
    );
    let e = render_on(&h, &Scene::parse(&text, "l.toml").unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("s.csv") && e.contains("line 4"), "{e}");
    let both = format!(
        "[technique.lines]\nfile = \"{}\"\nwell = {{ survey = \"x.csv\", head = [0.0, 0.0] }}\n",
        dir.join("p.csv").display()
    );
    let e = Scene::parse(&both, "l.toml").unwrap_err().to_string();
    assert!(
        e.contains("technique.lines.file") && e.contains("one of them"),
        "{e}"
    );
    let e = Scene::parse("[technique.lines]\nradius = 0.0\n", "l.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("technique.lines"), "{e}");
    // Stations in the scene are checked as a survey file's rows, by their number.
    let text = "[technique.lines]\nwell = { head = [0.0, 0.0], stations = [[0.0, 0.0, 0.0], [100.0, 5.0, 0.0], [90.0, 6.0, 0.0]] }\n";
    let e = render_on(&h, &Scene::parse(text, "l.toml").unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("well.stations") && e.contains("station 3") && e.contains("increasing"),
        "{e}"
    );
    let fine = format!(
        "[technique.lines]\nfile = \"{}\"\nradius = 0.1\n",
        dir.join("p.csv").display()
    );
    assert!(render_on(&h, &Scene::parse(&fine, "l.toml").unwrap()).is_ok());
}

/// `arbvis inspect` of lines files (the reader registry's `.csv`): the F3 well's survey
/// is a build-and-hold well whose end the textbook's arc formulas give (vertical to 60 m,
/// a 2-degree-per-10-m build to 36 degrees at 240 m, radius 180 / 0.6283 = 286.48 m, then
/// 90 m held: true vertical depth 60 + R sin 36 + 90 cos 36 = 301.20, displacement
/// R (1 - cos 36) + 90 sin 36 = 107.61 toward azimuth 125), its log's rows and range, and
/// polylines with their length.
#[test]
fn inspect_tells_a_survey_a_log_and_polylines_apart() {
    let said = common::inspect(&common::data_file("seismic/f3-well-survey.csv"));
    common::assert_says(
        &said,
        &[
            "read as a deviation survey (by its first line of names)",
            "stations: 23, measured depth 0 to 330",
            "largest inclination: 36.00 degrees at measured depth 240",
            "largest dogleg: 6.00 degrees per 30",
            "88.15 east, -61.72 north of the wellhead, true vertical depth 301.20",
            "horizontal displacement: 107.61",
        ],
    );
    let said = common::inspect(&common::data_file("seismic/f3-well-log.csv"));
    common::assert_says(
        &said,
        &[
            "read as a log",
            "rows: 661, measured depth 0 to 330",
            "(0 rows without a value)",
        ],
    );
    let dir = common::temp_dir("lines-inspect");
    let file = dir.join("faults.csv");
    std::fs::write(
        &file,
        "x,y,z,throw\n0,0,0,1\n3,4,0,2\n\n10,0,0,nan\n10,0,12,5\n",
    )
    .unwrap();
    common::assert_says(
        &common::inspect(&file),
        &[
            "read as polylines",
            "lines: 2, points: 4, length 17.00",
            "bounds: [0.0, 0.0, 0.0] .. [10.0, 4.0, 12.0]",
            "values: 1 to 5",
        ],
    );
}

/// Lines and a well's log given in the scene itself (`polylines = [...]`, `log_rows =
/// [...]`; what Python's arrays become) draw exactly the pictures of their files; bad
/// points are refused by their key (line and point from 0).
#[test]
fn lines_and_a_log_typed_in_the_scene_draw_as_their_files() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("lines-inline");
    // Two uneven lines, values on each point, one without (nan).
    let lines = [
        vec![
            [0.0, 0.0, 0.0, 1.5],
            [40.0, 10.0, -5.0, 2.0],
            [70.0, 45.0, -20.0, f64::NAN],
        ],
        vec![[10.0, 60.0, -30.0, 4.0], [35.0, 80.0, -12.5, 0.25]],
    ];
    let csv: String = lines
        .iter()
        .map(|l| {
            l.iter()
                .map(|p| format!("{},{},{},{}\n", p[0], p[1], p[2], p[3]))
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(dir.join("l.csv"), csv).unwrap();
    let typed: Vec<String> = lines
        .iter()
        .map(|l| {
            let points: Vec<String> = l
                .iter()
                .map(|p| {
                    format!(
                        "[{:?}, {:?}, {:?}, {}]",
                        p[0],
                        p[1],
                        p[2],
                        if p[3].is_nan() {
                            "nan".to_string()
                        } else {
                            format!("{:?}", p[3])
                        }
                    )
                })
                .collect();
            format!("[{}]", points.join(", "))
        })
        .collect();
    let head = "size = [64, 48]\nfidelity = \"precise\"\n[camera]\nrotation = [0.31, -0.22, 0.12, 0.917]\n[technique.lines]\nradius = 4.0\n";
    let draw = |text: &str| {
        render_on(&h, &Scene::parse(text, "l.toml").unwrap())
            .unwrap()
            .image
    };
    let from_file = draw(&format!(
        "{head}file = \"{}\"\n",
        dir.join("l.csv").display()
    ));
    let typed_in = draw(&format!("{head}polylines = [{}]\n", typed.join(", ")));
    assert_eq!(from_file.compare(&typed_in, 0.0).unwrap().pixels_over, 0);
    assert!(
        common::lit_pixels(&from_file, 0.05) > 100,
        "the lines are in view"
    );
    // The F3 well's log as rows, against its file.
    let log = arbvis::lines::read_log(&common::data_file("seismic/f3-well-log.csv")).unwrap();
    let rows: Vec<String> = log.iter().map(|(m, v)| format!("[{m:?}, {v:?}]")).collect();
    let well = |log: &str| {
        format!(
            "size = [64, 48]\n[technique.lines]\nwell = {{ survey = \"{}\", head = [620420.0, 6074520.0], {log} }}\nradius = 7.0\n",
            common::data_file("seismic/f3-well-survey.csv").display()
        )
    };
    let file_log = format!(
        "log = \"{}\"",
        common::data_file("seismic/f3-well-log.csv").display()
    );
    let a = draw(&well(&file_log));
    let b = draw(&well(&format!("log_rows = [{}]", rows.join(", "))));
    assert_eq!(a.compare(&b, 0.0).unwrap().pixels_over, 0);
    // Refusals by key.
    for (polylines, key, says) in [
        (
            "[[[0.0, 0.0, 0.0], [1.0, 1.0]]]",
            "polylines.0.1",
            "2 numbers",
        ),
        (
            "[[[0.0, 0.0, 0.0]], [[1.0, 1.0, 1.0], [2.0, inf, 0.0]]]",
            "polylines.1.1",
            "finite",
        ),
        ("[[[0.0, 0.0, 0.0]]]", "polylines", "two points"),
    ] {
        let e = render_on(
            &h,
            &Scene::parse(&format!("{head}polylines = {polylines}\n"), "l.toml").unwrap(),
        )
        .err()
        .expect("refused")
        .to_string();
        assert!(e.contains(key) && e.contains(says), "{polylines}: {e}");
    }
    let e = Scene::parse(
        &format!("{head}polylines = [[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]]\nfile = \"l.csv\"\n"),
        "l.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("one of them"), "{e}");
}
