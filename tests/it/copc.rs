//! COPC files (issue 28, item 1): laspy's own test files (`data/points/simple.copc.laz` and
//! `simple_with_page.copc.laz`, the second with its hierarchy in two pages) read node by
//! node and compared with laspy's `CopcReader` level by level, every point and attribute
//! equal; `inspect` on them; a damaged hierarchy (a cycle among its pages, a key twice,
//! a chunk outside the points) or header refused naming the byte, a damaged chunk an error
//! naming the node, never a panic. The laspy comparison is skipped
//! (SKIPPED on stderr) without `python3 -c "import laspy, lazrs"`; `ARBVIS_NO_SKIP=1`
//! makes a skip a failure.

use std::process::Command;

use crate::common::{data_file, temp_dir};
use arbvis::points::copc::Copc;

const FILES: [&str; 2] = ["points/simple.copc.laz", "points/simple_with_page.copc.laz"];

fn has_laspy() -> bool {
    crate::common::python_has(
        "import laspy, lazrs",
        "python3 with laspy and lazrs is missing (pip install laspy lazrs)",
    )
}

/// Every point of `level`, one line each (raw X Y Z, intensity, returns, classification,
/// user data, point source, scan angle in degrees, GPS time, RGB), sorted.
const LASPY_LEVEL: &str = r#"
import sys, laspy
with laspy.CopcReader.open(sys.argv[1]) as r:
    for level in range(int(sys.argv[2])):
        p = r.query(level=level)
        rows = sorted(
            f"{level} {x} {y} {z} {i} {rn} {nr} {c} {ud} {ps} {sa:.3f} {t!r} {red} {g} {b}"
            for x, y, z, i, rn, nr, c, ud, ps, sa, t, red, g, b in zip(
                p.X, p.Y, p.Z, p.intensity, p.return_number, p.number_of_returns,
                p.classification, p.user_data, p.point_source_id, p.scan_angle * 0.006,
                p.gps_time.tolist(), p.red, p.green, p.blue))
        print("\n".join(rows))
"#;

/// arbvis's lines for the same, node by node.
fn arbvis_lines(copc: &Copc) -> Vec<String> {
    let mut out = Vec::new();
    let levels = copc.levels().unwrap().last().map_or(0, |l| l.0 + 1);
    for level in 0..levels {
        let mut rows = Vec::new();
        for node in copc
            .all_nodes()
            .unwrap()
            .iter()
            .filter(|n| n.key[0] == level)
        {
            let p = copc.read_node(node).unwrap();
            let mut cols = crate::common::las_columns(&p);
            cols.push(p.scan_angle_degrees().map(|v| format!("{v:.3}")).collect());
            cols.push(p.gps_time().unwrap().map(python_float).collect());
            cols.push(
                p.rgb()
                    .unwrap()
                    .map(|(r, g, b)| format!("{r} {g} {b}"))
                    .collect(),
            );
            assert_eq!(p.len() as u64, node.points, "node {:?}", node.key);
            let lines = crate::common::rows_of(&cols, p.len());
            rows.extend(lines.into_iter().map(|l| format!("{level} {l}")));
        }
        rows.sort();
        out.extend(rows);
    }
    out
}

/// `v` as Python's `repr` writes a float (shortest round trip, `.0` for whole numbers).
fn python_float(v: f64) -> String {
    let s = format!("{v:?}");
    if s.contains('e') || s.contains('.') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}

#[test]
fn copc_nodes_read_as_laspy_reads_them() {
    for name in FILES {
        let path = data_file(name);
        let copc = Copc::open(&path).unwrap();
        // The files' octree: 1,065 points in 65 nodes over four levels.
        assert_eq!(copc.points, 1065);
        assert_eq!(copc.all_nodes().unwrap().len(), 65);
        let levels: Vec<(i32, usize, u64)> = copc.levels().unwrap();
        assert_eq!(levels, [(0, 1, 24), (1, 4, 66), (2, 12, 197), (3, 48, 778)]);
        let ours = arbvis_lines(&copc);
        assert_eq!(ours.len(), 1065);
        // The whole file through arbvis's LAS/LAZ reader: the same count.
        let whole = arbvis::points::lasfile::read(&path).unwrap();
        assert_eq!(whole.info.points, 1065);
        if !has_laspy() {
            continue;
        }
        let out = crate::common::stdout_of(
            Command::new("python3")
                .args(["-c", LASPY_LEVEL])
                .arg(&path)
                .arg("4"),
        );
        let theirs: Vec<String> = out.lines().map(str::to_string).collect();
        assert_eq!(theirs.len(), ours.len(), "{name}");
        for (a, b) in ours.iter().zip(&theirs) {
            assert_eq!(a, b, "{name}");
        }
    }
}

#[test]
fn inspect_describes_the_octree_without_decoding() {
    crate::common::assert_says(
        &crate::common::inspect(&data_file(FILES[1])),
        &[
            "format: COPC (LAZ 1.4, point format 7, 36-byte records), 1065 points",
            "65 nodes with points, 1065 points",
            "gps time, red, green, blue",
            "level 3: 48 nodes, 778 points, spacing 4.5271",
        ],
    );
}

