//! Which quantized levels each brick of a store may hold, per attribute and level: what
//! lets the bricked renderer leave out the bricks its tables make transparent. No GL.
//!
//! A brick's range is grown by its neighbours' (a brick is drawn with a one-voxel border
//! taken from them). A coarse level is the mean of the one below, so its own range can be
//! narrower than its children's (a reflection's peak averages away): a parent takes the
//! union of its children's ranges, so that leaving out a brick that looks transparent
//! never leaves out a visible brick under it.

use arbvis_data::store::{Store, StoreError};
use arbvis_data::volume::quantize::{quantize_level, NoData};

/// Per brick of one level (x fastest), per attribute, the lowest and highest quantized
/// level it may hold.
pub type LevelRanges = Vec<[(u8, u8); 3]>;

/// An attribute as a store holds it: its index in the store, the value range its levels
/// quantize, and how no-data is drawn.
pub type StoreAttribute = (usize, f64, f64, NoData);

/// The ranges of every level of `store` for the attributes `attrs` (by the scene's
/// attribute slot; `None`: absent, its ranges left `(0, 0)`).
pub fn brick_ranges(
    store: &Store,
    attrs: &[Option<StoreAttribute>; 3],
) -> Result<Vec<LevelRanges>, StoreError> {
    let meta = &store.meta;
    let counts: Vec<[usize; 3]> = (0..meta.levels).map(|l| meta.brick_counts(l)).collect();
    let mut levels = Vec::with_capacity(meta.levels);
    for (level, &level_counts) in counts.iter().enumerate() {
        let mut per = vec![[(0u8, 0u8); 3]; level_counts.iter().product::<usize>()];
        for (a, at) in attrs.iter().enumerate() {
            let Some((index, low, high, no_data)) = *at else {
                continue;
            };
            let ranges = store.ranges(index, level)?;
            let quantize = |v: f32| quantize_level(v, low, high, no_data);
            let grown = grown_by_neighbours(&ranges, level_counts, quantize);
            for (brick, (lo, hi)) in per.iter_mut().zip(grown) {
                // Where no-data can occur it takes level 0 (transparent by the table), so
                // every brick may hold 0; a brick with no values holds only it.
                let lo = if no_data != NoData::Absent || lo > hi {
                    0
                } else {
                    lo
                };
                brick[a] = (lo, hi);
            }
        }
        levels.push(per);
    }
    union_children(&mut levels, &counts);
    Ok(levels)
}

/// Each brick of a level of `counts` bricks: the quantized range (`quantize`d `[min,
/// max]`) of its own values and its 26 neighbours'; `(255, 0)` where none holds a value
/// (`min > max` in `ranges`).
pub fn grown_by_neighbours(
    ranges: &[[f32; 2]],
    counts: [usize; 3],
    quantize: impl Fn(f32) -> u8,
) -> Vec<(u8, u8)> {
    let near = |c: usize, n: usize| c.saturating_sub(1)..=(c + 1).min(n - 1);
    let mut out = Vec::with_capacity(counts.iter().product());
    for k in 0..counts[2] {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let (mut lo, mut hi) = (255u8, 0u8);
                for dk in near(k, counts[2]) {
                    for dj in near(j, counts[1]) {
                        for di in near(i, counts[0]) {
                            let r = ranges[di + counts[0] * (dj + counts[1] * dk)];
                            if r[0] <= r[1] {
                                lo = lo.min(quantize(r[0]));
                                hi = hi.max(quantize(r[1]));
                            }
                        }
                    }
                }
                out.push((lo, hi));
            }
        }
    }
    out
}

/// Widen each brick of level `l` to the union of its (up to eight) children's ranges in
/// level `l - 1`, from the finest level up; `counts` are the levels' brick counts.
pub fn union_children(levels: &mut [LevelRanges], counts: &[[usize; 3]]) {
    for level in 1..levels.len() {
        let (below, here) = levels.split_at_mut(level);
        let (fine, coarse) = (&below[level - 1], &mut here[0]);
        let (fc, cc) = (counts[level - 1], counts[level]);
        for k in 0..cc[2] {
            for j in 0..cc[1] {
                for i in 0..cc[0] {
                    let at = i + cc[0] * (j + cc[1] * k);
                    for (dk, dj, di) in (0..8).map(|n| (n >> 2, (n >> 1) & 1, n & 1)) {
                        let c = [2 * i + di, 2 * j + dj, 2 * k + dk];
                        if (0..3).any(|a| c[a] >= fc[a]) {
                            continue;
                        }
                        let child = fine[c[0] + fc[0] * (c[1] + fc[1] * c[2])];
                        for a in 0..3 {
                            let (lo, hi) = child[a];
                            if lo <= hi {
                                let r = &mut coarse[at][a];
                                *r = (r.0.min(lo), r.1.max(hi));
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Levels 0..=255 from 0..=1, as a table's quantization.
    fn level(v: f32) -> u8 {
        (v * 255.0).round() as u8
    }

    #[test]
    fn a_brick_takes_its_neighbours_values_and_an_empty_row_takes_nothing() {
        // Four bricks in a row, the third empty (min > max), on a 4x1x1 level.
        let ranges = [[0.0, 0.1], [0.5, 0.6], [1.0, -1.0], [0.9, 1.0]];
        let grown = grown_by_neighbours(&ranges, [4, 1, 1], level);
        assert_eq!(
            grown,
            vec![
                (0, level(0.6)),
                (0, level(0.6)),
                (level(0.5), 255),
                (level(0.9), 255)
            ]
        );
        // No brick holds a value: nothing anywhere.
        let empty = [[1.0, 0.0]; 3];
        assert_eq!(
            grown_by_neighbours(&empty, [1, 3, 1], level),
            vec![(255, 0); 3]
        );
    }

    #[test]
    fn neighbours_reach_across_all_three_axes() {
        // 3x3x3 bricks, one value in the far corner: only its 2x2x2 corner sees it.
        let mut ranges = vec![[1.0f32, 0.0]; 27];
        ranges[26] = [0.4, 0.4];
        let grown = grown_by_neighbours(&ranges, [3, 3, 3], level);
        for (n, r) in grown.iter().enumerate() {
            let (i, j, k) = (n % 3, (n / 3) % 3, n / 9);
            let sees = i >= 1 && j >= 1 && k >= 1;
            let want = if sees {
                (level(0.4), level(0.4))
            } else {
                (255, 0)
            };
            assert_eq!(*r, want, "brick ({i}, {j}, {k})");
        }
    }

    #[test]
    fn a_parent_covers_every_child_even_an_odd_edge_one() {
        // Level 0: 3x1x1 bricks; level 1: 2x1x1 (the second parent has one child).
        let fine: LevelRanges = vec![
            [(10, 20), (0, 0), (5, 5)],
            [(30, 40), (0, 0), (255, 0)],
            [(200, 210), (0, 0), (255, 0)],
        ];
        let coarse: LevelRanges = vec![[(25, 26), (0, 0), (255, 0)]; 2];
        let mut levels = vec![fine.clone(), coarse];
        union_children(&mut levels, &[[3, 1, 1], [2, 1, 1]]);
        assert_eq!(levels[0], fine, "the finest level is unchanged");
        // Attribute 0: the union; attribute 2: an empty child adds nothing.
        assert_eq!(levels[1][0], [(10, 40), (0, 0), (5, 5)]);
        assert_eq!(levels[1][1], [(25, 210), (0, 0), (255, 0)]);
    }
}
