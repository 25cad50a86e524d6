//! The `arbvis` binary as a user runs it: the README's main job, `info`, `--stats`,
//! and bad input that ends in a clear error and no output file.

use std::path::PathBuf;
use std::process::{Command, Output};

use arbvis::png_io::read_png;
use common::temp_dir;

use crate::common;

fn arbvis(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(args)
        .output()
        .unwrap()
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `arbvis render --demo quad -o DIR/FILE ARGS...` in a fresh temporary folder; returns
/// the command's output, the folder and the PNG path.
fn render_quad(name: &str, file: &str, args: &[&str]) -> (Output, PathBuf, PathBuf) {
    let dir = temp_dir(name);
    let png = dir.join(file);
    let mut all = vec!["render", "--demo", "quad", "-o", png.to_str().unwrap()];
    all.extend_from_slice(args);
    (arbvis(&all), dir, png)
}

#[test]
fn demo_render_writes_png_with_provenance() {
    let (out, dir, png) = render_quad("demo", "quad.png", &["--size", "96x64", "--stats"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("3 resources"), "{stdout}");
    let (img, chunks) = read_png(&png).unwrap();
    assert_eq!((img.width, img.height), (96, 64));
    let get = |k: &str| {
        chunks
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.as_str())
            .unwrap_or("")
    };
    assert_eq!(get("arbvis:technique"), "quad");
    assert_eq!(
        get("arbvis:programs"),
        "arb",
        "auto picks ARB on a driver that has it"
    );
    assert_eq!(get("arbvis:target"), "rgba8");
    assert!(!get("arbvis:renderer").is_empty());
    assert!(get("arbvis:scene").contains("[technique.quad]"));
    // No temporary file is left beside the output.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn float_target_writes_sixteen_bit_png() {
    let (out, dir, png) = render_quad(
        "float",
        "quad16.png",
        &["--size", "8x8", "--fidelity", "precise"],
    );
    assert!(out.status.success(), "{}", text(&out).1);
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let reader = decoder.read_info().unwrap();
    assert_eq!(reader.info().bit_depth, png::BitDepth::Sixteen);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn info_reports_arb_support_and_limits() {
    let out = arbvis(&["info"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    for field in [
        "GL_RENDERER:",
        "GL_VERSION:",
        "profile:",
        "software renderer:",
        "instructions:",
        "temporaries:",
        "texture indirections:",
        "linear filtering:",
        "interpolation:",
    ] {
        assert!(stdout.contains(field), "missing {field}:\n{stdout}");
    }
    // Mesa's llvmpipe (what CI has) offers both ARB program extensions in the compat profile.
    if stdout.contains("llvmpipe") {
        assert!(stdout.contains("GL_ARB_fragment_program: yes"), "{stdout}");
        assert!(stdout.contains("GL_ARB_vertex_program:   yes"), "{stdout}");
        assert!(
            stdout.contains("profile:                 compatibility"),
            "{stdout}"
        );
        assert!(stdout.contains("software renderer:       yes"), "{stdout}");
        // llvmpipe filters in f32 and interpolates from the true vertices: the probes
        // find both exact to rounding.
        assert!(stdout.contains("linear filtering:        f32"), "{stdout}");
        assert!(
            stdout.contains("interpolation:           from the true vertices"),
            "{stdout}"
        );
    }
    let json = arbvis(&["info", "--json", "--backend", "osmesa"]);
    let (j, _) = text(&json);
    assert!(json.status.success(), "{j}");
    // Real JSON, the limits nested (no repeated keys), the backend named.
    let v: serde_json::Value = serde_json::from_str(&j).unwrap();
    assert_eq!(v["backend"], "osmesa");
    assert!(v["arb_fragment_program"].is_boolean());
    assert!(v["fragment_limits"]["native_tex_indirections"].is_number());
    assert!(v["vertex_limits"]["native_instructions"].is_number());
    assert!(v["linear_filter_error"].is_number(), "{j}");
    assert!(v["interpolation_error"].is_number(), "{j}");
}

#[test]
fn bad_scene_names_file_line_column_and_writes_nothing() {
    let dir = temp_dir("bad");
    let scene = dir.join("bad.toml");
    std::fs::write(
        &scene,
        "size = [64, 64]\n[technique.quad]\nleft = [1.0, 0.0]x\n",
    )
    .unwrap();
    let png = dir.join("out.png");
    let out = arbvis(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    let (_, stderr) = text(&out);
    assert!(!out.status.success());
    assert!(stderr.contains("bad.toml:3:"), "{stderr}");
    assert!(!png.exists(), "no output on error");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_demo_lists_the_demos() {
    let out = arbvis(&["render", "--demo", "nope", "-o", "/tmp/never.png"]);
    let (_, stderr) = text(&out);
    assert!(!out.status.success());
    assert!(
        stderr.contains("nope") && stderr.contains("quad"),
        "{stderr}"
    );
}

#[test]
fn demo_without_a_name_lists_the_demos_as_an_answer() {
    for command in ["render", "bench"] {
        let out = arbvis(&[command, "--demo"]);
        let (stdout, stderr) = text(&out);
        assert!(out.status.success(), "{command} --demo: {stderr}");
        let listed: Vec<&str> = stdout.lines().collect();
        let demos: Vec<&str> = arbvis::scene::demos().map(|d| d.0).collect();
        assert_eq!(
            listed, demos,
            "{command} --demo lists every demo, one a line"
        );
    }
    // The help names every demo (its list is the catalog's).
    let (help, _) = text(&arbvis(&["render", "--help"]));
    for (name, _) in arbvis::scene::demos() {
        assert!(help.contains(name), "render --help lacks {name}:\n{help}");
    }
    // A render with a demo but no output says what is missing.
    let out = arbvis(&["render", "--demo", "quad"]);
    assert!(!out.status.success());
    assert!(text(&out).1.contains("-o OUT.png"), "{}", text(&out).1);
}

#[test]
fn unwritable_output_is_a_clear_error() {
    let out = arbvis(&[
        "render",
        "--demo",
        "quad",
        "--size",
        "8x8",
        "-o",
        "/nonexistent-dir/x.png",
    ]);
    let (_, stderr) = text(&out);
    assert!(!out.status.success());
    assert!(stderr.contains("/nonexistent-dir"), "{stderr}");
}

#[test]
fn bad_size_flag_is_rejected() {
    let out = arbvis(&[
        "render",
        "--demo",
        "quad",
        "--size",
        "0x10",
        "-o",
        "/tmp/never.png",
    ]);
    assert!(!out.status.success());
    assert!(text(&out).1.contains("1..=16384"));
}

#[test]
fn missing_osmesa_library_is_named_with_a_hint() {
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["info", "--backend", "osmesa"])
        .env("ARBVIS_OSMESA_LIBRARY", "libOSMesa-not-here.so.99")
        .output()
        .unwrap();
    let (_, stderr) = text(&out);
    assert!(!out.status.success());
    assert!(
        stderr.contains("libOSMesa-not-here.so.99") && stderr.contains("libosmesa6"),
        "{stderr}"
    );
}

#[test]
fn study_writes_csv_and_plot_and_bench_times() {
    // A small sweep (16³ volume, 32², two slice counts): the full study is a benchmark.
    let dir = temp_dir("study");
    let out = arbvis(&[
        "study",
        "--volume",
        "16",
        "--size",
        "32",
        "--slices",
        "8,32",
        "--frames",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    let csv = std::fs::read_to_string(dir.join("opacity3d.csv")).unwrap();
    // Per slice count and program kind: 1 faithful + 3 targets x 2 corrections = 7.
    assert_eq!(csv.lines().count(), 1 + 2 * 2 * 7, "{csv}");
    for line in csv.lines().skip(1) {
        let rmse: f64 = line.split(',').nth(7).unwrap().parse().unwrap();
        assert!(rmse.is_finite() && rmse >= 0.0, "{line}");
    }
    let (plot, _) = read_png(&dir.join("opacity3d.png")).unwrap();
    assert_eq!((plot.width, plot.height), (1100, 700));
    assert!(stdout.contains("wrote"), "{stdout}");
    // No peer figure written in the code: the summary names no VTK time (it once printed
    // "(1.2x VTK's 1260 ms)" from a constant) and says how to measure one here instead.
    let peer_times: Vec<&str> = stdout
        .lines()
        .filter(|l| l.contains("VTK") && (l.contains(" ms") || l.contains("1260")))
        .collect();
    assert!(peer_times.is_empty(), "{peer_times:?}");
    assert!(
        stdout.contains("benches/peers/vtk_volume.py") && stdout.contains("--from run.json"),
        "{stdout}"
    );
    // stderr is a pipe here: lines, never a bar (no carriage returns, no escapes).
    assert_no_bar(&stderr);
    assert!(stderr.contains("slices"), "{stderr}");
    // bench times any scene; for 3D opacity it sweeps, scores and exports for a peer.
    let export = dir.join("peer");
    let bench = arbvis(&[
        "bench",
        "--demo",
        "v3o2-product",
        "--size",
        "16x12",
        "--faithful",
        "4",
        "--precise",
        "4,8",
        "--raycast",
        "0.5",
        "--frames",
        "2",
        "--rounds",
        "2",
        "--score",
        "--oversample",
        "2",
        "--json",
        "--export",
        export.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&bench);
    assert!(bench.status.success(), "{stderr}");
    for key in [
        "\"faithful slicing 4\"",
        "\"precise slicing 8\"",
        "\"raycast 0.5 step/voxel\"",
        "\"median_ms\"",
        "\"rmse\"",
    ] {
        assert!(stdout.contains(key), "{key} in {stdout}");
    }
    for file in [
        "scene.json",
        "levels_primary.u8",
        "table_primary.u8",
        "reference.f32",
    ] {
        assert!(export.join(file).is_file(), "{file}");
    }
    // 16 x 12 pixels, RGB f32.
    assert_eq!(
        std::fs::metadata(export.join("reference.f32"))
            .unwrap()
            .len(),
        16 * 12 * 12
    );
    let quad = arbvis(&["bench", "--demo", "quad", "--size", "8x8", "--frames", "1"]);
    let (stdout, stderr) = text(&quad);
    assert!(quad.status.success(), "{stderr}");
    assert!(
        stdout.contains("quad") && stdout.contains("median"),
        "{stdout}"
    );
    let bad = arbvis(&["bench", "--demo", "quad", "--score"]);
    assert!(!bad.status.success());
    assert!(text(&bad).1.contains("3D-opacity"), "{}", text(&bad).1);
}

#[test]
fn study_from_peer_runs_writes_plots_and_the_readme_table() {
    let dir = temp_dir("study-from");
    let run = r#"{"arbvis": {"scene": "s", "renderer": "llvmpipe", "version": "4.5",
        "size": [8, 8], "settings": []},
      "arbvis_frames": {
        "precise slicing 128": {"rmse": 0.004, "max_abs": 0.1, "frames_ms": [10]},
        "raycast 0.5 step/voxel": {"rmse": 0.002, "max_abs": 0.1, "frames_ms": [5]}},
      "vtk": [{"type": "float32", "sample_distance": 2.0, "first_ms": 1, "frames_ms": [12],
               "rmse": 0.003, "max_abs": 0.1}],
      "vtk_version": "9.7.2"}"#;
    std::fs::write(dir.join("cube-axis.json"), run).unwrap();
    let out = dir.join("out");
    let study = arbvis(&[
        "study",
        "--from",
        dir.join("cube-axis.json").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&study);
    assert!(study.status.success(), "{stderr}");
    assert!(stdout.contains("2.40x"), "{stdout}");
    assert!(out.join("cube-axis.png").is_file() && out.join("study.csv").is_file());
    // A broken run names the file and the position.
    std::fs::write(dir.join("broken.json"), "{\"arbvis\": 3").unwrap();
    let bad = arbvis(&[
        "study",
        "--from",
        dir.join("broken.json").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!bad.status.success());
    assert!(text(&bad).1.contains("broken.json:1:"), "{}", text(&bad).1);
}

#[test]
fn flags_take_any_case_and_outputs_must_be_png() {
    let (out, dir, png) = render_quad("case", "q.png", &["--programs", "ARB", "--size", "16X8"]);
    assert!(out.status.success(), "{}", text(&out).1);
    assert!(png.exists());
    let (out, _, jpg) = render_quad("jpg", "q.jpg", &[]);
    assert!(!out.status.success());
    assert!(
        text(&out).1.contains("writes PNG images only"),
        "{}",
        text(&out).1
    );
    assert!(!jpg.exists());
    let help = arbvis(&["render", "--help"]);
    assert!(
        text(&help).0.contains("cellproj-spherical"),
        "--demo help lists the demos"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn study_of_cell_projection_writes_its_sweep() {
    // Two tiny grids (48 and 384 tetrahedra): the full sweep (up to a million) is a
    // benchmark. Every setting is timed, the edit latency measured and, for meshes this
    // small, scored against the f64 reference.
    let (dir, _) = study(
        "study-cellproj",
        &["--technique", "cellproj", "--grids", "3,5", "--frames", "1"],
    );
    assert_plot(&dir.join("cellproj.png"));
    let csv = std::fs::read_to_string(dir.join("cellproj.csv")).unwrap();
    // 9 settings per grid (the seed's two, three faithful, two precise, two view-ordered).
    assert_eq!(csv.lines().count(), 1 + 2 * 9, "{csv}");
    for line in csv.lines().skip(1) {
        // The setting is quoted (it holds commas): read the numbers from the end.
        let f: Vec<&str> = line.rsplitn(5, ',').collect();
        assert!(f[4].ends_with('"'), "{line}");
        let (ms, edit, agree): (f64, f64, f64) = (
            f[3].parse().unwrap(),
            f[1].parse().unwrap(),
            f[0].parse().unwrap(),
        );
        assert!(ms > 0.0 && edit > 0.0, "{line}");
        // Tiny meshes at 320x240: most pixels are interior; precise agrees everywhere on
        // llvmpipe, faithful within its 8-bit table. 0.9 is far below both: this checks
        // the column is a real score, not a placeholder.
        assert!(agree > 0.9 && agree <= 1.0, "{line}");
    }
    // A mesh above the scoring limit (here 4 points per side) is timed but not scored:
    // the line says "unscored", the CSV leaves the field empty, no "NaN" anywhere.
    let big = temp_dir("study-cellproj-unscored");
    let out = arbvis(&[
        "study",
        "--technique",
        "cellproj",
        "--grids",
        "5",
        "--score-up-to",
        "4",
        "--frames",
        "1",
        "--out",
        big.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("unscored") && !stderr.contains("NaN"),
        "{stderr}"
    );
    assert!(stdout.contains("no plot"), "{stdout}");
    let csv = std::fs::read_to_string(big.join("cellproj.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 9, "{csv}");
    // 5 points per side: 4³ cubes of 6 tetrahedra.
    assert!(
        csv.lines()
            .skip(1)
            .all(|l| l.starts_with("384,") && l.ends_with(',')),
        "{csv}"
    );
    let bad = arbvis(&["study", "--technique", "cellproj", "--grids", "1"]);
    assert!(!bad.status.success());
    assert!(text(&bad).1.contains("--grids"), "{}", text(&bad).1);
}

#[test]
fn study_of_clipping_writes_its_sweeps() {
    // A 24³ clip grid, B = 4 and 8, frames of a 16³ volume at 32²: the issue's 256³ and
    // 512³ are a benchmark.
    let (dir, _) = study(
        "study-clip",
        &[
            "--technique",
            "clip",
            "--clip-sizes",
            "24",
            "--blocks",
            "4,8",
            "--volume",
            "16",
            "--size",
            "32",
            "--frames",
            "1",
        ],
    );
    let textures = std::fs::read_to_string(dir.join("clip-textures.csv")).unwrap();
    // Per shape (sphere, torus, the open half-torus, and the cow from data/): single + 2 B.
    let shapes = textures.lines().skip(1).count() / 3;
    assert_eq!(shapes, 4, "{textures}");
    for line in textures.lines().skip(1) {
        let ratio: f64 = line.rsplit(',').nth(1).unwrap().parse().unwrap();
        assert!(ratio > 0.0 && ratio.is_finite(), "{line}");
    }
    let frames = std::fs::read_to_string(dir.join("clip-frames.csv")).unwrap();
    let rows: Vec<&str> = frames.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{frames}");
    // No clip draws another picture (nothing to score, nothing to compare); the single
    // texture is the comparison's baseline: empty fields, not NaN.
    assert!(
        rows[0].starts_with("\"no clip\",") && rows[0].ends_with(",,"),
        "{frames}"
    );
    assert!(
        rows[1].starts_with("\"single\",") && rows[1].ends_with(','),
        "{frames}"
    );
    let rmse = |row: &str| -> f64 { row.rsplit(',').nth(1).unwrap().parse().unwrap() };
    for row in &rows[2..] {
        // INDEX-DATA keeps what the single texture keeps (the keep/discard decision is
        // the same at every point, clip/mod.rs): the issue's bound is 1/255 (measured 0 here,
        // 1 level at 512², where the 8-bit target rounds a blend the other way).
        let levels: f64 = row.rsplit(',').next().unwrap().parse().unwrap();
        assert!(levels <= 1.0, "{row}");
        // So its error against the clipped f64 reference is the single texture's, within
        // what one level (1/255) at every pixel could change.
        assert!((rmse(row) - rmse(rows[1])).abs() <= 1.0 / 255.0, "{frames}");
    }
    // A real score: faithful 8-bit slicing of 16³ at 32² is neither exact nor far off
    // (measured about 0.01; 1e-4 and 0.2 bound it by 50x and 20x).
    assert!(rmse(rows[1]) > 1e-4 && rmse(rows[1]) < 0.2, "{frames}");
    assert_plot(&dir.join("clip.png"));
}

#[test]
fn study_of_splats_writes_its_sweeps() {
    // 3,000 points (at the demo's 1600x900): the seed's 570k and 10 M are a benchmark.
    let (dir, _) = study(
        "study-splats",
        &[
            "--technique",
            "splats",
            "--points",
            "3000",
            "--frame-points",
            "3000",
            "--frames",
            "1",
        ],
    );
    let sorts = std::fs::read_to_string(dir.join("splats-sorts.csv")).unwrap();
    assert!(
        sorts.contains("seed comparator") && sorts.contains("radix"),
        "{sorts}"
    );
    let frames = std::fs::read_to_string(dir.join("splats-frames.csv")).unwrap();
    let names: Vec<&str> = frames
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "seed",
            "keys",
            "radix",
            "none",
            "oit",
            "radix (precise)",
            "tiles 1px (precise)",
            "tiles 2px (precise)",
            "tiles 3px (precise)",
            "tiles 4px (precise)"
        ],
        "{frames}"
    );
    let mut rmse = std::collections::BTreeMap::new();
    for line in frames.lines().skip(1) {
        let ms: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        assert!(ms > 0.0 && ms.is_finite(), "{line}");
        // Tiles report their lists' time as the order's.
        let order: f64 = line.split(',').nth(2).unwrap().parse().unwrap();
        assert!(!line.starts_with("tiles") || order > 0.0, "{line}");
        let e: f64 = line.split(',').nth(3).unwrap().parse().unwrap();
        rmse.insert(line.split(',').next().unwrap().to_string(), e);
    }
    // Against the f64 reference in exact order: precise tiles are exact to float
    // rounding (the README's 3e-5 per pixel; 1e-3 RMSE leaves room for llvmpipe), and
    // the file order ("none") is further off than the sorted faithful draw.
    assert!(rmse["tiles 2px (precise)"] < 1e-3, "{rmse:?}");
    assert!(rmse["none"] > rmse["radix"], "{rmse:?}");
    assert_plot(&dir.join("splats.png"));
    let bad = arbvis(&["study", "--technique", "splats", "--points", "0"]);
    assert!(!bad.status.success() && text(&bad).1.contains("--points"));
}

#[test]
fn inspect_times_loading_when_asked() {
    let dir = temp_dir("inspect-time");
    let stl = dir.join("t.stl");
    std::fs::write(
        &stl,
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
    )
    .unwrap();
    let out = arbvis(&["inspect", stl.to_str().unwrap(), "--time", "3"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("triangles: 1"), "{stdout}");
    assert!(stdout.contains("ms (median of 3)"), "{stdout}");
}

#[test]
fn study_of_the_cell_projection_volume_writes_csv_and_a_plot_per_scored_mesh() {
    // The 3-point grid (48 tetrahedra): 8 settings x 2 projections, scored.
    let (dir, _) = study(
        "study-cellproj-volume",
        &[
            "--technique",
            "cellproj-volume",
            "--grids",
            "3",
            "--frames",
            "1",
        ],
    );
    let csv = std::fs::read_to_string(dir.join("cellproj-volume.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 16, "{csv}");
    for line in csv.lines().skip(1) {
        let rmse: f64 = line.rsplit(',').nth(3).unwrap().parse().unwrap();
        // A real score (not a placeholder): below 0.2 of full scale.
        assert!((0.0..0.2).contains(&rmse), "{line}");
    }
    assert_plot(&dir.join("cellproj-volume-grid3.png"));
}

#[test]
fn study_help_describes_every_technique_and_how_to_make_run_json() {
    let help = arbvis(&["study", "--help"]);
    let (stdout, _) = text(&help);
    assert!(help.status.success());
    // The studies the catalog registers ("- NAME: ..." under --technique):
    // each has its own paragraph, with what it writes.
    let values = stdout
        .split_once("--technique <TECHNIQUE>")
        .map(|(_, rest)| rest)
        .unwrap_or_default();
    let names: Vec<&str> = values
        .lines()
        .skip(1)
        .take_while(|l| !l.trim_start().starts_with("--"))
        .filter_map(|l| l.trim().strip_prefix("- "))
        .filter_map(|l| l.split(':').next())
        .collect();
    assert!(
        names.len() >= 5 && names.contains(&"cellproj-volume"),
        "{names:?}\n{stdout}"
    );
    for name in names {
        assert!(
            stdout.contains(&format!("--technique {name}")),
            "{name}: {stdout}"
        );
    }
    for file in [
        "opacity3d.png",
        "cellproj.png",
        "cellproj-volume-MESH.png",
        "clip.png",
        "splats.png",
        "vtk_volume.py",
        "--json run.json",
        "minutes",
    ] {
        assert!(stdout.contains(file), "{file}: {stdout}");
    }
}

#[test]
fn progress_bars_only_on_a_terminal_outside_ci() {
    // The smallest 3D-opacity study (8³, 16², 4 slices): well under a second of work.
    let dir = temp_dir("study-bars");
    let args = format!(
        "{} study --volume 8 --size 16 --slices 4 --frames 1 --out {}",
        env!("CARGO_BIN_EXE_arbvis"),
        dir.display()
    );
    // A pipe (as in every test): no bar whatever CI says.
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(args.split(' ').skip(1))
        .env_remove("CI")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out).1);
    assert_no_bar(&text(&out).1);
    // A terminal: `script` gives the command one (stdout and stderr both go to it).
    let tty = |ci: Option<&str>| -> Option<String> {
        let mut c = Command::new("script");
        c.args(["-qec", &args, "/dev/null"]);
        match ci {
            Some(v) => c.env("CI", v),
            None => c.env_remove("CI"),
        };
        let out = c.output().ok()?;
        out.status.success().then(|| text(&out).0)
    };
    let Some(with_ci) = tty(Some("true")) else {
        eprintln!("SKIPPED: no `script` (util-linux) to run the study on a terminal");
        return;
    };
    assert!(with_ci.contains("wrote"), "{with_ci}");
    assert_no_bar(&with_ci);
    // Outside CI the same terminal shows the bar (so the check above can fail).
    let without = tty(None).unwrap();
    assert!(
        without.contains("3D-opacity study") && without.contains("left"),
        "{without}"
    );
}

/// Stderr holds lines only: no bar drawn (indicatif redraws with carriage returns and
/// escape sequences, and its template says how long is "left").
fn assert_no_bar(stderr: &str) {
    assert!(
        !stderr.contains('\u{1b}') && !stderr.contains("left") && !stderr.contains("[="),
        "{stderr:?}"
    );
    // `script` turns each newline into CR LF; any other carriage return is a redraw.
    assert!(!stderr.replace("\r\n", "\n").contains('\r'), "{stderr:?}");
}

/// A study's plot: a 1100x700 PNG.
fn assert_plot(path: &std::path::Path) {
    let (plot, _) = read_png(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!((plot.width, plot.height), (1100, 700), "{}", path.display());
}

/// Run `arbvis study ARGS --out DIR` in a fresh folder named `name`; fails the test if
/// the study fails or prints NaN or a bar; returns the folder and the study's lines.
fn study(name: &str, args: &[&str]) -> (std::path::PathBuf, String) {
    let dir = temp_dir(name);
    let mut all = vec!["study"];
    all.extend_from_slice(args);
    all.extend(["--out", dir.to_str().unwrap()]);
    let out = arbvis(&all);
    let (_, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    // Every unmeasured value is said in words: no "NaN" in the lines.
    assert!(!stderr.contains("NaN"), "{stderr}");
    assert_no_bar(&stderr);
    (dir, stderr)
}
