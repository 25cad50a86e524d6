//! The GPU brick cache: a fixed number of brick textures (the texture-memory budget over
//! one brick's bytes), filled by a loader thread so that a frame never waits for the disk,
//! least recently used out first.
//!
//! # How it works
//! - The renderer asks for the bricks its view wants, most urgent first
//!   ([`BrickCache::request`]); the loader thread works through the newest list, reads each
//!   brick of each attribute with its one-voxel border ([`arbvis_data::store::Store::brick`]), quantizes
//!   and packs it ([`Packing`]) and sends the texels back.
//! - Each frame the renderer takes what has arrived ([`BrickCache::receive`], at most a
//!   few bricks a frame, so an upload never stalls a frame) and uploads it into a free
//!   slot, or into the least recently used slot not drawn this frame.
//! - A brick that fails to load (a missing or corrupt chunk) is remembered with its error
//!   and never asked for again; the renderer draws its nearest resident ancestor instead.
//! - [`BrickCache::ensure`] is the blocking form for offscreen renders: it waits until the
//!   given bricks are resident (or failed).
//!
//! Two layouts of the slots: one texture per brick ([`BrickCache::new`], what the faithful
//! brick-by-brick renderer binds, one brick a draw, as 2004's bricked renderers did), or
//! one atlas texture of slots ([`BrickCache::atlas`], the INDEX-DATA layout of
//! [`arbvis_data::volume::index_data`], which the precise one-pass ray caster reads through its
//! page table).
//!
//! The renderers see only resident bricks: [`BrickCache::texture`] or
//! [`BrickCache::slot`] of a brick id.

use crate::error::{RenderError, RenderResult};
use std::collections::{HashMap, HashSet};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use arbvis_data::store::lod::BrickId;
use arbvis_data::store::reader::Store;
use arbvis_data::store::StoreError;
use arbvis_data::volume::index_data::SlotGrid;
use arbvis_data::volume::quantize::{quantize_level, NoData};
use arbvis_gl::{Extent, Filter, Gpu, TexelData, TexelFormat, Texture};

/// How a brick's attributes become texels: per texture channel (R, G, B), the store's
/// attribute and its quantization range (v3o2: G primary, B secondary, R tertiary).
#[derive(Debug, Clone, PartialEq)]
pub struct Packing {
    /// Per channel R, G, B: `(attribute index in the store, low, high, what NaN becomes)`,
    /// or none (0).
    pub channels: [Option<(usize, f64, f64, NoData)>; 3],
}

impl Packing {
    /// Bytes of one packed brick of side `side`.
    pub fn brick_bytes(side: usize) -> usize {
        side * side * side * 3
    }
}

/// Counts for `--stats` and the viewer.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CacheStats {
    /// Bricks resident now.
    pub resident: usize,
    /// Resident bricks per level.
    pub per_level: Vec<usize>,
    /// Texture bytes of the resident bricks.
    pub bytes: u64,
    /// Slots (the budget in bricks).
    pub capacity: usize,
    /// Bricks uploaded since the start.
    pub uploaded: u64,
    /// Bricks evicted since the start.
    pub evicted: u64,
    /// Bricks asked for and not yet back.
    pub loading: usize,
    /// Bricks that could not be read, with the first error.
    pub failed: usize,
    /// The first load error, if any.
    pub first_error: Option<String>,
}

enum Reply {
    Loaded(BrickId, Vec<u8>),
    Failed(BrickId, StoreError),
}

struct Slot {
    /// The brick's own texture (none in an atlas).
    texture: Option<Texture>,
    brick: Option<BrickId>,
    used: u64,
}

/// An atlas's texture (made at the first upload) and its slot layout.
struct Atlas {
    texture: Option<Texture>,
    grid: SlotGrid,
}

