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
//! on rayon's stable `par_sort_by`, [`SortMethod::Radix`] on LSD radix passes being
//! stable over pairs laid out in index order. So all three give identical orders
//! whenever their keys agree (always for Keys and Radix; for Seed, except for the
//! square-root rounding above).
//!
//! # The methods
//!
//! - [`SortMethod::Seed`], the baseline: [`SeedPoint`] structs holding the position and
//!   every attribute the seed's struct held (14 floats; an index is added so the order
//!   can be reported), sorted in place with a comparator computing both distances at
//!   every comparison. In a [`SortCache`] the structs persist between frames and each
//!   sort starts from the previous frame's order, as the seed's vector did.
//! - [`SortMethod::Keys`]: one key per point computed in parallel, then a parallel
//!   stable sort of (key, index) pairs.
//! - [`SortMethod::Radix`]: keys mapped to u32 so that integer order is the float order
//!   (flip all bits of negatives, the sign bit of positives), reversed for farthest
//!   first, offset by the smallest key so only the bits that vary are sorted; then LSD
//!   radix passes of [`RADIX_BITS`]-bit digits over (key, index) pairs packed into u64.
//!   Each pass splits the array into one chunk per thread: per-chunk histograms in
//!   parallel, then each chunk scatters into its own disjoint ranges of the output
//!   (split with `split_at_mut`, no `unsafe`). Small inputs run on one thread.
//!   [`RadixScratch`] keeps the buffers between frames (fresh pages cost about as much
//!   as the sort).
//!
//! [`SortCache`] returns the previous order untouched when the view did not change (same
//! bits) and the point count is the same; call [`SortCache::invalidate`] when the
//! positions change.
//!
//! Orders are u32 indices, as a GL index buffer holds: slices of more than `u32::MAX`
//! points have no such order and get an empty one (point readers stop at
//! [`crate::points::MAX_POINTS`], far below).

use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;

