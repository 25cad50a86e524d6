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
    let cells: Vec<(&str, usize)> = m
        .info
        .cells
        .iter()
        .map(|c| (c.name.as_str(), c.count))
        .collect();
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
