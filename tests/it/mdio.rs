//! MDIO stores written by mdio-python (`multidimio` from PyPI, installed by `.ci/run`),
//! opened by arbvis: every sample equal to the same SEG-Y read by arbvis's own reader,
//! the dataset's inline, crossline and time coordinates on the axes, and dead traces
//! (`trace_mask` false) read as no data and drawn transparent. Skipped (SKIPPED on stderr)
//! without `python3 -c "import mdio"`; `ARBVIS_NO_SKIP=1` makes a skip a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{data_file, headless, temp_dir};
use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::Scene;
use arbvis::store::Store;
use arbvis::volume::segy;

/// mdio-python's SEG-Y ingestion of the F3 crop's header layout (rev 1: inline at byte 189,
/// crossline at 193, CDP x/y at 181/185), as its documentation shows it; written as
/// `ingest.py`, whose `segy_spec` other tests' scripts import.
pub(crate) const INGEST: &str = r#"
import sys
from mdio import segy_to_mdio
from mdio.builder.template_registry import get_template
from segy.standards import get_segy_standard
from segy.schema import HeaderField

def segy_spec():
    return get_segy_standard(1.0).customize(trace_header_fields=[
        HeaderField(name="inline", byte=189, format="int32"),
        HeaderField(name="crossline", byte=193, format="int32"),
        HeaderField(name="cdp_x", byte=181, format="int32"),
        HeaderField(name="cdp_y", byte=185, format="int32"),
    ])

def main():
    template = sys.argv[3] if len(sys.argv) > 3 else "PostStack3DTime"
    segy_to_mdio(segy_spec=segy_spec(), mdio_template=get_template(template),
                 input_path=sys.argv[1], output_path=sys.argv[2], overwrite=True)

if __name__ == "__main__":
    main()
"#;

pub(crate) fn has_mdio() -> bool {
    crate::common::python_has(
        "import mdio",
        "python3 with multidimio is missing (pip install multidimio)",
    )
}

/// The F3 crop ingested by mdio-python with `template` as `NAME.mdio` in a folder of its
/// own for test `test`: (the folder, the SEG-Y, the dataset); `None` without mdio-python
/// (the test skipped, or failed under `ARBVIS_NO_SKIP=1`).
pub(crate) fn f3_ingested(
    test: &str,
    name: &str,
    template: &str,
) -> Option<(PathBuf, PathBuf, PathBuf)> {
    if !has_mdio() {
        return None;
    }
    let dir = temp_dir(test);
    let sgy = data_file("seismic/f3.sgy");
    let mdio = ingest_as(&dir, &sgy, name, template);
    Some((dir, sgy, mdio))
}

/// A fresh folder for test `name`, F3's SEG-Y, and F3 converted into `f3.zarr` in that
/// folder in bricks of 8 (a plane crosses several).
pub(crate) fn f3_store(name: &str) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf) {
    let dir = temp_dir(name);
    let f3 = data_file("seismic/f3.sgy");
    let store = dir.join("f3.zarr");
    convert_quietly(&f3, &store, Some(8));
    (dir, f3, store)
}

/// `src` converted into the store `dst` by the library, quietly, in bricks of `brick`
/// (`None`: the default).
pub(crate) fn convert_quietly(src: &Path, dst: &Path, brick: Option<usize>) {
    let mut o = arbvis::store::convert::ConvertOptions {
        progress: false,
        ..Default::default()
    };
    if let Some(b) = brick {
        o.brick = b;
    }
    arbvis::store::convert::convert(src, dst, &o).unwrap();
}

/// `sgy` ingested by mdio-python into `DIR/NAME.mdio`.
fn ingest(dir: &Path, sgy: &Path, name: &str) -> PathBuf {
    ingest_as(dir, sgy, name, "PostStack3DTime")
}

