//! The octree: which node each point goes to, for clouds larger than memory.
//!
//! The rule, the same at every level: a node's cube is divided into `grid`³ cells
//! (spacing = side / grid); a point stays in the first node, from the root down, whose
//! cell it falls in is still free, so each level is an even sample at its spacing and
//! every point is in exactly one node. A node whose whole subtree holds at most
//! `node_points` points keeps them all (a leaf).
//!
//! Out of core: a subtree of more than `memory_points` points is distributed in one
//! streamed pass: the points taken by its first `d` levels stay in memory (a sample:
//! at most the cells of those levels), the others are appended to one spill file per
//! node of level `d` below it; each spill file is then built the same way, in memory
//! when it fits (`d` chosen so that the files hold about half of `memory_points` if the
//! points spread over the nodes the cloud's extent reaches, at most 4^d: a surface; at
//! most 4 levels), else distributed again. The spill files' buffers
//! hold at most [`SPILL_BUFFERS`] bytes together.

use std::collections::{HashMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::records::xyz;
use crate::points::PointsError;

/// An octree node's key: level, then x, y, z in `0..2^level`.
pub type Key = [i32; 4];

/// Deepest level a point may reach (cells per side stay below 2^21 for the level ids).
pub(super) const MAX_LEVEL: i32 = 14;

/// The root cube and how a point's integer coordinates map into it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cube {
    /// Smallest corner and side, in the file's coordinates.
    pub(super) min: [f64; 3],
    pub(super) side: f64,
    pub(super) scale: [f64; 3],
    pub(super) offset: [f64; 3],
    /// Cells per node side.
    pub(super) grid: u32,
    /// The points' extent along each axis (at most the side).
    pub(super) extent: [f64; 3],
}

impl Cube {
    /// Where a record lies in the cube, 0..1 per axis (outside for a point outside).
    pub(super) fn unit(&self, record: &[u8]) -> [f64; 3] {
        let q = xyz(record);
        std::array::from_fn(|a| {
            (q[a] as f64 * self.scale[a] + self.offset[a] - self.min[a]) / self.side
        })
    }

    /// The cell of `u` at `level` (cells per side: grid · 2^level), per axis.
    fn cell(&self, u: [f64; 3], level: i32) -> [u64; 3] {
        let m = (self.grid as u64) << level;
        u.map(|c| ((c * m as f64) as u64).min(m - 1))
    }
}

/// Where the built nodes go: a node's key and its records.
pub(super) type Emit<'a> = dyn FnMut(Key, Vec<u8>) -> Result<(), PointsError> + 'a;

/// Limits of a build.
pub(super) struct Limits {
    pub(super) node_points: usize,
    pub(super) memory_points: u64,
    pub(super) record: usize,
}

/// A build: the input (for errors), the cube, its limits and the folder for spill files.
pub(super) struct Tree<'a> {
    pub(super) input: &'a Path,
    pub(super) cube: &'a Cube,
    pub(super) limits: &'a Limits,
    pub(super) spill: &'a Path,
}

/// Build the subtree under `root` from `count` records that `next` appends a batch at a
/// time, spilling into the tree's folder when they are more than fit in memory.
pub(super) fn build(
    tree: &Tree,
    root: Key,
    count: u64,
    next: &mut dyn FnMut(&mut Vec<u8>) -> Result<u64, PointsError>,
    emit: &mut Emit,
    placed: &dyn Fn(u64),
) -> Result<(), PointsError> {
    let (cube, limits, spill) = (tree.cube, tree.limits, tree.spill);
    if count <= limits.memory_points || root[0] >= MAX_LEVEL - 1 {
        let mut records = Vec::new();
        while next(&mut records)? > 0 {}
        let n = records.len() / limits.record;
        let units: Vec<[f64; 3]> = records
            .par_chunks_exact(limits.record)
            .map(|r| cube.unit(r))
            .collect();
        let all: Vec<u32> = (0..n as u32).collect();
        in_memory(cube, limits, root, &records, &units, all, emit)?;
        placed(n as u64);
        return Ok(());
    }
    // Levels kept in memory: enough that each spill file holds about half of
    // memory_points, if the points spread over the nodes of depth d that the cloud's
    // extent reaches and at most 4^d of them (a surface), at most 4 levels.
    let nodes_at = |d: i32| -> f64 {
        let side = cube.side / f64::from(1u32 << root[0]);
        let reach: f64 = (0..3)
            .map(|a| {
                (cube.extent[a].min(side) * f64::from(1u32 << d) / side)
                    .ceil()
                    .max(1.0)
            })
            .product();
        reach.min(4f64.powi(d))
    };
    let mut d = 1;
    while d < 4
        && root[0] + d < MAX_LEVEL - 1
        && count as f64 / nodes_at(d) > (limits.memory_points / 2) as f64
    {
        d += 1;
    }
    let mut taken: Vec<HashSet<u64>> = vec![HashSet::new(); d as usize];
    let mut upper: HashMap<Key, Vec<u8>> = HashMap::new();
    let mut files: HashMap<Key, Spill> = HashMap::new();
    let mut batch = Vec::new();
    let mut upper_points = 0u64;
    let mut buffered = 0usize;
    loop {
        batch.clear();
        if next(&mut batch)? == 0 {
            break;
        }
        for r in batch.chunks_exact(limits.record) {
            let u = cube.unit(r);
            let mut home = None;
            for k in 0..d {
                let level = root[0] + k;
                let c = cube.cell(u, level);
                let m = (cube.grid as u64) << level;
                if taken[k as usize].insert((c[0] * m + c[1]) * m + c[2]) {
                    home = Some(level);
                    break;
                }
            }
            match home {
                Some(level) => {
                    upper_points += 1;
                    upper
                        .entry(node_of(cube, u, level))
                        .or_default()
                        .extend_from_slice(r);
                }
                None => {
                    let key = node_of(cube, u, root[0] + d);
                    files
                        .entry(key)
                        .or_insert_with(|| Spill::new(spill, key))
                        .push(r);
                    buffered += r.len();
                }
            }
        }
        if buffered >= SPILL_BUFFERS {
            for file in files.values_mut() {
                file.flush().map_err(|e| PointsError::io(spill, e))?;
            }
            buffered = 0;
        }
        // The levels in memory cost a record and a cell id a point, less than a third of
        // what a point costs in an in-memory build.
        if upper_points > 2 * limits.memory_points {
            return Err(PointsError::unsupported(
                tree.input,
                format!(
                    "the top {d} levels under node {root:?} sample more than {} points: give more points in memory at once (--memory-points) or a larger memory budget (--memory-budget)",
                    2 * limits.memory_points
                ),
            ));
        }
    }
    drop(taken);
    placed(upper_points);
    // In key order: the same input makes the same file.
    let mut upper: Vec<(Key, Vec<u8>)> = upper.into_iter().collect();
    upper.sort_by_key(|(key, _)| *key);
    for (key, records) in upper {
        emit(key, records)?;
    }
    let mut keys: Vec<Key> = files.keys().copied().collect();
    keys.sort();
    for key in keys {
        let mut file = files.remove(&key).expect("listed");
        file.flush().map_err(|e| PointsError::io(spill, e))?;
        let mut reader = file.reader().map_err(|e| PointsError::io(spill, e))?;
        let record = limits.record;
        let path = file.path.clone();
        let mut read = |out: &mut Vec<u8>| -> Result<u64, PointsError> {
            let at = out.len();
            out.resize(at + (1 << 20) / record * record, 0);
            let mut got = 0;
            while got < out.len() - at {
                match reader.read(&mut out[at + got..]) {
                    Ok(0) => break,
                    Ok(k) => got += k,
                    Err(e) => return Err(PointsError::io(&path, e)),
                }
            }
            out.truncate(at + got / record * record);
            Ok((got / record) as u64)
        };
        build(tree, key, file.count, &mut read, emit, placed)?;
        let _ = std::fs::remove_file(&file.path);
    }
    Ok(())
}

