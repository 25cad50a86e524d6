//! Hostile mesh files of issue 17, made byte by byte: legal or nearly legal files that
//! once panicked, hung or made arbvis allocate far more than they hold. Shared by the
//! unit tests, `tests/fuzz.rs` (fixed cases under the allocation caps) and
//! `tests/hostile.rs` (the same files through the binary), through `#[path]`, so it uses
//! nothing from the crate.
#![allow(dead_code)]

use std::io::Write;

use base64::Engine;

/// One `DataArray` of a zlib-compressed, base64 (`format="binary"`) `.vtu`.
pub struct Array {
    /// `Points`, `Cells`, `PointData` or `CellData`.
    pub section: &'static str,
    /// Its `Name`.
    pub name: &'static str,
    /// Its `type` (`Float64`, `Int32`, `UInt8`).
    pub ty: &'static str,
    /// `NumberOfComponents`.
    pub comps: usize,
    /// The values.
    pub data: Data,
}

/// What an array holds.
pub enum Data {
    /// These little-endian bytes.
    Bytes(Vec<u8>),
    /// This many zero bytes (compressed a block at a time, never all made).
    Zeros(usize),
}

/// Little-endian bytes of f64 values.
pub fn f64s(v: impl IntoIterator<Item = f64>) -> Data {
    Data::Bytes(v.into_iter().flat_map(f64::to_le_bytes).collect())
}

/// Little-endian bytes of i32 values.
pub fn i32s(v: impl IntoIterator<Item = i32>) -> Data {
    Data::Bytes(v.into_iter().flat_map(i32::to_le_bytes).collect())
}

fn deflate(b: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(b).unwrap();
    e.finish().unwrap()
}

/// `data` as VTK writes a zlib array in base64: the header (block count, block size,
/// last block size, compressed sizes; UInt32) and the blocks, encoded separately. Zeros
/// go in blocks of 1 MiB (about 1,000 bytes each compressed), other data in 64 kiB.
fn zlib_base64(data: &Data) -> String {
    let (len, block) = match data {
        Data::Bytes(b) => (b.len(), 1 << 16),
        Data::Zeros(n) => (*n, 1 << 20),
    };
    let count = len.div_ceil(block);
    let last = len - count.saturating_sub(1) * block;
    let compressed: Vec<Vec<u8>> = match data {
        Data::Bytes(b) => b.chunks(block).map(deflate).collect(),
        Data::Zeros(_) => {
            let full = deflate(&vec![0; block]);
            let mut v = vec![full; count.saturating_sub(1)];
            if count > 0 {
                v.push(deflate(&vec![0; last]));
            }
            v
        }
    };
    let last_field = if count == 0 || last == block { 0 } else { last };
    let mut header = vec![count as u32, block as u32, last_field as u32];
    header.extend(compressed.iter().map(|c| c.len() as u32));
    let header: Vec<u8> = header.iter().flat_map(|v| v.to_le_bytes()).collect();
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    b64(&header) + &b64(&compressed.concat())
}

/// A `.vtu` piece declaring `points` and `cells`, with `arrays` zlib-compressed.
pub fn zlib_vtu(points: u64, cells: u64, arrays: &[Array]) -> Vec<u8> {
    let mut s = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\" compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">\n"
    );
    for section in ["PointData", "CellData", "Points", "Cells"] {
        s += &format!("<{section}>\n");
        for a in arrays.iter().filter(|a| a.section == section) {
            s += &format!(
                "<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"binary\">\n{}\n</DataArray>\n",
                a.ty,
                a.name,
                a.comps,
                zlib_base64(&a.data)
            );
        }
        s += &format!("</{section}>\n");
    }
    s += "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    s.into_bytes()
}

