//! CPU mirrors of the 3D-opacity renderer (vello's habit: every GPU path has one).
//!
//! - [`reference`] (f64): what precise mode aims at, the emission-absorption integral of
//!   the classified field along each pixel's ray through the box. The field is the
//!   trilinear interpolation of the quantized attributes (GL's texel-centre convention),
//!   looked up at texel centres in the tables, combined (sum with an exact 1/3, or product)
//!   and clamped to [0, 1]. Table alpha is the opacity of one reference spacing
//!   ([`Prepared::reference_spacing`]), so a step `h` has `1 - (1 - a)^(h / ref)`. The
//!   integral is taken by the midpoint rule with `oversample` steps per reference spacing,
//!   far to near, over the background.
//!   With a clip, [`reference_clipped`] takes the analytic predicate
//!   ([`crate::techniques::clip::shape::Shape::inside`], `invert` applied): a sample
//!   outside the clip contributes nothing.
//! - [`super::mirror`] holds the CPU mirrors of the precise paths.
//! - [`emulate_faithful_llvmpipe`]: the same pipeline bit for bit as llvmpipe computes
//!   it (f32 program, llvmpipe's 8-bit blend), where filtering arithmetic is not involved.
//! - [`emulate_faithful`]: an independent emulation of the faithful 8-bit pipeline: the
//!   same slices as the GPU (planes perpendicular to the view axis at layer centres),
//!   trilinear fetch with 8-bit filtering arithmetic ([`Filtering::Unorm8`]), the original table addressing (`coord = v` into 256 texels), the
//!   verbatim constant 0.3333, no opacity correction, colour clamped and rounded to 8 bits
//!   and blended `SRC_ALPHA, ONE_MINUS_SRC_ALPHA` into an 8-bit target as 8-bit hardware
//!   does: `dst = round(src a / 255) + round(dst (255 - a) / 255)`, each product rounded on
//!   its own (measured on llvmpipe with constant tables: a = 2/255 over black adds exactly
//!   round(200 * 2 / 255) = 2 per slice, where one rounding of the sum would add 1 or 2).
//!
//! Both return the colour the target holds, top row first; alpha is coverage (the blend's
//! alpha factors are `ONE, ONE_MINUS_SRC_ALPHA`).

use glam::DVec3;

use super::prepare::Prepared;
use super::{coefficients, Combine, Opacity3dScene};
use crate::techniques::rays::{box_interval, trace_pixels};
use arbvis_core::camera::Camera;
use arbvis_core::colortable::ColorTable;
use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;
use arbvis_gl::Filter;

/// How a table is addressed with a value `v` in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Addressing {
    /// v3o2: `coord = v` into 256 texels (`k/255` lands a little right of texel `k`'s centre).
    Original,
    /// Precise: `coord = v * 255/256 + 0.5/256`, the centre of texel `v * 255`.
    TexelCentre,
}

/// Arithmetic of texture filtering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filtering {
    /// Exact (f64) interpolation: the reference.
    Exact,
    /// 8-bit hardware: every linear interpolation of unorm8 texels returns a value rounded
    /// to 8 bits (measured on llvmpipe: with it the emulation matches within 2 levels,
    /// without it by up to 37 levels after 64 slices, because the 8-bit blend accumulates
    /// any bias). Weights are kept exact.
    Unorm8,
}

fn lerp(p: f64, q: f64, w: f64, precision: Filtering) -> f64 {
    let v = p + (q - p) * w;
    match precision {
        Filtering::Exact => v,
        Filtering::Unorm8 => (v * 255.0).round() / 255.0,
    }
}

/// Look a value up in a table as GL does for a 256 x 1 texture with clamp-to-edge.
pub fn lookup(
    table: &ColorTable,
    v: f64,
    filter: Filter,
    addressing: Addressing,
    precision: Filtering,
) -> [f64; 4] {
    let coord = match addressing {
        Addressing::Original => v,
        Addressing::TexelCentre => v * 255.0 / 256.0 + 0.5 / 256.0,
    };
    let entry = |k: i64| table.entries[k.clamp(0, 255) as usize].map(|c| c as f64 / 255.0);
    match filter {
        Filter::Nearest => entry((coord * 256.0).floor() as i64),
        Filter::Linear => {
            let u = coord * 256.0 - 0.5;
            let k = u.floor();
            let w = u - k;
            let (a, b) = (entry(k as i64), entry(k as i64 + 1));
            std::array::from_fn(|c| lerp(a[c], b[c], w, precision))
        }
    }
}

