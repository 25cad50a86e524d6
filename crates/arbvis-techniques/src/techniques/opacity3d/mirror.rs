//! CPU mirrors of the precise paths at the GPU's own sample points, in f64: GPU against a
//! mirror isolates arithmetic (storage, filtering, f32) from discretization, which
//! [`reference`](super::reference::reference) measures.
//!
//! - [`emulate_precise`]: precise slicing, each sample with the opacity of its slab
//!   ([`slab_length`]).
//! - [`emulate_preintegrated`]: the pre-integrated ray caster: full steps from the entry,
//!   samples at both ends, the step read bilinearly from the same table the GPU gets,
//!   and the partial last step by its midpoint.

use glam::DVec3;

use super::prepare::Prepared;
use super::reference::{exact_rgba, over, sample, Filtering, ViewSlices};
use super::Opacity3dScene;
use crate::techniques::rays::{box_interval, trace_pixels};
use arbvis_core::camera::Camera;
use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;

/// Length of ray a precise slicing sample at `p` stands for, on a ray of unit direction
/// `dir` whose samples lie `2 half_step` apart: half a step each side, or, where the
/// neighbouring sample would lie outside the box `[-half, half]`, all the way to the face
/// where the ray enters or leaves. The slabs of one ray so tile its chord exactly (the
/// program templates compute the same in f32).
pub fn slab_length(p: DVec3, dir: DVec3, half: DVec3, half_step: f64) -> f64 {
    let q = DVec3::select(dir.cmplt(DVec3::ZERO), -p, p);
    let inv = DVec3::ONE / dir.abs().max(DVec3::splat(1e-20));
    let back = ((half + q) * inv).min_element();
    let fwd = ((half - q) * inv).min_element();
    let end = |d: f64| if d < 2.0 * half_step { d } else { half_step };
    end(back) + end(fwd)
}

/// CPU mirror of precise slicing: the GPU's slice planes and sample points, each sample
/// classified exactly as [`reference`] does, given the opacity of its slab
/// ([`slab_length`]) and composited far to near in f64. GPU against this isolates the
/// arithmetic (storage of the levels, filtering, f32) from the discretization, which
/// [`reference`] measures.
pub fn emulate_precise(
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    let half = prepared.half;
    let reference = prepared.reference_spacing();
    let corrected = super::renderer::corrected(params, arbvis_core::vocab::Fidelity::Precise);
    let slices = ViewSlices::new(half, camera, params.slices);
    trace_pixels(camera, size, TargetFormat::Rgba32f, |origin, dir| {
        let mut dst = background;
        let unit = dir.normalize();
        let half_step = slices.spacing() / 2.0 / unit.dot(slices.normal()).abs();
        for (p, tc) in slices.crossings(origin, dir) {
            let c = exact_rgba(prepared, params, tc);
            let a = if corrected {
                1.0 - (1.0 - c[3]).powf(slab_length(p, unit, half, half_step) / reference)
            } else {
                c[3]
            };
            over(&mut dst, c, a);
        }
        dst
    })
}

/// Bilinear lookup of a `SIZE²` RGBA table (row = back) at texel centres, clamped.
fn bilinear(table: &[f32], front: f64, back: f64) -> [f64; 4] {
    let n = super::preint::SIZE;
    let at = |i: i64, j: i64| {
        let (i, j) = (
            i.clamp(0, n as i64 - 1) as usize,
            j.clamp(0, n as i64 - 1) as usize,
        );
        let e = &table[(j * n + i) * 4..][..4];
        [e[0] as f64, e[1] as f64, e[2] as f64, e[3] as f64]
    };
    let (u, v) = (front * 255.0, back * 255.0);
    let (i, j) = (u.floor(), v.floor());
    let (wu, wv) = (u - i, v - j);
    let (i, j) = (i as i64, j as i64);
    let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
    std::array::from_fn(|k| {
        let lo = a[k] + (b[k] - a[k]) * wu;
        let hi = c[k] + (d[k] - c[k]) * wu;
        lo + (hi - lo) * wv
    })
}

/// CPU mirror of the pre-integrated ray caster (one attribute) with steps of
/// `1 / steps_per_voxel` reference spacings and the pre-integration `table` the GPU
/// gets ([`super::preint::preintegrate`]).
pub fn emulate_preintegrated(
    prepared: &Prepared,
    params: &Opacity3dScene,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
    steps_per_voxel: f64,
    table: &[f32],
) -> Image {
    let half = prepared.half;
    let reference = prepared.reference_spacing();
    let h = reference / steps_per_voxel;
    trace_pixels(camera, size, TargetFormat::Rgba32f, |origin, dir| {
        let Some((enter, exit)) = box_interval(origin, dir, half) else {
            return background;
        };
        let unit = dir.normalize();
        let entry = origin + dir * enter;
        let chord = (exit - enter) * dir.length();
        let full = (chord / h + 1e-4).floor();
        let rest = (chord - full * h).max(0.0);
        let tc = |t: f64| (entry + unit * t + half) / (2.0 * half);
        let value = |t: f64| sample(prepared, tc(t), params.volume_filter, Filtering::Exact)[0];
        let mut acc = [0.0f64; 4];
        let mut front = value(0.0);
        for j in 1..=full as usize {
            let back = value(j as f64 * h);
            let seg = bilinear(table, front, back);
            let w = 1.0 - acc[3];
            for (a, s) in acc.iter_mut().zip(seg) {
                *a += w * s;
            }
            front = back;
        }
        if rest > 1e-4 * h {
            let c = exact_rgba(prepared, params, tc(full * h + rest / 2.0));
            let a = 1.0 - (1.0 - c[3]).powf(rest / reference);
            let w = (1.0 - acc[3]) * a;
            for ch in 0..3 {
                acc[ch] += w * c[ch];
            }
            acc[3] += w;
        }
        // Over the background (premultiplied, as the blend does).
        std::array::from_fn(|c| acc[c] + (1.0 - acc[3]) * background[c])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_tile_the_chord() {
        // A ray along x through a box of half 1: chord 2, samples 0.3 apart.
        let half = DVec3::ONE;
        let dir = DVec3::X;
        let hs = 0.15;
        let xs: Vec<f64> = (0..7).map(|i| -0.95 + 0.3 * i as f64).collect();
        let total: f64 = xs
            .iter()
            .map(|&x| slab_length(DVec3::new(x, 0.2, -0.4), dir, half, hs))
            .sum();
        assert!((total - 2.0).abs() < 1e-12, "{total}");
        // The first sample stands for the 0.05 before it and half a step after.
        let first = slab_length(DVec3::new(-0.95, 0.2, -0.4), dir, half, hs);
        assert!((first - 0.2).abs() < 1e-12, "{first}");
        // A diagonal ray leaves through the nearest face: the end slab stops there.
        let d = DVec3::new(1.0, 1.0, 0.0).normalize();
        let p = DVec3::new(0.0, 0.9, 0.0);
        let to_face = 0.1 * 2f64.sqrt();
        let h = slab_length(p, d, half, 0.5);
        assert!((h - (0.5 + to_face)).abs() < 1e-12, "{h}");
    }
}