/// The cache.
pub struct BrickCache {
    side: usize,
    capacity: usize,
    slots: Vec<Slot>,
    resident: HashMap<BrickId, usize>,
    asked: HashSet<BrickId>,
    failed: HashMap<BrickId, Arc<StoreError>>,
    frame: u64,
    requests: Option<Sender<Vec<BrickId>>>,
    replies: Receiver<Reply>,
    thread: Option<JoinHandle<()>>,
    filter: Filter,
    format: TexelFormat,
    uploaded: u64,
    evicted: u64,
    levels: usize,
    atlas: Option<Atlas>,
}

impl BrickCache {
    /// A cache of `budget` bytes of brick textures for `store`'s bricks packed by
    /// `packing` (at least one brick).
    pub fn new(store: Arc<Store>, packing: Packing, budget: u64, filter: Filter) -> BrickCache {
        let side = store.meta.brick + 2;
        let capacity = (budget / Packing::brick_bytes(side) as u64).max(1) as usize;
        let levels = store.meta.levels;
        let (req_tx, req_rx) = channel::<Vec<BrickId>>();
        let (rep_tx, rep_rx) = channel::<Reply>();
        let thread = std::thread::Builder::new()
            .name("arbvis brick loader".into())
            .spawn(move || loader(store, packing, req_rx, rep_tx))
            .ok();
        BrickCache {
            side,
            capacity,
            slots: Vec::new(),
            resident: HashMap::new(),
            asked: HashSet::new(),
            failed: HashMap::new(),
            frame: 0,
            requests: Some(req_tx),
            replies: rep_rx,
            thread,
            filter,
            format: TexelFormat::Rgb8,
            uploaded: 0,
            evicted: 0,
            levels,
            atlas: None,
        }
    }

    /// A cache whose slots share one atlas texture of 16-bit unorm texels (the same
    /// 8-bit levels, filtered in float, as the precise volume): the budget's slots (at
    /// that texel size), at most `most` (the bricks there are), in a near-cubic grid
    /// within `max_side` texels per axis (fewer slots when the budget's do not fit).
    pub fn atlas(
        store: Arc<Store>,
        packing: Packing,
        budget: u64,
        filter: Filter,
        max_side: usize,
        most: usize,
    ) -> BrickCache {
        // 16-bit texels are twice the RGB8 slot's bytes.
        let mut cache = BrickCache::new(store, packing, budget / 2, filter);
        cache.format = TexelFormat::Rgb16FromU8;
        let side = cache.side;
        let cap = (max_side / side).max(1);
        let count = cache.capacity.min(most.max(1)).min(cap.pow(3));
        // `count` fits by construction (at most cap³ slots of `side` in `max_side`).
        let grid = SlotGrid::arrange(count, side, max_side).unwrap_or(SlotGrid {
            slots: [1, 1, 1],
            side,
        });
        cache.capacity = count;
        cache.atlas = Some(Atlas {
            texture: None,
            grid,
        });
        cache
    }

    /// The atlas texture (once a brick is resident) and its slot layout.
    pub fn atlas_texture(&self) -> Option<(&Texture, SlotGrid)> {
        let a = self.atlas.as_ref()?;
        Some((a.texture.as_ref()?, a.grid))
    }

    /// The atlas slot of resident brick `id`, marked used in this frame.
    pub fn slot(&mut self, id: BrickId) -> Option<usize> {
        let s = *self.resident.get(&id)?;
        self.slots[s].used = self.frame;
        Some(s)
    }

    /// Bricks the budget holds.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Start a frame: bricks drawn from now on count as used in it.
    pub fn begin_frame(&mut self) {
        self.frame += 1;
    }

    /// Whether `id` is resident.
    pub fn is_resident(&self, id: BrickId) -> bool {
        self.resident.contains_key(&id)
    }

    /// Whether `id` failed to load.
    pub fn has_failed(&self, id: BrickId) -> bool {
        self.failed.contains_key(&id)
    }

    /// The texture of resident brick `id`, marked used in this frame.
    pub fn texture(&mut self, id: BrickId) -> Option<&Texture> {
        let s = *self.resident.get(&id)?;
        self.slots[s].used = self.frame;
        self.slots[s].texture.as_ref()
    }

