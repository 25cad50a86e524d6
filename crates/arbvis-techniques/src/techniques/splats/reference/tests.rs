use super::*;
use crate::techniques::splats::sort::{keys_order, View};
use arbvis_data::points::section::SplitMix64;

const BG: [f64; 4] = [0.0, 0.0, 0.1, 1.0];

fn params(footprint: Footprint, point_size: f64) -> SplatParams {
    SplatParams::sized(footprint, point_size)
}

fn scene<'a>(
    positions: &'a [[f32; 3]],
    rgba: &'a [[f64; 4]],
    params: SplatParams,
    background: [f64; 4],
) -> SplatScene<'a> {
    SplatScene {
        positions,
        rgba,
        params,
        background,
    }
}

fn f32s(v: [f64; 4]) -> [f32; 4] {
    v.map(|x| x as f32)
}

/// `c` over `dst` with the seed's blend.
fn over(dst: [f64; 4], c: [f64; 3], a: f64) -> [f64; 4] {
    [
        c[0] * a + dst[0] * (1.0 - a),
        c[1] * a + dst[1] * (1.0 - a),
        c[2] * a + dst[2] * (1.0 - a),
        a + dst[3] * (1.0 - a),
    ]
}

fn non_background(image: &Image, bg: [f64; 4]) -> usize {
    image
        .data
        .chunks_exact(4)
        .filter(|p| *p != f32s(bg))
        .count()
}

#[test]
fn one_splat_by_hand() {
    // Orthographic, 9 x 9: the origin lands on the centre of pixel (4, 4).
    let rgba = [[1.0, 0.5, 0.25, 0.8]];
    let s = scene(
        &[[0.0, 0.0, 0.0]],
        &rgba,
        params(Footprint::Smoothstep, 5.0),
        BG,
    );
    let image = composite(&s, &Camera::default(), [9, 9]);
    let expect = |n_dist: f64| {
        let a = 0.8 * smoothstep(0.0, 1.0, 1.0 - n_dist);
        f32s(over(BG, [1.0, 0.5, 0.25], a))
    };
    assert_eq!(image.pixel(4, 4), f32s([0.8, 0.4, 0.22, 1.0]));
    assert_eq!(image.pixel(5, 4), expect(0.4));
    assert_eq!(image.pixel(4, 2), expect(0.8));
    assert_eq!(image.pixel(6, 5), expect(2.0 * 5f64.sqrt() / 5.0));
    // The 5 x 5 square less its 4 corners (outside the inscribed circle).
    assert_eq!(non_background(&image, BG), 21);
    assert_eq!(image.pixel(6, 6), f32s(BG));
    assert_eq!(image.pixel(7, 4), f32s(BG));
}

#[test]
fn rows_are_top_first() {
    // (0.3, 0.5) lands at window (5.85, 6.75): pixel column 5, GL row 6 = image row 2.
    let rgba = [[1.0, 1.0, 1.0, 1.0]];
    let s = scene(&[[0.3, 0.5, 0.0]], &rgba, params(Footprint::Disc, 1.0), BG);
    let image = composite(&s, &Camera::default(), [9, 9]);
    assert_eq!(non_background(&image, BG), 1);
    assert_eq!(image.pixel(5, 2), [1.0; 4]);
}

