//! The real files in data/tets: counts from its README, values read by hand
//! from the files (python struct / the ASCII text), and properties every mesh must have.

use std::collections::HashMap;

use crate::mesh::quality::{signed_volume, Quality};
use crate::mesh::{inspect, read, Mesh};
use arbvis_core::input::data_file;

fn load(name: &str) -> Mesh {
    read(&data_file(&format!("tets/{name}"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Every tetrahedron positive and every point index valid.
fn well_formed(m: &Mesh) {
    assert_eq!(m.source_cell.len(), m.tets.len());
    for &t in &m.tets {
        assert!(t.iter().all(|&i| (i as usize) < m.points.len()));
        assert!(signed_volume(&m.points, t) > 0.0, "{t:?}");
    }
    for a in m.point_arrays.iter() {
        assert_eq!(a.tuples(), m.points.len(), "{}", a.name);
    }
    for a in m.cell_arrays.iter() {
        assert_eq!(a.tuples(), m.tets.len(), "{}", a.name);
    }
}

/// How often each triangle (sorted vertex triple) is a face of a tetrahedron.
pub fn face_counts(tets: &[[u32; 4]]) -> HashMap<[u32; 3], u32> {
    let mut faces = HashMap::new();
    for t in tets {
        for skip in 0..4 {
            let mut f: Vec<u32> = (0..4).filter(|&k| k != skip).map(|k| t[k]).collect();
            f.sort_unstable();
            *faces.entry([f[0], f[1], f[2]]).or_insert(0) += 1;
        }
    }
    faces
}

#[test]
fn post_vtk_binary_legacy() {
    let m = load("post.vtk");
    well_formed(&m);
    assert_eq!((m.points.len(), m.tets.len()), (2288, 8750));
    assert_eq!((m.info.version.as_str(), m.info.flipped), ("3.0", 0));
    assert_eq!(m.points[0], [0.5, 0.0, 0.0]);
    assert_eq!(m.tets[0], [12, 1, 287, 0]);
    let p = m.point_array("Pressure").expect("Pressure");
    assert_eq!(
        p.values[..3],
        [0.9558984041213989, 0.8389104008674622, 0.7296856641769409]
    );
    assert_eq!(
        m.point_arrays.len(),
        1,
        "the dataset's own FIELD data (Properties) is not a point array"
    );
}

#[test]
fn tetra_mesh_vtk_ascii_half_of_its_tetrahedra_are_flipped() {
    let m = load("tetraMesh.vtk");
    well_formed(&m);
    assert_eq!(
        (m.points.len(), m.tets.len(), m.info.flipped),
        (55, 160, 80)
    );
    assert_eq!(m.points[0], [9.78032, -1.80307, 0.98754]);
    // The cells as written (lines 63 to 222: "4 54 32 26 7", ...): each tetrahedron is
    // the file's cell or the file's cell with its last two vertices swapped, 80 of them.
    let text = std::fs::read_to_string(data_file("tets/tetraMesh.vtk")).unwrap();
    let file: Vec<[u32; 4]> = text
        .lines()
        .skip(62)
        .take(160)
        .map(|l| {
            let v: Vec<u32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            assert_eq!(v[0], 4);
            [v[1], v[2], v[3], v[4]]
        })
        .collect();
    assert_eq!(file[0], [54, 32, 26, 7]);
    let swapped = file
        .iter()
        .zip(&m.tets)
        .filter(|(f, t)| {
            assert!(*f == *t || [f[0], f[1], f[3], f[2]] == **t);
            f != t
        })
        .count();
    assert_eq!(swapped, 80);
    let s = m.point_array("scalars").expect("scalars");
    assert_eq!((s.values[0], s.values[12]), (4.0, 0.0));
}

#[test]
fn tetrahedron_vtu_fills_its_cube() {
    let m = load("Tetrahedron.vtu");
    well_formed(&m);
    assert_eq!((m.points.len(), m.tets.len()), (35, 96));
    assert_eq!(m.bounds(), Some(([0.0; 3], [2.0; 3])));
    let q = Quality::of(&m);
    assert!((q.total_volume - 8.0).abs() < 1e-12, "{}", q.total_volume);
    let d = m.point_array("DistanceToCenter").expect("DistanceToCenter");
    let max = d.values.iter().copied().fold(f64::MIN, f64::max);
    assert_eq!(max, 1.7320508f32 as f64);
    assert!(m.point_array("Polynomial").is_some());
    assert!(m.info.encoding.contains("appended raw") && m.info.encoding.contains("UInt64"));
}

/// The hexahedra of can.vtu, read straight from its appended data (Int64 connectivity
/// after a UInt64 byte count), for the conformity check.
fn can_hexes(bytes: &[u8]) -> Vec<[i64; 8]> {
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(40_000)]);
    let tag = text.find("Name=\"connectivity\"").expect("connectivity");
    let off: usize = text[tag..]
        .split("offset=\"")
        .nth(1)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let tag = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .unwrap();
    let start = tag + bytes[tag..].iter().position(|&b| b == b'_').unwrap() + 1;
    let data = &bytes[start + off..];
    let n = u64::from_le_bytes(data[..8].try_into().unwrap()) as usize / 8;
    let v: Vec<i64> = data[8..8 + 8 * n]
        .chunks_exact(8)
        .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    v.chunks_exact(8).map(|c| c.try_into().unwrap()).collect()
}

#[test]
fn can_vtu_hexahedra_split_conformingly() {
    let path = data_file("tets/can.vtu");
    let m = read(&path).unwrap();
    well_formed(&m);
    assert_eq!(
        (m.points.len(), m.info.split_cells, m.tets.len()),
        (6724, 4800, 6 * 4800)
    );
    assert_eq!(m.info.cells[0].name, "VTK_HEXAHEDRON");
    let eqps = m.cell_array("EQPS").expect("EQPS");
    assert_eq!(eqps.tuples(), 28800);
    for (k, t) in eqps.values.chunks(6).enumerate() {
        assert!(
            t.iter().all(|&v| v == t[0]),
            "hexahedron {k}'s six tetrahedra carry its value"
        );
    }
    assert_eq!(m.point_array("DISPL").map(|a| a.components), Some(3));
    // Conformity: no triangle is used more than twice, and the triangles used once are
    // exactly two per boundary quadrilateral of the hexahedral mesh (a shared face cut
    // two ways would leave four triangles used once inside the mesh).
    let faces = face_counts(&m.tets);
    assert!(faces.values().all(|&c| c <= 2));
    let boundary_tris = faces.values().filter(|&&c| c == 1).count();
    let hexes = can_hexes(&std::fs::read(&path).unwrap());
    assert_eq!(hexes.len(), 4800);
    let mut quads: HashMap<Vec<i64>, u32> = HashMap::new();
    for h in &hexes {
        for f in [
            [0, 1, 2, 3],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ] {
            let mut q: Vec<i64> = f.iter().map(|&i| h[i]).collect();
            q.sort_unstable();
            *quads.entry(q).or_insert(0) += 1;
        }
    }
    let boundary_quads = quads.values().filter(|&&c| c == 1).count();
    assert_eq!(boundary_tris, 2 * boundary_quads);
}

#[test]
fn the_three_bracket_files_give_one_mesh() {
    let (a, b, c) = (
        load("bracket-2.2.msh"),
        load("bracket-4.1.msh"),
        load("bracket-4.1-binary.msh"),
    );
    for m in [&a, &b, &c] {
        well_formed(m);
        assert_eq!((m.points.len(), m.tets.len()), (8715, 40710));
        assert_eq!(m.bounds(), Some(([0.0; 3], [2.0, 1.0, 1.0])));
    }
    assert_eq!(
        (a.info.version.as_str(), c.info.version.as_str()),
        ("2.2", "4.1")
    );
    assert!(c.info.encoding.starts_with("binary"));
    assert_eq!(a.tets, b.tets);
    assert_eq!(a.tets, c.tets);
    assert_eq!(a.points, b.points);
    let ta = &a.point_array("temperature").unwrap().values;
    let tb = &b.point_array("temperature").unwrap().values;
    let tc = &c.point_array("temperature").unwrap().values;
    assert_eq!(ta, tb);
    assert_eq!(ta[0], 0.366273355072379);
    assert_eq!(ta[6], -0.2794154981989259);
    // ASCII holds 16 significant digits, binary the exact doubles.
    for (x, y) in ta.iter().zip(tc) {
        assert!((x - y).abs() <= 1e-15, "{x} {y}");
    }
    for (p, q) in a.points.iter().zip(&c.points) {
        assert!((0..3).all(|k| (p[k] - q[k]).abs() <= 1e-15));
    }
    // The box with two holes is non-convex: some faces are on the boundary, none shared
    // by more than two tetrahedra.
    assert!(face_counts(&a.tets).values().all(|&n| n <= 2));
}

#[test]
fn inspect_reports_what_was_read() {
    let p = data_file("tets/can.vtu");
    let s = inspect(&p).unwrap();
    for want in [
        "format: VTK XML UnstructuredGrid 1.0 (appended raw, UInt64 headers, little-endian)",
        "points: 6724",
        "  VTK_HEXAHEDRON: 4800",
        "split into tetrahedra: 4800 cells",
        "tetrahedra: 28800",
        "point array \"DISPL\": 3 components, range [",
        "cell array \"EQPS\": 1 component, range [",
        "flipped to positive orientation: 0",
        "flat (degenerate) tetrahedra (|volume| <= 1e-12 x longest edge^3, not drawn): 0\n",
        "repeated tetrahedra (at the place of an earlier one): 0\n",
        "sliver tetrahedra (radius ratio < 0.1): ",
        "depth: a line through the bounding box crosses ",
    ] {
        assert!(s.contains(want), "missing {want:?} in\n{s}");
    }
}
