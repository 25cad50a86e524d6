//! COPC as copclib writes it and COPC copclib reads (issue 42, item 3), with copclib from
//! PyPI (RockRobotic's C++ library, installed by `.ci/run`): copclib writes each hierarchy
//! page as an EVLR of its own (child pages before their parents); a key whose parent has
//! no entry is read as copclib reads it; and every COPC arbvis writes, from an input with
//! a coordinate system or without, opens in copclib (which wants LAS 1.4's WKT bit) with
//! the points laspy reads. Skipped (SKIPPED on stderr) without `python3 -c "import
//! copclib, laspy, lazrs"`; `ARBVIS_NO_SKIP=1` makes a skip a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use arbvis::points::copc::Copc;

use crate::common::{data_file, stdout_of, temp_dir};

fn has_copclib() -> bool {
    crate::common::python_has(
        "import copclib, laspy, lazrs",
        "python3 with copclib, laspy and lazrs is missing (pip install copclib laspy lazrs)",
    )
}

/// copclib writes `argv[1]`: `argv[2]` points of format 7, random over a folded surface,
/// spread over levels 0-4 (four times the points a level down), each node of level 2 and
/// below in the page of its level-2 ancestor (an EVLR each); with `orphan`, the first
/// level-1 node that has children loses its entry (its points go down a level).
const WRITE: &str = r#"
import sys
import numpy as np
import laspy, copclib as copc
out, n, orphan = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "orphan"
rng = np.random.default_rng(5)
scale, offset = np.array([0.01] * 3), np.array([637000.0, 851000.0, 0.0])
xyz = np.array([637012.34, 851123.45, 80.0]) + rng.random((n, 3)) * [1000.0, 800.0, 150.0]
xyz[:, 2] = 140 + 40 * np.sin(xyz[:, 0] / 97) * np.cos(xyz[:, 1] / 61) + rng.normal(0, 8, n)
XYZ = np.round((xyz - offset) / scale).astype(np.int32)
xyz = XYZ * scale + offset
lo, span = xyz.min(axis=0), float((xyz.max(axis=0) - xyz.min(axis=0)).max())
def key(i, d):
    k = np.minimum(np.floor((xyz[i] - lo) / (span / 2 ** d)).astype(int), 2 ** d - 1)
    return (d, *map(int, k))
w = 4.0 ** np.arange(5)
levels = rng.choice(5, size=n, p=w / w.sum())
nodes = {}
for i in range(n):
    nodes.setdefault(key(i, int(levels[i])), []).append(i)
