//! Irregular post-stack surveys (issue 42): the F3 crop renumbered to inlines 1000..1044
//! in steps of 2, written crossline by crossline, with a missing corner (inline indices
//! 0..6, crossline indices 0..5) and, in one variant, a whole inline missing (a gap).
//! Read in memory, converted into a store, inspected and drawn, every position without a
//! trace is dead (NaN, `trace_mask` false, never drawn); and mdio-python's ingestion of
//! the same file has the same trace mask and values.

use std::path::{Path, PathBuf};
use std::process::Command;

use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::Scene;
use arbvis::store::Store;
use arbvis::volume::segy;

use crate::common::{data_file, headless, inspect, stdout_of, temp_dir};

/// F3's traces: 23 inlines of 18 crosslines, 240 + 75 x 2 bytes each, after 3600 bytes.
const TRACE: usize = 240 + 75 * 2;
const NK: usize = 23;
const NJ: usize = 18;

fn corner(k: usize, j: usize) -> bool {
    k < 6 && j < 5
}

/// The irregular F3 at `dir/NAME`: inline numbers `1000 + 2k`, crossline-sorted, the
/// corner gone, and inline index `gap` gone too where one is given.
fn irregular(dir: &Path, name: &str, gap: Option<usize>) -> PathBuf {
    let bytes = std::fs::read(data_file("seismic/f3.sgy")).unwrap();
    let mut out = bytes[..3600].to_vec();
    for j in 0..NJ {
        for k in 0..NK {
            if corner(k, j) || gap == Some(k) {
                continue;
            }
            let mut t = bytes[3600 + (k * NJ + j) * TRACE..][..TRACE].to_vec();
            t[188..192].copy_from_slice(&(1000 + 2 * k as i32).to_be_bytes());
            out.extend_from_slice(&t);
        }
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

fn dead(k: usize, j: usize, gap: Option<usize>) -> bool {
    corner(k, j) || gap == Some(k)
}

/// Equal values, NaN where the other is NaN.
fn same(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
}

#[test]
fn an_irregular_survey_reads_with_dead_traces_and_inspect_says_its_grid() {
    let dir = temp_dir("irregular-read");
    let gap = Some(11);
    let path = irregular(&dir, "gap.sgy", gap);
    let f3 = segy::read(&data_file("seismic/f3.sgy"), &Default::default()).unwrap();
    let cube = segy::read(&path, &Default::default()).unwrap();
    // The grid keeps the gap as a line: 23 inlines, step 2.
    assert_eq!(cube.volume.dims, [75, NJ, NK]);
    assert_eq!(
        cube.inlines,
        (0..NK as i32).map(|k| 1000 + 2 * k).collect::<Vec<_>>()
    );
    assert_eq!(cube.grid.live, NK * NJ - 30 - 18);
    let v = &cube.volume;
    for k in 0..NK {
        for j in 0..NJ {
            let trace = &v.values[v.index(0, j, k)..][..75];
            if dead(k, j, gap) {
                assert!(trace.iter().all(|x| x.is_nan()), "({k}, {j}) is dead");
            } else {
                assert_eq!(
                    trace,
                    &f3.volume.values[v.index(0, j, k)..][..75],
                    "({k}, {j})"
                );
            }
        }
    }
    // The proportions from a plane through live traces: F3's 25.004 x 24.996 m (its CDP
    // coordinates are rounded to 0.1 m, so a fit and the corners differ by millimetres).
    for a in [1, 2] {
        assert!(
            (v.spacing[a] - f3.volume.spacing[a]).abs() < 0.01,
            "{:?} against {:?}",
            v.spacing,
            f3.volume.spacing
        );
    }
    // The statistics leave the dead traces out; no NaN is the file's own.
    let text = inspect(&path);
    crate::common::assert_says(
        &text,
        &[
            "inlines: 1000..=1044 (23 values, step 2, 1 of them without traces)",
            "crosslines: 875..=892 (18 values, step 1)",
            "grid: 23 inlines x 18 crosslines = 414 positions, 366 live traces, 48 dead",
        ],
    );
    assert!(!text.contains("NaN or infinite"), "{text}");
    // Two traces at one position are refused naming both (1-based trace numbers).
    let mut twice = std::fs::read(&path).unwrap();
    let (a, b) = (3600 + 3 * TRACE, 3600 + 4 * TRACE);
    let header: Vec<u8> = twice[a + 188..a + 196].to_vec();
    twice[b + 188..b + 196].copy_from_slice(&header);
    std::fs::write(dir.join("twice.sgy"), &twice).unwrap();
    let named = segy::ReadOptions {
        keys: segy::KeyBytes {
            iline: Some(189),
            xline: Some(193),
        },
        ..Default::default()
    };
    let e = segy::read(&dir.join("twice.sgy"), &named)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("traces 4 and 5") && e.contains("both sit at"),
        "{e}"
    );
}

/// `arbvis convert SRC DST` to success.
fn convert(src: &Path, dst: &Path) {
    stdout_of(
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("convert")
            .arg(src)
            .arg(dst),
    );
}

#[test]
fn an_irregular_survey_converts_as_it_reads() {
    let dir = temp_dir("irregular-convert");
    let path = irregular(&dir, "gap.sgy", Some(11));
    let cube = segy::read(&path, &Default::default()).unwrap();
    let store_path = dir.join("gap.zarr");
    convert(&path, &store_path);
    let store = Store::open(&store_path).unwrap();
    assert_eq!(store.meta.dims, cube.volume.dims);
    assert_eq!(store.meta.source.inlines, Some([1000, 2]));
    let level0 = store.region(0, 0, [0; 3], store.meta.dims).unwrap();
    assert!(
        same(&level0, &cube.volume.values),
        "level 0 is the SEG-Y read"
    );
    // The statistics are the live samples'.
    let a = &store.meta.attributes[0];
    let live: Vec<f32> = cube
        .volume
        .values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    let max = live.iter().fold(f32::MIN, |m, &v| m.max(v));
    assert_eq!(a.max, Some(max as f64));
    assert_eq!(a.non_finite, 48 * 75, "the dead traces' samples");
}

/// mdio-python's ingestion and arbvis's conversion of `sgy`, compared by zarr-python:
/// prints `same` when the trace masks are equal (arbvis's gap lines, `drop`, removed
/// first), the live amplitudes equal and arbvis's dead ones NaN with a NaN fill.
const COMPARE: &str = r#"
import sys, json
import numpy as np
import zarr
mdio = zarr.open_group(sys.argv[1], mode="r")
ours = zarr.open_group(sys.argv[2], mode="r")
drop = json.loads(sys.argv[3])
mask_m = np.asarray(mdio["trace_mask"][:])
mask_o = np.asarray(ours["trace_mask"][:])
amp_m = np.asarray(mdio["amplitude"][:])
amp_o = np.asarray(ours["amplitude"][:])
assert np.isnan(ours["amplitude"].fill_value), ours["amplitude"].fill_value
# arbvis's dead traces are NaN, never zero amplitude.
assert np.isnan(amp_o[~mask_o]).all()
keep = [k for k in range(mask_o.shape[0]) if k not in drop]
assert not mask_o[drop].any() if drop else True
mask_o, amp_o = mask_o[keep], amp_o[keep]
inl_o = np.asarray(ours["inline"][:])[keep]
assert np.array_equal(np.asarray(mdio["inline"][:]), inl_o), (mdio["inline"][:], inl_o)
assert np.array_equal(np.asarray(mdio["crossline"][:]), np.asarray(ours["crossline"][:]))
assert np.array_equal(mask_m, mask_o), (mask_m.sum(), mask_o.sum())
assert np.array_equal(amp_m[mask_m], amp_o[mask_o])
print("same", int(mask_m.sum()))
"#;

#[test]
fn mdio_python_ingests_the_same_mask_and_values() {
    if !crate::mdio::has_mdio() {
        return;
    }
    let dir = temp_dir("irregular-mdio");
    let script = dir.join("compare.py");
    std::fs::write(&script, COMPARE).unwrap();
    // Without a gap mdio-python's grid (the numbers present) is arbvis's; with one,
    // arbvis keeps the gap as a dead line where mdio-python's grid leaves it out.
    for (name, gap, drop, live) in [
        ("corner.sgy", None, "[]", 384),
        ("gap.sgy", Some(11), "[11]", 366),
    ] {
        let sgy = irregular(&dir, name, gap);
        let mdio = crate::mdio::ingest_as(&dir, &sgy, name, "PostStack3DTime");
        let ours = dir.join(format!("{name}.zarr"));
        convert(&sgy, &ours);
        let out = stdout_of(
            Command::new("python3")
                .arg(&script)
                .arg(&mdio)
                .arg(&ours)
                .arg(drop),
        );
        assert!(out.starts_with(&format!("same {live}")), "{name}: {out}");
        // And arbvis reads mdio-python's dataset as its own SEG-Y reader reads the file
        // (the gap left out of mdio-python's grid).
        let theirs = Store::open(&mdio).unwrap();
        let cube = segy::read(&sgy, &Default::default()).unwrap().volume;
        let keep: Vec<usize> = (0..NK).filter(|&k| Some(k) != gap).collect();
        let expected: Vec<f32> = keep
            .iter()
            .flat_map(|&k| cube.values[cube.index(0, 0, k)..][..75 * NJ].to_vec())
            .collect();
        let level0 = theirs.region(0, 0, [0; 3], theirs.meta.dims).unwrap();
        assert!(
            same(&level0, &expected),
            "{name}: mdio's dataset as arbvis reads it"
        );
    }
}

/// A scene looking down the time axis (object x): screen x is the inline axis, screen y
/// the crossline axis; every finite value white and opaque.
fn top_view(dir: &Path, volume: &str, fidelity: &str) -> Scene {
    let table: String = (0..256).map(|_| "255 255 255 255\n").collect();
    std::fs::write(dir.join("white.table"), table).unwrap();
    let text = format!(
        "size = [92, 92]\nfidelity = \"{fidelity}\"\nbackground = [0.0, 0.0, 0.0, 1.0]\n[camera]\nprojection = \"orthographic\"\nrotation = [0.0, 0.7071067811865476, 0.0, 0.7071067811865476]\nzoom = 1.0\n[technique.opacity3d]\ncombine = \"product\"\n[technique.opacity3d.primary]\nvolume = {volume}\nattribute = \"amplitude\"\nquantize = {{ range = [-6000.0, 6000.0] }}\ntable = {{ file = \"white.table\" }}\n"
    );
    let path = dir.join(format!("top-{fidelity}.toml"));
    std::fs::write(&path, text).unwrap();
    Scene::load(&path).unwrap()
}

#[test]
fn dead_traces_are_never_drawn_in_memory_or_from_a_store() {
    let dir = temp_dir("irregular-draw");
    let sgy = irregular(&dir, "corner.sgy", None);
    convert(&sgy, &dir.join("corner.zarr"));
    let h = headless(Backend::Egl);
    for volume in ["{ segy = \"corner.sgy\" }", "{ store = \"corner.zarr\" }"] {
        for fidelity in ["faithful", "precise"] {
            let scene = top_view(&dir, volume, fidelity);
            let image = render_on(&h, &scene).unwrap().image;
            let name = format!("{}-{fidelity}.png", volume.len());
            arbvis::png_io::write_png(&dir.join(name), &image, &[]).ok();
            let (w, hgt) = (image.width as f64, image.height as f64);
            // The box spans [-1, 1] along the inlines (F3's longest side) and 450/575 of
            // that along the crosslines; a position's column covers its voxel's cell. A
            // pixel whose column is dead at least one voxel away from any live trace
            // (linear filtering reaches half a voxel) shows the background; one inside
            // the live traces is white.
            let half_j = 18.0 * 25.004 / (23.0 * 24.996);
            let pixel = |k: f64, j: f64| {
                let x = -1.0 + 2.0 * k / 23.0;
                let y = half_j * (-1.0 + 2.0 * j / 18.0);
                let px = ((x + 1.0) / 2.0 * w) as u32;
                let py = ((1.0 - y) / 2.0 * hgt) as u32;
                let p = &image.data[4 * (py * image.width + px) as usize..][..3];
                p[0] + p[1] + p[2]
            };
            let what = format!("{volume}, {fidelity}");
            let mut dead_seen = 0;
            for k in (5..=45).map(|q| q as f64 / 10.0) {
                for j in (5..=35).map(|q| q as f64 / 10.0) {
                    assert!(pixel(k, j) < 0.01, "{what}: dead ({k}, {j}) drawn");
                    dead_seen += 1;
                }
            }
            assert!(dead_seen > 100);
            for (k, j) in [(8.0, 2.0), (3.0, 8.0), (15.0, 12.0), (22.5, 17.5)] {
                assert!(pixel(k, j) > 2.5, "{what}: live ({k}, {j}) not drawn");
            }
        }
    }
}