    /// Mark `id` used in this frame (kept over older bricks).
    pub fn touch(&mut self, id: BrickId) {
        if let Some(&s) = self.resident.get(&id) {
            self.slots[s].used = self.frame;
        }
    }

    /// Ask for `wanted` (most urgent first), replacing any earlier list; resident, failed
    /// and already-asked bricks are left out.
    pub fn request(&mut self, wanted: &[BrickId]) {
        let new: Vec<BrickId> = wanted
            .iter()
            .copied()
            .filter(|id| {
                !self.resident.contains_key(id)
                    && !self.failed.contains_key(id)
                    && !self.asked.contains(id)
            })
            .collect();
        if new.is_empty() {
            return;
        }
        self.asked.extend(new.iter().copied());
        if let Some(tx) = &self.requests {
            let _ = tx.send(new);
        }
    }

    /// Upload bricks that have arrived (without waiting) until `time` has passed;
    /// returns how many.
    pub fn receive(&mut self, gpu: &Gpu, time: Duration) -> RenderResult<usize> {
        let start = std::time::Instant::now();
        let mut n = 0;
        while n == 0 || start.elapsed() < time {
            match self.replies.try_recv() {
                Ok(reply) => {
                    self.take(gpu, reply)?;
                    n += 1;
                }
                Err(_) => break,
            }
        }
        Ok(n)
    }

    /// Wait until every brick of `ids` is resident or failed (asking for the missing ones);
    /// `ids` must fit the cache.
    pub fn ensure(&mut self, gpu: &Gpu, ids: &[BrickId]) -> RenderResult<()> {
        for &id in ids {
            self.touch(id);
        }
        self.request(ids);
        loop {
            let done = ids
                .iter()
                .all(|id| self.resident.contains_key(id) || self.failed.contains_key(id));
            if done {
                return Ok(());
            }
            match self.replies.recv_timeout(Duration::from_secs(600)) {
                Ok(reply) => {
                    let id = match &reply {
                        Reply::Loaded(id, _) | Reply::Failed(id, _) => *id,
                    };
                    self.take(gpu, reply)?;
                    self.touch(id);
                }
                Err(_) => return Err(RenderError::Stalled("the brick loader stopped answering")),
            }
        }
    }

    fn take(&mut self, gpu: &Gpu, reply: Reply) -> RenderResult<()> {
        match reply {
            Reply::Failed(id, e) => {
                self.asked.remove(&id);
                self.failed.insert(id, Arc::new(e));
                Ok(())
            }
            Reply::Loaded(id, texels) => {
                self.asked.remove(&id);
                if self.resident.contains_key(&id) {
                    return Ok(());
                }
                let Some(slot) = self.free_slot(gpu)? else {
                    // Every slot is in use by this frame: drop it (asked again later).
                    return Ok(());
                };
                match (&self.slots[slot].texture, &self.atlas) {
                    (Some(t), _) => t.update(gpu, &texels)?,
                    (
                        None,
                        Some(Atlas {
                            texture: Some(t),
                            grid,
                        }),
                    ) => t.update_region(gpu, grid.slot_corner(slot), [self.side; 3], &texels)?,
                    (None, _) => {}
                }
                if let Some(old) = self.slots[slot].brick.replace(id) {
                    self.resident.remove(&old);
                    self.evicted += 1;
                }
                self.slots[slot].used = self.frame;
                self.resident.insert(id, slot);
                self.uploaded += 1;
                Ok(())
            }
        }
    }

