//! Every layout, from the fixtures: each must give the same mesh.

use std::path::Path;

use super::fixtures::{self, Vtu, VtuData, MAT, POINTS, TEMP, TETS};
use crate::mesh::{parse, Mesh};

/// Assert that `m` is the fixture mesh (`tol`: coordinate tolerance, for float32 files).
pub fn check_fixture(m: &Mesh, tol: f64, what: &str) {
    assert_eq!(m.points.len(), 6, "{what}");
    for (i, (p, q)) in m.points.iter().zip(POINTS).enumerate() {
        for a in 0..3 {
            assert!(
                (p[a] - q[a]).abs() <= tol,
                "{what}: point {i}: {p:?} vs {q:?}"
            );
        }
    }
    assert_eq!(m.tets, TETS, "{what}");
    assert_eq!(m.source_cell, [0, 2, 4], "{what}");
    assert_eq!(m.info.flipped, 1, "{what}");
    assert_eq!(m.info.skipped_cells, 2, "{what}");
    assert_eq!(m.info.split_cells, 0, "{what}");
    let cells = cell_counts(m);
    assert_eq!(
        cells,
        [("VTK_TETRA", 3), ("VTK_TRIANGLE", 1), ("VTK_VERTEX", 1)],
        "{what}"
    );
    let temp = m
        .point_array("temp")
        .unwrap_or_else(|| panic!("{what}: no temp"));
    assert_eq!(temp.values, TEMP, "{what}");
    let vel = m
        .point_array("vel")
        .unwrap_or_else(|| panic!("{what}: no vel"));
    assert_eq!(vel.components, 3, "{what}");
    let want: Vec<f64> = (0..6).flat_map(fixtures::vel).collect();
    assert_eq!(vel.values, want, "{what}");
    let mat = m
        .cell_array("mat")
        .unwrap_or_else(|| panic!("{what}: no mat"));
    assert_eq!(mat.values, [MAT[0], MAT[2], MAT[4]], "{what}");
}

fn ok(bytes: &[u8], what: &str) -> Mesh {
    parse(Path::new(what), bytes).unwrap_or_else(|e| panic!("{what}: {e}"))
}

#[test]
fn legacy_ascii_classic_layout() {
    let m = ok(&fixtures::legacy_ascii(), "ascii.vtk");
    check_fixture(&m, 0.0, "ascii.vtk");
    assert_eq!(
        (m.info.format.as_str(), m.info.version.as_str()),
        ("VTK legacy", "4.2")
    );
    assert_eq!(m.info.encoding, "ascii");
}

#[test]
fn legacy_binary_classic_layout_is_big_endian() {
    let m = ok(&fixtures::legacy_binary(), "binary.vtk");
    check_fixture(&m, 1e-7, "binary.vtk");
    // float32 coordinates: 1.1 is read as the float nearest to it.
    assert_eq!(m.points[2][1], 1.1f32 as f64);
}

#[test]
fn legacy_51_offsets_connectivity_int32_and_int64() {
    for int64 in [false, true] {
        for binary in [false, true] {
            let what = format!("5.1 int64={int64} binary={binary}");
            let m = ok(&fixtures::legacy_51(int64, binary), &what);
            check_fixture(&m, 0.0, &what);
            assert_eq!(m.info.version, "5.1");
        }
    }
}

