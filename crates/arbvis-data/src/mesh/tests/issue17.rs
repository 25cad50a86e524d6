//! Issue 17 (hostile input, round 2), the mesh part, at the library level: sections in
//! any order, arrays that do not match, collapsed and stacked cells, coordinates near
//! the largest f64, truncated and unclosed XML, and messages that name the real cause.
//! (Memory refusals need a small budget, which is process-wide: they are tested in
//! `tests/fuzz.rs` and, through the binary, `tests/hostile.rs`.)

use std::path::Path;
use std::time::Instant;

use base64::Engine;

use super::fixtures::{self, Vtu, VtuData};
use super::hostile_files as hostile;
use crate::mesh::cells::RawCells;
use crate::mesh::quality::Quality;
use crate::mesh::{parse, DataArray, Mesh, MeshError, MeshInfo, ReadArray};

fn err(name: &str, bytes: &[u8]) -> String {
    match parse(Path::new(name), bytes) {
        Ok(_) => panic!("{name} was read"),
        Err(e) => e.to_string(),
    }
}

fn contains_all(e: &str, parts: &[&str]) {
    for p in parts {
        assert!(e.contains(p), "expected {p:?} in: {e}");
    }
}

fn replace(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    let s = String::from_utf8(bytes.to_vec()).unwrap();
    assert!(s.contains(from), "{from:?} not in the fixture");
    s.replacen(from, to, 1).into_bytes()
}

#[test]
fn gmsh_data_sections_may_come_before_what_they_name() {
    let m = parse(Path::new("first.msh"), &hostile::gmsh_data_first()).unwrap();
    assert_eq!(m.points.len(), 5);
    assert_eq!(m.source_cell, [0, 1]);
    assert_eq!(
        m.point_array("t").unwrap().values,
        [0.5, -1.5, 2.25, 7.0, 3.0]
    );
    // One tuple per tetrahedron, from its element (11 is in the second $Elements).
    assert_eq!(m.cell_array("m").unwrap().values, [40.0, 41.0]);
}

#[test]
fn gmsh_entries_for_unknown_or_too_many_items_name_the_entry() {
    let bad = replace(&hostile::gmsh_data_first(), "11 41\n", "12 41\n");
    let e = err("bad.msh", &bad);
    contains_all(
        &e,
        &[
            "bad.msh: line 41, column 1",
            "data entry for element 12, which is in no $Elements section",
        ],
    );
    // Three entries for the file's two elements (the count's own position).
    let many = replace(
        &hostile::gmsh_data_first(),
        "1\n2\n10 40\n11 41\n",
        "1\n3\n10 40\n11 41\n11 42\n",
    );
    let e = err("many.msh", &many);
    contains_all(
        &e,
        &[
            "many.msh: line 39, column 1",
            "3 entries for the 2 elements",
        ],
    );
}

#[test]
fn legacy_data_sections_are_checked_against_points_and_cells_in_any_order() {
    let a = String::from_utf8(fixtures::legacy_ascii()).unwrap();
    // Move the CELL_DATA block before POINTS: still the same mesh.
    let start = a.find("CELL_DATA 5").unwrap();
    let end = a.find("POINT_DATA 6").unwrap();
    let block = &a[start..end];
    let moved = a
        .replacen(block, "", 1)
        .replacen("POINTS 6", &format!("{block}POINTS 6"), 1);
    let m = parse(Path::new("moved.vtk"), moved.as_bytes()).unwrap();
    assert_eq!(m.cell_array("mat").unwrap().values, [10.0, 30.0, 50.0]);
    // A CELL_DATA count that the cells do not have, given before the cells.
    let wrong = moved.replacen(
        "CELL_DATA 5\nSCALARS mat float\nLOOKUP_TABLE default\n10 20 30 40 50",
        "CELL_DATA 4\nSCALARS mat float\nLOOKUP_TABLE default\n10 20 30 40",
        1,
    );
    let e = err("wrong.vtk", wrong.as_bytes());
    contains_all(
        &e,
        &[
            "wrong.vtk: line 8, column 1",
            "CELL_DATA 4 does not match the 5 cells of CELLS (line 19)",
        ],
    );
    let twice = a.replacen("CELL_TYPES 5", "POINTS 1 float\n0 0 0\nCELL_TYPES 5", 1);
    let e = err("twice.vtk", twice.as_bytes());
    contains_all(
        &e,
        &["a second POINTS section: the file already has one at line 8"],
    );
}

