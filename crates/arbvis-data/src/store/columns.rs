//! One column of a level in a conversion ([`super::convert`]): a level-0 column read from
//! the input with its derived attributes, a quad of them with its level-1 column filtered
//! in memory, or a column filtered from the level below read back; each cut into bricks,
//! written as chunks with their ranges and statistics, and logged for resuming.

use std::collections::HashMap;
use std::fs::File;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;

use rustfft::FftPlanner;
use zarrs::array::CodecOptions;

use super::filter::{halve, BrickStats, Grid};
use super::input::Input;
use super::layout;
use super::meta::StoreMeta;
use super::progress::Unit;
use super::reader::Store;
use super::StoreError;
use crate::volume::attributes::{derive_trace, Attribute};

/// The progress log, appended to by every worker.
pub(super) struct Log {
    pub(super) file: Mutex<File>,
}

/// What every column of a conversion shares.
pub(super) struct Ctx<'a> {
    pub(super) store: &'a Path,
    pub(super) meta: &'a StoreMeta,
    pub(super) writers: &'a layout::Writers,
    pub(super) attributes: &'a [Attribute],
    pub(super) log: &'a Log,
    pub(super) log_path: &'a Path,
    pub(super) written: AtomicUsize,
    pub(super) stop_after: Option<usize>,
    pub(super) watch: Option<super::progress::Watch>,
    /// Columns done before this run (a resumed conversion).
    pub(super) resumed: usize,
    /// Columns of the whole store, all levels.
    pub(super) total: usize,
    pub(super) bytes: AtomicU64,
}

