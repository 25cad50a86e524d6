//! `arbvis convert SURVEY STORE`: a survey (SEG-Y, NIfTI-1, raw) to a store.
//!
//! # How it works
//! 1. Level 0 in columns: the survey is cut into columns of `B x B` traces (every sample
//!    of `B` crosslines and `B` inlines); each column is read ([`super::input`]), its
//!    derived attributes computed trace by trace (one analytic signal per trace gives
//!    envelope, phase and frequency, [`crate::volume::attributes::derive_trace`]), cut
//!    into its `ceil(samples / B)` bricks, and each brick written as a zarr chunk of
//!    every attribute. Columns go in quads of 2 x 2, one level-1 column's worth: each
//!    column's quarter of it is filtered while the column is in memory, and the level-1
//!    column written after the quad's fourth (for an even `B`, where no 2x2x2 cell
//!    straddles two columns). Quads run in parallel (rayon, two workers per core: one
//!    computes while the other waits on the disk).
//! 2. Levels 2, 3, ... (and level 1 where a quad could not give it: an odd `B`, a resumed
//!    quad): each brick of level `L` is filtered from the (up to) eight bricks of level
//!    `L - 1` below it, read back from the store; again in columns, in parallel. Columns
//!    are made in `columns`; the filter and the statistics are `filter`'s, the same on
//!    both paths, so a level is the same bit for bit whichever path made it.
//! 3. The per-brick ranges and each attribute's statistics are written, and the group's
//!    `complete` flag set.
//!
//! # Resuming
//! Every finished column appends one line to `STORE/arbvis-progress.log` (after its
//! chunks are written and synced) with its bricks' ranges and its statistics; the first
//! line describes the job (the input's path, length and modification time, and the
//! options). Running the same command again skips the columns the log lists and redoes
//! any other (a chunk half-written when the process died is written again); another
//! input or other options are refused. The log is removed when the store is complete.
//!
//! # Memory
//! Each worker holds one column: `samples x B² x (1 + derived attributes)` f32 plus the
//! transform's f64 buffers (`samples x 48` bytes), its quad's level-1 column (`samples /
//! 2 x B²` per attribute) and one brick per attribute while encoding; a level brick
//! reads eight chunks. With `W` workers the conversion holds about `W x samples x B² x 4
//! x (1.5 attributes + 1)` bytes, whatever the number of traces
//! ([`memory_bound`]); the reader's chunk cache adds 64 chunks. The bound is checked
//! against the memory budget before anything is written.

use std::collections::{BTreeMap, HashMap};
use std::fs::OpenOptions;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use rayon::prelude::*;
use zarrs::array::{Array, CodecOptions};
use zarrs::filesystem::FilesystemStore;

use super::columns::{Ctx, Log};
use super::input::Input;
use super::layout;
use super::meta::{AttributeMeta, StoreMeta, FORMAT, VERSION};
use super::progress::{holds_nothing, read_log, start_log, Job, StoreLock, Unit};
use super::reader::Store;
use super::StoreError;
use crate::volume::attributes::Attribute;
use crate::volume::raw::RawSpec;

pub use super::compression::Compression;
pub use super::progress::{Watch, PROGRESS_LOG};

/// How to convert.
#[derive(Debug, Clone)]
pub struct ConvertOptions {
    /// Brick side in voxels (the chunk shape).
    pub brick: usize,
    /// Derived attributes to compute (amplitude is always stored).
    pub derived: Vec<Attribute>,
    /// How chunks are compressed.
    pub compression: Compression,
    /// A raw input's description.
    pub raw: Option<RawSpec>,
    /// A SEG-Y input's inline and crossline bytes, where named (else detected).
    pub segy_keys: crate::volume::segy::KeyBytes,
    /// Draw a progress bar (when stderr is a terminal).
    pub progress: bool,
    /// Told after every column written: (columns of the store done, all its columns);
    /// false stops the conversion as an interruption (running it again resumes).
    pub watch: Option<Watch>,
    /// For tests: stop with [`StoreError::Interrupted`] once this many columns are done
    /// in this run, as a killed process would.
    pub stop_after: Option<usize>,
}

