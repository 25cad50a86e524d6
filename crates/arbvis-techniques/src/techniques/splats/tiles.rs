//! Tile lists: the CPU half of `draw = "tiles"`, the splats composited per pixel by a
//! gather program instead of rasterized as `GL_POINTS` (the way tile-based splat
//! renderers such as 3D Gaussian splatting, Kerbl et al. 2023, composite).
//!
//! # Why
//!
//! On llvmpipe every `GL_POINT` costs single-threaded vertex and point setup before any
//! pixel is touched (`examples/point_floor` times sprites that draw nothing; measured:
//! docs/benchmarks.md, "Figures behind the splats' settings"), so no point renderer gets
//! under that floor. Here the per-point work is plain parallel Rust on every core, and
//! the GPU's work is per pixel, where llvmpipe spreads it over its threads and SIMD lanes.
//!
//! # How
//!
//! 0. [`spatial_order`] (once per scene): the visible points in Morton order, so that
//!    what follows reads and writes memory mostly in order whatever the file's order.
//! 1. [`place_splats`]: each point placed where GL draws it, in f32 as the vertex
//!    program computes it: clip position by the camera's matrix, points outside the
//!    clip volume (or at or behind the eye) dropped, size by the seed's rule clamped to
//!    `[1, 255]` (llvmpipe's point size range), window position; with its depth key
//!    ([`View::key`], the sorts' key: larger is farther), the tiles it touches, and the
//!    bands of tile rows it reaches.
//! 2. [`bin`]: the screen cut into square tiles of `tile` pixels; each splat is listed
//!    in every tile its covered pixels touch (the reference's half-open square, widened
//!    by [`MARGIN`] pixels so rounding cannot miss a pixel: the program decides coverage
//!    exactly). Bands of tile rows, several per thread, each count then fill their own
//!    part of one array, then sort each tile's list back to front by key, ties by point
//!    index (the rule of every sort method). No global sort is needed: within a tile
//!    this is the global order. `ordered = false` gives index order (`sort = "none"`).
//! 3. [`point_colours`]: each point's RGBA (the precise programs' colour, lighting and
//!    transfer alpha, [`rgba_of`]) in f32, recomputed only when lighting makes it
//!    depend on the view.
//!
//! # What is guaranteed
//!
//! Order: every list holds its splats in the order of the f32 key [`View::key`], largest
//! (farthest) first, equal keys in point index order; that is the order of the `keys`
//! and `radix` sorts that draw points and of the f64 reference's
//! [`composite`](super::reference::composite), which computes the same key the same way
//! ([`key_order`](super::reference::key_order)). So two splats whose true depths differ
//! by less than their keys' f32 rounding (about 1e-7 of the depth) are drawn in the
//! key's order by tiles, points and reference alike, whatever the true order; against
//! the true f64 order ([`exact_order`](super::reference::exact_order)) such a pair can
//! swap (in a cloud built of such pairs, pixels change by up to the difference of their
//! colours). Coverage and footprint: the gather computes them from f32 window positions
//! and sizes, so a pixel agrees with the reference to f32 rounding (measured below 3e-5)
//! unless a splat's rim passes within that rounding of its centre, where the rim
//! fragment's alpha may be taken or not
//! ([`rim_allowance`](super::reference::rim_allowance)).
//!
//! The lists are bounded ([`bin`]'s `max_entries`): a close-up of large splats (up to
//! 255 pixels each) could ask for billions of entries; past the bound the renderer
//! draws points instead and says so.

use glam::{DVec3, Vec3, Vec4Swizzles};
use rayon::prelude::*;

use super::prepare::{rgba_of, Prepared};
use super::reference::SplatParams;
use super::scene::SplatsScene;
use super::sort::View;
use arbvis_core::camera::Camera;
use arbvis_core::vocab::Fidelity;

/// Pixels a splat's listed square is widened by on each side (f32 rounding of window
/// positions is far below it; the program's exact test decides).
pub const MARGIN: f32 = 1.0 / 64.0;

pub use super::scene::DEFAULT_TILE;

/// Default bound on list entries (16 M entries, 256 MiB).
pub const DEFAULT_MAX_ENTRIES: usize = 1 << 24;

/// Points per parallel work item.
const CHUNK: usize = 16_384;

/// A splat on screen as the gather program reads it: GL window position (y up), size in
/// pixels, and the point it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreenSplat {
    /// Window x.
    pub x: f32,
    /// Window y (up).
    pub y: f32,
    /// Side of the splat's square in pixels.
    pub size: f32,
    /// The point's index (its colour's).
    pub point: u32,
}

