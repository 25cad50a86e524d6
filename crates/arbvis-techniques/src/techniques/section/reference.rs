//! The f64 CPU twin of a precise section: at each pixel centre the ray's hit on the plane,
//! the value there interpolated bilinearly from the four nearest samples (indices clamped
//! at the edges), its level over the range and the table interpolated between entries,
//! premultiplied by the opacity over the background. The arithmetic of
//! `programs/section/precise.*`, in f64; also what a section's picture is checked against
//! ("each pixel the survey's value on that plane").

use glam::{DVec3, DVec4};

use super::prepare::{Plane, Prepared};
use arbvis_core::camera::Camera;
use arbvis_core::colortable::ColorTable;
use arbvis_core::image::Image;
use arbvis_data::volume::axes::section_axes;

/// The least interpolated data weight a pixel is drawn with (the programs' `KIL`): a
/// sample without data given any weight above a millionth empties the pixel.
pub const DATA_WEIGHT: f64 = 0.999999;

/// The value at texture coordinates `st` (0..1 across and down, the plane's faces), or
/// None where a sample without data weighs in.
pub fn value_at(plane: &Plane, st: [f64; 2]) -> Option<f64> {
    let [nu, nw] = plane.size.map(|n| n.max(1));
    let t = [st[0] * nu as f64 - 0.5, st[1] * nw as f64 - 0.5];
    let lo = t.map(f64::floor);
    let f = [t[0] - lo[0], t[1] - lo[1]];
    let sample = |dx: f64, dy: f64| -> (f64, f64) {
        let x = (lo[0] + dx).clamp(0.0, (nu - 1) as f64) as usize;
        let y = (lo[1] + dy).clamp(0.0, (nw - 1) as f64) as usize;
        let v = plane.values[y * nu + x] as f64;
        match v.is_nan() {
            true => (0.0, 0.0),
            false => (v, 1.0),
        }
    };
    let lerp =
        |a: (f64, f64), b: (f64, f64), t: f64| (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
    let low = lerp(sample(0.0, 0.0), sample(1.0, 0.0), f[0]);
    let high = lerp(sample(0.0, 1.0), sample(1.0, 1.0), f[0]);
    let (value, data) = lerp(low, high, f[1]);
    (data >= DATA_WEIGHT).then_some(value)
}

/// The table's colour for `value` over `range`: level 255 (v - low) / (high - low)
/// clamped to [0, 255] (0 for an empty range), interpolated between the entries either side.
pub fn colour_of(table: &ColorTable, range: (f64, f64), value: f64) -> DVec3 {
    let (low, high) = range;
    let scale = if high > low {
        255.0 / (high - low)
    } else {
        0.0
    };
    let level = ((value - low) * scale).clamp(0.0, 255.0);
    let k = level.floor().min(254.0);
    let t = level - k;
    let entry = |k: usize| {
        let e = table.entries[k];
        DVec3::new(e[0] as f64, e[1] as f64, e[2] as f64) / 255.0
    };
    entry(k as usize).lerp(entry(k as usize + 1), t)
}

/// Where the ray through `ndc` (normalized device x, y) meets the plane, as texture
/// coordinates, if it does within the plane's faces and the depth range (`inverse`: the
/// inverse view-projection).
pub fn hit(prepared: &Prepared, inverse: glam::DMat4, ndc: [f64; 2]) -> Option<[f64; 2]> {
    let unproject = |z: f64| {
        let p: DVec4 = inverse * DVec4::new(ndc[0], ndc[1], z, 1.0);
        p.truncate() / p.w
    };
    let (near, far) = (unproject(-1.0), unproject(1.0));
    let axis = prepared.plane.axis;
    let (u, w) = section_axes(axis);
    let n = prepared.dims[axis].max(1) as f64;
    let at = ((prepared.plane.position + 0.5) / n * 2.0 - 1.0) * prepared.half[axis];
    let d: DVec3 = far - near;
    let t = (at - near[axis]) / d[axis];
    if !(0.0..=1.0).contains(&t) {
        return None;
    }
    let p = near + d * t;
    let st = [
        (p[u] / prepared.half[u] + 1.0) / 2.0,
        (p[w] / prepared.half[w] + 1.0) / 2.0,
    ];
    st.iter().all(|s| (0.0..=1.0).contains(s)).then_some(st)
}

/// The picture of `prepared`'s plane seen by `camera` on `size` pixels over `background`
/// (RGBA32F, top row first, alpha the coverage).
pub fn reference(
    prepared: &Prepared,
    opacity: f64,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> Image {
    let [w, h] = size.map(|s| s.max(1));
    let inverse = camera.view_projection(w as f64 / h as f64).inverse();
    let mut pixels = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        for x in 0..w {
            let ndc = [
                (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
                1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
            ];
            let colour = hit(prepared, inverse, ndc)
                .and_then(|st| value_at(&prepared.plane, st))
                .map(|v| colour_of(&prepared.table, prepared.range, v));
            let (c, a) = match colour {
                Some(c) => (c * opacity, opacity),
                None => (DVec3::ZERO, 0.0),
            };
            pixels.push([
                c.x + background[0] * (1.0 - a),
                c.y + background[1] * (1.0 - a),
                c.z + background[2] * (1.0 - a),
                a + background[3] * (1.0 - a),
            ]);
        }
    }
    Image::from_f64_pixels(w, h, arbvis_gl::TargetFormat::Rgba32f, pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(values: Vec<f32>, size: [usize; 2]) -> Plane {
        Plane {
            axis: 2,
            position: 0.0,
            size,
            values,
        }
    }

    #[test]
    fn values_interpolate_between_sample_centres_and_clamp_at_the_faces() {
        let p = plane(vec![0.0, 10.0, 20.0, 30.0, 40.0, 50.0], [3, 2]);
        // Sample centres at (i + 0.5) / n.
        assert_eq!(value_at(&p, [0.5 / 3.0, 0.25]), Some(0.0));
        assert_eq!(value_at(&p, [2.5 / 3.0, 0.75]), Some(50.0));
        // Half way between samples 0 and 1 across, a quarter of the way down from row 0
        // to row 1 (rows 30 apart).
        let v = value_at(&p, [1.0 / 3.0, 0.375]).unwrap();
        assert!((v - (5.0 + 7.5)).abs() < 1e-12, "{v}");
        // The faces clamp to the edge samples.
        assert_eq!(value_at(&p, [0.0, 0.0]), Some(0.0));
        assert_eq!(value_at(&p, [1.0, 1.0]), Some(50.0));
    }

    #[test]
    fn a_sample_without_data_empties_the_pixels_it_weighs_in() {
        let p = plane(vec![1.0, f32::NAN, 3.0, 4.0], [2, 2]);
        assert_eq!(
            value_at(&p, [0.25, 0.25]),
            Some(1.0),
            "its neighbour's centre"
        );
        assert_eq!(value_at(&p, [0.5, 0.25]), None);
        assert_eq!(value_at(&p, [0.25, 0.75]), Some(3.0));
    }

    #[test]
    fn colours_interpolate_between_entries_and_clamp_outside_the_range() {
        let table = ColorTable {
            entries: (0..256u32)
                .map(|k| [k as u8, (255 - k) as u8, (k * 7 % 256) as u8, 255])
                .collect(),
        };
        let c = colour_of(&table, (-1.0, 1.0), 0.0);
        // Level 127.5: half way between entries 127 and 128.
        assert!((c.x - 127.5 / 255.0).abs() < 1e-12);
        assert!((c.z - (127.0 * 7.0 % 256.0 + 128.0 * 7.0 % 256.0) / 2.0 / 255.0).abs() < 1e-12);
        assert_eq!(
            colour_of(&table, (-1.0, 1.0), 5.0),
            DVec3::new(1.0, 0.0, (255.0 * 7.0 % 256.0) / 255.0)
        );
        assert_eq!(
            colour_of(&table, (-1.0, 1.0), -5.0),
            DVec3::new(0.0, 1.0, 0.0)
        );
        assert_eq!(
            colour_of(&table, (2.0, 2.0), 9.0),
            DVec3::new(0.0, 1.0, 0.0),
            "an empty range is level 0"
        );
    }
}
