//! [`SortMethod::Radix`](super::SortMethod::Radix): a parallel radix sort of
//! (key bits, index) pairs, one most-significant-digit pass over the whole array, then
//! least-significant-digit passes inside each bucket (see [`super`] for the keys and
//! the stability rule, and `radix_with` for the steps).

use rayon::prelude::*;

use super::{too_many, View};

/// The u32 whose integer order is the reverse of `k`'s float order (for a canonical
/// key: no NaN, no -0), so that ascending radix order is farthest first.
#[inline]
fn descending_bits(k: f32) -> u32 {
    let b = k.to_bits();
    let ascending = if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    };
    !ascending
}

/// Bits of the first (most significant) radix digit: 2048 buckets.
pub const RADIX_BITS: u32 = 11;

/// Below this many points the radix sort runs on one thread.
pub(super) const PARALLEL_MIN: usize = 1 << 16;

/// Buckets up to this size are finished with a comparison sort.
const SMALL_BUCKET: usize = 48;

/// Buffers kept between radix sorts.
#[derive(Debug, Default, Clone)]
pub struct RadixScratch {
    a: Vec<u64>,
    b: Vec<u64>,
}

/// The radix sort into `out` (cleared first), reusing `scratch`.
pub fn radix_order_into(
    positions: &[[f32; 3]],
    view: View,
    scratch: &mut RadixScratch,
    out: &mut Vec<u32>,
) {
    radix_with(positions, view, scratch, out, RADIX_BITS);
}

/// `slice` cut into consecutive parts of the given sizes.
fn split_sizes<T>(mut rest: &mut [T], sizes: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut parts = Vec::new();
    for size in sizes {
        let (part, tail) = std::mem::take(&mut rest).split_at_mut(size);
        parts.push(part);
        rest = tail;
    }
    parts
}

/// The radix sort with a first digit of `top_bits` bits. Pairs are `key << 32 | index`
/// with `key` the descending bits less the smallest one, so only `bits` bits vary:
/// 1. one most-significant-digit pass on the top `top_bits` of them: per-chunk
///    histograms, then every chunk scatters into its own ranges (stable);
/// 2. each bucket, now independent and small enough for the cache, is sorted on the
///    remaining low bits by LSD passes of up to 8 bits between its range of the output
///    and the same range of the input buffer (a comparison sort below
///    [`SMALL_BUCKET`]: pairs are unique, so any correct sort is the stable order),
///    buckets in parallel, and writes its indices straight into `out`.
pub(super) fn radix_with(
    positions: &[[f32; 3]],
    view: View,
    scratch: &mut RadixScratch,
    out: &mut Vec<u32>,
    top_bits: u32,
) {
    out.clear();
    let n = positions.len();
    if n == 0 || too_many(n) {
        return;
    }
    let chunks = if n < PARALLEL_MIN {
        1
    } else {
        rayon::current_num_threads().max(1)
    };
    let chunk_len = n.div_ceil(chunks);
    let RadixScratch { a, b } = scratch;
    a.resize(n, 0);
    b.resize(n, 0);
    out.resize(n, 0);
    let (lo, hi) = a
        .par_chunks_mut(chunk_len)
        .zip(positions.par_chunks(chunk_len))
        .enumerate()
        .map(|(c, (slots, points))| match view {
            // One loop per kind, so the view is not matched per point.
            View::Eye(_) => fill_pairs(slots, points, c * chunk_len, |p| view.key(p)),
            View::Along(_) => fill_pairs(slots, points, c * chunk_len, |p| view.key(p)),
        })
        .reduce(|| (u32::MAX, 0), |x, y| (x.0.min(y.0), x.1.max(y.1)));
    let bits = 32 - (hi - lo).leading_zeros();
    if bits == 0 {
        // All keys equal: index order.
        out.par_iter_mut()
            .enumerate()
            .for_each(|(i, o)| *o = i as u32);
        return;
    }
    let top = top_bits.clamp(1, 16).min(bits);
    let low_bits = bits - top;
    let radix = 1usize << top;
    let digit = move |v: u64| (((v >> 32) as u32 - lo) >> low_bits) as usize;
    let counts: Vec<Vec<usize>> = a
        .par_chunks(chunk_len)
        .map(|chunk| {
            let mut count = vec![0usize; radix];
            for &v in chunk {
                count[digit(v)] += 1;
            }
            count
        })
        .collect();
    // Ranges of `b` ordered by digit, then chunk: each chunk writes only its own.
    let sizes = (0..radix).flat_map(|d| counts.iter().map(move |count| count[d]));
    let mut ranges: Vec<Vec<&mut [u64]>> = (0..counts.len())
        .map(|_| Vec::with_capacity(radix))
        .collect();
    for (k, range) in split_sizes(b, sizes).into_iter().enumerate() {
        ranges[k % counts.len()].push(range);
    }
    a.par_chunks(chunk_len)
        .zip(ranges.into_par_iter())
        .for_each(|(chunk, ranges)| {
            let mut slots: Vec<_> = ranges.into_iter().map(|r| r.iter_mut()).collect();
            for &v in chunk {
                // Never `None`: the ranges were sized by this chunk's own counts.
                if let Some(slot) = slots[digit(v)].next() {
                    *slot = v;
                }
            }
        });
    let buckets = (0..radix).map(|d| counts.iter().map(|count| count[d]).sum::<usize>());
    let buckets: Vec<usize> = buckets.collect();
    split_sizes(b, buckets.iter().copied())
        .into_par_iter()
        .zip(split_sizes(out, buckets.iter().copied()))
        .for_each_init(
            || (vec![0u32; 1024], Vec::new()),
            |(hist, spare), (data, out)| {
                // A per-task buffer that stays in the cache, not a cold range of `a`.
                spare.resize(spare.len().max(data.len()), 0);
                sort_bucket(data, &mut spare[..data.len()], out, hist, lo, low_bits)
            },
        );
}

