//! Reading a store back: its description, chunks (f32 whatever the stored type), bricks
//! grown by one voxel on every side (clamped at the survey's faces, as CLAMP_TO_EDGE), the
//! per-brick ranges, and level-0 windows as a [`Volume`] (sections, references).
//!
//! Every file is read through [`super::zarr`] (bounded, regular files only) and every
//! array checked against the store's metadata at open ([`super::check`]). Every error
//! names the store and, for a chunk, its file and indices. An absent chunk is zarr's
//! "all fill value" where the store's own ranges agree (zarr-python does not write such
//! chunks); where the ranges say the brick holds other values, or while a conversion is
//! still writing the store (it writes every chunk before it logs the column), an absent
//! chunk is corruption.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use super::meta::StoreMeta;
use super::zarr::ArrayMeta;
use super::StoreError;
use crate::volume::Volume;

/// Per-brick ranges read so far, by (attribute, level).
type RangeTables = HashMap<(usize, usize), Arc<Vec<[f32; 2]>>>;

/// A decoded chunk, by (attribute, level, chunk index), with its last use.
type CachedChunks = HashMap<(usize, usize, [usize; 3]), (Arc<Vec<f32>>, u64)>;

/// An open store.
pub struct Store {
    /// The store's folder.
    pub path: PathBuf,
    /// Its description.
    pub meta: StoreMeta,
    /// The data arrays, by attribute and level.
    arrays: Vec<Vec<ArrayMeta>>,
    /// The per-brick range arrays, by attribute and level.
    range_arrays: Vec<Vec<ArrayMeta>>,
    ranges: Mutex<RangeTables>,
    cache: Mutex<ChunkCache>,
    /// Being written by a conversion: every chunk it logged must be present.
    incomplete: bool,
    /// An MDIO dataset's level 0, read in place (then there are no arbvis arrays).
    mdio: Option<super::mdio::Mdio>,
}

/// Decoded chunks kept for neighbouring bricks' borders, least recently used first out.
struct ChunkCache {
    chunks: CachedChunks,
    tick: u64,
    capacity: usize,
}

impl ChunkCache {
    fn get(&mut self, key: &(usize, usize, [usize; 3])) -> Option<Arc<Vec<f32>>> {
        self.tick += 1;
        let tick = self.tick;
        self.chunks.get_mut(key).map(|(c, t)| {
            *t = tick;
            c.clone()
        })
    }
    fn put(&mut self, key: (usize, usize, [usize; 3]), chunk: Arc<Vec<f32>>) {
        while self.chunks.len() >= self.capacity.max(1) {
            let oldest = self
                .chunks
                .iter()
                .min_by_key(|(_, (_, t))| *t)
                .map(|(k, _)| *k);
            match oldest {
                Some(k) => self.chunks.remove(&k),
                None => break,
            };
        }
        self.tick += 1;
        self.chunks.insert(key, (chunk, self.tick));
    }
}

/// Decoded chunks kept by default (64 MiB of 64³ f32 chunks).
pub const CHUNK_CACHE: usize = 64;

impl Store {
    /// Open the store at `path`: its description and every array checked.
    pub fn open(path: &Path) -> Result<Store, StoreError> {
        let path = &crate::fetch::local_or_url(path);
        let folder = crate::fetch::probe_folder(path)
            .map_err(|e| StoreError::invalid(path, e.to_string()))?;
        if !folder {
            let why = if crate::fetch::exists(path) {
                "not a folder: a store is a folder (make one with `arbvis convert SURVEY STORE`)"
            } else {
                "no such store: no such file or folder (make one with `arbvis convert SURVEY STORE`)"
            };
            return Err(StoreError::invalid(path, why));
        }
        // An MDIO dataset of any flavour, read in place as one level.
        if let Some(flavour) = super::mdio::flavour(path)?.filter(|f| f.in_place()) {
            let (meta, mdio) = super::mdio::open_flavour(path, &flavour)?;
            let mut store = Store::with_arrays(path, meta, (Vec::new(), Vec::new()), false);
            store.mdio = Some(mdio);
            return Ok(store);
        }
        let meta = super::check::read_meta(path)?;
        if !meta.complete {
            return Err(StoreError::invalid(
                path,
                "the conversion has not finished (run the same `arbvis convert` again to resume it)",
            ));
        }
        Store::with_meta(path, meta, false)
    }

    /// A store being written (the conversion reads the level below back).
    pub(crate) fn open_incomplete(path: &Path, meta: StoreMeta) -> Result<Store, StoreError> {
        Store::with_meta(path, meta, true)
    }