    /// A new slot while under the budget, else the least recently used one not drawn
    /// this frame.
    fn free_slot(&mut self, gpu: &Gpu) -> RenderResult<Option<usize>> {
        if self.slots.len() < self.capacity {
            let s = self.side as u32;
            let texture = match &mut self.atlas {
                Some(atlas) => {
                    if atlas.texture.is_none() {
                        atlas.texture = Some(Texture::empty_3d(
                            gpu,
                            &format!("store brick atlas of {:?} slots", atlas.grid.slots),
                            atlas.grid.texels(),
                            self.format,
                            self.filter,
                        )?);
                    }
                    None
                }
                None => Some(Texture::new(
                    gpu,
                    &format!("store brick slot {}", self.slots.len()),
                    Extent::D3(s, s, s),
                    TexelFormat::Rgb8,
                    self.filter,
                    TexelData::U8(&vec![0u8; Packing::brick_bytes(self.side)]),
                )?),
            };
            self.slots.push(Slot {
                texture,
                brick: None,
                used: 0,
            });
            return Ok(Some(self.slots.len() - 1));
        }
        Ok(self
            .slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.used < self.frame)
            .min_by_key(|(_, s)| s.used)
            .map(|(i, _)| i))
    }

    /// The first load error of `id`.
    pub fn error(&self, id: BrickId) -> Option<Arc<StoreError>> {
        self.failed.get(&id).cloned()
    }

    /// Counts for `--stats` and the viewer.
    pub fn stats(&self) -> CacheStats {
        let mut per_level = vec![0; self.levels];
        for id in self.resident.keys() {
            if let Some(c) = per_level.get_mut(id.level as usize) {
                *c += 1;
            }
        }
        CacheStats {
            resident: self.resident.len(),
            per_level,
            bytes: (self.resident.len() * self.side.pow(3) * self.format.bytes()) as u64,
            capacity: self.capacity,
            uploaded: self.uploaded,
            evicted: self.evicted,
            loading: self.asked.len(),
            failed: self.failed.len(),
            first_error: self.failed.values().next().map(|e| e.to_string()),
        }
    }
}

impl Drop for BrickCache {
    fn drop(&mut self) {
        self.requests = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Read and pack one brick: each channel's attribute with its border, quantized.
pub fn pack_brick(store: &Store, packing: &Packing, id: BrickId) -> Result<Vec<u8>, StoreError> {
    let side = store.meta.brick + 2;
    let mut texels = vec![0u8; Packing::brick_bytes(side)];
    let c = id.c.map(|x| x as usize);
    for (ch, p) in packing.channels.iter().enumerate() {
        let Some((attr, low, high, no_data)) = *p else {
            continue;
        };
        let values = store.brick(attr, id.level as usize, c)?;
        for (t, &v) in texels.chunks_exact_mut(3).zip(&values) {
            t[ch] = quantize_level(v, low, high, no_data);
        }
    }
    Ok(texels)
}

/// Bricks whose chunks a remote store fetches ahead of the one being read.
const PREFETCH_BRICKS: usize = 64;

/// Start fetching the chunks of the next bricks in `queue` (a remote store's; the
/// ones fetched or on their way are passed over).
fn prefetch_ahead(store: &Store, packing: &Packing, queue: &[BrickId]) {
    let attrs: Vec<usize> = packing.channels.iter().flatten().map(|p| p.0).collect();
    let bricks: Vec<(usize, usize, [usize; 3])> = queue
        .iter()
        .take(PREFETCH_BRICKS)
        .flat_map(|id| {
            let c = id.c.map(|x| x as usize);
            attrs.iter().map(move |&a| (a, id.level as usize, c))
        })
        .collect();
    store.prefetch(&bricks);
}

fn loader(
    store: Arc<Store>,
    packing: Packing,
    requests: Receiver<Vec<BrickId>>,
    replies: Sender<Reply>,
) {
    let mut queue: Vec<BrickId> = Vec::new();
    loop {
        // Take the newest list (older ones are superseded), waiting when idle.
        if queue.is_empty() {
            match requests.recv() {
                Ok(list) => queue = list,
                Err(_) => return,
            }
        }
        while let Ok(list) = requests.try_recv() {
            // Newer asks first (the cache never asks twice for a brick on its way), then
            // what the older lists still hold.
            queue = list.into_iter().chain(queue.drain(..)).collect();
        }
        prefetch_ahead(&store, &packing, &queue);
        let id = queue.remove(0);
        let reply = match pack_brick(&store, &packing, id) {
            Ok(t) => Reply::Loaded(id, t),
            Err(e) => Reply::Failed(id, e),
        };
        if replies.send(reply).is_err() {
            return;
        }
    }
}