#[test]
fn two_overlapping_splats_in_both_orders() {
    // Red nearer (z = 0.5, the orthographic viewer looks down -z), blue farther.
    let positions = [[0.0, 0.0, 0.5], [0.0, 0.0, -0.5]];
    let rgba = [[1.0, 0.0, 0.0, 0.6], [0.0, 0.0, 1.0, 0.3]];
    let black = [0.0; 4];
    let s = scene(&positions, &rgba, params(Footprint::Disc, 3.0), black);
    let camera = Camera::default();
    assert_eq!(exact_order(&positions, &camera), vec![1, 0]);
    let exact = composite(&s, &camera, [9, 9]);
    let blue_then_red = over(over(black, [0.0, 0.0, 1.0], 0.3), [1.0, 0.0, 0.0], 0.6);
    assert_eq!(blue_then_red, [0.6, 0.0, 0.3 * 0.4, 0.6 + 0.3 * 0.4]);
    assert_eq!(exact.pixel(4, 4), f32s(blue_then_red));
    assert_eq!(composite_in_order(&s, &[1, 0], &camera, [9, 9]), exact);
    let wrong = composite_in_order(&s, &[0, 1], &camera, [9, 9]);
    let red_then_blue = over(over(black, [1.0, 0.0, 0.0], 0.6), [0.0, 0.0, 1.0], 0.3);
    assert_eq!(wrong.pixel(4, 4), f32s(red_then_blue));
    // Depth, not index, decides: swapping the points gives the same picture.
    let (p2, c2) = ([positions[1], positions[0]], [rgba[1], rgba[0]]);
    assert_eq!(
        composite(&scene(&p2, &c2, s.params, black), &camera, [9, 9]),
        exact
    );
    // Weighted blended with w = a: (c a², a²) summed, revealage 0.4 x 0.7.
    let oit = weighted_blended(&s, OitWeight::Alpha, &camera, [9, 9]);
    let cover = 1.0 - 0.4 * 0.7;
    let expected = [0.36 / 0.45 * cover, 0.0, 0.09 / 0.45 * cover, cover];
    let got = oit.pixel(4, 4);
    for k in 0..4 {
        assert!(
            (got[k] as f64 - expected[k]).abs() < 1e-6,
            "{got:?} vs {expected:?}"
        );
    }
    // Out-of-range indices are skipped.
    assert_eq!(
        composite_in_order(&s, &[1, 7, 0, 2], &camera, [9, 9]),
        exact
    );
}

#[test]
fn zero_points_and_empty_images() {
    let s = scene(&[], &[], SplatParams::default(), BG);
    let image = composite(&s, &Camera::default(), [7, 5]);
    assert_eq!(
        image,
        Image::from_f64_pixels(7, 5, TargetFormat::Rgba32f, vec![BG; 35])
    );
    for size in [[0, 0], [4, 0], [0, 3]] {
        let rgba = [[1.0; 4]];
        let s = scene(&[[0.0; 3]], &rgba, SplatParams::default(), BG);
        assert!(composite(&s, &Camera::default(), size).data.is_empty());
        assert!(
            weighted_blended(&s, OitWeight::Eq7, &Camera::default(), size)
                .data
                .is_empty()
        );
    }
}

#[test]
fn coincident_points_blend_in_index_order() {
    let positions = [[0.0f32, 0.0, 0.0]; 3];
    let rgba = [
        [1.0, 0.0, 0.0, 0.5],
        [0.0, 1.0, 0.0, 0.5],
        [0.0, 0.0, 1.0, 0.5],
    ];
    let s = scene(&positions, &rgba, params(Footprint::Disc, 2.0), [0.0; 4]);
    assert_eq!(exact_order(&positions, &Camera::default()), vec![0, 1, 2]);
    let image = composite(&s, &Camera::default(), [9, 9]);
    let p = image.pixel(4, 4);
    assert_eq!([p[0], p[1], p[2]], [0.125, 0.25, 0.5]);
    assert_eq!(composite(&s, &Camera::default(), [9, 9]), image);
}

fn perspective(zoom: f64) -> Camera {
    Camera {
        projection: Projection::Perspective,
        zoom,
        ..Camera::default()
    }
}

