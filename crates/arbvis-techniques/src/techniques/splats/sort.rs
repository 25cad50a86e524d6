//! Back-to-front order of the splats: every method returns the draw order, a `Vec<u32>`
//! of point indices, farthest first, for a [`View`] (an eye position in perspective, a
//! viewing direction in orthographic).
//!
//! # Depth keys
//!
//! All arithmetic is f32 on the cloud's f32 positions, as the seed's (and the GPU's):
//! - perspective ([`View::Eye`]): the squared distance `(p - e)·(p - e)` ([`SortMethod::Keys`],
//!   [`SortMethod::Radix`]); the seed's comparator takes its square root, as
//!   `glm::distance` did. The square root is monotonic, so the orders agree except
//!   where two distinct squared distances round to the same distance, which the seed
//!   then treats as a tie;
//! - orthographic ([`View::Along`]): `p·v` with `v` pointing from the viewer into the
//!   scene (larger is farther).
//!
//! A key is made canonical before it is compared: NaN (a NaN position, or an eye at
//! infinity) becomes +∞, so such points are drawn **first**, before every finite point,
//! in index order among themselves; -0 becomes +0 so the two zeros tie. This also keeps
//! every comparator a total order (the seed's `distanceP1 > distanceP2` is not one with
//! NaN, which is undefined behaviour for `std::sort` and a panic risk for Rust's sorts).
//!
//! # Ties
//!
//! Every method is **stable**: points with equal keys keep their index order (the lower
//! index is drawn first). [`SortMethod::Seed`] relies on `sort_by` being stable (C++'s
//! `std::sort` was not, so the seed's tie order was unspecified), [`SortMethod::Keys`]
//! on comparing the index after the key, [`SortMethod::Radix`] on its scatter being
//! stable over pairs laid out in index order (and on pairs being unique where it uses
//! a comparison sort). So all three give identical orders whenever their keys agree
//! (always for Keys and Radix; for Seed, except for the square-root rounding above).
//!
//! # The methods
//!
//! - [`SortMethod::Seed`], the baseline: [`SeedPoint`] structs holding the position and
//!   every attribute the seed's struct held (14 floats; an index is added so the order
//!   can be reported), sorted in place with a comparator computing both distances at
//!   every comparison. In a [`SortCache`] the structs persist between frames and each
//!   sort starts from the previous frame's order, as the seed's vector did.
//! - [`SortMethod::Keys`]: one key per point computed in parallel, then a parallel
//!   sort of (key, index) pairs (rayon's `par_sort_unstable_by`, ties by index).
//! - [`SortMethod::Radix`] (in `sort/radix.rs`): keys mapped to u32 so that integer
//!   order is the float order (flip all bits of negatives, the sign bit of positives),
//!   reversed for farthest first, offset by the smallest key so only the bits that vary
//!   are sorted, packed with the index into u64. One most-significant-digit pass on the
//!   top [`RADIX_BITS`] bits, split into one chunk per thread: per-chunk histograms in
//!   parallel, then each chunk scatters into its own disjoint ranges of the output
//!   (split with `split_at_mut`, no `unsafe`). The 2048 buckets are then independent
//!   and small enough for the cache: each is finished by LSD passes of up to 8 bits
//!   into a per-task buffer, the last pass writing indices straight into the order,
//!   buckets in parallel. Small inputs run on one thread. [`RadixScratch`] keeps the
//!   buffers between frames (fresh pages were a noticeable share of the sort). Three
//!   full LSD passes of 11 bits over the whole array were memory-bound; this layout does
//!   about half the memory traffic, and sorted faster (measured: docs/benchmarks.md,
//!   "Figures behind the splats' settings").
//!
//! [`SortCache`] returns the previous order untouched when the view did not change (same
//! bits) and the point count is the same; call [`SortCache::invalidate`] when the
//! positions change.
//!
//! Orders are u32 indices, as a GL index buffer holds: slices of more than `u32::MAX`
//! points have no such order and get an empty one (point readers stop at
//! [`arbvis_data::points::MAX_POINTS`], far below).

use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;

use arbvis_core::camera::{Camera, Projection};
use arbvis_data::points::{
    PointCloud, Values, AMPLITUDE, FACIES, FAULT, JOINT_DIP, LAYER, POROSITY,
};

mod radix;
pub use radix::{radix_order_into, RadixScratch, RADIX_BITS};
#[cfg(test)]
use radix::{radix_with, PARALLEL_MIN};