    fn with_meta(path: &Path, meta: StoreMeta, incomplete: bool) -> Result<Store, StoreError> {
        let arrays = super::check::open_arrays(path, &meta)?;
        let mdio = match &meta.source_variable {
            // Levels added beside an MDIO dataset: its own variable is level 0.
            Some(_) => {
                let root = super::zarr::read_json(&path.join("zarr.json"))?;
                Some(super::mdio::open(path, &root)?.1)
            }
            None => None,
        };
        let mut store = Store::with_arrays(path, meta, arrays, incomplete);
        store.mdio = mdio;
        Ok(store)
    }

    fn with_arrays(
        path: &Path,
        meta: StoreMeta,
        (arrays, range_arrays): (super::check::ArraysByLevel, super::check::ArraysByLevel),
        incomplete: bool,
    ) -> Store {
        Store {
            path: path.to_path_buf(),
            meta,
            arrays,
            range_arrays,
            ranges: Mutex::new(HashMap::new()),
            cache: Mutex::new(ChunkCache {
                chunks: HashMap::new(),
                tick: 0,
                capacity: CHUNK_CACHE,
            }),
            incomplete,
            mdio: None,
        }
    }

    /// Whether `attr` may read NaN ("no data": non-finite samples, dead traces, absent
    /// chunks of an MDIO variable whose fill is NaN).
    pub fn may_hold_nan(&self, attr: usize) -> bool {
        self.meta.attributes[attr].non_finite > 0 || self.mdio.as_ref().is_some_and(|m| m.nan_fill)
    }

    /// Each trace's map coordinates (`cdp_x`, `cdp_y`, inline-major over the whole survey),
    /// where the store or dataset has them: read whole, so a caller keeps them.
    pub fn map_coordinates(&self) -> Result<Option<[Vec<f64>; 2]>, StoreError> {
        if let Some(m) = &self.mdio {
            return Ok(m.cdp.clone());
        }
        let [_, nj, nk] = self.meta.dims;
        if self.meta.version < 2 {
            return Ok(None);
        }
        super::mdio::map_coordinates(&self.path, nk, nj)
    }

    /// True when this is an MDIO dataset read in place without levels (one level, no
    /// brick ranges: `arbvis convert` on it adds them).
    pub fn is_mdio(&self) -> bool {
        self.mdio.is_some() && self.arrays.is_empty()
    }

    /// How the survey's samples were compressed lossily, where they were (an MDIO
    /// dataset's ZFP in a lossy mode, read in place or converted): what a reference of
    /// this store is of, the decoded values, not the survey's own.
    pub fn lossy(&self) -> Option<String> {
        if let Some(z) = self.mdio.as_ref().and_then(|m| m.data.zfp.as_ref()) {
            return z.lossy().then(|| z.describe());
        }
        self.meta
            .source
            .facts
            .get("codecs")
            .filter(|c| c.contains("lossy"))
            .cloned()
    }

    /// The zarr path of attribute `attr`'s level `level` ([`StoreMeta::array_path`]).
    pub fn array_path(meta: &StoreMeta, attr: usize, level: usize) -> String {
        meta.array_path(attr, level)
    }

    /// The zarr path of the per-brick ranges of `attr` at `level`.
    pub fn range_path(meta: &StoreMeta, attr: usize, level: usize) -> String {
        meta.range_path(attr, level)
    }

    /// The file of chunk `c` (`[i, j, k]` brick indices) of `attr` at `level`.
    pub fn chunk_file(&self, attr: usize, level: usize, c: [usize; 3]) -> PathBuf {
        if let Some(m) = self.mdio.as_ref().filter(|_| attr == 0 && level == 0) {
            return m.chunk_file(self.meta.brick, c);
        }
        self.arrays[attr][level].chunk_file(&[c[2] as u64, c[1] as u64, c[0] as u64])
    }

    /// Start fetching ahead what bricks `bricks` (attribute, level, brick) and their
    /// borders read, when the store is remote (nothing for a local one): a level at a
    /// time, the coarsest first (a first picture's bricks do not share the link with the
    /// finer ones), many requests at once.
    pub fn prefetch(&self, bricks: &[(usize, usize, [usize; 3])]) {
        if crate::fetch::url_of(&self.path).is_none() {
            return;
        }
        let mut order: Vec<_> = bricks.to_vec();
        order.sort_by_key(|b| std::cmp::Reverse(b.1));
        let mut seen = std::collections::HashSet::new();
        let mut stages: Vec<Vec<PathBuf>> = Vec::new();
        let mut level = usize::MAX;
        for (attr, l, c) in order {
            if l != level {
                stages.push(Vec::new());
                level = l;
            }
            let stage = stages.last_mut().expect("a stage per level");
            for file in self.brick_files(attr, l, c) {
                if seen.insert(file.clone()) {
                    stage.push(file);
                }
            }
        }
        crate::fetch::prefetch_in_stages(stages);
    }

