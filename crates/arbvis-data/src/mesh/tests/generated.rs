//! The generated grid, scalars and quality.

use std::path::Path;

use super::real_files::face_counts;
use crate::mesh::grid::{generate, Field, GridSpec, MAX_GRID_TETS};
use crate::mesh::quality::{is_flat, radius_ratio, signed_volume, Quality, SLIVER_RADIUS_RATIO};
use crate::mesh::scalars::{FromCells, ScalarSpec};
use crate::mesh::{parse, DataArray, MeshSource};

#[test]
fn the_seed_mesh_has_24576_conforming_tetrahedra() {
    let m = generate(&GridSpec::default()).unwrap();
    assert_eq!((m.points.len(), m.tets.len()), (17 * 17 * 17, 24_576));
    let q = Quality::of(&m);
    assert!((q.total_volume - 1.0).abs() < 1e-12, "{}", q.total_volume);
    assert!((q.min_volume - 1.0 / 16f64.powi(3) / 6.0).abs() < 1e-15);
    assert_eq!((q.flat, q.slivers), (0, 0));
    // Interior triangles twice; boundary: 6 sides x 16 x 16 squares x 2 triangles.
    let faces = face_counts(&m.tets);
    assert!(faces.values().all(|&n| n == 1 || n == 2));
    assert_eq!(faces.values().filter(|&&n| n == 1).count(), 6 * 256 * 2);
    assert_eq!(m.bounds(), Some(([0.0; 3], [1.0; 3])));
    assert_eq!(m.info.cells[0].count, 4096);
}

#[test]
fn fields_are_normalized_and_shaped_as_named() {
    let c = 8 + 17 * (8 + 17 * 8); // the centre point (8, 8, 8)
    for f in Field::ALL {
        let m = generate(&GridSpec {
            points: [17, 17, 17],
            field: f,
        })
        .unwrap();
        let a = &m.point_arrays[0];
        assert_eq!(a.name, f.name());
        let lo = a.values.iter().copied().fold(f64::MAX, f64::min);
        let hi = a.values.iter().copied().fold(f64::MIN, f64::max);
        assert_eq!((lo, hi), (0.0, 1.0), "{}", f.name());
    }
    let get = |f: Field| {
        generate(&GridSpec {
            points: [17, 17, 17],
            field: f,
        })
        .unwrap()
        .point_arrays[0]
            .values
            .clone()
    };
    let sph = get(Field::Spherical);
    assert_eq!(sph[c], 0.0);
    assert_eq!(sph[0], 1.0); // a corner
                             // Point (16, 8, 8) is at half the corner distance from the centre: 0.5 / sqrt(0.75).
    assert!((sph[16 + 17 * (8 + 17 * 8)] - 0.5 / 0.75f64.sqrt()).abs() < 1e-15);
    let planar = get(Field::Planar);
    assert_eq!(planar[8], 0.5); // i = 8: the isovalue 0.5 sits on a vertex plane
    assert_eq!(planar[3 + 17 * 5], 3.0 / 16.0);
    let cyl = get(Field::Cylindrical);
    assert_eq!(cyl[8 + 17 * 8 + 17 * 17 * 3], 0.0); // on the z axis through the centre
}

#[test]
fn odd_sizes_and_absurd_ones() {
    let m = generate(&GridSpec {
        points: [2, 5, 3],
        field: Field::Saddle,
    })
    .unwrap();
    assert_eq!((m.points.len(), m.tets.len()), (30, 6 * 8));
    assert_eq!(m.bounds(), Some(([0.0; 3], [0.25, 1.0, 0.5])));
    for bad in [
        [1, 17, 17],
        [0, 0, 0],
        [1_000_000, 1_000_000, 1_000_000],
        [usize::MAX, 2, 2],
    ] {
        let e = generate(&GridSpec {
            points: bad,
            field: Field::Planar,
        })
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("at least 2 points per axis and at most 16777216 tetrahedra"),
            "{e}"
        );
    }
    // The largest allowed cube of cubes is accepted by the check (not generated here).
    assert!(6 * 140u64.pow(3) <= MAX_GRID_TETS && 6 * 141u64.pow(3) > MAX_GRID_TETS);
}