/// The attributes' values (0..1) at texture coordinate `tc`, as GL samples the packed
/// RGB8 volume: primary, secondary, tertiary.
pub fn sample(prepared: &Prepared, tc: DVec3, filter: Filter, precision: Filtering) -> [f64; 3] {
    let d = prepared.dims;
    let byte = |i: i64, j: i64, k: i64, a: usize| {
        let (i, j, k) = (
            i.clamp(0, d[0] as i64 - 1) as usize,
            j.clamp(0, d[1] as i64 - 1) as usize,
            k.clamp(0, d[2] as i64 - 1) as usize,
        );
        prepared.byte(i + d[0] * (j + d[1] * k), a) as f64 / 255.0
    };
    let t = tc.to_array();
    match filter {
        Filter::Nearest => {
            let idx: [i64; 3] = std::array::from_fn(|a| (t[a] * d[a] as f64).floor() as i64);
            std::array::from_fn(|a| byte(idx[0], idx[1], idx[2], a))
        }
        Filter::Linear => {
            let u: [f64; 3] = std::array::from_fn(|a| t[a] * d[a] as f64 - 0.5);
            let i0: [i64; 3] = u.map(|x| x.floor() as i64);
            let w: [f64; 3] = std::array::from_fn(|a| u[a] - i0[a] as f64);
            let lerp = |p: f64, q: f64, w: f64| lerp(p, q, w, precision);
            std::array::from_fn(|a| {
                let v = |di: i64, dj: i64, dk: i64| byte(i0[0] + di, i0[1] + dj, i0[2] + dk, a);
                let x00 = lerp(v(0, 0, 0), v(1, 0, 0), w[0]);
                let x10 = lerp(v(0, 1, 0), v(1, 1, 0), w[0]);
                let x01 = lerp(v(0, 0, 1), v(1, 0, 1), w[0]);
                let x11 = lerp(v(0, 1, 1), v(1, 1, 1), w[0]);
                let y0 = lerp(x00, x10, w[1]);
                let y1 = lerp(x01, x11, w[1]);
                lerp(y0, y1, w[2])
            })
        }
    }
}

/// The combined RGBA at texture coordinate `tc`, before clamping: the sum scaled by
/// `sum_scale` (v3o2's 0.3333, or 1/3) or the product.
pub fn classify(
    prepared: &Prepared,
    params: &Opacity3dScene,
    tc: DVec3,
    addressing: Addressing,
    sum_scale: f64,
    precision: Filtering,
) -> [f64; 4] {
    let v = sample(prepared, tc, params.volume_filter, precision);
    let coeff = coefficients(params);
    let mut out = match params.combine {
        Combine::Sum => [0.0; 4],
        Combine::Product => [1.0; 4],
    };
    for a in 0..3 {
        let lut = match &prepared.tables[a] {
            Some(t) => lookup(t, v[a], params.table_filter, addressing, precision),
            None => match params.combine {
                Combine::Sum => continue,
                Combine::Product => [1.0; 4],
            },
        };
        for c in 0..4 {
            match params.combine {
                Combine::Sum => out[c] += coeff[a][c] * lut[c],
                Combine::Product => out[c] *= coeff[a][c] * lut[c],
            }
        }
    }
    if params.combine == Combine::Sum {
        out = out.map(|c| c * sum_scale);
    }
    out
}

/// The exact model's colour at texture coordinate `tc` (texel-centre addressing, the
/// sum's 1/3 exact, no 8-bit rounding), clamped to [0, 1] as a target would.
pub fn exact_rgba(prepared: &Prepared, params: &Opacity3dScene, tc: DVec3) -> [f64; 4] {
    classify(
        prepared,
        params,
        tc,
        Addressing::TexelCentre,
        1.0 / 3.0,
        Filtering::Exact,
    )
    .map(|v| v.clamp(0.0, 1.0))
}

