//! `arbvis convert CLOUD X.copc.laz`: a COPC file (copc.io 1.0) from a LAS/LAZ, PLY or
//! seed `.dat` cloud, for clouds larger than memory.
//!
//! The octree (`octree.rs`): a root cube around the points, `grid`³ cells per node, each
//! point in the first node from the root whose cell is free, leaves of at most
//! `node_points` points; clouds of more than `memory_points` points are distributed
//! through spill files beside the output, in streamed passes over the input. Records are
//! point format 6, 7 or 8 with the input's extra bytes (`records.rs`); a LAS input keeps
//! its scales and offsets, so coordinates are copied exactly.
//!
//! The file: the LAS 1.4 header, the `copc` info VLR first, the `laszip encoded` VLR
//! (layered chunks of variable size), the input's extra-bytes and coordinate-system VLRs;
//! then one LAZ chunk per node, compressed in parallel (rayon) by `laz`'s layered
//! compressor, the chunk table, and the hierarchy EVLR (`copc`, 1000) as one page of
//! every node's key, offset, size and count. Written to a temporary beside the output
//! and renamed when complete; an interrupted run leaves nothing named like the output
//! (its temporary and spill folder are removed on error, on Ctrl-C, or by the next run),
//! and a run starts over (cleanly restartable, not resumable).
//!
//! The header's bounds are trusted for the cube, and checked: when a point lies outside
//! them the octree is built again around the points' own bounds.

mod file;
mod octree;
mod pages;
pub(crate) mod records;
mod source;

use std::path::Path;

use crate::points::PointsError;
pub use octree::Key;
use octree::{Cube, Limits};

/// How the octree is built.
#[derive(Debug, Clone)]
pub struct CopcWriteOptions {
    /// A node whose subtree holds more points than this keeps one point per cell of its
    /// level's grid and pushes the rest down (so a node may hold more: one per occupied
    /// cell); PDAL's and Untwine's order of magnitude.
    pub node_points: usize,
    /// Most points built in memory at once; `None`: a quarter of the memory budget, at
    /// most 8 Mi points.
    pub memory_points: Option<u64>,
    /// Cells per node side (a level's spacing is its side over this).
    pub grid: u32,
}

impl Default for CopcWriteOptions {
    fn default() -> Self {
        CopcWriteOptions {
            node_points: 100_000,
            memory_points: None,
            grid: 128,
        }
    }
}

/// What a conversion wrote.
#[derive(Debug, Clone)]
pub struct CopcWriteReport {
    /// Points written.
    pub points: u64,
    /// Point format (6, 7 or 8) and record length.
    pub format: (u8, usize),
    /// Nodes and the deepest level.
    pub nodes: usize,
    pub depth: i32,
    /// Bytes of the file.
    pub bytes: u64,
    /// Whether points went through spill files.
    pub spilled: bool,
    /// Points built in memory at once, at most.
    pub memory_points: u64,
}

/// Write `input` as a COPC file at `output`.
pub fn write_copc(
    input: &Path,
    output: &Path,
    options: &CopcWriteOptions,
) -> Result<CopcWriteReport, PointsError> {
    // One writer per output: a second conversion into the same file is refused naming
    // the first (as a store's are), never interleaved with it.
    let _lock = lock(output)?;
    let mut source = source::Source::open(input)?;
    if source.count == 0 {
        return Err(PointsError::unsupported(input, "the cloud has no points"));
    }
    // What a point costs while a subtree is built in memory: its record, its place in
    // the cube, its index, its copy into a node and its share of the compressed chunk.
    let each = 2 * source.record as u64 + 24 + 8 + 8;
    // At most 8 Mi points at once (about 1 GB with format 7): the whole conversion stays
    // under 2 GB of memory for any size of cloud.
    let memory_points = options.memory_points.unwrap_or_else(|| {
        (arbvis_core::budget::current().bytes / 4 / each).clamp(1 << 16, 1 << 23)
    });
    arbvis_core::budget::check(
        format!(
            "building {memory_points} points of {} in memory",
            input.display()
        ),
        memory_points.saturating_mul(each) + (64 << 20) * 2,
    )
    .map_err(|e| PointsError::unsupported(input, e.to_string()))?;
    let limits = Limits {
        node_points: options.node_points.max(1),
        memory_points: memory_points.max(options.node_points as u64),
        record: source.record,
    };
    let grid = options.grid.clamp(2, 1 << 12);
    let spilled = source.count > limits.memory_points;
    let valid = |b: &[[f64; 3]; 2]| {
        (0..3).all(|a| b[0][a].is_finite() && b[1][a].is_finite() && b[0][a] <= b[1][a])
    };
    let mut bounds = source.bounds;
    if !valid(&bounds) {
        bounds = scan_bounds(&mut source)?;
    }
    for attempt in 0..2 {
        let cube = cube_around(input, &bounds, &source, grid)?;
        let mut out = file::CopcFile::create(output, &source, &cube)?;
        let bar = arbvis_core::progress::Bar::new(
            source.count,
            &format!("writing {}", output.display()),
            arbvis_core::progress::Unit::Points,
        );
        let spill = out.spill_dir().to_path_buf();
        let count = source.count;
        // A point outside the cube (the header's bounds were wrong) stops the pass: the
        // octree is built again around the points' own bounds.
        let mut outside = false;
        let built = {
            let src = &mut source;
            let mut next = |buf: &mut Vec<u8>| -> Result<u64, PointsError> {
                let at = buf.len();
                let n = src.next(buf)?;
                for r in buf[at..].chunks_exact(src.record) {
                    let u = cube.unit(r);
                    if u.iter().any(|c| !(0.0..=1.0).contains(c)) {
                        outside = true;
                        return Err(PointsError::unsupported(
                            input,
                            "a point outside the header's bounds",
                        ));
                    }
                }
                Ok(n)
            };
            let tree = octree::Tree {
                input,
                cube: &cube,
                limits: &limits,
                spill: &spill,
            };
            octree::build(
                &tree,
                [0, 0, 0, 0],
                count,
                &mut next,
                &mut |key, records| out.add(key, records),
                &|n| bar.inc(n),
            )
        };
        drop(bar);
        match built {
            // A point outside the header's bounds, or a failure where the header's bounds
            // are not the points' (a degenerate axis misleads the spill depth): again
            // around the points' own bounds.
            Err(e) if attempt == 0 => {
                drop(out);
                let own = scan_bounds(&mut source)?;
                let pad = 2.0 * source.scale.iter().fold(0f64, |m, s| m.max(s.abs()));
                let differ = (0..2).any(|k| (0..3).any(|a| (own[k][a] - bounds[k][a]).abs() > pad));
                if !(outside || differ) {
                    return Err(e);
                }
                arbvis_core::progress::line(&format!(
                    "{}: the points' bounds are not the header's; building the octree again around the points' own",
                    input.display()
                ));
                bounds = own;
                continue;
            }
            Err(e) => return Err(e),
            Ok(()) => {}
        }
        let written = out.finish(&source, &cube)?;
        return Ok(CopcWriteReport {
            points: written.points,
            format: (source.format, source.record),
            nodes: written.nodes,
            depth: written.depth,
            bytes: written.bytes,
            spilled,
            memory_points: limits.memory_points,
        });
    }
    unreachable!("the second attempt uses the points' own bounds")
}

