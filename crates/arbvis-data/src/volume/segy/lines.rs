//! The grid a survey's inline and crossline numbers span, whether or not every position
//! holds a trace. Real surveys have irregular outlines (a missing corner, a gap where a
//! platform stood, lines shot short), so the grid is not the traces' count but the lines
//! their numbers name: from the smallest number to the largest in the numbers' common step
//! (the greatest common divisor of their differences; inlines 1000, 1002, ... give step 2).
//! A line whose number lies in that run but holds no trace (a gap) is a line of dead
//! traces, so the box keeps the survey's proportions. Every reader (in memory, the
//! streaming conversion, `inspect`) grids through [`Lines`], and a position without a
//! trace is dead: no data (NaN, `trace_mask` false), never zero amplitude.
//!
//! mdio-python grids by the numbers present (`np.unique`); the two agree wherever no whole
//! line is missing, and where one is, arbvis's grid holds it as a dead line (docs/stores.md).

use std::collections::BTreeSet;

/// How many lines the grid may hold per line present, beyond [`SPARSE_SLACK`]: more, and
/// the numbers are refused as no survey's lines (a stray number far off the others would
/// otherwise make a grid of millions of empty lines).
pub const MAX_SPARSITY: usize = 4;

/// Lines a grid may add beyond `MAX_SPARSITY` times those present.
pub const SPARSE_SLACK: usize = 64;

/// The line numbers of one axis: `first + q * step` for `q` in `0..count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lines {
    /// The smallest number.
    pub first: i32,
    /// The common step (1 for a single line).
    pub step: i64,
    /// Lines in the grid, gaps included.
    pub count: usize,
    /// Lines that hold at least one trace.
    pub present: usize,
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 {
        a.abs()
    } else {
        gcd(b, a % b)
    }
}

impl Lines {
    /// The lines `numbers` (the distinct numbers of the traces, any order) span; `axis`
    /// ("inline", "crossline") names them in the error.
    pub fn of(numbers: &BTreeSet<i32>, axis: &str) -> Result<Lines, GridError> {
        let (Some(&first), Some(&last)) = (numbers.first(), numbers.last()) else {
            return Err(GridError::Lines(format!("no {axis} numbers")));
        };
        let step = numbers
            .iter()
            .fold(0i64, |g, &n| gcd(g, n as i64 - first as i64))
            .max(1);
        let count = ((last as i64 - first as i64) / step + 1) as usize;
        let present = numbers.len();
        if count > MAX_SPARSITY * present + SPARSE_SLACK {
            let shown: Vec<String> = numbers.iter().take(8).map(i32::to_string).collect();
            return Err(GridError::Lines(format!(
                "the {present} {axis} numbers ({}{}) have no common step above {step}: a grid from {first} to {last} in steps of {step} would hold {count} {axis}s for the {present} that have traces (at most {MAX_SPARSITY}x + {SPARSE_SLACK} is gridded); if these are not {axis} numbers, name the bytes that hold them",
                shown.join(", "),
                if present > 8 { ", ..." } else { "" },
            )));
        }
        Ok(Lines {
            first,
            step,
            count,
            present,
        })
    }

    /// The grid's numbers, ascending.
    pub fn numbers(&self) -> Vec<i32> {
        (0..self.count)
            .map(|q| (self.first as i64 + q as i64 * self.step) as i32)
            .collect()
    }

    /// The index of line `number`, if it is one of the grid's.
    pub fn index(&self, number: i32) -> Option<usize> {
        let d = number as i64 - self.first as i64;
        (d >= 0 && d % self.step == 0 && ((d / self.step) as usize) < self.count)
            .then_some((d / self.step) as usize)
    }

    /// Lines of the grid that hold no trace.
    pub fn gaps(&self) -> usize {
        self.count - self.present
    }

    /// `1000..=2798 (900 values, step 2)`, with the lines without traces where there are
    /// any.
    pub fn describe(&self) -> String {
        if self.count == 1 {
            return format!("{} (one value)", self.first);
        }
        let last = self.first as i64 + (self.count as i64 - 1) * self.step;
        let gaps = match self.gaps() {
            0 => String::new(),
            1 => ", 1 of them without traces".to_string(),
            g => format!(", {g} of them without traces"),
        };
        format!(
            "{}..={last} ({} values, step {}{gaps})",
            self.first, self.count, self.step
        )
    }
}

/// The grid over (inline, crossline) of a post-stack survey: its lines, and which trace (if
/// any) sits at each position, inline-major (`k * crosslines + j`).
#[derive(Debug, Clone, PartialEq)]
pub struct TraceGrid {
    /// The inline lines (axis k).
    pub inlines: Lines,
    /// The crossline lines (axis j).
    pub crosslines: Lines,
    /// The trace at each position, [`TraceGrid::DEAD`] where none is.
    cells: Vec<u32>,
    /// Positions that hold a trace.
    pub live: usize,
}