/// Blend colour `c` of alpha `a` over `dst` as the renderer blends: `SRC_ALPHA,
/// ONE_MINUS_SRC_ALPHA` for colour, `ONE, ONE_MINUS_SRC_ALPHA` for alpha.
pub fn over(dst: &mut [f64; 4], c: [f64; 4], a: f64) {
    for ch in 0..3 {
        dst[ch] = c[ch] * a + dst[ch] * (1.0 - a);
    }
    dst[3] = a + dst[3] * (1.0 - a);
}

/// The f64 reference image (see the module doc); `oversample` steps per reference
/// spacing (8 or more keeps the quadrature error far below 8-bit steps).
pub fn reference(
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
    oversample: f64,
) -> Image {
    reference_clipped(
        prepared,
        params,
        camera,
        size,
        background,
        oversample,
        |_| true,
    )
}

/// [`reference()`] where only samples at object-space points `keep` accepts contribute
/// (a clip's [`crate::techniques::clip::shape::Shape::inside`]).
pub fn reference_clipped(
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
    oversample: f64,
    keep: impl Fn(DVec3) -> bool + Sync,
) -> Image {
    let reference = prepared.reference_spacing();
    let half = prepared.half;
    trace_pixels(camera, size, TargetFormat::Rgba32f, |origin, dir| {
        let mut dst = background;
        let Some((enter, exit)) = box_interval(origin, dir, half) else {
            return dst;
        };
        let length = (exit - enter) * dir.length();
        // A chord within 1e-4 step of a whole number of steps takes that number (the ray
        // caster rounds alike), so that f32 and f64 agree on ties such as axis views.
        let steps = ((length / reference * oversample - 1e-4).ceil() as usize).max(1);
        let exponent = length / steps as f64 / reference;
        // Far to near.
        for s in (0..steps).rev() {
            let t = enter + (exit - enter) * (s as f64 + 0.5) / steps as f64;
            let x = origin + dir * t;
            if !keep(x) {
                continue;
            }
            let tc = (x + half) / (2.0 * half);
            let c = exact_rgba(prepared, params, tc);
            let a = 1.0 - (1.0 - c[3]).powf(exponent);
            over(&mut dst, c, a);
        }
        dst
    })
}

/// The `count` view-aligned slices the renderer draws through a box of half-size `half`
/// (evenly spaced along the view direction over the box's extent, each at the centre of
/// its slab), and where a ray crosses them: what the CPU mirrors of slicing share.
pub(crate) struct ViewSlices {
    half: DVec3,
    normal: DVec3,
    extent: f64,
    spacing: f64,
    count: usize,
}

impl ViewSlices {
    /// The slices of `camera`'s view.
    pub(crate) fn new(half: DVec3, camera: &Camera, count: usize) -> ViewSlices {
        let normal = camera.toward_viewer().normalize();
        let extent = (half * normal.abs()).element_sum();
        ViewSlices {
            half,
            normal,
            extent,
            spacing: 2.0 * extent / count as f64,
            count,
        }
    }

    /// The slices' normal (toward the viewer).
    pub(crate) fn normal(&self) -> DVec3 {
        self.normal
    }

    /// Distance between neighbouring slices.
    pub(crate) fn spacing(&self) -> f64 {
        self.spacing
    }

    /// Where the ray `origin + t dir` crosses each slice inside the box, back to front:
    /// the point and its texture coordinate (none for a ray along the slices).
    pub(crate) fn crossings(
        &self,
        origin: DVec3,
        dir: DVec3,
    ) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
        let along = dir.dot(self.normal);
        let count = if along.abs() < 1e-300 { 0 } else { self.count };
        (0..count).filter_map(move |i| {
            let depth = -self.extent + (i as f64 + 0.5) * self.spacing;
            let p = origin + dir * ((depth - origin.dot(self.normal)) / along);
            let inside = (p.abs() - self.half).max_element() <= 1e-9;
            inside.then(|| (p, (p + self.half) / (2.0 * self.half)))
        })
    }
}

