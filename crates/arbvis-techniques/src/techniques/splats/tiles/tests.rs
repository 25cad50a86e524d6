use super::*;
use crate::techniques::splats::reference::{composite, exact_order, Footprint, SplatScene};
use crate::techniques::splats::sort::View;
use arbvis_core::camera::Projection;
use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;
use arbvis_data::points::section::SplitMix64;

/// Odd sizes: tiles do not divide them.
const SIZE: [u32; 2] = [37, 23];
const BG: [f64; 4] = [0.1, 0.2, 0.05, 1.0];

/// `n` points in the unit cube around the origin, random colours and alphas.
fn random_cloud(n: usize, seed: u64) -> (Vec<[f32; 3]>, Vec<[f64; 4]>) {
    let mut rng = SplitMix64::new(seed);
    let positions = (0..n)
        .map(|_| [0, 1, 2].map(|_| rng.range(-0.5, 0.5) as f32))
        .collect();
    let rgba = (0..n)
        .map(|_| [0, 1, 2, 3].map(|_| rng.next_f64()))
        .collect();
    (positions, rgba)
}

fn camera(projection: Projection) -> Camera {
    Camera {
        projection,
        rotation: [0.31, -0.22, 0.12, 0.917],
        zoom: 1.3,
        ..Camera::default()
    }
}

fn params(footprint: Footprint, point_size: f64) -> SplatParams {
    SplatParams::sized(footprint, point_size)
}

fn all(positions: &[[f32; 3]]) -> SpatialPoints {
    spatial_order(positions, &vec![true; positions.len()])
}

fn lists_of(positions: &[[f32; 3]], camera: &Camera, params: &SplatParams, tile: u32) -> TileLists {
    let placed = place_splats(&all(positions), camera, SIZE, tile, params);
    bin(&placed, DEFAULT_MAX_ENTRIES, true).unwrap()
}

/// Whether the pixel centre `(i + 0.5, j + 0.5)` is in the splat's half-open square and
/// its inscribed circle (the reference's rule, on the f32 position the program gets).
fn covers(s: &[u32; 4], i: u32, j: u32) -> Option<f64> {
    let [x, y, size] = [s[0], s[1], s[2]].map(|b| f32::from_bits(b) as f64);
    let (dx, dy) = (i as f64 + 0.5 - x, j as f64 + 0.5 - y);
    let h = size / 2.0;
    let inside = -h <= dx && dx < h && -h <= dy && dy < h;
    let n_dist = (dx * dx + dy * dy).sqrt() / h;
    (inside && n_dist <= 1.0).then_some(n_dist)
}

/// What tiles.frag computes, in f64 and without its early stop: each pixel composites
/// its tile's list from the end (front to back), then goes over the background.
fn gather(lists: &TileLists, rgba: &[[f64; 4]], footprint: Footprint) -> Image {
    let mut pixels = Vec::new();
    for j in (0..SIZE[1]).rev() {
        for i in 0..SIZE[0] {
            let (mut c, mut t) = ([0.0f64; 3], 1.0f64);
            for e in lists.list(i / lists.tile, j / lists.tile).iter().rev() {
                let Some(n_dist) = covers(e, i, j) else {
                    continue;
                };
                let p = rgba[e[3] as usize];
                let a = (p[3] * footprint.alpha(n_dist)).clamp(0.0, 1.0);
                for k in 0..3 {
                    c[k] += t * a * p[k].clamp(0.0, 1.0);
                }
                t *= 1.0 - a;
            }
            pixels.push([
                c[0] + t * BG[0],
                c[1] + t * BG[1],
                c[2] + t * BG[2],
                1.0 - t + t * BG[3],
            ]);
        }
    }
    Image::from_f64_pixels(SIZE[0], SIZE[1], TargetFormat::Rgba32f, pixels)
}