/// The unit cube's corners in VTK hexahedron order.
pub const CUBE: [[f64; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
];

/// `n` hexahedra on the same 8 points, which stand at `corners` (`CUBE`: `n` identical
/// cubes stacked on each other; fewer distinct places: every cell collapsed flat). The
/// scalar `s` is uneven over the corners. 200,000 of them make a 0.3 MB file.
pub fn stacked_hexahedra(n: usize, corners: [[f64; 3]; 8]) -> Vec<u8> {
    stacked_hexahedra_with(n, corners, 0)
}

/// [`stacked_hexahedra`] with a cell array `c` of `comps` components (zeros), which a
/// reader copies to each of the 6 tetrahedra of every cell.
pub fn stacked_hexahedra_with(n: usize, corners: [[f64; 3]; 8], comps: usize) -> Vec<u8> {
    let s = [0.0, 1.0, 0.5, 0.2, 0.9, 0.1, 0.7, 0.3];
    let mut arrays = vec![
        Array {
            section: "PointData",
            name: "s",
            ty: "Float64",
            comps: 1,
            data: f64s(s),
        },
        Array {
            section: "Points",
            name: "Points",
            ty: "Float64",
            comps: 3,
            data: f64s(corners.iter().flatten().copied()),
        },
        Array {
            section: "Cells",
            name: "connectivity",
            ty: "Int32",
            comps: 1,
            data: i32s((0..n).flat_map(|_| 0..8)),
        },
        Array {
            section: "Cells",
            name: "offsets",
            ty: "Int32",
            comps: 1,
            data: i32s((1..=n as i32).map(|c| 8 * c)),
        },
        Array {
            section: "Cells",
            name: "types",
            ty: "UInt8",
            comps: 1,
            data: Data::Bytes(vec![12; n]),
        },
    ];
    if comps > 0 {
        arrays.push(Array {
            section: "CellData",
            name: "c",
            ty: "Float64",
            comps,
            data: Data::Zeros(n * comps * 8),
        });
    }
    zlib_vtu(8, n as u64, &arrays)
}

/// The corners of a hexahedron put on only four places (the unit tetrahedron's corners,
/// twice): every tetrahedron it splits into is flat, while its faces are not.
pub const FOUR_PLACES: [[f64; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];

/// A piece of `points` points (all zeros, so they compress a thousandfold: 60 million
/// points are 1.4 GB inflated from 1.9 MB of base64) and `cells` cells; with `cells > 0` they
/// are triangles, faces only. The reader must refuse before inflating the points.
pub fn inflating_points_without_volume(points: u64, cells: u64) -> Vec<u8> {
    inflating_points(points, cells, 5)
}

/// [`inflating_points_without_volume`] with cells of VTK type `cell_type` (5, triangles,
/// or 10, tetrahedra), all on the first points.
pub fn inflating_points(points: u64, cells: u64, cell_type: u8) -> Vec<u8> {
    let c = cells as usize;
    let k = if cell_type == 10 { 4 } else { 3 };
    zlib_vtu(
        points,
        cells,
        &[
            Array {
                section: "Points",
                name: "Points",
                ty: "Float64",
                comps: 3,
                data: Data::Zeros(points as usize * 24),
            },
            Array {
                section: "Cells",
                name: "connectivity",
                ty: "Int32",
                comps: 1,
                data: i32s((0..c).flat_map(|_| 0..k)),
            },
            Array {
                section: "Cells",
                name: "offsets",
                ty: "Int32",
                comps: 1,
                data: i32s((1..=c as i32).map(|j| k * j)),
            },
            Array {
                section: "Cells",
                name: "types",
                ty: "UInt8",
                comps: 1,
                data: Data::Bytes(vec![cell_type; c]),
            },
        ],
    )
}

/// `n` thin hexahedral plates across the unit square, stacked in z (each `h` thick):
/// a legal mesh whose cells do not overlap, but where a line crosses about 2.3 `n`
/// tetrahedra (VTK legacy ASCII; 1,400 plates are 90 kB).
pub fn stacked_plates(n: usize, h: f64) -> Vec<u8> {
    let mut s =
        String::from("# vtk DataFile Version 3.0\nplates\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    s += &format!("POINTS {} double\n", 4 * (n + 1));
    for i in 0..=n {
        let z = i as f64 * h;
        s += &format!("0 0 {z}\n1 0 {z}\n1 1 {z}\n0 1 {z}\n");
    }
    s += &format!("CELLS {n} {}\n", 9 * n);
    for i in 0..n {
        let (a, b) = (4 * i, 4 * (i + 1));
        s += &format!(
            "8 {a} {} {} {} {b} {} {} {}\n",
            a + 1,
            a + 2,
            a + 3,
            b + 1,
            b + 2,
            b + 3
        );
    }
    s += &format!("CELL_TYPES {n}\n{}", "12\n".repeat(n));
    s += &format!(
        "POINT_DATA {}\nSCALARS s double\nLOOKUP_TABLE default\n",
        4 * (n + 1)
    );
    for _ in 0..=n {
        s += "0 0.7 1 0.3\n";
    }
    s.into_bytes()
}

/// An ASCII gmsh 2.2 file of `nodes` nodes in a row, one tetrahedron, and `sections`
/// `$NodeData` sections of 9 components that list no entry: each once made a dense
/// `nodes x 9` array, so 40 bytes of file made `72 x nodes` bytes of memory.
pub fn empty_node_data(nodes: usize, sections: usize) -> Vec<u8> {
    let mut s = format!("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{nodes}\n");
    for i in 0..nodes {
        s += &format!("{} {} {} {}\n", i + 1, i % 2, (i / 2) % 2, i / 4);
    }
    s += "$EndNodes\n$Elements\n1\n1 4 0 1 2 3 5\n$EndElements\n";
    let section = "$NodeData\n1\n\"empty\"\n0\n3\n0\n9\n0\n$EndNodeData\n";
    s += &section.repeat(sections);
    s.into_bytes()
}

/// An ASCII gmsh 2.2 mesh of two tetrahedra in two `$Elements` sections, with its
/// `$NodeData` before `$Nodes` and its `$ElementData` between the `$Elements` sections,
/// naming an element of the second: legal in any order, and it must read as if the
/// data came last.
pub fn gmsh_data_first() -> Vec<u8> {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
    s += "$NodeData\n1\n\"t\"\n1\n0.0\n3\n0\n1\n5\n1 0.5\n2 -1.5\n3 2.25\n4 7\n5 3\n$EndNodeData\n";
    s += "$Nodes\n5\n1 0 0 0\n2 1.5 0 0\n3 0.2 1.1 0\n4 0.3 0.4 1.7\n5 1.6 1.2 0.9\n$EndNodes\n";
    s += "$Elements\n1\n10 4 2 7 8 1 2 3 4\n$EndElements\n";
    s += "$ElementData\n1\n\"m\"\n1\n0.0\n3\n0\n1\n2\n10 40\n11 41\n$EndElementData\n";
    s += "$Elements\n1\n11 4 2 7 8 2 3 5 4\n$EndElements\n";
    s.into_bytes()
}

/// A VTK legacy file whose hexahedron is collapsed to one point (all 8 corners the same
/// point index): no tetrahedron can be made of it.
pub fn collapsed_hexahedron() -> Vec<u8> {
    b"# vtk DataFile Version 3.0\ncollapsed\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 13\n3 0 1 2\n8 3 3 3 3 3 3 3 3\nCELL_TYPES 2\n5\n12\n"
        .to_vec()
}

/// A VTK legacy tetrahedron pair with coordinates near ±1.7e308, the largest f64.
pub fn huge_coordinates() -> Vec<u8> {
    b"# vtk DataFile Version 3.0\nhuge\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n-1.7e308 -1.7e308 -1.7e308\n1.7e308 -1.7e308 -1.7e308\n-1.7e308 1.7e308 -1.7e308\n-1.7e308 -1.7e308 1.7e308\n1.7e308 1.7e308 1.7e308\nCELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 2\n10\n10\nPOINT_DATA 5\nSCALARS s double\nLOOKUP_TABLE default\n0 0.3 0.6 0.9 1\n"
        .to_vec()
}