/// Independent emulation of the faithful pipeline into an 8-bit target (see the module
/// doc); values are multiples of 1/255.
pub fn emulate_faithful(
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    let slices = ViewSlices::new(prepared.half, camera, params.slices);
    let to8 = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round();
    // 8-bit blending: each product rounded on its own, then summed.
    let mul = |x: f64, y: f64| (x * y / 255.0).round();
    trace_pixels(camera, size, TargetFormat::Rgba8, |origin, dir| {
        let mut dst = background.map(to8);
        for (_, tc) in slices.crossings(origin, dir) {
            let src = classify(
                prepared,
                params,
                tc,
                Addressing::Original,
                0.3333_f32 as f64,
                Filtering::Unorm8,
            )
            .map(to8);
            let a = src[3];
            for ch in 0..3 {
                dst[ch] = (mul(src[ch], a) + mul(dst[ch], 255.0 - a)).min(255.0);
            }
            dst[3] = (a + mul(dst[3], 255.0 - a)).min(255.0);
        }
        dst.map(|v| v / 255.0)
    })
}

/// The two emulations of the faithful pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// Any 8-bit hardware: exact arithmetic rounded where 8-bit storage rounds
    /// ([`emulate_faithful`]).
    Generic,
    /// Mesa's llvmpipe, bit for bit where no filtering arithmetic is involved
    /// ([`emulate_faithful_llvmpipe`]).
    Llvmpipe,
}

/// `x · y / 255` as llvmpipe's 8-bit blend computes it: `p = x y`, then
/// `(p + (p >> 8) + 128) >> 8`, which is `round(p / 255)` except for 24 of the 65536
/// products (e.g. 152 · 229 / 255 = 136.5 gives 136).
pub fn llvmpipe_mul8(x: u32, y: u32) -> u32 {
    let p = x * y;
    (p + (p >> 8) + 128) >> 8
}

/// The faithful pipeline as llvmpipe computes it: texels convert to `k · f32(1/255)`, the
/// verbatim program runs in f32 (the coefficients as f32, `0.3333` as f32, each `MUL` and
/// `MAD` rounded to f32), the colour converts to 8 bits as `rint(f32(x · 255))` after
/// clamping, and each blend product is [`llvmpipe_mul8`], the two added with saturation
/// (alpha: `ONE, ONE_MINUS_SRC_ALPHA`). Linear filtering still goes through the generic
/// 8-bit model ([`Filtering::Unorm8`]), whose rounding order is not llvmpipe's.
pub fn emulate_faithful_llvmpipe(
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    let slices = ViewSlices::new(prepared.half, camera, params.slices);
    let unit = 1.0f32 / 255.0;
    let to8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round_ties_even() as u32;
    let coeff = coefficients(params).map(|c| c.map(|x| x as f32));
    // A texel value (a multiple of 1/255 from the 8-bit models) as llvmpipe's float.
    let texel = |v: f64| (v * 255.0).round() as f32 * unit;
    trace_pixels(camera, size, TargetFormat::Rgba8, |origin, dir| {
        let mut dst = background.map(|v| to8(v as f32));
        for (_, tc) in slices.crossings(origin, dir) {
            let v = sample(prepared, tc, params.volume_filter, Filtering::Unorm8).map(texel);
            let lut = |a: usize| -> [f32; 4] {
                match &prepared.tables[a] {
                    Some(t) => lookup_f32(t, v[a], params.table_filter).map(texel),
                    // The 1x1 white table of an absent attribute in a product; in a
                    // sum its coefficients are 0 and texture 0 reads black.
                    None => match params.combine {
                        Combine::Sum => [0.0; 4],
                        Combine::Product => [1.0; 4],
                    },
                }
            };
            let [l1, l2, l3] = [lut(0), lut(1), lut(2)];
            let src: [f32; 4] = std::array::from_fn(|c| match params.combine {
                Combine::Sum => {
                    let t = coeff[0][c] * l1[c];
                    let t = coeff[1][c] * l2[c] + t;
                    let t = coeff[2][c] * l3[c] + t;
                    t * 0.3333f32
                }
                Combine::Product => {
                    let (t1, t2, t3) = (
                        coeff[0][c] * l1[c],
                        coeff[1][c] * l2[c],
                        coeff[2][c] * l3[c],
                    );
                    (t2 * t1) * t3
                }
            });
            let src = src.map(to8);
            let a = src[3];
            for ch in 0..3 {
                dst[ch] = (llvmpipe_mul8(src[ch], a) + llvmpipe_mul8(dst[ch], 255 - a)).min(255);
            }
            dst[3] = (llvmpipe_mul8(a, 255) + llvmpipe_mul8(dst[3], 255 - a)).min(255);
        }
        dst.map(|v| v as f64 / 255.0)
    })
}

