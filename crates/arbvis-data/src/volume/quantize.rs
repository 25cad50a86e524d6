//! v3o2's quantization: every attribute becomes integers 0..255 (so it can be shown with a
//! 256-entry colour table), linearly over a range: `q = round(255 (v - low) / (high - low))`,
//! clamped. The range is the volume's min..max by default (as v3o2 did), percentiles that
//! clip outliers, or fixed values.
//!
//! Extremes, decided here: NaN samples become 0 (the table's first entry; use a table with
//! alpha 0 there to hide them); +inf and -inf clamp to 255 and 0 and never set the range;
//! a constant volume (low = high) maps every sample to 0.

use serde::{Deserialize, Serialize};

use super::{Volume, VolumeError};

/// How the quantization range is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantization {
    /// Finite min..max of the volume (v3o2).
    #[default]
    MinMax,
    /// The `[low, high]` percentiles (0..100) of the finite samples.
    Percentile([f64; 2]),
    /// A fixed value range.
    Range([f64; 2]),
}

/// A quantized attribute.
#[derive(Debug, Clone, PartialEq)]
pub struct Quantized {
    /// One byte per voxel, same order as the volume.
    pub bytes: Vec<u8>,
    /// Value that maps to 0.
    pub low: f64,
    /// Value that maps to 255.
    pub high: f64,
}

/// Quantize one value over `[low, high]`.
pub fn quantize_value(v: f32, low: f64, high: f64) -> u8 {
    if v.is_nan() || high <= low {
        return 0;
    }
    let t = (v as f64 - low) / (high - low);
    (t * 255.0).round().clamp(0.0, 255.0) as u8
}

/// What NaN ("no data": dead traces, non-finite samples) becomes when quantized.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoData {
    /// The attribute holds no NaN: level 0 as [`quantize_value`] gives it.
    Absent,
    /// NaN takes this level, one the colour table makes transparent (the one nearest the
    /// table's middle), so no data draws nothing and fades at its edges as data does.
    Level(u8),
    /// No level is transparent: level 0 is kept for NaN, finite values take 1..=255, and
    /// the renderer clears the table's entry 0.
    Reserved,
}

impl NoData {
    /// The choice for an attribute that may hold NaN (`may_hold_nan`) and whose colour
    /// table has opacity `alpha` per level (256 entries).
    pub fn choose(may_hold_nan: bool, alpha: &[u8]) -> NoData {
        if !may_hold_nan {
            return NoData::Absent;
        }
        (0..alpha.len())
            .filter(|&l| alpha[l] == 0)
            .min_by_key(|&l| (l as i64 - 128).abs())
            .map_or(NoData::Reserved, |l| NoData::Level(l as u8))
    }
}

/// `v` as a level, NaN as `no_data` says ([`NoData`]).
pub fn quantize_level(v: f32, low: f64, high: f64, no_data: NoData) -> u8 {
    match no_data {
        NoData::Absent => quantize_value(v, low, high),
        NoData::Level(l) if v.is_nan() => l,
        NoData::Level(_) => quantize_value(v, low, high),
        NoData::Reserved if v.is_nan() => 0,
        NoData::Reserved if high <= low => 1,
        NoData::Reserved => {
            let t = (v as f64 - low) / (high - low);
            1 + (t * 254.0).round().clamp(0.0, 254.0) as u8
        }
    }
}

#[cfg(test)]
#[test]
fn no_data_takes_a_transparent_level_or_a_reserved_one() {
    let mut alpha = vec![255u8; 256];
    assert_eq!(NoData::choose(false, &alpha), NoData::Absent);
    assert_eq!(NoData::choose(true, &alpha), NoData::Reserved);
    alpha[100..=110].fill(0);
    alpha[200] = 0;
    assert_eq!(NoData::choose(true, &alpha), NoData::Level(110));
    assert_eq!(quantize_level(f32::NAN, 0.0, 1.0, NoData::Level(110)), 110);
    assert_eq!(quantize_level(1.0, 0.0, 1.0, NoData::Level(110)), 255);
    assert_eq!(quantize_level(f32::NAN, 0.0, 1.0, NoData::Reserved), 0);
    assert_eq!(quantize_level(0.0, 0.0, 1.0, NoData::Reserved), 1);
    assert_eq!(quantize_level(1.0, 0.0, 1.0, NoData::Reserved), 255);
}

