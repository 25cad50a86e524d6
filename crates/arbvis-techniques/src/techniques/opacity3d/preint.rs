//! Pre-integrated classification (Engel, Kraus and Ertl 2001) for the precise ray
//! caster of a one-attribute scene (CPU, no GL).
//!
//! The ray caster samples the attribute at both ends of each step of length `h` and reads
//! the step's colour and opacity from a 256 x 256 table indexed by the front and back
//! values: the emission-absorption integral over a segment along which the value runs
//! linearly from front to back, with the classification of precise mode (texel-centre
//! lookup, coefficients, 1/3 in a sum, clamp) and the extinction `-ln(1 - alpha) /
//! reference` that the reference's opacity correction implies. Each entry is integrated
//! in f64 with enough substeps to resolve every table entry the segment crosses (the
//! reference's own per-substep rule, 4 per level crossed), and stored
//! premultiplied: (colour, opacity) to composite front to back as they are.
//!
//! What is exact: along a ray the value is linear between samples only within one cell and
//! along an axis (trilinear interpolation is cubic along a general line), so this is the
//! integral of the piecewise-linear interpolation of the samples: second order in `h`, like
//! point sampling, but without point sampling's error from the table's own detail, which
//! dominates when the table changes faster than the data. Between table entries the
//! ray caster interpolates bilinearly. Only one attribute: the combined alpha of a sum or
//! product depends on all attributes' values, and a table over all of them would need
//! 256^6 entries (the sum's extinction does not even separate per attribute, because the
//! alphas add before the logarithm).

use rayon::prelude::*;

use super::reference::{lookup, Addressing, Filtering};
use super::Combine;
use arbvis_core::colortable::ColorTable;
use arbvis_gl::Filter;

/// Entries per side of the table (one per level).
pub const SIZE: usize = 256;

/// The classification of one attribute at value `v` in [0, 1]: colour and alpha.
pub fn classify_value(
    table: &ColorTable,
    coefficients: [f64; 4],
    combine: Combine,
    filter: Filter,
    v: f64,
) -> [f64; 4] {
    let lut = lookup(table, v, filter, Addressing::TexelCentre, Filtering::Exact);
    let scale = match combine {
        Combine::Sum => 1.0 / 3.0,
        Combine::Product => 1.0,
    };
    std::array::from_fn(|c| (coefficients[c] * lut[c] * scale).clamp(0.0, 1.0))
}

/// Entries of the baked table: 16 per level, so that every level is an entry.
pub const BAKED: usize = 255 * 16 + 1;

/// Largest error the baked table may leave (else the ray caster keeps `pow`).
pub const BAKED_TOLERANCE: f64 = 1e-5;

/// The ray caster's baked table for one attribute and steps of `exponent` reference
/// spacings: `BAKED` entries over [0, 1], each the classification at its value with the
/// exact opacity of one step, premultiplied; and the largest difference between its
/// linear interpolation and the exact model (alpha interpolated, then corrected), taken
/// at the midpoints and quarter points between entries. The model is smooth between
/// levels, its curvature `exponent (exponent - 1) Δalpha² (1 - alpha)^(exponent - 2)`
/// for an alpha step Δalpha between neighbouring entries: a table whose alpha moves by
/// 0.1 between entries keeps the error under [`BAKED_TOLERANCE`] (1.5 steps per voxel
/// or fewer), one that jumps from 0 to 0.9 does not (tested).
pub fn baked(
    table: &ColorTable,
    coefficients: [f64; 4],
    combine: Combine,
    filter: Filter,
    exponent: f64,
) -> (Vec<f32>, f64) {
    let exact = |v: f64| {
        let c = classify_value(table, coefficients, combine, filter, v);
        let a = 1.0 - (1.0 - c[3]).powf(exponent);
        [c[0] * a, c[1] * a, c[2] * a, a]
    };
    let step = 1.0 / (BAKED - 1) as f64;
    let entries: Vec<[f64; 4]> = (0..BAKED).map(|m| exact(m as f64 * step)).collect();
    let worst = entries
        .windows(2)
        .enumerate()
        .flat_map(|(m, pair)| {
            [0.25, 0.5, 0.75].map(|w| {
                let e = exact((m as f64 + w) * step);
                (0..4)
                    .map(|c| (pair[0][c] + (pair[1][c] - pair[0][c]) * w - e[c]).abs())
                    .fold(0.0, f64::max)
            })
        })
        .fold(0.0, f64::max);
    let data = entries.iter().flat_map(|e| e.map(|x| x as f32)).collect();
    (data, worst)
}