/// Where the splats are seen from, in the cloud's coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum View {
    /// Perspective: the eye position; farther from it is drawn first.
    Eye([f32; 3]),
    /// Orthographic: the viewing direction (from the viewer into the scene); larger
    /// `p·v` is drawn first. Need not be normalized.
    Along([f32; 3]),
}

impl View {
    /// The view of `camera` in the cloud's frame: its eye ([`Camera::eye`]) in
    /// perspective, its direction `R⁻¹ (0, 0, -1)` in orthographic (`R` the camera's
    /// rotation).
    pub fn of_camera(camera: &Camera) -> View {
        match camera.projection {
            Projection::Perspective => View::Eye(to_f32(camera.eye())),
            Projection::Orthographic => View::Along(to_f32(-camera.toward_viewer())),
        }
    }

    /// The bits of the view, for [`SortCache`]'s "did it move" test.
    fn bits(&self) -> (bool, [u32; 3]) {
        match self {
            View::Eye(e) => (true, e.map(f32::to_bits)),
            View::Along(v) => (false, v.map(f32::to_bits)),
        }
    }

    /// The canonical depth key of `p` (squared distance or `p·v`; larger is farther).
    #[inline]
    pub fn key(&self, p: &[f32; 3]) -> f32 {
        canonical(match self {
            View::Eye(e) => squared_distance(p, e),
            View::Along(v) => p[0] * v[0] + p[1] * v[1] + p[2] * v[2],
        })
    }

    /// The seed's comparator value: `glm::distance(p, eye)` (the square root of
    /// [`View::key`]), or `p·v` in orthographic.
    #[inline]
    pub fn seed_key(&self, p: &[f32; 3]) -> f32 {
        canonical(match self {
            View::Eye(e) => squared_distance(p, e).sqrt(),
            View::Along(v) => p[0] * v[0] + p[1] * v[1] + p[2] * v[2],
        })
    }
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

#[inline]
fn squared_distance(p: &[f32; 3], e: &[f32; 3]) -> f32 {
    let d = [p[0] - e[0], p[1] - e[1], p[2] - e[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// NaN → +∞ (drawn first), -0 → +0.
#[inline]
fn canonical(k: f32) -> f32 {
    if k.is_nan() {
        f32::INFINITY
    } else {
        k + 0.0
    }
}

/// The sorting methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SortMethod {
    /// The seed's baseline: structs sorted with a distance comparator.
    Seed,
    /// One key per point, a parallel sort of (key, index) pairs.
    Keys,
    /// A parallel radix sort of (key bits, index) pairs.
    Radix,
}

impl SortMethod {
    /// All methods, baseline first.
    pub const ALL: [SortMethod; 3] = [SortMethod::Seed, SortMethod::Keys, SortMethod::Radix];

    /// Its name in scenes and reports.
    pub fn name(self) -> &'static str {
        match self {
            SortMethod::Seed => "seed",
            SortMethod::Keys => "keys",
            SortMethod::Radix => "radix",
        }
    }
}

/// The back-to-front order of `positions` seen from `view` with `method` (fresh buffers;
/// [`SortCache`] reuses them).
pub fn back_to_front(method: SortMethod, positions: &[[f32; 3]], view: View) -> Vec<u32> {
    match method {
        SortMethod::Seed => seed_order(&mut SeedPoint::from_positions(positions), view),
        SortMethod::Keys => keys_order(positions, view),
        SortMethod::Radix => {
            let mut out = Vec::new();
            radix_order_into(positions, view, &mut RadixScratch::default(), &mut out);
            out
        }
    }
}

fn too_many(n: usize) -> bool {
    u32::try_from(n).is_err()
}

/// One point as the seed's `Cloud` held it: 14 floats (ids as ints), plus the index the
/// seed did not need (it re-uploaded the sorted structs; here the order is reported).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SeedPoint {
    /// Position (the only field the comparator reads).
    pub position: [f32; 3],
    /// Facies colour, 0..1.
    pub colour: [f32; 3],
    /// Layer id.
    pub layer: i32,
    /// Fault id (negative: not on a fault).
    pub fault: i32,
    /// Porosity.
    pub porosity: f32,
    /// Seismic amplitude.
    pub amplitude: f32,
    /// Joint dip.
    pub joint_dip: f32,
    /// Normal.
    pub normal: [f32; 3],
    /// Index of the point in the cloud.
    pub index: u32,
}

impl SeedPoint {
    /// Structs of positions only (other fields zero: the size, and so the sort's cost,
    /// is the same).
    pub fn from_positions(positions: &[[f32; 3]]) -> Vec<SeedPoint> {
        if too_many(positions.len()) {
            return Vec::new();
        }
        positions
            .iter()
            .enumerate()
            .map(|(i, &position)| SeedPoint {
                position,
                index: i as u32,
                ..SeedPoint::default()
            })
            .collect()
    }