#[test]
fn vtu_every_encoding_header_compression_and_byte_order() {
    let mut n = 0;
    for data in [
        VtuData::Ascii,
        VtuData::Base64,
        VtuData::AppendedRaw,
        VtuData::AppendedBase64,
    ] {
        for header64 in [false, true] {
            for zlib in [false, true] {
                for big in [false, true] {
                    for joint_base64 in [false, true] {
                        if (data == VtuData::Ascii && (zlib || joint_base64))
                            || (joint_base64
                                && !matches!(data, VtuData::Base64 | VtuData::AppendedBase64))
                        {
                            continue;
                        }
                        let cfg = Vtu {
                            data,
                            header64,
                            zlib,
                            big,
                            joint_base64,
                        };
                        let what = format!("{cfg:?}");
                        let m = ok(&fixtures::vtu(cfg), &what);
                        check_fixture(&m, 0.0, &what);
                        assert_eq!(
                            m.info.encoding.contains("zlib"),
                            zlib,
                            "{what}: {}",
                            m.info.encoding
                        );
                        assert!(m.info.encoding.contains(if header64 {
                            "UInt64"
                        } else {
                            "UInt32"
                        }));
                        n += 1;
                    }
                }
            }
        }
    }
    assert_eq!(n, 4 + 16 + 8 + 16);
}

#[test]
fn gmsh_22_and_41_ascii_and_binary() {
    for (what, bytes) in [
        ("2.2 ascii", fixtures::msh22(false)),
        ("2.2 binary", fixtures::msh22(true)),
        ("4.1 ascii", fixtures::msh41(false)),
        ("4.1 binary", fixtures::msh41(true)),
    ] {
        let m = ok(&bytes, what);
        check_fixture(&m, 0.0, what);
        assert_eq!(m.info.format, "gmsh MSH");
        assert_eq!(
            m.info.encoding.starts_with("binary"),
            what.ends_with("binary")
        );
    }
}

#[test]
fn the_format_is_recognized_from_the_content() {
    let e = parse(Path::new("x.vtk"), b"solid cube\nfacet normal 0 0 1\n").unwrap_err();
    let s = e.to_string();
    assert!(s.starts_with("x.vtk: at byte 0: not a mesh file"), "{s}");
    assert!(s.contains("\"solid cube"), "{s}");
    // A vtu with an XML declaration and leading blank lines.
    let mut b = b"\n\n".to_vec();
    b.extend(fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    }));
    check_fixture(&ok(&b, "blank.vtu"), 0.0, "blank.vtu");
}

#[test]
fn legacy_other_datasets_and_versions_are_refused_by_name() {
    let e = parse(
        Path::new("p.vtk"),
        b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("line 4, column 9") && e.contains("DATASET POLYDATA is not a volume mesh"),
        "{e}"
    );
    let e = parse(
        Path::new("v.vtk"),
        b"# vtk DataFile Version 6.0\nt\nASCII\n",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("version 6.0 is not supported"), "{e}");
    let e = parse(Path::new("v.vtu"), b"<VTKFile type=\"PolyData\"></VTKFile>")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 1, column 1") && e.contains("\"PolyData\" is not a volume mesh"),
        "{e}"
    );
    let e = parse(
        Path::new("v.msh"),
        b"$MeshFormat\n4.0 0 8\n$EndMeshFormat\n",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("line 2, column 1") && e.contains("MSH format \"4.0\" is not supported"),
        "{e}"
    );
}

#[test]
fn vtu_lz4_and_several_pieces_are_refused() {
    let base = String::from_utf8(fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    }))
    .unwrap();
    let lz4 = base.replacen(
        "header_type=\"UInt32\"",
        "header_type=\"UInt32\" compressor=\"vtkLZ4DataCompressor\"",
        1,
    );
    let e = parse(Path::new("lz4.vtu"), lz4.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("compressor \"vtkLZ4DataCompressor\" is not supported"),
        "{e}"
    );
    let two = base.replacen(
        "</Piece>",
        "</Piece><Piece NumberOfPoints=\"0\" NumberOfCells=\"0\"></Piece>",
        1,
    );
    let e = parse(Path::new("two.vtu"), two.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(e.contains("more than one <Piece>"), "{e}");
}

