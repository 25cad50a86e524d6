//! The multi-resolution INDEX-DATA clip texture, built as the seed builds it (§2.1):
//!
//! 1. split the single-resolution texture into blocks of `B³` voxels; where the sides are
//!    not multiples of `B`, the last blocks are partial and are padded by clamping to the
//!    edge (the padding repeats the border voxels, exactly what CLAMP_TO_EDGE shows);
//! 2. per block: every value 1 → INDEX `(0,0,0,1)`; every value 0 → INDEX `(0,0,0,0)`;
//!    otherwise copy the *extended* block (grown by one voxel on each side, `(B+2)³`,
//!    voxels beyond the volume clamped to its edge) into the next free DATA slot and set
//!    INDEX `(r,s,t,0.5)`, `(r,s,t)` being the normalized DATA coordinate of the slot's
//!    centre.
//!
//! Slots are numbered in block order (i fastest) and laid out in a near-cubic grid of
//! `sx x sy x sz` slots, `max(sx, sy, sz) = ceil(cbrt(slots))`, the product as small as
//! possible; the DATA texture is `(B+2) * (sx, sy, sz)` texels and must fit in
//! `max_3d_texture_size` per side (the renderer passes the driver's limit); only when
//! even the cubic arrangement does not fit is it refused.
//!
//! # The lookup (§2.2, after Kraus and Ertl's adaptive texture maps)
//! With `p` the fragment's normalized volume coordinate, `n` the volume size in voxels,
//! `nb = ceil(n / B)` the INDEX size, `D` the DATA size in texels (all per axis):
//!
//! - INDEX, GL_NEAREST, at `index_tc = p * (n / (nb B))` (the INDEX covers `nb B >= n`
//!   voxels): block `b = floor(p n / B)`. Alpha 0: discard. Alpha 1: keep.
//! - Alpha 0.5: `data_tc = slot_centre + (p - block_centre) * (n / D)` with
//!   `block_centre = (b B + B/2) / n`, then DATA with GL_LINEAR; keep when >= 0.5.
//!
//! One DATA texel is one volume voxel, so the scale `n / D` maps the block's voxels onto
//! the slot's inner `B³` texels and the trilinear weights are the single-resolution ones;
//! the slot's outer ring supplies the neighbours a lookup near the block's faces needs.
//! As one MAD with constants: `data_tc = p * S + O_b`, `S = n / D` (a program constant),
//! `O_b = slot_centre - block_centre * S` (per block). [`IndexEncoding::Offset`] stores
//! `O_b` in the INDEX so the program is `MAD data_tc, p, S, index.xyzw` (robust: the
//! block is decided by the one INDEX fetch). [`IndexEncoding::SlotCentre`] is the seed's
//! Table 1 verbatim; the program must then rebuild `block_centre` with a FLR of
//! `p n / B`, which can disagree with the sampler's NEAREST choice exactly on a block
//! face.
//!
//! # INDEX precision
//! The slot centres take `sx`, `sy`, `sz` distinct values per axis
//! ([`MultiRes::slot_grid`]); an 8-bit INDEX has 256 levels but must hit each centre to
//! a small fraction of a DATA texel, which `i / 255` does not: the error is up to
//! `D / 510` texels (a quarter of a texel on a 128-texel DATA axis already).
//! [`MultiRes::index_coordinate_error`] measures it for 8, 16 and 32 bits (at
//! 300 x 300 x 12 with `B = 1`, D = 216: over a quarter texel at 8 bits; see
//! `tests::more_slots_than_8_bits_address`). The INDEX is therefore
//! RGBA32F (exact to `D * 2^-25` texels); RGBA16 unorm would allow `D / 131070` texels
//! (0.016 texel at D = 2048: values off by up to 0.5 % of the 0..1 range near the
//! boundary), and cannot hold the signed offsets of [`IndexEncoding::Offset`].

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::error::ClipError;
use super::texture::{trilinear, ClipTexture};
use arbvis_data::volume::index_data::{self, SlotGrid};

/// Largest DATA texture built (texels; 2 GiB of f32).
pub const MAX_DATA_TEXELS: usize = 1 << 29;