use crate::camera::{Camera, Projection};
use crate::points::{PointCloud, Values, AMPLITUDE, FACIES, FAULT, JOINT_DIP, LAYER, POROSITY};

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
    /// The view of `camera`: its eye `R⁻¹ (0, 0, d)` in perspective, its direction
    /// `R⁻¹ (0, 0, -1)` in orthographic (`R` the camera's rotation, `d` its eye distance).
    pub fn of_camera(camera: &Camera) -> View {
        let inverse = camera.quat().inverse();
        match camera.projection {
            Projection::Perspective => View::Eye(to_f32(
                inverse * DVec3::new(0.0, 0.0, camera.eye_distance()),
            )),
            Projection::Orthographic => View::Along(to_f32(inverse * DVec3::NEG_Z)),
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

/// The u32 whose integer order is the reverse of `k`'s float order (for a canonical
/// key: no NaN, no -0), so that ascending radix order is farthest first.
#[inline]
fn descending_bits(k: f32) -> u32 {
    let b = k.to_bits();
    let ascending = if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    };
    !ascending
}

/// The sorting methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SortMethod {
    /// The seed's baseline: structs sorted with a distance comparator.
    Seed,
    /// One key per point, a parallel stable sort of (key, index) pairs.
    Keys,
    /// A parallel LSD radix sort of (key bits, index) pairs.
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
    /// from [`crate::points::section::facies_colour`]; the cloud's normals if it has them).
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
                p.colour = crate::points::section::facies_colour(f).map(|c| c as f32 / 255.0);
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

/// Keys computed once (in parallel), then a parallel stable sort of (key, index) pairs.
pub fn keys_order(positions: &[[f32; 3]], view: View) -> Vec<u32> {
    if too_many(positions.len()) {
        return Vec::new();
    }
    let mut pairs: Vec<(f32, u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| (view.key(p), i as u32))
        .collect();
    pairs.par_sort_by(|a, b| b.0.total_cmp(&a.0));
    pairs.into_par_iter().map(|(_, i)| i).collect()
}

/// Bits per radix digit (2048 buckets; 32-bit keys take at most 3 passes).
pub const RADIX_BITS: u32 = 11;

/// Below this many points the radix sort runs on one thread.
const PARALLEL_MIN: usize = 1 << 16;

/// Buffers kept between radix sorts.
#[derive(Debug, Default, Clone)]
pub struct RadixScratch {
    a: Vec<u64>,
    b: Vec<u64>,
}

/// The radix sort into `out` (cleared first), reusing `scratch`.
pub fn radix_order_into(
    positions: &[[f32; 3]],
    view: View,
    scratch: &mut RadixScratch,
    out: &mut Vec<u32>,
) {
    radix_with(positions, view, scratch, out, RADIX_BITS);
}

fn radix_with(
    positions: &[[f32; 3]],
    view: View,
    scratch: &mut RadixScratch,
    out: &mut Vec<u32>,
    digit_bits: u32,
) {
    out.clear();
    let n = positions.len();
    if n == 0 || too_many(n) {
        return;
    }
    let chunks = if n < PARALLEL_MIN {
        1
    } else {
        rayon::current_num_threads().max(1)
    };
    let chunk_len = n.div_ceil(chunks);
    let RadixScratch { a, b } = scratch;
    a.resize(n, 0);
    b.resize(n, 0);
    // Pairs (key bits << 32 | index), and the range of the key bits.
    let (lo, hi) = a
        .par_chunks_mut(chunk_len)
        .zip(positions.par_chunks(chunk_len))
        .enumerate()
        .map(|(c, (slots, points))| {
            let (mut lo, mut hi) = (u32::MAX, 0u32);
            for (j, (slot, p)) in slots.iter_mut().zip(points).enumerate() {
                let k = descending_bits(view.key(p));
                lo = lo.min(k);
                hi = hi.max(k);
                *slot = (k as u64) << 32 | (c * chunk_len + j) as u64;
            }
            (lo, hi)
        })
        .reduce(|| (u32::MAX, 0), |x, y| (x.0.min(y.0), x.1.max(y.1)));
    let bits = 32 - (hi - lo).leading_zeros();
    let radix = 1usize << digit_bits;
    let mask = (radix - 1) as u32;
    let (mut src, mut dst) = (a, b);
    let mut shift = 0;
    while shift < bits {
        let digit = move |v: u64| ((((v >> 32) as u32 - lo) >> shift) & mask) as usize;
        let counts: Vec<Vec<usize>> = src
            .par_chunks(chunk_len)
            .map(|chunk| {
                let mut count = vec![0usize; radix];
                for &v in chunk {
                    count[digit(v)] += 1;
                }
                count
            })
            .collect();
        // Destination ranges ordered by digit, then chunk: each chunk gets its own.
        let mut ranges: Vec<Vec<&mut [u64]>> = (0..counts.len())
            .map(|_| Vec::with_capacity(radix))
            .collect();
        let mut rest: &mut [u64] = dst;
        for d in 0..radix {
            for (c, count) in counts.iter().enumerate() {
                let (range, tail) = rest.split_at_mut(count[d]);
                ranges[c].push(range);
                rest = tail;
            }
        }
        src.par_chunks(chunk_len)
            .zip(ranges.into_par_iter())
            .for_each(|(chunk, mut ranges)| {
                let mut cursor = vec![0usize; radix];
                for &v in chunk {
                    let d = digit(v);
                    ranges[d][cursor[d]] = v;
                    cursor[d] += 1;
                }
            });
        std::mem::swap(&mut src, &mut dst);
        shift += digit_bits;
    }
    out.resize(n, 0);
    out.par_chunks_mut(chunk_len)
        .zip(src.par_chunks(chunk_len))
        .for_each(|(o, s)| {
            for (o, &v) in o.iter_mut().zip(s) {
                *o = v as u32;
            }
        });
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
/// fresh copy each run, copy not timed), the same starting from the order of a view 1°
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
        "keys (parallel stable sort of pairs)",
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