for d in range(4, 0, -1):  # every ancestor holds a point
    for k in [k for k in nodes if k[0] == d]:
        parent = (d - 1, k[1] // 2, k[2] // 2, k[3] // 2)
        if parent not in nodes and len(nodes[k]) > 1:
            nodes[parent] = [nodes[k].pop()]
if orphan:
    k = min(k for k in nodes if k[0] == 1 and any(c[0] == 2 and (c[1] // 2, c[2] // 2, c[3] // 2) == k[1:] for c in nodes))
    for i in nodes.pop(k):
        nodes.setdefault(key(i, 2), []).append(i)
rec = np.zeros(n, dtype=laspy.PointFormat(7).dtype())
rec["X"], rec["Y"], rec["Z"] = XYZ.T
rec["intensity"] = rng.integers(0, 65535, n)
rec["bit_fields"] = 1 | (1 << 4)
rec["classification"] = rng.choice([1, 2, 5, 6], n)
rec["gps_time"] = 3e8 + rng.random(n) * 3600
for c in ("red", "green", "blue"):
    rec[c] = rng.integers(0, 65535, n)
cfg = copc.CopcConfigWriter(point_format_id=7, scale=tuple(scale), offset=tuple(offset), wkt="")
cfg.las_header.min, cfg.las_header.max = copc.Vector3(*xyz.min(axis=0)), copc.Vector3(*xyz.max(axis=0))
cfg.copc_info.center_x, cfg.copc_info.center_y, cfg.copc_info.center_z = (lo + span / 2).tolist()
cfg.copc_info.halfsize, cfg.copc_info.spacing = span / 2, span / 128
writer = copc.FileWriter(out, cfg)
for k in sorted(nodes):
    page = (2, k[1] >> (k[0] - 2), k[2] >> (k[0] - 2), k[3] >> (k[0] - 2)) if k[0] >= 2 else (0, 0, 0, 0)
    data = rec[np.array(sorted(nodes[k]))].tobytes()
    writer.AddNode(copc.VoxelKey(*k), copc.VectorChar(np.frombuffer(data, np.int8)), copc.VoxelKey(*page))
writer.Close()
"#;

/// copclib's and laspy's reading of `argv[1]`: `copclib N SUMX SUMY SUMZ` over every node
/// `GetAllNodes` gives, then `laspy N SUMX SUMY SUMZ` of `laspy.read`; raw integers.
const READ: &str = r#"
import sys
import numpy as np
import laspy, copclib as copc
reader = copc.FileReader(sys.argv[1])
n, s = 0, np.zeros(3, np.int64)
header = reader.copc_config.las_header
dtype = laspy.PointFormat(header.point_format_id).dtype()
if header.point_record_length > dtype.itemsize:  # extra bytes
    dtype = np.dtype(dtype.descr + [("extra", f"V{header.point_record_length - dtype.itemsize}")])
for node in reader.GetAllNodes():
    pts = np.frombuffer(bytes(reader.GetPointData(node)), dtype=dtype)
    n += len(pts)
    s += [pts["X"].astype(np.int64).sum(), pts["Y"].astype(np.int64).sum(), pts["Z"].astype(np.int64).sum()]
print("copclib", n, *s)
las = laspy.read(sys.argv[1])
print("laspy", len(las.points), int(las.X.astype(np.int64).sum()), int(las.Y.astype(np.int64).sum()), int(las.Z.astype(np.int64).sum()))
"#;

fn python(dir: &Path, name: &str, script: &str, args: &[&str]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, script).unwrap();
    stdout_of(Command::new("python3").arg(&path).args(args))
}

/// arbvis's count and raw sums of every point of `path`, as [`READ`] prints them.
fn ours(path: &Path) -> String {
    let c = Copc::open(path).unwrap();
    let (mut n, mut s) = (0u64, [0i64; 3]);
    for node in c.all_nodes().unwrap() {
        let p = c.read_node(&node).unwrap();
        n += p.len() as u64;
        for (sum, values) in s.iter_mut().zip([
            p.x_raw().map(i64::from).sum::<i64>(),
            p.y_raw().map(i64::from).sum(),
            p.z_raw().map(i64::from).sum(),
        ]) {
            *sum += values;
        }
    }
    format!("{n} {} {} {}", s[0], s[1], s[2])
}

fn write_with_copclib(dir: &Path, name: &str, orphan: bool) -> PathBuf {
    let out = dir.join(name);
    let mode = if orphan { "orphan" } else { "whole" };
    python(
        dir,
        "write.py",
        WRITE,
        &[out.to_str().unwrap(), "20000", mode],
    );
    out
}

#[test]
fn copclib_files_read_page_by_page_orphans_included() {
    if !has_copclib() {
        return;
    }
    let dir = temp_dir("copclib-read");
    for (name, orphan) in [("paged.copc.laz", false), ("orphan.copc.laz", true)] {
        let path = write_with_copclib(&dir, name, orphan);
        let theirs = python(&dir, "read.py", READ, &[path.to_str().unwrap()]);
        let lines: Vec<&str> = theirs.lines().collect();
        let copclib = lines[0].strip_prefix("copclib ").unwrap();
        assert_eq!(lines[1].strip_prefix("laspy ").unwrap(), copclib, "{name}");
        assert_eq!(
            ours(&path),
            copclib,
            "{name}: arbvis reads what copclib and laspy read"
        );
        // Its pages are EVLRs of their own: more than one read, the first at opening.
        let c = Copc::open(&path).unwrap();
        let (read, unread) = c.pages();
        assert!(
            read == 1 && unread > 1,
            "{name}: {read} read, {unread} unread"
        );
        // A view's cut reaches the orphan's subtree: every point drawn at a budget of all.
        let (cloud, _) = arbvis::points::PointSource::copc(path.clone(), 1 << 40)
            .load_for(&dir, None)
            .unwrap();
        assert_eq!(cloud.len(), 20000, "{name}: the whole cut");
        // inspect describes it, its pages counted.
        let text = crate::common::inspect(&path);
        assert!(text.contains("20000 points"), "{text}");
    }
}

/// Every COPC arbvis writes opens in copclib: from LAS with a WKT (autzen), from a PLY
/// without a coordinate system, and from a LAZ cloud.
#[test]
fn copclib_opens_every_copc_arbvis_writes_with_laspys_points() {
    if !has_copclib() {
        return;
    }
    let dir = temp_dir("copclib-open");
    for input in [
        data_file("points/autzen_trim.laz"),
        data_file("points/bunny.ply"),
    ] {
        let name = input.file_stem().unwrap().to_string_lossy().to_string();
        let out = dir.join(format!("{name}.copc.laz"));
        stdout_of(
            Command::new(env!("CARGO_BIN_EXE_arbvis"))
                .arg("convert")
                .arg(&input)
                .arg(&out),
        );
        // LAS 1.4 R15: formats 6-10 have the WKT bit (global encoding bit 4).
        let bytes = std::fs::read(&out).unwrap();
        assert_eq!(bytes[6] & 16, 16, "{name}: the WKT bit");
        let theirs = python(&dir, "read.py", READ, &[out.to_str().unwrap()]);
        let lines: Vec<&str> = theirs.lines().collect();
        let copclib = lines[0].strip_prefix("copclib ").unwrap();
        assert_eq!(lines[1].strip_prefix("laspy ").unwrap(), copclib, "{name}");
        assert_eq!(ours(&out), copclib, "{name}");
    }
}