/// Fill `slots` with `key bits << 32 | index` (indices from `first`); the range of the
/// key bits.
#[inline]
fn fill_pairs(
    slots: &mut [u64],
    points: &[[f32; 3]],
    first: usize,
    key: impl Fn(&[f32; 3]) -> f32,
) -> (u32, u32) {
    let (mut lo, mut hi) = (u32::MAX, 0u32);
    for (j, (slot, p)) in slots.iter_mut().zip(points).enumerate() {
        let k = descending_bits(key(p));
        lo = lo.min(k);
        hi = hi.max(k);
        *slot = (k as u64) << 32 | (first + j) as u64;
    }
    (lo, hi)
}

/// Sort one bucket on its low `bits` key bits (see [`radix_with`]) and write its
/// indices into `out`; `hist` is a reusable buffer of at least 1024 counters.
fn sort_bucket(
    data: &mut [u64],
    spare: &mut [u64],
    out: &mut [u32],
    hist: &mut [u32],
    lo: u32,
    bits: u32,
) {
    if bits == 0 || data.len() <= SMALL_BUCKET {
        // Equal keys are already in index order; unique pairs sort to the stable order.
        if bits != 0 {
            data.sort_unstable();
        }
        for (o, v) in out.iter_mut().zip(data.iter()) {
            *o = *v as u32;
        }
        return;
    }
    // Up to 4 passes of up to 8 bits; one sweep counts the digits of all of them.
    let passes = bits.div_ceil(8);
    let width = bits.div_ceil(passes);
    let radix = 1usize << width;
    let mask = (1u32 << width) - 1;
    let key = |v: u64| (v >> 32) as u32 - lo;
    let hist = &mut hist[..passes as usize * radix];
    hist.fill(0);
    for (p, h) in hist.chunks_exact_mut(radix).enumerate() {
        let shift = p as u32 * width;
        for &v in data.iter() {
            h[((key(v) >> shift) & mask) as usize] += 1;
        }
    }
    for h in hist.chunks_exact_mut(radix) {
        let mut sum = 0;
        for c in h.iter_mut() {
            let count = *c;
            *c = sum;
            sum += count;
        }
    }
    let (mut src, mut dst) = (data, spare);
    for (p, h) in hist.chunks_exact_mut(radix).enumerate() {
        let shift = p as u32 * width;
        if p as u32 + 1 == passes {
            // The last pass writes the indices straight into `out`.
            for &v in src.iter() {
                let d = ((key(v) >> shift) & mask) as usize;
                out[h[d] as usize] = v as u32;
                h[d] += 1;
            }
        } else {
            for &v in src.iter() {
                let d = ((key(v) >> shift) & mask) as usize;
                dst[h[d] as usize] = v;
                h[d] += 1;
            }
            std::mem::swap(&mut src, &mut dst);
        }
    }
}
