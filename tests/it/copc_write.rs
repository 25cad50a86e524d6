//! `arbvis convert CLOUD X.copc.laz` (issue 28, item 2): the written file read back by
//! arbvis's own COPC reader and by laspy's `CopcReader` (skipped, SKIPPED on stderr,
//! without laspy and lazrs; `ARBVIS_NO_SKIP=1` makes that a failure), every point and
//! attribute equal to the input's; built in memory and through spill files; every point
//! inside its node's cube (what a reader's spatial query relies on); seed `.dat` and PLY
//! attributes as extra bytes; one point, equal points, coordinates near ±1e9, wrong
//! header bounds; bad input (short, empty, a zero scale, a LAS 1.4 legacy count that
//! disagrees) refused naming the byte, with nothing left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{data_file, stdout_of, temp_dir};
use arbvis::points::copc::Copc;

fn convert(input: &Path, output: &Path, extra: &[&str]) -> String {
    stdout_of(
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("convert")
            .arg(input)
            .arg(output)
            .args(extra),
    )
}

/// Every point of a LAS/LAZ/COPC file as one sorted line of raw fields (X Y Z,
/// intensity, returns, classification, user data, source, GPS time bits, RGB).
fn las_rows(pd: &las::PointData) -> Vec<String> {
    let mut cols = crate::common::las_columns(pd);
    cols.push(match pd.gps_time() {
        Some(t) => t.map(|v| format!("{:x}", v.to_bits())).collect(),
        None => vec!["0".into(); pd.len()],
    });
    cols.push(match pd.rgb() {
        Some(c) => c.map(|(r, g, b)| format!("{r},{g},{b}")).collect(),
        None => vec!["-".into(); pd.len()],
    });
    let mut rows = crate::common::rows_of(&cols, pd.len());
    rows.sort();
    rows
}

/// The rows of every node, and a check that each node's points lie in its cube (one
/// scale step of slack: coordinates are rounded to it).
fn copc_rows(path: &Path) -> (Vec<String>, Copc) {
    let copc = Copc::open(path).unwrap();
    let i = copc.info;
    let mut rows = Vec::new();
    for node in &copc.all_nodes().unwrap() {
        let pd = copc.read_node(node).unwrap();
        let side = 2.0 * i.halfsize / f64::from(1 << node.key[0]);
        let lo = [
            i.center_x - i.halfsize + side * node.key[1] as f64,
            i.center_y - i.halfsize + side * node.key[2] as f64,
            i.center_z - i.halfsize + side * node.key[3] as f64,
        ];
        let slack = 1e-3;
        for (a, coords) in [
            pd.x().collect::<Vec<f64>>(),
            pd.y().collect(),
            pd.z().collect(),
        ]
        .iter()
        .enumerate()
        {
            for v in coords {
                assert!(
                    *v >= lo[a] - slack && *v <= lo[a] + side + slack,
                    "node {:?}: coordinate {v} outside {}..{}",
                    node.key,
                    lo[a],
                    lo[a] + side
                );
            }
        }
        rows.extend(las_rows(&pd));
    }
    rows.sort();
    (rows, copc)
}

fn input_rows(path: &Path) -> Vec<String> {
    let mut reader = las::Reader::from_path(path).unwrap();
    las_rows(&reader.read_all().unwrap())
}

fn has_laspy() -> bool {
    crate::common::python_has(
        "import laspy, lazrs",
        "python3 with laspy and lazrs is missing (pip install laspy lazrs)",
    )
}

/// laspy reads the input whole and the COPC file through `CopcReader.query()`; every
/// dimension of the input, sorted the same way, must be equal.
const LASPY_SAME: &str = r#"
import sys, numpy as np, laspy
a = laspy.read(sys.argv[1])
with laspy.CopcReader.open(sys.argv[2]) as r:
    b = r.query()
