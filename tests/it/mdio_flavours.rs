//! Every MDIO flavour mdio-python writes (issue 42, item 2), made by mdio-python itself
//! (`multidimio` and numcodecs' `zfpy` from PyPI, installed by `.ci/run`): MDIO v1 on
//! zarr v2 (`default_zarr_format = 2`) and v3, with blosc and with ZFP in each of its
//! modes (mdio-python's ZFP compressor on a template's variable); and an MDIO v0 dataset
//! with ZFP (the v0 layout written by zarr-python, as `mdio_v0.rs` does). Reversible ZFP
//! reads back the SEG-Y's samples bit for bit and is called lossless; the lossy modes
//! read back what zarr-python decodes, bit for bit, and `inspect` calls them lossy. Also:
//! coordinates checked at open, a damaged chunk named by its own file. Skipped (SKIPPED
//! on stderr) without `python3 -c "import mdio, zfpy"`; `ARBVIS_NO_SKIP=1` makes a skip
//! a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use arbvis::store::Store;
use arbvis::volume::segy;

use crate::common::{data_file, inspect, stdout_of, temp_dir};

fn has_mdio_zfp() -> bool {
    crate::common::python_has(
        "import mdio, zfpy, numcodecs.zfpy",
        "python3 with multidimio and zfpy is missing (pip install multidimio zfpy==1.0.1)",
    )
}

/// mdio-python ingests the F3 crop (`argv[1]`) into `argv[2]` on zarr format `argv[3]`
/// (the header layout of `mdio.rs`'s `ingest.py`, beside it) with the amplitude
/// compressed by `argv[4]`: `blosc` (mdio's default) or a ZFP mode;
/// then zarr-python's decoding of the amplitude goes to `argv[2].f32` (inline, crossline,
/// time; little-endian).
const INGEST: &str = r#"
import sys, zarr
sgy, out, fmt, codec = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
zarr.config.set({"default_zarr_format": fmt})
import numcodecs.zfpy
# numcodecs 0.16 sets compression_kwargs only for modes 2-4: reversible (5) fails without.
if not hasattr(numcodecs.zfpy.ZFPY, "compression_kwargs"):
    numcodecs.zfpy.ZFPY.compression_kwargs = {}
from mdio import segy_to_mdio
from mdio.builder.template_registry import get_template
from mdio.builder.templates.seismic_3d_poststack import Seismic3DPostStackTemplate
from mdio.builder.schemas.compressors import ZFP, ZFPMode
from mdio.builder.schemas.dtype import ScalarType
from mdio.builder.schemas.chunk_grid import RegularChunkGrid, RegularChunkShape
from mdio.builder.schemas.v1.variable import VariableMetadata
from ingest import segy_spec

ZFPS = {
    "reversible": ZFP(mode=ZFPMode.REVERSIBLE),
    "accuracy": ZFP(mode=ZFPMode.FIXED_ACCURACY, tolerance=1.0),
    "rate": ZFP(mode=ZFPMode.FIXED_RATE, rate=8.0),
    "precision": ZFP(mode=ZFPMode.FIXED_PRECISION, precision=16),
}

class ZfpPostStack(Seismic3DPostStackTemplate):
    """mdio's PostStack3DTime, the amplitude compressed by ZFP."""
    def _add_variables(self):
        grid = RegularChunkGrid(configuration=RegularChunkShape(chunk_shape=self.full_chunk_shape))
        self._builder.add_variable(
            name=self.default_variable_name, dimensions=self._dim_names,
            data_type=ScalarType.FLOAT32, compressor=ZFPS[codec],
            coordinates=self.coordinate_names,
            metadata=VariableMetadata(chunk_grid=grid, units_v1=self.get_unit_by_key(self._default_variable_name)))

def main():
    template = get_template("PostStack3DTime") if codec == "blosc" else ZfpPostStack("time")
    segy_to_mdio(segy_spec=segy_spec(), mdio_template=template, input_path=sgy, output_path=out, overwrite=True)
    a = zarr.open_group(out, mode="r")["amplitude"][:]
    a.astype("<f4").tofile(out + ".f32")

if __name__ == "__main__":
    main()
"#;

fn ingest(dir: &Path, format: u8, codec: &str) -> PathBuf {
    std::fs::write(dir.join("ingest.py"), crate::mdio::INGEST).unwrap();
    let script = dir.join("flavour.py");
    std::fs::write(&script, INGEST).unwrap();
    let out = dir.join(format!("f3-{codec}-v{format}.mdio"));
    stdout_of(
        Command::new("python3")
            .arg(&script)
            .arg(data_file("seismic/f3.sgy"))
            .arg(&out)
            .arg(format.to_string())
            .arg(codec)
            .current_dir(dir),
    );
    out
}

