//! Hostile input: every one is an error naming the file and the position, quickly, with
//! no panic and no allocation the file cannot back.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use super::fixtures::{self, all_fixtures, Vtu, VtuData};
use crate::mesh::parse;

/// `parse` must fail, naming the file and a position, and the message must contain `want`.
fn fails(name: &str, bytes: &[u8], want: &str) -> String {
    let t = Instant::now();
    let e = match parse(Path::new(name), bytes) {
        Ok(_) => panic!("{name}: parsed, expected an error containing {want:?}"),
        Err(e) => e.to_string(),
    };
    assert!(
        t.elapsed().as_millis() < 200,
        "{name}: slow ({:?})",
        t.elapsed()
    );
    assert!(e.starts_with(&format!("{name}: ")), "{e}");
    assert!(
        e.contains("line ") || e.contains("at byte "),
        "no position: {e}"
    );
    assert!(e.contains(want), "{name}: expected {want:?} in: {e}");
    e
}

fn replace(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    let i = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap_or_else(|| panic!("{from:?} not in fixture"));
    [&bytes[..i], to.as_bytes(), &bytes[i + from.len()..]].concat()
}

#[test]
fn truncated_at_every_byte() {
    let t = Instant::now();
    let mut errors = 0;
    for (name, bytes) in all_fixtures() {
        let full = parse(Path::new(&name), &bytes).unwrap();
        for len in 0..bytes.len() {
            match parse(Path::new(&name), &bytes[..len]) {
                Err(e) => {
                    let e = e.to_string();
                    assert!(
                        e.starts_with(&format!("{name}: "))
                            && (e.contains("line ") || e.contains("at byte ")),
                        "{e}"
                    );
                    errors += 1;
                }
                // Only a cut in trailing bytes the mesh does not need may parse, and then
                // to the same mesh.
                Ok(m) => {
                    assert_eq!(m.tets, full.tets, "{name} cut at {len}");
                    assert_eq!(m.points, full.points, "{name} cut at {len}");
                }
            }
        }
    }
    assert!(errors > 15_000, "{errors}");
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
}

#[test]
fn truncated_right_after_each_section_keyword() {
    for (name, bytes) in all_fixtures() {
        for kw in [
            "POINTS",
            "CELLS",
            "OFFSETS",
            "CONNECTIVITY",
            "CELL_TYPES",
            "POINT_DATA",
            "CELL_DATA",
            "SCALARS",
            "<Points>",
            "<Cells>",
            "<AppendedData",
            "$Nodes",
            "$Elements",
            "$NodeData",
        ] {
            if let Some(i) = bytes.windows(kw.len()).position(|w| w == kw.as_bytes()) {
                fails(&name, &bytes[..i + kw.len()], "");
            }
        }
    }
}

#[test]
fn counts_larger_than_the_file() {
    let a = fixtures::legacy_ascii();
    fails(
        "big.vtk",
        &replace(&a, "POINTS 6 double", "POINTS 1099511627776 double"),
        "the point count is 1099511627776, but the",
    );
    fails(
        "big.vtk",
        &replace(&a, "CELLS 5 21", "CELLS 5 1099511627776"),
        "the cell list size is 1099511627776",
    );
    fails(
        "big.vtk",
        &replace(&a, "SCALARS temp double 1", "SCALARS temp double 100000000"),
        "the values of \"temp\" is 600000000",
    );
    let b = fixtures::legacy_binary();
    fails(
        "big.vtk",
        &replace(&b, "POINTS 6 float", "POINTS 1099511627776 float"),
        "at least 12 bytes each",
    );
    let m = fixtures::legacy_51(true, true);
    fails(
        "big.vtk",
        &replace(&m, "CELLS 6 16", "CELLS 1099511627776 16"),
        "the offset count is 1099511627776",
    );
    let v = fixtures::vtu(Vtu {
        data: VtuData::AppendedRaw,
        header64: true,
        zlib: false,
        big: false,
        joint_base64: false,
    });
    fails(
        "big.vtu",
        &replace(&v, "NumberOfPoints=\"6\"", "NumberOfPoints=\"1e12\""),
        "NumberOfPoints=\"1e12\" is not a whole number",
    );
    fails(
        "big.vtu",
        &replace(
            &v,
            "NumberOfPoints=\"6\"",
            "NumberOfPoints=\"1000000000000\"",
        ),
        "the header says 144 bytes, but 24000000000000 are needed",
    );
    fails(
        "big.vtu",
        &replace(
            &v,
            "NumberOfCells=\"5\"",
            "NumberOfCells=\"18446744073709551615\"",
        ),
        "",
    );
    let va = fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: true,
        zlib: false,
        big: false,
        joint_base64: false,
    });
    fails(
        "big.vtu",
        &replace(
            &va,
            "NumberOfPoints=\"6\"",
            "NumberOfPoints=\"1000000000000\"",
        ),
        "DataArray \"Points\": holds 18 values, but 3 x NumberOfPoints=\"1000000000000\" (line 5) needs 3000000000000",
    );
    let g = fixtures::msh22(false);
    fails(
        "big.msh",
        &replace(&g, "$Nodes\n6\n", "$Nodes\n1099511627776\n"),
        "the node count is 1099511627776",
    );
    let g4 = fixtures::msh41(true);
    let mut header = [3u64, 6, 10, 60].map(|v| v.to_le_bytes()).concat();
    let at = g4
        .windows(header.len())
        .position(|w| w == header.as_slice())
        .unwrap();
    header[8..16].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let patched = [&g4[..at], &header, &g4[at + 32..]].concat();
    fails("big.msh", &patched, "the node count is 1099511627776");
}