assert len(a.points) == len(b), (len(a.points), len(b))
def order(p):
    t = np.asarray(p.gps_time) if "gps_time" in p.point_format.dimension_names else np.zeros(len(p))
    return np.lexsort((np.asarray(p.Z), np.asarray(p.Y), np.asarray(p.X), t))
ia, ib = order(a), order(b)
names = [d for d in a.point_format.dimension_names if d in b.point_format.dimension_names
         and d not in ("scan_angle_rank", "scan_angle")]
for d in names:
    va, vb = np.asarray(a[d])[ia], np.asarray(b[d])[ib]
    assert np.array_equal(va, vb), (d, int(np.sum(va != vb)))
print("same", len(b), len(names))
"#;

/// [`LASPY_SAME`] on the input and its COPC file: `same POINTS DIMENSIONS`.
fn laspy_same(input: &Path, out: &Path) -> String {
    stdout_of(
        Command::new("python3")
            .args(["-c", LASPY_SAME])
            .arg(input)
            .arg(out),
    )
}

#[test]
fn a_laz_file_becomes_copc_with_every_point_and_attribute() {
    let input = data_file("points/autzen_trim.laz");
    let dir = temp_dir("copc-write-autzen");
    let theirs = input_rows(&input);
    // In memory, and through spill files (60,000 points in memory at once: the root's
    // sample stays in memory, four spill files of about 27,000 points each).
    for (name, extra) in [
        ("memory.copc.laz", vec![]),
        (
            "spilled.copc.laz",
            vec!["--memory-points", "60000", "--node-points", "3000"],
        ),
    ] {
        let out = dir.join(name);
        let said = convert(&input, &out, &extra);
        assert!(said.contains("110000 points, point format 7"), "{said}");
        assert_eq!(said.contains("spill files"), !extra.is_empty(), "{said}");
        let (ours, copc) = copc_rows(&out);
        assert_eq!(ours.len(), theirs.len());
        assert!(ours == theirs, "{name}: the points differ from the input's");
        if !extra.is_empty() {
            assert!(
                copc.levels().unwrap().len() >= 3,
                "{:?}",
                copc.levels().unwrap()
            );
            assert!(copc.all_nodes().unwrap().iter().all(|n| n.points <= 20_000));
        }
        // Nothing left beside it but the outputs.
        let left: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with('.'))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        if has_laspy() {
            let said = laspy_same(&input, &out);
            assert!(said.starts_with("same 110000"), "{said}");
        }
    }
}

#[test]
fn seed_dat_and_ply_attributes_become_extra_bytes() {
    use arbvis::points::{dat, section, PointSource, Values};
    let dir = temp_dir("copc-write-dat");
    let cloud = section::generate(&section::SectionSpec {
        points: 3001,
        seed: 5,
    })
    .unwrap();
    let path = dir.join("s.dat");
    std::fs::write(
        &path,
        dat::write(&cloud, &dat::DatColumns::default()).unwrap(),
    )
    .unwrap();
    let read = dat::read(&path, &Default::default()).unwrap();
    let out = dir.join("s.copc.laz");
    convert(&path, &out, &["--node-points", "500"]);
    let back = PointSource::copc(out.clone(), 1 << 40)
        .load(Path::new("."))
        .unwrap();
    assert_eq!(back.len(), read.len());
    // Points come back in node order: match them by position (the .dat's are distinct).
    let key = |p: [f64; 3]| p.map(|v| (v * 1e3).round() as i64);
    let mut at = std::collections::HashMap::new();
    for i in 0..read.len() {
        at.insert(key(read.original(i).unwrap()), i);
    }
    for a in &read.attributes {
        let b = back
            .attribute(&a.name)
            .unwrap_or_else(|| panic!("attribute {} is missing", a.name));
        for j in 0..back.len() {
            let i = at[&key(back.original(j).unwrap())];
            match (&a.values, &b.values) {
                (Values::Int(x), Values::Int(y)) => assert_eq!(x[i], y[j], "{}", a.name),
                (Values::Float(x), Values::Float(y)) => {
                    assert!(
                        x[i] == y[j] || (x[i].is_nan() && y[j].is_nan()),
                        "{}",
                        a.name
                    )
                }
                _ => panic!(
                    "{}: {:?} came back as {:?}",
                    a.name,
                    a.values.kind(),
                    b.values.kind()
                ),
            }
        }
    }
    // PLY: the bunny's float `intensity` is not LAS's (an integer): an extra attribute
    // named `intensity_extra`, as laspy requires.
    let bunny = dir.join("bunny.copc.laz");
    convert(&data_file("points/bunny.ply"), &bunny, &[]);
    let back = PointSource::copc(bunny.clone(), 1 << 40)
        .load(Path::new("."))
        .unwrap();
    assert!(back.floats("confidence").is_some() && back.floats("intensity_extra").is_some());
    if has_laspy() {
        let said = stdout_of(Command::new("python3").args([
            "-c",
            "import sys, laspy\nwith laspy.CopcReader.open(sys.argv[1]) as r:\n p = r.query()\n print(len(p), sorted(p.point_format.extra_dimension_names))",
        ]).arg(&bunny));
        assert_eq!(said.trim(), "35947 ['confidence', 'intensity_extra']");
    }
}