/// What an INDEX texel says about its block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockClass {
    /// Every value 0: `(0,0,0,0)`.
    Outside,
    /// Every value 1: `(0,0,0,1)`.
    Inside,
    /// Values between: `(r,s,t,0.5)`, its extended copy in DATA slot `.0`.
    Boundary(u32),
}

/// What the INDEX texture's RGB holds for boundary blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IndexEncoding {
    /// The slot centre's normalized DATA coordinate (the seed's Table 1).
    SlotCentre,
    /// `slot_centre - block_centre * S`: `data_tc = p * S + rgb` is one MAD.
    Offset,
}

/// Texel formats for byte counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TexelFormat {
    /// One byte (the era's LUMINANCE8 / ALPHA8).
    R8,
    /// One 16-bit channel.
    R16,
    /// One float.
    R32F,
    /// Four bytes.
    Rgba8,
    /// Four 16-bit channels (unorm or half float).
    Rgba16,
    /// Four floats.
    Rgba32F,
}

impl TexelFormat {
    /// Bytes per texel.
    pub fn bytes(self) -> usize {
        match self {
            TexelFormat::R8 => 1,
            TexelFormat::R16 => 2,
            TexelFormat::R32F | TexelFormat::Rgba8 => 4,
            TexelFormat::Rgba16 => 8,
            TexelFormat::Rgba32F => 16,
        }
    }
}

/// An INDEX-DATA clip texture.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiRes {
    /// Volume (single-resolution) size `n`.
    pub dims: [usize; 3],
    /// Block side `B`.
    pub block: usize,
    /// INDEX size `nb = ceil(n / B)`.
    pub index_dims: [usize; 3],
    /// One class per block, i fastest.
    pub classes: Vec<BlockClass>,
    /// Boundary blocks (DATA slots in use).
    pub slots: usize,
    /// Slot arrangement `(sx, sy, sz)`; zeros when no block is a boundary block.
    pub slot_grid: [usize; 3],
    /// DATA size `D = (B+2) * slot_grid`.
    pub data_dims: [usize; 3],
    /// DATA texels, i fastest; unused slots hold 0.
    pub data: Vec<f32>,
    /// Seconds spent building (wall clock).
    pub build_seconds: f64,
}

fn ceil_div(a: usize, b: usize) -> usize {
    a.div_ceil(b)
}

/// The near-cubic slot arrangement for `count` boundary blocks' slots of side `side`
/// texels within `max_size` texels per axis (the atlas layout the store's bricks share:
/// [`SlotGrid::arrange`]).
pub fn arrange_slots(count: usize, side: usize, max_size: usize) -> Result<[usize; 3], ClipError> {
    SlotGrid::arrange(count, side, max_size)
        .map(|g| g.slots)
        .map_err(|e| {
            ClipError::Invalid(format!(
                "{e}: {count} boundary blocks need a larger block or a coarser clip resolution"
            ))
        })
}