    /// The chunk files brick `c` of `attr` at `level` reads, its border included: its
    /// own first (an MDIO variable's chunks under the grown box).
    fn brick_files(&self, attr: usize, level: usize, c: [usize; 3]) -> Vec<PathBuf> {
        let b = self.meta.brick;
        let n = self.meta.level_dims(level);
        let mut files = vec![self.chunk_file(attr, level, c)];
        if let Some(m) = self.mdio.as_ref().filter(|_| attr == 0 && level == 0) {
            // The variable's chunks under voxels c B - 1 ..= (c + 1) B, clamped.
            let ch = &m.data.chunks;
            let span = |a: usize| {
                let lo = (c[a] * b).saturating_sub(1).min(n[a] - 1);
                let hi = ((c[a] + 1) * b).min(n[a] - 1);
                let per = ch[2 - a] as usize;
                (lo / per)..=(hi / per)
            };
            for k in span(2) {
                for j in span(1) {
                    for i in span(0) {
                        files.push(m.data.chunk_file(&[k as u64, j as u64, i as u64]));
                    }
                }
            }
            return files;
        }
        let counts = self.meta.brick_counts(level);
        for dz in 0..3 {
            for dy in 0..3 {
                for dx in 0..3 {
                    let cc = [c[0] + dx, c[1] + dy, c[2] + dz].map(|v| v.wrapping_sub(1));
                    if (0..3).all(|a| cc[a] < counts[a]) && cc != c {
                        files.push(self.chunk_file(attr, level, cc));
                    }
                }
            }
        }
        files
    }

    /// Chunk `c` (`[i, j, k]` brick indices) of `attr` at `level`: `B³` values, i fastest
    /// (edge chunks padded with 0 beyond the level's voxels).
    pub fn chunk(
        &self,
        attr: usize,
        level: usize,
        c: [usize; 3],
    ) -> Result<Arc<Vec<f32>>, StoreError> {
        let key = (attr, level, c);
        if let Some(hit) = self.cache.lock().expect("chunk cache").get(&key) {
            return Ok(hit);
        }
        let index = [c[2] as u64, c[1] as u64, c[0] as u64];
        let fail = |message: String| StoreError::Chunk {
            path: self.chunk_file(attr, level, c),
            array: Store::array_path(&self.meta, attr, level)[1..].to_string(),
            chunk: index,
            message,
        };
        let counts = self.meta.brick_counts(level);
        if (0..3).any(|a| c[a] >= counts[a]) {
            return Err(fail(format!(
                "outside the level's {counts:?} bricks (sample, crossline, inline)"
            )));
        }
        if let Some(m) = &self.mdio {
            if attr == 0 && level == 0 {
                // A chunk that fails names its own file and index.
                let brick = m.brick(self.meta.dims, self.meta.brick, c);
                let values = Arc::new(brick.map_err(|f| f.into_error(&m.variable()))?);
                self.cache
                    .lock()
                    .expect("chunk cache")
                    .put(key, values.clone());
                return Ok(values);
            }
            if self.arrays.is_empty() {
                return Err(fail(
                    "an MDIO dataset read in place has one attribute and one level".into(),
                ));
            }
        }
        let array = &self.arrays[attr][level];
        let values = match array.read_chunk(&index).map_err(|e| fail(e.to_string()))? {
            Some(values) => values,
            None => {
                self.absent_chunk_is_fill(attr, level, c).map_err(fail)?;
                vec![array.fill_value as f32; array.chunk_elements()]
            }
        };
        let values = Arc::new(values);
        self.cache
            .lock()
            .expect("chunk cache")
            .put(key, values.clone());
        Ok(values)
    }

    /// Why an absent chunk may not be read as the fill value, if it may not: a store
    /// being converted (its chunks are all written before their column is logged), or a
    /// brick whose recorded range is not the fill value's.
    fn absent_chunk_is_fill(&self, attr: usize, level: usize, c: [usize; 3]) -> Result<(), String> {
        if self.incomplete {
            return Err("missing, though the conversion wrote it: the store is damaged (convert again into a new store)".into());
        }
        let ranges = self.range_table(attr, level).map_err(|e| e.to_string())?;
        let counts = self.meta.brick_counts(level);
        let r = ranges[c[0] + counts[0] * (c[1] + counts[1] * c[2])];
        let fill = self.arrays[attr][level].fill_value as f32;
        let only_fill = r[0].is_nan() || (r[0] == fill && r[1] == fill);
        if only_fill {
            Ok(())
        } else {
            Err(format!(
                "missing, but the store's ranges say it holds values in [{}, {}]: the store is damaged (convert again into a new store)",
                r[0], r[1]
            ))
        }
    }