#[test]
fn gmsh_mixed_elements_conform_and_quadratic_tets_use_corners() {
    let mut nodes = super::hostile_files::CUBE.to_vec();
    nodes.extend([
        [0.5, 0.5, 1.8],
        [2.0, 0.0, 0.0],
        [2.0, 0.0, 1.0],
        [5.0, 5.0, 5.0],
        [6.0, 5.0, 5.0],
        [5.0, 6.0, 5.0],
        [5.0, 5.0, 6.0],
    ]);
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n21\n");
    for (i, p) in nodes.iter().enumerate() {
        s += &format!("{} {} {} {}\n", i + 1, p[0], p[1], p[2]);
    }
    for i in 16..=21 {
        s += &format!("{i} 5.{i} 5.1 5.2\n"); // edge nodes of the quadratic tetra
    }
    s += "$EndNodes\n$Elements\n6\n";
    s += "1 1 2 0 1 1 2\n"; // line
    s += "2 2 2 0 1 1 2 3\n"; // triangle
    s += "3 5 2 0 1 1 2 3 4 5 6 7 8\n"; // hexahedron
    s += "4 6 2 0 1 2 10 3 6 11 7\n"; // prism sharing the hexahedron's face x = 1
    s += "5 7 2 0 1 5 6 7 8 9\n"; // pyramid on the hexahedron's top
    s += "6 11 2 0 1 12 13 14 15 16 17 18 19 20 21\n"; // 10-node tetrahedron
    s += "$EndElements\n";
    let m = parse(Path::new("mixed.msh"), s.as_bytes()).unwrap();
    let cells = cell_counts(&m);
    assert_eq!(
        cells,
        [
            ("VTK_LINE", 1),
            ("VTK_TRIANGLE", 1),
            ("VTK_HEXAHEDRON", 1),
            ("VTK_WEDGE", 1),
            ("VTK_PYRAMID", 1),
            ("VTK_QUADRATIC_TETRA", 1)
        ]
    );
    let i = &m.info;
    assert_eq!(
        (
            i.split_cells,
            i.reduced_to_corners,
            i.skipped_cells,
            m.tets.len()
        ),
        (3, 1, 2, 6 + 3 + 2 + 1)
    );
    assert_eq!(m.source_cell, [2, 2, 2, 2, 2, 2, 3, 3, 3, 4, 4, 5]);
    let faces = super::real_files::face_counts(&m.tets);
    // The shared quadrilaterals are cut the same way on both sides: through index 1
    // (tag 2) on the face x = 1, through index 4 (tag 5) on the top.
    for f in [[1, 2, 6], [1, 5, 6], [4, 5, 6], [4, 6, 7]] {
        assert_eq!(faces.get(&f), Some(&2), "{f:?}");
    }
    assert!(faces.values().all(|&n| n <= 2));
    let q = crate::mesh::quality::Quality::of(&m);
    assert!(
        (q.total_volume - (1.0 + 0.5 + 0.8 / 3.0 + 1.0 / 6.0)).abs() < 1e-12,
        "{}",
        q.total_volume
    );
    let mut last = m.tets[11];
    last.sort_unstable();
    assert_eq!(last, [11, 12, 13, 14]);
}

#[test]
fn gmsh_sparse_tags_far_apart() {
    // Node tag 250 becomes 10^12 (and node 17 becomes -3) everywhere: the tag table
    // turns into a map, with the same mesh.
    let text = String::from_utf8(fixtures::msh22(false)).unwrap();
    let text = text
        .replace(" 250", " 1000000000000")
        .replace("\n250 ", "\n1000000000000 ");
    let text = text.replace(" 17", " -3").replace("\n17 ", "\n-3 ");
    assert!(text.contains("1000000000000 1.6 1.2 0.9"));
    let m = ok(text.as_bytes(), "sparse.msh");
    check_fixture(&m, 0.0, "sparse.msh");
}

/// (VTK cell type name, count) of each cell kind a mesh was read with.
fn cell_counts(m: &crate::mesh::Mesh) -> Vec<(&str, usize)> {
    m.info
        .cells
        .iter()
        .map(|c| (c.name.as_str(), c.count))
        .collect()
}