/// A LAS 1.2 file of point format 1 (GPS time) by hand: `points` raw X Y Z, with the
/// header's bounds given (they may be wrong on purpose).
fn write_las(
    path: &Path,
    points: &[[i32; 3]],
    scale: f64,
    offset: [f64; 3],
    bounds: [[f64; 3]; 2],
) {
    let mut h = vec![0u8; 227];
    h[0..4].copy_from_slice(b"LASF");
    h[24] = 1;
    h[25] = 2;
    h[94..96].copy_from_slice(&227u16.to_le_bytes());
    h[96..100].copy_from_slice(&227u32.to_le_bytes());
    h[104] = 1;
    h[105..107].copy_from_slice(&28u16.to_le_bytes());
    h[107..111].copy_from_slice(&(points.len() as u32).to_le_bytes());
    for a in 0..3 {
        h[131 + 8 * a..139 + 8 * a].copy_from_slice(&scale.to_le_bytes());
        h[155 + 8 * a..163 + 8 * a].copy_from_slice(&offset[a].to_le_bytes());
        h[179 + 16 * a..187 + 16 * a].copy_from_slice(&bounds[1][a].to_le_bytes());
        h[187 + 16 * a..195 + 16 * a].copy_from_slice(&bounds[0][a].to_le_bytes());
    }
    for (k, p) in points.iter().enumerate() {
        let mut r = [0u8; 28];
        for a in 0..3 {
            r[4 * a..4 * a + 4].copy_from_slice(&p[a].to_le_bytes());
        }
        r[14] = 1 | 1 << 3;
        r[15] = (k % 20) as u8;
        r[20..28].copy_from_slice(&(k as f64 * 0.25).to_le_bytes());
        h.extend_from_slice(&r);
    }
    std::fs::write(path, h).unwrap();
}

/// A test cloud: name, raw points, the header's bounds, convert's extra arguments.
type Case = (
    &'static str,
    Vec<[i32; 3]>,
    [[f64; 3]; 2],
    &'static [&'static str],
);