/// The node of `level` that holds `u`.
fn node_of(cube: &Cube, u: [f64; 3], level: i32) -> Key {
    let c = cube.cell(u, level);
    let g = cube.grid as u64;
    [
        level,
        (c[0] / g) as i32,
        (c[1] / g) as i32,
        (c[2] / g) as i32,
    ]
}

/// Build the subtree under `key` from the points `idx` (indices into `records` and
/// `units`), all in memory.
fn in_memory(
    cube: &Cube,
    limits: &Limits,
    key: Key,
    records: &[u8],
    units: &[[f64; 3]],
    idx: Vec<u32>,
    emit: &mut Emit,
) -> Result<(), PointsError> {
    let gather = |idx: &[u32]| -> Vec<u8> {
        let r = limits.record;
        let mut out = Vec::with_capacity(idx.len() * r);
        for &i in idx {
            out.extend_from_slice(&records[i as usize * r..(i as usize + 1) * r]);
        }
        out
    };
    if idx.len() <= limits.node_points || key[0] >= MAX_LEVEL {
        return emit(key, gather(&idx));
    }
    let g = cube.grid as u64;
    let mut taken: HashSet<u64> = HashSet::with_capacity(idx.len().min(1 << 20));
    let mut kept = Vec::new();
    let mut children: [Vec<u32>; 8] = Default::default();
    for i in idx {
        let u = units[i as usize];
        let c = cube.cell(u, key[0]);
        let local = c.map(|v| v % g);
        if taken.insert((local[0] * g + local[1]) * g + local[2]) {
            kept.push(i);
        } else {
            let child = node_of(cube, u, key[0] + 1);
            let k = (child[1] & 1) | (child[2] & 1) << 1 | (child[3] & 1) << 2;
            children[k as usize].push(i);
        }
    }
    drop(taken);
    emit(key, gather(&kept))?;
    for (k, child) in children.into_iter().enumerate() {
        if !child.is_empty() {
            let k = k as i32;
            let child_key = [
                key[0] + 1,
                2 * key[1] + (k & 1),
                2 * key[2] + (k >> 1 & 1),
                2 * key[3] + (k >> 2 & 1),
            ];
            in_memory(cube, limits, child_key, records, units, child, emit)?;
        }
    }
    Ok(())
}

/// One spill file: records appended through a buffer, all buffers flushed together when
/// they hold [`SPILL_BUFFERS`] bytes (files opened only to flush, so thousands of them
/// need no open descriptors).
struct Spill {
    path: PathBuf,
    buffer: Vec<u8>,
    count: u64,
}

/// Bytes buffered for all spill files together before they are appended to.
const SPILL_BUFFERS: usize = 64 << 20;

impl Spill {
    fn new(dir: &Path, key: Key) -> Spill {
        Spill {
            path: dir.join(format!("{}-{}-{}-{}", key[0], key[1], key[2], key[3])),
            buffer: Vec::new(),
            count: 0,
        }
    }

    fn push(&mut self, record: &[u8]) {
        self.buffer.extend_from_slice(record);
        self.count += 1;
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if !self.buffer.is_empty() {
            OpenOptions::new()
                .create(true)
                .append(true)
                .open(&self.path)?
                .write_all(&self.buffer)?;
            self.buffer.clear();
        }
        Ok(())
    }

    fn reader(&self) -> std::io::Result<std::io::BufReader<File>> {
        Ok(std::io::BufReader::with_capacity(
            1 << 20,
            File::open(&self.path)?,
        ))
    }
}
