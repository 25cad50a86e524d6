//! Small mesh files written byte by byte, one per layout the real files do not cover.
//! Shared by the unit tests and by `tests/fuzz.rs` (through `#[path]`), so it
//! uses nothing from the crate.
//!
//! Every fixture holds the same mesh, chosen not to be friendly: 6 points with uneven
//! coordinates; 5 cells in the order tetrahedron, triangle, tetrahedron with a negative
//! volume, vertex, tetrahedron; point arrays `temp` (scalar) and `vel` (vector); cell
//! array `mat`.
#![allow(dead_code)]

use std::io::Write;

use base64::Engine;

/// The points.
pub const POINTS: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [1.5, 0.0, 0.0],
    [0.2, 1.1, 0.0],
    [0.3, 0.4, 1.7],
    [1.6, 1.2, 0.9],
    [-0.7, 0.5, 0.6],
];

/// The cells as (VTK type, gmsh type, nodes).
pub const CELLS: [(u8, u8, &[u32]); 5] = [
    (10, 4, &[0, 1, 2, 3]),
    (5, 2, &[0, 1, 2]),
    (10, 4, &[1, 2, 4, 3]),
    (1, 15, &[5]),
    (10, 4, &[0, 2, 5, 3]),
];

/// The tetrahedra a reader must produce (the second one flipped).
pub const TETS: [[u32; 4]; 3] = [[0, 1, 2, 3], [1, 2, 3, 4], [0, 2, 5, 3]];

/// Point scalar `temp`.
pub const TEMP: [f64; 6] = [0.5, -1.25, 3.0, 2.0, 0.0, 7.5];

/// Point vector `vel` of point `i`.
pub fn vel(i: usize) -> [f64; 3] {
    let x = i as f64;
    [x + 0.5, 2.0 - x, x * x]
}

/// Cell scalar `mat`.
pub const MAT: [f64; 5] = [10.0, 20.0, 30.0, 40.0, 50.0];

fn conn_len() -> usize {
    CELLS.iter().map(|c| c.2.len()).sum()
}

