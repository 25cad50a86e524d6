//! The checks a CI user relies on: `--dry-run` finds every file a scene reads (each data
//! key: SEG-Y, store, table file, clip mesh, tetrahedral mesh, LAS and COPC clouds), a
//! missing data file names its key, the path as written and as resolved, a missing output
//! folder is named as the output's, and `render --json` says what was written.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::temp_dir;

fn arbvis(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// A scene per data key, each naming `missing.*` (relative to the scene's folder), with the
/// dotted key the error must name.
fn scenes_with_a_missing_file() -> Vec<(&'static str, String, &'static str)> {
    let opacity = |volume: &str, extra: &str| {
        format!("size = [16, 16]\n[technique.opacity3d]\nslices = 4\n{extra}[technique.opacity3d.primary]\nvolume = {volume}\n")
    };
    vec![
        (
            "technique.opacity3d.primary.volume.segy",
            opacity("{ segy = \"missing.sgy\" }", ""),
            "missing.sgy",
        ),
        (
            "technique.opacity3d.primary.volume.store",
            opacity("{ store = \"missing.zarr\" }", ""),
            "missing.zarr",
        ),
        (
            "technique.opacity3d.primary.table.file",
            opacity("{ synthetic = { size = [8, 8, 8] } }", "")
                + "table = { file = \"missing.table\" }\n",
            "missing.table",
        ),
        (
            "technique.opacity3d.clip.shape",
            opacity(
                "{ synthetic = { size = [8, 8, 8] } }",
                "[technique.opacity3d.clip]\nshape = { mesh = { path = \"missing.stl\" } }\n",
            ),
            "missing.stl",
        ),
        (
            "technique.cellproj.mesh.file",
            "[technique.cellproj]\nmesh = { file = \"missing.vtk\" }\n".to_string(),
            "missing.vtk",
        ),
        (
            "technique.splats.cloud.las",
            "[technique.splats]\ncloud = { las = \"missing.laz\" }\n".to_string(),
            "missing.laz",
        ),
        (
            "technique.splats.cloud.copc",
            "[technique.splats]\ncloud = { copc = { path = \"missing.copc.laz\", points = 1000 } }\n"
                .to_string(),
            "missing.copc.laz",
        ),
    ]
}

#[test]
fn dry_run_and_render_name_a_missing_data_file_by_key_and_path() {
    for (i, (key, text, file)) in scenes_with_a_missing_file().into_iter().enumerate() {
        let dir = temp_dir(&format!("missing-file-{i}"));
        std::fs::create_dir_all(dir.join("scenes")).unwrap();
        std::fs::write(dir.join("scenes/s.toml"), &text).unwrap();
        let resolved = dir.join("scenes").join(file);
        for dry in [true, false] {
            let mut args = vec!["render", "scenes/s.toml", "-o", "out.png"];
            if dry {
                args.push("--dry-run");
            }
            let out = arbvis(&dir, &args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{key} (dry {dry}) was accepted");
            for want in [
                "scenes/s.toml:".to_string(),
                format!("{key}: no such file: \"{file}\" as written"),
                format!("{} as resolved", resolved.display()),
                "relative to the scene's folder".to_string(),
            ] {
                assert!(stderr.contains(&want), "{want:?} not in {stderr}");
            }
            assert!(!dir.join("out.png").exists());
        }
        // With the file there (empty: a dry run checks only that it exists) the dry run
        // passes, so the check is the file's and nothing else's.
        if file.ends_with(".zarr") {
            std::fs::create_dir_all(&resolved).unwrap();
        } else {
            std::fs::write(&resolved, b"").unwrap();
        }
        let out = arbvis(
            &dir,
            &["render", "scenes/s.toml", "-o", "out.png", "--dry-run"],
        );
        assert!(
            out.status.success(),
            "{key}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_missing_output_folder_is_named_as_the_output() {
    let dir = temp_dir("missing-output-folder");
    for dry in [false, true] {
        let mut args = vec![
            "render",
            "--demo",
            "quad",
            "--size",
            "8x8",
            "-o",
            "no/such/folder/x.png",
        ];
        if dry {
            args.push("--dry-run");
        }
        let out = arbvis(&dir, &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(
            stderr.contains(
                "the output no/such/folder/x.png: its folder no/such/folder does not exist"
            ),
            "{stderr}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn render_json_says_what_was_written_and_what_it_held() {
    let dir = temp_dir("render-json");
    let out = arbvis(
        &dir,
        &[
            "render", "--demo", "v3o2-sum", "--size", "40x24", "-o", "x.png", "--stats", "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("stdout is one JSON value");
    assert_eq!(v["output"], "x.png");
    assert_eq!(v["size"], serde_json::json!([40, 24]));
    assert_eq!(v["technique"], "opacity3d");
    assert_eq!(v["fidelity"], "faithful");
    assert_eq!(v["target"], "rgba8");
    assert!(v["renderer"].as_str().is_some_and(|r| !r.is_empty()));
    let resources = v["resources"].as_array().expect("resources with --stats");
    assert!(!resources.is_empty());
    let sum: u64 = resources.iter().map(|r| r["bytes"].as_u64().unwrap()).sum();
    assert_eq!(v["resource_bytes"].as_u64(), Some(sum));
    // The 3 attributes' packed 64³ texture is among them, at 3 bytes a voxel.
    assert!(
        resources
            .iter()
            .any(|r| r["kind"] == "texture" && r["bytes"].as_u64() >= Some(64 * 64 * 64 * 3)),
        "{resources:?}"
    );
    for key in ["build_ms", "draw_ms"] {
        assert!(v[key].as_f64().is_some_and(|t| t >= 0.0), "{key}: {v}");
    }
    assert!(dir.join("x.png").exists());
    // Without --stats: what was written, no resources.
    let out = arbvis(
        &dir,
        &[
            "render", "--demo", "quad", "--size", "8x8", "-o", "q.png", "--json",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["technique"], "quad");
    assert!(v.get("resources").is_none(), "{v}");
    let _ = std::fs::remove_dir_all(&dir);
}