    /// The first file of the store's own nodes (its level groups, and their arrays' and
    /// per-brick ranges' chunks; an MDIO dataset's variable is not the store's) that is
    /// missing: every one of a finished conversion is written, so one missing is damage.
    pub fn missing_file(&self) -> Option<PathBuf> {
        let first_level = usize::from(self.meta.source_variable.is_some());
        for level in 1..self.meta.levels {
            let group = self.path.join(format!("level_{level}/zarr.json"));
            if !crate::fetch::exists(&group) {
                return Some(group);
            }
        }
        for (attr, levels) in self.arrays.iter().enumerate() {
            for (level, array) in levels.iter().enumerate().skip(first_level) {
                // The ranges: one chunk of every brick's pair.
                let ranges = self.range_arrays[attr][level].chunk_file(&[0, 0, 0, 0]);
                if !crate::fetch::exists(&ranges) {
                    return Some(ranges);
                }
                let c = self.meta.brick_counts(level);
                for k in 0..c[2] as u64 {
                    for j in 0..c[1] as u64 {
                        for i in 0..c[0] as u64 {
                            let file = array.chunk_file(&[k, j, i]);
                            if !crate::fetch::exists(&file) {
                                return Some(file);
                            }
                        }
                    }
                }
            }
        }
        None
    }

    /// Per-brick `[min, max]` of `attr` at `level`, i fastest.
    pub fn ranges(&self, attr: usize, level: usize) -> Result<Vec<[f32; 2]>, StoreError> {
        Ok(self.range_table(attr, level)?.as_ref().clone())
    }

    fn range_table(&self, attr: usize, level: usize) -> Result<Arc<Vec<[f32; 2]>>, StoreError> {
        if let Some(t) = self
            .ranges
            .lock()
            .expect("range tables")
            .get(&(attr, level))
        {
            return Ok(t.clone());
        }
        if self.mdio.is_some() && self.arrays.is_empty() {
            // No per-brick ranges: every brick may hold the whole range.
            let a = &self.meta.attributes[attr];
            let range = [
                a.min.map_or(f32::MIN, |v| v as f32),
                a.max.map_or(f32::MAX, |v| v as f32),
            ];
            let n = self.meta.brick_counts(level).iter().product::<usize>();
            return Ok(Arc::new(vec![range; n]));
        }
        let array = &self.range_arrays[attr][level];
        let file = array.chunk_file(&[0, 0, 0, 0]);
        let values = array
            .read_chunk(&[0, 0, 0, 0])
            .map_err(|e| StoreError::invalid(&file, e.to_string()))?
            .ok_or_else(|| StoreError::invalid(&file, "the brick ranges are missing"))?;
        let table: Vec<[f32; 2]> = values.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        let table = Arc::new(table);
        self.ranges
            .lock()
            .expect("range tables")
            .insert((attr, level), table.clone());
        Ok(table)
    }

    /// The values of `attr` at `level` over the box `lo .. lo + size` (voxel indices, i
    /// fastest), positions outside the level clamped to its faces.
    pub fn region(
        &self,
        attr: usize,
        level: usize,
        lo: [i64; 3],
        size: [usize; 3],
    ) -> Result<Vec<f32>, StoreError> {
        let n = self.meta.level_dims(level);
        let b = self.meta.brick;
        let count = size.iter().product::<usize>();
        let mut out = arbvis_core::budget::vec_for::<f32>(count, "a region of a store")
            .map_err(|e| StoreError::Budget(e.to_string()))?;
        out.resize(count, 0.0);
        let clamp = |v: i64, a: usize| v.clamp(0, n[a] as i64 - 1) as usize;
        // Per axis and output index: the chunk and the voxel within it (the source voxel
        // clamped to the level's faces).
        let src: [Vec<(usize, usize)>; 3] = std::array::from_fn(|a| {
            (0..size[a])
                .map(|t| {
                    let v = clamp(lo[a] + t as i64, a);
                    (v / b, v % b)
                })
                .collect()
        });
        // The chunks a row of the box crosses, fetched when the row's (j, k) chunk changes.
        let first = src[0].first().map_or(0, |c| c.0);
        let last = src[0].last().map_or(0, |c| c.0);
        let mut key = (usize::MAX, usize::MAX);
        let mut row_chunks: Vec<Arc<Vec<f32>>> = Vec::new();
        for (z, &(ck, vk)) in src[2].iter().enumerate() {
            for (y, &(cj, vj)) in src[1].iter().enumerate() {
                if key != (cj, ck) {
                    key = (cj, ck);
                    row_chunks = (first..=last)
                        .map(|ci| self.chunk(attr, level, [ci, cj, ck]))
                        .collect::<Result<_, _>>()?;
                }
                let row = &mut out[size[0] * (y + size[1] * z)..][..size[0]];
                let plane = b * (vj + b * vk);
                for (o, &(ci, vi)) in row.iter_mut().zip(&src[0]) {
                    *o = row_chunks[ci - first][vi + plane];
                }
            }
        }
        Ok(out)
    }

