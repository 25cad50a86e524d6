use super::*;
use arbvis_data::points::section::SplitMix64;
use arbvis_data::points::CloudParts;

/// Angle in degrees between two axes (sign ignored).
fn axis_angle(a: DVec3, b: DVec3) -> f64 {
    a.normalize()
        .dot(b.normalize())
        .abs()
        .min(1.0)
        .acos()
        .to_degrees()
}

fn n64(n: &[f32; 3]) -> DVec3 {
    DVec3::from_array(n.map(f64::from))
}

/// `count` points uniformly on a `size` square of the plane through `centre` with
/// normal `normal`, plus Gaussian noise of `noise` along the normal.
fn plane(
    count: usize,
    centre: DVec3,
    normal: DVec3,
    size: f64,
    noise: f64,
    seed: u64,
) -> Vec<[f32; 3]> {
    let n = normal.normalize();
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let mut r = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let g = gaussian(&mut r);
            let p = centre
                + u * r.range(-size, size) / 2.0
                + v * r.range(-size, size) / 2.0
                + n * g * noise;
            p.as_vec3().to_array()
        })
        .collect()
}

fn gaussian(r: &mut SplitMix64) -> f64 {
    let (a, b) = (r.next_f64().max(1e-300), r.next_f64());
    (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
}

fn angles(report: &NormalReport, truth: impl Fn(usize) -> DVec3) -> (f64, f64) {
    let a: Vec<f64> = report
        .normals
        .iter()
        .enumerate()
        .map(|(i, n)| axis_angle(n64(n), truth(i)))
        .collect();
    let max = a.iter().copied().fold(0.0, f64::max);
    (a.iter().sum::<f64>() / a.len() as f64, max)
}

#[test]
fn planes_in_any_orientation_give_their_normal() {
    let normals = [
        DVec3::new(0.3, -0.7, 0.2),
        DVec3::new(-0.9, 0.05, 0.4),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 1e-3, 0.0),
    ];
    for (s, normal) in normals.into_iter().enumerate() {
        let points = plane(
            2000,
            DVec3::new(0.1, -0.2, 0.05),
            normal,
            1.6,
            0.0,
            s as u64,
        );
        let report = estimate(&points, LayerIds::None, DEFAULT_K);
        let (mean, max) = angles(&report, |_| normal);
        assert!(max < 1e-3, "{normal}: mean {mean}°, max {max}°");
        assert_eq!(
            (report.collinear, report.coincident, report.too_few),
            (0, 0, 0)
        );
        for n in &report.normals {
            assert!((n64(n).length() - 1.0).abs() < 1e-6);
        }
    }
}

#[test]
fn grid_plane_with_shared_coordinates() {
    // 120 x 120 points on z = 0.25 with every x and y value shared by 120 points: the
    // tree must cope with runs of equal coordinates.
    let points: Vec<[f32; 3]> = (0..120 * 120)
        .map(|i| {
            [
                (i % 120) as f32 / 60.0 - 1.0,
                (i / 120) as f32 / 60.0 - 1.0,
                0.25,
            ]
        })
        .collect();
    let report = estimate(&points, LayerIds::None, DEFAULT_K);
    assert!(report.normals.iter().all(|n| *n == [0.0, 0.0, 1.0]));
}

#[test]
fn spheres_within_two_degrees_at_k16() {
    // Fibonacci sampling of the unit sphere (2,000 points), off-centre.
    let count = 2000;
    let centre = DVec3::new(0.05, -0.1, 0.02);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let points: Vec<[f32; 3]> = (0..count)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            (centre + DVec3::new(r * t.cos(), r * t.sin(), z) * 0.9)
                .as_vec3()
                .to_array()
        })
        .collect();
    let report = estimate(&points, LayerIds::None, 16);
    let (mean, max) = angles(&report, |i| n64(&points[i]) - centre);
    eprintln!("fibonacci sphere: mean {mean:.3}°, max {max:.3}°");
    assert!(max < 1.5 && mean < 0.6, "mean {mean}°, max {max}°");
    // Uniform random sampling: lopsided neighbourhoods, a looser bound.
    let mut r = SplitMix64::new(21);
    let points: Vec<[f32; 3]> = (0..count)
        .map(|_| {
            let d = DVec3::new(gaussian(&mut r), gaussian(&mut r), gaussian(&mut r)).normalize();
            (centre + d * 0.9).as_vec3().to_array()
        })
        .collect();
    let report = estimate(&points, LayerIds::None, 16);
    let (mean, max) = angles(&report, |i| n64(&points[i]) - centre);
    eprintln!("random sphere: mean {mean:.3}°, max {max:.3}°");
    assert!(max < 8.0 && mean < 2.0, "mean {mean}°, max {max}°");
}

