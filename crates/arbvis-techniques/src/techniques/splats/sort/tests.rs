use super::*;
use arbvis_data::points::section::SplitMix64;
use arbvis_data::points::CloudParts;

fn random_cloud(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut r = SplitMix64::new(seed);
    // Anisotropic and off-centre, so no axis or sign is special.
    (0..n)
        .map(|_| {
            [
                r.range(-1.0, 0.9) as f32,
                r.range(-0.3, 0.45) as f32,
                r.range(-0.8, 0.2) as f32,
            ]
        })
        .collect()
}

/// Coordinates on a 1/64 grid: squared distances to a grid eye are exact in f32, so
/// the seed's square roots do not merge distinct keys, and ties are plentiful.
fn grid_cloud(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut r = SplitMix64::new(seed);
    (0..n)
        .map(|_| std::array::from_fn(|_| (r.next_u64() % 129) as f32 / 64.0 - 1.0))
        .collect()
}

fn random_views(seed: u64) -> Vec<View> {
    let mut r = SplitMix64::new(seed);
    let mut views = Vec::new();
    for _ in 0..4 {
        // Outside the cloud, at 2..10 from the centre.
        let d = DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0))
            .normalize_or(DVec3::Z)
            * r.range(2.0, 10.0);
        views.push(View::Eye(to_f32(d)));
        // Inside it.
        views.push(View::Eye([
            r.range(-0.5, 0.5) as f32,
            r.range(-0.2, 0.3) as f32,
            r.range(-0.6, 0.0) as f32,
        ]));
        views.push(View::Along([
            r.range(-1.0, 1.0) as f32,
            r.range(-1.0, 1.0) as f32,
            r.range(-1.0, 1.0) as f32,
        ]));
    }
    views
}

/// Equal orders, or the first difference.
fn assert_same(got: &[u32], expected: &[u32], what: &str) {
    assert_eq!(got.len(), expected.len(), "{what}: lengths");
    if let Some(i) = (0..got.len()).find(|&i| got[i] != expected[i]) {
        panic!("{what}: at {i} got {} expected {}", got[i], expected[i]);
    }
}

fn is_permutation(order: &[u32], n: usize) -> bool {
    let mut seen = vec![false; n];
    order.len() == n
        && order
            .iter()
            .all(|&i| (i as usize) < n && !std::mem::replace(&mut seen[i as usize], true))
}

/// Keys never increase along the order, and equal keys come in index order.
fn assert_back_to_front(order: &[u32], positions: &[[f32; 3]], key: impl Fn(&[f32; 3]) -> f32) {
    assert!(is_permutation(order, positions.len()));
    for w in order.windows(2) {
        let (a, b) = (
            key(&positions[w[0] as usize]),
            key(&positions[w[1] as usize]),
        );
        assert!(a > b || (a == b && w[0] < w[1]), "{w:?}: keys {a} then {b}");
    }
}

/// The f64 depth of a point (distance or depth along the direction).
fn depth64(view: View, p: &[f32; 3]) -> f64 {
    let p = DVec3::from_array(p.map(f64::from));
    match view {
        View::Eye(e) => p.distance(DVec3::from_array(e.map(f64::from))),
        View::Along(v) => p.dot(DVec3::from_array(v.map(f64::from))),
    }
}

#[test]
fn every_method_orders_back_to_front_for_random_views() {
    let positions = random_cloud(3001, 7);
    for view in random_views(11) {
        for method in SortMethod::ALL {
            let order = back_to_front(method, &positions, view);
            if method == SortMethod::Seed {
                assert_back_to_front(&order, &positions, |p| view.seed_key(p));
            } else {
                assert_back_to_front(&order, &positions, |p| view.key(p));
            }
            // Against f64 depths: never out of order by more than f32 rounding.
            let mut worst = 0f64;
            for w in order.windows(2) {
                let (a, b) = (
                    depth64(view, &positions[w[0] as usize]),
                    depth64(view, &positions[w[1] as usize]),
                );
                worst = worst.max(b - a);
            }
            assert!(worst < 1e-5, "{method:?} {view:?}: inversion {worst}");
        }
    }
}