#[test]
fn points_behind_the_camera_or_before_the_near_plane_are_not_drawn() {
    let camera = perspective(1.0);
    let d = camera.eye_distance();
    let positions = [
        [0.0, 0.0, (d + 1.0) as f32],
        [0.0, 0.0, d as f32],
        [0.0, 0.0, (d - 0.5) as f32],
        [f32::NAN, 0.0, 0.0],
    ];
    let rgba = [[1.0; 4]; 4];
    let s = scene(&positions, &rgba, params(Footprint::Disc, 50.0), BG);
    let image = composite(&s, &camera, [16, 16]);
    assert_eq!(non_background(&image, BG), 0);
    let oit = weighted_blended(&s, OitWeight::Eq9, &camera, [16, 16]);
    assert_eq!(non_background(&oit, BG), 0);
}

#[test]
fn camera_inside_the_cloud() {
    // Zoom 10 puts the eye at 0.65 from the centre, inside [-1, 1]³.
    let camera = perspective(10.0);
    let d = camera.eye_distance();
    assert!(d < 1.0);
    let eye = eye_position(&camera).unwrap();
    assert!((eye - DVec3::new(0.0, 0.0, d)).length() < 1e-12);
    let front = [[0.0f32, 0.0, 0.0], [0.02, -0.01, -0.5]];
    let all = [front[0], front[1], [0.0, 0.0, 0.9], [0.3, 0.2, 0.8]];
    let rgba = [
        [0.2, 0.7, 0.4, 0.7],
        [0.9, 0.1, 0.1, 0.5],
        [1.0; 4],
        [1.0; 4],
    ];
    let p = params(Footprint::Smoothstep, 4.0);
    let image = composite(&scene(&all, &rgba, p, BG), &camera, [32, 24]);
    assert!(image.data.iter().all(|v| v.is_finite()));
    assert_eq!(
        image,
        composite(&scene(&front, &rgba[..2], p, BG), &camera, [32, 24])
    );
    assert!(non_background(&image, BG) > 0);
    // Sizes: pointSize / distance * factor.
    let p = SplatParams { factor: 2.0, ..p };
    assert!((splat_size(&p, &camera, DVec3::ZERO) - 4.0 / d * 2.0).abs() < 1e-12);
    let far = perspective(1.0);
    assert!((splat_size(&p, &far, DVec3::ZERO) - 8.0 / far.eye_distance()).abs() < 1e-12);
    // Clamped to the size range; orthographic sizes are constant.
    assert_eq!(splat_size(&p, &camera, eye), 255.0);
    assert_eq!(
        splat_size(&p, &Camera::default(), DVec3::new(0.3, 0.1, -0.9)),
        8.0
    );
    assert!(splat_size(&p, &camera, DVec3::NAN).is_nan());
}

#[test]
fn seed_footprints_as_written() {
    // Smoothstep of n_dist: transparent centre, opaque rim.
    assert_eq!(Footprint::SeedSmoothstep.alpha(0.0), 0.0);
    assert_eq!(Footprint::SeedSmoothstep.alpha(0.5), 0.5);
    assert_eq!(Footprint::SeedSmoothstep.alpha(1.0), 1.0);
    assert_eq!(Footprint::Smoothstep.alpha(0.0), 1.0);
    assert_eq!(Footprint::Smoothstep.alpha(1.0), 0.0);
    // The Gaussian peaks on the rim at 1/sqrt(2π sx).
    let g = Footprint::SeedGaussian { width: 1.0 };
    assert!((g.alpha(1.0) - 0.398_942_280_4).abs() < 1e-9);
    assert!((g.alpha(0.0) - 0.241_970_724_5).abs() < 1e-9);
    assert!((Footprint::SeedGaussian { width: 0.01 }.alpha(1.0) - 3.989_422_804).abs() < 1e-8);
    assert!(Footprint::SeedGaussian { width: 0.0 }.alpha(0.5).is_nan());
    assert!(Footprint::SeedGaussian { width: -1.0 }.alpha(0.5).is_nan());
    assert!((Footprint::Gaussian { width: 0.25 }.alpha(1.0) - (-2f64).exp()).abs() < 1e-15);
    // A peak above 1 is clamped: a flat-topped splat.
    let rgba = [[1.0, 1.0, 1.0, 1.0]];
    let s = scene(
        &[[0.0; 3]],
        &rgba,
        params(Footprint::SeedGaussian { width: 0.01 }, 5.0),
        BG,
    );
    let image = composite(&s, &Camera::default(), [9, 9]);
    // n_dist 0.8: 3.99 exp(-2) = 0.54; n_dist 0.89: 2.28, clamped to 1.
    let a = seed_gauss(0.8, 1.0, 0.01);
    assert!((a - 0.539_909_665).abs() < 1e-8);
    assert_eq!(image.pixel(6, 4), f32s(over(BG, [1.0; 3], a)));
    assert_eq!(image.pixel(6, 5), [1.0; 4]);
}