#[test]
fn noise_degrades_gracefully() {
    // Noise of 1/20 of the point spacing (about 0.04) along the normal.
    let normal = DVec3::new(0.2, 0.5, -0.8);
    let points = plane(2000, DVec3::ZERO, normal, 1.8, 0.002, 5);
    let (mean, max) = angles(&estimate(&points, LayerIds::None, 16), |_| normal);
    eprintln!("noisy plane k=16: mean {mean:.3}°, max {max:.3}°");
    assert!(mean < 2.0 && max < 10.0, "mean {mean}°, max {max}°");
    // More neighbours average more noise away.
    let (mean32, _) = angles(&estimate(&points, LayerIds::None, 32), |_| normal);
    assert!(mean32 < mean, "k=32 {mean32}° vs k=16 {mean}°");
}

#[test]
fn layers_keep_their_own_normals() {
    // Two parallel planes 0.1 apart (about the neighbourhood radius) with ids 3 and 7,
    // interleaved in the file.
    let normal = DVec3::new(0.1, -0.2, 1.0);
    let a = plane(1000, DVec3::ZERO, normal, 2.0, 0.0, 1);
    let b = plane(1000, normal.normalize() * 0.1, normal, 2.0, 0.0, 2);
    let mut points = Vec::new();
    let mut ids = Vec::new();
    for (p, q) in a.iter().zip(&b) {
        points.extend([*p, *q]);
        ids.extend([3, 7]);
    }
    let per_layer = estimate(&points, LayerIds::Int(&ids), 16);
    assert_eq!(per_layer.groups, 2);
    let (_, max) = angles(&per_layer, |_| normal);
    assert!(max < 1e-3, "per layer: max {max}°");
    let pooled = estimate(&points, LayerIds::None, 16);
    assert_eq!(pooled.groups, 1);
    let (mean, max) = angles(&pooled, |_| normal);
    eprintln!("pooled layers: mean {mean:.2}°, max {max:.2}°");
    assert!(mean > 5.0 && max > 45.0, "pooled: mean {mean}°, max {max}°");
    // Real ids group by value too.
    let fids: Vec<f32> = ids.iter().map(|&i| i as f32).collect();
    assert_eq!(estimate(&points, LayerIds::Float(&fids), 16), per_layer);
}

#[test]
fn cloud_normals_use_the_layer_attribute() {
    let normal = DVec3::new(0.0, 0.3, 1.0);
    let a = plane(300, DVec3::ZERO, normal, 2.0, 0.0, 8);
    let b = plane(300, normal.normalize() * 0.1, normal, 2.0, 0.0, 9);
    let positions: Vec<[f64; 3]> = a.iter().chain(&b).map(|p| p.map(f64::from)).collect();
    let layer: Vec<i32> = (0..600).map(|i| (i >= 300) as i32).collect();
    let cloud = PointCloud::from_parts(CloudParts {
        positions,
        attributes: vec![(LAYER.to_string(), Values::Int(layer))],
        ..CloudParts::default()
    })
    .unwrap();
    assert_eq!(estimate_cloud(&cloud, 16, true).groups, 2);
    assert_eq!(estimate_cloud(&cloud, 16, false).groups, 1);
    let (_, max) = angles(&estimate_cloud(&cloud, 16, true), |_| normal);
    assert!(max < 1e-3);
}

#[test]
fn degenerate_inputs_fall_back() {
    let report = estimate(&[], LayerIds::None, 16);
    assert!(report.normals.is_empty());
    // One and two points: too few.
    for n in [1, 2] {
        let points = vec![[0.5f32, -0.25, 0.125]; n];
        let r = estimate(&points[..n], LayerIds::None, 16);
        assert_eq!((r.too_few, r.normals[0]), (n, [0.0, 0.0, 1.0]));
    }
    // Coincident points.
    let r = estimate(&vec![[0.1f32, 0.2, 0.3]; 100], LayerIds::None, 16);
    assert_eq!((r.coincident, r.normals[50]), (100, [0.0, 0.0, 1.0]));
    // Many of them (a tree of one position), and half a cloud stacked on one point.
    let r = estimate(&vec![[0.5f32, -0.5, 0.0]; 60_000], LayerIds::None, 16);
    assert_eq!(r.coincident, 60_000);
    let mut stacked = plane(20_000, DVec3::ZERO, DVec3::new(0.0, 1.0, 1.0), 2.0, 0.0, 3);
    stacked.extend(vec![[0.25f32, 0.0, 0.0]; 20_000]);
    let r = estimate(&stacked, LayerIds::None, 16);
    assert_eq!(r.coincident, 20_000);
    // Collinear points along a tilted line: the perpendicular closest to +Z.
    let dir = DVec3::new(0.6, 0.0, 0.8);
    let line: Vec<[f32; 3]> = (0..50)
        .map(|i| (dir * (i as f64 / 64.0)).as_vec3().to_array())
        .collect();
    let r = estimate(&line, LayerIds::None, 8);
    assert_eq!(r.collinear, 50);
    let expected = DVec3::new(-0.8, 0.0, 0.6);
    assert!(r
        .normals
        .iter()
        .all(|n| axis_angle(n64(n), expected) < 1e-4));
    // A vertical line: +X.
    let line: Vec<[f32; 3]> = (0..20).map(|i| [0.25, -0.5, i as f32 / 32.0]).collect();
    let r = estimate(&line, LayerIds::None, 8);
    assert!(
        r.normals.iter().all(|n| *n == [1.0, 0.0, 0.0]),
        "{:?}",
        r.normals[0]
    );
    // k = 0, 1, 2: too few; k beyond the count uses every point.
    let points = plane(40, DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), 1.0, 0.0, 4);
    for k in [0, 1, 2] {
        assert_eq!(estimate(&points, LayerIds::None, k).too_few, 40);
    }
    let (_, max) = angles(&estimate(&points, LayerIds::None, 1000), |_| {
        DVec3::new(1.0, 2.0, 3.0)
    });
    assert!(max < 1e-3);
    // Non-finite positions: too few, the others unharmed.
    let mut points = points;
    points[7] = [f32::NAN, 0.0, 0.0];
    points[9][2] = f32::INFINITY;
    let r = estimate(&points, LayerIds::None, 16);
    assert_eq!(r.too_few, 2);
    let (_, max) = angles(&r, |i| {
        if i == 7 || i == 9 {
            DVec3::Z
        } else {
            DVec3::new(1.0, 2.0, 3.0)
        }
    });
    assert!(max < 1e-3);
    // Layer ids shorter than the points: the rest form a group of their own.
    assert_eq!(estimate(&points, LayerIds::Int(&[1, 2, 3]), 16).groups, 4);
}