#[test]
fn methods_agree_exactly_with_ties_in_index_order() {
    // Random clouds: keys and radix always agree.
    for seed in 1..4 {
        let positions = random_cloud(2000 + seed as usize, seed);
        for view in random_views(seed + 100) {
            let radix = back_to_front(SortMethod::Radix, &positions, view);
            assert_same(&radix, &keys_order(&positions, view), "radix vs keys");
        }
    }
    // Grid clouds: many ties, and all three agree.
    let positions = grid_cloud(5000, 3);
    let views = [
        View::Eye([0.25, -1.5, 2.0]),
        View::Eye([0.0, 0.0, 0.0]),
        View::Along([0.0, 0.0, -1.0]),
        View::Along([0.5, -0.25, 1.0]),
    ];
    for view in views {
        let keys = keys_order(&positions, view);
        let ties = keys
            .windows(2)
            .filter(|w| view.key(&positions[w[0] as usize]) == view.key(&positions[w[1] as usize]))
            .count();
        assert!(ties > 300, "{view:?}: only {ties} ties");
        assert_same(
            &back_to_front(SortMethod::Seed, &positions, view),
            &keys,
            "seed",
        );
        assert_same(
            &back_to_front(SortMethod::Radix, &positions, view),
            &keys,
            "radix",
        );
    }
}

#[test]
fn radix_parallel_path_and_digit_widths_agree() {
    let positions = random_cloud(PARALLEL_MIN * 2 + 17, 5);
    for view in [View::Eye([3.0, 2.0, -4.0]), View::Along([0.3, -1.0, 0.2])] {
        let keys = keys_order(&positions, view);
        for bits in [8, 11, 16] {
            let mut out = Vec::new();
            radix_with(
                &positions,
                view,
                &mut RadixScratch::default(),
                &mut out,
                bits,
            );
            assert_same(&out, &keys, &format!("{bits} bits, {view:?}"));
        }
    }
}

#[test]
fn radix_handles_skewed_and_narrow_keys() {
    // A dense cluster and two far outliers: nearly everything in one top bucket,
    // finished by LSD passes over the low bits.
    let mut positions: Vec<[f32; 3]> = random_cloud(PARALLEL_MIN + 5000, 6)
        .iter()
        .map(|p| p.map(|c| c * 1e-3))
        .collect();
    positions[17] = [50.0, 0.0, 0.0];
    positions[40_000] = [-50.0, 1.0, 0.0];
    // Keys a few hundred ulps apart: the top digit alone sorts them.
    let mut r = SplitMix64::new(2);
    let narrow: Vec<[f32; 3]> = (0..5000)
        .map(|_| [0.0, 0.0, 0.5 + (r.next_u64() % 300) as f32 * 2f32.powi(-24)])
        .collect();
    for (cloud, view) in [
        (&positions, View::Eye([0.0, 0.0, 0.0])),
        (&positions, View::Along([1.0, 0.0, 0.0])),
        (&narrow, View::Along([0.0, 0.0, 1.0])),
    ] {
        let keys = keys_order(cloud, view);
        for bits in [4, 11] {
            let mut out = Vec::new();
            radix_with(cloud, view, &mut RadixScratch::default(), &mut out, bits);
            assert_same(&out, &keys, &format!("{bits} bits, {view:?}"));
        }
    }
}

#[test]
fn zero_one_and_coincident_points() {
    let view = View::Eye([0.0, 0.0, 5.0]);
    for method in SortMethod::ALL {
        assert!(back_to_front(method, &[], view).is_empty());
        assert_eq!(back_to_front(method, &[[0.5, 0.25, -1.0]], view), vec![0]);
        // Coincident points tie: index order, whatever the method.
        let same = vec![[0.1f32, -0.2, 0.3]; 1000];
        let identity: Vec<u32> = (0..1000).collect();
        assert_eq!(back_to_front(method, &same, view), identity, "{method:?}");
        assert_eq!(
            back_to_front(method, &same, View::Along([1.0, 2.0, 3.0])),
            identity
        );
    }
}

#[test]
fn nan_positions_are_drawn_first_in_index_order() {
    let mut positions = random_cloud(500, 9);
    for i in [3usize, 250, 499] {
        positions[i][i % 3] = f32::NAN;
    }
    positions[100] = [f32::NAN; 3];
    for view in [View::Eye([0.2, 3.0, 1.0]), View::Along([0.0, 1.0, 0.0])] {
        let keys = keys_order(&positions, view);
        assert_eq!(&keys[..4], &[3, 100, 250, 499]);
        for method in SortMethod::ALL {
            assert_eq!(back_to_front(method, &positions, view), keys, "{method:?}");
        }
    }
    // A NaN view: every key is NaN, so all tie.
    let identity: Vec<u32> = (0..500).collect();
    for method in SortMethod::ALL {
        assert_eq!(
            back_to_front(method, &positions, View::Eye([f32::NAN; 3])),
            identity
        );
    }
}

#[test]
fn signed_zeros_tie() {
    // Depths -0 (point 0) and +0 (point 1) along x; point 2 is farther.
    let positions = [[-0.0f32, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0]];
    for method in SortMethod::ALL {
        assert_eq!(
            back_to_front(method, &positions, View::Along([1.0, 0.0, 0.0])),
            vec![2, 0, 1]
        );
    }
}

