//! COPC faults found by the held-out hostile files (issue 42, item 3): a COPC path that is
//! a FIFO is refused at once by `render` as by `inspect`; `inspect` refuses what `render`
//! refuses (extra-bytes descriptors past the record, a legacy point count disagreeing
//! with the 64-bit one, LAS 1.2 with point format 7); two conversions into one output
//! never run at once; a scene whose data a command makes says that command; a colour
//! mode the cloud has no data for says so.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::{data_file, stdout_of, temp_dir};

/// `arbvis ARGS` in `dir`, killed after 60 s (`timeout`'s exit 124: it hung).
fn arbvis(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new("timeout")
        .arg("60")
        .arg(env!("CARGO_BIN_EXE_arbvis"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(124), "arbvis {args:?} hung");
    out
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A splats scene drawing the COPC file `cloud` (relative to `dir`), in `colour`.
fn scene(dir: &Path, cloud: &str, colour: &str) -> PathBuf {
    let path = dir.join(format!("{cloud}-{colour}.toml"));
    std::fs::write(
        &path,
        format!("size = [48, 40]\nfidelity = \"precise\"\nprograms = \"glsl\"\n[technique.splats]\ncloud = {{ copc = {{ path = \"{cloud}\" }} }}\ncolour = \"{colour}\"\n"),
    )
    .unwrap();
    path
}

/// The bunny (format 6, two extra-bytes attributes) converted to COPC in `dir`.
fn bunny(dir: &Path) -> Vec<u8> {
    let out = dir.join("bunny.copc.laz");
    stdout_of(
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("convert")
            .arg(data_file("points/bunny.ply"))
            .arg(&out),
    );
    std::fs::read(&out).unwrap()
}

#[test]
fn inspect_and_render_refuse_the_same_files_and_never_wait_on_a_fifo() {
    let dir = temp_dir("copc-faults");
    let good = bunny(&dir);
    // A drawable file first: both commands take it.
    let s = scene(&dir, "bunny.copc.laz", "elevation");
    assert!(arbvis(&dir, &["inspect", "bunny.copc.laz"])
        .status
        .success());
    let out = arbvis(&dir, &["render", s.to_str().unwrap(), "-o", "bunny.png"]);
    assert!(out.status.success(), "{}", stderr(&out));

    let mut cases: Vec<(&str, Vec<u8>, &str)> = Vec::new();
    // The legacy 32-bit count (byte 107) one more than the 64-bit one (byte 247).
    let mut b = good.clone();
    let count = u64::from_le_bytes(b[247..255].try_into().unwrap());
    b[107..111].copy_from_slice(&(count as u32 + 1).to_le_bytes());
    cases.push(("legacy.copc.laz", b, "legacy point count"));
    // The first extra-bytes descriptor made a double: the two attributes then need more
    // bytes than the records' extra bytes.
    let mut b = good.clone();
    let at = b.windows(9).position(|w| w == b"LASF_Spec").unwrap() - 2 + 54;
    b[at + 2] = 10;
    cases.push(("extra.copc.laz", b, "extra bytes descriptor"));
    // The first descriptor "undocumented" (type 0) of 200 bytes, its size in `options`:
    // past the records' extra bytes as any other type's would be (issue 54 item 2).
    let mut b = good.clone();
    b[at + 2] = 0;
    b[at + 3] = 200;
    cases.push(("undocumented.copc.laz", b, "extra bytes descriptor"));
    // LAS 1.2 with point format 7 (the version byte only).
    let mut b = good.clone();
    b[104] = 0x80 | 7;
    b[25] = 2;
    cases.push(("v12.copc.laz", b, "LAS"));
    for (name, bytes, cause) in cases {
        std::fs::write(dir.join(name), bytes).unwrap();
        let inspected = arbvis(&dir, &["inspect", name]);
        let s = scene(&dir, name, "elevation");
        let rendered = arbvis(&dir, &["render", s.to_str().unwrap(), "-o", "x.png"]);
        for (what, out) in [("inspect", &inspected), ("render", &rendered)] {
            let e = stderr(out);
            assert!(!out.status.success(), "{what} {name} succeeded");
            assert!(e.contains(cause) && e.contains(name), "{what} {name}: {e}");
        }
    }

    // A FIFO named as the cloud: refused at once, never read from.
    let fifo = dir.join("fifo.copc.laz");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let s = scene(&dir, "fifo.copc.laz", "elevation");
    for args in [
        vec!["inspect", "fifo.copc.laz"],
        vec!["render", s.to_str().unwrap(), "-o", "fifo.png"],
    ] {
        let out = arbvis(&dir, &args);
        let e = stderr(&out);
        assert!(
            !out.status.success() && e.contains("fifo.copc.laz"),
            "{args:?}: {e}"
        );
    }
}

#[test]
fn a_format_6_cloud_drawn_in_rgb_says_it_has_no_colours() {
    let dir = temp_dir("copc-rgb");
    bunny(&dir);
    let s = scene(&dir, "bunny.copc.laz", "rgb");
    let out = arbvis(&dir, &["render", s.to_str().unwrap(), "-o", "rgb.png"]);
    let e = stderr(&out);
    assert!(out.status.success(), "{e}");
    assert!(
        e.contains("technique.splats.colour = \"rgb\": the cloud has no colours"),
        "{e}"
    );
    // A cloud with colours says nothing.
    let out = arbvis(
        &dir,
        &[
            "convert",
            data_file("points/autzen_trim.laz").to_str().unwrap(),
            "autzen.copc.laz",
        ],
    );
    assert!(out.status.success());
    let s = scene(&dir, "autzen.copc.laz", "rgb");
    let out = arbvis(&dir, &["render", s.to_str().unwrap(), "-o", "autzen.png"]);
    assert!(
        out.status.success() && !stderr(&out).contains("warning"),
        "{}",
        stderr(&out)
    );
}

/// Names in `dir` that hold `part` (what a conversion into it left).
fn left_in(dir: &std::path::Path, part: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.contains(part))
        .collect();
    names.sort();
    names
}

/// SIGINT in the middle of a conversion: exit 130, and neither the lock file nor a
/// temporary is left (the output is not made). A lock file left by a process that is gone
/// (SIGKILL leaves one) is taken over with a note, and the conversion goes on.
#[test]
fn an_interrupt_leaves_no_lock_and_a_dead_writers_lock_is_taken_over() {
    let dir = temp_dir("copc-sigint");
    let ply = data_file("points/bunny.ply");
    let lock = dir.join(".cut.copc.laz.arbvis-convert.lock");
    // Tried until the signal lands while the conversion runs (it takes about a second).
    let mut interrupted = false;
    for _ in 0..5 {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .current_dir(&dir)
            .args(["convert", ply.to_str().unwrap(), "cut.copc.laz"])
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        while !lock.exists() && start.elapsed() < std::time::Duration::from_secs(20) {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        // (A conversion that ended first makes kill fail: tried again.)
        let _ = std::process::Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        if child.wait().unwrap().code() == Some(130) {
            interrupted = true;
            break;
        }
        let _ = std::fs::remove_file(dir.join("cut.copc.laz"));
    }
    assert!(interrupted, "no conversion was interrupted in 5 tries");
    assert_eq!(left_in(&dir, "cut"), Vec::<String>::new(), "left behind");
    // A writer killed outright leaves its lock file with its pid: a pid that is gone.
    let mut gone = std::process::Command::new("true").spawn().unwrap();
    let pid = gone.id();
    gone.wait().unwrap();
    std::fs::write(&lock, pid.to_string()).unwrap();
    let out = arbvis(&dir, &["convert", ply.to_str().unwrap(), "cut.copc.laz"]);
    let e = stderr(&out);
    assert!(out.status.success(), "{e}");
    assert!(
        e.contains(&format!("the lock of pid {pid}")) && e.contains("taken over"),
        "{e}"
    );
    assert_eq!(left_in(&dir, "cut"), vec!["cut.copc.laz".to_string()]);
}

#[test]
fn a_second_conversion_into_one_output_is_refused_naming_the_first() {
    let dir = temp_dir("copc-lock");
    let out = dir.join("busy.copc.laz");
    // The first writer's lock, held by this process.
    let lock = arbvis::png_io::WriterLock::acquire(&dir.join(".busy.copc.laz.arbvis-convert.lock"))
        .unwrap()
        .expect("free");
    let ply = data_file("points/bunny.ply");
    let second = arbvis(&dir, &["convert", ply.to_str().unwrap(), "busy.copc.laz"]);
    let e = stderr(&second);
    assert!(
        !second.status.success() && e.contains(&format!("pid {}", std::process::id())),
        "{e}"
    );
    assert!(!out.exists(), "the second writer wrote nothing");
    drop(lock);
    let third = arbvis(&dir, &["convert", ply.to_str().unwrap(), "busy.copc.laz"]);
    assert!(third.status.success(), "{}", stderr(&third));
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.contains("busy"))
        .collect();
    assert_eq!(
        left,
        vec!["busy.copc.laz".to_string()],
        "no lock file or temporary left"
    );
}

#[test]
fn the_copc_scene_says_which_command_makes_its_file() {
    // The repository's scene, copied where the file it names is not.
    let dir = temp_dir("copc-data-from");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data/autzen-copc.toml"),
    )
    .unwrap();
    let sub = dir.join("a/b");
    std::fs::create_dir_all(&sub).unwrap();
    std::fs::write(sub.join("autzen-copc.toml"), text).unwrap();
    let e = arbvis::scene::Scene::load_checked(&sub.join("autzen-copc.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("arbvis convert data/points/autzen_trim.laz autzen.copc.laz"),
        "{e}"
    );
}