#[test]
fn damaged_copc_files_are_refused_naming_the_byte_or_the_node() {
    let dir = temp_dir("copc-hostile");
    let bytes = std::fs::read(data_file(FILES[0])).unwrap();
    let write = |name: &str, b: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, b).unwrap();
        p
    };
    // Cut short: the EVLRs (the hierarchy) are gone.
    let p = write("cut.copc.laz", &bytes[..bytes.len() / 2]);
    let e = Copc::open(&p).err().expect("refused").to_string();
    assert!(e.contains("cut.copc.laz") && e.contains("EVLR"), "{e}");
    // The root hierarchy page's first entry claims 2 GB of chunk.
    let vlr = 375 + 54;
    let root = u64::from_le_bytes(bytes[vlr + 40..vlr + 48].try_into().unwrap()) as usize;
    let mut b = bytes.clone();
    b[root + 24..root + 28].copy_from_slice(&i32::MAX.to_le_bytes());
    let p = write("entry.copc.laz", &b);
    let e = Copc::open(&p).err().expect("refused").to_string();
    assert!(
        e.contains("hierarchy entry") && e.contains("point data"),
        "{e}"
    );
    // The root page's first entry made a pointer to the root page itself: a cycle (las
    // 0.11's own reader collects entries until memory runs out on this).
    let size = u64::from_le_bytes(bytes[vlr + 48..vlr + 56].try_into().unwrap());
    let mut b = bytes.clone();
    b[root + 16..root + 24].copy_from_slice(&(root as u64).to_le_bytes());
    b[root + 24..root + 28].copy_from_slice(&(size as i32).to_le_bytes());
    b[root + 28..root + 32].copy_from_slice(&(-1i32).to_le_bytes());
    let p = write("cycle.copc.laz", &b);
    let e = Copc::open(&p).err().expect("refused").to_string();
    assert!(e.contains("referenced twice"), "{e}");
    // A key listed twice, named at the second entry's byte.
    let mut b = bytes.clone();
    b.copy_within(root..root + 16, root + 32);
    let p = write("twice.copc.laz", &b);
    let e = Copc::open(&p).err().expect("refused").to_string();
    assert!(
        e.contains(&format!("at byte {}", root + 32)) && e.contains("listed twice"),
        "{e}"
    );
    // An octree spacing that is not a number.
    let mut b = bytes.clone();
    b[vlr + 32..vlr + 40].copy_from_slice(&f64::NAN.to_le_bytes());
    let p = write("spacing.copc.laz", &b);
    let e = Copc::open(&p).err().expect("refused").to_string();
    assert!(e.contains("positive sizes"), "{e}");
    // Not LAS 1.4.
    let mut b = bytes.clone();
    b[25] = 2;
    let p = write("version.copc.laz", &b);
    let e = Copc::open(&p).err().expect("refused").to_string();
    assert!(e.contains("at byte 0") && e.contains("LAS 1.4"), "{e}");
    // Every node's chunk scrambled: each read is an error naming its node or garbage
    // points, never a panic or an allocation past the node's count.
    let copc = Copc::open(&data_file(FILES[0])).unwrap();
    let mut b = bytes.clone();
    for n in &copc.all_nodes().unwrap() {
        for k in 0..n.bytes as usize {
            let at = n.offset as usize + k;
            b[at] = b[at].wrapping_mul(31).wrapping_add(7);
        }
    }
    let p = write("chunks.copc.laz", &b);
    let scrambled = Copc::open(&p).unwrap();
    for n in &scrambled.all_nodes().unwrap() {
        match scrambled.read_node(n) {
            Ok(points) => assert_eq!(points.len() as u64, n.points),
            Err(e) => assert!(e.to_string().contains(&format!("node {:?}", n.key)), "{e}"),
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene's `{ copc = { path, points } }`: whole levels from the root within the budget
/// (a stride of the root's points when it alone is past it), all of them equal to the file read whole as LAZ; and
/// drawn as splats.
#[test]
fn a_copc_cloud_in_a_scene_takes_whole_levels_within_its_budget() {
    use arbvis::points::PointSource;
    let base = data_file("points/simple.copc.laz")
        .parent()
        .unwrap()
        .to_path_buf();
    let load = |points| {
        PointSource::copc("simple_with_page.copc.laz", points)
            .load(&base)
            .unwrap()
    };
    // Levels hold 24, 66, 197 and 778 points; a budget under the root's takes every
    // third of the root's 24 points (never more than the budget).
    assert_eq!(load(10).len(), 8);
    assert_eq!(load(100).len(), 90);
    assert_eq!(load(286).len(), 90);
    assert_eq!(load(287).len(), 287);
    let all = load(1_000_000);
    let whole = arbvis::points::lasfile::read(&base.join("simple_with_page.copc.laz"))
        .unwrap()
        .cloud;
    assert_eq!(all.len(), whole.len());
    // The same points (in the octree's order, not the file's): sorted positions equal.
    let sorted = |c: &arbvis::points::PointCloud| {
        let mut p: Vec<[u64; 3]> = (0..c.len())
            .map(|i| c.original(i).unwrap().map(f64::to_bits))
            .collect();
        p.sort_unstable();
        p
    };
    assert_eq!(sorted(&all), sorted(&whole));
    // Drawn: the autzen scene's settings on the COPC cloud at 96 x 72.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data/autzen.toml"),
    )
    .unwrap()
    .replace(
        r#"cloud = { las = "../../data/points/autzen_trim.laz" }"#,
        r#"cloud = { copc = { path = "../../data/points/simple.copc.laz", points = 100 } }"#,
    );
    let mut scene = arbvis::scene::Scene::parse(&text, "copc.toml").unwrap();
    scene.base = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data");
    scene.size = [96, 72];
    let h = crate::common::headless(arbvis::gl::Backend::Egl);
    let image = arbvis::render::render_on(&h, &scene).unwrap().image;
    let lit = crate::common::lit_pixels(&image, 0.05);
    assert!(lit > 20, "{lit} pixels lit");
}

/// GPS time reaches the cloud as seconds after the file's earliest (the COPC info VLR's
/// minimum; a plain LAS/LAZ read, the earliest point's), in f32: every cut of the COPC
/// file and the whole-file read give each point the same value, equal to the node's raw
/// f64 time less that reference, rounded once to f32.
#[test]
fn gps_time_is_an_attribute_after_the_files_earliest() {
    use arbvis::points::PointSource;
    for name in FILES {
        let path = data_file(name);
        let copc = Copc::open(&path).unwrap();
        let reference = copc.info.gps_range[0];
        let mut raw: Vec<f64> = Vec::new();
        for node in &copc.all_nodes().unwrap() {
            raw.extend(copc.read_node(node).unwrap().gps_time().unwrap());
        }
        let earliest = raw.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            reference <= earliest,
            "{name}: info {reference}, points {earliest}"
        );
        let expected = |reference: f64| -> Vec<u32> {
            let mut v: Vec<u32> = raw
                .iter()
                .map(|&t| ((t - reference) as f32).to_bits())
                .collect();
            v.sort_unstable();
            v
        };
        let values = |cloud: &arbvis::points::PointCloud| -> Vec<u32> {
            let a = cloud.attribute("gps_time").expect("a gps_time attribute");
            let arbvis::points::Values::Float(v) = &a.values else {
                panic!("gps_time is not float")
            };
            let mut v: Vec<u32> = v.iter().map(|t| t.to_bits()).collect();
            v.sort_unstable();
            v
        };
        let base = path.parent().unwrap();
        let file = path.file_name().unwrap().to_str().unwrap();
        let all = PointSource::copc(file, 1_000_000).load(base).unwrap();
        assert_eq!(values(&all), expected(reference), "{name}");
        // A coarser cut: its points keep the values they have in the full one.
        let cut = PointSource::copc(file, 100).load(base).unwrap();
        let full = values(&all);
        assert!(values(&cut).iter().all(|v| full.binary_search(v).is_ok()));
        let whole = arbvis::points::lasfile::read(&path).unwrap().cloud;
        assert_eq!(values(&whole), expected(earliest), "{name}");
    }
}

