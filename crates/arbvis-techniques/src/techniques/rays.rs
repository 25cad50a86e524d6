//! Pixel rays for the CPU references: one ray per pixel centre, in object space, from
//! the near plane to the far plane of the camera's projection (so orthographic and
//! perspective views are handled alike), traced in parallel rows. A large reference is
//! announced with its estimated time before it starts (timed on 1 pixel in 256), and
//! shows a progress bar ([`arbvis_core::progress`]), or plain lines where no bar is drawn,
//! when it runs longer than a couple of seconds.

use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

use arbvis_core::camera::Camera;
use arbvis_core::image::Image;
use arbvis_core::progress::{Bar, Lines, Unit};
use arbvis_core::vocab::TargetFormat;

/// A pixel's ray in object space: origin on the near plane, direction toward the far
/// plane (not normalized: the parameter runs 0..1 from near to far).
pub fn pixel_ray(inverse: &DMat4, x: u32, y: u32, width: u32, height: u32) -> (DVec3, DVec3) {
    let nx = 2.0 * (x as f64 + 0.5) / width as f64 - 1.0;
    let ny = 1.0 - 2.0 * (y as f64 + 0.5) / height as f64;
    let unproject = |z: f64| {
        let p = *inverse * DVec4::new(nx, ny, z, 1.0);
        p.truncate() / p.w
    };
    let near = unproject(-1.0);
    (near, unproject(1.0) - near)
}

/// Parameter interval `[enter, exit]` of a ray inside the box `[-half, half]`.
pub fn box_interval(origin: DVec3, dir: DVec3, half: DVec3) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if dir[a].abs() < 1e-300 {
            if origin[a].abs() > half[a] {
                return None;
            }
            continue;
        }
        let t0 = (-half[a] - origin[a]) / dir[a];
        let t1 = (half[a] - origin[a]) / dir[a];
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    (hi > lo).then_some((lo, hi))
}

/// How long a reference runs before its bar appears.
const BAR_AFTER: std::time::Duration = std::time::Duration::from_secs(2);

/// Trace one ray per pixel centre (object space, near to far) in parallel rows and
/// collect `shade(origin, dir)` as an image of `format`, top row first.
pub fn trace_pixels(
    camera: &Camera,
    size: [u32; 2],
    format: TargetFormat,
    shade: impl Fn(DVec3, DVec3) -> [f64; 4] + Sync,
) -> Image {
    let pixels = trace_rays(camera, size, shade);
    Image::from_f64_pixels(size[0], size[1], format, pixels)
}

/// [`trace_pixels`] for any per-pixel result: `shade(origin, dir)` of every pixel, top
/// row first.
pub fn trace_rays<T: Send>(
    camera: &Camera,
    size: [u32; 2],
    shade: impl Fn(DVec3, DVec3) -> T + Sync,
) -> Vec<T> {
    let [width, height] = size;
    let aspect = width as f64 / height.max(1) as f64;
    let inverse = camera.view_projection(aspect).inverse();
    announce_cost(size, &|x, y| {
        let (origin, dir) = pixel_ray(&inverse, x, y, width, height);
        shade(origin, dir);
    });
    // A bar (rows done, time left) for references that run past a couple of seconds, or
    // plain lines where no bar is drawn.
    let bar = Bar::delayed(height as u64, "f64 reference", Unit::Rows, BAR_AFTER);
    let lines = Lines::new("f64 reference, rows", height as u64, BAR_AFTER, LINE_EVERY);
    (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            let row: Vec<T> = (0..width)
                .map(|x| {
                    let (origin, dir) = pixel_ray(&inverse, x, y, width, height);
                    shade(origin, dir)
                })
                .collect();
            bar.inc(1);
            lines.inc(1);
            row
        })
        .collect()
}

/// How often a plain progress line is printed while a reference runs.
const LINE_EVERY: std::time::Duration = std::time::Duration::from_secs(10);

/// References estimated to take longer than this are announced before they start.
const ANNOUNCE_ABOVE_S: f64 = 5.0;

/// Before a large reference: trace every 16th pixel of every 16th row (1/256 of the work,
/// spread over the image), and if the whole would take more than [`ANNOUNCE_ABOVE_S`], say
/// how long before starting it.
fn announce_cost(size: [u32; 2], trace: &(impl Fn(u32, u32) + Sync)) {
    let [width, height] = size;
    const STRIDE: u32 = 16;
    let pixels = width as u64 * height as u64;
    if pixels < 256 * 256 {
        return;
    }
    let t0 = std::time::Instant::now();
    let samples: u64 = (0..height)
        .into_par_iter()
        .step_by(STRIDE as usize)
        .map(|y| {
            (0..width)
                .step_by(STRIDE as usize)
                .for_each(|x| trace(x, y));
            width.div_ceil(STRIDE) as u64
        })
        .sum();
    let estimate = t0.elapsed().as_secs_f64() * pixels as f64 / samples.max(1) as f64;
    if estimate > ANNOUNCE_ABOVE_S {
        arbvis_core::progress::line(&format!(
            "f64 reference at {width}x{height}: about {estimate:.0} s on this machine (timed on 1 pixel in {}); its progress follows",
            STRIDE * STRIDE
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_interval_of_an_axis_ray() {
        let half = DVec3::new(1.0, 0.5, 0.25);
        let (a, b) =
            box_interval(DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.0, 0.0, -4.0), half).unwrap();
        assert!((a - 1.75 / 4.0).abs() < 1e-12 && (b - 2.25 / 4.0).abs() < 1e-12);
        assert!(
            box_interval(DVec3::new(2.0, 0.0, 2.0), DVec3::new(0.0, 0.0, -4.0), half).is_none()
        );
    }
}
