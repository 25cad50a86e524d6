//! The single-resolution distance-field clip texture (Weiskopf, Engel and Ertl 2003, the
//! seed's §1): for each voxel centre the clip distance `d` (positive inside), normalized
//! by the voxel diagonal `diag = |(hx, hy, hz)|` and mapped to
//!
//! `value = clamp(0.5 + 0.5 * d / diag, 0, 1)`
//!
//! so that the boundary is the 0.5 isosurface, 0 means at least one diagonal outside and
//! 1 at least one diagonal inside. A fragment is kept when the filtered value is >= 0.5.
//!
//! The grid spans the volume's object-space box `[-half, half]` (longest side `[-1, 1]`,
//! [`arbvis_data::volume::Volume::half_extent`]); voxel `(i, j, k)`'s centre is at
//! `-half + (i + 0.5, j + 0.5, k + 0.5) * h` with `h = 2 half / dims`, i.e. at texture
//! coordinate `(i + 0.5) / ni` (GL's texel centres). [`ClipTexture::sample_single`] is
//! the CPU emulation of a GL_LINEAR, CLAMP_TO_EDGE lookup.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::shape::Shape;

pub use super::grid::{ClipGrid, MAX_CLIP_VOXELS};

/// The clip distance of `shape` at every voxel centre of `grid` (i fastest). Exact within
/// one voxel diagonal of the boundary; beyond it meshes and masks store `±2 diag` (the
/// texture clamps at one diagonal, and `min`/`max`/negation commute with that monotone
/// odd cut, so CSG of cut fields equals the cut of the CSG).
pub fn field(shape: &Shape, grid: &ClipGrid) -> Vec<f32> {
    let combine = |list: &[Shape], f: fn(f32, f32) -> f32| {
        let mut it = list.iter();
        let mut acc = it
            .next()
            .map_or_else(|| vec![f32::NEG_INFINITY; grid.len()], |s| field(s, grid));
        for s in it {
            let other = field(s, grid);
            acc.par_iter_mut()
                .zip(other.par_iter())
                .for_each(|(a, b)| *a = f(*a, *b));
        }
        acc
    };
    match shape {
        Shape::Mesh(m) => m.field(grid),
        Shape::Mask(m) => m.field(grid),
        Shape::Union(list) => combine(list, f32::max),
        Shape::Intersection(list) => combine(list, f32::min),
        Shape::Difference(a, b) => {
            let mut acc = field(a, grid);
            let other = field(b, grid);
            acc.par_iter_mut()
                .zip(other.par_iter())
                .for_each(|(a, b)| *a = a.min(-b));
            acc
        }
        Shape::Invert(a) => {
            let mut acc = field(a, grid);
            acc.par_iter_mut().for_each(|a| *a = -*a);
            acc
        }
        _ => {
            let [ni, nj, _] = grid.dims;
            let mut out = vec![0f32; grid.len()];
            out.par_chunks_mut(ni * nj)
                .enumerate()
                .for_each(|(k, slice)| {
                    for j in 0..nj {
                        for i in 0..ni {
                            let d = shape.distance(grid.centre(i, j, k)).unwrap_or(f64::NAN);
                            slice[i + ni * j] = d as f32;
                        }
                    }
                });
            out
        }
    }
}

/// `clamp(0.5 + 0.5 d / diag, 0, 1)`: the seed's mapping of a clip distance.
pub fn clip_value(d: f32, diag: f64) -> f32 {
    (0.5 + 0.5 * d as f64 / diag).clamp(0.0, 1.0) as f32
}

/// A single-resolution clip texture.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipTexture {
    /// Its grid.
    pub grid: ClipGrid,
    /// One value in [0, 1] per voxel, i fastest.
    pub values: Vec<f32>,
    /// Seconds spent computing the distances and values (wall clock, rayon in parallel).
    pub build_seconds: f64,
}

impl ClipTexture {
    /// Compute the texture of `shape` on `grid` (in parallel), timing it.
    pub fn build(shape: &Shape, grid: &ClipGrid) -> ClipTexture {
        let start = Instant::now();
        let diag = grid.diagonal();
        let mut values = field(shape, grid);
        values
            .par_iter_mut()
            .for_each(|v| *v = clip_value(*v, diag));
        ClipTexture {
            grid: *grid,
            values,
            build_seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Value of voxel `(i, j, k)`, indices clamped to the grid (CLAMP_TO_EDGE).
    pub fn texel(&self, i: i64, j: i64, k: i64) -> f32 {
        let c = |v: i64, n: usize| v.clamp(0, n as i64 - 1) as usize;
        let [ni, nj, nk] = self.grid.dims;
        self.values[self.grid.index(c(i, ni), c(j, nj), c(k, nk))]
    }

    /// GL_LINEAR lookup at normalized texture coordinates `p` with CLAMP_TO_EDGE, in f64.
    pub fn sample_single(&self, p: DVec3) -> f64 {
        trilinear(self.grid.dims, p, |i, j, k| self.texel(i, j, k))
    }

    /// True where the seed's fragment program keeps the fragment (value >= 0.5).
    pub fn keeps(&self, p: DVec3) -> bool {
        self.sample_single(p) >= 0.5
    }
}

/// GL trilinear filtering of a `dims` texture at normalized `p`: `u = p * n - 0.5`,
/// the two texels `floor(u)` and `floor(u) + 1` weighted by `fract(u)`; `texel` clamps.
pub fn trilinear(dims: [usize; 3], p: DVec3, texel: impl Fn(i64, i64, i64) -> f32) -> f64 {
    let u = [0, 1, 2].map(|a| p[a] * dims[a] as f64 - 0.5);
    let base = u.map(|x| x.floor());
    let f = [0, 1, 2].map(|a| u[a] - base[a]);
    let b = base.map(|x| x as i64);
    let mut sum = 0.0;
    for dk in 0..2 {
        for dj in 0..2 {
            for di in 0..2 {
                let w = (if di == 1 { f[0] } else { 1.0 - f[0] })
                    * (if dj == 1 { f[1] } else { 1.0 - f[1] })
                    * (if dk == 1 { f[2] } else { 1.0 - f[2] });
                if w != 0.0 {
                    sum += w * texel(b[0] + di, b[1] + dj, b[2] + dk) as f64;
                }
            }
        }
    }
    sum
}