#[test]
fn assemble_refuses_arrays_that_do_not_match_and_never_indexes_past_them() {
    let points = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let raw = RawCells {
        kinds: vec![crate::mesh::cells::vtk_kind(10).unwrap(); 2],
        offsets: vec![0, 4, 8],
        nodes: vec![0, 1, 2, 3, 3, 2, 1, 0],
        at: vec![0, 0],
        token_base: None,
        text: false,
        indexed: false,
    };
    let array = |values: Vec<f64>, components| ReadArray {
        array: DataArray {
            name: "c".into(),
            components,
            values,
        },
        at: 3,
    };
    let bytes = b"x\ny\nz";
    let e = Mesh::assemble(
        Path::new("m"),
        bytes,
        points.clone(),
        &raw,
        Vec::new(),
        vec![array(vec![1.0, 2.0, 3.0], 2)],
        MeshInfo::default(),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        "m: line 2, column 2 (byte 3): cell array \"c\" holds 3 values (2 components each), but the mesh has 2 cells: one tuple per cell is needed"
    );
    let e = Mesh::assemble(
        Path::new("m"),
        bytes,
        points.clone(),
        &raw,
        vec![array(vec![1.0; 3], 1)],
        Vec::new(),
        MeshInfo::default(),
    )
    .unwrap_err();
    assert!(matches!(e, MeshError::Format { .. }), "{e}");
    let m = Mesh::assemble(
        Path::new("m"),
        bytes,
        points,
        &raw,
        Vec::new(),
        vec![array(vec![1.0, 2.0, 3.0, 4.0], 2)],
        MeshInfo::default(),
    )
    .unwrap();
    assert_eq!(m.cell_arrays[0].values, [1.0, 2.0, 3.0, 4.0]);
}

#[test]
fn a_collapsed_cell_is_named_as_collapsed() {
    let e = err("c.vtk", &hostile::collapsed_hexahedron());
    contains_all(
        &e,
        &[
            "c.vtk: line 9, column 1",
            "no tetrahedra: all 1 volume cells are collapsed (degenerate)",
            "the first is cell 1 (VTK_HEXAHEDRON) with points [3, 3, 3, 3, 3, 3, 3, 3]",
        ],
    );
    assert!(!e.contains("no volume cells"), "{e}");
    // A file tetrahedron with a repeated point is collapsed too, not kept flat.
    let t = b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nCELLS 1 5\n4 0 1 2 2\nCELL_TYPES 1\n10\n";
    contains_all(
        &err("t.vtk", t),
        &[
            "all 1 volume cells are collapsed",
            "cell 0 (VTK_TETRA) with points [0, 1, 2, 2]",
        ],
    );
}

fn ascii_vtu() -> Vec<u8> {
    fixtures::vtu(Vtu {
        data: VtuData::Ascii,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    })
}

#[test]
fn a_number_of_cells_lie_is_told_as_such() {
    let v = replace(&ascii_vtu(), "NumberOfCells=\"5\"", "NumberOfCells=\"6\"");
    let e = err("lie.vtu", &v);
    contains_all(
        &e,
        &["DataArray \"offsets\": holds 5 values, but NumberOfCells=\"6\" (line 5) needs 6"],
    );
    assert!(!e.contains("bytes left"), "{e}");
}

