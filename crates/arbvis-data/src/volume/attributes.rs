//! Attributes derived from an amplitude cube along each trace (axis i) through the
//! analytic signal `a(t) = x(t) + i H[x](t)`, computed with an FFT (rustfft): zero the
//! negative frequencies, double the positive ones, transform back.
//!
//! - envelope: `|a|` (reflection strength);
//! - phase: `arg a` in degrees, [-180, 180];
//! - cosine of phase: `cos(arg a)`, amplitude-free continuity of events;
//! - frequency: instantaneous frequency, the derivative of the unwrapped phase, in cycles
//!   per sample (central differences);
//! - amplitude: the input itself.

use rustfft::{num_complex::Complex, FftPlanner};
use serde::{Deserialize, Serialize};

use super::Volume;

/// Which attribute of an amplitude cube to show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Attribute {
    /// The samples as read.
    #[default]
    Amplitude,
    /// Envelope (instantaneous amplitude).
    Envelope,
    /// Instantaneous phase, degrees.
    Phase,
    /// Cosine of the instantaneous phase.
    CosinePhase,
    /// Instantaneous frequency, cycles per sample.
    Frequency,
}

impl Attribute {
    /// Every attribute.
    pub const ALL: [Attribute; 5] = [
        Attribute::Amplitude,
        Attribute::Envelope,
        Attribute::Phase,
        Attribute::CosinePhase,
        Attribute::Frequency,
    ];

    /// Name as in scenes.
    pub fn name(self) -> &'static str {
        match self {
            Attribute::Amplitude => "amplitude",
            Attribute::Envelope => "envelope",
            Attribute::Phase => "phase",
            Attribute::CosinePhase => "cosine-phase",
            Attribute::Frequency => "frequency",
        }
    }
}