#[test]
fn view_of_camera_matches_the_camera_matrices() {
    // Unplaced, and placed as a layer of a scene (an odd scale and offset): the eye and
    // the direction are the camera's own in the layer's frame.
    let placed = arbvis_core::camera::Placement {
        scale: 0.37,
        rotation: glam::DQuat::from_euler(glam::EulerRot::XYZ, -0.6, 0.2, 1.3),
        offset: DVec3::new(0.21, -0.53, 0.11),
    };
    for placement in [Default::default(), placed] {
        let camera = Camera {
            projection: Projection::Perspective,
            rotation: glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.4).to_array(),
            zoom: 1.3,
            fov_y_deg: 40.0,
            placement,
        };
        let View::Eye(eye) = View::of_camera(&camera) else {
            panic!("perspective gives an eye");
        };
        let e = DVec3::from_array(eye.map(f64::from));
        // f32 eye coordinates of size ~10: 1e-5 relative.
        assert!(camera.view().transform_point3(e).length() < 1e-4);
        if placement == Default::default() {
            assert!((e.length() - camera.eye_distance()).abs() < 1e-5);
        }
        let ortho = Camera {
            projection: Projection::Orthographic,
            ..camera
        };
        let View::Along(v) = View::of_camera(&ortho) else {
            panic!("orthographic gives a direction");
        };
        let v = DVec3::from_array(v.map(f64::from));
        let seen = ortho.view().transform_vector3(v).normalize();
        assert!((seen - DVec3::NEG_Z).length() < 1e-6);
    }
}

#[test]
fn cache_sorts_only_when_the_view_moves() {
    let positions = random_cloud(4000, 13);
    for method in SortMethod::ALL {
        let mut cache = SortCache::new(method);
        let a = View::Eye([0.0, 1.0, 4.0]);
        let b = View::Eye([0.0, 1.0, 4.000001]);
        let first = cache.order(&positions, a).to_vec();
        assert_same(&first, &back_to_front(method, &positions, a), "first sort");
        assert_eq!(cache.order(&positions, a), &first[..]);
        assert_eq!(cache.sorts(), 1, "{method:?}: a still camera sorts nothing");
        let moved = cache.order(&positions, b).to_vec();
        assert_eq!(cache.sorts(), 2);
        assert_same(&moved, &back_to_front(method, &positions, b), "moved");
        // Back to a: the seed's structs start from b's order and still end sorted.
        assert_eq!(cache.order(&positions, a), &first[..]);
        cache.invalidate();
        cache.order(&positions, a);
        assert_eq!(cache.sorts(), 4);
        // Fewer points: a new sort, not a stale order.
        assert_eq!(cache.order(&positions[..10], a).len(), 10);
    }
}

#[test]
fn time_methods_reports_every_row() {
    let positions = random_cloud(3000, 17)
        .iter()
        .map(|p| p.map(f64::from))
        .collect();
    let cloud = PointCloud::from_parts(CloudParts {
        positions,
        ..CloudParts::default()
    })
    .unwrap();
    let rows = time_methods(&cloud, &Camera::default(), 2);
    assert_eq!(rows.len(), 8);
    assert!(rows[0].0.starts_with("seed"));
}

#[test]
fn lidar_tile_orders_agree() {
    // 110,000 lidar returns quantized to centimetres: plenty of exact ties.
    let path = arbvis_core::input::data_file("points/autzen_trim.laz");
    let cloud = arbvis_data::points::lasfile::read(&path).unwrap().cloud;
    assert_eq!(cloud.len(), 110_000);
    let positions = &cloud.positions;
    for view in [
        View::Along([0.0, 0.0, -1.0]),
        View::Along([0.6, -0.3, -0.74]),
        View::Eye([0.2, -2.5, 1.5]),
        View::Eye([0.0, 0.0, 0.0]),
    ] {
        let keys = keys_order(positions, view);
        assert_back_to_front(&keys, positions, |p| view.key(p));
        assert_same(
            &back_to_front(SortMethod::Radix, positions, view),
            &keys,
            "radix",
        );
        let seed = back_to_front(SortMethod::Seed, positions, view);
        assert_back_to_front(&seed, positions, |p| view.seed_key(p));
        if let View::Along(_) = view {
            assert_same(&seed, &keys, "seed");
        }
    }
    let down = View::Along([0.0, 0.0, -1.0]);
    let order = keys_order(positions, down);
    let ties = order
        .windows(2)
        .filter(|w| down.key(&positions[w[0] as usize]) == down.key(&positions[w[1] as usize]))
        .count();
    eprintln!("autzen: {ties} ties seen from above");
    assert!(ties > 50_000, "{ties}");
}