impl Ctx<'_> {
    fn store_chunk(
        &self,
        attr: usize,
        level: usize,
        c: [usize; 3],
        values: &[f32],
    ) -> Result<(), StoreError> {
        // An MDIO dataset's own variable is left as it is.
        let Some(array) = &self.writers.data[attr][level] else {
            return Ok(());
        };
        let index = [c[2] as u64, c[1] as u64, c[0] as u64];
        let options = CodecOptions::default().with_store_empty_chunks(true);
        let result = if self.meta.attributes[attr].dtype == "float16" {
            let h: Vec<half::f16> = values.iter().map(|&v| half::f16::from_f32(v)).collect();
            array.store_chunk_opt(&index, h.as_slice(), &options)
        } else {
            array.store_chunk_opt(&index, values, &options)
        };
        result.map_err(|e| StoreError::Chunk {
            path: self.store.join(format!(
                "{}/c/{}/{}/{}",
                &Store::array_path(self.meta, attr, level)[1..],
                c[2],
                c[1],
                c[0]
            )),
            array: Store::array_path(self.meta, attr, level)[1..].to_string(),
            chunk: index,
            message: format!("cannot be written: {e}"),
        })
    }

    /// A column's traces: the trace mask (the input's, `known`, else live unless every
    /// sample is NaN) and, where the survey gives them, the CDP coordinates, as `B x B`
    /// chunks over (inline, crossline).
    fn store_traces(
        &self,
        u: [usize; 3],
        [nj, nk]: [usize; 2],
        column: &[f32],
        coordinates: &[[f64; 2]],
        known: Option<Vec<bool>>,
    ) -> Result<(), StoreError> {
        let b = self.meta.brick;
        let index = [u[2] as u64, u[1] as u64];
        let options = CodecOptions::default().with_store_empty_chunks(true);
        let fail = |what: &str, e: String| StoreError::Io {
            path: self.store.join(what),
            message: format!("chunk {index:?} cannot be written: {e}"),
        };
        let ni = self.meta.dims[0];
        let mut live = vec![false; b * b];
        for y in 0..nk {
            for x in 0..nj {
                let t = y * nj + x;
                live[y * b + x] = match &known {
                    Some(mask) => mask[t],
                    None => column[t * ni..][..ni].iter().any(|v| !v.is_nan()),
                };
            }
        }
        if let Some(mask) = &self.writers.mask {
            mask.store_chunk_opt(&index, live.as_slice(), &options)
                .map_err(|e| fail("trace_mask", e.to_string()))?;
        }
        if let Some(cdp) = &self.writers.cdp {
            for (c, (array, name)) in cdp.iter().zip(["cdp_x", "cdp_y"]).enumerate() {
                let mut values = vec![f64::NAN; b * b];
                for y in 0..nk {
                    for x in 0..nj {
                        values[y * b + x] = coordinates[y * nj + x][c];
                    }
                }
                array
                    .store_chunk_opt(&index, values.as_slice(), &options)
                    .map_err(|e| fail(name, e.to_string()))?;
            }
        }
        Ok(())
    }

    /// Values as the store will hold them (float16 attributes rounded), so that ranges
    /// and statistics are the stored values'.
    fn round_to_stored(&self, attr: usize, values: &mut [f32]) {
        if self.meta.attributes[attr].dtype == "float16" {
            values
                .iter_mut()
                .for_each(|v| *v = half::f16::from_f32(*v).to_f32());
        }
    }

    /// Log a finished column, or stop as the tests' interruption asks (decided under the
    /// log's lock, so exactly `stop_after` columns are logged).
    pub(super) fn finish(&self, unit: Unit) -> Result<Unit, StoreError> {
        let line = serde_json::to_string(&unit).map_err(|e| StoreError::io(self.log_path, e))?;
        let mut f = self.log.file.lock().expect("progress log");
        if let Some(limit) = self.stop_after {
            if self.written.load(Ordering::SeqCst) >= limit {
                return Err(StoreError::Interrupted(format!(
                    "{}: conversion stopped after {limit} columns (run it again to resume)",
                    self.store.display()
                )));
            }
        }
        f.write_all(line.as_bytes())
            .and_then(|_| f.write_all(b"\n"))
            .and_then(|_| f.sync_data())
            .map_err(|e| StoreError::io(self.log_path, e))?;
        let written = self.written.fetch_add(1, Ordering::SeqCst) + 1;
        drop(f);
        if let Some(watch) = &self.watch {
            let done = self.resumed + written;
            if !(watch.0)(done, self.total) {
                return Err(StoreError::Interrupted(format!(
                    "{}: conversion stopped after {done} of {} columns (run it again to resume)",
                    self.store.display(),
                    self.total
                )));
            }
        }
        Ok(unit)
    }

    /// One level-0 column: read, derive, cut, write; its planes (one per attribute,
    /// `samples x traces`, the sample axis fastest, as stored) are returned for the level
    /// above.
    fn level0(&self, src: &Input, u: [usize; 3]) -> Result<(Unit, Vec<Vec<f32>>), StoreError> {
        let b = self.meta.brick;
        let [ni, nj, nk] = self.meta.dims;
        let (j0, k0) = (u[1] * b, u[2] * b);
        let (j1, k1) = ((j0 + b).min(nj), (k0 + b).min(nk));
        let traces = (j1 - j0) * (k1 - k0);
        let mut column = vec![0f32; ni * traces];
        let mut coordinates = vec![[f64::NAN; 2]; traces];
        let wanted = self
            .writers
            .cdp
            .is_some()
            .then_some(coordinates.as_mut_slice());
        src.read_column(j0..j1, k0..k1, &mut column, wanted)?;
        let known = src.live(j0..j1, k0..k1);
        self.store_traces(u, [j1 - j0, k1 - k0], &column, &coordinates, known)?;
        self.bytes
            .fetch_add(traces as u64 * src.bytes_per_trace(), Ordering::Relaxed);
        let mut planes: Vec<Vec<f32>> = vec![column];
        let derived: Vec<Attribute> = self.attributes[1..].to_vec();
        if !derived.is_empty() {
            let mut outs: Vec<Vec<f32>> = derived.iter().map(|_| vec![0f32; ni * traces]).collect();
            let mut planner = FftPlanner::new();
            for t in 0..traces {
                let src = &planes[0][t * ni..(t + 1) * ni];
                let mut slices: Vec<(Attribute, &mut [f32])> = derived
                    .iter()
                    .zip(outs.iter_mut())
                    .map(|(&a, o)| (a, &mut o[t * ni..(t + 1) * ni]))
                    .collect();
                derive_trace(src, &mut planner, &mut slices);
            }
            planes.extend(outs);
        }
        for (a, plane) in planes.iter_mut().enumerate() {
            self.round_to_stored(a, plane);
        }
        let unit = self.store_column(u, &planes, [j1 - j0, k1 - k0])?;
        Ok((unit, planes))
    }

    /// A column of level `u[0]` held whole (`planes`: one per attribute, `samples x
    /// traces[0] x traces[1]`, samples fastest) cut into its bricks and written.
    fn store_column(
        &self,
        u: [usize; 3],
        planes: &[Vec<f32>],
        traces: [usize; 2],
    ) -> Result<Unit, StoreError> {
        let b = self.meta.brick;
        let ni = self.meta.level_dims(u[0])[0];
        let bricks_i = ni.div_ceil(b);
        let mut ranges = vec![Vec::with_capacity(bricks_i); planes.len()];
        let mut sums = vec![[0.0f64; 3]; planes.len()];
        let mut squares = vec![0.0f64; planes.len()];
        let mut chunk = vec![0f32; b * b * b];
        let [nj_c, nk_c] = traces;
        for (a, plane) in planes.iter().enumerate() {
            for bi in 0..bricks_i {
                let (i0, i1) = (bi * b, ((bi + 1) * b).min(ni));
                if i1 - i0 < b || nj_c < b || nk_c < b {
                    chunk.fill(0.0);
                }
                let mut stats = BrickStats::new();
                for z in 0..nk_c {
                    for y in 0..nj_c {
                        let src = &plane[(z * nj_c + y) * ni..][i0..i1];
                        chunk[b * (y + b * z)..][..i1 - i0].copy_from_slice(src);
                        stats.add(src);
                    }
                }
                let (range, s, sq) = stats.finish();
                ranges[a].push(range);
                for q in 0..3 {
                    sums[a][q] += s[q];
                }
                squares[a] += sq;
                self.store_chunk(a, u[0], [bi, u[1], u[2]], &chunk)?;
            }
        }
        Ok(Unit {
            u,
            ranges,
            sums,
            squares,
        })
    }

    /// A quad of level-0 columns (`2J .. 2J + 1` x `2K .. 2K + 1`, those of them inside
    /// the survey and not `done`), one after the other, and, where all of them are new,
    /// the level-1 column `(J, K)` filtered from them in memory (not read back).
    pub(super) fn quad(
        &self,
        src: &Input,
        q: [usize; 2],
        done: &HashMap<[usize; 3], Unit>,
        bar: Option<&indicatif::ProgressBar>,
    ) -> Result<Vec<Unit>, StoreError> {
        let b = self.meta.brick;
        let counts = self.meta.brick_counts(0);
        // Level-1 cells lie within one column only where the brick side is even.
        let above =
            self.meta.levels > 1 && b.is_multiple_of(2) && !done.contains_key(&[1, q[0], q[1]]);
        let members: Vec<[usize; 3]> = (0..2)
            .flat_map(|dk| (0..2).map(move |dj| [0, 2 * q[0] + dj, 2 * q[1] + dk]))
            .filter(|u| u[1] < counts[1] && u[2] < counts[2])
            .collect();
        let whole = above && members.iter().all(|u| !done.contains_key(u));
        let n1 = self.meta.level_dims(1);
        // The level-1 column: its traces and, per attribute, its plane.
        let traces1: [usize; 2] =
            std::array::from_fn(|a| ((q[a] + 1) * b).min(n1[a + 1]) - q[a] * b);
        let mut planes1: Vec<Vec<f32>> = if whole {
            let len = n1[0] * traces1[0] * traces1[1];
            vec![vec![0f32; len]; self.attributes.len()]
        } else {
            Vec::new()
        };
        let mut units = Vec::with_capacity(5);
        for u in members {
            if done.contains_key(&u) {
                continue;
            }
            let (unit, planes) = self.level0(src, u)?;
            if let Some(bar) = bar {
                bar.inc((b * b) as u64 * src.bytes_per_trace());
            }
            units.push(self.finish(unit)?);
            if !whole {
                continue;
            }
            // This column's quarter of the level-1 column: traces from (dj, dk) B / 2.
            let ni = self.meta.dims[0];
            let nj_c = (b * (u[1] + 1)).min(self.meta.dims[1]) - b * u[1];
            let nk_c = (b * (u[2] + 1)).min(self.meta.dims[2]) - b * u[2];
            let (y0, z0) = ((u[1] % 2) * b / 2, (u[2] % 2) * b / 2);
            let to = Grid::dense(n1[0], traces1[0]);
            for ((a, plane), out) in planes.iter().enumerate().zip(planes1.iter_mut()) {
                halve(
                    plane,
                    Grid::dense(ni, nj_c),
                    [ni, nj_c, nk_c],
                    [n1[0], nj_c.div_ceil(2), nk_c.div_ceil(2)],
                    self.attributes[a] == Attribute::Phase,
                    &mut out[to.at(0, y0, z0)..],
                    to,
                );
            }
        }
        if whole {
            for (a, plane) in planes1.iter_mut().enumerate() {
                self.round_to_stored(a, plane);
            }
            let unit = self.store_column([1, q[0], q[1]], &planes1, traces1)?;
            units.push(self.finish(unit)?);
        }
        Ok(units)
    }

    /// One column of level `u[0]`, filtered from the level below read back from the
    /// store, brick by brick.
    pub(super) fn upper(&self, below: &Store, u: [usize; 3]) -> Result<Unit, StoreError> {
        let level = u[0];
        let b = self.meta.brick;
        let n = self.meta.level_dims(level);
        let m = self.meta.level_dims(level - 1);
        let bricks_i = n[0].div_ceil(b);
        let mut ranges = vec![Vec::with_capacity(bricks_i); self.attributes.len()];
        let mut sums = vec![[0.0f64; 3]; self.attributes.len()];
        let mut squares = vec![0.0f64; self.attributes.len()];
        let mut chunk = vec![0f32; b * b * b];
        for (a, &attribute) in self.attributes.iter().enumerate() {
            for bi in 0..bricks_i {
                let c = [bi, u[1], u[2]];
                let lo = c.map(|x| x * b);
                let hi: [usize; 3] = std::array::from_fn(|q| ((c[q] + 1) * b).min(n[q]));
                let out: [usize; 3] = std::array::from_fn(|q| hi[q] - lo[q]);
                // The voxels below: 2 lo .. 2 hi, clamped to the level below.
                let size = out.map(|x| 2 * x);
                let below_vals = below.region(a, level - 1, lo.map(|x| 2 * x as i64), size)?;
                chunk.fill(0.0);
                halve(
                    &below_vals,
                    Grid::dense(size[0], size[1]),
                    std::array::from_fn(|q| m[q] - 2 * lo[q]),
                    out,
                    attribute == Attribute::Phase,
                    &mut chunk,
                    Grid::dense(b, b),
                );
                self.round_to_stored(a, &mut chunk);
                let mut stats = BrickStats::new();
                for z in 0..out[2] {
                    for y in 0..out[1] {
                        stats.add(&chunk[b * (y + b * z)..][..out[0]]);
                    }
                }
                let (range, s, sq) = stats.finish();
                ranges[a].push(range);
                for q in 0..3 {
                    sums[a][q] += s[q];
                }
                squares[a] += sq;
                self.store_chunk(a, level, c, &chunk)?;
            }
        }
        Ok(Unit {
            u,
            ranges,
            sums,
            squares,
        })
    }
}
