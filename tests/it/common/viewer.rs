//! Running the viewer under Xvfb for tests: an X display (the caller's, or a fresh Xvfb
//! with a screen of a given size), `arbvis view` with a script, its output.
//!
//! Needs an X server: `DISPLAY`, or `Xvfb` on PATH (started here). Without either the
//! tests say so and pass, unless `ARBVIS_NO_SKIP=1` (set by `.ci/run`) makes that a failure.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use super::temp_dir;

pub struct Display {
    name: String,
    _server: Option<KillOnDrop>,
}

/// An Xvfb on display `.1`, killed when dropped. SIGKILL leaves its lock file and
/// socket behind, which would make the display look taken to the next test: remove them.
struct KillOnDrop(Child, u32);
impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
        let _ = std::fs::remove_file(format!("/tmp/.X{}-lock", self.1));
        let _ = std::fs::remove_file(format!("/tmp/.X11-unix/X{}", self.1));
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

/// An X display: the caller's, or a fresh Xvfb on a free number with a 1024x768 screen.
pub fn display() -> Option<Display> {
    display_of(None)
}

/// A display with a `screen` of this size (`1280x1024`): always a fresh Xvfb, so that
/// the screen's size is known; without one, the caller's display when there is one.
pub fn display_of(screen: Option<&str>) -> Option<Display> {
    if let Some(d) = std::env::var_os("DISPLAY").filter(|d| !d.is_empty() && screen.is_none()) {
        return Some(Display {
            name: d.to_string_lossy().into_owned(),
            _server: None,
        });
    }
    // Display numbers per test process and per test, so nothing collides.
    let base = 100 + (std::process::id() % 200) * 8;
    for _ in 0..16 {
        let n = base + NEXT_DISPLAY.fetch_add(1, std::sync::atomic::Ordering::SeqCst) % 8;
        if display_taken(n) {
            continue;
        }
        // A socket left by a dead server would pass the readiness check below at once.
        let _ = std::fs::remove_file(format!("/tmp/.X11-unix/X{n}"));
        let child = match Command::new("Xvfb")
            .args([
                format!(":{n}"),
                "-screen".into(),
                "0".into(),
                format!("{}x24", screen.unwrap_or("1024x768")),
                "-nolisten".into(),
                "tcp".into(),
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
        {
            Ok(c) => KillOnDrop(c, n),
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

/// Whether display `n` belongs to a live X server: its lock file names a running process.
/// A lock left by a killed server does not count (Xvfb replaces a stale lock itself);
/// neither does a socket without a lock.
fn display_taken(n: u32) -> bool {
    match std::fs::read_to_string(format!("/tmp/.X{n}-lock")) {
        Ok(pid) => Path::new(&format!("/proc/{}", pid.trim())).exists(),
        Err(_) => false,
    }
}

/// What a viewer run left.
pub struct Run {
    pub ok: bool,
    pub stdout: String,
    pub stderr: String,
}

/// Run `arbvis view --demo DEMO --size SIZE` with `script` (the scene's own size when
/// SIZE is empty).
pub fn run_viewer(display: &Display, dir: &Path, demo: &str, size: &str, script: &str) -> Run {
    let script_path = dir.join("script.txt");
    std::fs::write(&script_path, script).unwrap();
    // A demo's name, or a scene file.
    let source: Vec<&str> = if demo.ends_with(".toml") {
        vec![demo]
    } else {
        vec!["--demo", demo]
    };
    let size: Vec<&str> = if size.is_empty() {
        vec![]
    } else {
        vec!["--size", size]
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .arg("view")
        .args(source)
        .args(size)
        .arg("--screenshot-dir")
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
            return Run {
                ok: status.success(),
                stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
                stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
            };
        }
        if t0.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("viewer did not finish its script within 120 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Run `script` in the viewer on `demo` (one test at a time) and return its screenshot
/// folder and stdout, or `None` when the test is skipped for lack of a display. Fails if
/// the viewer fails.
pub fn run_script(name: &str, demo: &str, size: &str, script: &str) -> Option<(PathBuf, String)> {
    run_script_on(None, name, demo, size, script)
}

/// [`run_script`] on a fresh Xvfb whose screen is `screen` (`1280x1024`), when given.
pub fn run_script_on(
    screen: Option<&str>,
    name: &str,
    demo: &str,
    size: &str,
    script: &str,
) -> Option<(PathBuf, String)> {
    let dir = temp_dir(name);
    let stdout = run_script_in(screen, &dir, demo, size, script)?;
    Some((dir, stdout))
}

/// [`run_script_on`] with screenshots and saved scenes in `dir` (not emptied first);
/// returns stdout.
pub fn run_script_in(
    screen: Option<&str>,
    dir: &Path,
    demo: &str,
    size: &str,
    script: &str,
) -> Option<String> {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = display_of(screen)?;
    let run = run_viewer(&display, dir, demo, size, script);
    assert!(run.ok, "viewer failed: {}", run.stderr);
    Some(run.stdout)
}

/// Run scripts that must fail; returns each one's stderr (`None`: skipped).
pub fn failing_scripts(name: &str, demo: &str, scripts: &[&str]) -> Option<Vec<String>> {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let display = display()?;
    let dir = temp_dir(name);
    let errors = scripts
        .iter()
        .map(|script| {
            let run = run_viewer(&display, &dir, demo, "160x160", script);
            assert!(!run.ok, "script {script:?} should fail: {}", run.stdout);
            run.stderr
        })
        .collect();
    let _ = std::fs::remove_dir_all(&dir);
    Some(errors)
}