/// Two traces at one position: their indices and the position's numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Duplicate {
    /// The earlier trace (0-based).
    pub first: u32,
    /// The later trace (0-based).
    pub second: u32,
    /// The inline and crossline numbers they share.
    pub at: (i32, i32),
}

/// Why traces cannot be gridded.
#[derive(Debug, Clone, PartialEq)]
pub enum GridError {
    /// Two traces at one position.
    Duplicate(Duplicate),
    /// The numbers of one axis are no survey's lines ([`Lines::of`]).
    Lines(String),
}

impl Duplicate {
    /// `traces 7 and 12 (bytes ... and ...) both sit at inline 3 crossline 9 (the bytes)`:
    /// trace numbers 1-based, `offset_of` the byte where a (0-based) trace starts.
    pub fn describe(&self, keys: &super::Keys, offset_of: impl Fn(u32) -> u64) -> String {
        format!(
            "traces {} and {} (bytes {} and {}) both sit at inline {} crossline {} ({})",
            self.first as u64 + 1,
            self.second as u64 + 1,
            offset_of(self.first),
            offset_of(self.second),
            self.at.0,
            self.at.1,
            keys.describe()
        )
    }
}

impl GridError {
    /// The error for `path`: a duplicate as [`Duplicate::describe`] with `duplicate_hint`
    /// after it, bad lines with the bytes they were read from.
    pub fn into_volume_error(
        self,
        path: &std::path::Path,
        keys: &super::Keys,
        offset_of: impl Fn(u32) -> u64,
        duplicate_hint: &str,
    ) -> crate::volume::VolumeError {
        let message = match self {
            GridError::Duplicate(d) => format!("{}{duplicate_hint}", d.describe(keys, offset_of)),
            GridError::Lines(m) => format!("{m} ({})", keys.describe()),
        };
        crate::volume::VolumeError::Unsupported {
            path: path.into(),
            message,
        }
    }
}

impl TraceGrid {
    /// The cell value of a position without a trace.
    pub const DEAD: u32 = u32::MAX;