#[test]
fn mesh_sources_from_toml() {
    #[derive(serde::Deserialize)]
    struct S {
        mesh: MeshSource,
    }
    let s: S =
        toml::from_str("mesh = { grid = { points = [5, 4, 3], field = \"waves\" } }").unwrap();
    let m = s.mesh.load(Path::new("/nowhere")).unwrap();
    assert_eq!(
        (m.points.len(), m.point_arrays[0].name.as_str()),
        (60, "waves")
    );
    let s: S = toml::from_str("mesh = { grid = {} }").unwrap();
    assert_eq!(s.mesh.load(Path::new(".")).unwrap().tets.len(), 24_576);
    let s: S = toml::from_str("mesh = { file = \"tets/post.vtk\" }").unwrap();
    assert_eq!(s.mesh.path(), Some(Path::new("tets/post.vtk")));
    let data = arbvis_core::input::data_file("tets/post.vtk");
    let m = s
        .mesh
        .load(data.parent().unwrap().parent().unwrap())
        .unwrap();
    assert_eq!(m.tets.len(), 8750);
    for bad in [
        "mesh = { grid = { points = [5, 4, 3], field = \"cubic\" } }",
        "mesh = { grid = { point = [5, 4, 3] } }",
        "mesh = { files = \"a.vtk\" }",
    ] {
        assert!(toml::from_str::<S>(bad).is_err(), "{bad}");
    }
    let e = MeshSource::File("missing.vtk".into())
        .load(Path::new("/nonexistent-dir"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("/nonexistent-dir/missing.vtk: "), "{e}");
}

fn fixture_mesh() -> crate::mesh::Mesh {
    parse(Path::new("f.vtk"), &super::fixtures::legacy_ascii()).unwrap()
}

#[test]
fn scalars_by_name_component_magnitude_and_range() {
    let m = fixture_mesh();
    let s = ScalarSpec {
        array: Some("temp".into()),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!(s.range, [-1.25, 7.5]);
    assert_eq!(s.values[1], 0.0);
    assert_eq!(s.values[5], 1.0);
    assert!((s.values[0] - 1.75 / 8.75).abs() < 1e-15);
    // The vector: magnitude by default, or one component.
    let mag = ScalarSpec {
        array: Some("vel".into()),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!(mag.name, "|vel|");
    let norms: Vec<f64> = (0..6)
        .map(|i| {
            super::fixtures::vel(i)
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    assert_eq!(
        mag.range,
        [
            norms.iter().copied().fold(f64::MAX, f64::min),
            norms.iter().copied().fold(f64::MIN, f64::max)
        ]
    );
    let y = ScalarSpec {
        array: Some("vel".into()),
        component: Some(1),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!((y.name.as_str(), y.range), ("vel[1]", [-3.0, 2.0]));
    // A fixed range, values outside it not clamped.
    let f = ScalarSpec {
        array: Some("temp".into()),
        range: Some([0.0, 2.0]),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!(f.values, [0.25, -0.625, 1.5, 1.0, 0.0, 3.75]);
    // No name: the first point array.
    assert_eq!(ScalarSpec::default().evaluate(&m).unwrap().name, "temp");
}

#[test]
fn scalar_errors_list_the_arrays() {
    let m = fixture_mesh();
    let e = ScalarSpec {
        array: Some("pressure".into()),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap_err()
    .to_string();
    assert!(e.contains("f.vtk: no array \"pressure\" (point arrays: \"temp\" (1 components), \"vel\" (3 components); cell arrays: \"mat\" (1 components))"), "{e}");
    let e = ScalarSpec {
        array: Some("mat".into()),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("\"mat\" is a cell array; add from_cells = \"average\""),
        "{e}"
    );
    let e = ScalarSpec {
        array: Some("vel".into()),
        component: Some(3),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("has 3 components, so component 3 does not exist (0 to 2)"),
        "{e}"
    );
    let e = ScalarSpec {
        array: Some("temp".into()),
        range: Some([1.0, f64::NAN]),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap_err()
    .to_string();
    assert!(e.contains("must be finite"), "{e}");
}

#[test]
fn constant_and_nan_arrays() {
    let mut m = fixture_mesh();
    m.point_arrays.push(DataArray {
        name: "c".into(),
        components: 1,
        values: vec![4.5; 6],
    });
    m.point_arrays.push(DataArray {
        name: "n".into(),
        components: 1,
        values: vec![1.0, f64::NAN, 3.0, f64::INFINITY, 2.0, 1.0],
    });
    let c = ScalarSpec {
        array: Some("c".into()),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!(
        (c.values, c.range, c.non_finite),
        (vec![0.0; 6], [4.5, 4.5], 0)
    );
    let n = ScalarSpec {
        array: Some("n".into()),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!((n.range, n.non_finite), ([1.0, 3.0], 2));
    assert_eq!((n.values[2], n.values[4]), (1.0, 0.5));
    assert!(n.values[1].is_nan() && n.values[3] == f64::INFINITY);
}

#[test]
fn cell_values_averaged_to_points_by_volume() {
    let m = fixture_mesh();
    let s = ScalarSpec {
        array: Some("mat".into()),
        from_cells: Some(FromCells::Average),
        ..ScalarSpec::default()
    }
    .evaluate(&m)
    .unwrap();
    assert_eq!(s.name, "mat (cell average)");
    // Tetrahedra 0, 1, 2 carry 10, 30, 50; point 4 is only in tetrahedron 1, point 5
    // only in 2, points 2 and 3 in all three.
    let v: Vec<f64> = m
        .tets
        .iter()
        .map(|&t| signed_volume(&m.points, t))
        .collect();
    let want: Vec<f64> = (0..6u32)
        .map(|p| {
            let around: Vec<usize> = (0..3).filter(|&t| m.tets[t].contains(&p)).collect();
            let w: f64 = around.iter().map(|&t| v[t]).sum();
            around
                .iter()
                .map(|&t| v[t] * [10.0, 30.0, 50.0][t])
                .sum::<f64>()
                / w
        })
        .collect();
    assert_eq!((want[4], want[5]), (30.0, 50.0));
    let lo = want.iter().copied().fold(f64::MAX, f64::min);
    assert_eq!(s.range, [lo, 50.0]);
    for (p, (&got, &w)) in s.values.iter().zip(&want).enumerate() {
        assert!((lo + got * (50.0 - lo) - w).abs() < 1e-12, "point {p}");
    }
}

#[test]
fn quality_of_regular_kuhn_flat_and_sliver_tetrahedra() {
    let s = 1.0 / 2f64.sqrt();
    let p = vec![
        [1.0, 0.0, -s],
        [-1.0, 0.0, -s],
        [0.0, 1.0, s],
        [0.0, -1.0, s],
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1e-14], // nearly in the plane z = 0 with 4, 5, 6
        [0.5, 0.5, 0.05],  // a sliver over 4, 5, 6 ... 8
    ];
    assert!((radius_ratio(&p, [0, 1, 2, 3]) - 1.0).abs() < 1e-12);
    let kuhn = radius_ratio(&p, [4, 5, 6, 7]);
    assert!((kuhn - 0.7174389352).abs() < 1e-9, "{kuhn}");
    assert!(is_flat(&p, [4, 5, 6, 8]));
    assert!(!is_flat(&p, [4, 5, 6, 7]));
    let sliver = radius_ratio(&p, [4, 5, 9, 6]);
    assert!(sliver < SLIVER_RADIUS_RATIO && sliver > 0.0, "{sliver}");
    let mut m = fixture_mesh();
    m.points = p;
    m.tets = vec![[0, 1, 2, 3], [4, 5, 6, 7], [4, 5, 6, 8], [4, 5, 9, 6]];
    let q = Quality::of(&m);
    assert_eq!((q.flat, q.slivers), (1, 1));
}
