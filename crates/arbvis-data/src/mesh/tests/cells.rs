//! Cell conversion: conformity of split hexahedra, wedges and pyramids under shuffled
//! global numbering, voxels, quadratic cells, refused types and bad indices.

use std::path::Path;

use super::real_files::face_counts;
use crate::mesh::cells::{vtk_kind, Converted, RawCells};
use crate::mesh::parse;
use crate::mesh::quality::signed_volume;

/// A 3x3x3-point grid (2x2x2 unit cubes) whose point `(i, j, k)` gets the global index
/// `shuffle(i + 3j + 9k)`, a bijection that scrambles the numbering.
fn shuffle(n: usize) -> u32 {
    ((n * 10 + 7) % 27) as u32
}

fn grid_points() -> Vec<[f64; 3]> {
    let mut p = vec![[0.0; 3]; 27];
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                // A small shear so that no face is axis-aligned.
                p[shuffle(i + 3 * j + 9 * k) as usize] = [
                    i as f64 + 0.1 * j as f64,
                    j as f64,
                    k as f64 + 0.05 * i as f64,
                ];
            }
        }
    }
    p
}

/// The 8 corners (VTK hexahedron order) of cube `(i, j, k)`, global indices.
fn hex(i: usize, j: usize, k: usize) -> [u32; 8] {
    let g = |a: usize, b: usize, c: usize| shuffle(i + a + 3 * (j + b) + 9 * (k + c));
    [
        g(0, 0, 0),
        g(1, 0, 0),
        g(1, 1, 0),
        g(0, 1, 0),
        g(0, 0, 1),
        g(1, 0, 1),
        g(1, 1, 1),
        g(0, 1, 1),
    ]
}

fn cubes() -> impl Iterator<Item = [u32; 8]> {
    (0..8).map(|c| hex(c & 1, (c >> 1) & 1, c >> 2))
}

fn convert(points: &[[f64; 3]], cells: &[(i64, Vec<u32>)]) -> Converted {
    let mut raw = RawCells {
        text: true,
        ..RawCells::default()
    };
    raw.offsets.push(0);
    for (t, nodes) in cells {
        raw.kinds.push(vtk_kind(*t).unwrap());
        raw.nodes.extend(nodes);
        raw.offsets.push(raw.nodes.len());
        raw.at.push(0);
    }
    raw.convert(Path::new("test"), b"", points).unwrap()
}

/// Interior triangles used exactly twice, `boundary` triangles used once, total volume 8.
fn assert_conforming(points: &[[f64; 3]], c: &Converted, boundary: usize, what: &str) {
    let faces = face_counts(&c.tets);
    assert!(
        faces.values().all(|&n| n == 1 || n == 2),
        "{what}: a triangle used more than twice"
    );
    assert_eq!(
        faces.values().filter(|&&n| n == 1).count(),
        boundary,
        "{what}: boundary triangles"
    );
    let volume: f64 = c.tets.iter().map(|&t| signed_volume(points, t)).sum();
    assert!((volume - 8.0).abs() < 1e-12, "{what}: volume {volume}");
    assert!(
        c.tets.iter().all(|&t| signed_volume(points, t) > 0.0),
        "{what}: orientation"
    );
}

#[test]
fn hexahedra_conform_under_shuffled_numbering_and_rotated_local_order() {
    let p = grid_points();
    // Each cell's local order is rotated differently (the same hexahedron, another
    // starting vertex): the split must not depend on it.
    let rotations: [[usize; 8]; 3] = [
        [0, 1, 2, 3, 4, 5, 6, 7],
        [1, 2, 3, 0, 5, 6, 7, 4],
        [4, 7, 6, 5, 0, 3, 2, 1],
    ];
    let cells: Vec<(i64, Vec<u32>)> = cubes()
        .enumerate()
        .map(|(n, h)| (12, rotations[n % 3].iter().map(|&i| h[i]).collect()))
        .collect();
    let c = convert(&p, &cells);
    assert_eq!((c.tets.len(), c.split, c.flipped), (48, 8, 0));
    // 6 sides x 4 quadrilaterals x 2 triangles on the boundary.
    assert_conforming(&p, &c, 48, "hexahedra");
    // Every tetrahedron has the smallest vertex of its cell (the pulling rule).
    for (t, &cell) in c.tets.iter().zip(&c.source_cell) {
        let min = *cells[cell as usize].1.iter().min().unwrap();
        assert!(t.contains(&min));
    }
}

#[test]
fn wedges_conform() {
    let p = grid_points();
    // Each cube as two wedges cut by the plane through its edges 0-4 and 2-6.
    let mut cells = Vec::new();
    for h in cubes() {
        cells.push((13, [0, 1, 2, 4, 5, 6].iter().map(|&i| h[i]).collect()));
        cells.push((13, [0, 2, 3, 4, 6, 7].iter().map(|&i| h[i]).collect()));
    }
    let c = convert(&p, &cells);
    assert_eq!((c.tets.len(), c.split), (48, 16));
    // 16 side quadrilaterals (32 triangles) + 16 top and bottom triangles.
    assert_conforming(&p, &c, 48, "wedges");
}

