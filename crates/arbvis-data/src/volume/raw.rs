//! Headerless volumes described in the scene: dimensions, sample type, byte order and a
//! byte offset. The file must hold exactly `offset + ni*nj*nk*bytes` bytes (a size that
//! does not match is an error, because it usually means wrong dimensions or type).

use arbvis_core::vocab::FieldError;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{read_file, Endian, SampleType, Volume, VolumeError};

/// A raw file's description, as in a scene:
/// `{ path = "a.raw", dims = [64, 64, 64], type = "u16", endian = "little" }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSpec {
    /// The file (relative to the scene's folder).
    pub path: PathBuf,
    /// Samples along i (fastest), j, k.
    pub dims: [usize; 3],
    /// Sample type.
    #[serde(rename = "type")]
    pub sample: SampleType,
    /// Byte order.
    #[serde(default)]
    pub endian: Endian,
    /// Bytes to skip at the start.
    #[serde(default)]
    pub offset: u64,
    /// Voxel size along i, j, k.
    #[serde(default = "unit_spacing")]
    pub spacing: [f64; 3],
}

fn unit_spacing() -> [f64; 3] {
    [1.0; 3]
}

impl RawSpec {
    /// Check what the scene says: positive dims whose byte size fits 64 bits, positive
    /// finite spacing.
    pub fn validate(&self) -> Result<(), FieldError> {
        self.byte_size()?;
        if self.spacing.iter().any(|v| !v.is_finite() || *v <= 0.0) {
            return Err(FieldError::new(
                "",
                format!("spacing {:?}: must be positive", self.spacing),
            ));
        }
        Ok(())
    }

    /// Bytes the file must hold: `offset + ni*nj*nk*bytes`, with checked arithmetic.
    fn byte_size(&self) -> Result<u64, FieldError> {
        let samples = self
            .dims
            .iter()
            .try_fold(1u64, |a, &d| a.checked_mul(d as u64))
            .filter(|&n| n > 0);
        samples
            .and_then(|n| n.checked_mul(self.sample.bytes() as u64))
            .and_then(|n| n.checked_add(self.offset))
            .ok_or_else(|| {
                let message = format!(
                    "dims {:?} of {} after an offset of {} bytes: the dims must be positive and the size must fit 64 bits",
                    self.dims,
                    self.sample.name(),
                    self.offset
                );
                FieldError::new("", message)
            })
    }
}

/// Read a raw file; `base` resolves a relative path. The size the scene declares is
/// checked against `limits` and the file's length before anything is read.
pub fn read(base: &Path, spec: &RawSpec, limits: &super::Limits) -> Result<Volume, VolumeError> {
    let path = base.join(&spec.path);
    let need = spec
        .byte_size()
        .map_err(|e| VolumeError::Invalid(format!("{}: {}", path.display(), e.message)))?;
    limits.check(spec.dims, &path.display().to_string())?;
    let (_, len) =
        arbvis_core::input::open_regular(&path).map_err(|e| VolumeError::io(&path, e))?;
    if len != need {
        return Err(VolumeError::format(
            &path,
            len.min(need),
            format!(
                "the file has {len} bytes but {}x{}x{} samples of {} after an offset of {} need {need}",
                spec.dims[0],
                spec.dims[1],
                spec.dims[2],
                spec.sample.name(),
                spec.offset
            ),
        ));
    }
    let bytes = read_file(&path, need)?;
    let big = spec.endian == Endian::Big;
    let width = spec.sample.bytes();
    let values = bytes[spec.offset as usize..]
        .chunks_exact(width)
        .map(|b| spec.sample.decode(b, big))
        .collect();
    Volume::new(spec.dims, spec.spacing, values)
}