impl ScreenSplat {
    /// The list entry: x, y and size as f32 bits, the point index.
    pub fn entry(&self) -> [u32; 4] {
        [
            self.x.to_bits(),
            self.y.to_bits(),
            self.size.to_bits(),
            self.point,
        ]
    }

    /// Tile ranges `[x0, x1)` across and `[y0, y1)` up that the splat's covered pixels
    /// touch (empty when it covers none).
    fn tiles(&self, size: [u32; 2], tile: u32) -> [u32; 4] {
        let h = self.size / 2.0 + MARGIN;
        // Pixels whose centres k + 0.5 lie in [c - h, c + h), clamped to the image.
        let covered = |c: f32, limit: u32| {
            let (lo, hi) = (
                ceil_clamped(c - h - 0.5, limit),
                ceil_clamped(c + h - 0.5, limit),
            );
            (lo, hi)
        };
        let (x0, x1) = covered(self.x, size[0]);
        let (y0, y1) = covered(self.y, size[1]);
        if x0 >= x1 || y0 >= y1 {
            return [0; 4];
        }
        [
            x0 / tile,
            (x1 - 1) / tile + 1,
            y0 / tile,
            (y1 - 1) / tile + 1,
        ]
    }
}

/// `ceil(v)` clamped to `[0, limit]` (NaN gives 0), without `f32::ceil`: the default
/// x86-64 target has no rounding instruction, and the libm call was a third of the
/// binning time.
fn ceil_clamped(v: f32, limit: u32) -> u32 {
    let v = v.clamp(0.0, limit as f32);
    if v.is_nan() {
        return 0;
    }
    let t = v as u32;
    if (t as f32) < v {
        t + 1
    } else {
        t
    }
}

/// The visible points in a spatial order (Morton order of their positions), with their
/// indices: neighbours in space are neighbours in memory, so placing and binning read
/// and write memory mostly in order whatever the file's order (the generated section's
/// and many scanners' files are in no spatial order).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SpatialPoints {
    /// Positions, in Morton order.
    pub positions: Vec<[f32; 3]>,
    /// Each one's index in the cloud.
    pub index: Vec<u32>,
    /// Each point's size over the scene's, by index in the cloud (empty: all 1; a COPC
    /// cut's coarser points stand in for their missing children).
    pub size_scales: Vec<f32>,
}

