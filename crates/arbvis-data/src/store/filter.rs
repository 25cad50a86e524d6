//! The conversion's arithmetic: one level from the level below ([`halve`]) and a brick's
//! statistics ([`BrickStats`]), both written so that the compiler keeps several values in
//! flight (independent lanes, no branch per value): together they were a quarter of a
//! conversion's time as one long chain of dependent additions.

/// Independent accumulators per statistic.
const LANES: usize = 8;

/// Range, sums (sum, finite count, non-finite count) and sum of squares of a brick's
/// values, gathered a run of values at a time into [`LANES`] lanes.
pub(crate) struct BrickStats {
    lo: [f32; LANES],
    hi: [f32; LANES],
    sum: [f64; LANES],
    squares: [f64; LANES],
    finite: [u64; LANES],
    count: u64,
}

impl BrickStats {
    pub(crate) fn new() -> BrickStats {
        BrickStats {
            lo: [f32::INFINITY; LANES],
            hi: [f32::NEG_INFINITY; LANES],
            sum: [0.0; LANES],
            squares: [0.0; LANES],
            finite: [0; LANES],
            count: 0,
        }
    }

    /// Value `v` into lane `l`: a non-finite value counts only as non-finite.
    #[inline(always)]
    fn lane(&mut self, l: usize, v: f32) {
        let f = v.is_finite();
        let x = if f { v } else { 0.0 };
        let low = if f { v } else { f32::INFINITY };
        let high = if f { v } else { f32::NEG_INFINITY };
        self.lo[l] = if low < self.lo[l] { low } else { self.lo[l] };
        self.hi[l] = if high > self.hi[l] { high } else { self.hi[l] };
        self.sum[l] += x as f64;
        self.squares[l] += x as f64 * x as f64;
        self.finite[l] += f as u64;
    }

    pub(crate) fn add(&mut self, values: &[f32]) {
        let runs = values.chunks_exact(LANES);
        let rest = runs.remainder();
        for run in runs {
            for (l, &v) in run.iter().enumerate() {
                self.lane(l, v);
            }
        }
        for (l, &v) in rest.iter().enumerate() {
            self.lane(l, v);
        }
        self.count += values.len() as u64;
    }

    /// `[min, max]` (NaN where no value is finite), `[sum, finite, non-finite]`, squares.
    pub(crate) fn finish(self) -> ([f32; 2], [f64; 3], f64) {
        let lo = self.lo.iter().fold(f32::INFINITY, |a, &b| a.min(b));
        let hi = self.hi.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
        let range = if lo > hi { [f32::NAN; 2] } else { [lo, hi] };
        let finite: u64 = self.finite.iter().sum();
        let sums = [
            self.sum.iter().sum(),
            finite as f64,
            (self.count - finite) as f64,
        ];
        (range, sums, self.squares.iter().sum())
    }
}

/// Where [`halve`] reads and writes: axis 0 fastest, rows `strides[0]` values apart and
/// planes `strides[1]` apart.
#[derive(Clone, Copy)]
pub(crate) struct Grid {
    pub strides: [usize; 2],
}

impl Grid {
    /// A dense block `n[0] x n[1] x ...`.
    pub(crate) fn dense(n0: usize, n1: usize) -> Grid {
        Grid {
            strides: [n0, n0 * n1],
        }
    }

    pub(crate) fn at(self, x: usize, y: usize, z: usize) -> usize {
        x + self.strides[0] * y + self.strides[1] * z
    }
}

/// The next level's voxels `n` (per axis) from the level below, `src` from its voxel
/// `2 t` for output voxel `t`, `present[a]` voxels of it existing along axis `a` from
/// there: each output voxel the mean (summed in f64) of the finite voxels among `2t,
/// 2t + 1` per axis that exist, NaN where none is finite; for phase (`first`) the cell's
/// first voxel.
pub(crate) fn halve(
    src: &[f32],
    from: Grid,
    present: [usize; 3],
    n: [usize; 3],
    first: bool,
    out: &mut [f32],
    to: Grid,
) {
    // Output voxels along axis 0 whose both voxels below exist.
    let pairs = (present[0] / 2).min(n[0]);
    for z in 0..n[2] {
        let dz = if 2 * z + 1 < present[2] { 2 } else { 1 };
        for y in 0..n[1] {
            let dy = if 2 * y + 1 < present[1] { 2 } else { 1 };
            let row = &mut out[to.at(0, y, z)..][..n[0]];
            let base = from.at(0, 2 * y, 2 * z);
            if first {
                for (x, o) in row.iter_mut().enumerate() {
                    *o = src[base + 2 * x];
                }
                continue;
            }
            let mut done = 0;
            if dz == 2 && dy == 2 {
                // The whole cell: eight voxels, in the order of the general case below.
                let (sx, sxy) = (from.strides[0], from.strides[1]);
                let r = [base, base + sx, base + sxy, base + sx + sxy]
                    .map(|start| &src[start..][..2 * pairs]);
                for (x, o) in row[..pairs].iter_mut().enumerate() {
                    let mut cell = [0f32; 8];
                    for (q, r) in r.iter().enumerate() {
                        cell[2 * q] = r[2 * x];
                        cell[2 * q + 1] = r[2 * x + 1];
                    }
                    *o = mean_of_finite(&cell);
                }
                done = pairs;
            }
            for (x, o) in row.iter_mut().enumerate().skip(done) {
                let dx = if 2 * x + 1 < present[0] { 2 } else { 1 };
                let mut cell = [0f32; 8];
                let mut k = 0;
                for cz in 0..dz {
                    for cy in 0..dy {
                        for cx in 0..dx {
                            cell[k] = src[base + 2 * x + cx + from.at(0, cy, cz)];
                            k += 1;
                        }
                    }
                }
                *o = mean_of_finite(&cell[..k]);
            }
        }
    }
}

