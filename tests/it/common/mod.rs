//! Shared test harness: contexts, pixel probes with bit-depth tolerances, golden images.
#![allow(dead_code)]

pub mod frame;
pub mod hostile_files;
pub mod serve;
pub mod splats;
#[cfg(feature = "viewer")]
pub mod viewer;

use std::path::{Path, PathBuf};

use arbvis::gl::{Backend, Headless};
use arbvis::image::Image;
use arbvis::png_io::{read_png, write_png};
use arbvis::scene::{Scene, TechniqueScene};
use arbvis::techniques::opacity3d::Opacity3dScene;

/// One step of an 8-bit channel.
pub const LEVEL: f32 = 1.0 / 255.0;

/// A context on `backend`; fails the test with the backend's own error when unavailable
/// (CI installs Mesa's EGL and libosmesa6, so a missing backend is a real failure).
pub fn headless(backend: Backend) -> Headless {
    Headless::new(backend).unwrap_or_else(|e| panic!("no {} context: {e}", backend.name()))
}

/// Whether `h` renders with llvmpipe, the driver whose 8-bit arithmetic the faithful CPU
/// models follow (`emulate_faithful_llvmpipe` bit for bit; the generic model's level
/// tolerances were measured there). Another driver rounds its own way (NVIDIA: 8-bit
/// filter weights, its own blend rounding), where a faithful picture is the era's
/// arithmetic on that hardware, not the model's: the caller skips the comparison, and
/// this says so on stderr with `what`.
pub fn faithful_models_hold(h: &Headless, what: &str) -> bool {
    let renderer = &h.gpu().caps().renderer;
    let llvmpipe = renderer.contains("llvmpipe");
    if !llvmpipe {
        eprintln!("{what}: not compared with the faithful models (llvmpipe's) on {renderer}");
    }
    llvmpipe
}

/// Assert that `actual` is within `tolerance` of `expected` in every channel.
pub fn assert_close(actual: [f32; 4], expected: [f32; 4], tolerance: f32, what: &str) {
    let worst = actual
        .iter()
        .zip(&expected)
        .map(|(a, e)| (a - e).abs())
        .fold(0f32, f32::max);
    assert!(
        worst <= tolerance,
        "{what}: got {actual:?}, expected {expected:?} (largest difference {worst}, {:.2} levels; tolerance {tolerance})",
        worst / LEVEL
    );
}

/// Assert the 8-bit pixel at (x, y) equals `expected` exactly.
pub fn assert_pixel_u8(image: &Image, x: u32, y: u32, expected: [u8; 4], what: &str) {
    let got = image.pixel_u8(x, y);
    assert_eq!(got, expected, "{what}: pixel ({x}, {y})");
}

fn snapshot_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots")
}

/// Compare `image` with the golden `tests/snapshots/NAME.png`: the largest channel
/// difference must be at most `tolerance`. On failure `NAME.new.png` and `NAME.diff.png`
/// are written beside it; `UPDATE_SNAPSHOTS=1` accepts the new image instead.
pub fn assert_snapshot(name: &str, image: &Image, tolerance: f32) {
    let golden = snapshot_dir().join(format!("{name}.png"));
    let new = snapshot_dir().join(format!("{name}.new.png"));
    let diff = snapshot_dir().join(format!("{name}.diff.png"));
    if let Some(parent) = golden.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    let image8 = Image {
        format: arbvis::gl::TargetFormat::Rgba8,
        ..image.clone()
    };
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some_and(|v| v == "1") {
        write_png(&golden, &image8, &[]).unwrap();
        let _ = std::fs::remove_file(&new);
        let _ = std::fs::remove_file(&diff);
        return;
    }
    let (expected, _) = match read_png(&golden) {
        Ok(g) => g,
        Err(e) => {
            write_png(&new, &image8, &[]).unwrap();
            panic!(
                "golden {} unreadable ({e}); wrote {}; accept with UPDATE_SNAPSHOTS=1",
                golden.display(),
                new.display()
            );
        }
    };
    // Compare what the PNG can hold: 8-bit levels.
    let actual = arbvis::image::Image {
        data: image8
            .to_rgba8()
            .iter()
            .map(|&b| b as f32 / 255.0)
            .collect(),
        ..image8
    };
    let Some(d) = actual.compare(&expected, tolerance) else {
        write_png(&new, &actual, &[]).unwrap();
        panic!(
            "{name}: size {}x{} differs from golden {}x{}; wrote {}",
            actual.width,
            actual.height,
            expected.width,
            expected.height,
            new.display()
        );
    };
    if d.max_abs > tolerance as f64 + 1e-6 {
        write_png(&new, &actual, &[]).unwrap();
        let diff_image = actual.diff_image(&expected, tolerance, 16.0).unwrap();
        write_png(&diff, &diff_image, &[]).unwrap();
        panic!(
            "{name}: max abs {:.4} ({:.1} levels) at {:?} over tolerance {tolerance}; {} pixels over; RMSE {:.5}, PSNR {:.1} dB; wrote {} and {}",
            d.max_abs,
            d.max_abs * 255.0,
            d.worst,
            d.pixels_over,
            d.rmse,
            d.psnr,
            new.display(),
            diff.display()
        );
    }
    let _ = std::fs::remove_file(&new);
    let _ = std::fs::remove_file(&diff);
}

