//! The faithful volume's pre-integrated table `T(sf, sb, length)` (Röttger, Kraus and Ertl
//! 2000; Engel, Kraus and Ertl 2001), CPU only: RGBA8, premultiplied colour and opacity,
//! `n x n x m` texels, texel `(i, j, k)` holding the segment from `sf = i/(n-1)` to `sb =
//! j/(n-1)` of length `k/(m-1)` times the longest edge of the mesh (so `sf`, `sb` and a
//! zero length fall on texels exactly; the programs map the three with one `MAD`).
//!
//! Two builds:
//! - [`Build::Engel`] (the era's): Engel et al.'s integral functions `T(s) = ∫0^s tau`
//!   and `K(s) = ∫0^s c tau`, exact for the piecewise-linear function; the opacity of a
//!   segment is then exact (`1 - exp(-L (T(sb) - T(sf)) / (sb - sf))`) and its colour the
//!   attenuation-weighted mean colour `(K(sb) - K(sf)) / (T(sb) - T(sf))` times that
//!   opacity: what it leaves out is the absorption inside the segment (front colours hide
//!   back ones). O(1) per texel: 1 M texels in a few ms.
//! - [`Build::Exact`]: every texel is [`Transfer::segment`] (cut at every control point
//!   crossed, each piece exact): no approximation but the texel grid and 8 bits, and
//!   O(points crossed) per texel.

use rayon::prelude::*;

pub use super::transfer::Build;
use super::transfer::Transfer;

/// `∫0^s tau` and `∫0^s c tau` of a piecewise-linear transfer function, exact.
struct Integrals<'a> {
    tf: &'a Transfer,
    /// Prefix sums at each control point: `[K_r, K_g, K_b, T]`.
    prefix: Vec<[f64; 4]>,
}

/// `∫x0^x1` of `[c tau (3), tau]` where both are linear between `a` at x0 and `b` at x1
/// (Simpson's rule: exact for the quadratic `c tau`).
fn piece(a: [f64; 4], b: [f64; 4], width: f64, unit: f64) -> [f64; 4] {
    let m: [f64; 4] = std::array::from_fn(|c| (a[c] + b[c]) / 2.0);
    let mut out = [0.0; 4];
    for c in 0..3 {
        out[c] = width / 6.0 * (a[c] * a[3] + 4.0 * m[c] * m[3] + b[c] * b[3]) / unit;
    }
    out[3] = width * (a[3] + b[3]) / 2.0 / unit;
    out
}

