//! Hostile stores and conversions: every number in a store checked at open, chunks that
//! inflate or are not files, conversions killed at any moment or raced by a second
//! writer, damaged progress logs, work that grows faster than its input, and the legal
//! stores that must still be read (absent all-fill chunks). Each case ends in an error
//! naming the file and what is wrong, or reads, and never panics or hangs.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::temp_dir;
use crate::store::{all_values, options, survey, write_segy};
use arbvis::store::convert::{convert, ConvertOptions};
use arbvis::store::progress::{LOCK_FILE, PROGRESS_LOG};
use arbvis::store::Store;

/// A converted survey of 21 x 13 x 11 in 8³ bricks (3 x 2 x 2 bricks, 3 levels), one
/// derived attribute: its folder and the store.
fn store(name: &str) -> (PathBuf, PathBuf) {
    let dir = temp_dir(name);
    let sgy = write_segy(&dir, &survey([21, 13, 11]));
    let o = ConvertOptions {
        derived: vec![arbvis::volume::attributes::Attribute::Envelope],
        ..options(8)
    };
    convert(&sgy, &dir.join("s.zarr"), &o).unwrap();
    (dir.clone(), dir.join("s.zarr"))
}

/// `Store::open`'s error, as text.
fn open_error(store: &Path) -> String {
    match Store::open(store) {
        Ok(_) => panic!("{} opened", store.display()),
        Err(e) => e.to_string(),
    }
}