#[test]
fn negative_counts() {
    let a = fixtures::legacy_ascii();
    fails(
        "neg.vtk",
        &replace(&a, "POINTS 6 double", "POINTS -6 double"),
        "the point count is negative: -6",
    );
    fails(
        "neg.vtk",
        &replace(&a, "CELLS 5 21", "CELLS -5 22"),
        "negative count",
    );
    fails(
        "neg.vtk",
        &replace(&a, "CELL_DATA 5", "CELL_DATA -5"),
        "negative tuple count -5",
    );
    fails(
        "neg.msh",
        &replace(&fixtures::msh22(false), "$Nodes\n6\n", "$Nodes\n-3\n"),
        "the node count is negative: \"-3\"",
    );
    fails(
        "neg.msh",
        &replace(&fixtures::msh41(false), "$Elements\n5 5", "$Elements\n-5 5"),
        "the element block count is negative",
    );
    let v = fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    });
    fails(
        "neg.vtu",
        &replace(&v, "NumberOfCells=\"5\"", "NumberOfCells=\"-5\""),
        "NumberOfCells=\"-5\" is not a whole number",
    );
}

#[test]
fn non_numbers_nan_and_wrong_types() {
    let a = fixtures::legacy_ascii();
    let e = fails(
        "nan.vtk",
        &replace(&a, "\n0.3 0.4 1.7\n", "\n0.3 abc 1.7\n"),
        "expected a number (value 11 of 18 of the point coordinates), found \"abc\"",
    );
    assert!(e.contains("line 12, column 5"), "{e}");
    let e = fails(
        "nan.vtk",
        &replace(&a, "\n0.3 0.4 1.7\n", "\n0.3 nan 1.7\n"),
        "point 3 has a coordinate that is not finite (NaN)",
    );
    assert!(e.contains("line 12, column 5"), "{e}");
    fails(
        "inf.msh",
        &replace(&fixtures::msh22(false), "4 0.3 0.4 1.7", "4 0.3 -inf 1.7"),
        "node 4 has a coordinate that is not finite (-inf)",
    );
    let v = fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    });
    fails(
        "nan.vtu",
        &replace(&v, "0.3 0.4 1.7", "0.3 NaN 1.7"),
        "point 3 has a coordinate that is not finite",
    );
    fails(
        "t.vtu",
        &replace(
            &v,
            "type=\"Int64\" Name=\"connectivity\"",
            "type=\"Float32\" Name=\"connectivity\"",
        ),
        "Float32 must be an integer type",
    );
    fails(
        "t.vtu",
        &replace(
            &v,
            "type=\"Int64\" Name=\"connectivity\"",
            "type=\"String\" Name=\"connectivity\"",
        ),
        "type \"String\" is not a numeric type",
    );
    fails(
        "t.vtk",
        &replace(
            &fixtures::legacy_51(true, false),
            "OFFSETS vtktypeint64",
            "OFFSETS float",
        ),
        "the cell offsets must be integers",
    );
    fails(
        "t.vtk",
        &replace(&a, "POINTS 6 double", "POINTS 6 quad"),
        "data type \"quad\" is not supported",
    );
    // NaN in a data array is kept, not an error.
    let m = parse(
        Path::new("ok.vtk"),
        &replace(&a, "0.5 -1.25 3 2 0 7.5", "0.5 -1.25 nan 2 0 7.5"),
    )
    .unwrap();
    assert!(m.point_array("temp").unwrap().values[2].is_nan());
}