impl<'a> Integrals<'a> {
    fn new(tf: &'a Transfer) -> Integrals<'a> {
        let mut prefix = vec![[0.0; 4]];
        for k in 1..tf.s.len() {
            let p = piece(tf.rgba[k - 1], tf.rgba[k], tf.s[k] - tf.s[k - 1], tf.unit);
            let last = prefix[k - 1];
            prefix.push(std::array::from_fn(|c| last[c] + p[c]));
        }
        Integrals { tf, prefix }
    }

    /// The integrals from `s[0]` to `s` (the function is constant beyond the ends).
    fn at(&self, s: f64) -> [f64; 4] {
        let tf = self.tf;
        let n = tf.s.len();
        if s <= tf.s[0] {
            return piece(tf.rgba[0], tf.rgba[0], s - tf.s[0], tf.unit);
        }
        let k = tf.s.partition_point(|&x| x <= s).min(n);
        let base = self.prefix[k - 1];
        let rest = piece(tf.rgba[k - 1], tf.at(s), s - tf.s[k - 1], tf.unit);
        std::array::from_fn(|c| base[c] + rest[c])
    }
}

/// The table: `n x n x m` RGBA8 texels, `sf` fastest, then `sb`, then the length;
/// `longest` is the length of the last layer (object units).
pub fn table(tf: &Transfer, n: usize, m: usize, longest: f64, build: Build) -> Vec<u8> {
    texels(tf, n, m, longest, build, |v| {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    })
}

/// [`table`] in float (precise mode's `table` method): the same texels, unrounded.
pub fn table_f32(tf: &Transfer, n: usize, m: usize, longest: f64, build: Build) -> Vec<f32> {
    texels(tf, n, m, longest, build, |v| v.clamp(0.0, 1.0) as f32)
}

fn texels<T: Send>(
    tf: &Transfer,
    n: usize,
    m: usize,
    longest: f64,
    build: Build,
    texel: impl Fn(f64) -> T + Sync + Send + Copy,
) -> Vec<T> {
    let integrals = Integrals::new(tf);
    let s_at = |i: usize| i as f64 / (n - 1).max(1) as f64;
    let at: Vec<[f64; 4]> = (0..n).map(|i| integrals.at(s_at(i))).collect();
    (0..m)
        .into_par_iter()
        .flat_map_iter(|k| {
            let length = longest * k as f64 / (m - 1).max(1) as f64;
            let (at, integrals) = (&at, &integrals);
            (0..n * n).flat_map(move |ij| {
                let (i, j) = (ij % n, ij / n);
                let (sf, sb) = (s_at(i), s_at(j));
                let rgba = match build {
                    Build::Exact => tf.segment(sf, sb, length),
                    Build::Engel => engel(integrals, at[i], at[j], sf, sb, length),
                };
                rgba.map(texel)
            })
        })
        .collect()
}

/// One texel by integral functions (see the module doc).
fn engel(
    integrals: &Integrals<'_>,
    f: [f64; 4],
    b: [f64; 4],
    sf: f64,
    sb: f64,
    len: f64,
) -> [f64; 4] {
    let ds = sb - sf;
    let (depth, colour) = if ds.abs() < 1e-12 {
        let c = integrals.tf.at(sf);
        (len * c[3] / integrals.tf.unit, [c[0], c[1], c[2]])
    } else {
        let dt = b[3] - f[3];
        let mean = if dt.abs() > 1e-300 {
            std::array::from_fn(|c| (b[c] - f[c]) / dt)
        } else {
            let c = integrals.tf.at((sf + sb) / 2.0);
            [c[0], c[1], c[2]]
        };
        (len * dt / ds, mean)
    };
    let alpha = 1.0 - (-depth.max(0.0)).exp();
    [
        colour[0] * alpha,
        colour[1] * alpha,
        colour[2] * alpha,
        alpha,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tf() -> Transfer {
        Transfer {
            s: vec![0.0, 0.4, 0.45, 1.0],
            rgba: vec![
                [0.1, 0.2, 0.9, 0.0],
                [0.9, 0.6, 0.1, 0.2],
                [1.0, 0.0, 0.0, 0.9],
                [0.5, 0.5, 0.5, 0.1],
            ],
            unit: 0.2,
        }
    }

    #[test]
    fn engel_opacity_is_exact_and_colour_close_for_thin_segments() {
        let t = tf();
        let (n, m) = (11, 5);
        let longest = 0.4;
        let engel = table(&t, n, m, longest, Build::Engel);
        let exact = table(&t, n, m, longest, Build::Exact);
        let at = |v: &[u8], i: usize, j: usize, k: usize| -> [u8; 4] {
            let o = ((k * n + j) * n + i) * 4;
            [v[o], v[o + 1], v[o + 2], v[o + 3]]
        };
        for k in 0..m {
            for j in 0..n {
                for i in 0..n {
                    let (e, x) = (at(&engel, i, j, k), at(&exact, i, j, k));
                    // Opacity: both exact, then rounded to 8 bits: at most 1 level apart.
                    assert!(e[3].abs_diff(x[3]) <= 1, "{i} {j} {k}: {e:?} {x:?}");
                }
            }
        }
        // Zero length: nothing.
        assert_eq!(at(&engel, 3, 7, 0), [0; 4]);
        // Thin layer (k = 1): the colours agree within a few levels.
        for j in 0..n {
            for i in 0..n {
                let (e, x) = (at(&engel, i, j, 1), at(&exact, i, j, 1));
                for c in 0..3 {
                    assert!(e[c].abs_diff(x[c]) <= 3, "{i} {j}: {e:?} {x:?}");
                }
            }
        }
    }
}