/// Rewrite the JSON of `file` through `change`.
fn edit_json(file: &Path, change: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    change(&mut v);
    std::fs::write(file, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

#[test]
fn a_stores_own_numbers_are_checked_against_each_other() {
    use serde_json::json;
    let (dir, s) = store("sh-numbers");
    let root = s.join("zarr.json");
    let original = std::fs::read_to_string(&root).unwrap();
    let with = |field: &str, value: serde_json::Value| {
        std::fs::write(&root, &original).unwrap();
        edit_json(&root, |v| v["attributes"]["arbvis"][field] = value);
        open_error(&s)
    };
    // A brick side whose cube overflows, dimensions whose brick count wraps, a level
    // count that disagrees: each named with both values, no division by zero.
    let e = with("brick", json!(4294967296u64));
    assert!(
        e.contains("arbvis.brick is 4294967296: must be 2..=512"),
        "{e}"
    );
    let e = with("brick", json!(0));
    assert!(e.contains("arbvis.brick is 0"), "{e}");
    let e = with("levels", json!(7));
    assert!(
        e.contains("arbvis.levels is 7, but dims [21, 13, 11] in 8³ bricks make 3 levels"),
        "{e}"
    );
    let e = with("dims", json!([u64::MAX, 13, 11]));
    assert!(e.contains("arbvis.dims[0] is 18446744073709551615"), "{e}");
    let e = with("dims", json!([1u64 << 31, 1u64 << 31, 1u64 << 31]));
    assert!(e.contains("more than 67108864 bricks in a level"), "{e}");
    // A type error names its field, line and column.
    let e = with("dims", json!(["21", 13, 11]));
    assert!(
        e.contains("attributes.arbvis.dims[0]") && e.contains("line "),
        "{e}"
    );
    let e = with("spacing", json!([-1.0, 1.0, 1.0]));
    assert!(e.contains("arbvis.spacing[0] is -1"), "{e}");
    std::fs::write(&root, &original).unwrap();
    // An array whose shape disagrees with the metadata: named, with both values (once
    // this drew a crop of the survey and exited 0).
    let array = s.join("amplitude/zarr.json");
    let array_text = std::fs::read_to_string(&array).unwrap();
    edit_json(&array, |v| v["shape"] = json!([5, 13, 21]));
    let e = open_error(&s);
    assert!(
        e.contains(
            "amplitude: shape is [5, 13, 21], but the store's metadata makes it [11, 13, 21]"
        ),
        "{e}"
    );
    std::fs::write(&array, &array_text).unwrap();
    edit_json(&array, |v| v["data_type"] = json!("float64"));
    let e = open_error(&s);
    assert!(
        e.contains("amplitude: data type is float64, but the store's metadata makes it float32"),
        "{e}"
    );
    std::fs::write(&array, &array_text).unwrap();
    edit_json(&array, |v| {
        v["chunk_grid"]["configuration"]["chunk_shape"] = json!([8, 8, 4])
    });
    let e = open_error(&s);
    assert!(e.contains("amplitude: chunk shape is [8, 8, 4]"), "{e}");
    std::fs::write(&array, &array_text).unwrap();
    edit_json(&s.join("level_1/envelope_range/zarr.json"), |v| {
        v["shape"] = json!([9, 1, 2, 2])
    });
    let e = open_error(&s);
    assert!(
        e.contains("level_1/envelope_range: shape is [9, 1, 2, 2]"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn special_files_in_a_store_are_refused_at_once_with_their_cause() {
    let (dir, s) = store("sh-special");
    let mkfifo = |p: &Path| {
        std::fs::remove_file(p).unwrap();
        assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
    };
    // A FIFO as an array's zarr.json: refused in milliseconds, naming it.
    let array = s.join("level_1/amplitude/zarr.json");
    let saved = std::fs::read(&array).unwrap();
    mkfifo(&array);
    let t0 = Instant::now();
    let e = open_error(&s);
    assert!(
        e.contains("level_1/amplitude/zarr.json") && e.contains("FIFO"),
        "{e}"
    );
    assert!(t0.elapsed() < Duration::from_secs(2));
    std::fs::remove_file(&array).unwrap();
    std::fs::write(&array, saved).unwrap();
    // The root zarr.json linked to /dev/zero: the true cause, not "no zarr.json".
    let root = s.join("zarr.json");
    let saved = std::fs::read(&root).unwrap();
    std::fs::remove_file(&root).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &root).unwrap();
    let e = open_error(&s);
    assert!(e.contains("character device"), "{e}");
    std::fs::remove_file(&root).unwrap();
    std::fs::write(&root, saved).unwrap();
    // A FIFO as a chunk: the chunk's read fails at once, naming it.
    let store = Store::open(&s).unwrap();
    let chunk = store.chunk_file(0, 0, [1, 1, 1]);
    mkfifo(&chunk);
    let e = store.chunk(0, 0, [1, 1, 1]).unwrap_err().to_string();
    assert!(e.contains("c/1/1/1") && e.contains("FIFO"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_absent_chunk_is_its_fill_value_unless_the_stores_ranges_say_otherwise() {
    let (dir, s) = store("sh-absent");
    // zarr-python does not write a chunk that is all fill value: make one so (all
    // NaN, the fill value, no finite range) and delete it, as such a writer leaves it.
    let store = Store::open(&s).unwrap();
    let chunk = store.chunk_file(1, 0, [2, 1, 1]);
    drop(store);
    let ranges = s.join("envelope_range/c/0/0/0/0");
    let store = Store::open(&s).unwrap();
    let mut table = store.ranges(1, 0).unwrap();
    drop(store);
    // Brick [2, 1, 1] of level 0's 3 x 2 x 2, i fastest.
    let (c, counts) = ([2usize, 1, 1], [3usize, 2, 2]);
    let at = c[0] + counts[0] * (c[1] + counts[1] * c[2]);
    table[at] = [f32::NAN, f32::NAN];
    let raw: Vec<u8> = table
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(&ranges, raw).unwrap();
    std::fs::remove_file(&chunk).unwrap();
    let store = Store::open(&s).unwrap();
    let read = store.chunk(1, 0, [2, 1, 1]).unwrap();
    assert!(read.iter().all(|v| v.is_nan()), "the fill value, NaN");
    // A deleted chunk whose recorded range holds data is damage, named as such.
    let lost = store.chunk_file(0, 0, [0, 0, 0]);
    std::fs::remove_file(&lost).unwrap();
    let e = store.chunk(0, 0, [0, 0, 0]).unwrap_err().to_string();
    assert!(
        e.contains("c/0/0/0") && e.contains("the store's ranges say it holds values in"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_second_writer_is_refused_with_the_firsts_pid() {
    let (dir, _) = store("sh-lock");
    let sgy = dir.join("survey.sgy");
    let target = dir.join("t.zarr");
    std::fs::create_dir_all(&target).unwrap();
    // The first writer: this process holds the lock, as a running conversion would.
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .read(true)
        .open(target.join(LOCK_FILE))
        .unwrap();
    lock.try_lock().unwrap();
    std::fs::write(target.join(LOCK_FILE), "4242").unwrap();
    let e = convert(&sgy, &target, &options(8)).unwrap_err().to_string();
    assert!(
        e.contains("another conversion (pid 4242) is writing this store"),
        "{e}"
    );
    lock.unlock().unwrap();
    drop(lock);
    // Once it is gone (killed before its progress log existed: only the lock and a
    // temporary are left), the same command starts afresh instead of refusing.
    std::fs::write(target.join(".arbvis-progress.log.arbvis-tmp.99"), "{").unwrap();
    convert(&sgy, &target, &options(8)).unwrap();
    assert!(Store::open(&target).is_ok());
    assert!(
        !target.join(LOCK_FILE).exists(),
        "the lock goes with its writer"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A conversion of `sgy` into `store` stopped after `columns` columns (as a kill would).
fn stopped(sgy: &Path, store: &Path, columns: usize) {
    let o = ConvertOptions {
        stop_after: Some(columns),
        ..options(8)
    };
    assert!(convert(sgy, store, &o).is_err());
}

#[test]
fn damaged_progress_logs_are_errors_naming_their_line() {
    let dir = temp_dir("sh-log");
    let sgy = write_segy(&dir, &survey([21, 13, 11]));
    let s = dir.join("s.zarr");
    stopped(&sgy, &s, 3);
    let log = s.join(PROGRESS_LOG);
    let text = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4, "{text}");
    // Records that index past the store's arrays (they once panicked), and wrong counts.
    let cases = [
        (r#""u":[0,"#, r#""u":[9,"#, "level 9, but the store has 3"),
        (r#""u":[0,"#, r#""u":[0,77"#, "column 77"),
        (r#""ranges":[["#, r#""ranges":[[[1.0,2.0]],["#, "ranges, "),
        (r#""sums":[["#, r#""sums":[[1e400,"#, ""),
    ];
    for (from, to, want) in cases {
        let bad = lines[1].replacen(from, to, 1);
        assert_ne!(bad, lines[1], "{from}");
        let damaged = format!("{}\n{bad}\n{}\n{}\n", lines[0], lines[2], lines[3]);
        std::fs::write(&log, damaged).unwrap();
        let e = convert(&sgy, &s, &options(8)).unwrap_err().to_string();
        assert!(
            e.contains("arbvis-progress.log") && e.contains("line 2"),
            "{to}: {e}"
        );
        assert!(e.contains(want), "{to}: {e}");
    }
    // A last line torn by a kill is dropped and its column redone: the store completes.
    let torn = format!(
        "{}\n{}\n{}\n{}",
        lines[0],
        lines[1],
        lines[2],
        &lines[3][..lines[3].len() / 2]
    );
    std::fs::write(&log, torn).unwrap();
    convert(&sgy, &s, &options(8)).unwrap();
    let whole = dir.join("whole.zarr");
    convert(&sgy, &whole, &options(8)).unwrap();
    assert_eq!(
        all_values(&Store::open(&s).unwrap()),
        all_values(&Store::open(&whole).unwrap())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_conversion_stopped_at_any_column_resumes_to_the_same_store() {
    let dir = temp_dir("sh-stops");
    let sgy = write_segy(&dir, &survey([21, 13, 11]));
    let whole = dir.join("whole.zarr");
    convert(&sgy, &whole, &options(8)).unwrap();
    let want = all_values(&Store::open(&whole).unwrap());
    // 2 x 2 columns at level 0, 1 at each of levels 1 and 2: stopped after 0..=5 of
    // them, then resumed; once with the metadata of one array cut to nothing by the kill.
    for columns in 0..=5 {
        let s = dir.join(format!("s{columns}.zarr"));
        stopped(&sgy, &s, columns);
        if columns == 2 {
            std::fs::write(s.join("amplitude/zarr.json"), "").unwrap();
        }
        convert(&sgy, &s, &options(8)).unwrap();
        assert_eq!(
            all_values(&Store::open(&s).unwrap()),
            want,
            "stopped after {columns}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn work_that_grows_faster_than_the_input_is_refused_before_it_starts() {
    let dir = temp_dir("sh-thin");
    // 2 MiB of samples as 1 x 1 x 2^20 (i, j, k): in 64³ bricks, 16,384 chunks a level.
    let raw = dir.join("thin.raw");
    std::fs::write(&raw, vec![0u8; 2 << 20]).unwrap();
    let t0 = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args([
            "convert",
            raw.to_str().unwrap(),
            dir.join("t.zarr").to_str().unwrap(),
        ])
        .args(["--raw-dims", "1,1,1048576", "--raw-type", "u16"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        e.contains("chunk files for a 2.1 MB survey") && e.contains("mostly padding"),
        "{e}"
    );
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    // Nothing was written.
    assert!(!dir.join("t.zarr").join("amplitude").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn raw_dims_are_given_as_the_guide_writes_them() {
    let dir = temp_dir("sh-raw-dims");
    let raw = dir.join("cube.raw");
    std::fs::write(&raw, vec![7u8; 40 * 30 * 20 * 2]).unwrap();
    let run = |dims: &str, store: &str| {
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .args([
                "convert",
                raw.to_str().unwrap(),
                dir.join(store).to_str().unwrap(),
            ])
            .args([
                "--raw-dims",
                dims,
                "--raw-type",
                "i16",
                "--raw-endian",
                "big",
                "--attributes",
                "none",
            ])
            .env("CI", "true")
            .output()
            .unwrap()
    };
    let out = run("40,30,20", "a.zarr");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        Store::open(&dir.join("a.zarr")).unwrap().meta.dims,
        [40, 30, 20]
    );
    let out = run("40,30", "b.zarr");
    crate::common::refused(&out, "expected three sizes I,J,K");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn inspect_describes_a_store_and_an_interrupted_one() {
    let (dir, s) = store("sh-inspect");
    let inspect = crate::common::inspect;
    let text = inspect(&s);
    for want in [
        "format: arbvis store version 2 (zarr v3, the MDIO v1 layout), complete",
        "sample: 21, time 0..40 ms (every 2 ms)",
        "crossline: 13, numbers 20..32 (step 1)",
        "inline: 11, numbers 100..110 (step 1)",
        "levels: 3 of 8³ bricks",
        "level 0: 21 x 13 x 11 voxels, 3 x 2 x 2 bricks",
        "amplitude: float32, chunks [8, 8, 8], codecs bytes + blosc (lz4, shuffle)",
        "envelope: float32",
        "size on disk:",
    ] {
        assert!(text.contains(want), "{want}\n{text}");
    }
    let part = dir.join("part.zarr");
    stopped(&dir.join("survey.sgy"), &part, 2);
    let text = inspect(&part);
    assert!(
        text.contains("INCOMPLETE: an interrupted conversion, 2 of 6 columns written"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_says_what_it_cannot_do_with_a_store() {
    let (dir, _) = store("sh-bench");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[technique.opacity3d]\n[technique.opacity3d.primary]\nvolume = { store = \"s.zarr\" }\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["bench", scene.to_str().unwrap(), "--frames", "1"])
        .env("CI", "true")
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        e.contains("streams a store") && e.contains("arbvis render SCENE --stats"),
        "{e}"
    );
    assert!(!e.contains("every attribute's volume"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_default_budget_holds_to_the_process_address_space_limit() {
    // A generated grid of 64³ points (1.5 million tetrahedra, 2.8 GiB): under `ulimit -v`
    // of about 3.8 GiB the default budget refuses it before allocating (it once aborted
    // with "memory allocation of N bytes failed").
    let dir = temp_dir("sh-ulimit");
    let scene = dir.join("g.toml");
    std::fs::write(
        &scene,
        "[technique.cellproj]\nmesh = { grid = { points = [64, 64, 64], field = \"spherical\" } }\n",
    )
    .unwrap();
    let script = format!(
        "ulimit -v 4000000 && exec {} render {} -o {}",
        env!("CARGO_BIN_EXE_arbvis"),
        scene.display(),
        dir.join("g.png").display()
    );
    let out = Command::new("sh").args(["-c", &script]).output().unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        e.contains("more than the memory budget") && e.contains("ulimit -v"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn zarr_v2_stores_and_mdio_v0_datasets_without_their_variable_are_refused() {
    let dir = temp_dir("sh-v2");
    let v0 = dir.join("survey_v0.mdio");
    std::fs::create_dir_all(v0.join("data")).unwrap();
    std::fs::write(v0.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    std::fs::write(v0.join("data/.zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    let e = open_error(&v0);
    assert!(
        e.contains("an MDIO v0 dataset (zarr v2) without its variable data/chunked_012"),
        "{e}"
    );
    let v2 = dir.join("plain.zarr");
    std::fs::create_dir_all(&v2).unwrap();
    std::fs::write(v2.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    let e = open_error(&v2);
    assert!(
        e.contains("a zarr v2 store that is not an MDIO dataset"),
        "{e}"
    );
    // convert says the same of them as inputs.
    let e = convert(&v0, &dir.join("out.zarr"), &options(8))
        .unwrap_err()
        .to_string();
    assert!(e.contains("an MDIO v0 dataset"), "{e}");
    // A v0 variable's .zarray: each field checked, the file named.
    let array = v0.join("data/chunked_012");
    std::fs::create_dir_all(&array).unwrap();
    std::fs::write(
        v0.join(".zattrs"),
        r#"{"api_version": "0.8.5", "dimension": []}"#,
    )
    .unwrap();
    let zarray = |dtype: &str, extra: &str| {
        format!(
            r#"{{"zarr_format": 2, "shape": [4, 5, 6], "chunks": [4, 5, 6], "dtype": {dtype},
            "order": "C", "filters": null, "compressor": null, "fill_value": 0{extra}}}"#
        )
    };
    for (text, want) in [
        (zarray(r#""""#, ""), "`dtype` \"\": arbvis reads bool"),
        (zarray(r#"">c8""#, ""), "`dtype` \">c8\""),
        (zarray(r#"[["a", "<i4"]]"#, ""), "`dtype` a structured type"),
        (
            zarray(r#""<f4""#, r#", "dimension_separator": "-""#),
            "`dimension_separator` \"-\"",
        ),
        (
            zarray(r#""<f4""#, "").replace(r#""order": "C""#, r#""order": "F""#),
            "`order` is not \"C\"",
        ),
        (
            zarray(r#""<f4""#, "")
                .replace(r#""compressor": null"#, r#""compressor": {"id": "lzma"}"#),
            "\"lzma\" is not a compressor arbvis reads",
        ),
        (
            zarray(r#""<f4""#, "").replace("[4, 5, 6], \"dtype", "[4000, 5000, 6000], \"dtype"),
            "MiB arbvis reads in one chunk",
        ),
        (zarray(r#""<f4""#, ""), "has dimensions []"),
    ] {
        std::fs::write(array.join(".zarray"), &text).unwrap();
        let e = open_error(&v0);
        assert!(e.contains(want) && e.contains("chunked_012"), "{want}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
