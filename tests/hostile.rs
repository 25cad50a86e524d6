//! Hostile input through the binary, as a user (or an attacker's file) would give it:
//! special files, absurd sizes and huge scenes end in a clear error naming the place,
//! fast, in bounded memory, with no output file. Each case is a reproducer of something
//! that once hung, panicked or ran out of memory (issue "Hostile input").

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use common::temp_dir;

mod common;

/// Longest a refusal may take (a debug build, two busy cores; the real cost is
/// milliseconds: these once took 10-70 s or never ended).
const REFUSAL_TIME: Duration = Duration::from_secs(20);

fn render(scene: &Path, png: &Path) -> (Output, Duration) {
    let t0 = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // A hang must fail the test, not the suite.
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > REFUSAL_TIME * 2 {
            let _ = child.kill();
            panic!("{} hung", scene.display());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    (child.wait_with_output().unwrap(), t0.elapsed())
}

/// Render `scene_text` (written to DIR/scene.toml) and expect a refusal containing every
/// `expect` string, within the time bound, and no output file.
fn refused(name: &str, scene_text: &str, expect: &[&str]) {
    let dir = temp_dir(name);
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, scene_text).unwrap();
    refused_at(&dir, &scene, expect);
}

fn refused_at(dir: &Path, scene: &Path, expect: &[&str]) {
    let png = dir.join("out.png");
    let (out, took) = render(scene, &png);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{} was accepted", scene.display());
    for e in expect {
        assert!(stderr.contains(e), "expected {e:?} in: {stderr}");
    }
    assert!(stderr.len() < 4000, "error of {} bytes", stderr.len());
    assert!(took < REFUSAL_TIME, "{} took {took:?}", scene.display());
    let left: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().contains("out.png"))
        })
        .collect();
    assert!(left.is_empty(), "output left behind: {left:?}");
}

fn volume_scene(volume: &str) -> String {
    format!("size = [32, 32]\n[technique.opacity3d]\nslices = 8\n[technique.opacity3d.primary]\nvolume = {volume}\n")
}