/// zarr-python's decoding of the dataset's amplitude, i fastest (as arbvis holds it).
fn zarr_python_values(dataset: &Path) -> Vec<f32> {
    let bytes = std::fs::read(dataset.with_extension("mdio.f32")).unwrap();
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn level0(store: &Store) -> Vec<f32> {
    store.region(0, 0, [0; 3], store.meta.dims).unwrap()
}

#[test]
fn every_mdio_flavour_mdio_python_writes_opens() {
    if !has_mdio_zfp() {
        return;
    }
    let dir = temp_dir("mdio-flavours");
    let f3 = segy::read(&data_file("seismic/f3.sgy"), &Default::default())
        .unwrap()
        .volume;
    for (format, codec) in [
        (2, "blosc"),
        (3, "reversible"),
        (2, "reversible"),
        (3, "accuracy"),
        (2, "rate"),
        (3, "precision"),
    ] {
        let what = format!("zarr v{format}, {codec}");
        let dataset = ingest(&dir, format, codec);
        let store = Store::open(&dataset).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(store.meta.dims, f3.dims, "{what}");
        let values = level0(&store);
        let text = inspect(&dataset);
        assert!(
            text.contains(&format!("(zarr v{format})")),
            "{what}: {text}"
        );
        match codec {
            "blosc" | "reversible" => {
                // Lossless: the SEG-Y's samples, bit for bit.
                assert_eq!(values, f3.values, "{what}");
                assert!(!text.contains("lossy"), "{what}: {text}");
                assert_eq!(store.lossy(), None, "{what}");
            }
            _ => {
                // Lossy: what zarr-python decodes, bit for bit; inspect says it.
                assert_eq!(
                    values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    zarr_python_values(&dataset)
                        .iter()
                        .map(|v| v.to_bits())
                        .collect::<Vec<_>>(),
                    "{what}"
                );
                assert_ne!(values, f3.values, "{what}: lossy changes some samples");
                assert!(text.contains("lossy"), "{what}: {text}");
                assert!(store.lossy().is_some_and(|c| c.contains("lossy")), "{what}");
            }
        }
        if codec == "reversible" {
            assert!(text.contains("zfpy (reversible: lossless)"), "{text}");
        }
        // Converted into a store of its own, its levels from the decoded values.
        let out = dir.join(format!("{codec}-v{format}.zarr"));
        stdout_of(
            Command::new(env!("CARGO_BIN_EXE_arbvis"))
                .arg("convert")
                .arg(&dataset)
                .arg(&out),
        );
        let converted = Store::open(&out).unwrap();
        assert_eq!(level0(&converted), values, "{what}: converted");
        // A store converted from lossy data says so, as the dataset does.
        assert_eq!(
            converted.lossy().is_some(),
            store.lossy().is_some(),
            "{what}"
        );
    }
}

/// An MDIO v0 dataset as mdio-python 0.9 writes one with ZFP (`lossless=False`: fixed
/// accuracy, 64³ chunks), laid out by zarr-python: read as zarr-python decodes it.
const WRITE_V0_ZFP: &str = r#"
import sys, numpy as np, zarr
from numcodecs.zfpy import ZFPY
raw, out, nk, nj, ni = sys.argv[1], sys.argv[2], *map(int, sys.argv[3:6])
a = np.fromfile(raw, "<f4").reshape(nk, nj, ni)
root = zarr.open_group(out, mode="w", zarr_format=2)
root.attrs.update({
    "api_version": "0.9.3",
    "dimension": [
        {"name": "inline", "coords": list(range(111, 111 + nk))},
        {"name": "crossline", "coords": list(range(875, 875 + nj))},
        {"name": "sample", "coords": list(range(0, 4 * ni, 4))},
    ],
    "min": float(a.min()), "max": float(a.max()), "mean": float(a.mean()),
    "trace_count": nk * nj,
})
sep = {"name": "v2", "separator": "/"}
d = root.create_group("data").create_array("chunked_012", shape=a.shape,
    chunks=(64, 64, 64), dtype="<f4", fill_value=0.0, chunk_key_encoding=sep,
    compressors=ZFPY(mode=4, tolerance=0.01))
d[:] = a
np.asarray(d[:]).astype("<f4").tofile(out + ".f32")
zarr.consolidate_metadata(out)
"#;

#[test]
fn an_mdio_v0_dataset_with_zfp_reads_as_zarr_python_decodes_it() {
    if !has_mdio_zfp() {
        return;
    }
    let dir = temp_dir("mdio-v0-zfp");
    let f3 = segy::read(&data_file("seismic/f3.sgy"), &Default::default())
        .unwrap()
        .volume;
    // The samples inline-major, as the dataset holds them (arbvis: i fastest, k slowest:
    // the same order).
    let raw = dir.join("f3.f32");
    let bytes: Vec<u8> = f3.values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&raw, bytes).unwrap();
    let script = dir.join("v0.py");
    std::fs::write(&script, WRITE_V0_ZFP).unwrap();
    let out = dir.join("f3-v0.mdio");
    let [ni, nj, nk] = f3.dims;
    stdout_of(
        Command::new("python3")
            .arg(&script)
            .arg(&raw)
            .arg(&out)
            .args([nk.to_string(), nj.to_string(), ni.to_string()]),
    );
    let store = Store::open(&out).unwrap();
    assert_eq!(level0(&store), zarr_python_values(&out));
    let text = inspect(&out);
    assert!(text.contains("zfpy (fixed accuracy 0.01: lossy)"), "{text}");
}