impl Default for ConvertOptions {
    fn default() -> Self {
        ConvertOptions {
            brick: 64,
            // Amplitude and envelope: what v3o2's displays start from, worth the disk and
            // conversion time they cost beyond amplitude alone; phase and frequency, each
            // costing more again, on request (measured: docs/benchmarks.md, "Figures
            // behind the store's settings").
            derived: vec![Attribute::Envelope],
            compression: Compression::default(),
            raw: None,
            segy_keys: Default::default(),
            progress: true,
            watch: None,
            stop_after: None,
        }
    }
}

/// What a conversion did.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvertReport {
    /// Columns written in this run (all levels).
    pub written: usize,
    /// Columns found done by an earlier run.
    pub resumed: usize,
    /// Bytes of the input read.
    pub bytes_read: u64,
    /// Seconds.
    pub seconds: f64,
    /// The store's description.
    pub meta: StoreMeta,
}

/// Bytes the conversion holds at once with `workers` workers (see the module doc).
pub fn memory_bound(samples: usize, brick: usize, attributes: usize, workers: usize) -> u64 {
    let column = samples as u64 * (brick * brick) as u64 * 4 * (attributes as u64 + 1);
    // The level-1 column its quad fills: half the samples, every attribute.
    let above = samples.div_ceil(2) as u64 * (brick * brick) as u64 * 4 * attributes as u64;
    let fft = samples as u64 * 48;
    let cache = super::reader::CHUNK_CACHE as u64 * (brick as u64).pow(3) * 4;
    workers as u64 * (column + above + fft + 9 * (brick as u64).pow(3) * 4) + cache
}

/// The zarr data type name of an attribute: float32 for amplitude and envelope (any
/// range), float16 for the bounded ones (phase within ±180, frequency within ±0.5,
/// cosine within ±1).
pub fn dtype(a: Attribute) -> &'static str {
    match a {
        Attribute::Amplitude | Attribute::Envelope => "float32",
        _ => "float16",
    }
}

/// The length and modification time (seconds) of the file that stands for the input; of
/// a remote one, its length and a hash of its ETag (a rewritten object is a new input).
fn identity_of(identity: &Path) -> Result<(u64, u64), StoreError> {
    if crate::fetch::url_of(identity).is_some() {
        let bytes = crate::fetch::read_object(identity, super::zarr::MAX_METADATA_BYTES)
            .map_err(|e| StoreError::io(identity, e))?
            .map_or(0, |b| b.len() as u64);
        let etag = crate::fetch::version(identity).unwrap_or_default();
        let mut h = std::collections::hash_map::DefaultHasher::new();
        std::hash::Hash::hash(&etag, &mut h);
        return Ok((bytes, std::hash::Hasher::finish(&h) >> 12));
    }
    let m = std::fs::metadata(identity).map_err(|e| StoreError::io(identity, e))?;
    let modified = m
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_secs());
    Ok((m.len(), modified))
}

/// The job: the input (its length and time taken from `identity`, the file that stands
/// for it: an MDIO dataset's variable's `zarr.json`) and the options.
fn job_of(
    input: &Path,
    identity: &Path,
    o: &ConvertOptions,
    attributes: &[Attribute],
) -> Result<Job, StoreError> {
    let (bytes, modified) = identity_of(identity)?;
    let input = std::fs::canonicalize(input).unwrap_or_else(|_| input.to_path_buf());
    Ok(Job {
        input: input.display().to_string(),
        bytes,
        modified,
        brick: o.brick,
        attributes: attributes.iter().map(|a| a.name().to_string()).collect(),
        compression: o.compression.to_string(),
        legacy_zstd: None,
        raw: o.raw.as_ref().map(|r| format!("{r:?}")),
        layout: VERSION,
    })
}

/// Convert `input` into a new store at `store`, or resume an interrupted conversion there.
///
/// Columns run on two workers per rayon thread (one per core unless `RAYON_NUM_THREADS`
/// says otherwise): each chunk write waits for the disk (synced), and a second worker per
/// core computes meanwhile, which converted faster than one worker per core (measured:
/// docs/benchmarks.md, "Figures behind the store's settings"). Where twice the workers'
/// memory would pass the budget, one per thread.
pub fn convert(
    input: &Path,
    store: &Path,
    o: &ConvertOptions,
) -> Result<ConvertReport, StoreError> {
    // A URL as every front end hands it (a Python str, a CLI argument): read as a URL.
    let input = &crate::fetch::local_or_url(input);
    if crate::fetch::url_of(store).is_some() {
        return Err(StoreError::invalid(
            store,
            "convert writes a store to a local folder (copy it to object storage with the bucket's own tools: aws s3 sync, rclone)",
        ));
    }
    let threads = rayon::current_num_threads().max(1);
    let on = |workers: usize| match rayon::ThreadPoolBuilder::new().num_threads(workers).build() {
        Ok(pool) => pool.install(|| convert_on_workers(input, store, o)),
        Err(_) => convert_on_workers(input, store, o),
    };
    // The budget is checked before anything is written: a refusal leaves nothing behind.
    match on(2 * threads) {
        Err(StoreError::Budget(_)) => on(threads),
        done => done,
    }
}

