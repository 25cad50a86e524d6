//! A seismic-like cube with no data file: gently folded layers with random reflection
//! coefficients, cut by two normal faults, as a reflectivity series along each trace,
//! convolved with a Ricker wavelet, plus a little noise. Deterministic for a seed.
//! Axes as in SEG-Y: sample (i, time), crossline (j), inline (k).

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

/// The amplitude cube.
pub fn amplitude(spec: &SyntheticSpec) -> Result<Volume, VolumeError> {
    let [ns, nx, ny] = spec.size;
    if spec.size.contains(&0) || ns.saturating_mul(nx).saturating_mul(ny) > 1 << 28 {
        return Err(VolumeError::Invalid(format!(
            "synthetic size {:?}: each side must be at least 1 and the cube at most 2^28 samples",
            spec.size
        )));
    }
    if !(spec.peak.is_finite() && spec.peak > 0.0 && spec.noise.is_finite()) {
        return Err(VolumeError::Invalid(
            "synthetic peak must be positive and noise finite".into(),
        ));
    }
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
    let half = (1.5 / f).ceil() as i64;
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
    Volume::new(spec.size, [1.0; 3], values).map_err(VolumeError::Invalid)
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
        let a = amplitude(&spec).unwrap();
        assert_eq!(a, amplitude(&spec).unwrap());
        let s = a.stats();
        // Zero-mean wavelet: the mean is small next to the peaks; both signs occur.
        assert!(
            s.min < -0.2 && s.max > 0.2 && s.mean.abs() < 0.1 * s.max,
            "{s:?}"
        );
        let other = amplitude(&SyntheticSpec { seed: 2, ..spec }).unwrap();
        assert_ne!(a, other);
    }

    #[test]
    fn bad_sizes_are_errors() {
        for size in [[0, 4, 4], [1 << 20, 1 << 10, 1 << 10]] {
            let spec = SyntheticSpec {
                size,
                ..Default::default()
            };
            assert!(amplitude(&spec).is_err());
        }
        let one = SyntheticSpec {
            size: [1, 1, 1],
            ..Default::default()
        };
        assert!(amplitude(&one).unwrap().values[0].is_finite());
    }
}