#[test]
fn gaussian_width_to_zero_stays_finite() {
    let rgba = [[1.0, 0.0, 0.0, 1.0]];
    for width in [0.0, -0.0, 1e-300, f64::MIN_POSITIVE, -2.0, f64::NAN] {
        for footprint in [
            Footprint::SeedGaussian { width },
            Footprint::Gaussian { width },
        ] {
            let s = scene(&[[0.0; 3]], &rgba, params(footprint, 5.0), BG);
            let image = composite(&s, &Camera::default(), [9, 9]);
            assert!(image.data.iter().all(|v| v.is_finite()), "{footprint:?}");
            let oit = weighted_blended(&s, OitWeight::Eq10, &Camera::default(), [9, 9]);
            assert!(oit.data.iter().all(|v| v.is_finite()), "{footprint:?}");
        }
    }
    // The precise limit keeps the centre pixel only; the seed's NaN draws nothing.
    let s = scene(
        &[[0.0; 3]],
        &rgba,
        params(Footprint::Gaussian { width: 0.0 }, 5.0),
        BG,
    );
    let image = composite(&s, &Camera::default(), [9, 9]);
    assert_eq!(non_background(&image, BG), 1);
    assert_eq!(image.pixel(4, 4), [1.0, 0.0, 0.0, 1.0]);
    let s = scene(
        &[[0.0; 3]],
        &rgba,
        params(Footprint::SeedGaussian { width: 0.0 }, 5.0),
        BG,
    );
    assert_eq!(
        non_background(&composite(&s, &Camera::default(), [9, 9]), BG),
        0
    );
}

#[test]
fn points_are_clipped_by_their_centre() {
    // Just right of the view: its 10-pixel square would reach into the image.
    let rgba = [[1.0; 4]];
    let s = scene(
        &[[1.05, 0.0, 0.0]],
        &rgba,
        params(Footprint::Disc, 10.0),
        BG,
    );
    assert_eq!(
        non_background(&composite(&s, &Camera::default(), [20, 20]), BG),
        0
    );
    let s = scene(
        &[[0.95, 0.0, 0.0]],
        &rgba,
        params(Footprint::Disc, 10.0),
        BG,
    );
    assert!(non_background(&composite(&s, &Camera::default(), [20, 20]), BG) > 0);
}

fn random_splats(n: usize, seed: u64, one_colour: bool) -> (Vec<[f32; 3]>, Vec<[f64; 4]>) {
    let mut r = SplitMix64::new(seed);
    let positions = (0..n)
        .map(|_| {
            [
                r.range(-0.9, 0.9) as f32,
                r.range(-0.6, 0.7) as f32,
                r.range(-1.0, 1.0) as f32,
            ]
        })
        .collect();
    let rgba = (0..n)
        .map(|_| {
            if one_colour {
                [0.9, 0.6, 0.2, r.range(0.2, 0.9)]
            } else {
                [r.next_f64(), r.next_f64(), r.next_f64(), r.range(0.2, 0.9)]
            }
        })
        .collect();
    (positions, rgba)
}