    /// Structs of a cloud with the seed's attributes (missing ones zero; facies colours
    /// from [`arbvis_data::points::section::facies_colour`]; the cloud's normals if it has them).
    pub fn from_cloud(cloud: &PointCloud) -> Vec<SeedPoint> {
        let mut points = SeedPoint::from_positions(&cloud.positions);
        let int = |name: &str, i: usize| cloud.ints(name).and_then(|v| v.get(i).copied());
        let float = |name: &str, i: usize| match cloud.attribute(name).map(|a| &a.values) {
            Some(Values::Float(v)) => v.get(i).copied(),
            Some(Values::Int(v)) => v.get(i).map(|&x| x as f32),
            None => None,
        };
        for (i, p) in points.iter_mut().enumerate() {
            if let Some(f) = int(FACIES, i) {
                p.colour = arbvis_data::points::section::facies_colour(f).map(|c| c as f32 / 255.0);
            }
            p.layer = int(LAYER, i).unwrap_or(0);
            p.fault = int(FAULT, i).unwrap_or(-1);
            p.porosity = float(POROSITY, i).unwrap_or(0.0);
            p.amplitude = float(AMPLITUDE, i).unwrap_or(0.0);
            p.joint_dip = float(JOINT_DIP, i).unwrap_or(0.0);
            if let Some(n) = cloud.normals.as_ref().and_then(|n| n.get(i)) {
                p.normal = *n;
            }
        }
        points
    }
}

/// The seed's sort: `points` sorted in place, farthest first, by a comparator that
/// computes both distances at every comparison; returns their indices in the new order.
pub fn seed_order(points: &mut [SeedPoint], view: View) -> Vec<u32> {
    points.sort_by(|a, b| {
        view.seed_key(&b.position)
            .total_cmp(&view.seed_key(&a.position))
    });
    points.iter().map(|p| p.index).collect()
}

/// Keys computed once (in parallel), then a parallel sort of (key, index) pairs by key,
/// then index.
pub fn keys_order(positions: &[[f32; 3]], view: View) -> Vec<u32> {
    if too_many(positions.len()) {
        return Vec::new();
    }
    let mut pairs: Vec<(f32, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| (view.key(p), i as u32))
        .collect();
    // Farthest first, ties by index: a total order on unique pairs, so the unstable
    // (faster) sort gives the one stable result.
    pairs.par_sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    pairs.into_par_iter().map(|(_, i)| i).collect()
}

/// A sorter that keeps its buffers (and, for the seed's method, its structs) between
/// frames and does nothing when the view did not move.
#[derive(Debug, Clone)]
pub struct SortCache {
    method: SortMethod,
    last: Option<((bool, [u32; 3]), usize)>,
    order: Vec<u32>,
    scratch: RadixScratch,
    seed_points: Vec<SeedPoint>,
    sorts: u64,
}

impl SortCache {
    /// An empty cache for `method`.
    pub fn new(method: SortMethod) -> SortCache {
        SortCache {
            method,
            last: None,
            order: Vec::new(),
            scratch: RadixScratch::default(),
            seed_points: Vec::new(),
            sorts: 0,
        }
    }

    /// The method.
    pub fn method(&self) -> SortMethod {
        self.method
    }

    /// The order for `view`: the previous one untouched when `view` has the same bits
    /// and `positions` the same length as last time, else a new sort.
    pub fn order(&mut self, positions: &[[f32; 3]], view: View) -> &[u32] {
        let key = (view.bits(), positions.len());
        if self.last != Some(key) {
            match self.method {
                SortMethod::Seed => {
                    if self.seed_points.len() != positions.len() {
                        self.seed_points = SeedPoint::from_positions(positions);
                    }
                    self.order = seed_order(&mut self.seed_points, view);
                }
                SortMethod::Keys => self.order = keys_order(positions, view),
                SortMethod::Radix => {
                    radix_order_into(positions, view, &mut self.scratch, &mut self.order)
                }
            }
            self.last = Some(key);
            self.sorts += 1;
        }
        &self.order
    }