/// A file under the project's `data/` (real files no one here wrote, which travel with
/// the clone; `data/README.md` gives their sources and licences).
/// Pixels of `image` whose red + green + blue exceed `threshold` (what a picture drew
/// over a black background).
pub fn lit_pixels(image: &Image, threshold: f32) -> usize {
    image
        .data
        .chunks(4)
        .filter(|p| p[0] + p[1] + p[2] > threshold)
        .count()
}

/// A file under the repository's `data/` (the one helper every crate's tests use).
pub use arbvis::input::data_file;

/// A fresh, empty folder for one test's files (emptied at the start of each run). The
/// first call of a run also removes what earlier runs left behind ([`sweep_stale`]).
pub fn temp_dir(name: &str) -> std::path::PathBuf {
    static SWEEP: std::sync::Once = std::sync::Once::new();
    SWEEP.call_once(|| sweep_stale(&std::env::temp_dir()));
    let d = std::env::temp_dir().join(format!("arbvis-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The process id a test file or folder in the temporary folder was named after
/// (`arbvis-...-PID` or `arbvis-...-PID-...`: the first all-digit part), if any.
pub fn owner_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix("arbvis-")?;
    rest.split(['-', '.'])
        .find(|part| !part.is_empty() && part.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|part| part.parse().ok())
}

/// Remove the `arbvis-*` files and folders in `tmp` named after a process that is no
/// longer running (where `/proc` tells): the tests name what they write after their
/// process and most leave it for inspection, so without this every run of the suite
/// left its 100 MB or so behind for good. Whatever a live process owns stays.
pub fn sweep_stale(tmp: &std::path::Path) {
    if !std::path::Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(tmp) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(owner_pid) else {
            continue;
        };
        if std::path::Path::new(&format!("/proc/{pid}")).exists() {
            continue;
        }
        let path = entry.path();
        // Never follow a link out of the temporary folder: remove the link itself.
        let _ = match entry.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&path),
            _ => std::fs::remove_file(&path),
        };
    }
}

/// The 3D-opacity parameters of `scene` (a test's own scene: anything else is a bug).
pub fn opacity3d(scene: &Scene) -> &Opacity3dScene {
    match &scene.technique {
        TechniqueScene::Opacity3d(p) => p,
        _ => panic!("not an opacity3d scene"),
    }
}

/// [`opacity3d`], to change.
pub fn opacity3d_mut(scene: &mut Scene) -> &mut Opacity3dScene {
    match &mut scene.technique {
        TechniqueScene::Opacity3d(p) => p,
        _ => panic!("not an opacity3d scene"),
    }
}

/// The cell-projection tests' rotated camera: it sees all three axes of the seed's grid
/// (no face is edge-on) with a margin.
pub fn seed_grid_camera(projection: arbvis::camera::Projection) -> arbvis::camera::Camera {
    arbvis::camera::Camera {
        projection,
        rotation: [0.2391, 0.3696, 0.0990, 0.8924],
        zoom: 0.9,
        ..arbvis::camera::Camera::default()
    }
}