/// [`convert`] on the workers of the rayon pool it runs in.
fn convert_on_workers(
    input: &Path,
    store: &Path,
    o: &ConvertOptions,
) -> Result<ConvertReport, StoreError> {
    let start = Instant::now();
    if !(2..=512).contains(&o.brick) {
        return Err(StoreError::invalid(
            store,
            format!("brick {}: must be 2..=512 voxels", o.brick),
        ));
    }
    let attributes = attributes_of(o);
    let plan = Plan::new(input, store, o, &attributes)?;
    let meta = plan.meta(o, &attributes);
    let log_path = store.join(PROGRESS_LOG);
    // One writer at a time; the lock goes when this function returns.
    let (_lock, beside, mut done) = open_store(store, &meta, &plan, o, &log_path)?;
    let storage = Arc::new(FilesystemStore::new(store).map_err(|e| StoreError::io(store, e))?);
    // Every zarr.json, written whole (again on a resume: a kill may have cut one).
    let options = layout_options(store, o, plan.src.has_coordinates());
    let writers = layout::write_layout(&storage, store, &meta, &options, None, beside.as_ref())?;
    let log = Log {
        file: Mutex::new(
            OpenOptions::new()
                .append(true)
                .open(&log_path)
                .map_err(|e| StoreError::io(&log_path, e))?,
        ),
    };
    let resumed = done.len();
    let ctx = Ctx {
        store,
        meta: &meta,
        writers: &writers,
        attributes: &attributes,
        log: &log,
        log_path: &log_path,
        written: AtomicUsize::new(0),
        stop_after: o.stop_after,
        watch: o.watch.clone(),
        resumed,
        total: (0..meta.levels)
            .map(|l| meta.brick_counts(l)[1] * meta.brick_counts(l)[2])
            .sum(),
        bytes: AtomicU64::new(0),
    };
    let new = level_zero(&ctx, &plan.src, &done, input, o)?;
    done.extend(new.into_iter().flatten().map(|u| (u.u, u)));
    upper_levels(&ctx, &mut done)?;
    let meta = finish_store(
        &storage,
        store,
        meta.clone(),
        &done,
        &options,
        beside.as_ref(),
    )?;
    std::fs::remove_file(&log_path).map_err(|e| StoreError::io(&log_path, e))?;
    Ok(ConvertReport {
        written: ctx.written.load(Ordering::Relaxed),
        resumed,
        bytes_read: ctx.bytes.load(Ordering::Relaxed),
        seconds: start.elapsed().as_secs_f64(),
        meta,
    })
}

/// The attributes written: amplitude, then each derived one asked for, once.
fn attributes_of(o: &ConvertOptions) -> Vec<Attribute> {
    let mut attributes = vec![Attribute::Amplitude];
    for &a in &o.derived {
        if !attributes.contains(&a) {
            attributes.push(a);
        }
    }
    attributes
}

/// A conversion's input and what follows from it, checked against the budget and the
/// work it implies before anything is written.
struct Plan {
    src: Input,
    levels: usize,
    /// An MDIO dataset converted into itself: levels and ranges beside its own arrays.
    in_place: bool,
    /// The MDIO variable that is level 0 of amplitude, in place.
    source_variable: Option<String>,
    job: Job,
}