/// The lock on `output` (`.NAME.arbvis-convert.lock` beside it), or the error naming the
/// process that holds it.
fn lock(output: &Path) -> Result<arbvis_core::png_io::WriterLock, PointsError> {
    let name = output
        .file_name()
        .ok_or_else(|| PointsError::unsupported(output, "not a file path"))?
        .to_string_lossy();
    let path = output.with_file_name(format!(".{name}.arbvis-convert.lock"));
    match arbvis_core::png_io::WriterLock::acquire(&path).map_err(|e| PointsError::io(&path, e))? {
        Ok(lock) => {
            if let Some(pid) = lock.taken_over() {
                arbvis_core::progress::line(&format!(
                    "note: {}: the lock of pid {pid}, which is no longer running, taken over",
                    path.display()
                ));
            }
            Ok(lock)
        }
        Err(holder) => Err(PointsError::unsupported(
            output,
            format!(
                "another conversion ({holder}) is writing this file; wait for it, or stop it and run this command again (a conversion starts over)"
            ),
        )),
    }
}

/// The points' own bounds, from a pass over them (the source rewound before and after).
fn scan_bounds(source: &mut source::Source) -> Result<[[f64; 3]; 2], PointsError> {
    source.rewind()?;
    let mut seen = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    let mut buf = Vec::new();
    loop {
        buf.clear();
        if source.next(&mut buf)? == 0 {
            break;
        }
        for r in buf.chunks_exact(source.record) {
            for (a, q) in records::xyz(r).into_iter().enumerate() {
                let v = q as f64 * source.scale[a] + source.offset[a];
                seen[0][a] = seen[0][a].min(v);
                seen[1][a] = seen[1][a].max(v);
            }
        }
    }
    source.rewind()?;
    Ok(seen)
}

/// The root cube: centred on `bounds`, its side the largest extent, padded by two steps
/// of the coordinates' scale so that points on the bounds are inside.
fn cube_around(
    input: &Path,
    bounds: &[[f64; 3]; 2],
    source: &source::Source,
    grid: u32,
) -> Result<Cube, PointsError> {
    let pad = 2.0 * source.scale.iter().fold(0f64, |m, s| m.max(s.abs()));
    let side = (0..3)
        .map(|a| bounds[1][a] - bounds[0][a])
        .fold(0f64, f64::max)
        + 2.0 * pad;
    let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * bounds[0][a] + 0.5 * bounds[1][a]);
    if !(side.is_finite() && side > 0.0 && centre.iter().all(|c| c.is_finite())) {
        // Byte 179: the LAS header's bounds, where they came from (or the points'
        // own, scanned, when those were not valid).
        let m = format!(
            "bounds {:?}..{:?}: too far apart (or not finite) for an octree's cube",
            bounds[0], bounds[1]
        );
        return Err(PointsError::format(input, 179, m));
    }
    Ok(Cube {
        min: centre.map(|c| c - 0.5 * side),
        extent: std::array::from_fn(|a| (bounds[1][a] - bounds[0][a]).min(side)),
        side,
        scale: source.scale,
        offset: source.offset,
        grid,
    })
}