impl MultiRes {
    /// Build from a single-resolution texture with blocks of `block³` voxels and a DATA
    /// texture of at most `max_3d_texture_size` texels per side.
    pub fn build(
        texture: &ClipTexture,
        block: usize,
        max_3d_texture_size: usize,
    ) -> Result<MultiRes, ClipError> {
        let start = Instant::now();
        let n = texture.grid.dims;
        if block == 0 || block > n.iter().copied().max().unwrap_or(1) {
            return Err(ClipError::Invalid(format!(
                "block size {block}: must be 1 up to the largest side of the clip grid {n:?}"
            )));
        }
        let nb = n.map(|d| ceil_div(d, block));
        let blocks = nb[0] * nb[1] * nb[2];
        let mut classes: Vec<BlockClass> = (0..blocks)
            .into_par_iter()
            .map(|b| {
                let o = [b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])].map(|x| x * block);
                let (mut zeros, mut ones, mut all) = (true, true, 0usize);
                for k in o[2]..(o[2] + block).min(n[2]) {
                    for j in o[1]..(o[1] + block).min(n[1]) {
                        for i in o[0]..(o[0] + block).min(n[0]) {
                            let v = texture.values[texture.grid.index(i, j, k)];
                            zeros &= v == 0.0;
                            ones &= v == 1.0;
                            all += 1;
                        }
                    }
                }
                match (zeros && all > 0, ones && all > 0) {
                    (true, _) => BlockClass::Outside,
                    (_, true) => BlockClass::Inside,
                    _ => BlockClass::Boundary(0),
                }
            })
            .collect();
        let mut slots = 0u32;
        for c in &mut classes {
            if let BlockClass::Boundary(s) = c {
                *s = slots;
                slots += 1;
            }
        }
        let side = block + 2;
        let slot_grid = arrange_slots(slots as usize, side, max_3d_texture_size)?;
        let data_dims = slot_grid.map(|s| s * side);
        let texels = data_dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        let texels = texels.filter(|&t| t <= MAX_DATA_TEXELS).ok_or_else(|| {
            ClipError::Invalid(format!(
                "a DATA texture of {data_dims:?} texels is more than the {MAX_DATA_TEXELS} texels built here"
            ))
        })?;
        // DATA as f32 here, and its 8-bit or float texture: checked once the boundary
        // blocks are counted (the scene's estimate could not know how many there are).
        let mut data: Vec<f32> = arbvis_core::budget::vec_for(
            texels,
            &format!(
                "the DATA texture of {slots} boundary blocks of {side}³ ({data_dims:?} texels)"
            ),
        )
        .map_err(|e| ClipError::Invalid(e.to_string()))?;
        data.resize(texels, 0f32);
        // Which block each slot holds.
        let mut slot_block = vec![0usize; slots as usize];
        for (b, c) in classes.iter().enumerate() {
            if let BlockClass::Boundary(s) = c {
                slot_block[*s as usize] = b;
            }
        }
        let layer = data_dims[0] * data_dims[1] * side;
        if layer > 0 {
            data.par_chunks_mut(layer)
                .enumerate()
                .for_each(|(sz, chunk)| {
                    for sy in 0..slot_grid[1] {
                        for sx in 0..slot_grid[0] {
                            let s = sx + slot_grid[0] * (sy + slot_grid[1] * sz);
                            let Some(&b) = slot_block.get(s) else {
                                continue;
                            };
                            let o = [b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])]
                                .map(|x| (x * block) as i64 - 1);
                            for k in 0..side {
                                for j in 0..side {
                                    for i in 0..side {
                                        let v = texture.texel(
                                            o[0] + i as i64,
                                            o[1] + j as i64,
                                            o[2] + k as i64,
                                        );
                                        let (x, y) = (sx * side + i, sy * side + j);
                                        chunk[x + data_dims[0] * (y + data_dims[1] * k)] = v;
                                    }
                                }
                            }
                        }
                    }
                });
        }
        Ok(MultiRes {
            dims: n,
            block,
            index_dims: nb,
            classes,
            slots: slots as usize,
            slot_grid,
            data_dims,
            data,
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Normalized DATA coordinate of slot `s`'s centre.
    pub fn slot_centre(&self, s: u32) -> DVec3 {
        let grid = SlotGrid {
            slots: self.slot_grid,
            side: self.block + 2,
        };
        grid.slot_centre(s as usize)
    }

    /// Normalized volume coordinate of block `(bi, bj, bk)`'s centre (`(b B + B/2) / n`;
    /// beyond 1 - B/2n for a partial block).
    pub fn block_centre(&self, b: [usize; 3]) -> DVec3 {
        let bs = self.block as f64;
        DVec3::from_array([0, 1, 2].map(|a| (b[a] as f64 * bs + 0.5 * bs) / self.dims[a] as f64))
    }

    /// The scale `S = n / D` of the DATA lookup.
    pub fn data_scale(&self) -> DVec3 {
        DVec3::from_array([0, 1, 2].map(|a| self.dims[a] as f64 / self.data_dims[a].max(1) as f64))
    }

    /// The INDEX texture's scale: `index_tc = p * (n / (nb B))`.
    pub fn index_scale(&self) -> DVec3 {
        DVec3::from_array(
            [0, 1, 2].map(|a| self.dims[a] as f64 / (self.index_dims[a] * self.block) as f64),
        )
    }

    fn block_of(&self, p: DVec3) -> [usize; 3] {
        // GL_NEAREST at index_tc with CLAMP_TO_EDGE: floor(index_tc * nb), clamped.
        let tc = p * self.index_scale();
        [0, 1, 2].map(|a| {
            let i = (tc[a] * self.index_dims[a] as f64).floor();
            (i.max(0.0) as usize).min(self.index_dims[a] - 1)
        })
    }

    /// The INDEX texels (RGBA, i fastest) with boundary blocks in `encoding`.
    pub fn index_texels(&self, encoding: IndexEncoding) -> Vec<[f32; 4]> {
        let nb = self.index_dims;
        self.classes
            .iter()
            .enumerate()
            .map(|(b, c)| match c {
                BlockClass::Outside => [0.0; 4],
                BlockClass::Inside => [0.0, 0.0, 0.0, 1.0],
                BlockClass::Boundary(s) => {
                    let centre = self.slot_centre(*s);
                    let rgb = match encoding {
                        IndexEncoding::SlotCentre => centre,
                        IndexEncoding::Offset => {
                            let bc = self.block_centre([
                                b % nb[0],
                                (b / nb[0]) % nb[1],
                                b / (nb[0] * nb[1]),
                            ]);
                            index_data::offset(centre, bc, self.data_scale())
                        }
                    };
                    [rgb.x as f32, rgb.y as f32, rgb.z as f32, 0.5]
                }
            })
            .collect()
    }

    /// DATA texel `(i, j, k)`, clamped to the texture (CLAMP_TO_EDGE).
    pub fn data_texel(&self, i: i64, j: i64, k: i64) -> f32 {
        let c = |v: i64, n: usize| v.clamp(0, n as i64 - 1) as usize;
        let [di, dj, dk] = self.data_dims;
        self.data[c(i, di) + di * (c(j, dj) + dj * c(k, dk))]
    }

    /// CPU emulation of the fragment program's lookup at normalized volume coordinates
    /// `p`: INDEX nearest, then 0, 1, or DATA linear at `slot_centre + (p - block_centre)
    /// * n / D`, in f64.
    pub fn sample_multires(&self, p: DVec3) -> f64 {
        let b = self.block_of(p);
        let nb = self.index_dims;
        match self.classes[b[0] + nb[0] * (b[1] + nb[1] * b[2])] {
            BlockClass::Outside => 0.0,
            BlockClass::Inside => 1.0,
            BlockClass::Boundary(s) => {
                let q = self.slot_centre(s) + (p - self.block_centre(b)) * self.data_scale();
                trilinear(self.data_dims, q, |i, j, k| self.data_texel(i, j, k))
            }
        }
    }

    /// The class of the block `p` falls in (the INDEX lookup alone).
    pub fn class_at(&self, p: DVec3) -> BlockClass {
        let b = self.block_of(p);
        let nb = self.index_dims;
        self.classes[b[0] + nb[0] * (b[1] + nb[1] * b[2])]
    }

    /// Bytes of INDEX and DATA in the given formats.
    pub fn bytes(&self, index: TexelFormat, data: TexelFormat) -> (usize, usize) {
        (
            self.classes.len() * index.bytes(),
            self.data.len() * data.bytes(),
        )
    }

    /// The seed's compression ratio `(INDEX + DATA) / single-resolution`, in bytes of the
    /// given formats (DATA counted whole, unused slots included).
    pub fn compression_ratio(
        &self,
        index: TexelFormat,
        data: TexelFormat,
        single: TexelFormat,
    ) -> f64 {
        let (i, d) = self.bytes(index, data);
        let n: usize = self.dims.iter().product();
        (i + d) as f64 / (n * single.bytes()) as f64
    }

    /// Largest error, in DATA texels, of the slot-centre coordinates when stored with
    /// `bits` per channel: 8 or 16 (unorm, `round(c (2^bits - 1)) / (2^bits - 1)`) or 32
    /// (f32). 0 when there is no boundary block.
    pub fn index_coordinate_error(&self, bits: u32) -> f64 {
        let mut worst: f64 = 0.0;
        for s in 0..self.slots as u32 {
            let c = self.slot_centre(s);
            for a in 0..3 {
                let stored = if bits >= 32 {
                    c[a] as f32 as f64
                } else {
                    let levels = ((1u64 << bits) - 1) as f64;
                    (c[a] * levels).round() / levels
                };
                worst = worst.max((stored - c[a]).abs() * self.data_dims[a] as f64);
            }
        }
        worst
    }
}
