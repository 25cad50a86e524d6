//! Images read back from targets: RGBA f32, top row first, with the precision they came
//! from; comparison metrics (max abs, RMSE, PSNR) and diff images for tests and studies.

use crate::vocab::TargetFormat;

/// An RGBA image, top row first, channels in 0..1 (float targets may exceed that).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Precision of the target it was read from.
    pub format: TargetFormat,
    /// `width * height * 4` values, row-major from the top.
    pub data: Vec<f32>,
}

/// How two images differ.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Difference {
    /// Largest absolute channel difference.
    pub max_abs: f64,
    /// Root mean square channel difference.
    pub rmse: f64,
    /// Peak signal-to-noise ratio in dB for a peak of 1 (infinite when identical).
    pub psnr: f64,
    /// Pixels with any channel differing by more than the tolerance given to `compare`.
    pub pixels_over: usize,
    /// Where the largest difference is (x, y).
    pub worst: (u32, u32),
}

impl Image {
    /// Build from GL's bottom-up rows.
    pub fn from_bottom_up(width: u32, height: u32, format: TargetFormat, data: Vec<f32>) -> Image {
        let row = width as usize * 4;
        let mut flipped = Vec::with_capacity(data.len());
        for r in data.chunks_exact(row).rev() {
            flipped.extend_from_slice(r);
        }
        Image {
            width,
            height,
            format,
            data: flipped,
        }
    }

    /// An image from f64 pixels (a CPU reference's output), top row first.
    pub fn from_f64_pixels(
        width: u32,
        height: u32,
        format: TargetFormat,
        pixels: impl IntoIterator<Item = [f64; 4]>,
    ) -> Image {
        let data = pixels
            .into_iter()
            .flat_map(|p| p.map(|v| v as f32))
            .collect();
        Image {
            width,
            height,
            format,
            data,
        }
    }

    /// A `width` x `height` image filled with `rgba`.
    pub fn filled(width: u32, height: u32, format: TargetFormat, rgba: [f32; 4]) -> Image {
        Image {
            width,
            height,
            format,
            data: rgba.repeat(width as usize * height as usize),
        }
    }

    /// The RGBA value at (x, y), y counted from the top.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

    /// Set the RGBA value at (x, y).
    pub fn set_pixel(&mut self, x: u32, y: u32, rgba: [f32; 4]) {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        self.data[i..i + 4].copy_from_slice(&rgba);
    }

    /// The RGBA value at (x, y) as 8-bit levels (rounded, clamped).
    pub fn pixel_u8(&self, x: u32, y: u32) -> [u8; 4] {
        self.pixel(x, y).map(to_u8)
    }

    /// 8-bit RGBA bytes (rounded, clamped), top row first.
    pub fn to_rgba8(&self) -> Vec<u8> {
        self.data.iter().map(|&v| to_u8(v)).collect()
    }

    /// 16-bit RGBA samples (rounded, clamped), top row first.
    pub fn to_rgba16(&self) -> Vec<u16> {
        self.data
            .iter()
            .map(|&v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16)
            .collect()
    }

    /// What the screen shows: the same colours, every pixel opaque. A frame drawn with
    /// "over" blending onto an opaque background already holds the composited colour;
    /// only its alpha (which counts coverage, or the SRC_ALPHA rule) is replaced.
    pub fn opaque(&self) -> Image {
        let mut out = self.clone();
        out.data.chunks_exact_mut(4).for_each(|p| p[3] = 1.0);
        out
    }

    /// Straight (un-premultiplied) colour and coverage alpha, as image files and
    /// browsers expect, from a frame cleared to transparent black and blended with
    /// coverage alpha (colour then holds `C = sum c_i a_i prod (1 - a_j)`, a premultiplied
    /// colour). Composited over any background `B` it gives `C + B (1 - A)`: the frame
    /// that would have been drawn on `B`.
    pub fn unpremultiplied(&self) -> Image {
        let mut out = self.clone();
        for p in out.data.chunks_exact_mut(4) {
            let a = p[3];
            for c in &mut p[..3] {
                *c = if a > 0.0 { (*c / a).min(1.0) } else { 0.0 };
            }
        }
        out
    }

    /// This image (straight colour, coverage alpha) composited over `background`, as a
    /// browser shows it.
    pub fn over(&self, background: impl Fn(u32, u32) -> [f32; 3]) -> Image {
        let mut out = self.clone();
        for y in 0..self.height {
            for x in 0..self.width {
                let p = self.pixel(x, y);
                let b = background(x, y);
                let a = p[3];
                out.set_pixel(
                    x,
                    y,
                    [
                        p[0] * a + b[0] * (1.0 - a),
                        p[1] * a + b[1] * (1.0 - a),
                        p[2] * a + b[2] * (1.0 - a),
                        1.0,
                    ],
                );
            }
        }
        out
    }