impl Plan {
    /// Open `input` for `store`.
    fn new(
        input: &Path,
        store: &Path,
        o: &ConvertOptions,
        attributes: &[Attribute],
    ) -> Result<Plan, StoreError> {
        let src = Input::open(input, o.raw.as_ref(), o.segy_keys)?;
        let dims = src.dims();
        let b = o.brick;
        let levels = super::level_count(dims, b);
        // In place: the same folder (a URL or a store not yet made is never the input).
        let same = |a: &Path, b: &Path| match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        let in_place = matches!(src, Input::Mdio(..)) && same(input, store);
        if in_place && matches!(&src, Input::Mdio(_, m) if m.source_variable.is_none()) {
            return Err(StoreError::invalid(
                input,
                "a zarr v2 dataset (MDIO v0, or v1 written with zarr format 2) cannot gain zarr v3 levels in place: convert it into a store of its own (arbvis convert DATASET STORE)",
            ));
        }
        let (identity, source_variable) = match &src {
            Input::Mdio(m, meta) => (
                m.data.metadata_file(),
                meta.source_variable.clone().filter(|_| in_place),
            ),
            _ => (input.to_path_buf(), None),
        };
        let job = job_of(input, &identity, o, attributes)?;
        let workers = rayon::current_num_threads().max(1);
        let bound = memory_bound(dims[0], b, attributes.len(), workers)
            + match &src {
                Input::Mdio(m, _) => m.cache_bytes(),
                _ => 0,
            };
        arbvis_core::budget::check(
            format!(
                "converting {} ({} samples per trace, {b}³ bricks, {} attributes, {workers} workers)",
                input.display(),
                dims[0],
                attributes.len()
            ),
            bound,
        )
        .map_err(|e| StoreError::Budget(e.to_string()))?;
        check_work(input, &src, dims, b, attributes.len())?;
        Ok(Plan {
            src,
            levels,
            in_place,
            source_variable,
            job,
        })
    }

    /// The store's metadata, incomplete (no statistics yet).
    fn meta(&self, o: &ConvertOptions, attributes: &[Attribute]) -> StoreMeta {
        let src = &self.src;
        StoreMeta {
            format: FORMAT.into(),
            version: VERSION,
            dims: src.dims(),
            spacing: src.spacing(),
            brick: o.brick,
            levels: self.levels,
            filter: "box: the mean of each 2x2x2 cell (of the voxels present at a far face of odd size); phase: the cell's first voxel".into(),
            attributes: attributes
                .iter()
                .map(|&a| AttributeMeta {
                    name: a.name().into(),
                    dtype: dtype(a).into(),
                    min: None,
                    max: None,
                    mean: None,
                    non_finite: 0,
                })
                .collect(),
            source: src.source_meta(),
            compression: o.compression.to_string(),
            complete: false,
            source_variable: self.source_variable.clone(),
        }
    }
}

/// What [`open_store`] returns: the lock held while converting, an MDIO dataset's root
/// attributes (in place), and the units already written.
type Opened = (
    StoreLock,
    Option<serde_json::Map<String, serde_json::Value>>,
    HashMap<[usize; 3], Unit>,
);

/// The store folder, made (with room on its disk) and locked, and the units done: read
/// from the progress log at `log_path` when resuming; else the log started, in a new
/// store (or in place).
fn open_store(
    store: &Path,
    meta: &StoreMeta,
    plan: &Plan,
    o: &ConvertOptions,
    log_path: &Path,
) -> Result<Opened, StoreError> {
    if store.exists() && !store.is_dir() {
        return Err(StoreError::invalid(
            store,
            "exists and is not a folder: name a new store",
        ));
    }
    std::fs::create_dir_all(store).map_err(|e| StoreError::io(store, e))?;
    check_disk(store, meta, usize::from(plan.in_place), o.progress)?;
    let lock = StoreLock::acquire(store)?;
    let beside = if plan.in_place {
        Some(mdio_root_attributes(store)?)
    } else {
        None
    };
    let done = if log_path.exists() {
        read_log(log_path, &plan.job, meta)?
    } else if plan.in_place || holds_nothing(store)? {
        // A new store, or one killed before its log existed: the log first, whole, so
        // that from here on any interruption can be resumed.
        start_log(log_path, &plan.job)?;
        HashMap::new()
    } else {
        return Err(StoreError::invalid(
            store,
            "already exists and holds no interrupted conversion: name a new store (arbvis never overwrites one)",
        ));
    };
    Ok((lock, beside, done))
}

