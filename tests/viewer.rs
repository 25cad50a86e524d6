//! The desktop viewer under Xvfb: one rendered frame, screenshots, and simulated UI
//! interaction (clicks and a drag injected through egui's input path by `--script`).
//!
//! Needs an X server: `DISPLAY`, or `Xvfb` on PATH (started here). Without either the
//! tests say so and pass, unless `ARBVIS_NO_SKIP=1` (set by `.ci/run`) makes that a failure.
#![cfg(feature = "viewer")]

mod common;

use std::path::{Path, PathBuf};

use common::temp_dir;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use arbvis::gl::Backend;
use arbvis::gl::TargetFormat;
use arbvis::png_io::read_png;
use arbvis::render::render;
use arbvis::scene::{Scene, TechniqueScene};
use arbvis::techniques::opacity3d::Combine;
use arbvis::techniques::quad::{reference_image, QuadScene};

struct Display {
    name: String,
    _server: Option<KillOnDrop>,
}

struct KillOnDrop(Child);
impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn skip(reason: &str) -> Option<Display> {
    if std::env::var_os("ARBVIS_NO_SKIP").is_some_and(|v| v == "1") {
        panic!("ARBVIS_NO_SKIP=1 but {reason}");
    }
    eprintln!("SKIPPED: {reason}");
    None
}

/// Viewer tests run one at a time: each may own an Xvfb, and none may outlive its test.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());
static NEXT_DISPLAY: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);

/// An X display: the caller's, or a fresh Xvfb on a free number.
fn display() -> Option<Display> {
    if let Some(d) = std::env::var_os("DISPLAY").filter(|d| !d.is_empty()) {
        return Some(Display {
            name: d.to_string_lossy().into_owned(),
            _server: None,
        });
    }
    // Display numbers per test process and per test, so nothing collides.
    let base = 100 + (std::process::id() % 200) * 8;
    for _ in 0..8 {
        let n = base + NEXT_DISPLAY.fetch_add(1, std::sync::atomic::Ordering::SeqCst) % 8;
        if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
            || Path::new(&format!("/tmp/.X{n}-lock")).exists()
        {
            continue;
        }
        let child = match Command::new("Xvfb")
            .args([
                format!(":{n}"),
                "-screen".into(),
                "0".into(),
                "1024x768x24".into(),
                "-nolisten".into(),
                "tcp".into(),
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
        {
            Ok(c) => KillOnDrop(c),
            Err(e) => {
                return skip(&format!(
                    "no DISPLAY and Xvfb cannot start ({e}); install xvfb"
                ))
            }
        };
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(10) {
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                return Some(Display {
                    name: format!(":{n}"),
                    _server: Some(child),
                });
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    skip("no DISPLAY and Xvfb did not come up")
}

/// Run `arbvis view --demo DEMO --size SIZE` with `script`; returns (success, stderr).
fn run_viewer(
    display: &Display,
    dir: &Path,
    demo: &str,
    size: &str,
    script: &str,
) -> (bool, String) {
    let script_path = dir.join("script.txt");
    std::fs::write(&script_path, script).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["view", "--demo", demo, "--size", size, "--screenshot-dir"])
        .arg(dir)
        .arg("--script")
        .arg(&script_path)
        .env("DISPLAY", &display.name)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            return (
                status.success(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            );
        }
        if t0.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("viewer did not finish its script within 120 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Run `script` in the viewer on `demo` (one test at a time) and return its screenshot
/// folder, or `None` when the test is skipped for lack of a display. Fails if the viewer
/// fails.
fn run_script(name: &str, demo: &str, size: &str, script: &str) -> Option<PathBuf> {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = display()?;
    let dir = temp_dir(name);
    let (ok, stderr) = run_viewer(&display, &dir, demo, size, script);
    assert!(ok, "viewer failed: {stderr}");
    Some(dir)
}

#[test]
fn frame_screenshot_and_program_switch() {
    let Some(dir) = run_script(
        "switch",
        "quad",
        "160x160",
        "wait 2\nclick Screenshot\nwait 1\nclick GLSL\nwait 2\nclick Screenshot\nwait 1\nclick Save scene\nwait 1\n",
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

    // The view is the window minus the side panel; the quad fills it. Both screenshots
    // match the CPU reference at the view's size within one 8-bit level (the window's
    // back buffer is 8 bits per channel, as an RGBA8 target).
    assert_eq!(arb.width, 160, "view width = scene width");
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

    // "Save scene" wrote a scene that parses and records the switch.
    let saved = Scene::load(&dir.join("arbvis-scene.toml")).unwrap();
    assert_eq!(saved.programs, arbvis::gl::ProgramChoice::Glsl);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn drag_rotates_the_camera() {
    let Some(dir) = run_script(
        "drag",
        "quad",
        "160x160",
        "wait 2\ndrag 60 0\nwait 1\nclick Save scene\nwait 1\n",
    ) else {
        return;
    };
    let saved = Scene::load(&dir.join("arbvis-scene.toml")).unwrap();
    // A horizontal drag rotates about the vertical axis only.
    let q = saved.camera.quat();
    let (axis, angle) = q.to_axis_angle();
    assert!(angle > 0.1, "rotation angle {angle}");
    assert!((axis - glam::DVec3::Y).length() < 1e-6, "axis {axis}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn script_naming_a_missing_widget_fails_clearly() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let Some(display) = display() else { return };
    let dir = temp_dir("missing");
    let (ok, stderr) = run_viewer(
        &display,
        &dir,
        "quad",
        "160x160",
        "wait 1\nclick No such button\n",
    );
    assert!(!ok, "a bad script must fail the viewer");
    assert!(
        stderr.contains("No such button") && stderr.contains("Screenshot"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn lut3d_editor_switches_combination_and_locks_a_table() {
    let Some(dir) = run_script(
        "lut3d",
        "v3o2-sum",
        "160x400",
        "wait 2\nclick Product\nwait 2\nclick Lock primary\nwait 2\nclick Screenshot\nwait 1\nclick Save scene\nwait 1\n",
    ) else {
        return;
    };
    // The edits are in the saved scene: product, and the locked primary's four
    // coefficients made one (the demo's are [1, 1, 1, 0.8]; the lock takes Cr).
    let saved = Scene::load(&dir.join("arbvis-scene.toml")).unwrap();
    let TechniqueScene::Opacity3d(o) = &saved.technique else {
        panic!("saved scene is not opacity3d");
    };
    assert_eq!(o.combine, Combine::Product);
    assert_eq!(o.primary.coefficients, [1.0; 4]);
    // And they showed on the next frame: the screenshot equals an offscreen render of the
    // saved scene at the view's size, within one 8-bit level (same driver, same program,
    // an 8-bit back buffer as the RGBA8 target).
    let (shot, _) = read_png(&dir.join("arbvis-screenshot-001.png")).unwrap();
    let mut scene = saved.clone();
    scene.size = [shot.width, shot.height];
    scene.programs = arbvis::gl::ProgramChoice::Arb;
    let offscreen = render(&scene, Backend::Egl).unwrap().image;
    let d = shot.compare(&offscreen, common::LEVEL).unwrap();
    assert!(d.max_abs <= common::LEVEL as f64 * 1.01, "{d:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