#[test]
fn edge_clouds_one_point_equal_points_far_coordinates_wrong_bounds() {
    let dir = temp_dir("copc-write-edges");
    let far = [1e9, -1e9, 1e9 - 0.5];
    // Pseudo-random, not smooth: a scrambled walk over ±2e6 steps of 1 mm.
    let scattered: Vec<[i32; 3]> = (0..5000u64)
        .map(|k| {
            let h = k.wrapping_mul(0x9E37_79B9_7F4A_7C15);
            [
                (h % 4_000_001) as i32 - 2_000_000,
                (h >> 22) as i32 % 1_000_000,
                (h >> 43) as i32 % 50_000,
            ]
        })
        .collect();
    let real = |p: &[i32; 3], a: usize| p[a] as f64 * 1e-3 + far[a];
    let true_bounds = [
        std::array::from_fn(|a| {
            scattered
                .iter()
                .map(|p| real(p, a))
                .fold(f64::INFINITY, f64::min)
        }),
        std::array::from_fn(|a| {
            scattered
                .iter()
                .map(|p| real(p, a))
                .fold(f64::NEG_INFINITY, f64::max)
        }),
    ];
    let cases: Vec<Case> = vec![
        (
            "one",
            vec![[5, -7, 9]],
            [
                [far[0], far[1] - 1.0, far[2]],
                [far[0] + 1.0, far[1], far[2] + 1.0],
            ],
            &[],
        ),
        (
            "equal",
            vec![[12, 34, 56]; 2000],
            [
                [far[0], far[1], far[2]],
                [far[0] + 1.0, far[1] + 1.0, far[2] + 1.0],
            ],
            &["--node-points", "10"],
        ),
        (
            "far",
            scattered.clone(),
            true_bounds,
            &["--node-points", "400"],
        ),
        // The header's bounds a tenth of the true ones: the octree is built again.
        (
            "wrong-bounds",
            scattered.clone(),
            [
                true_bounds[0],
                std::array::from_fn(|a| {
                    true_bounds[0][a] + 0.1 * (true_bounds[1][a] - true_bounds[0][a])
                }),
            ],
            &["--node-points", "400"],
        ),
    ];
    for (name, points, bounds, extra) in cases {
        let input = dir.join(format!("{name}.las"));
        write_las(&input, &points, 1e-3, far, bounds);
        let out = dir.join(format!("{name}.copc.laz"));
        let mut command = Command::new(env!("CARGO_BIN_EXE_arbvis"));
        let run = command
            .arg("convert")
            .arg(&input)
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{name}: {stderr}");
        assert_eq!(
            stderr.contains("not the header's"),
            name == "wrong-bounds",
            "{name}: {stderr}"
        );
        let (ours, copc) = copc_rows(&out);
        assert_eq!(ours, input_rows(&input), "{name}");
        if name == "equal" {
            // Each level keeps one of the equal points until the deepest level holds the rest.
            assert_eq!(copc.all_nodes().unwrap().first().unwrap().points, 1);
            assert!(
                copc.all_nodes()
                    .unwrap()
                    .iter()
                    .map(|n| n.points)
                    .max()
                    .unwrap()
                    > 1900
            );
        }
        // The real coordinates: integers times 1e-3 plus ±1e9, exact.
        let pd = Copc::open(&out).unwrap();
        let first = pd.read_node(&pd.all_nodes().unwrap()[0]).unwrap();
        let x = first.x().next().unwrap();
        let xr = first.x_raw().next().unwrap();
        assert_eq!(x, xr as f64 * 1e-3 + far[0], "{name}");
    }
}

#[test]
fn bad_clouds_are_refused_leaving_nothing_behind() {
    let dir = temp_dir("copc-write-bad");
    let input = dir.join("short.las");
    write_las(
        &input,
        &[[1, 2, 3]; 100],
        0.01,
        [0.0; 3],
        [[0.0; 3], [1.0; 3]],
    );
    let bytes = std::fs::read(&input).unwrap();
    std::fs::write(&input, &bytes[..bytes.len() - 100]).unwrap();
    let empty = dir.join("empty.las");
    write_las(&empty, &[], 0.01, [0.0; 3], [[0.0; 3], [0.0; 3]]);
    // Scales of 0 and below (an octree's cube would be inverted or empty).
    let flat = dir.join("flat.las");
    write_las(&flat, &[[1, 2, 3]; 10], 0.0, [0.0; 3], [[0.0; 3], [1.0; 3]]);
    // LAS 1.4 whose legacy 32-bit count disagrees with its 64-bit count (laspy's COPC
    // file, 1,065 points, the legacy field set to 41): taking either would lose points.
    let mut b = std::fs::read(data_file("points/simple.copc.laz")).unwrap();
    b[107..111].copy_from_slice(&41u32.to_le_bytes());
    let legacy = dir.join("legacy.las");
    std::fs::write(&legacy, &b).unwrap();
    for (file, says) in [
        (&input, "the header declares 100 points of 28 bytes, but the 2700 bytes after the point offset hold only 96"),
        (&empty, "no points"),
        (&flat, "at byte 131: x scale 0: a COPC file needs a positive scale"),
        (&legacy, "at byte 107: the legacy point count 41 disagrees with LAS 1.4's 64-bit count 1065 at byte 247"),
    ] {
        let out = dir.join("out.copc.laz");
        let run = Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("convert")
            .arg(file)
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success());
        assert!(stderr.contains(says) && stderr.contains(&*file.to_string_lossy()), "{stderr}");
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| n.ends_with(".las")), "{names:?}");
    }
}