/// The points with `visible` set, in Morton order (10 bits per axis over their bounds).
pub fn spatial_order(positions: &[[f32; 3]], visible: &[bool]) -> SpatialPoints {
    let shown = |i: usize| visible.get(i).copied().unwrap_or(false);
    let finite = |p: &[f32; 3]| p.iter().all(|v| v.is_finite());
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for (i, p) in positions.iter().enumerate() {
        if shown(i) && finite(p) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let code = |p: &[f32; 3]| -> u32 {
        let mut c = 0u32;
        for k in 0..3 {
            let extent = (hi[k] - lo[k]).max(f32::MIN_POSITIVE);
            let q = ((p[k] - lo[k]) / extent * 1023.0).clamp(0.0, 1023.0) as u32;
            c |= spread_bits(q) << k;
        }
        c
    };
    let mut keyed: Vec<(u32, u32)> = (0..positions.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .filter(|&i| shown(i))
        .map(|i| (code(&positions[i]), i as u32))
        .collect();
    keyed.par_sort_unstable();
    SpatialPoints {
        positions: keyed.iter().map(|&(_, i)| positions[i as usize]).collect(),
        index: keyed.into_iter().map(|(_, i)| i).collect(),
        size_scales: Vec::new(),
    }
}

/// The 10 low bits of `v` spread to every third bit.
fn spread_bits(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

/// Splats placed on screen for one image and tile size, in the order of the points
/// given, in parts (one per [`CHUNK`] points) that also say which band of tile rows each
/// splat reaches.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Placed {
    size: [u32; 2],
    tile: u32,
    /// Tile rows per band.
    band_rows: u32,
    parts: Vec<PlacedPart>,
}

/// One chunk's splats.
#[derive(Debug, Clone, Default, PartialEq)]
struct PlacedPart {
    splats: Vec<ScreenSplat>,
    /// Each splat's [`View::key`] (larger is farther).
    keys: Vec<f32>,
    /// Each splat's tile ranges (see [`ScreenSplat::tiles`]).
    rects: Vec<[u32; 4]>,
    /// Per band, the splats (indices into this part) that reach it, in order.
    bands: Vec<Vec<u32>>,
    /// List entries these splats make (the tiles of their rects).
    entries: u64,
}

impl Placed {
    /// The splats, in order.
    pub fn splats(&self) -> impl Iterator<Item = &ScreenSplat> {
        self.parts.iter().flat_map(|p| &p.splats)
    }

    /// Tiles across and up.
    pub fn tiles(&self) -> [u32; 2] {
        let t = self.tile.max(1);
        [self.size[0].div_ceil(t), self.size[1].div_ceil(t)]
    }

    fn bands(&self) -> Vec<[u32; 2]> {
        let rows = self.tiles()[1];
        (0..rows)
            .step_by(self.band_rows.max(1) as usize)
            .map(|r| [r, (r + self.band_rows).min(rows)])
            .collect()
    }
}

/// `points` placed on a `size` image as GL draws them (those GL would not draw left
/// out), for tiles of `tile` pixels.
pub fn place_splats(
    points: &SpatialPoints,
    camera: &Camera,
    size: [u32; 2],
    tile: u32,
    params: &SplatParams,
) -> Placed {
    let mvp = camera
        .view_projection(size[0] as f64 / size[1].max(1) as f64)
        .as_mat4();
    let view = View::of_camera(camera);
    let eye = super::reference::eye_position(camera).map(|e| e.as_vec3());
    let (point_size, factor) = (params.point_size as f32, params.factor as f32);
    let [lo, hi] = params.size_range.map(|v| v as f32);
    let [w, h] = size.map(|v| v as f32);
    let tile = tile.max(1);
    // Bands of tile rows: a few per thread, for the binning's work stealing.
    let rows = size[1].div_ceil(tile);
    let band_rows = rows
        .div_ceil(8 * rayon::current_num_threads() as u32)
        .max(1);
    let band_count = rows.div_ceil(band_rows) as usize;
    let parts = points
        .positions
        .par_chunks(CHUNK)
        .zip(points.index.par_chunks(CHUNK))
        .map(|(chunk, index)| {
            let n = chunk.len();
            let mut part = PlacedPart {
                splats: Vec::with_capacity(n),
                keys: Vec::with_capacity(n),
                rects: Vec::with_capacity(n),
                bands: (0..band_count)
                    .map(|_| Vec::with_capacity(2 * n / band_count.max(1) + 16))
                    .collect(),
                entries: 0,
            };
            for (p, &i) in chunk.iter().zip(index) {
                let q = Vec3::from_array(*p);
                let clip = mvp * q.extend(1.0);
                let inside = clip.w > 0.0
                    && clip.x.abs() <= clip.w
                    && clip.y.abs() <= clip.w
                    && clip.z.abs() <= clip.w;
                let s = match eye {
                    Some(e) => point_size / q.distance(e) * factor,
                    None => point_size * factor,
                } * points.size_scales.get(i as usize).copied().unwrap_or(1.0);
                // The reference's rule: a NaN size draws nothing, others are clamped.
                let s = if s.is_nan() { s } else { s.max(lo).min(hi) };
                let drawn = s > 0.0;
                if !inside || !drawn {
                    continue;
                }
                let ndc = clip.xy() / clip.w;
                let splat = ScreenSplat {
                    x: (ndc.x + 1.0) / 2.0 * w,
                    y: (ndc.y + 1.0) / 2.0 * h,
                    size: s,
                    point: i,
                };
                let rect = splat.tiles(size, tile);
                part.entries += (rect[1] - rect[0]) as u64 * (rect[3] - rect[2]) as u64;
                let k = part.splats.len() as u32;
                if rect[2] < rect[3] {
                    let first = (rect[2] / band_rows) as usize;
                    let last = ((rect[3] - 1) / band_rows) as usize;
                    for band in &mut part.bands[first..=last] {
                        band.push(k);
                    }
                }
                part.splats.push(splat);
                part.keys.push(view.key(p));
                part.rects.push(rect);
            }
            part
        })
        .collect();
    Placed {
        size,
        tile,
        band_rows,
        parts,
    }
}

/// Per-tile lists of splats, back to front.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TileLists {
    /// Image size in pixels.
    pub size: [u32; 2],
    /// Tile side in pixels.
    pub tile: u32,
    /// Tiles across and up.
    pub tiles: [u32; 2],
    /// Where each tile's list starts in `entries` (row-major tiles, bottom row first),
    /// and the total at the end.
    pub offsets: Vec<u32>,
    /// [`ScreenSplat::entry`]s, tile after tile.
    pub entries: Vec<[u32; 4]>,
}

impl TileLists {
    /// Pixel rectangles `[x0, y0, x1, y1)` covering every tile that holds an entry: the
    /// blocks of `block` x `block` tiles with any, runs along a row merged. Pixels outside
    /// them have empty lists, so the gather need not run there.
    pub fn occupied(&self, block: u32) -> Vec<[u32; 4]> {
        let block = block.max(1);
        let [across, up] = self.tiles;
        let empty = |tx: u32, ty: u32| {
            let t = (ty * across + tx) as usize;
            self.offsets[t] == self.offsets[t + 1]
        };
        let pixel = |t: u32, limit: u32| (t * self.tile).min(limit);
        let mut rects: Vec<[u32; 4]> = Vec::new();
        for by in (0..up).step_by(block as usize) {
            let rows = by..(by + block).min(up);
            let mut run: Option<u32> = None;
            for bx in (0..across).step_by(block as usize).chain([across]) {
                let cols = bx..(bx + block).min(across);
                let any =
                    bx < across && rows.clone().any(|ty| cols.clone().any(|tx| !empty(tx, ty)));
                match (any, run) {
                    (true, None) => run = Some(bx),
                    (false, Some(start)) => {
                        rects.push([
                            pixel(start, self.size[0]),
                            pixel(rows.start, self.size[1]),
                            pixel(bx, self.size[0]),
                            pixel(rows.end, self.size[1]),
                        ]);
                        run = None;
                    }
                    _ => {}
                }
            }
        }
        rects
    }

    /// The entries of tile (`tx`, `ty`), back to front.
    pub fn list(&self, tx: u32, ty: u32) -> &[[u32; 4]] {
        let t = (ty * self.tiles[0] + tx) as usize;
        &self.entries[self.offsets[t] as usize..self.offsets[t + 1] as usize]
    }
}

/// Lists would exceed the bound: the entries they need.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TooManyEntries(pub u64);

/// Bin `placed` into tiles, at most `max_entries` entries; each list back to front
/// when `ordered`, else in file order.
pub fn bin(
    placed: &Placed,
    max_entries: usize,
    ordered: bool,
) -> Result<TileLists, TooManyEntries> {
    let mut binner = Binner::default();
    binner.bin(placed, max_entries, ordered)?;
    Ok(binner.lists)
}

/// [`bin`] with its buffers kept from frame to frame (no allocation, no page faults
/// once they have grown).
#[derive(Debug, Default)]
pub struct Binner {
    counts: Vec<u32>,
    keys: Vec<f32>,
    /// The lists of the last [`Binner::bin`].
    pub lists: TileLists,
}

/// One band of tile rows `[rows[0], rows[1])` and its part of the counts or entries.
struct Band<T> {
    rows: [u32; 2],
    start: usize,
    part: T,
}

impl Binner {
    /// Bin as [`bin`] does into `self.lists`.
    pub fn bin(
        &mut self,
        placed: &Placed,
        max_entries: usize,
        ordered: bool,
    ) -> Result<(), TooManyEntries> {
        let tiles = placed.tiles();
        let across = tiles[0] as usize;
        let bands = placed.bands();
        // The bound first: a close-up of large splats must not count billions of entries
        // to learn that it is drawn as points.
        let needed: u64 = placed.parts.iter().map(|p| p.entries).sum();
        if needed > max_entries.min(u32::MAX as usize) as u64 {
            return Err(TooManyEntries(needed));
        }
        // Count per tile, each band its own rows.
        self.counts.clear();
        self.counts.resize(across * tiles[1] as usize, 0);
        split_by_rows(&mut self.counts, &bands, |r| r * across)
            .into_par_iter()
            .for_each(|band| {
                let rows = band.rows;
                let counts = band.part;
                for_each_tile(placed, rows, across, |_, _, t| counts[t] += 1);
            });
        let offsets = &mut self.lists.offsets;
        offsets.clear();
        let mut total = 0u32;
        for c in &self.counts {
            offsets.push(total);
            total += c;
        }
        offsets.push(total);
        let offsets = &self.lists.offsets;
        // Resizing keeps what is there: only growth is written.
        self.lists.entries.resize(total as usize, [0; 4]);
        self.keys.resize(total as usize, 0.0);
        let at = |r: usize| offsets[r * across] as usize;
        let entries = split_by_rows(&mut self.lists.entries, &bands, at);
        let keys = split_by_rows(&mut self.keys, &bands, at);
        entries.into_par_iter().zip(keys).for_each(|(band, keys)| {
            let [r0, r1] = band.rows;
            let in_band = &offsets[r0 as usize * across..=r1 as usize * across];
            let mut cursor: Vec<usize> = in_band[..in_band.len() - 1]
                .iter()
                .map(|&o| o as usize - band.start)
                .collect();
            let (entries, keys) = (band.part, keys.part);
            for_each_tile(placed, band.rows, across, |part, k, t| {
                let c = &mut cursor[t];
                entries[*c] = part.splats[k].entry();
                keys[*c] = part.keys[k];
                *c += 1;
            });
            let mut scratch = Vec::new();
            for w in in_band.windows(2) {
                let [a, b] = [w[0], w[1]].map(|o| o as usize - band.start);
                back_to_front(&mut entries[a..b], &mut keys[a..b], ordered, &mut scratch);
            }
        });
        self.lists.size = placed.size;
        self.lists.tile = placed.tile.max(1);
        self.lists.tiles = tiles;
        Ok(())
    }
}

/// `data` cut into one slice per band; `at(row)` is where a band starting at `row`
/// starts in `data`.
fn split_by_rows<'a, T>(
    data: &'a mut [T],
    bands: &[[u32; 2]],
    at: impl Fn(usize) -> usize,
) -> Vec<Band<&'a mut [T]>> {
    let mut parts = Vec::with_capacity(bands.len());
    let mut rest = data;
    for &[r0, r1] in bands {
        let start = at(r0 as usize);
        let (part, tail) = rest.split_at_mut(at(r1 as usize) - start);
        parts.push(Band {
            rows: [r0, r1],
            start,
            part,
        });
        rest = tail;
    }
    parts
}