#[test]
fn weighted_blended_against_exact_order() {
    let (positions, rgba) = random_splats(400, 3, false);
    let camera = Camera {
        rotation: glam::DQuat::from_euler(glam::EulerRot::YXZ, 0.6, -0.3, 0.0).to_array(),
        ..perspective(1.4)
    };
    let s = scene(&positions, &rgba, params(Footprint::Smoothstep, 60.0), BG);
    let exact = composite(&s, &camera, [48, 32]);
    let oit = weighted_blended(&s, OitWeight::Eq7, &camera, [48, 32]);
    let e = rmse_rgb(&exact, &oit).unwrap();
    eprintln!("OIT eq. 7 vs exact order: RMSE {e:.4}");
    assert!(e > 1e-3 && e < 0.3, "{e}");
    assert_eq!(rmse_rgb(&exact, &exact), Some(0.0));
    assert_eq!(rmse_rgb(&exact, &composite(&s, &camera, [48, 33])), None);
    // The wrong order is worse than no order at all.
    let mut reversed = exact_order(&positions, &camera);
    reversed.reverse();
    let wrong = composite_in_order(&s, &reversed, &camera, [48, 32]);
    assert!(rmse_rgb(&exact, &wrong).unwrap() > e);
    // Order-independent: a permutation of the points gives the same image.
    let perm: Vec<usize> = (0..positions.len()).rev().collect();
    let p2: Vec<[f32; 3]> = perm.iter().map(|&i| positions[i]).collect();
    let c2: Vec<[f64; 4]> = perm.iter().map(|&i| rgba[i]).collect();
    let oit2 = weighted_blended(
        &scene(&p2, &c2, s.params, BG),
        OitWeight::Eq7,
        &camera,
        [48, 32],
    );
    assert!(rmse_rgb(&oit, &oit2).unwrap() < 1e-7);
    // One colour: order does not matter, both give that colour over the background.
    let (positions, rgba) = random_splats(300, 4, true);
    let s = scene(
        &positions,
        &rgba,
        params(Footprint::SeedGaussian { width: 0.3 }, 40.0),
        BG,
    );
    for weight in [OitWeight::Alpha, OitWeight::Eq8, OitWeight::Eq10] {
        let oit = weighted_blended(&s, weight, &camera, [40, 40]);
        assert!(rmse_rgb(&composite(&s, &camera, [40, 40]), &oit).unwrap() < 1e-6);
    }
}

#[test]
fn exact_order_matches_the_sort_module_where_both_are_exact() {
    // A 1/64 grid seen straight down -z: f32 and f64 depths agree exactly.
    let mut r = SplitMix64::new(8);
    let positions: Vec<[f32; 3]> = (0..3000)
        .map(|_| std::array::from_fn(|_| (r.next_u64() % 129) as f32 / 64.0 - 1.0))
        .collect();
    let camera = Camera::default();
    assert_eq!(
        exact_order(&positions, &camera),
        keys_order(&positions, View::of_camera(&camera))
    );
}

#[test]
fn oit_weights() {
    assert_eq!(OitWeight::Alpha.weight(0.5, 100.0, 0.3), 0.5);
    // Eq. 7 at z = 5: 10 / (1e-5 + 1 + (1/40)^6).
    let w = OitWeight::Eq7.weight(1.0, 5.0, 0.0);
    assert!((w - 10.0 / (1.0 + 1e-5 + 0.025f64.powi(6))).abs() < 1e-12);
    // Clamped to [1e-2, 3e3].
    assert_eq!(OitWeight::Eq7.weight(1.0, 0.0, 0.0), 3e3);
    assert_eq!(OitWeight::Eq9.weight(1.0, 1e4, 0.0), 1e-2);
    assert_eq!(OitWeight::Eq10.weight(0.5, 0.0, 1.0), 0.5e-2);
    assert!((OitWeight::Eq10.weight(1.0, 0.0, 0.5) - 375.0).abs() < 1e-12);
    assert!(
        (OitWeight::Eq8.weight(1.0, 10.0, 0.0) - 10.0 / (1.0 + 1e-5 + 0.05f64.powi(6))).abs()
            < 1e-12
    );
}

