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
