//! MDIO v0 datasets (zarr v2, mdio-python 0.x): `data/chunked_012` with `metadata/live_mask`
//! and the dimensions' coordinates in the root `.zattrs`. Written here by zarr-python 3
//! (`zarr_format=2`, blosc as mdio 0.x writes it; installed by `.ci/run`), since mdio 0.x
//! and 1.x do not install side by side; the layout is mdio-python 0.8.5's (compared by hand
//! with its own output when this reader was written). Skipped (SKIPPED on stderr) without
//! `python3 -c "import zarr, numcodecs"`; `ARBVIS_NO_SKIP=1` makes a skip a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{data_file, headless, temp_dir};
use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::Scene;
use arbvis::store::convert::{convert, ConvertOptions};
use arbvis::store::Store;
use arbvis::volume::segy;

/// Writes an MDIO v0 dataset: RAW (float32, C order inline, crossline, sample) of the shape
/// given, traces where LIVE (uint8 per inline, crossline) is 0 dead and written as zeros,
/// as mdio 0.x does; inlines numbered 200, 202, ... (a step of 2), crosslines from 1000,
/// samples every 4 ms.
const WRITE_V0: &str = r#"
import sys, numpy as np, zarr
from numcodecs import Blosc
raw, out, nk, nj, ni, live = sys.argv[1], sys.argv[2], *map(int, sys.argv[3:6]), sys.argv[6]
a = np.fromfile(raw, "<f4").reshape(nk, nj, ni)
live = np.fromfile(live, "u1").reshape(nk, nj).astype(bool)
root = zarr.open_group(out, mode="w", zarr_format=2)
root.attrs.update({
    "api_version": "0.8.5",
    "dimension": [
        {"name": "inline", "coords": list(range(200, 200 + 2 * nk, 2))},
        {"name": "crossline", "coords": list(range(1000, 1000 + nj))},
        {"name": "sample", "coords": list(range(0, 4 * ni, 4))},
    ],
    "min": float(a.min()), "max": float(a.max()), "mean": float(a.mean()),
    "trace_count": int(live.sum()),
})
sep = {"name": "v2", "separator": "/"}
d = root.create_group("data").create_array("chunked_012", shape=a.shape,
    chunks=(16, 16, 32), dtype="<f4", fill_value=0.0, chunk_key_encoding=sep,
    compressors=Blosc(cname="zstd", clevel=5, shuffle=Blosc.SHUFFLE))
d[:] = np.where(live[:, :, None], a, 0)
m = root.create_group("metadata").create_array("live_mask", shape=live.shape,
    chunks=live.shape, dtype="|b1", fill_value=False, chunk_key_encoding=sep,
    compressors=Blosc(cname="lz4", clevel=5, shuffle=Blosc.SHUFFLE))
m[:] = live
zarr.consolidate_metadata(out)
"#;

fn has_zarr() -> bool {
    crate::common::python_has(
        "import zarr, numcodecs; assert int(zarr.__version__[0]) >= 3",
        "python3 with zarr 3 and numcodecs is missing (pip install zarr)",
    )
}

/// Traces dead in the test's dataset: inline 7, crosslines 3..12 (inside the grid).
fn dead(k: usize, j: usize) -> bool {
    k == 7 && (3..12).contains(&j)
}

/// The F3 crop as an MDIO v0 dataset with a row of dead traces, and its values.
fn write_v0(dir: &Path) -> (PathBuf, arbvis::volume::Volume) {
    let cube = segy::read(&data_file("seismic/f3.sgy"), &Default::default())
        .unwrap()
        .volume;
    let [ni, nj, nk] = cube.dims;
    // arbvis's values run i (sample) fastest, then crossline, then inline: MDIO's C order.
    let raw: Vec<u8> = cube.values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let live: Vec<u8> = (0..nk * nj)
        .map(|t| u8::from(!dead(t / nj, t % nj)))
        .collect();
    std::fs::write(dir.join("a.raw"), raw).unwrap();
    std::fs::write(dir.join("live.raw"), live).unwrap();
    std::fs::write(dir.join("write_v0.py"), WRITE_V0).unwrap();
    let out = dir.join("f3_v0.mdio");
    crate::common::stdout_of(
        Command::new("python3")
            .arg(dir.join("write_v0.py"))
            .arg(dir.join("a.raw"))
            .arg(&out)
            .args([nk, nj, ni].map(|n| n.to_string()))
            .arg(dir.join("live.raw")),
    );
    (out, cube)
}

