//! A seismic-like cube with no data file: gently folded layers with random reflection
//! coefficients, cut by two normal faults, as a reflectivity series along each trace,
//! convolved with a Ricker wavelet, plus a little noise. Deterministic for a seed.
//! Axes as in SEG-Y: sample (i, time), crossline (j), inline (k).

use arbvis_core::vocab::FieldError;
use serde::{Deserialize, Serialize};

use super::{Volume, VolumeError};

/// Parameters of the synthetic cube, as in a scene: `{ size = [64, 64, 64], seed = 1 }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SyntheticSpec {
    /// Samples per trace, crosslines, inlines.
    pub size: [usize; 3],
    /// Random seed (layers, coefficients, noise).
    pub seed: u64,
    /// Ricker peak frequency in cycles per 100 samples.
    pub peak: f64,
    /// Noise amplitude relative to the largest reflection.
    pub noise: f64,
}

impl Default for SyntheticSpec {
    fn default() -> Self {
        SyntheticSpec {
            size: [64, 64, 64],
            seed: 1,
            peak: 8.0,
            noise: 0.02,
        }
    }
}

/// A small deterministic generator (SplitMix64): the cube must not change between
/// versions of a random-number crate.
#[derive(Debug, Clone)]
pub struct SplitMix(u64);

impl SplitMix {
    /// Seeded generator.
    pub fn new(seed: u64) -> SplitMix {
        SplitMix(seed)
    }
    /// Next value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Ricker wavelet at `t` samples from its centre, peak frequency `f` cycles per sample.
pub fn ricker(t: f64, f: f64) -> f64 {
    let a = (std::f64::consts::PI * f * t).powi(2);
    (1.0 - 2.0 * a) * (-a).exp()
}

/// Highest Ricker peak frequency: 50 cycles per 100 samples is the Nyquist frequency.
pub const MAX_PEAK: f64 = 50.0;

impl SyntheticSpec {
    /// Check the parameters: each side at least 1, `0 < peak <= 50` (Nyquist), noise finite.
    pub fn validate(&self) -> Result<(), FieldError> {
        if self.size.contains(&0) {
            return Err(FieldError::new(
                "",
                format!("size {:?}: each side must be at least 1", self.size),
            ));
        }
        if !(self.peak.is_finite() && self.peak > 0.0 && self.peak <= MAX_PEAK) {
            return Err(FieldError::new("", format!(
                "peak = {}: must be in (0, {MAX_PEAK}] cycles per 100 samples (50 is the Nyquist frequency)",
                self.peak
            )));
        }
        if !(self.noise.is_finite() && self.noise.abs() <= 1e6) {
            return Err(FieldError::new(
                "",
                format!("noise = {}: must be finite, at most 1e6", self.noise),
            ));
        }
        Ok(())
    }
}

/// The amplitude cube; its size is checked against `limits` before anything is made.
pub fn amplitude(spec: &SyntheticSpec, limits: &super::Limits) -> Result<Volume, VolumeError> {
    spec.validate()
        .map_err(|e| VolumeError::Invalid(format!("synthetic volume: {}", e.message)))?;
    limits.check(spec.size, "synthetic volume")?;
    let [ns, nx, ny] = spec.size;
    let mut rng = SplitMix::new(spec.seed);
    // Layer boundaries: depth in [0, 1] of the trace, reflection coefficient in [-1, 1].
    let layers = 6 + ns / 6;
    let boundaries: Vec<(f64, f64)> = (0..layers)
        .map(|b| {
            let depth = (b as f64 + 0.5 + 0.6 * (rng.next_f64() - 0.5)) / layers as f64;
            let r = (rng.next_f64() * 2.0 - 1.0).signum() * (0.3 + 0.7 * rng.next_f64());
            (depth, r)
        })
        .collect();
    let fold = (rng.next_f64() * 6.0, rng.next_f64() * 6.0);
    // Two faults: planes in (x, y) with a throw of a few samples on their far side.
    let faults = [
        (0.35 + 0.1 * rng.next_f64(), 0.6, 0.08),
        (0.65 + 0.1 * rng.next_f64(), -0.4, -0.05),
    ];
    let f = spec.peak / 100.0;
    // The wavelet is cut at 1.5 periods, and never longer than the trace (beyond it, it
    // multiplies nothing): a low peak costs no more than a trace-long convolution.
    let half = (1.5 / f).ceil().min(ns as f64) as i64;
    let wavelet: Vec<f64> = (-half..=half).map(|t| ricker(t as f64, f)).collect();
    let mut values = vec![0f32; ns * nx * ny];
    let mut reflectivity = vec![0f64; ns];
    for k in 0..ny {
        for j in 0..nx {
            let (x, y) = (j as f64 / nx as f64, k as f64 / ny as f64);
            let mut shift = 0.08 * (fold.0 + 6.0 * x).sin() * (fold.1 + 4.0 * y).cos() + 0.1 * x;
            for &(at, slope, throw) in &faults {
                if x + slope * (y - 0.5) > at {
                    shift += throw;
                }
            }
            reflectivity.iter_mut().for_each(|r| *r = 0.0);
            for &(depth, r) in &boundaries {
                // Sub-sample placement: split the spike between the two nearest samples.
                let s = (depth + shift) * ns as f64;
                let s0 = s.floor();
                if s0 >= 0.0 && (s0 as usize) < ns {
                    reflectivity[s0 as usize] += r * (1.0 - (s - s0));
                }
                if s0 + 1.0 >= 0.0 && ((s0 + 1.0) as usize) < ns {
                    reflectivity[(s0 + 1.0) as usize] += r * (s - s0);
                }
            }
            let trace = &mut values[(k * nx + j) * ns..][..ns];
            for (i, out) in trace.iter_mut().enumerate() {
                let mut sum = 0.0;
                for (w, &a) in wavelet.iter().enumerate() {
                    let src = i as i64 + w as i64 - half;
                    if (0..ns as i64).contains(&src) {
                        sum += a * reflectivity[src as usize];
                    }
                }
                *out = (sum + spec.noise * (rng.next_f64() * 2.0 - 1.0)) as f32;
            }
        }
    }
    Volume::new(spec.size, [1.0; 3], values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_seismic_like() {
        let spec = SyntheticSpec {
            size: [48, 20, 16],
            ..Default::default()
        };
        let limits = crate::volume::Limits::default();
        let a = amplitude(&spec, &limits).unwrap();
        assert_eq!(a, amplitude(&spec, &limits).unwrap());
        let s = a.stats();
        // Zero-mean wavelet: the mean is small next to the peaks; both signs occur.
        assert!(
            s.min < -0.2 && s.max > 0.2 && s.mean.abs() < 0.1 * s.max,
            "{s:?}"
        );
        let other = amplitude(&SyntheticSpec { seed: 2, ..spec }, &limits).unwrap();
        assert_ne!(a, other);
    }

    #[test]
    fn bad_sizes_are_errors() {
        let limits = crate::volume::Limits::default();
        for size in [[0, 4, 4], [1 << 20, 1 << 10, 1 << 10], [268_435_456, 1, 1]] {
            let spec = SyntheticSpec {
                size,
                ..Default::default()
            };
            assert!(amplitude(&spec, &limits).is_err(), "{size:?}");
        }
        // The GL's limit is checked before anything is generated.
        let small_gl = crate::volume::Limits {
            max_side: 64,
            max_voxels: 1 << 30,
        };
        let spec = SyntheticSpec {
            size: [65, 2, 2],
            ..Default::default()
        };
        let e = amplitude(&spec, &small_gl).unwrap_err().to_string();
        assert!(e.contains("GL_MAX_3D_TEXTURE_SIZE"), "{e}");
        let one = SyntheticSpec {
            size: [1, 1, 1],
            ..Default::default()
        };
        assert!(amplitude(&one, &limits).unwrap().values[0].is_finite());
    }

    #[test]
    fn extreme_peaks_are_refused_or_cheap() {
        let limits = crate::volume::Limits::default();
        for peak in [1e-300, 0.0, -1.0, 51.0, f64::NAN] {
            let spec = SyntheticSpec {
                peak,
                ..Default::default()
            };
            if peak > 0.0 && peak < 1e-200 {
                // Within the range but tiny: the wavelet is cut at the trace length, so
                // this is as fast as any other cube (the fuzzer once saw minutes here).
                let t0 = std::time::Instant::now();
                let v = amplitude(
                    &SyntheticSpec {
                        size: [16; 3],
                        ..spec
                    },
                    &limits,
                )
                .unwrap();
                assert!(v.values.iter().all(|x| x.is_finite()));
                assert!(t0.elapsed().as_secs_f64() < 1.0);
            } else {
                assert!(amplitude(&spec, &limits).is_err(), "peak {peak}");
            }
        }
    }
}