#[test]
fn pyramids_conform() {
    let mut p = grid_points();
    // Each cube as six pyramids on its faces with its centre as apex.
    let mut cells = Vec::new();
    for h in cubes() {
        let centre: [f64; 3] =
            std::array::from_fn(|a| h.iter().map(|&i| p[i as usize][a]).sum::<f64>() / 8.0);
        let apex = p.len() as u32;
        p.push(centre);
        for f in [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ] {
            let mut nodes: Vec<u32> = f.iter().map(|&i| h[i]).collect();
            nodes.push(apex);
            cells.push((14, nodes));
        }
    }
    let c = convert(&p, &cells);
    assert_eq!((c.tets.len(), c.split), (96, 48));
    assert_conforming(&p, &c, 48, "pyramids");
}

#[test]
fn voxels_use_x_fastest_order() {
    let p: Vec<[f64; 3]> = (0..8)
        .map(|c| [(c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64 * 2.0])
        .collect();
    let c = convert(&p, &[(11, (0..8).collect())]);
    assert_eq!(c.tets.len(), 6);
    let v: f64 = c.tets.iter().map(|&t| signed_volume(&p, t)).sum();
    assert!((v - 2.0).abs() < 1e-15, "{v}");
    assert_eq!(c.cells[0].name, "VTK_VOXEL");
}

#[test]
fn quadratic_cells_use_their_corners() {
    let p = grid_points();
    let h = hex(1, 0, 1);
    // A quadratic tetra: 4 corners then 6 edge nodes (any indices: they are not used).
    let mut tet10 = vec![h[0], h[1], h[3], h[4]];
    tet10.extend([0, 1, 2, 3, 4, 5]);
    let mut hex20: Vec<u32> = h.to_vec();
    hex20.extend(0..12);
    let c = convert(&p, &[(24, tet10), (25, hex20)]);
    assert_eq!((c.reduced, c.split, c.tets.len()), (2, 1, 7));
    let mut first = c.tets[0];
    first.sort_unstable();
    let mut want = [h[0], h[1], h[3], h[4]];
    want.sort_unstable();
    assert_eq!(first, want);
    let names: Vec<&str> = c.cells.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["VTK_QUADRATIC_TETRA", "VTK_QUADRATIC_HEXAHEDRON"]);
}

#[test]
fn a_collapsed_hexahedron_drops_its_empty_tetrahedra() {
    let p = grid_points();
    let h = hex(0, 0, 0);
    // Top face collapsed to an edge: a wedge written as a hexahedron.
    let c = convert(
        &p,
        &[(12, vec![h[0], h[1], h[2], h[3], h[4], h[5], h[5], h[4]])],
    );
    assert!(c.degenerate_dropped > 0);
    assert!(c
        .tets
        .iter()
        .all(|t| (0..4).all(|a| (a + 1..4).all(|b| t[a] != t[b]))));
}

fn legacy(types: &str, cells: &str, ncells: usize, size: usize) -> Vec<u8> {
    format!(
        "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\nCELLS {ncells} {size}\n{cells}\nCELL_TYPES {ncells}\n{types}\n"
    )
    .into_bytes()
}

#[test]
fn refused_types_name_number_name_and_cell() {
    let e = parse(
        Path::new("poly.vtk"),
        &legacy("10\n42", "4 0 1 2 3\n4 1 2 3 4", 2, 10),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("poly.vtk: line 12, column 1 (byte 153): "),
        "{e}"
    );
    assert!(
        e.contains("cell 1: cell type 42 (VTK_POLYHEDRON) is not supported"),
        "{e}"
    );
    let e = parse(Path::new("odd.vtk"), &legacy("99", "4 0 1 2 3", 1, 5))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cell 0: cell type 99 (not a VTK cell type)") && e.contains("line 10, column 1"),
        "{e}"
    );
    let e = parse(Path::new("lag.vtk"), &legacy("71", "4 0 1 2 3", 1, 5))
        .unwrap_err()
        .to_string();
    assert!(e.contains("VTK_LAGRANGE_TETRAHEDRON"), "{e}");
}

#[test]
fn wrong_node_counts_and_indices_name_the_cell_and_its_line() {
    let e = parse(
        Path::new("n.vtk"),
        &legacy("10\n10", "4 0 1 2 3\n5 0 1 2 3 4", 2, 11),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("line 9, column 1")
            && e.contains("cell 1 is a VTK_TETRA and needs 4 points, but the file gives 5"),
        "{e}"
    );
    let e = parse(
        Path::new("i.vtk"),
        &legacy("10\n10", "4 0 1 2 3\n4 1 2 3 5", 2, 10),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("line 9, column 1")
            && e.contains(
                "cell 1 (VTK_TETRA) refers to point 5, but there are only 5 points (0 to 4)"
            ),
        "{e}"
    );
    let e = parse(Path::new("neg.vtk"), &legacy("10", "4 0 1 -2 3", 1, 5))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 8, column 7") && e.contains("cell 0 has point index -2"),
        "{e}"
    );
}

#[test]
fn a_surface_only_file_is_an_error() {
    let e = parse(Path::new("tri.vtk"), &legacy("5", "3 0 1 2", 1, 4))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no volume cells") && e.contains("VTK_TRIANGLE: 1"),
        "{e}"
    );
}