#[test]
fn an_mdio_v0_dataset_reads_as_the_segy_does_with_dead_traces_as_no_data() {
    if !has_zarr() {
        return;
    }
    let dir = temp_dir("mdio-v0");
    let (v0, cube) = write_v0(&dir);
    let store = Store::open(&v0).unwrap();
    assert!(store.is_mdio());
    assert_eq!(store.meta.dims, cube.dims);
    let [ni, nj, _] = cube.dims;
    let got = store.region(0, 0, [0; 3], cube.dims).unwrap();
    for (n, (&g, &want)) in got.iter().zip(&cube.values).enumerate() {
        let (k, j) = (n / (ni * nj), n / ni % nj);
        if dead(k, j) {
            assert!(g.is_nan(), "dead trace {k}, {j}: {g}");
        } else {
            // Every live sample exactly: float32 holding the SEG-Y's int16 samples.
            assert_eq!(g, want, "sample {n}");
        }
    }
    // The dimensions' coordinates from the root attributes, on the axes.
    let src = &store.meta.source;
    assert_eq!(src.inlines, Some([200, 2]));
    assert_eq!(src.crosslines, Some([1000, 1]));
    assert_eq!(src.interval_us, Some(4000));
    assert!(
        src.facts["live traces"].starts_with("405 of 414"),
        "{:?}",
        src.facts
    );
    // inspect names the format and the way to levels.
    crate::common::assert_says(
        &crate::common::inspect(&v0),
        &[
            "format: MDIO v0.8.5 (zarr v2)",
            "inline: 23, numbers 200..244 (step 2)",
            "data/chunked_012: float32 shape [23, 18, 75], chunks [16, 16, 32], codecs bytes + blosc",
            "metadata/live_mask: bool",
            "(a zarr v2 dataset is not converted in place)",
        ],
    );
    drop(store);
    // Converted into a store of its own: the same samples, the dead traces dead; in place
    // it is refused (arbvis writes zarr v3 beside MDIO v1 arrays only).
    let o = ConvertOptions {
        progress: false,
        ..Default::default()
    };
    let e = convert(&v0, &v0, &o).unwrap_err().to_string();
    assert!(e.contains("MDIO v0") && e.contains("STORE"), "{e}");
    let copy = dir.join("copy.zarr");
    convert(&v0, &copy, &o).unwrap();
    let converted = Store::open(&copy).unwrap();
    let back = converted.region(0, 0, [0; 3], cube.dims).unwrap();
    assert!(back
        .iter()
        .zip(&got)
        .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())));
    assert_eq!(converted.meta.source.inlines, Some([200, 2]));
    // Drawn as it is and from the converted store: the same voxels at level 0, so the
    // same picture to the bit (both 8-bit targets, the same texture values).
    let h = headless(Backend::Egl);
    let render = |store: &Path| {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/store/f3.toml"),
        )
        .unwrap()
        .replace("../../f3.zarr", store.to_str().unwrap());
        let mut scene = Scene::parse(&text, "f3-v0.toml").unwrap();
        scene.base = dir.clone();
        scene.size = [96, 80];
        render_on(&h, &scene).unwrap().image
    };
    let (a, b) = (render(&v0), render(&copy));
    let lit = a.data.iter().filter(|&&v| v > 2.0 / 255.0).count();
    assert!(lit > 1000, "{lit} lit channels: nothing drawn");
    assert_eq!(a.data, b.data);
    std::fs::remove_dir_all(&dir).unwrap();
}