/// The layout's options; a resumed conversion keeps the `createdOn` its first run wrote.
fn layout_options(store: &Path, o: &ConvertOptions, has_cdp: bool) -> layout::LayoutOptions {
    let created_on = super::zarr::read_json(&store.join("zarr.json"))
        .ok()
        .and_then(|root| root["attributes"]["createdOn"].as_str().map(str::to_string))
        .unwrap_or_else(layout::created_now);
    layout::LayoutOptions {
        compression: o.compression,
        has_cdp,
        created_on,
    }
}

/// Level 0 from the input, in quads of 2 x 2 columns (those not `done`): each quad also
/// gives its level-1 column, filtered in memory.
fn level_zero(
    ctx: &Ctx,
    src: &Input,
    done: &HashMap<[usize; 3], Unit>,
    input: &Path,
    o: &ConvertOptions,
) -> Result<Vec<Vec<Unit>>, StoreError> {
    let b = o.brick;
    let counts = ctx.meta.brick_counts(0);
    let (quads_j, quads_k) = (counts[1].div_ceil(2), counts[2].div_ceil(2));
    let mut quads: Vec<[usize; 2]> = (0..quads_k)
        .flat_map(|k| (0..quads_j).map(move |j| [j, k]))
        .collect();
    let columns = (0..counts[2])
        .flat_map(|k| (0..counts[1]).map(move |j| [0, j, k]))
        .filter(|u| !done.contains_key(u))
        .count();
    // An MDIO input's chunks span several columns: convert those columns one after the
    // other (in tiles of quads), so each chunk is decoded about once.
    if let Input::Mdio(m, _) = src {
        let t = m.tile(b).div_ceil(2);
        quads.sort_by_key(|q| (q[1] / t, q[0] / t, q[1] % t, q[0] % t));
    }
    let bar = progress_bar(
        o.progress,
        (columns * b * b) as u64 * src.bytes_per_trace(),
        &format!("converting {} (level 0)", input.display()),
    );
    let new: Vec<Vec<Unit>> = quads
        .par_iter()
        .map(|&q| ctx.quad(src, q, done, bar.as_ref()))
        .collect::<Result<_, _>>()?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    Ok(new)
}

/// The levels above 0, each from the one below (read back through a reader): the units
/// not `done` yet (most of level 1 comes with its quads); each one written is added.
fn upper_levels(ctx: &Ctx, done: &mut HashMap<[usize; 3], Unit>) -> Result<(), StoreError> {
    let meta = ctx.meta;
    let reader = Store::open_incomplete(ctx.store, meta.clone())?;
    for level in 1..meta.levels {
        let counts = meta.brick_counts(level);
        let units: Vec<[usize; 3]> = (0..counts[2])
            .flat_map(|k| (0..counts[1]).map(move |j| [level, j, k]))
            .filter(|u| !done.contains_key(u))
            .collect();
        let new: Vec<Unit> = units
            .par_iter()
            .map(|&u| {
                let unit = ctx.upper(&reader, u)?;
                ctx.finish(unit)
            })
            .collect::<Result<_, _>>()?;
        done.extend(new.into_iter().map(|u| (u.u, u)));
    }
    Ok(())
}

/// Bytes the store's chunks can take before compression: every brick of every attribute
/// and level, less the first `skip` attributes' level 0 (an MDIO dataset's own).
pub fn store_bytes(meta: &StoreMeta, skip: usize) -> u64 {
    let brick = (meta.brick as u64).pow(3);
    let mut total = 0u64;
    for (a, am) in meta.attributes.iter().enumerate() {
        let each = if am.dtype == "float16" { 2 } else { 4 };
        for level in 0..meta.levels {
            if level == 0 && a < skip {
                continue;
            }
            let bricks = meta.brick_counts(level).iter().product::<usize>() as u64;
            total = total.saturating_add(bricks.saturating_mul(brick * each + 8));
        }
    }
    total
}

/// Say what the conversion will write, and refuse when the store's disk has less room.
fn check_disk(store: &Path, meta: &StoreMeta, skip: usize, say: bool) -> Result<(), StoreError> {
    let need = store_bytes(meta, skip);
    let free = nix::sys::statvfs::statvfs(store)
        .ok()
        .map(|s| s.blocks_available().saturating_mul(s.fragment_size()));
    let size = arbvis_core::budget::format_bytes;
    if say {
        arbvis_core::progress::line(&format!(
            "{}: writes up to {} (before compression){}",
            store.display(),
            size(need),
            free.map_or(String::new(), |f| format!("; {} free on its disk", size(f)))
        ));
    }
    match free {
        Some(f) if f < need => Err(StoreError::invalid(
            store,
            format!(
                "the conversion writes up to {} (before compression) and its disk has {} free: free some space or name a store on another disk",
                size(need),
                size(f)
            ),
        )),
        _ => Ok(()),
    }
}