/// A table lookup with the original addressing for an f32 value, as llvmpipe does it:
/// nearest reads entry `floor(v · 256)` computed in f32 (clamped); linear goes through
/// the generic 8-bit model.
fn lookup_f32(table: &ColorTable, v: f32, filter: Filter) -> [f64; 4] {
    match filter {
        Filter::Nearest => {
            let k = ((v * 256.0).floor() as i64).clamp(0, 255) as usize;
            table.entries[k].map(|c| c as f64 / 255.0)
        }
        Filter::Linear => lookup(
            table,
            v as f64,
            filter,
            Addressing::Original,
            Filtering::Unorm8,
        ),
    }
}

/// The faithful emulation of `model`.
pub fn emulate_faithful_with(
    model: Model,
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    match model {
        Model::Generic => emulate_faithful(prepared, params, camera, size, background),
        Model::Llvmpipe => emulate_faithful_llvmpipe(prepared, params, camera, size, background),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn llvmpipe_mul8_is_not_always_round_p_over_255() {
        let mut differ = 0;
        for x in 0..=255u32 {
            for y in 0..=255u32 {
                let rounded = ((x * y) as f64 / 255.0).round() as u32;
                let l = llvmpipe_mul8(x, y);
                assert!(l.abs_diff(rounded) <= 1, "{x} {y}");
                differ += (l != rounded) as u32;
            }
            // Multiplying by 255 (a factor ONE) is exact.
            assert_eq!(llvmpipe_mul8(x, 255), x);
        }
        assert_eq!(differ, 24);
        assert_eq!(llvmpipe_mul8(152, 229), 136);
    }

    #[test]
    fn original_addressing_with_nearest_reads_entry_k() {
        let mut t = ColorTable::builtin("grey").unwrap();
        for (k, e) in t.entries.iter_mut().enumerate() {
            *e = [k as u8; 4];
        }
        for k in 0..256 {
            let v = k as f64 / 255.0;
            let orig = lookup(
                &t,
                v,
                Filter::Nearest,
                Addressing::Original,
                Filtering::Exact,
            );
            let centre = lookup(
                &t,
                v,
                Filter::Nearest,
                Addressing::TexelCentre,
                Filtering::Exact,
            );
            assert_eq!(orig[0] * 255.0, k as f64);
            assert!((centre[0] * 255.0 - k as f64).abs() < 1e-9);
            // With LINEAR, texel-centre addressing is exact and the original is not.
            let lin = lookup(
                &t,
                v,
                Filter::Linear,
                Addressing::TexelCentre,
                Filtering::Exact,
            );
            assert!((lin[0] * 255.0 - k as f64).abs() < 1e-9);
        }
        // The original addressing reads k + (k/255 - 0.5): half an entry off at the ends.
        let end = lookup(
            &t,
            0.0,
            Filter::Linear,
            Addressing::Original,
            Filtering::Exact,
        );
        assert_eq!(end[0], 0.0); // clamped at the edge
        let mid = lookup(
            &t,
            64.0 / 255.0,
            Filter::Linear,
            Addressing::Original,
            Filtering::Exact,
        );
        assert!((mid[0] * 255.0 - (64.0 + 64.0 / 255.0 - 0.5)).abs() < 1e-9);
    }
}