/// Substeps per level a segment is integrated with.
const SUB: usize = 4;

/// The table for steps of `exponent` reference spacings (`h / reference`): `SIZE²`
/// RGBA entries, row = back value, column = front value, premultiplied colour.
pub fn preintegrate(
    table: &ColorTable,
    coefficients: [f64; 4],
    combine: Combine,
    filter: Filter,
    exponent: f64,
) -> Vec<f32> {
    let g = |v: f64| classify_value(table, coefficients, combine, filter, v);
    let levels: Vec<[f64; 4]> = (0..SIZE).map(|k| g(k as f64 / 255.0)).collect();
    // A segment from level i to j takes SUB |i - j| substeps, whose midpoints are the
    // midpoints of a fixed grid of SUB parts per level: classify those once, keeping
    // ln(1 - alpha) so that a substep's opacity is one exp.
    let fine: Vec<([f64; 3], f64)> = (0..(SIZE - 1) * SUB)
        .map(|m| {
            let c = g((m as f64 + 0.5) / (SUB as f64 * 255.0));
            ([c[0], c[1], c[2]], (1.0 - c[3]).max(1e-300).ln())
        })
        .collect();
    (0..SIZE)
        .into_par_iter()
        .flat_map_iter(|back| {
            let (levels, fine) = (&levels, &fine);
            (0..SIZE).flat_map(move |front| {
                let rgba = if front == back {
                    // A homogeneous segment: exact.
                    let c = levels[front];
                    let a = 1.0 - (1.0 - c[3]).powf(exponent);
                    [c[0] * a, c[1] * a, c[2] * a, a]
                } else {
                    segment(fine, exponent, front, back)
                };
                rgba.map(|x| x as f32)
            })
        })
        .collect()
}