/// Legacy ASCII, classic `CELLS n size` layout, with `LOOKUP_TABLE`, `VECTORS`, `FIELD`,
/// `CELL_DATA` and a `METADATA` block.
pub fn legacy_ascii() -> Vec<u8> {
    let mut s = String::from(
        "# vtk DataFile Version 4.2\nfixture mesh\nASCII\nDATASET UNSTRUCTURED_GRID\n",
    );
    s += "FIELD FieldData 1\nTIME 1 1 double\n0.25\n";
    s += "POINTS 6 double\n";
    for p in POINTS {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    s += &format!("CELLS 5 {}\n", conn_len() + 5);
    for c in CELLS {
        s += &format!("{} {}\n", c.2.len(), join(c.2));
    }
    s += "CELL_TYPES 5\n";
    for c in CELLS {
        s += &format!("{}\n", c.0);
    }
    s += "CELL_DATA 5\nSCALARS mat float\nLOOKUP_TABLE default\n";
    s += &join(&MAT);
    s += "\nPOINT_DATA 6\nSCALARS temp double 1\nLOOKUP_TABLE default\n";
    s += &join(&TEMP);
    s += "\nMETADATA\nINFORMATION 1\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 1\n\n";
    s += "FIELD FieldData 1\nvel 3 6 float\n";
    for i in 0..6 {
        s += &format!("{}\n", join(&vel(i)));
    }
    s.into_bytes()
}

fn join<T: ToString>(v: &[T]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Legacy BINARY (big-endian), classic layout.
pub fn legacy_binary() -> Vec<u8> {
    let mut b =
        b"# vtk DataFile Version 3.0\nfixture\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 6 float\n"
            .to_vec();
    for p in POINTS {
        for x in p {
            b.extend((x as f32).to_be_bytes());
        }
    }
    b.extend(format!("\nCELLS 5 {}\n", conn_len() + 5).bytes());
    for c in CELLS {
        b.extend((c.2.len() as i32).to_be_bytes());
        for &n in c.2 {
            b.extend((n as i32).to_be_bytes());
        }
    }
    b.extend(b"\nCELL_TYPES 5\n");
    for c in CELLS {
        b.extend((c.0 as i32).to_be_bytes());
    }
    b.extend(b"\nCELL_DATA 5\nSCALARS mat double\nLOOKUP_TABLE default\n");
    for m in MAT {
        b.extend(m.to_be_bytes());
    }
    b.extend(b"\nPOINT_DATA 6\nSCALARS temp double\nLOOKUP_TABLE default\n");
    for t in TEMP {
        b.extend(t.to_be_bytes());
    }
    b.extend(b"\nVECTORS vel double\n");
    for i in 0..6 {
        for x in vel(i) {
            b.extend(x.to_be_bytes());
        }
    }
    b.push(b'\n');
    b
}

/// Legacy 5.1 with `OFFSETS`/`CONNECTIVITY` of `vtktypeint64` or `vtktypeint32`, ASCII or
/// BINARY.
pub fn legacy_51(int64: bool, binary: bool) -> Vec<u8> {
    let ty = if int64 {
        "vtktypeint64"
    } else {
        "vtktypeint32"
    };
    let mut b = format!(
        "# vtk DataFile Version 5.1\nvtk output\n{}\nDATASET UNSTRUCTURED_GRID\nPOINTS 6 double\n",
        if binary { "BINARY" } else { "ASCII" }
    )
    .into_bytes();
    let int = |b: &mut Vec<u8>, v: i64| {
        if !binary {
            b.extend(format!("{v}\n").bytes());
        } else if int64 {
            b.extend(v.to_be_bytes());
        } else {
            b.extend((v as i32).to_be_bytes());
        }
    };
    for p in POINTS {
        for x in p {
            if binary {
                b.extend(x.to_be_bytes());
            } else {
                b.extend(format!("{x} ").bytes());
            }
        }
    }
    b.extend(format!("\nCELLS 6 {}\nOFFSETS {ty}\n", conn_len()).bytes());
    let mut o = 0;
    int(&mut b, 0);
    for c in CELLS {
        o += c.2.len() as i64;
        int(&mut b, o);
    }
    b.extend(format!("\nCONNECTIVITY {ty}\n").bytes());
    for c in CELLS {
        for &n in c.2 {
            int(&mut b, n as i64);
        }
    }
    b.extend(b"\nCELL_TYPES 5\n");
    for c in CELLS {
        if binary {
            b.extend((c.0 as i32).to_be_bytes());
        } else {
            b.extend(format!("{}\n", c.0).bytes());
        }
    }
    b.extend(b"\nCELL_DATA 5\nFIELD FieldData 1\nmat 1 5 double\n");
    for m in MAT {
        if binary {
            b.extend(m.to_be_bytes());
        } else {
            b.extend(format!("{m}\n").bytes());
        }
    }
    b.extend(b"\nMETADATA\nINFORMATION 0\n\nPOINT_DATA 6\nFIELD FieldData 2\ntemp 1 6 double\n");
    for t in TEMP {
        if binary {
            b.extend(t.to_be_bytes());
        } else {
            b.extend(format!("{t}\n").bytes());
        }
    }
    b.extend(b"\nvel 3 6 double\n");
    for i in 0..6 {
        for x in vel(i) {
            if binary {
                b.extend(x.to_be_bytes());
            } else {
                b.extend(format!("{x}\n").bytes());
            }
        }
    }
    b.push(b'\n');
    b
}

/// How a `.vtu` fixture stores its arrays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VtuData {
    /// `format="ascii"`.
    Ascii,
    /// `format="binary"` (inline base64).
    Base64,
    /// `format="appended"`, `encoding="raw"`.
    AppendedRaw,
    /// `format="appended"`, `encoding="base64"`.
    AppendedBase64,
}

/// A `.vtu` fixture.
#[derive(Debug, Clone, Copy)]
pub struct Vtu {
    /// Storage.
    pub data: VtuData,
    /// UInt64 headers (else UInt32).
    pub header64: bool,
    /// vtkZLibDataCompressor (binary and appended only).
    pub zlib: bool,
    /// BigEndian (else LittleEndian).
    pub big: bool,
    /// Header and data base64-encoded together (as some writers do), not separately (VTK).
    pub joint_base64: bool,
}

/// One array: (type name, bytes per value, values as f64).
struct Arr {
    name: &'static str,
    ty: &'static str,
    comps: usize,
    values: Vec<f64>,
}

fn encode_values(a: &Arr, big: bool) -> Vec<u8> {
    let mut b = Vec::new();
    for &v in &a.values {
        match (a.ty, big) {
            ("Float64", false) => b.extend(v.to_le_bytes()),
            ("Float64", true) => b.extend(v.to_be_bytes()),
            ("Float32", false) => b.extend((v as f32).to_le_bytes()),
            ("Float32", true) => b.extend((v as f32).to_be_bytes()),
            ("Int64", false) => b.extend((v as i64).to_le_bytes()),
            ("Int64", true) => b.extend((v as i64).to_be_bytes()),
            ("Int32", false) => b.extend((v as i32).to_le_bytes()),
            ("Int32", true) => b.extend((v as i32).to_be_bytes()),
            ("UInt16", false) => b.extend((v as u16).to_le_bytes()),
            ("UInt16", true) => b.extend((v as u16).to_be_bytes()),
            ("Int8", _) => b.push(v as i8 as u8),
            _ => b.push(v as u8), // UInt8
        }
    }
    b
}

fn header_int(v: u64, cfg: &Vtu) -> Vec<u8> {
    match (cfg.header64, cfg.big) {
        (true, false) => v.to_le_bytes().to_vec(),
        (true, true) => v.to_be_bytes().to_vec(),
        (false, false) => (v as u32).to_le_bytes().to_vec(),
        (false, true) => (v as u32).to_be_bytes().to_vec(),
    }
}

/// Header and data of one binary array (compressed in blocks of 16 bytes, so that there
/// are several blocks and a partial last one).
fn binary_parts(data: &[u8], cfg: &Vtu) -> (Vec<u8>, Vec<u8>) {
    if !cfg.zlib {
        return (header_int(data.len() as u64, cfg), data.to_vec());
    }
    let block = 16;
    let chunks: Vec<&[u8]> = data.chunks(block).collect();
    let compressed: Vec<Vec<u8>> = chunks
        .iter()
        .map(|c| {
            let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            e.write_all(c).unwrap();
            e.finish().unwrap()
        })
        .collect();
    let last = data.len() % block;
    let mut h = header_int(chunks.len() as u64, cfg);
    h.extend(header_int(block as u64, cfg));
    h.extend(header_int(last as u64, cfg));
    for c in &compressed {
        h.extend(header_int(c.len() as u64, cfg));
    }
    (h, compressed.concat())
}

fn b64(b: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(b)
}

/// A `.vtu` file of the fixture mesh stored as `cfg` says.
pub fn vtu(cfg: Vtu) -> Vec<u8> {
    let mut appended = Vec::new();
    let mut x = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" header_type=\"{}\"{}>\n<UnstructuredGrid>\n<FieldData><DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">0.5</DataArray></FieldData>\n<Piece NumberOfPoints=\"6\" NumberOfCells=\"5\">\n",
        if cfg.big { "BigEndian" } else { "LittleEndian" },
        if cfg.header64 { "UInt64" } else { "UInt32" },
        if cfg.zlib { " compressor=\"vtkZLibDataCompressor\"" } else { "" }
    );
    let mut open = "";
    for (section, a) in &vtu_arrays() {
        if open != *section {
            if !open.is_empty() {
                x += &format!("</{open}>\n");
            }
            x += &format!("<{section}>\n");
            open = section;
        }
        x += &vtu_array(a, &cfg, &mut appended);
    }
    x += &format!("</{open}>\n</Piece>\n</UnstructuredGrid>\n");
    let mut b = x.into_bytes();
    if matches!(cfg.data, VtuData::AppendedRaw | VtuData::AppendedBase64) {
        let enc = if cfg.data == VtuData::AppendedRaw {
            "raw"
        } else {
            "base64"
        };
        b.extend(format!("<AppendedData encoding=\"{enc}\">\n   _").bytes());
        b.extend(appended);
        b.extend(b"\n</AppendedData>\n");
    }
    b.extend(b"</VTKFile>\n");
    b
}