    /// Brick `c` of `attr` at `level` grown by one voxel on each side: `(B+2)³` values, i
    /// fastest, the voxels `c B - 1 ..= (c + 1) B` clamped to the level. Only the brick's
    /// own chunk must be readable: where a neighbour's chunk is missing or corrupt, the
    /// border repeats the brick's own edge (as at the survey's faces), so one bad chunk
    /// costs one brick.
    pub fn brick(&self, attr: usize, level: usize, c: [usize; 3]) -> Result<Vec<f32>, StoreError> {
        let b = self.meta.brick;
        let n = self.meta.level_dims(level);
        let own = self.chunk(attr, level, c)?;
        let side = b + 2;
        let mut out = vec![0f32; side * side * side];
        // Own voxels present: c B .. min((c + 1) B, n) - 1 per axis.
        let own_hi: [usize; 3] = std::array::from_fn(|a| ((c[a] + 1) * b).min(n[a]) - 1);
        // Per axis and texel: which neighbour (0 below, 1 own, 2 above) and the voxel
        // within its chunk, or (where that chunk cannot be read) within the own chunk.
        let axis = |a: usize| -> Vec<(usize, usize, usize)> {
            (0..side)
                .map(|t| {
                    let g = ((c[a] * b + t) as i64 - 1).clamp(0, n[a] as i64 - 1) as usize;
                    let d = (g / b + 1).saturating_sub(c[a]).min(2);
                    (d, g % b, g.clamp(c[a] * b, own_hi[a]) % b)
                })
                .collect()
        };
        let (ax, ay, az) = (axis(0), axis(1), axis(2));
        // The 27 chunks around the own one, read when a texel needs them.
        let mut near: [Option<Option<Arc<Vec<f32>>>>; 27] = std::array::from_fn(|_| None);
        near[13] = Some(Some(own.clone()));
        for (z, &(dz, kz, oz)) in az.iter().enumerate() {
            for (y, &(dy, ky, oy)) in ay.iter().enumerate() {
                let row = side * (y + side * z);
                for (x, &(dx, kx, ox)) in ax.iter().enumerate() {
                    let slot = dx + 3 * (dy + 3 * dz);
                    let chunk = near[slot].get_or_insert_with(|| {
                        let cc = [c[0] + dx, c[1] + dy, c[2] + dz].map(|v| v.wrapping_sub(1));
                        self.chunk(attr, level, cc).ok()
                    });
                    out[x + row] = match chunk {
                        Some(ch) => ch[kx + b * (ky + b * kz)],
                        None => own[ox + b * (oy + b * oz)],
                    };
                }
            }
        }
        Ok(out)
    }

    /// Level 0 of `attr` over voxels `lo .. hi` as a volume (held to the memory budget).
    pub fn window(
        &self,
        attr: usize,
        lo: [usize; 3],
        hi: [usize; 3],
    ) -> Result<Volume, StoreError> {
        let size: [usize; 3] = std::array::from_fn(|a| hi[a].saturating_sub(lo[a]).max(1));
        let values = self.region(attr, 0, lo.map(|v| v as i64), size)?;
        Volume::new(size, self.meta.spacing, values)
            .map_err(|e| StoreError::invalid(&self.path, e.to_string()))
    }

    /// Index of attribute `name`, or an error listing the stored ones.
    pub fn attribute_index(&self, name: &str) -> Result<usize, StoreError> {
        self.meta.attribute(name).map(|(i, _)| i).ok_or_else(|| {
            StoreError::invalid(
                &self.path,
                format!(
                    "no attribute {name:?}; the store holds {}",
                    self.meta
                        .attributes
                        .iter()
                        .map(|a| a.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })
    }
}