/// laspy writes a LAZ 1.4 file of point format 7 with an extra-bytes attribute, in
/// chunks of 5,000 points (`argv[2]` points): layered chunks, decoded apart.
const LASPY_LAZ14: &str = r#"
import sys, numpy as np, laspy
n = int(sys.argv[2])
rng = np.random.default_rng(3)
h = laspy.LasHeader(point_format=7, version="1.4")
h.add_extra_dim(laspy.ExtraBytesParams(name="wetness", type=np.float32))
h.scales, h.offsets = [0.01] * 3, [500000.0, 4000000.0, 0.0]
las = laspy.LasData(h)
t = np.sort(rng.random(n)) * 100
las.x = 500000 + 300 * np.cos(t) + rng.normal(0, 3, n)
las.y = 4000000 + 300 * np.sin(t * 1.3) + rng.normal(0, 3, n)
las.z = 100 + 20 * np.sin(t / 7) + rng.normal(0, 0.5, n)
las.gps_time = t
las.intensity = rng.integers(0, 65535, n)
las.classification = rng.choice([1, 2, 6], n)
las.red, las.green, las.blue = (rng.integers(0, 65535, n) for _ in range(3))
las.wetness = rng.random(n).astype(np.float32)
with laspy.open(sys.argv[1], mode="w", header=las.header, do_compress=True,
                laz_backend=laspy.LazBackend.Lazrs) as w:
    w.write_points(las.points)
"#;

/// A layered LAZ 1.4 file decoded chunk by chunk in parallel ahead of the writer (and
/// again from its first chunk when the spill depth is chosen): every point and attribute
/// as laspy reads the input.
#[test]
fn a_laz_1_4_file_decodes_chunk_by_chunk_with_every_point() {
    if !has_laspy() {
        return;
    }
    let dir = temp_dir("copc-write-laz14");
    let input = dir.join("in.laz");
    stdout_of(
        Command::new("python3")
            .args(["-c", LASPY_LAZ14])
            .arg(&input)
            .arg("123457"),
    );
    let out = dir.join("out.copc.laz");
    let said = convert(
        &input,
        &out,
        &["--memory-points", "40000", "--node-points", "8000"],
    );
    assert!(said.contains("123457 points, point format 7"), "{said}");
    let same = laspy_same(&input, &out);
    assert!(same.starts_with("same 123457"), "{same}");
    // The header's largest x made too small: a point outside it stops the first pass, the
    // points' own bounds are read in a pass of their own, and the build starts over, the
    // chunks decoded from the first again each time.
    let mut b = std::fs::read(&input).unwrap();
    let min_x = f64::from_le_bytes(b[187..195].try_into().unwrap());
    b[179..187].copy_from_slice(&(min_x + 1.0).to_le_bytes());
    let wrong = dir.join("wrong-bounds.laz");
    std::fs::write(&wrong, b).unwrap();
    let out = dir.join("wrong.copc.laz");
    convert(
        &wrong,
        &out,
        &["--memory-points", "40000", "--node-points", "8000"],
    );
    let same = laspy_same(&input, &out);
    assert!(same.starts_with("same 123457"), "{same}");
}