/// Colour by elevation is over the file's z range: a point has the same colour in a
/// coarse cut and in the whole cloud (and the lowest z of the header bounds sits at the
/// gradient's start, not the cut's lowest point).
#[test]
fn elevation_colours_a_point_alike_in_every_cut() {
    use arbvis::points::PointSource;
    use arbvis::techniques::splats::prepare::from_cloud;
    use arbvis::techniques::splats::scene::ColourMode;
    use std::collections::HashMap;
    let path = data_file("points/simple_with_page.copc.laz");
    let base = path.parent().unwrap();
    let file = path.file_name().unwrap().to_str().unwrap();
    let mut scene: arbvis::techniques::splats::SplatsScene =
        toml::from_str(&format!("cloud = {{ copc = {{ path = {file:?} }} }}")).unwrap();
    scene.colour = ColourMode::Elevation;
    let colours = |points: u64| -> HashMap<[u32; 3], [u32; 3]> {
        let cloud = PointSource::copc(file, points).load(base).unwrap();
        let p = from_cloud(&cloud, &scene, None).unwrap();
        (0..cloud.len())
            .map(|i| {
                (
                    cloud.positions[i].map(f32::to_bits),
                    p.colours[i].map(f32::to_bits),
                )
            })
            .collect()
    };
    let (coarse, all) = (colours(24), colours(1_000_000));
    assert!(coarse.len() >= 20 && all.len() > coarse.len());
    for (p, c) in &coarse {
        assert_eq!(all.get(p), Some(c), "point {p:?}");
    }
}