/// `sgy` ingested by mdio-python into `DIR/NAME.mdio` with its template `template`.
pub(crate) fn ingest_as(dir: &Path, sgy: &Path, name: &str, template: &str) -> PathBuf {
    let script = dir.join("ingest.py");
    std::fs::write(&script, INGEST).unwrap();
    let out = dir.join(format!("{name}.mdio"));
    crate::common::stdout_of(
        Command::new("python3")
            .arg(&script)
            .arg(sgy)
            .arg(&out)
            .arg(template)
            .current_dir(dir),
    );
    out
}

/// The F3 crop without the traces of crosslines 0..9 of inlines 5..11 (a hole inside the
/// grid, which mdio-python keeps and marks dead).
fn with_hole(dir: &Path) -> PathBuf {
    let bytes = std::fs::read(data_file("seismic/f3.sgy")).unwrap();
    // 3600 bytes of headers, then traces of 240 + 75 x 2 bytes, 18 crosslines an inline.
    let trace = 240 + 75 * 2;
    let mut out = bytes[..3600].to_vec();
    for t in 0..23 * 18 {
        let (k, j) = (t / 18, t % 18);
        if !(HOLE_K.contains(&k) && HOLE_J.contains(&j)) {
            out.extend_from_slice(&bytes[3600 + t * trace..][..trace]);
        }
    }
    let path = dir.join("holes.sgy");
    std::fs::write(&path, out).unwrap();
    path
}

const HOLE_K: std::ops::Range<usize> = 5..11;
const HOLE_J: std::ops::Range<usize> = 0..9;

/// Level 0 of attribute 0, i fastest.
fn level0(store: &Store) -> Vec<f32> {
    store.region(0, 0, [0; 3], store.meta.dims).unwrap()
}