/// The fixture mesh's arrays, each with its section.
fn vtu_arrays() -> [(&'static str, Arr); 7] {
    let mut offsets = Vec::new();
    let mut o = 0.0;
    for c in CELLS {
        o += c.2.len() as f64;
        offsets.push(o);
    }
    [
        (
            "PointData",
            Arr {
                name: "temp",
                ty: "Float64",
                comps: 1,
                values: TEMP.to_vec(),
            },
        ),
        (
            "PointData",
            Arr {
                name: "vel",
                ty: "Float32",
                comps: 3,
                values: (0..6).flat_map(vel).collect(),
            },
        ),
        (
            "CellData",
            Arr {
                name: "mat",
                ty: "UInt16",
                comps: 1,
                values: MAT.to_vec(),
            },
        ),
        (
            "Points",
            Arr {
                name: "Points",
                ty: "Float64",
                comps: 3,
                values: POINTS.concat(),
            },
        ),
        (
            "Cells",
            Arr {
                name: "connectivity",
                ty: "Int64",
                comps: 1,
                values: CELLS
                    .iter()
                    .flat_map(|c| c.2.iter().map(|&n| n as f64))
                    .collect(),
            },
        ),
        (
            "Cells",
            Arr {
                name: "offsets",
                ty: "Int32",
                comps: 1,
                values: offsets,
            },
        ),
        (
            "Cells",
            Arr {
                name: "types",
                ty: "UInt8",
                comps: 1,
                values: CELLS.iter().map(|c| c.0 as f64).collect(),
            },
        ),
    ]
}

/// One `DataArray` element stored as `cfg` says (its data added to `appended` when
/// appended).
fn vtu_array(a: &Arr, cfg: &Vtu, appended: &mut Vec<u8>) -> String {
    let mut out = String::new();
    let head = format!(
        "<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"",
        a.ty, a.name, a.comps
    );
    let bytes = encode_values(a, cfg.big);
    let (h, d) = binary_parts(&bytes, cfg);
    let enc = |h: &[u8], d: &[u8]| {
        if cfg.joint_base64 {
            b64(&[h, d].concat())
        } else {
            b64(h) + &b64(d)
        }
    };
    match cfg.data {
        VtuData::Ascii => {
            out += &format!(
                "{head} format=\"ascii\">\n  {}\n</DataArray>\n",
                join(&a.values)
            );
        }
        VtuData::Base64 => {
            let text = enc(&h, &d);
            // Break the text over lines, as writers do.
            let lines: Vec<&str> = text
                .as_bytes()
                .chunks(40)
                .map(|c| std::str::from_utf8(c).unwrap())
                .collect();
            out += &format!(
                "{head} format=\"binary\">\n  {}\n</DataArray>\n",
                lines.join("\n  ")
            );
        }
        VtuData::AppendedRaw | VtuData::AppendedBase64 => {
            out += &format!(
                "{head} format=\"appended\" offset=\"{}\"/>\n",
                appended.len()
            );
            if cfg.data == VtuData::AppendedRaw {
                appended.extend(h);
                appended.extend(d);
            } else {
                appended.extend(enc(&h, &d).bytes());
            }
        }
    }
    out
}

/// gmsh 2.2, ASCII or binary (little-endian).
pub fn msh22(binary: bool) -> Vec<u8> {
    let mut b = format!("$MeshFormat\n2.2 {} 8\n", u8::from(binary)).into_bytes();
    if binary {
        b.extend(1i32.to_le_bytes());
        b.push(b'\n');
    }
    b.extend(b"$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"solid\"\n$EndPhysicalNames\n$Nodes\n6\n");
    // Sparse node tags in a shuffled order: tag of point i.
    let tag = |i: usize| [17i32, 3, 99, 4, 250, 5][i];
    for (i, p) in POINTS.iter().enumerate() {
        if binary {
            b.extend(tag(i).to_le_bytes());
            for x in p {
                b.extend(x.to_le_bytes());
            }
        } else {
            b.extend(format!("{} {} {} {}\n", tag(i), p[0], p[1], p[2]).bytes());
        }
    }
    b.extend(b"$EndNodes\n$Elements\n5\n");
    for (e, c) in CELLS.iter().enumerate() {
        let etag = 100 + e as i32;
        if binary {
            for v in [c.1 as i32, 1, 2, etag, 7, 8] {
                b.extend(v.to_le_bytes());
            }
            for &n in c.2 {
                b.extend(tag(n as usize).to_le_bytes());
            }
        } else {
            let nodes: Vec<String> = c.2.iter().map(|&n| tag(n as usize).to_string()).collect();
            b.extend(format!("{etag} {} 2 7 8 {}\n", c.1, nodes.join(" ")).bytes());
        }
    }
    b.extend(b"$EndElements\n");
    data_sections(&mut b, binary, &|i| tag(i) as i64);
    b
}

fn data_sections(b: &mut Vec<u8>, binary: bool, tag: &dyn Fn(usize) -> i64) {
    b.extend(b"$NodeData\n1\n\"temp\"\n1\n0.0\n3\n0\n1\n6\n");
    // Entries in reverse order.
    for i in (0..6).rev() {
        if binary {
            b.extend((tag(i) as i32).to_le_bytes());
            b.extend(TEMP[i].to_le_bytes());
        } else {
            b.extend(format!("{} {}\n", tag(i), TEMP[i]).bytes());
        }
    }
    b.extend(b"$EndNodeData\n$NodeData\n1\n\"vel\"\n1\n0.0\n3\n0\n3\n6\n");
    for i in 0..6 {
        let v = vel(i);
        if binary {
            b.extend((tag(i) as i32).to_le_bytes());
            for x in v {
                b.extend(x.to_le_bytes());
            }
        } else {
            b.extend(format!("{} {} {} {}\n", tag(i), v[0], v[1], v[2]).bytes());
        }
    }
    b.extend(b"$EndNodeData\n$ElementData\n1\n\"mat\"\n0\n3\n0\n1\n5\n");
    for (e, m) in MAT.iter().enumerate() {
        if binary {
            b.extend((100 + e as i32).to_le_bytes());
            b.extend(m.to_le_bytes());
        } else {
            b.extend(format!("{} {m}\n", 100 + e).bytes());
        }
    }
    b.extend(b"$EndElementData\n");
}

/// gmsh 4.1, ASCII or binary (little-endian, 8-byte size_t), with the nodes in three
/// entity blocks (one parametric) and the elements in one block per type.
pub fn msh41(binary: bool) -> Vec<u8> {
    let mut b = format!("$MeshFormat\n4.1 {} 8\n", u8::from(binary)).into_bytes();
    if binary {
        b.extend(1i32.to_le_bytes());
        b.push(b'\n');
    }
    b.extend(b"$EndMeshFormat\n$Entities\n1 0 0 0\n1 0 0 0 0\n$EndEntities\n$Nodes\n");
    let tag = |i: usize| (i as i64 + 1) * 10;
    let sz = |b: &mut Vec<u8>, v: i64| {
        if binary {
            b.extend((v as u64).to_le_bytes());
        } else {
            b.extend(format!("{v} ").bytes());
        }
    };
    let int = |b: &mut Vec<u8>, v: i32| {
        if binary {
            b.extend(v.to_le_bytes());
        } else {
            b.extend(format!("{v} ").bytes());
        }
    };
    let nl = |b: &mut Vec<u8>| {
        if !binary {
            b.push(b'\n');
        }
    };
    // Blocks: points 0-1 (dim 3), point 2 alone (dim 1, parametric: one extra value), 3-5.
    let blocks: [(i32, i32, &[usize]); 3] = [(3, 0, &[0, 1]), (1, 1, &[2]), (3, 0, &[3, 4, 5])];
    for v in [3, 6, 10, 60] {
        sz(&mut b, v);
    }
    nl(&mut b);
    for (dim, param, pts) in blocks {
        int(&mut b, dim);
        int(&mut b, 7);
        int(&mut b, param);
        sz(&mut b, pts.len() as i64);
        nl(&mut b);
        for &p in pts {
            sz(&mut b, tag(p));
            nl(&mut b);
        }
        for &p in pts {
            for x in POINTS[p] {
                if binary {
                    b.extend(x.to_le_bytes());
                } else {
                    b.extend(format!("{x} ").bytes());
                }
            }
            if param == 1 {
                if binary {
                    b.extend(0.125f64.to_le_bytes());
                } else {
                    b.extend(b"0.125 ");
                }
            }
            nl(&mut b);
        }
    }
    b.extend(b"\n$EndNodes\n$Elements\n");
    for v in [5, 5, 100, 104] {
        sz(&mut b, v);
    }
    nl(&mut b);
    for (e, c) in CELLS.iter().enumerate() {
        int(&mut b, 3);
        int(&mut b, 1);
        int(&mut b, c.1 as i32);
        sz(&mut b, 1);
        nl(&mut b);
        sz(&mut b, 100 + e as i64);
        for &n in c.2 {
            sz(&mut b, tag(n as usize));
        }
        nl(&mut b);
    }
    b.extend(b"\n$EndElements\n");
    data_sections(&mut b, binary, &tag);
    b
}

/// All fixtures, by name.
pub fn all_fixtures() -> Vec<(String, Vec<u8>)> {
    let mut v = vec![
        ("ascii.vtk".to_string(), legacy_ascii()),
        ("binary.vtk".to_string(), legacy_binary()),
    ];
    for (i, (a, b)) in [(false, false), (false, true), (true, false), (true, true)]
        .into_iter()
        .enumerate()
    {
        v.push((format!("v51-{i}.vtk"), legacy_51(a, b)));
    }
    for (i, data) in [
        VtuData::Ascii,
        VtuData::Base64,
        VtuData::AppendedRaw,
        VtuData::AppendedBase64,
    ]
    .into_iter()
    .enumerate()
    {
        let zlib = data != VtuData::Ascii;
        v.push((
            format!("f{i}.vtu"),
            vtu(Vtu {
                data,
                header64: i % 2 == 0,
                zlib,
                big: i == 2,
                joint_base64: i == 3,
            }),
        ));
    }
    v.push((
        "raw32.vtu".into(),
        vtu(Vtu {
            data: VtuData::AppendedRaw,
            header64: false,
            zlib: false,
            big: false,
            joint_base64: false,
        }),
    ));
    for (name, b) in [
        ("a22.msh", msh22(false)),
        ("b22.msh", msh22(true)),
        ("a41.msh", msh41(false)),
        ("b41.msh", msh41(true)),
    ] {
        v.push((name.into(), b));
    }
    v
}

/// A small deterministic generator (xorshift64*), so the mutation tests are repeatable.
pub struct Rng(u64);

impl Rng {
    /// Seeded (0 is replaced by a fixed odd constant).
    pub fn new(seed: u64) -> Rng {
        Rng(if seed == 0 {
            0x9e37_79b9_7f4a_7c15
        } else {
            seed
        })
    }

    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// A number in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// `bytes` with 1 to 3 random edits: a byte flipped, set to a digit, sign, space, line
/// end or `$`; a cut; an insertion of random bytes or of a long number; a range deleted
/// or repeated.
pub fn mutate(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for _ in 0..1 + rng.below(3) {
        let at = rng.below(b.len() + 1);
        match rng.below(7) {
            0 if at < b.len() => b[at] ^= 1 << rng.below(8),
            1 if at < b.len() => {
                let set = b"0123456789-+ \n$.eE";
                b[at] = set[rng.below(set.len())];
            }
            2 => b.truncate(at),
            3 => {
                let n = 1 + rng.below(8);
                let junk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                b.splice(at..at, junk);
            }
            4 => {
                let digits = [
                    "4294967296",
                    "1099511627776",
                    "18446744073709551615",
                    "-1",
                    "9e99",
                    "nan",
                ][rng.below(6)];
                b.splice(at..at, digits.bytes());
            }
            5 => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                b.drain(at.min(end)..end);
            }
            _ => {
                let end = (at + 1 + rng.below(64)).min(b.len());
                let piece = b[at.min(end)..end].to_vec();
                b.splice(at..at, piece);
            }
        }
    }
    b
}

/// The sections of a mesh file as byte ranges, for mutations that move, repeat or swap
/// whole sections: gmsh `$Name ... $EndName` blocks (to the end of the end line), XML
/// elements (`Piece`, `Points`, `Cells`, `PointData`, `CellData`, `DataArray`, from `<` to
/// the end of the closing tag; they nest), and legacy sections (a keyword at a line
/// start up to the next keyword line).
pub fn sections(b: &[u8]) -> Vec<(usize, usize)> {
    let find = |from: usize, what: &[u8]| {
        b.get(from..)
            .and_then(|r| r.windows(what.len()).position(|w| w == what))
            .map(|p| from + p)
    };
    let line_end = |at: usize| find(at, b"\n").map_or(b.len(), |p| p + 1);
    let starts: Vec<usize> = std::iter::once(0)
        .chain(
            b.iter()
                .enumerate()
                .filter(|(_, &c)| c == b'\n')
                .map(|(i, _)| i + 1),
        )
        .filter(|&i| i < b.len())
        .collect();
    let mut out = Vec::new();
    if b.starts_with(b"$MeshFormat") {
        for &s in &starts {
            if b[s] != b'$' || b[s..].starts_with(b"$End") {
                continue;
            }
            let name_end = (s..b.len())
                .find(|&i| b[i].is_ascii_whitespace())
                .unwrap_or(b.len());
            // Binary data may run right up to the end line (no line end before it).
            let end_tag = [b"$End".as_slice(), &b[s + 1..name_end]].concat();
            if let Some(e) = find(name_end, &end_tag) {
                out.push((s, line_end(e)));
            }
        }
    } else if b.starts_with(b"# vtk") {
        const KEYWORDS: [&[u8]; 12] = [
            b"POINTS",
            b"CELLS",
            b"CELL_TYPES",
            b"POINT_DATA",
            b"CELL_DATA",
            b"SCALARS",
            b"VECTORS",
            b"FIELD",
            b"METADATA",
            b"OFFSETS",
            b"CONNECTIVITY",
            b"LOOKUP_TABLE",
        ];
        let keyed: Vec<usize> = starts
            .iter()
            .copied()
            .filter(|&s| KEYWORDS.iter().any(|k| b[s..].starts_with(k)))
            .collect();
        for (i, &s) in keyed.iter().enumerate() {
            out.push((s, keyed.get(i + 1).copied().unwrap_or(b.len())));
        }
    } else {
        for tag in [
            "Piece",
            "Points",
            "Cells",
            "PointData",
            "CellData",
            "DataArray",
        ] {
            let open = format!("<{tag}");
            let close = format!("</{tag}>");
            let mut from = 0;
            while let Some(s) = find(from, open.as_bytes()) {
                from = s + 1;
                let after = b.get(s + open.len()).copied().unwrap_or(b' ');
                if !(after.is_ascii_whitespace() || after == b'>' || after == b'/') {
                    continue;
                }
                let Some(gt) = find(s, b">") else { break };
                let end = if b[gt - 1] == b'/' {
                    Some(gt + 1)
                } else {
                    find(gt, close.as_bytes()).map(|e| e + close.len())
                };
                if let Some(e) = end {
                    out.push((s, e));
                }
            }
        }
    }
    out
}