/// Call `f(part, splat, tile)` for every tile of rows `[r0, r1)` (a band) that a splat
/// reaching the band touches, splats in order; `tile` counts from the band's first row.
fn for_each_tile(
    placed: &Placed,
    [r0, r1]: [u32; 2],
    across: usize,
    mut f: impl FnMut(&PlacedPart, usize, usize),
) {
    let index = (r0 / placed.band_rows.max(1)) as usize;
    for part in &placed.parts {
        for &k in &part.bands[index] {
            let r = part.rects[k as usize];
            for ty in r[2].max(r0)..r[3].min(r1) {
                let row = (ty - r0) as usize * across;
                for tx in r[0] as usize..r[1] as usize {
                    f(part, k as usize, row + tx);
                }
            }
        }
    }
}

/// Sort one tile's list back to front: by key, largest (farthest) first, ties by point
/// index (the sorts' rule); by point index alone when not `ordered` (file order).
/// `scratch` is reused from tile to tile (no allocation per tile).
fn back_to_front(
    entries: &mut [[u32; 4]],
    keys: &mut [f32],
    ordered: bool,
    scratch: &mut Vec<(u32, u32, [u32; 4])>,
) {
    // One integer per key that orders as the key does, largest first (flip the bits of
    // the positive floats, all bits of the negative ones).
    let rank = |k: f32| -> u32 {
        if !ordered {
            return 0;
        }
        let b = k.to_bits();
        let ascending = if b >> 31 == 1 { !b } else { b | 1 << 31 };
        !ascending
    };
    if entries.len() <= 16 {
        for i in 1..entries.len() {
            let (e, k) = (entries[i], keys[i]);
            let key = (rank(k), e[3]);
            let mut j = i;
            while j > 0 && key < (rank(keys[j - 1]), entries[j - 1][3]) {
                entries[j] = entries[j - 1];
                keys[j] = keys[j - 1];
                j -= 1;
            }
            entries[j] = e;
            keys[j] = k;
        }
        return;
    }
    scratch.clear();
    scratch.extend(
        entries
            .iter()
            .zip(keys.iter())
            .map(|(e, &k)| (rank(k), e[3], *e)),
    );
    scratch.sort_unstable_by_key(|&(r, point, _)| (r, point));
    for (slot, &(_, _, e)) in entries.iter_mut().zip(scratch.iter()) {
        *slot = e;
    }
}

/// Every point's RGBA in f32 as the precise programs compute it (see [`rgba_of`]).
pub fn point_colours(
    prepared: &Prepared,
    scene: &SplatsScene,
    eye: Option<DVec3>,
    view_dir: DVec3,
) -> Vec<[f32; 4]> {
    (0..prepared.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| rgba_of(prepared, scene, Fidelity::Precise, eye, view_dir, i).map(|v| v as f32))
        .collect()
}

#[cfg(test)]
mod tests;