/// Copy the folder `from` to `to`, recursively (files and folders only).
pub fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// Whether `python3 -c CHECK` succeeds (the Python tool a test compares with is there).
/// If not: "SKIPPED: `missing`" on stderr, or a panic under `ARBVIS_NO_SKIP=1` (set by
/// `.ci/run`, which installs the tools).
pub fn python_has(check: &str, missing: &str) -> bool {
    let ok = std::process::Command::new("python3")
        .args(["-c", check])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        if std::env::var_os("ARBVIS_NO_SKIP").is_some_and(|v| v == "1") {
            panic!("ARBVIS_NO_SKIP=1 but {missing}");
        }
        eprintln!("SKIPPED: {missing}");
    }
    ok
}

/// The stderr of `out`, a command asserted to have failed saying `says`.
pub fn refused(out: &std::process::Output, says: &str) -> String {
    let e = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && e.contains(says),
        "expected a failure saying {says:?}: {e}"
    );
    e
}

/// Run `command` to success (its standard error in the failure) and return its standard
/// output.
pub fn stdout_of(command: &mut std::process::Command) -> String {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{command:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `arbvis inspect PATH`'s standard output, the command having succeeded.
pub fn inspect(path: &Path) -> String {
    stdout_of(
        std::process::Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("inspect")
            .arg(path),
    )
}

/// `text` holds every line of `wants` (each named with the whole text on failure).
pub fn assert_says(text: &str, wants: &[&str]) {
    for want in wants {
        assert!(text.contains(want), "{want}\n{text}");
    }
}

/// The raw fields every point of a LAS record has, a column each, as text: X Y Z,
/// intensity, return number, number of returns, classification, user data, point source.
pub fn las_columns(pd: &las::PointData) -> Vec<Vec<String>> {
    fn text<T: ToString>(it: impl Iterator<Item = T>) -> Vec<String> {
        it.map(|v| v.to_string()).collect()
    }
    vec![
        text(pd.x_raw()),
        text(pd.y_raw()),
        text(pd.z_raw()),
        text(pd.intensity()),
        text(pd.return_number()),
        text(pd.number_of_returns()),
        text(pd.classification()),
        text(pd.user_data()),
        text(pd.point_source_id()),
    ]
}

/// One line per point: each column's text, space-separated.
pub fn rows_of(columns: &[Vec<String>], points: usize) -> Vec<String> {
    (0..points)
        .map(|k| {
            columns
                .iter()
                .map(|c| c[k].as_str())
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect()
}

/// The sweep removes exactly what a finished process left: not a live process's folder,
/// not a name without a process id, not what a link points to.
#[test]
fn the_sweep_removes_only_what_finished_runs_left() {
    let root = temp_dir("sweep");
    let tmp = root.join("tmp");
    let outside = root.join("outside");
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::write(outside.join("keep"), b"x").unwrap();
    // No process has an id this large (Linux caps them at 2^22).
    let dead = 3_999_999_999u32;
    let own = std::process::id();
    let stale_dir = tmp.join(format!("arbvis-test-copc-lod-render-{dead}"));
    std::fs::create_dir_all(stale_dir.join("inner")).unwrap();
    std::fs::write(stale_dir.join("inner/file"), b"x").unwrap();
    let stale_file = tmp.join(format!("arbvis-fuzz-copc-{dead}-ThreadId(7).copc.laz"));
    std::fs::write(&stale_file, b"x").unwrap();
    let stale_link = tmp.join(format!("arbvis-link-{dead}"));
    std::os::unix::fs::symlink(&outside, &stale_link).unwrap();
    let live = tmp.join(format!("arbvis-test-i17-open-clip-{own}"));
    std::fs::create_dir_all(&live).unwrap();
    let unnamed = tmp.join("arbvis-vtk-points");
    std::fs::create_dir_all(&unnamed).unwrap();
    let foreign = tmp.join(format!("other-{dead}"));
    std::fs::create_dir_all(&foreign).unwrap();
    assert_eq!(owner_pid("arbvis-test-i17-open-clip-123"), Some(123));
    assert_eq!(owner_pid("arbvis-vtk-points"), None);
    sweep_stale(&tmp);
    for gone in [&stale_dir, &stale_file, &stale_link] {
        assert!(
            std::fs::symlink_metadata(gone).is_err(),
            "{} left",
            gone.display()
        );
    }
    for kept in [&live, &unnamed, &foreign, &outside.join("keep")] {
        assert!(kept.exists(), "{} removed", kept.display());
    }
    std::fs::remove_dir_all(&root).unwrap();
}