#[test]
fn special_files_are_refused_by_kind() {
    for (i, volume) in [
        "{ segy = \"/dev/zero\" }",
        "{ nifti = \"/dev/urandom\" }",
        "{ raw = { path = \"/dev/zero\", dims = [4, 4, 4], type = \"u8\" } }",
    ]
    .iter()
    .enumerate()
    {
        refused(
            &format!("special-{i}"),
            &volume_scene(volume),
            &["/dev/", "not a regular file", "character device"],
        );
    }
    let table =
        volume_scene("{ synthetic = { size = [8, 8, 8] } }") + "table = { file = \"/dev/zero\" }\n";
    refused("special-table", &table, &["/dev/zero", "character device"]);
    // The scene itself.
    let dir = temp_dir("special-scene");
    refused_at(
        &dir,
        Path::new("/dev/zero"),
        &["/dev/zero", "character device"],
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_does_not_block() {
    let dir = temp_dir("fifo");
    let fifo = dir.join("pipe.sgy");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    refused(
        "fifo-volume",
        &volume_scene(&format!("{{ segy = {:?} }}", fifo.to_str().unwrap())),
        &["pipe.sgy", "FIFO"],
    );
    refused_at(&dir, &fifo, &["pipe.sgy", "FIFO"]);
}

#[test]
fn absurd_sizes_are_refused_before_loading() {
    refused(
        "raw-wrap",
        &volume_scene(
            "{ raw = { path = \"empty.raw\", dims = [2305843009213693951, 1, 1], type = \"f64\", offset = 8 } }",
        ),
        &["scene.toml:5:12: technique.opacity3d.primary.volume.raw", "64 bits"],
    );
    refused(
        "synthetic-long",
        &volume_scene("{ synthetic = { size = [268435456, 1, 1] } }"),
        &["GL_MAX_3D_TEXTURE_SIZE"],
    );
    refused(
        "synthetic-peak",
        &volume_scene("{ synthetic = { size = [16, 16, 16], peak = 60 } }"),
        &["scene.toml:5:", "peak = 60", "Nyquist"],
    );
    // A tiny peak is valid and, with the wavelet cut at the trace length, as fast as any
    // other (it once panicked at 1e-300 and ran for minutes at 1e-5).
    let dir = temp_dir("tiny-peak");
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        volume_scene("{ synthetic = { size = [16, 16, 16], peak = 1e-300 } }"),
    )
    .unwrap();
    let (out, took) = render(&scene, &dir.join("out.png"));
    assert!(out.status.success() && took < REFUSAL_TIME, "{took:?}");
}

#[test]
fn huge_scenes_and_keys_are_refused_or_shortened() {
    let dir = temp_dir("huge-scene");
    let scene = dir.join("scene.toml");
    let big = "# padding\n".repeat(5_000_000); // 50 MB
    std::fs::write(&scene, big + "[technique.quad]\n").unwrap();
    refused_at(&dir, &scene, &["scene.toml", "50000017 bytes", "1048576"]);
    let key = format!("{} = 1\n[technique.quad]\n", "k".repeat(500_000));
    refused("huge-key", &key, &["scene.toml:1:1", "more characters"]);
    let mut not_utf8 = b"size = [8, 8]\n# caf".to_vec();
    not_utf8.extend([0xe9, b'\n']);
    not_utf8.extend(b"[technique.quad]\n");
    let dir = temp_dir("latin1");
    std::fs::write(dir.join("scene.toml"), &not_utf8).unwrap();
    refused_at(
        &dir,
        &dir.join("scene.toml"),
        &["line 2, column 6 (byte 19)", "not UTF-8"],
    );
}

#[test]
fn errors_point_at_the_place() {
    // The OS error once, and the path that was tried.
    let dir = temp_dir("missing");
    let (out, _) = render(&dir.join("nope.toml"), &dir.join("out.png"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.matches("No such file").count(), 1, "{stderr}");
    refused(
        "missing-data",
        &volume_scene("{ segy = \"not-here.sgy\" }"),
        &["missing-data", "/not-here.sgy: No such file"],
    );
    // A scene named relative to the current folder: the error shows where it looked.
    let dir = temp_dir("missing-relative");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::write(
        dir.join("scenes/s.toml"),
        volume_scene("{ segy = \"data/not-here.sgy\" }"),
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["render", "scenes/s.toml", "-o", "out.png"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let tried = dir.join("scenes/data/not-here.sgy");
    assert!(
        stderr.contains(&format!("looked for {}", tried.display())),
        "{stderr}"
    );
    // Checks after parsing name line and column.
    refused(
        "slices-zero",
        "[technique.opacity3d]\nslices = 0\n[technique.opacity3d.primary]\nvolume = { synthetic = {} }\n",
        &["scene.toml:2:1: technique.opacity3d.slices"],
    );
    refused(
        "builtin",
        &(volume_scene("{ synthetic = {} }") + "table = { builtin = \"nope\" }\n"),
        &[
            "scene.toml:6:11: technique.opacity3d.primary.table.builtin",
            "seismic",
        ],
    );
    refused(
        "bare-word",
        "fidelity = faithful\n[technique.quad]\n",
        &["scene.toml:1:12", "\"faithful\""],
    );
}

// --- issue 17: what a scene makes arbvis allocate ---

/// The parts of a refusal by the memory budget: the estimate, the budget, where it came
/// from and how to raise it.
const OVER_BUDGET: [&str; 3] = [
    "more than the memory budget of",
    "--memory-budget",
    "ARBVIS_MEMORY_BUDGET",
];

fn over_budget(name: &str, scene_text: &str, parts: &[&str]) {
    let mut expect: Vec<&str> = OVER_BUDGET.to_vec();
    expect.extend_from_slice(parts);
    refused(name, scene_text, &expect);
}

#[test]
fn scene_values_the_machine_cannot_hold_are_refused_before_any_work() {
    // Each of these once allocated gigabytes (or tried to) before failing; each is
    // estimated from the scene alone and refused in milliseconds under a 1 GiB budget.
    let budget = "memory_budget = \"1G\"\n";
    over_budget(
        "readback",
        &format!("{budget}size = [16384, 16384]\n[technique.quad]\n"),
        &[
            "the 16384x16384 rgba8 target",
            "reading back and writing the 16384x16384 frame",
            "1.00 GiB (from the scene's memory_budget)",
        ],
    );
    over_budget(
        "grid64",
        &format!(
            "{budget}[technique.cellproj]\nmesh = {{ grid = {{ points = [64, 64, 64] }} }}\nisovalues = []\n"
        ),
        &["the generated grid's 1500282 tetrahedra"],
    );
    over_budget(
        "clip512-block1",
        &format!(
            "{budget}[technique.opacity3d]\nslices = 8\n[technique.opacity3d.primary]\n\
             volume = {{ synthetic = {{ size = [16, 16, 16] }} }}\n\
             [technique.opacity3d.clip]\nshape = {{ sphere = {{ center = [0.0, 0.0, 0.0], radius = 0.5 }} }}\n\
             block = 1\nresolution = [512, 512, 512]\n"
        ),
        &["the clip's [512, 512, 512] grid", "the INDEX texture of 134217728 blocks of 1³"],
    );
    over_budget(
        "tiles-16384",
        &format!(
            "{budget}size = [16384, 16384]\nfidelity = \"precise\"\nprograms = \"glsl\"\n\
             [technique.splats]\ncloud = {{ section = {{ points = 1000, seed = 1 }} }}\n\
             draw = \"tiles\"\ntile = 1\n"
        ),
        &["the lists of 268435456 tiles of 1 pixels"],
    );
    over_budget(
        "section-20m",
        &format!(
            "{budget}[technique.splats]\ncloud = {{ section = {{ points = 20000000, seed = 1 }} }}\n"
        ),
        &["the generated section's 20000000 points"],
    );
}

#[test]
fn the_budget_comes_from_the_flag_then_the_environment_then_the_scene() {
    let dir = temp_dir("budget-order");
    let scene = dir.join("scene.toml");
    // A 64x64 quad needs about 0.25 MiB (target and read-back): over 100K, under 1G.
    std::fs::write(
        &scene,
        "memory_budget = \"1G\"\nsize = [64, 64]\n[technique.quad]\n",
    )
    .unwrap();
    let png = dir.join("out.png");
    let run = |flag: Option<&str>, env: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_arbvis"));
        c.env_remove("ARBVIS_MEMORY_BUDGET");
        if let Some(e) = env {
            c.env("ARBVIS_MEMORY_BUDGET", e);
        }
        if let Some(f) = flag {
            c.args(["--memory-budget", f]);
        }
        let out = c
            .args([
                "render",
                scene.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    assert!(run(None, None).0, "the scene's 1G holds a 64x64 quad");
    let (ok, e) = run(Some("100K"), None);
    assert!(!ok && e.contains("100 KiB (from --memory-budget)"), "{e}");
    let (ok, e) = run(None, Some("100K"));
    assert!(!ok && e.contains("(from ARBVIS_MEMORY_BUDGET)"), "{e}");
    // The flag wins over the environment, the environment over the scene.
    assert!(run(Some("1G"), Some("100K")).0);
    let (ok, e) = run(None, Some("nonsense"));
    assert!(!ok && e.contains("ARBVIS_MEMORY_BUDGET=nonsense"), "{e}");
    let (ok, e) = run(Some("12 parsecs"), None);
    assert!(!ok && e.contains("is not a memory size"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