#[test]
fn composite_draws_the_f32_keys_order_ties_by_index() {
    // Orthographic along -z (the key is -z, larger is farther): points 0 and 1 have
    // equal keys (same z, nearer than point 2), so the lower index is drawn first.
    let camera = Camera::default();
    let positions = [[0.0, 0.0, 0.3], [0.001, 0.0, 0.3], [0.0, 0.0, 0.2]];
    let rgba = [
        [1.0, 0.0, 0.0, 0.7],
        [0.0, 1.0, 0.0, 0.7],
        [0.0, 0.0, 1.0, 0.2],
    ];
    let s = scene(&positions, &rgba, params(Footprint::Disc, 5.0), BG);
    let order = key_order(&positions, &camera);
    assert_eq!(order, vec![2, 0, 1]);
    assert_eq!(order, keys_order(&positions, View::of_camera(&camera)));
    assert_eq!(
        composite(&s, &camera, [9, 9]),
        composite_in_order(&s, &order, &camera, [9, 9])
    );
    // A rotated view and a pair a few ulps apart that the f32 key orders otherwise than
    // their f64 depths: composite follows the key, not the f64 order.
    let camera = Camera {
        rotation: [0.31, -0.22, 0.12, 0.917],
        ..Camera::default()
    };
    let mut rng = SplitMix64::new(3);
    let found = (0..10_000).find_map(|_| {
        let p: [f32; 3] = [0, 1, 2].map(|_| rng.range(-0.5, 0.5) as f32);
        let q = p
            .map(|v| f32::from_bits((v.to_bits() as i32 + (rng.next_u64() % 7) as i32 - 3) as u32));
        let pair = [p, q];
        (key_order(&pair, &camera) != exact_order(&pair, &camera)).then_some(pair)
    });
    let pair = found.expect("a pair the f32 key misorders");
    let rgba = [[1.0, 0.0, 0.0, 0.9], [0.0, 0.0, 1.0, 0.9]];
    let s = scene(&pair, &rgba, params(Footprint::Disc, 5.0), BG);
    let by_key = composite_in_order(&s, &key_order(&pair, &camera), &camera, [9, 9]);
    let by_depth = composite_in_order(&s, &exact_order(&pair, &camera), &camera, [9, 9]);
    assert_eq!(composite(&s, &camera, [9, 9]), by_key);
    assert!(by_key.compare(&by_depth, 0.0).unwrap().max_abs > 0.5);
}

#[test]
fn rim_allowance_marks_pixel_centres_near_rims() {
    // Orthographic, 9 x 9: the origin on the centre of pixel (4, 4); a 4-pixel splat's
    // rim (radius 2) passes through the centres of pixels (2, 4), (6, 4), (4, 2) and
    // (4, 6) and no other (the nearest others are sqrt(5) - 2 = 0.24 px off it).
    let rgba = [[1.0, 1.0, 1.0, 0.5]];
    let footprint = Footprint::Gaussian { width: 0.35 };
    let s = scene(&[[0.0; 3]], &rgba, params(footprint, 4.0), BG);
    let allowance = rim_allowance(&s, &Camera::default(), [9, 9], 1e-3);
    let rim = 0.5 * (-1.0f64 / 0.7).exp();
    let marked: Vec<(usize, usize)> = (0..81)
        .filter(|&k| allowance[k] > 0.0)
        .map(|k| (k % 9, k / 9))
        .collect();
    assert_eq!(marked, vec![(4, 2), (2, 4), (6, 4), (4, 6)]);
    assert!(marked.iter().all(|&(i, j)| allowance[j * 9 + i] == rim));
}