#[test]
fn every_covering_splat_is_listed_in_its_pixels_tile_back_to_front() {
    let (positions, _) = random_cloud(400, 11);
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let cam = camera(projection);
        // 5 pixels (orthographic); 10 / distance, about 2 to 4 pixels (perspective).
        let size = if projection == Projection::Orthographic {
            5.0
        } else {
            10.0
        };
        let p = params(Footprint::Disc, size);
        // The rank of each point in the exact back-to-front order.
        let order = exact_order(&positions, &cam);
        let mut rank = vec![0; positions.len()];
        for (r, &i) in order.iter().enumerate() {
            rank[i as usize] = r;
        }
        let view = View::of_camera(&cam);
        for tile in [1, 4, 5, 16, 64] {
            let placed = place_splats(&all(&positions), &cam, SIZE, tile, &p);
            let splats: Vec<ScreenSplat> = placed.splats().copied().collect();
            assert!(splats.len() > 300, "{} of 400 drawn", splats.len());
            let lists = bin(&placed, DEFAULT_MAX_ENTRIES, true).unwrap();
            assert_eq!(lists.tiles, placed.tiles());
            assert_eq!(
                lists.tiles,
                [SIZE[0].div_ceil(tile), SIZE[1].div_ceil(tile)]
            );
            assert_eq!(*lists.offsets.last().unwrap() as usize, lists.entries.len());
            let mut touched = 0;
            for j in 0..SIZE[1] {
                for i in 0..SIZE[0] {
                    let list = lists.list(i / tile, j / tile);
                    let mut brute: Vec<[u32; 4]> = splats
                        .iter()
                        .map(ScreenSplat::entry)
                        .filter(|e| covers(e, i, j).is_some())
                        .collect();
                    brute.sort_by_key(|e| rank[e[3] as usize]);
                    let listed: Vec<[u32; 4]> = list
                        .iter()
                        .filter(|e| covers(e, i, j).is_some())
                        .copied()
                        .collect();
                    // Back to front in the f32 keys; the f64 exact order agrees here
                    // (no two of these random points are within f32 rounding in depth).
                    assert_eq!(listed, brute, "pixel ({i}, {j}), tile {tile}");
                    touched += brute.len();
                }
            }
            assert!(touched > 1000, "{touched} fragments");
            // Every list is back to front by the f32 key, ties by index.
            for l in lists.offsets.windows(2) {
                let keys: Vec<(f32, u32)> = lists.entries[l[0] as usize..l[1] as usize]
                    .iter()
                    .map(|e| (view.key(&positions[e[3] as usize]), e[3]))
                    .collect();
                assert!(
                    keys.windows(2)
                        .all(|k| k[0].0 > k[1].0 || (k[0].0 == k[1].0 && k[0].1 < k[1].1)),
                    "{keys:?}"
                );
            }
        }
    }
}

#[test]
fn file_order_lists_and_ties_keep_index_order() {
    // Four coincident points (equal keys) and one nearer: back to front is the ties in
    // index order, then the nearer one; file order is index order.
    let positions = [[0.0; 3], [0.0; 3], [0.0, 0.0, 0.3], [0.0; 3], [0.0; 3]];
    let cam = Camera::default();
    let p = params(Footprint::Disc, 3.0);
    let placed = place_splats(&all(&positions), &cam, SIZE, 4, &p);
    let points = |ordered| -> Vec<u32> {
        let lists = bin(&placed, DEFAULT_MAX_ENTRIES, ordered).unwrap();
        lists.list(18 / 4, 11 / 4).iter().map(|e| e[3]).collect()
    };
    assert_eq!(exact_order(&positions, &cam), vec![0, 1, 3, 4, 2]);
    assert_eq!(points(true), vec![0, 1, 3, 4, 2]);
    assert_eq!(points(false), vec![0, 1, 2, 3, 4]);
}

#[test]
fn gathering_the_lists_equals_the_f64_reference() {
    let (positions, rgba) = random_cloud(600, 5);
    for (footprint, size) in [
        (Footprint::Smoothstep, 7.0),
        (Footprint::Gaussian { width: 0.15 }, 9.0),
        (Footprint::Gaussian { width: 0.0 }, 5.0),
    ] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let cam = camera(projection);
            let p = params(footprint, size);
            let lists = lists_of(&positions, &cam, &p, 4);
            let scene = SplatScene {
                positions: &positions,
                rgba: &rgba,
                params: p,
                background: BG,
            };
            let reference = composite(&scene, &cam, SIZE);
            let d = gather(&lists, &rgba, footprint)
                .compare(&reference, 0.0)
                .unwrap();
            // The lists carry window positions and sizes in f32 (relative error 6e-8 of
            // values up to 37 pixels): n_dist moves by ~1e-6, alpha by less; a pixel
            // centre exactly on a rim could flip, which these random points do not hit.
            assert!(d.max_abs < 1e-5, "{footprint:?} {projection:?}: {d:?}");
        }
    }
}