#[test]
fn a_base64_header_one_byte_short_is_told_as_such() {
    // One zlib block of the 4 points, in a UInt64 header of 4 integers (32 bytes),
    // written one byte short: 31 bytes encode to 44 characters ending in '='.
    let data: Vec<u8> = [0.0f64, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    std::io::Write::write_all(&mut z, &data).unwrap();
    let z = z.finish().unwrap();
    let header: Vec<u8> = [1u64, 96, 0, z.len() as u64]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let text = b64(&header[..31]) + &b64(&z);
    let file = format!(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">{text}</DataArray></Points>\n<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n</Piece></UnstructuredGrid></VTKFile>\n"
    );
    let e = err("short.vtu", file.as_bytes());
    contains_all(
        &e,
        &[
            "short.vtu: line 3, column 9",
            "the base64 header decodes to 31 bytes, but 4 8-byte integers",
            "the header is cut short",
        ],
    );
    assert!(!e.contains("overflow"), "{e}");
    // The same with the header whole reads.
    let whole = file.replace(&b64(&header[..31]), &b64(&header));
    let m = parse(Path::new("whole.vtu"), whole.as_bytes()).unwrap();
    assert_eq!(m.points[3], [0.0, 0.0, 1.0]);
}

#[test]
fn truncated_and_unclosed_xml_is_refused_where_it_ends() {
    let v = ascii_vtu();
    let cut = &v[..v.len() - "</VTKFile>\n".len()];
    let e = err("cut.vtu", cut);
    contains_all(
        &e,
        &[
            &format!("(byte {})", cut.len()),
            "the file ends inside <VTKFile> (opened at line 2)",
        ],
    );
    let raw = fixtures::vtu(Vtu {
        data: VtuData::AppendedRaw,
        header64: false,
        zlib: false,
        big: false,
        joint_base64: false,
    });
    let close = raw
        .windows(15)
        .position(|w| w == b"</AppendedData>")
        .unwrap();
    // Cut after the data, before the closing tags: every array decodes, yet the file is
    // not whole.
    let e = err("cut.vtu", &raw[..close]);
    contains_all(
        &e,
        &[
            &format!("(byte {close})"),
            &format!("the file ends at byte {close} without </AppendedData> and </VTKFile>"),
        ],
    );
    assert!(parse(Path::new("whole.vtu"), &raw).is_ok());
}

#[test]
fn coordinates_near_the_largest_f64_give_finite_volumes_and_orientations() {
    let huge = hostile::huge_coordinates();
    let small = String::from_utf8(huge.clone())
        .unwrap()
        .replace("e308", "e8");
    let (h, s) = (
        parse(Path::new("huge.vtk"), &huge).unwrap(),
        parse(Path::new("small.vtk"), small.as_bytes()).unwrap(),
    );
    // The same mesh 10^300 times larger: the same orientation decisions.
    assert_eq!(h.tets, s.tets);
    assert_eq!(h.info.flipped, s.info.flipped);
    let (qh, qs) = (Quality::of(&h), Quality::of(&s));
    assert_eq!((qh.flat, qs.flat), (0, 0));
    assert!(qh.scaled_volumes.0 > 0.0 && qh.scaled_volumes.0.is_finite());
    // Volumes scale by (10^300)^3: same digits, exponent 900 higher. The total of the
    // small mesh is (3.4e8)^3 x (1/6 + 1/3) = 1.9652e25.
    let text = |m: &Mesh| crate::mesh::describe(m);
    let (th, ts) = (text(&h), text(&s));
    assert!(ts.contains("volume: total 1.965200e25,"), "{ts}");
    assert!(th.contains("volume: total 1.965200e925,"), "{th}");
    assert!(th.contains("bounds: x [-1.7e308, 1.7e308]"), "{th}");
    assert!(!th.contains("NaN") && !th.contains("inf"), "{th}");
    assert_eq!(
        qh.total_volume,
        f64::INFINITY,
        "beyond f64: the scaled form is kept"
    );
}

#[test]
fn stacked_and_collapsed_hexahedra_are_read_fast_and_reported() {
    let n = 20_000;
    let t = Instant::now();
    let m = parse(
        Path::new("stacked.vtu"),
        &hostile::stacked_hexahedra(n, hostile::CUBE),
    )
    .unwrap();
    let q = Quality::of(&m);
    assert_eq!(m.tets.len(), 6 * n);
    assert_eq!(q.repeated, 6 * (n - 1));
    assert_eq!(q.first_repeat, Some((6, 0)));
    // Six tetrahedra of one cube: a line crosses about 2.5 (their surface areas, 15,
    // over the cube's, 6).
    assert!((q.depth - 2.5).abs() < 0.1, "{}", q.depth);
    let flat = parse(
        Path::new("four.vtu"),
        &hostile::stacked_hexahedra(n, hostile::FOUR_PLACES),
    )
    .unwrap();
    let qf = Quality::of(&flat);
    assert_eq!((qf.flat, qf.first_flat), (6 * n, Some(0)));
    assert_eq!(qf.depth, 0.0);
    // Both reads and measures of 120,000 tetrahedra take milliseconds in a release
    // build; 5 s bounds a debug build on two busy cores.
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
}

#[test]
fn pieces_without_volume_are_refused_before_their_points_are_inflated() {
    // 10 million points (240 MB inflated) in a 0.3 MB file: refused in milliseconds,
    // before the points are touched.
    for (cells, want) in [
        (0, "the piece has no cells (NumberOfCells=\"0\"), so no volume cells"),
        (3, "no volume cells (tetrahedra, hexahedra, voxels, wedges, pyramids): the 3 cells are points, lines and faces (the first is VTK_TRIANGLE)"),
    ] {
        let file = hostile::inflating_points_without_volume(10_000_000, cells);
        assert!(file.len() < 450_000, "{}", file.len());
        let t = Instant::now();
        let e = err("bomb.vtu", &file);
        contains_all(&e, &["bomb.vtu: line ", want]);
        // Inflating the points alone takes about a second in a debug build.
        assert!(t.elapsed().as_millis() < 300, "{:?}", t.elapsed());
    }
}

/// `bytes` with `block` cut out and put back at `to` (an offset into the original,
/// before the block), followed by a line end.
fn moved(bytes: &[u8], block: (usize, usize), to: usize) -> Vec<u8> {
    let (a, b) = block;
    assert!(to <= a, "moves go toward the start");
    let mut piece = bytes[a..b].to_vec();
    if piece.last() != Some(&b'\n') {
        piece.push(b'\n');
    }
    [&bytes[..to], &piece, &bytes[to..a], &bytes[b..]].concat()
}

#[test]
fn every_format_reads_the_same_mesh_with_its_data_before_its_mesh() {
    use super::formats::check_fixture;
    let find = |b: &[u8], what: &[u8]| b.windows(what.len()).position(|w| w == what).unwrap();
    for (name, bytes) in fixtures::all_fixtures() {
        // Float32 coordinates in some fixtures: within 1e-7 of the f64 ones (up to 1.7).
        let tol = 1e-6;
        let out = if name.ends_with(".msh") {
            // gmsh 2.2 and 4.1, ASCII and binary: every data section right after
            // $EndMeshFormat, before $Nodes and $Elements.
            let blocks: Vec<(usize, usize)> = fixtures::sections(&bytes)
                .into_iter()
                .filter(|&(a, _)| {
                    bytes[a..].starts_with(b"$NodeData") || bytes[a..].starts_with(b"$ElementData")
                })
                .collect();
            assert_eq!(blocks.len(), 3, "{name}");
            let to = find(&bytes, b"$EndMeshFormat\n") + 15;
            let mut out = bytes[..to].to_vec();
            for &(a, b) in &blocks {
                out.extend(&bytes[a..b]);
            }
            let mut at = to;
            for &(a, b) in &blocks {
                out.extend(&bytes[at..a]);
                at = b;
            }
            out.extend(&bytes[at..]);
            out
        } else if name.ends_with(".vtk") {
            // VTK legacy: POINT_DATA and CELL_DATA (to the end of the file) before POINTS.
            let data = ["\nCELL_DATA", "\nPOINT_DATA"]
                .iter()
                .map(|k| find(&bytes, k.as_bytes()) + 1)
                .min()
                .unwrap();
            moved(&bytes, (data, bytes.len()), find(&bytes, b"\nPOINTS ") + 1)
        } else {
            // .vtu: the order of XML elements is free; CellData first of all.
            let s = fixtures::sections(&bytes);
            let cell_data = s
                .iter()
                .find(|&&(a, _)| bytes[a..].starts_with(b"<CellData"))
                .copied()
                .unwrap();
            moved(&bytes, cell_data, find(&bytes, b"<PointData"))
        };
        assert_ne!(out, bytes, "{name}");
        let m = parse(Path::new(&name), &out).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_fixture(&m, tol, &format!("{name}, data first"));
    }
}