/// One segment from level `front` to level `back`: the midpoint rule over the fine grid's
/// parts between them, front to back.
fn segment(fine: &[([f64; 3], f64)], exponent: f64, front: usize, back: usize) -> [f64; 4] {
    let steps = SUB * front.abs_diff(back);
    let part = exponent / steps as f64;
    let mut acc = [0.0f64; 4];
    for s in 0..steps {
        let m = if back > front {
            front * SUB + s
        } else {
            front * SUB - 1 - s
        };
        let (c, log_transmit) = fine[m];
        let a = 1.0 - (log_transmit * part).exp();
        let w = (1.0 - acc[3]) * a;
        for ch in 0..3 {
            acc[ch] += w * c[ch];
        }
        acc[3] += w;
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> ColorTable {
        let mut t = ColorTable::builtin("grey").unwrap();
        for (k, e) in t.entries.iter_mut().enumerate() {
            *e = [k as u8, 255 - k as u8, 40, (k / 2) as u8];
        }
        t
    }

    #[test]
    fn the_diagonal_is_a_homogeneous_step_and_the_table_premultiplied() {
        let t = ramp();
        let p = preintegrate(&t, [1.0; 4], Combine::Product, Filter::Linear, 0.5);
        assert_eq!(p.len(), SIZE * SIZE * 4);
        let k = 200;
        let e = &p[(k * SIZE + k) * 4..][..4];
        let alpha = 100.0 / 255.0;
        let a = 1.0 - (1.0f64 - alpha).powf(0.5);
        assert!((e[3] as f64 - a).abs() < 1e-6, "{e:?}");
        assert!((e[0] as f64 - a * 200.0 / 255.0).abs() < 1e-6, "{e:?}");
        // Off the diagonal: opacity between the ends' (monotone alpha), colour <= opacity.
        let e = &p[(250 * SIZE + 10) * 4..][..4];
        let (lo, hi) = (
            1.0 - (1.0 - 5.0f64 / 255.0).powf(0.5),
            1.0 - (1.0 - 125.0f64 / 255.0).powf(0.5),
        );
        assert!(e[3] as f64 > lo && (e[3] as f64) < hi, "{e:?}");
        assert!(e.iter().take(3).all(|&c| c <= e[3] + 1e-7), "{e:?}");
    }

    /// The largest interpolation error over 20,000 values.
    fn dense_error(t: &ColorTable, c: [f64; 4], exponent: f64, b: &[f32]) -> f64 {
        let mut worst = 0f64;
        for s in 0..20_000 {
            let v = (s as f64 + 0.37) / 20_000.0;
            let x = v * (BAKED - 1) as f64;
            let (i, w) = (x.floor() as usize, x.fract());
            let g = classify_value(t, c, Combine::Product, Filter::Linear, v);
            let a = 1.0 - (1.0 - g[3]).powf(exponent);
            let exact = [g[0] * a, g[1] * a, g[2] * a, a];
            for ch in 0..4 {
                let lo = b[i * 4 + ch] as f64;
                let hi = b[(i + 1).min(BAKED - 1) * 4 + ch] as f64;
                worst = worst.max((lo + (hi - lo) * w - exact[ch]).abs());
            }
        }
        worst
    }

    #[test]
    fn the_baked_table_knows_its_own_error() {
        let c = [1.0, 0.8, 1.0, 1.0];
        // Alpha jumping between 0 and `top` at every entry: the steepest table there is.
        for (top, usable) in [(25u8, true), (229, false)] {
            let mut t = ramp();
            for (k, e) in t.entries.iter_mut().enumerate() {
                e[3] = if k % 2 == 0 { 0 } else { top };
            }
            for exponent in [0.25, 0.5, 1.0, 1.5] {
                let (b, worst) = baked(&t, c, Combine::Product, Filter::Linear, exponent);
                let dense = dense_error(&t, c, exponent, &b);
                // The estimate holds what 20,000 values find (f32 storage aside).
                assert!(
                    dense <= worst * 1.05 + 2e-7,
                    "{top} {exponent}: {dense} > {worst}"
                );
                // At exponent 1 there is no correction: only the premultiplication bends.
                let expected = usable || exponent == 1.0;
                assert_eq!(
                    worst < BAKED_TOLERANCE,
                    expected,
                    "{top} {exponent}: {worst}"
                );
            }
        }
    }

    #[test]
    fn a_segment_composites_like_many_small_steps() {
        // Front 30 to back 90 in one step of 2 reference spacings, against 20,000
        // homogeneous substeps composited front to back.
        let t = ramp();
        let c = [0.9, 1.0, 0.7, 0.8];
        let p = preintegrate(&t, c, Combine::Sum, Filter::Linear, 2.0);
        let e = &p[(90 * SIZE + 30) * 4..][..4];
        let n = 20_000;
        let mut acc = [0.0f64; 4];
        for s in 0..n {
            let v = (30.0 + 60.0 * (s as f64 + 0.5) / n as f64) / 255.0;
            let g = classify_value(&t, c, Combine::Sum, Filter::Linear, v);
            let a = 1.0 - (1.0 - g[3]).powf(2.0 / n as f64);
            let w = (1.0 - acc[3]) * a;
            for ch in 0..3 {
                acc[ch] += w * g[ch];
            }
            acc[3] += w;
        }
        for ch in 0..4 {
            assert!(
                (e[ch] as f64 - acc[ch]).abs() < 2e-6,
                "{ch}: {e:?} vs {acc:?}"
            );
        }
    }
}