/// Dimension coordinates are checked at open, a damaged chunk names its own file: on a
/// dataset from mdio-python, its coordinate arrays and a chunk rewritten by zarr-python.
const DAMAGE: &str = r#"
import sys, numpy as np, zarr
out, what = sys.argv[1], sys.argv[2]
g = zarr.open_group(out, mode="r+")
if what == "repeat":
    c = np.asarray(g["crossline"][:]); c[5] = c[4]; g["crossline"][:] = c
elif what == "order":
    c = np.asarray(g["inline"][:]); c[3], c[4] = c[4], c[3]; g["inline"][:] = c
elif what == "rechunk":
    a = g["amplitude"]
    data, attrs, names = a[:], dict(a.attrs), a.metadata.dimension_names
    b = g.create_array("amplitude", shape=data.shape, chunks=(8, 8, 32), dtype="float32",
                       fill_value=np.nan, dimension_names=names, overwrite=True)
    b[:] = data
    b.attrs.update(attrs)
"#;

#[test]
fn mdio_coordinates_are_checked_and_a_damaged_chunk_names_its_file() {
    if !crate::mdio::has_mdio() {
        return;
    }
    let dir = temp_dir("mdio-coordinates");
    let sgy = data_file("seismic/f3.sgy");
    let base = crate::mdio::ingest_as(&dir, &sgy, "base", "PostStack3DTime");
    let script = dir.join("damage.py");
    std::fs::write(&script, DAMAGE).unwrap();
    for (what, wants) in [
        ("repeat", "crossline[5] = 879 repeats crossline[4] = 879"),
        (
            "order",
            "inline[4] = 114 breaks the order of inline[3] = 115",
        ),
    ] {
        let copy = dir.join(format!("{what}.mdio"));
        crate::common::copy_tree(&base, &copy);
        stdout_of(Command::new("python3").arg(&script).arg(&copy).arg(what));
        let e = Store::open(&copy).err().expect("refused").to_string();
        assert!(
            e.contains(wants) && e.contains(&format!("{what}.mdio/")),
            "{what}: {e}"
        );
    }
    // A coordinate array gone.
    let copy = dir.join("missing.mdio");
    crate::common::copy_tree(&base, &copy);
    std::fs::remove_dir_all(copy.join("time")).unwrap();
    let e = Store::open(&copy).err().expect("refused").to_string();
    assert!(e.contains("no `time` coordinate"), "{e}");
    // A damaged chunk of a dataset chunked finer than the renderer's bricks (8 x 8 x 32):
    // the chunk's own file and index, not the brick's.
    let copy = dir.join("damaged.mdio");
    crate::common::copy_tree(&base, &copy);
    stdout_of(
        Command::new("python3")
            .arg(&script)
            .arg(&copy)
            .arg("rechunk"),
    );
    let chunk = copy.join("amplitude/c/1/1/1");
    let mut bytes = std::fs::read(&chunk).unwrap();
    let n = bytes.len();
    bytes[n / 2..].iter_mut().for_each(|b| *b ^= 0x5a);
    std::fs::write(&chunk, bytes).unwrap();
    let store = Store::open(&copy).unwrap();
    let e = store
        .region(0, 0, [0; 3], store.meta.dims)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&chunk.display().to_string()) && e.contains("[1, 1, 1]"),
        "{e}"
    );
}