    /// Forget the last view (the positions changed); the next [`SortCache::order`] sorts.
    pub fn invalidate(&mut self) {
        self.last = None;
        self.seed_points.clear();
    }

    /// How many sorts were done (calls that did not return the previous order).
    pub fn sorts(&self) -> u64 {
        self.sorts
    }
}

/// Median time of `runs` (at least 1) calls of each method on `cloud` seen from
/// `camera`, for the benchmark's report (call it from a release build). Rows:
/// the seed's comparator sort of [`SeedPoint::from_cloud`] structs in file order (a
/// fresh copy each run, copy not timed), the same with `sort_unstable_by` (as C++'s
/// unstable `std::sort`), the stable one starting from the order of a view 1°
/// away (the seed's persistent vector between frames of a slow drag),
/// keys, radix with fresh buffers, radix reusing its buffers (a [`SortCache`]'s steady
/// state), radix on one thread, and a [`SortCache`] hit (camera still).
pub fn time_methods(
    cloud: &PointCloud,
    camera: &Camera,
    runs: usize,
) -> Vec<(&'static str, Duration)> {
    let runs = runs.max(1);
    let view = View::of_camera(camera);
    let positions = &cloud.positions;
    let median = |mut f: Box<dyn FnMut() -> Duration + '_>| {
        let mut times: Vec<Duration> = (0..runs).map(|_| f()).collect();
        times.sort();
        times[times.len() / 2]
    };
    let timed = |f: &mut dyn FnMut()| {
        let start = Instant::now();
        f();
        start.elapsed()
    };
    let structs = SeedPoint::from_cloud(cloud);
    let mut rows = Vec::new();
    rows.push((
        "seed comparator sort of structs (file order)",
        median(Box::new(|| {
            let mut points = structs.clone();
            timed(&mut || {
                std::hint::black_box(seed_order(&mut points, view));
            })
        })),
    ));
    // C++'s std::sort is an unstable introsort: the closest Rust sort, for comparison
    // (ties then in no particular order).
    rows.push((
        "seed comparator, sort_unstable_by as std::sort (file order)",
        median(Box::new(|| {
            let mut points = structs.clone();
            timed(&mut || {
                points.sort_unstable_by(|a, b| {
                    view.seed_key(&b.position)
                        .total_cmp(&view.seed_key(&a.position))
                });
                std::hint::black_box(&points);
            })
        })),
    ));
    // The seed kept its vector between frames: after a small move (1° about y) the
    // previous order is nearly sorted.
    let moved = {
        let mut c = *camera;
        let turn = glam::DQuat::from_rotation_y(1f64.to_radians());
        c.rotation = (c.quat() * turn).to_array();
        View::of_camera(&c)
    };
    let mut sorted = structs.clone();
    seed_order(&mut sorted, moved);
    rows.push((
        "seed comparator sort of structs (previous frame's order, 1° move)",
        median(Box::new(|| {
            let mut points = sorted.clone();
            timed(&mut || {
                std::hint::black_box(seed_order(&mut points, view));
            })
        })),
    ));
    rows.push((
        "keys (parallel sort of (key, index) pairs)",
        median(Box::new(|| {
            timed(&mut || {
                std::hint::black_box(keys_order(positions, view));
            })
        })),
    ));
    rows.push((
        "radix (fresh buffers)",
        median(Box::new(|| {
            timed(&mut || {
                std::hint::black_box(back_to_front(SortMethod::Radix, positions, view));
            })
        })),
    ));
    let mut scratch = RadixScratch::default();
    let mut out = Vec::new();
    radix_order_into(positions, view, &mut scratch, &mut out);
    rows.push((
        "radix (buffers reused)",
        median(Box::new(|| {
            timed(&mut || radix_order_into(positions, view, &mut scratch, &mut out))
        })),
    ));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().ok();
    if let Some(pool) = pool {
        rows.push((
            "radix (buffers reused, 1 thread)",
            median(Box::new(|| {
                pool.install(|| {
                    timed(&mut || radix_order_into(positions, view, &mut scratch, &mut out))
                })
            })),
        ));
    }
    let mut cache = SortCache::new(SortMethod::Radix);
    cache.order(positions, view);
    rows.push((
        "sort cache hit (camera still)",
        median(Box::new(|| {
            timed(&mut || {
                std::hint::black_box(cache.order(positions, view));
            })
        })),
    ));
    rows
}

#[cfg(test)]
mod tests;