#[test]
fn eigen_solver_is_accurate_and_handles_repeated_values() {
    let mut r = SplitMix64::new(99);
    for _ in 0..200 {
        let m: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| r.range(-2.0, 2.0)));
        let a: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| m[i][j] + m[j][i]));
        let (values, vectors) = symmetric_eigen(a);
        assert!(values[0] <= values[1] && values[1] <= values[2]);
        for (l, v) in values.iter().zip(vectors) {
            let av = DVec3::new(
                a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
                a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
                a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z,
            );
            assert!((av - v * *l).length() < 1e-12, "{a:?}");
            assert!((v.length() - 1.0).abs() < 1e-12);
        }
    }
    let (values, _) = symmetric_eigen([[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    assert_eq!(values, [1.0, 1.0, 2.0]);
    let (values, vectors) = symmetric_eigen([[0.0; 3]; 3]);
    assert_eq!(values, [0.0; 3]);
    assert!(vectors.iter().all(|v| v.length() == 1.0));
    // Non-finite input ends without hanging.
    let (values, _) = symmetric_eigen([[f64::NAN, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    assert!(values.iter().any(|v| v.is_nan()));
}

#[test]
fn orientation_faces_the_eye() {
    let p = DVec3::new(0.5, 0.0, 0.0);
    let n = DVec3::new(-1.0, 0.0, 0.0);
    assert_eq!(orient_toward(n, p, DVec3::new(3.0, 1.0, 0.0)), DVec3::X);
    assert_eq!(orient_toward(n, p, DVec3::new(-3.0, 1.0, 0.0)), n);
    // Edge-on: kept.
    assert_eq!(orient_toward(n, p, DVec3::new(0.5, 4.0, 0.0)), n);
}

#[test]
fn bunny_normals_follow_its_surface() {
    // The Stanford bunny's vertices, against the area-weighted normals of its faces.
    let path = arbvis_core::input::data_file("points/bunny.ply");
    let ply = arbvis_data::points::ply::read(&path).unwrap();
    let cloud = arbvis_data::points::plycloud::cloud(&path, &ply).unwrap();
    assert_eq!(cloud.len(), 35_947);
    let faces = ply.element("face").and_then(|f| f.face_indices()).unwrap();
    let mut truth = vec![DVec3::ZERO; cloud.len()];
    for face in faces.iter() {
        let v: Vec<usize> = face.iter().map(|&i| i as usize).collect();
        let p = |i: usize| n64(&cloud.positions[v[i]]);
        for t in 1..v.len() - 1 {
            let n = (p(t) - p(0)).cross(p(t + 1) - p(0));
            for i in [0, t, t + 1] {
                truth[v[i]] += n;
            }
        }
    }
    let report = estimate_cloud(&cloud, DEFAULT_K, true);
    assert_eq!(
        (
            report.groups,
            report.collinear,
            report.coincident,
            report.too_few
        ),
        (1, 0, 0, 0)
    );
    let mut angles: Vec<f64> = truth
        .iter()
        .zip(&report.normals)
        .filter(|(t, _)| t.length() > 0.0)
        .map(|(t, n)| axis_angle(n64(n), *t))
        .collect();
    angles.sort_by(f64::total_cmp);
    let at = |q: f64| angles[(q * (angles.len() - 1) as f64) as usize];
    eprintln!(
        "bunny: {} vertices with faces; median {:.2}°, 90% {:.2}°, 99% {:.2}°",
        angles.len(),
        at(0.5),
        at(0.9),
        at(0.99)
    );
    assert!(angles.len() > 34_800);
    assert!(
        at(0.5) < 5.0 && at(0.9) < 15.0,
        "median {}°, 90% {}°",
        at(0.5),
        at(0.9)
    );
}