/// An MDIO dataset's root attributes, without an `arbvis` one an earlier run added; an
/// error if a finished conversion already added its levels and they are whole. Levels
/// that are damaged (an array or a chunk file missing, deleted halfway) are made again:
/// the conversion runs as the first did, over every level.
fn mdio_root_attributes(
    store: &Path,
) -> Result<serde_json::Map<String, serde_json::Value>, StoreError> {
    let file = store.join("zarr.json");
    let root = super::zarr::read_json(&file)?;
    let mut attributes = root["attributes"].as_object().cloned().unwrap_or_default();
    if let Some(a) = attributes.remove("arbvis") {
        if a["complete"].as_bool() == Some(true) {
            let damage = match super::Store::open(store) {
                Ok(opened) => opened
                    .missing_file()
                    .map(|f| format!("{} is missing", f.display())),
                Err(e) => Some(e.to_string()),
            };
            let Some(damage) = damage else {
                return Err(StoreError::invalid(
                    store,
                    "its levels and ranges were added already: the dataset opens as a store as it is",
                ));
            };
            arbvis_core::progress::line(&format!(
                "{}: the levels added earlier are damaged ({damage}): adding them again",
                store.display()
            ));
        }
    }
    Ok(attributes)
}

/// Most chunk files a conversion may write for an input of `bytes` (at least 65,536): a
/// thin volume in cubic bricks is mostly padding, and `1 x 1 x 2^21` samples in 64³ bricks
/// would be 32,768 chunks per attribute and level for 2 MB.
pub fn max_chunks(bytes: u64) -> u64 {
    (bytes / 1024).max(1 << 16)
}

/// The chunk files the store of `dims` in `brick`³ bricks holds with `attributes`.
pub fn chunk_count(dims: [usize; 3], brick: usize, attributes: usize) -> u64 {
    let levels = super::level_count(dims, brick);
    (0..levels)
        .map(|l| {
            let c = super::brick_counts(super::level_dims(dims, l), brick);
            (c[0] as u64)
                .saturating_mul(c[1] as u64)
                .saturating_mul(c[2] as u64)
        })
        .fold(0u64, u64::saturating_add)
        .saturating_mul(attributes as u64)
}

/// Refuse work that grows faster than the input: more chunk files than [`max_chunks`],
/// or chunks (before compression) of more than 64 bytes per byte of the survey.
fn check_work(
    input: &Path,
    src: &Input,
    dims: [usize; 3],
    brick: usize,
    attributes: usize,
) -> Result<(), StoreError> {
    let bytes = src
        .bytes_per_trace()
        .saturating_mul((dims[1] * dims[2]) as u64);
    let chunks = chunk_count(dims, brick, attributes);
    let most = max_chunks(bytes);
    // And at most 64 bytes of chunks (before compression) per byte of survey, at least 1 GiB.
    let padded = chunks.saturating_mul((brick as u64).pow(3) * 4);
    if chunks > most || padded > bytes.saturating_mul(64).max(1 << 30) {
        return Err(StoreError::invalid(
            input,
            format!(
                "{} x {} x {} voxels in {brick}³ bricks would make {chunks} chunk files for a {:.1} MB survey (at most {most}): bricks are cubes, so a volume this thin would be mostly padding; draw it from the file itself (a scene's {{ raw = ... }} or {{ segy = ... }} volume) instead of a store",
                dims[0], dims[1], dims[2],
                bytes as f64 / 1e6,
            ),
        ));
    }
    Ok(())
}