/// The range `how` selects for `volume`; `(0, 0)` when no sample is finite.
pub fn range(volume: &Volume, how: Quantization) -> Result<(f64, f64), VolumeError> {
    match how {
        Quantization::MinMax => {
            let s = volume.stats();
            Ok(if s.min <= s.max {
                (s.min, s.max)
            } else {
                (0.0, 0.0)
            })
        }
        Quantization::Range([low, high]) => {
            if low.is_finite() && high.is_finite() && low <= high {
                Ok((low, high))
            } else {
                Err(VolumeError::Invalid(format!(
                    "quantization range [{low}, {high}] must be finite and ordered"
                )))
            }
        }
        Quantization::Percentile([p_low, p_high]) => {
            if !(0.0..=100.0).contains(&p_low) || !(0.0..=100.0).contains(&p_high) || p_low > p_high
            {
                return Err(VolumeError::Invalid(format!(
                    "percentiles [{p_low}, {p_high}] must be ordered within 0..100"
                )));
            }
            let mut finite: Vec<f32> = volume
                .values
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            if finite.is_empty() {
                return Ok((0.0, 0.0));
            }
            let mut pick = |p: f64| {
                let at = ((p / 100.0) * (finite.len() - 1) as f64).round() as usize;
                *finite.select_nth_unstable_by(at, f32::total_cmp).1 as f64
            };
            Ok((pick(p_low), pick(p_high)))
        }
    }
}

/// Quantize a whole volume.
pub fn quantize(volume: &Volume, how: Quantization) -> Result<Quantized, VolumeError> {
    let (low, high) = range(volume, how)?;
    let bytes = volume
        .values
        .iter()
        .map(|&v| quantize_value(v, low, high))
        .collect();
    Ok(Quantized { bytes, low, high })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vol(values: Vec<f32>) -> Volume {
        Volume::new([values.len(), 1, 1], [1.0; 3], values).unwrap()
    }

    #[test]
    fn min_max_maps_ends_to_0_and_255() {
        let q = quantize(&vol(vec![-2.0, 0.0, 2.0, 1.0]), Quantization::MinMax).unwrap();
        assert_eq!(q.bytes, vec![0, 128, 255, 191]);
    }

    #[test]
    fn extremes() {
        let q = quantize(
            &vol(vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1.0, 3.0]),
            Quantization::MinMax,
        )
        .unwrap();
        assert_eq!(q.bytes, vec![0, 255, 0, 0, 255]);
        assert_eq!((q.low, q.high), (1.0, 3.0));
        let constant = quantize(&vol(vec![5.0; 4]), Quantization::MinMax).unwrap();
        assert_eq!(constant.bytes, vec![0; 4]);
        let none = quantize(&vol(vec![f32::NAN; 3]), Quantization::MinMax).unwrap();
        assert_eq!(none.bytes, vec![0; 3]);
    }

    #[test]
    fn percentiles_clip_outliers() {
        let mut values: Vec<f32> = (0..101).map(|v| v as f32).collect();
        values[100] = 1e9;
        let q = quantize(&vol(values), Quantization::Percentile([0.0, 99.0])).unwrap();
        assert_eq!((q.low, q.high), (0.0, 99.0));
        assert_eq!(q.bytes[99], 255);
        assert_eq!(q.bytes[100], 255);
        assert!(range(&vol(vec![1.0]), Quantization::Percentile([50.0, 10.0])).is_err());
        assert!(range(&vol(vec![1.0]), Quantization::Range([f64::NAN, 1.0])).is_err());
    }
}