/// `arbvis convert DATASET ARGS` in place, to its end: its standard error.
fn convert_in_place(dataset: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["convert", dataset.to_str().unwrap(), "--brick", "8"])
        .env("CI", "true")
        .output()
        .unwrap()
}

#[test]
fn damaged_added_levels_are_made_again_never_called_complete() {
    if !crate::mdio::has_mdio() {
        return;
    }
    let dir = temp_dir("mdio-repair");
    let dataset =
        crate::mdio::ingest_as(&dir, &data_file("seismic/f3.sgy"), "f3", "PostStack3DTime");
    let out = convert_in_place(&dataset);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let whole = Store::open(&dataset).unwrap();
    let levels = whole.meta.levels;
    let want: Vec<Vec<f32>> = (1..levels)
        .map(|l| {
            whole
                .region(0, l, [0; 3], whole.meta.level_dims(l))
                .unwrap()
        })
        .collect();
    drop(whole);
    // Whole: nothing to add.
    let out = convert_in_place(&dataset);
    crate::common::refused(&out, "were added already");
    // Half of level 1's chunk files deleted, then a whole level's metadata: each time the
    // levels are made again, the same as before.
    let chunks: Vec<PathBuf> = walk(&dataset.join("level_1/amplitude/c"));
    assert!(chunks.len() > 4, "{} chunks", chunks.len());
    for damage in ["chunks", "level"] {
        match damage {
            "chunks" => chunks
                .iter()
                .step_by(2)
                .for_each(|c| std::fs::remove_file(c).unwrap()),
            _ => std::fs::remove_file(dataset.join(format!("level_{}/zarr.json", levels - 1)))
                .unwrap(),
        }
        let out = convert_in_place(&dataset);
        let e = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{damage}: {e}");
        assert!(
            e.contains("damaged") && e.contains("adding them again"),
            "{damage}: {e}"
        );
        let store = Store::open(&dataset).unwrap();
        assert_eq!(store.missing_file(), None, "{damage}");
        for (l, w) in want.iter().enumerate() {
            let got = store
                .region(0, l + 1, [0; 3], store.meta.level_dims(l + 1))
                .unwrap();
            assert!(
                got.iter()
                    .zip(w)
                    .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())),
                "{damage}: level {}",
                l + 1
            );
        }
    }
}

/// Every file under `folder`, recursively.
fn walk(folder: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(folder).unwrap().flatten() {
        let p = entry.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// The attributes of the nodes mdio-python's dataset and arbvis's store of the same SEG-Y
/// share, compared: `same` when every one mdio-python writes is there with the same
/// value (`createdOn` and `statsV1` as kinds, not values).
const ATTRIBUTES: &str = r#"
import sys, json, os
theirs, ours = sys.argv[1], sys.argv[2]
def meta(root, node):
    return json.load(open(os.path.join(root, node, "zarr.json")))
diffs = []
for node in ["", "amplitude", "trace_mask", "cdp_x", "cdp_y", "inline", "crossline", "time"]:
    t, o = meta(theirs, node), meta(ours, node)
    if t.get("fill_value") != o.get("fill_value"):
        diffs.append(f"{node or '/'} fill_value {t.get('fill_value')} != {o.get('fill_value')}")
    if t.get("dimension_names") != o.get("dimension_names"):
        diffs.append(f"{node or '/'} dimension_names")
    ta, oa = t.get("attributes", {}), o.get("attributes", {})
    for k, v in ta.items():
        if k not in oa:
            diffs.append(f"{node or '/'} lacks {k}")
        elif k not in ("createdOn", "statsV1") and oa[k] != v:
            diffs.append(f"{node or '/'} {k}: {oa[k]} != {v}")
print("same" if not diffs else "\n".join(diffs))
"#;

#[test]
fn arbvis_stores_carry_what_mdio_python_writes_on_the_same_segy() {
    if !crate::mdio::has_mdio() {
        return;
    }
    let dir = temp_dir("mdio-attributes");
    let sgy = data_file("seismic/f3.sgy");
    let theirs = crate::mdio::ingest_as(&dir, &sgy, "theirs", "PostStack3DTime");
    let ours = dir.join("ours.zarr");
    stdout_of(
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("convert")
            .arg(&sgy)
            .arg(&ours),
    );
    let script = dir.join("attributes.py");
    std::fs::write(&script, ATTRIBUTES).unwrap();
    let out = stdout_of(Command::new("python3").arg(&script).arg(&theirs).arg(&ours));
    assert_eq!(out.trim(), "same");
}