/// Write the ranges and statistics from every column's record, and mark the store complete.
fn finish_store(
    storage: &Arc<FilesystemStore>,
    store: &Path,
    mut meta: StoreMeta,
    done: &HashMap<[usize; 3], Unit>,
    options: &layout::LayoutOptions,
    beside: Option<&serde_json::Map<String, serde_json::Value>>,
) -> Result<StoreMeta, StoreError> {
    let mut totals: BTreeMap<usize, [f64; 3]> = BTreeMap::new();
    let mut squares: BTreeMap<usize, f64> = BTreeMap::new();
    let mut extremes: BTreeMap<usize, [f64; 2]> = BTreeMap::new();
    for a in 0..meta.attributes.len() {
        for level in 0..meta.levels {
            let c = meta.brick_counts(level);
            let mut values = vec![f32::NAN; c[0] * c[1] * c[2] * 2];
            for k in 0..c[2] {
                for j in 0..c[1] {
                    let unit = done.get(&[level, j, k]).ok_or_else(|| {
                        StoreError::invalid(
                            store,
                            format!("column {j}, {k} of level {level} was never written"),
                        )
                    })?;
                    for (i, r) in unit.ranges[a].iter().enumerate() {
                        let at = 2 * (i + c[0] * (j + c[1] * k));
                        values[at] = r[0];
                        values[at + 1] = r[1];
                        if level == 0 && r[0] <= r[1] {
                            let e = extremes
                                .entry(a)
                                .or_insert([f64::INFINITY, f64::NEG_INFINITY]);
                            e[0] = e[0].min(r[0] as f64);
                            e[1] = e[1].max(r[1] as f64);
                        }
                    }
                    if level == 0 {
                        let t = totals.entry(a).or_insert([0.0; 3]);
                        for (total, sum) in t.iter_mut().zip(unit.sums[a]) {
                            *total += sum;
                        }
                        *squares.entry(a).or_insert(0.0) +=
                            unit.squares.get(a).copied().unwrap_or(0.0);
                    }
                }
            }
            let p = Store::range_path(&meta, a, level);
            let array = Array::open(storage.clone(), &p)
                .map_err(|e| StoreError::io(&store.join(&p[1..]), e))?;
            array
                .store_chunk_opt(
                    &[0, 0, 0, 0],
                    values.as_slice(),
                    &CodecOptions::default().with_store_empty_chunks(true),
                )
                .map_err(|e| StoreError::io(&store.join(&p[1..]), e))?;
        }
        let t = totals.get(&a).copied().unwrap_or([0.0; 3]);
        let e = extremes.get(&a).copied();
        let am = &mut meta.attributes[a];
        am.min = e.map(|e| e[0]);
        am.max = e.map(|e| e[1]);
        am.mean = (t[1] > 0.0).then(|| t[0] / t[1]);
        am.non_finite = t[2] as u64;
    }
    meta.complete = true;
    let stats: Vec<layout::Stats> = (0..meta.attributes.len())
        .map(|a| {
            let t = totals.get(&a).copied().unwrap_or([0.0; 3]);
            layout::Stats {
                count: t[1],
                sum: t[0],
                sum_squares: squares.get(&a).copied().unwrap_or(0.0),
            }
        })
        .collect();
    // Every zarr.json again, now with the statistics, the root (complete) last.
    layout::write_layout(storage, store, &meta, options, Some(&stats), beside)?;
    Ok(meta)
}

/// A bar of `total` bytes on stderr, when asked for and stderr is a terminal.
fn progress_bar(shown: bool, total: u64, what: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !shown || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(total),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg} [{bar:40}] {binary_bytes}/{binary_total_bytes} {binary_bytes_per_sec} {eta}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    Some(bar)
}

/// A summary of a conversion, for the command line.
pub fn describe(report: &ConvertReport, store: &Path) -> String {
    let m = &report.meta;
    let mut s = format!(
        "{}: {} x {} x {} (sample, crossline, inline), {} levels of {}³ bricks, attributes {}\n",
        store.display(),
        m.dims[0],
        m.dims[1],
        m.dims[2],
        m.levels,
        m.brick,
        m.attributes
            .iter()
            .map(|a| a.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    s += &format!(
        "{} columns written, {} resumed from an earlier run; {:.1} MB read in {:.1} s ({:.1} MB/s)\n",
        report.written,
        report.resumed,
        report.bytes_read as f64 / 1e6,
        report.seconds,
        report.bytes_read as f64 / 1e6 / report.seconds.max(1e-9)
    );
    s
}

/// Where a store's progress log would be.
pub fn progress_log(store: &Path) -> PathBuf {
    store.join(PROGRESS_LOG)
}