/// The mean of the finite values (summed in f64, in order), NaN where none is.
#[inline(always)]
fn mean_of_finite(values: &[f32]) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0u32);
    for &v in values {
        let f = v.is_finite();
        sum += if f { v as f64 } else { 0.0 };
        n += f as u32;
    }
    if n == 0 {
        f32::NAN
    } else {
        (sum / n as f64) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The straightforward statistics, one value after another.
    fn plain_stats(values: &[f32]) -> ([f32; 2], [f64; 3], f64) {
        let finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let range = if finite.is_empty() {
            [f32::NAN; 2]
        } else {
            [
                finite.iter().fold(f32::INFINITY, |a, &b| a.min(b)),
                finite.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b)),
            ]
        };
        let sum: f64 = finite.iter().map(|&v| v as f64).sum();
        let squares: f64 = finite.iter().map(|&v| v as f64 * v as f64).sum();
        let n = finite.len() as f64;
        (range, [sum, n, values.len() as f64 - n], squares)
    }

    #[test]
    fn lane_wise_statistics_match_the_plain_ones_on_odd_runs_with_non_finite_values() {
        let mut seed = 0x2545f491u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for case in 0..200 {
            let len = (next() % 300) as usize;
            let values: Vec<f32> = (0..len)
                .map(|_| match next() % 20 {
                    0 => f32::NAN,
                    1 => f32::INFINITY,
                    2 => f32::NEG_INFINITY,
                    _ => (next() % 100_000) as f32 / 7.0 - 5000.0,
                })
                .collect();
            // Added in runs of odd length, as a brick's rows at a far face arrive.
            let mut stats = BrickStats::new();
            let run = 1 + case % 13;
            values.chunks(run).for_each(|c| stats.add(c));
            let (range, sums, squares) = stats.finish();
            let (want_range, want_sums, want_squares) = plain_stats(&values);
            // Range and counts are exact; the sums change only by the order of the f64
            // additions: relative 1e-12 of the sum of magnitudes bounds that (300 values).
            assert_eq!(range.map(f32::to_bits), want_range.map(f32::to_bits));
            assert_eq!(sums[1..], want_sums[1..]);
            let scale: f64 = values
                .iter()
                .filter(|v| v.is_finite())
                .map(|&v| (v as f64).abs())
                .sum::<f64>()
                + 1.0;
            assert!(
                (sums[0] - want_sums[0]).abs() <= 1e-12 * scale,
                "case {case}"
            );
            assert!(
                (squares - want_squares).abs() <= 1e-12 * scale * scale,
                "case {case}"
            );
        }
    }

    #[test]
    fn halving_keeps_the_mean_of_the_finite_voxels_present_at_odd_faces() {
        // 5 x 3 x 3 voxels (odd on every axis) in a block with padded rows: 3 x 2 x 2 out.
        let (n0, n1, n2) = (5, 3, 3);
        let from = Grid {
            strides: [7, 7 * 4],
        };
        let mut src = vec![f32::MAX; 7 * 4 * n2];
        for z in 0..n2 {
            for y in 0..n1 {
                for x in 0..n0 {
                    src[from.at(x, y, z)] = (x * 100 + y * 10 + z) as f32;
                }
            }
        }
        src[from.at(0, 0, 0)] = f32::NAN;
        let n = [3, 2, 2];
        let mut out = vec![0f32; 12];
        let into = |first: bool, out: &mut [f32]| {
            halve(&src, from, [n0, n1, n2], n, first, out, Grid::dense(3, 2))
        };
        into(false, &mut out);
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..3 {
                    let (mut sum, mut k) = (0.0, 0);
                    for cz in 2 * z..(2 * z + 2).min(n2) {
                        for cy in 2 * y..(2 * y + 2).min(n1) {
                            for cx in 2 * x..(2 * x + 2).min(n0) {
                                let v = src[from.at(cx, cy, cz)];
                                if v.is_finite() {
                                    sum += v as f64;
                                    k += 1;
                                }
                            }
                        }
                    }
                    let want = (sum / k as f64) as f32;
                    assert_eq!(out[x + 3 * (y + 2 * z)], want, "voxel {x} {y} {z}");
                }
            }
        }
        // Phase keeps each cell's first voxel.
        into(true, &mut out);
        assert_eq!(out[1 + 3 * (1 + 2)], src[from.at(2, 2, 2)]);
        assert!(out[0].is_nan());
    }
}