    /// Compare with `other`; `tolerance` sets what counts in `pixels_over`.
    /// `None` when the sizes differ.
    pub fn compare(&self, other: &Image, tolerance: f32) -> Option<Difference> {
        if (self.width, self.height) != (other.width, other.height) {
            return None;
        }
        let (mut max_abs, mut sum_sq, mut over, mut worst) = (0f64, 0f64, 0usize, (0, 0));
        for (i, (a, b)) in self
            .data
            .chunks_exact(4)
            .zip(other.data.chunks_exact(4))
            .enumerate()
        {
            let mut pixel_max = 0f64;
            for (x, y) in a.iter().zip(b) {
                // NaN compares as the largest possible difference.
                let d = if x.is_nan() != y.is_nan() {
                    f64::INFINITY
                } else if x.is_nan() {
                    0.0
                } else {
                    (*x as f64 - *y as f64).abs()
                };
                sum_sq += if d.is_finite() { d * d } else { 1.0 };
                pixel_max = pixel_max.max(d);
            }
            if pixel_max > tolerance as f64 {
                over += 1;
            }
            if pixel_max > max_abs {
                max_abs = pixel_max;
                worst = (i as u32 % self.width, i as u32 / self.width);
            }
        }
        let rmse = (sum_sq / self.data.len().max(1) as f64).sqrt();
        let psnr = if rmse == 0.0 {
            f64::INFINITY
        } else {
            20.0 * (1.0 / rmse).log10()
        };
        Some(Difference {
            max_abs,
            rmse,
            psnr,
            pixels_over: over,
            worst,
        })
    }

    /// A diff image: each pixel's largest channel difference, scaled by `gain`, as grey;
    /// pixels over `tolerance` in red. Opaque.
    pub fn diff_image(&self, other: &Image, tolerance: f32, gain: f32) -> Option<Image> {
        if (self.width, self.height) != (other.width, other.height) {
            return None;
        }
        let mut out = Image::filled(self.width, self.height, TargetFormat::Rgba8, [0.0; 4]);
        for (o, (a, b)) in out
            .data
            .chunks_exact_mut(4)
            .zip(self.data.chunks_exact(4).zip(other.data.chunks_exact(4)))
        {
            let d = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0f32, |m, v| if v.is_nan() { 1.0 } else { m.max(v) });
            let g = (d * gain).min(1.0);
            let rgba = if d > tolerance {
                [1.0, 0.0, 0.0, 1.0]
            } else {
                [g, g, g, 1.0]
            };
            o.copy_from_slice(&rgba);
        }
        Some(out)
    }
}

fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compare_finds_the_worst_pixel_and_counts_those_over() {
        let a = Image::filled(4, 3, TargetFormat::Rgba8, [0.5; 4]);
        let mut b = a.clone();
        b.set_pixel(2, 1, [0.5, 0.6, 0.5, 0.5]);
        b.set_pixel(0, 0, [0.51, 0.5, 0.5, 0.5]);
        let d = a.compare(&b, 0.05).unwrap();
        assert!((d.max_abs - 0.1).abs() < 1e-6);
        assert_eq!(d.worst, (2, 1));
        assert_eq!(d.pixels_over, 1);
        assert!(d.psnr.is_finite());
        assert_eq!(a.compare(&a, 0.0).unwrap().psnr, f64::INFINITY);
        let diff = a.diff_image(&b, 0.05, 10.0).unwrap();
        assert_eq!(diff.pixel(2, 1), [1.0, 0.0, 0.0, 1.0]);
        assert!(a
            .compare(&Image::filled(3, 3, TargetFormat::Rgba8, [0.0; 4]), 0.0)
            .is_none());
    }

    #[test]
    fn nan_counts_as_a_difference() {
        let a = Image::filled(1, 1, TargetFormat::Rgba32f, [0.0; 4]);
        let b = Image::filled(1, 1, TargetFormat::Rgba32f, [f32::NAN, 0.0, 0.0, 0.0]);
        assert_eq!(a.compare(&b, 1.0).unwrap().pixels_over, 1);
    }

    #[test]
    fn rows_are_flipped_to_top_first() {
        let data = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let img = Image::from_bottom_up(1, 2, TargetFormat::Rgba8, data);
        assert_eq!(img.pixel(0, 0), [1.0; 4]);
    }
}