#[test]
fn an_mdio_store_from_mdio_python_reads_as_the_segy_does() {
    let Some((dir, sgy, mdio)) = f3_ingested("mdio-f3", "f3", "PostStack3DTime") else {
        return;
    };
    let store = Store::open(&mdio).unwrap();
    let cube = segy::read(&sgy, &Default::default()).unwrap().volume;
    assert_eq!(store.meta.dims, cube.dims);
    // Every sample exactly: MDIO holds the int16 samples as float32, as arbvis reads them.
    assert_eq!(level0(&store), cube.values);
    // The axes carry the dataset's own coordinates.
    let src = &store.meta.source;
    assert_eq!(src.inlines, Some([111, 1]));
    assert_eq!(src.crosslines, Some([875, 1]));
    assert_eq!(src.interval_us, Some(4000));
    assert!(
        src.facts["cdp_x"].starts_with("620181.9"),
        "{:?}",
        src.facts
    );
    assert!(store.is_mdio() && store.meta.levels == 1);
    // The survey's proportions as the SEG-Y's: its bins from cdp_x/cdp_y (the SEG-Y's
    // bytes 181/185 with their scalar, which mdio-python applied), 4 ms as 4 m. The
    // tolerance: f64 sums of a least-squares fit over 414 traces against the corners.
    for (a, b) in store.meta.spacing.iter().zip(cube.spacing) {
        assert!(
            (a - b).abs() < 1e-6 * b,
            "{:?} {:?}",
            store.meta.spacing,
            cube.spacing
        );
    }
    assert!(
        cube.spacing[1] > 10.0,
        "F3's bins are metres: {:?}",
        cube.spacing
    );
    // inspect describes it, the blosc codec and the trace headers it does not draw.
    crate::common::assert_says(
        &crate::common::inspect(&mdio),
        &[
            "format: MDIO v1.",
            "template: PostStack3DTime",
            "live traces: 414 of 414",
            "crossline: 18, numbers 875..892",
            "amplitude: float32 (inline, crossline, time) shape [23, 18, 75]",
            "codecs bytes + blosc",
            "headers: not read by arbvis",
        ],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The F3 store scene (scenes/store/f3.toml) on `store`, 160 px.
fn scene_on(dir: &Path, store: &Path) -> Scene {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/store/f3.toml"))
            .unwrap()
            .replace("../../f3.zarr", store.to_str().unwrap());
    let mut scene = Scene::parse(&text, "f3-mdio.toml").unwrap();
    scene.base = dir.to_path_buf();
    scene.size = [160, 160];
    scene
}

#[test]
fn dead_traces_read_as_no_data_and_draw_transparent() {
    if !has_mdio() {
        return;
    }
    let dir = temp_dir("mdio-holes");
    let full = ingest(&dir, &data_file("seismic/f3.sgy"), "full");
    let holes = ingest(&dir, &with_hole(&dir), "holes");
    let (a, b) = (Store::open(&full).unwrap(), Store::open(&holes).unwrap());
    // mdio-python keeps the whole grid and marks the missing traces dead.
    assert_eq!(a.meta.dims, b.meta.dims);
    assert!(b.meta.source.facts["live traces"].starts_with("360 of 414"));
    let (va, vb) = (level0(&a), level0(&b));
    let [ni, nj, _] = a.meta.dims;
    for (n, (x, y)) in va.iter().zip(&vb).enumerate() {
        let (k, j) = (n / (ni * nj), n / ni % nj);
        if HOLE_K.contains(&k) && HOLE_J.contains(&j) {
            assert!(y.is_nan(), "dead trace {k}, {j}: {y}");
        } else {
            assert_eq!(x, y, "live sample {n}");
        }
    }
    // Seen along the time axis (each pixel's ray runs down one trace), with a table whose
    // ends are opaque: the pixels over the hole go dark, about its share of the traces
    // (54 of 414), and nothing new lights up. Dead traces drawn as any value the table
    // shows (the lowest amplitude, or zero with a table that shows zero) would keep them lit.
    let h = headless(Backend::Egl);
    for fidelity in [
        arbvis::vocab::Fidelity::Faithful,
        arbvis::vocab::Fidelity::Precise,
    ] {
        let render = |store: &Path| {
            let mut scene = scene_on(&dir, store);
            scene.fidelity = fidelity;
            scene.camera.rotation = [
                0.0,
                std::f64::consts::FRAC_1_SQRT_2,
                0.0,
                std::f64::consts::FRAC_1_SQRT_2,
            ];
            let bg = scene.background;
            let image = render_on(&h, &scene).unwrap().image;
            image
                .data
                .chunks_exact(4)
                .map(|p| (0..3).any(|c| (p[c] - bg[c]).abs() > 2.0 / 255.0))
                .collect::<Vec<bool>>()
        };
        let (la, lb) = (render(&full), render(&holes));
        let lit = la.iter().filter(|&&x| x).count();
        let darkened = la.iter().zip(&lb).filter(|(a, b)| **a && !**b).count();
        let lightened = la.iter().zip(&lb).filter(|(a, b)| !**a && **b).count();
        // 54/414 = 13 % of the traces; the hole's edge pixels blend with live traces.
        assert!(
            darkened * 100 >= lit * 8,
            "{fidelity:?}: {darkened} of {lit} lit pixels went dark"
        );
        assert!(
            lightened * 100 <= lit,
            "{fidelity:?}: {lightened} pixels lit up"
        );
    }
    // Converted into a store of its own, the dataset keeps its dead traces dead.
    let copy = dir.join("copy.zarr");
    convert_quietly(&holes, &copy, None);
    let mask = arbvis::store::zarr::open_array(&copy.join("trace_mask")).unwrap();
    let live = mask.read_chunk(&[0, 0]).unwrap().unwrap();
    let dead = (0..23 * 18)
        .filter(|t| live[(t / 18) * 64 + t % 18] == 0.0)
        .count();
    assert_eq!(dead, HOLE_K.len() * HOLE_J.len());
    let nan = level0(&Store::open(&copy).unwrap())
        .iter()
        .filter(|v| v.is_nan())
        .count();
    assert_eq!(nan, dead * 75);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// arbvis's own store opened by mdio-python and xarray: the same amplitude, coordinates
/// and map coordinates as mdio-python's ingestion of the same SEG-Y, every level a
/// dataset of the data tree.
#[test]
fn an_arbvis_store_opens_in_mdio_python_and_xarray() {
    let Some((dir, sgy, theirs)) = f3_ingested("mdio-arbvis", "theirs", "PostStack3DTime") else {
        return;
    };
    let ours = dir.join("ours.zarr");
    convert_quietly(&sgy, &ours, Some(16));
    let script = r#"
import sys, numpy as np, xarray as xr, mdio
ours, theirs = mdio.open_mdio(sys.argv[1]), mdio.open_mdio(sys.argv[2])
for name in ["amplitude", "inline", "crossline", "time", "cdp_x", "cdp_y", "trace_mask"]:
    a, b = ours[name].values, theirs[name].values
    print(name, a.shape == b.shape and bool(np.array_equal(a, b)))
print("envelope", ours["envelope"].dims, ours["envelope"].dtype)
print("stats", ours["amplitude"].attrs["statsV1"][:9])
tree = xr.open_datatree(sys.argv[1], engine="zarr", consolidated=False)
print("levels", sorted(k for k in tree.children))
print("level_1", tree["level_1"]["amplitude"].dims, tree["level_1"]["amplitude"].shape)
"#;
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(&ours)
        .arg(&theirs)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for want in [
        "amplitude True",
        "inline True",
        "crossline True",
        "time True",
        "cdp_x True",
        "cdp_y True",
        "trace_mask True",
        "envelope ('inline', 'crossline', 'time') float32",
        "stats {\"count\"",
        "levels ['level_1', 'level_2', 'level_3']",
        "level_1 ('inline_1', 'crossline_1', 'time_1') (12, 9, 38)",
    ] {
        assert!(text.contains(want), "{want}\n{text}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every file of `dir` but its root `zarr.json`, with its bytes.
fn files_but_root(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p != dir.join("zarr.json") {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// `arbvis convert DATASET` adds levels, ranges and the derived attributes beside an MDIO
/// dataset's own arrays, which it leaves byte for byte; resumable; and the dataset still
/// opens in mdio-python with the same amplitude.
#[test]
fn convert_adds_levels_to_an_mdio_dataset_in_place() {
    if !has_mdio() {
        return;
    }
    let dir = temp_dir("mdio-in-place");
    let original = ingest(&dir, &with_hole(&dir), "holes");
    let before = files_but_root(&original);
    let whole = Store::open(&original).unwrap();
    let want = level0(&whole);
    drop(whole);
    // Stopped after one column, then resumed, by the command a user runs.
    let o = arbvis::store::convert::ConvertOptions {
        brick: 16,
        progress: false,
        stop_after: Some(1),
        ..Default::default()
    };
    assert!(arbvis::store::convert::convert(&original, &original, &o).is_err());
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["convert", original.to_str().unwrap(), "--brick", "16"])
        .env("CI", "true")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // MDIO's own files are as they were.
    let after = files_but_root(&original);
    for (path, bytes) in &before {
        let now = after.iter().find(|(p, _)| p == path).map(|(_, b)| b);
        assert_eq!(now, Some(bytes), "{} changed", path.display());
    }
    let store = Store::open(&original).unwrap();
    assert!(
        !store.is_mdio() && store.meta.levels == 4,
        "{:?}",
        store.meta.levels
    );
    assert_eq!(store.meta.source_variable.as_deref(), Some("amplitude"));
    let got = level0(&store);
    assert!(got
        .iter()
        .zip(&want)
        .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())));
    // The coarser levels hold the box filter of level 0 (a spot check of one voxel).
    let coarse = store.region(0, 1, [3, 5, 8], [1, 1, 1]).unwrap()[0];
    let [ni, nj, _] = store.meta.dims;
    let cell: Vec<f32> = (0..8)
        .map(|n| {
            let (i, j, k) = (6 + (n & 1), 10 + ((n >> 1) & 1), 16 + (n >> 2));
            want[i + ni * (j + nj * k)]
        })
        .filter(|v| v.is_finite())
        .collect();
    let mean = cell.iter().map(|&v| v as f64).sum::<f64>() / cell.len() as f64;
    assert!(
        (coarse as f64 - mean).abs() <= 1e-3 * mean.abs().max(1.0),
        "{coarse} {mean}"
    );
    // mdio-python still reads its variable, and xarray every level.
    let script = r#"
import sys, numpy as np, xarray as xr, mdio
ds = mdio.open_mdio(sys.argv[1])
print("vars", sorted(ds.data_vars))
tree = xr.open_datatree(sys.argv[1], engine="zarr", consolidated=False)
print("levels", sorted(tree.children))
"#;
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(&original)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("'amplitude', 'amplitude_range', 'envelope'"),
        "{text}"
    );
    assert!(
        text.contains("levels ['level_1', 'level_2', 'level_3']"),
        "{text}"
    );
    // A second run says there is nothing to do.
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["convert", original.to_str().unwrap(), "--brick", "16"])
        .output()
        .unwrap();
    crate::common::refused(&out, "were added already");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One survey draws as one picture from every path (issue 54 item 1): the SEG-Y file, the
/// store arbvis converts from it and the dataset mdio-python ingests from it, by one scene
/// that leaves the proportions to the data (no `spacing`), level 0 and one fixed range.
#[test]
fn one_survey_draws_one_picture_from_its_segy_store_and_mdio_dataset() {
    let Some((dir, sgy, mdio)) = f3_ingested("mdio-one-picture", "f3", "PostStack3DTime") else {
        return;
    };
    let store = dir.join("f3.zarr");
    convert_quietly(&sgy, &store, None);
    let scene = |volume: String, stored: bool| {
        let level = if stored {
            "[technique.opacity3d.store]\nlevel = 0\n"
        } else {
            ""
        };
        let text = format!(
            "size = [128, 128]\nbackground = [0.0, 0.0, 0.0, 1.0]\n[camera]\nrotation = [0.3265, -0.0923, -0.7011, 0.6272]\nzoom = 0.7\n\
             [technique.opacity3d]\nslices = 128\ncombine = \"product\"\n[technique.opacity3d.primary]\nvolume = {volume}\nattribute = \"amplitude\"\n\
             quantize = {{ range = [-6000.0, 6000.0] }}\ntable = {{ builtin = \"seismic\", alpha = [[0.0, 1.0], [0.3, 0.5], [0.45, 0.0], [0.55, 0.0], [0.7, 0.5], [1.0, 1.0]] }}\n{level}"
        );
        let mut s = Scene::parse(&text, "one-picture").unwrap();
        s.base = dir.clone();
        s
    };
    let at = |p: &Path| format!("{{ store = {:?} }}", p.to_str().unwrap());
    let h = headless(Backend::Egl);
    let draw = |s: &Scene| render_on(&h, s).unwrap().image;
    let own = draw(&scene(at(&store), true));
    let theirs = draw(&scene(at(&mdio), true));
    let direct = draw(&scene(
        format!("{{ segy = {:?} }}", sgy.to_str().unwrap()),
        false,
    ));
    // Both stores through one renderer: the same samples at the same proportions and
    // place, so the same picture, bit for bit.
    let d = own.compare(&theirs, 0.0).unwrap();
    assert!(
        d.max_abs == 0.0,
        "arbvis store against mdio-python's: {d:?}"
    );
    // The SEG-Y drawn whole by the slicing renderer: the same picture but for how the two
    // renderers sample (slices against bricks: RMSE 0.0006, at most 0.063 in a pixel on
    // this view when measured); bounded at RMSE 0.005, where the two proportions of the
    // issue differed by 0.35.
    let d = own.compare(&direct, 1.0).unwrap();
    assert!(d.rmse < 0.005, "store against the SEG-Y: {d:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