#[test]
fn lists_are_bounded_and_empty_inputs_give_empty_lists() {
    let (positions, _) = random_cloud(50, 3);
    let cam = camera(Projection::Orthographic);
    let big = params(Footprint::Disc, 200.0);
    let placed = place_splats(&all(&positions), &cam, SIZE, 4, &big);
    // Every splat covers the whole 37 x 23 image: 10 x 6 tiles of 4 each.
    let needed = placed.splats().count() * 60;
    assert!(needed > 0);
    let err = bin(&placed, needed - 1, true).unwrap_err();
    assert_eq!(err, TooManyEntries(needed as u64));
    assert_eq!(bin(&placed, needed, true).unwrap().entries.len(), needed);
    // No points, nothing visible, empty images.
    let none = place_splats(&all(&[]), &cam, SIZE, 4, &big);
    let lists = bin(&none, 10, true).unwrap();
    assert!(lists.entries.is_empty() && lists.offsets.iter().all(|&o| o == 0));
    let hidden = spatial_order(&positions, &vec![false; positions.len()]);
    assert!(hidden.positions.is_empty() && hidden.index.is_empty());
    // Points at NaN or infinity are ordered (anywhere) and never placed.
    let mut odd = positions.clone();
    odd[0] = [f32::NAN, 0.0, 0.0];
    odd[1] = [f32::INFINITY, 0.0, 0.0];
    odd[2] = [0.0, f32::NEG_INFINITY, f32::NAN];
    let spatial = all(&odd);
    assert_eq!(spatial.index.len(), odd.len());
    let small = params(Footprint::Disc, 3.0);
    let placed = place_splats(&spatial, &cam, SIZE, 4, &small);
    assert!(placed
        .splats()
        .all(|s| s.point > 2 && s.x.is_finite() && s.y.is_finite()));
    assert!(placed.splats().count() > 40);
    assert!(bin(&placed, DEFAULT_MAX_ENTRIES, true).is_ok());
    for size in [[0, 0], [0, 5], [9, 0]] {
        let placed = place_splats(&all(&positions), &cam, size, 4, &big);
        let lists = bin(&placed, 10, true).unwrap();
        assert!(lists.entries.is_empty(), "{size:?}");
        assert_eq!(
            lists.offsets.len(),
            lists.tiles[0] as usize * lists.tiles[1] as usize + 1
        );
    }
}

#[test]
fn occupied_blocks_cover_every_listed_tile_and_skip_empty_ones() {
    // A sparse cloud: 30 small splats on the odd-sized image.
    let (positions, _) = random_cloud(30, 17);
    let cam = camera(Projection::Orthographic);
    for (tile, block) in [(1, 1), (2, 3), (4, 2), (5, 2)] {
        let lists = lists_of(&positions, &cam, &params(Footprint::Disc, 2.0), tile);
        let rects = lists.occupied(block);
        let inside = |x: u32, y: u32| {
            rects
                .iter()
                .filter(|r| r[0] <= x && x < r[2] && r[1] <= y && y < r[3])
                .count()
        };
        let mut covered = 0;
        for y in 0..SIZE[1] {
            for x in 0..SIZE[0] {
                let n = inside(x, y);
                assert!(n <= 1, "pixel ({x}, {y}) in {n} rectangles");
                covered += n;
                if !lists.list(x / tile, y / tile).is_empty() {
                    assert_eq!(n, 1, "tile {tile} block {block}: pixel ({x}, {y}) left out");
                }
            }
        }
        // Every rectangle holds a listed tile; sparse splats leave most pixels out.
        for r in &rects {
            assert!(r[0] < r[2] && r[1] < r[3] && r[2] <= SIZE[0] && r[3] <= SIZE[1]);
            let listed = (r[1]..r[3])
                .any(|y| (r[0]..r[2]).any(|x| !lists.list(x / tile, y / tile).is_empty()));
            assert!(listed, "{r:?} holds no splat");
        }
        assert!(
            covered < (SIZE[0] * SIZE[1]) as usize,
            "tile {tile} block {block}"
        );
    }
    // Nothing listed: no rectangles.
    let none = bin(
        &place_splats(&all(&[]), &cam, SIZE, 2, &params(Footprint::Disc, 2.0)),
        10,
        true,
    );
    assert!(none.unwrap().occupied(4).is_empty());
}