#[test]
fn bad_indices_types_and_structure() {
    let v = fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    });
    fails(
        "idx.vtu",
        &replace(&v, "1 2 4 3 5 0 2 5 3", "1 2 4 3 5 0 2 9 3"),
        "cell 4 (VTK_TETRA) refers to point 9, but there are only 6 points",
    );
    fails(
        "ty.vtu",
        &replace(&v, "10 5 10 1 10", "10 5 10 1 42"),
        "cell 4: cell type 42 (VTK_POLYHEDRON) is not supported",
    );
    fails(
        "off.vtu",
        &replace(&v, "4 7 11 12 16", "4 7 3 12 16"),
        "offset 2 is 3, less than the one before (7)",
    );
    fails(
        "idx.msh",
        &replace(
            &fixtures::msh22(false),
            "104 4 2 7 8 17 99 5 4",
            "104 4 2 7 8 17 99 6 4",
        ),
        "element 104 (VTK_TETRA) refers to node 6, which is not in $Nodes",
    );
    fails(
        "ty.msh",
        &replace(&fixtures::msh41(false), "3 1 4 1 \n104", "3 1 29 1 \n104"),
        "gmsh element type 29 (a higher-order tetrahedron) is not supported",
    );
    fails(
        "dup.msh",
        &replace(&fixtures::msh22(false), "\n3 1.5 0 0\n", "\n17 1.5 0 0\n"),
        "node tag 17 appears twice",
    );
    fails(
        "end.msh",
        &replace(&fixtures::msh22(false), "$EndNodes", "$EndNodez"),
        "expected $EndNodes, found \"$EndNodez\"",
    );
    fails(
        "order.msh",
        &replace(
            &fixtures::msh22(true),
            "\x01\x00\x00\x00\n$EndMeshFormat",
            "\x02\x00\x00\x00\n$EndMeshFormat",
        ),
        "expected the integer 1 in either byte order",
    );
    fails(
        "data.msh",
        &replace(
            &fixtures::msh22(false),
            "$NodeData\n1\n\"temp\"\n1\n0.0\n3\n0\n1\n6\n5 7.5",
            "$NodeData\n1\n\"temp\"\n1\n0.0\n3\n0\n1\n6\n66 7.5",
        ),
        "data entry for node 66, which is in no $Nodes section",
    );
    let m = fixtures::legacy_51(false, false);
    fails(
        "dec.vtk",
        &replace(
            &m,
            "OFFSETS vtktypeint32\n0\n4\n7\n",
            "OFFSETS vtktypeint32\n0\n4\n2\n",
        ),
        "offset 2 is 2: offsets must not decrease",
    );
    let a = fixtures::legacy_ascii();
    let cut = &a[..a.windows(10).position(|w| w == b"CELL_TYPES").unwrap()];
    fails("nt.vtk", cut, "the file has no CELL_TYPES section");
    fails(
        "kw.vtk",
        &replace(&a, "CELL_DATA 5", "CELL_DATUM 5"),
        "expected a section keyword (POINTS, CELLS",
    );
    fails("n.vtk", &replace(&a, "CELL_DATA 5", "CELL_DATA 4"), "expected a section keyword (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, VECTORS, FIELD, METADATA, ...), found \"50\"");
}

/// A `.vtu` whose Points are the one appended array, given as raw bytes (header included).
fn vtu_points_appended(raw: &[u8], header64: bool) -> Vec<u8> {
    let mut b = format!(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"{}\" compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points>\n<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n</Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">_",
        if header64 { "UInt64" } else { "UInt32" }
    )
    .into_bytes();
    b.extend(raw);
    b.extend(b"</AppendedData></VTKFile>");
    b
}