    /// Grid traces given as `(inline, crossline, trace)`, in any order (sorted here).
    pub fn from_keys(mut keys: Vec<(i32, i32, u32)>) -> Result<TraceGrid, GridError> {
        keys.sort_unstable();
        if let Some(w) = keys
            .windows(2)
            .find(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1))
        {
            return Err(GridError::Duplicate(Duplicate {
                first: w[0].2.min(w[1].2),
                second: w[0].2.max(w[1].2),
                at: (w[0].0, w[0].1),
            }));
        }
        let inlines = Lines::of(&keys.iter().map(|k| k.0).collect(), "inline")?;
        let crosslines = Lines::of(&keys.iter().map(|k| k.1).collect(), "crossline")?;
        let nj = crosslines.count;
        let mut cells = vec![TraceGrid::DEAD; inlines.count * nj];
        for &(il, xl, t) in &keys {
            let (Some(k), Some(j)) = (inlines.index(il), crosslines.index(xl)) else {
                unreachable!("every number is on its axis's lines");
            };
            cells[k * nj + j] = t;
        }
        Ok(TraceGrid {
            inlines,
            crosslines,
            cells,
            live: keys.len(),
        })
    }

    /// A full grid whose trace at `(k, j)` is `trace(k, j)` (an inline-sorted file).
    pub fn full(inlines: Lines, crosslines: Lines, trace: impl Fn(usize, usize) -> u32) -> Self {
        let nj = crosslines.count;
        let cells = (0..inlines.count * nj)
            .map(|c| trace(c / nj, c % nj))
            .collect();
        TraceGrid {
            inlines,
            crosslines,
            cells,
            live: inlines.count * nj,
        }
    }

    /// The trace at inline index `k`, crossline index `j`, if one is there.
    pub fn trace(&self, k: usize, j: usize) -> Option<usize> {
        let t = self.cells[k * self.crosslines.count + j];
        (t != TraceGrid::DEAD).then_some(t as usize)
    }

    /// Positions in the grid.
    pub fn positions(&self) -> usize {
        self.cells.len()
    }

    /// Whether every position holds a trace.
    pub fn is_full(&self) -> bool {
        self.live == self.cells.len()
    }

    /// Whether each position holds a trace, inline-major.
    pub fn live_mask(&self) -> Vec<bool> {
        self.cells.iter().map(|&t| t != TraceGrid::DEAD).collect()
    }

    /// Up to six live traces spread over the grid (`(k, j, trace)`): the first and last
    /// live trace of the first, middle and last inline that hold any, for the survey's
    /// geometry.
    pub fn spread(&self) -> Vec<(usize, usize, usize)> {
        let nk = self.inlines.count;
        let rows: Vec<usize> = (0..nk)
            .filter(|&k| (0..self.crosslines.count).any(|j| self.trace(k, j).is_some()))
            .collect();
        let mut out = Vec::new();
        let picks = match rows.len() {
            0 => vec![],
            1 => vec![rows[0]],
            n => vec![rows[0], rows[n / 2], rows[n - 1]],
        };
        for k in picks {
            let live: Vec<usize> = (0..self.crosslines.count)
                .filter(|&j| self.trace(k, j).is_some())
                .collect();
            for j in [live[0], live[live.len() - 1]] {
                let t = (k, j, self.trace(k, j).expect("live"));
                if !out.contains(&t) {
                    out.push(t);
                }
            }
        }
        out
    }

    /// What `inspect` says of the grid: its size and the live traces.
    pub fn describe(&self) -> String {
        let (nk, nj, n) = (self.inlines.count, self.crosslines.count, self.positions());
        if self.is_full() {
            return format!("grid: {nk} inlines x {nj} crosslines, {n} traces");
        }
        format!(
            "grid: {nk} inlines x {nj} crosslines = {n} positions, {} live traces, {} dead (no trace there: no data, never drawn, left out of the statistics)",
            self.live,
            n - self.live
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(v: &[i32]) -> BTreeSet<i32> {
        v.iter().copied().collect()
    }

    #[test]
    fn lines_take_the_common_step_and_keep_gaps() {
        let l = Lines::of(&set(&[1000, 1002, 1008, 1004]), "inline").unwrap();
        assert_eq!((l.first, l.step, l.count, l.present), (1000, 2, 5, 4));
        assert_eq!(l.numbers(), vec![1000, 1002, 1004, 1006, 1008]);
        assert_eq!(l.index(1006), Some(3));
        assert_eq!(l.index(1005), None);
        assert_eq!(l.index(998), None);
        assert_eq!(l.index(1010), None);
        assert_eq!(
            l.describe(),
            "1000..=1008 (5 values, step 2, 1 of them without traces)"
        );
        // Negative and extreme numbers: differences in i64.
        let l = Lines::of(&set(&[i32::MIN, i32::MAX]), "crossline").unwrap();
        assert_eq!((l.step, l.count), (u32::MAX as i64, 2));
        assert_eq!(l.numbers(), vec![i32::MIN, i32::MAX]);
        let one = Lines::of(&set(&[-7]), "inline").unwrap();
        assert_eq!((one.step, one.count), (1, 1));
    }

    #[test]
    fn a_stray_number_is_refused_not_gridded_into_millions_of_lines() {
        let mut v: Vec<i32> = (0..100).map(|q| 1000 + 2 * q).collect();
        v.push(5_000_001);
        let Err(GridError::Lines(e)) = Lines::of(&set(&v), "inline") else {
            panic!("a stray number is refused as no survey's lines");
        };
        assert!(e.contains("the 101 inline numbers (1000, 1002,"), "{e}");
        assert!(
            e.contains("in steps of 1 would hold 4999002 inlines"),
            "{e}"
        );
    }

    #[test]
    fn a_grid_of_shuffled_keys_with_a_missing_corner() {
        // 4 inlines (step 3) x 5 crosslines (step 1), the corner (0, 0) and (0, 1) absent.
        let mut keys = Vec::new();
        let mut t = 0;
        for k in (0..4).rev() {
            for j in 0..5 {
                if k == 0 && j < 2 {
                    continue;
                }
                keys.push((10 + 3 * k, 7 + j, t));
                t += 1;
            }
        }
        let g = TraceGrid::from_keys(keys).unwrap();
        assert_eq!((g.inlines.count, g.crosslines.count, g.live), (4, 5, 18));
        assert_eq!(g.trace(0, 0), None);
        assert_eq!(g.trace(0, 2), Some(15));
        assert_eq!(g.trace(3, 0), Some(0));
        assert!(!g.is_full());
        assert_eq!(g.live_mask().iter().filter(|&&l| l).count(), 18);
        assert_eq!(
            g.spread(),
            vec![
                (0, 2, 15),
                (0, 4, 17),
                (2, 0, 5),
                (2, 4, 9),
                (3, 0, 0),
                (3, 4, 4)
            ]
        );
        assert!(
            g.describe().starts_with(
                "grid: 4 inlines x 5 crosslines = 20 positions, 18 live traces, 2 dead"
            ),
            "{}",
            g.describe()
        );
    }

    #[test]
    fn two_traces_at_one_position_are_named() {
        let e = TraceGrid::from_keys(vec![(1, 1, 0), (1, 2, 5), (1, 1, 3)]).unwrap_err();
        assert_eq!(
            e,
            GridError::Duplicate(Duplicate {
                first: 0,
                second: 3,
                at: (1, 1)
            })
        );
    }
}
