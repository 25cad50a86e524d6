//! SEG-Y files that keep their inline and crossline numbers elsewhere than rev 1's bytes
//! 189 and 193: detected (9/21, 17/13), or named by a scene (`iline`/`xline`), `inspect
//! --iline --xline` and `convert --iline --xline`; `inspect` says which bytes it used and
//! the grid they give.

use std::path::Path;
use std::process::Command;

use arbvis::volume::segy::{self, KeyBytes, ReadOptions};

use crate::common::{data_file, stdout_of, temp_dir};

/// F3 renumbered as a file from another system: the inline number (times 2 plus 1000,
/// so its step is 2) at `il`, the crossline (plus 5000) at `xl`, rev 1's bytes 189-196 and
/// F3's own copies at 9 and 21 cleared, and the traces in reverse order.
fn renumbered(il: usize, xl: usize, out: &Path) {
    let bytes = std::fs::read(data_file("seismic/f3.sgy")).unwrap();
    let trace_len = 240 + 75 * 2;
    let traces = (bytes.len() - 3600) / trace_len;
    assert_eq!(traces, 414);
    let mut file = bytes[..3600].to_vec();
    for t in (0..traces).rev() {
        let mut trace = bytes[3600 + t * trace_len..][..trace_len].to_vec();
        let be = |at: usize| i32::from_be_bytes(trace[at..at + 4].try_into().unwrap());
        let (inline, crossline) = (be(188), be(192));
        for at in [188, 192, 8, 20] {
            trace[at..at + 4].fill(0);
        }
        trace[il - 1..il + 3].copy_from_slice(&(1000 + 2 * inline).to_be_bytes());
        trace[xl - 1..xl + 3].copy_from_slice(&(5000 + crossline).to_be_bytes());
        file.extend_from_slice(&trace);
    }
    std::fs::write(out, file).unwrap();
}

fn arbvis(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

#[test]
fn numbers_at_other_bytes_are_found_and_grid_as_rev_1s_do() {
    let dir = temp_dir("segy-keys");
    let original = segy::read(&data_file("seismic/f3.sgy"), &Default::default()).unwrap();
    for (il, xl, what) in [
        (9, 21, "the field record number"),
        (17, 13, "the energy source point number"),
    ] {
        let path = dir.join(format!("f3-{il}-{xl}.sgy"));
        renumbered(il, xl, &path);
        let cube = segy::read(&path, &Default::default()).unwrap();
        assert_eq!((cube.keys.iline, cube.keys.xline), (il as u16, xl as u16));
        // The same samples in the same cells: the grid is sorted by the numbers, whatever
        // the traces' order in the file.
        assert_eq!(cube.volume, original.volume);
        assert_eq!(
            cube.inlines,
            original
                .inlines
                .iter()
                .map(|i| 1000 + 2 * i)
                .collect::<Vec<_>>()
        );
        assert_eq!(cube.crosslines[0], 5875);

        let text = stdout_of(
            Command::new(env!("CARGO_BIN_EXE_arbvis")).args(["inspect", path.to_str().unwrap()]),
        );
        for want in [
            format!("inline/crossline numbers: trace bytes {il} and {xl} (detected: {what}"),
            "inlines: 1222..=1266 (23 values, step 2)".to_string(),
            "crosslines: 5875..=5892 (18 values, step 1)".to_string(),
            "grid: 23 inlines x 18 crosslines, 414 traces".to_string(),
        ] {
            assert!(text.contains(&want), "{want:?} not in {text}");
        }
    }

    // Named bytes win over detection: rev 1's, empty in this file, grid nothing.
    let path = dir.join("f3-17-13.sgy");
    let named = ReadOptions {
        keys: KeyBytes {
            iline: Some(189),
            xline: Some(193),
        },
        ..Default::default()
    };
    let e = segy::read(&path, &named).unwrap_err().to_string();
    assert!(e.contains("trace bytes 189 and 193 (as named)"), "{e}");
    // A scene names them as segyio does; a byte outside the header is the key's error.
    let scene = |volume: &str| {
        format!("size = [24, 24]\n[technique.opacity3d]\nslices = 8\n[technique.opacity3d.primary]\nvolume = {volume}\n")
    };
    std::fs::write(
        dir.join("named.toml"),
        scene("{ segy = { path = \"f3-17-13.sgy\", iline = 17, xline = 13 } }"),
    )
    .unwrap();
    let out = arbvis(&dir, &["render", "named.toml", "-o", "named.png"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::write(
        dir.join("bad.toml"),
        scene("{ segy = { path = \"f3-17-13.sgy\", iline = 239, xline = 13 } }"),
    )
    .unwrap();
    let out = arbvis(&dir, &["render", "bad.toml", "-o", "bad.png"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("technique.opacity3d.primary.volume.segy: iline = 239: a 4-byte number's first byte in the 240-byte trace header, 1..=237"),
        "{stderr}"
    );
    // inspect and convert take them too.
    let out = arbvis(
        &dir,
        &["inspect", "f3-17-13.sgy", "--iline", "17", "--xline", "13"],
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("trace bytes 17 and 13 (as named)"));
    let out = arbvis(
        &dir,
        &[
            "convert",
            "f3-17-13.sgy",
            "f3.zarr",
            "--iline",
            "17",
            "--xline",
            "13",
            "--attributes",
            "none",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = arbvis(&dir, &["inspect", "f3.zarr"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("1222"),
        "the store keeps the file's inline numbers: {text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