fn zlib(data: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

#[test]
fn zlib_blocks_that_inflate_beyond_the_header_and_bombs() {
    let points: Vec<u8> = [0.0f64, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let table = |n: u32, block: u32, last: u32, sizes: &[u32]| -> Vec<u8> {
        [n, block, last]
            .iter()
            .chain(sizes)
            .flat_map(|v| v.to_le_bytes())
            .collect()
    };
    // The right table: one block of 96 bytes.
    let z = zlib(&points);
    let good = [table(1, 96, 0, &[z.len() as u32]), z.clone()].concat();
    let m = parse(Path::new("ok.vtu"), &vtu_points_appended(&good, false)).unwrap();
    assert_eq!(m.points[3], [0.0, 0.0, 1.0]);
    // Two blocks of 48 declared, but the first inflates to 96.
    let lie = [
        table(2, 48, 0, &[z.len() as u32, z.len() as u32]),
        z.clone(),
        z.clone(),
    ]
    .concat();
    fails(
        "lie.vtu",
        &vtu_points_appended(&lie, false),
        "zlib block 0 inflates to more than 48 bytes, but the header says 48",
    );
    // A bomb: 100 MB of zeros squeezed into ~100 kB, declared as the 96 bytes needed.
    let bomb = zlib(&vec![0u8; 100 << 20]);
    let b = [table(1, 96, 0, &[bomb.len() as u32]), bomb].concat();
    let t = Instant::now();
    fails(
        "bomb.vtu",
        &vtu_points_appended(&b, false),
        "inflates to more than 96 bytes",
    );
    assert!(t.elapsed().as_millis() < 100);
    // A table claiming more than deflate can produce from its compressed bytes.
    let huge = [table(1, 4_000_000_000, 0, &[z.len() as u32]), z.clone()].concat();
    fails(
        "ratio.vtu",
        &vtu_points_appended(&huge, false),
        "but 96 are needed",
    );
    let v = fixtures::vtu(Vtu {
        data: VtuData::AppendedRaw,
        header64: false,
        zlib: true,
        big: false,
        joint_base64: false,
    });
    let many = replace(&v, "NumberOfPoints=\"6\"", "NumberOfPoints=\"100000000\"");
    fails("ratio.vtu", &many, "");
    // Garbage instead of zlib.
    let junk = [table(1, 96, 0, &[20]), vec![0x55; 20]].concat();
    fails(
        "junk.vtu",
        &vtu_points_appended(&junk, false),
        "zlib block 0 does not inflate",
    );
    // A table whose block count disagrees with the points (found before the table,
    // which would run past the file, is read).
    let long = [table(1_000_000_000, 96, 0, &[]), vec![0; 8]].concat();
    fails(
        "table.vtu",
        &vtu_points_appended(&long, false),
        "the compression header declares 1000000000 blocks of 96 bytes (last 96): 96000000000 bytes, but 96 are needed",
    );
    // One that agrees with them but runs past the file.
    let long = [table(96, 1, 0, &[]), vec![0; 8]].concat();
    fails(
        "table.vtu",
        &vtu_points_appended(&long, false),
        "the appended data end inside its block table",
    );
}

#[test]
fn bad_base64() {
    let v = String::from_utf8(fixtures::vtu(Vtu {
        data: VtuData::Base64,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    }))
    .unwrap();
    let i = v.find("Name=\"Points\"").unwrap();
    let j = i + v[i..].find(">\n  ").unwrap() + 4;
    let mut bad = v.clone();
    bad.replace_range(j + 8..j + 12, "*!*!");
    fails(
        "b64.vtu",
        bad.as_bytes(),
        "DataArray \"Points\": bad base64 in its",
    );
    let mut short = v.clone();
    short.replace_range(j..j + 40, "");
    fails("b64.vtu", short.as_bytes(), "DataArray \"Points\"");
    let va = fixtures::vtu(Vtu {
        data: VtuData::AppendedBase64,
        header64: true,
        zlib: true,
        big: false,
        joint_base64: false,
    });
    let s = String::from_utf8(va).unwrap();
    let k = s.find("\n   _").unwrap() + 4;
    let mut bad = s.clone();
    bad.replace_range(k + 3..k + 5, "@@");
    fails("b64.vtu", bad.as_bytes(), "bad base64");
}

#[test]
fn garbage() {
    fails(
        "g.vtk",
        b"# vtk DataFile Version 3.0\n\xff\xfe\nGARBAGE\n",
        "expected ASCII or BINARY, found \"GARBAGE\"",
    );
    fails("g.vtu", b"<VTKFile type=\"UnstructuredGrid\"><Piece NumberOfPoints=\"1\" NumberOfCells=\"1\"></VTKFile>", "not well-formed XML");
    fails(
        "g.msh",
        b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n\x00\x01\x02",
        "expected a section such as $Nodes",
    );
    fails(
        "g.msh",
        b"$MeshFormat\n2.2 7 8\n$EndMeshFormat\n",
        "file type 7 is neither 0 (ASCII) nor 1 (binary)",
    );
    fails(
        "g.msh",
        b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Entities\n1 2 3\n",
        "section \"$Entities\" has no \"$EndEntities\" line",
    );
    fails("e.vtk", b"", "not a mesh file");
}