/// The analytic signal of one real trace.
pub fn analytic(trace: &[f64], planner: &mut FftPlanner<f64>) -> Vec<Complex<f64>> {
    let n = trace.len();
    let mut buf: Vec<Complex<f64>> = trace.iter().map(|&x| Complex::new(x, 0.0)).collect();
    if n < 2 {
        return buf;
    }
    planner.plan_fft_forward(n).process(&mut buf);
    // Keep DC (and Nyquist for even n), double positive frequencies, zero negative ones.
    for (f, c) in buf.iter_mut().enumerate() {
        let positive = f > 0 && 2 * f < n;
        let negative = 2 * f > n;
        if positive {
            *c *= 2.0;
        } else if negative {
            *c = Complex::new(0.0, 0.0);
        }
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    buf.iter_mut().for_each(|c| *c /= n as f64);
    buf
}

/// Derive `attribute` from an amplitude volume. Non-finite input samples are treated as 0
/// for the transform and stay NaN in the output.
pub fn derive(amplitude: &Volume, attribute: Attribute) -> Volume {
    if attribute == Attribute::Amplitude {
        return amplitude.clone();
    }
    let ns = amplitude.dims[0];
    let mut planner = FftPlanner::new();
    let mut out = amplitude.clone();
    for (src, dst) in amplitude
        .values
        .chunks_exact(ns)
        .zip(out.values.chunks_exact_mut(ns))
    {
        derive_trace(src, &mut planner, &mut [(attribute, dst)]);
    }
    out
}

/// Derive several attributes of one trace from one analytic signal: each `(attribute,
/// out)` gets `src.len()` values (the same as [`derive`] gives for a volume).
pub fn derive_trace(
    src: &[f32],
    planner: &mut FftPlanner<f64>,
    outputs: &mut [(Attribute, &mut [f32])],
) {
    let ns = src.len();
    let trace: Vec<f64> = src
        .iter()
        .map(|&v| if v.is_finite() { v as f64 } else { 0.0 })
        .collect();
    let a = analytic(&trace, planner);
    // The phase (atan2, the costliest step) only where an output needs it.
    let needs_phase = outputs.iter().any(|(at, _)| {
        matches!(
            at,
            Attribute::Phase | Attribute::CosinePhase | Attribute::Frequency
        )
    });
    // In f32 (atan2f): its error, about 1e-7 rad, is far below what the stores keep of
    // phase and frequency (float16: 0.125° at 180°, 2^-12 cycles a sample).
    let phase: Vec<f64> = if needs_phase {
        a.iter()
            .map(|c| (c.im as f32).atan2(c.re as f32) as f64)
            .collect()
    } else {
        Vec::new()
    };
    for (attribute, dst) in outputs.iter_mut() {
        for (i, d) in dst.iter_mut().enumerate() {
            let v = match attribute {
                Attribute::Amplitude => trace[i],
                // The modulus as a square root: a seismic trace's values are far from
                // overflowing a square, and hypot's care cost a noticeable share of a
                // conversion (measured: docs/benchmarks.md, "Figures behind the store's
                // settings").
                Attribute::Envelope => (a[i].re * a[i].re + a[i].im * a[i].im).sqrt(),
                Attribute::Phase => phase[i].to_degrees(),
                Attribute::CosinePhase => phase[i].cos(),
                Attribute::Frequency => {
                    let (lo, hi) = (i.saturating_sub(1), (i + 1).min(ns - 1));
                    if hi == lo {
                        0.0
                    } else {
                        let mut d = phase[hi] - phase[lo];
                        let tau = std::f64::consts::TAU;
                        d -= tau * (d / tau).round();
                        d / tau / (hi - lo) as f64
                    }
                }
            };
            *d = if src[i].is_finite() {
                v as f32
            } else {
                f32::NAN
            };
        }
    }
}

/// The attribute named `name` (as in scenes).
pub fn by_name(name: &str) -> Option<Attribute> {
    Attribute::ALL.into_iter().find(|a| a.name() == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cosine_trace(n: usize, cycles: f64) -> Volume {
        let values = (0..n)
            .map(|i| (std::f64::consts::TAU * cycles * i as f64 / n as f64).cos() as f32)
            .collect();
        Volume::new([n, 1, 1], [1.0; 3], values).unwrap()
    }

    #[test]
    fn cosine_has_unit_envelope_and_linear_phase() {
        // A whole number of cycles is periodic, so the FFT's Hilbert transform is exact:
        // H[cos] = sin. Tolerance 1e-5: f32 storage of the output.
        let v = cosine_trace(64, 5.0);
        let env = derive(&v, Attribute::Envelope);
        assert!(env.values.iter().all(|&e| (e - 1.0).abs() < 1e-5));
        let phase = derive(&v, Attribute::Phase);
        for (i, &p) in phase.values.iter().enumerate() {
            let expect = (360.0 * 5.0 * i as f64 / 64.0 + 180.0).rem_euclid(360.0) - 180.0;
            let diff = (p as f64 - expect + 180.0).rem_euclid(360.0) - 180.0;
            assert!(diff.abs() < 1e-3, "sample {i}: {p} vs {expect}");
        }
        let freq = derive(&v, Attribute::Frequency);
        assert!(freq
            .values
            .iter()
            .all(|&f| (f as f64 - 5.0 / 64.0).abs() < 1e-5));
        let cos = derive(&v, Attribute::CosinePhase);
        for (c, x) in cos.values.iter().zip(&v.values) {
            assert!((c - x).abs() < 1e-5);
        }
    }

    #[test]
    fn short_and_nan_traces_stay_finite_where_input_is() {
        let mut v = Volume::new([1, 2, 1], [1.0; 3], vec![2.0, -3.0]).unwrap();
        for a in Attribute::ALL {
            assert!(derive(&v, a).values.iter().all(|x| x.is_finite()), "{a:?}");
        }
        v = Volume::new([4, 1, 1], [1.0; 3], vec![1.0, f32::NAN, -1.0, 0.5]).unwrap();
        let env = derive(&v, Attribute::Envelope);
        assert!(env.values[1].is_nan());
        assert!(env.values[0].is_finite() && env.values[3].is_finite());
    }
}
