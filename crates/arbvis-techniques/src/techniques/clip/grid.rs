//! The regular grid a clip field is sampled on, over the volume's object-space box.

use glam::DVec3;

use super::error::ClipError;

/// Largest clip grid accepted (512³; 0.5 GiB of f32 distances per field).
pub const MAX_CLIP_VOXELS: usize = 512 * 512 * 512;

/// A regular grid over the volume's object-space box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClipGrid {
    /// Voxels along i (fastest), j, k.
    pub dims: [usize; 3],
    /// Half-extents of the box.
    pub half: DVec3,
}

impl ClipGrid {
    /// A grid of `dims` (each >= 1, at most [`MAX_CLIP_VOXELS`] in all) over `[-half, half]`.
    pub fn new(dims: [usize; 3], half: [f64; 3]) -> Result<ClipGrid, ClipError> {
        let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if dims.contains(&0) || count.is_none_or(|n| n > MAX_CLIP_VOXELS) {
            return Err(ClipError::Invalid(format!(
                "clip resolution {dims:?}: each side must be at least 1 and the grid at most {MAX_CLIP_VOXELS} voxels"
            )));
        }
        if half.iter().any(|h| !h.is_finite() || *h <= 0.0) {
            return Err(ClipError::Invalid(format!(
                "volume half-extent {half:?} must be positive"
            )));
        }
        Ok(ClipGrid {
            dims,
            half: DVec3::from_array(half),
        })
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// Never empty (dims >= 1).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Voxel size along x, y, z.
    pub fn voxel(&self) -> DVec3 {
        2.0 * self.half
            / DVec3::new(
                self.dims[0] as f64,
                self.dims[1] as f64,
                self.dims[2] as f64,
            )
    }

    /// Voxel diagonal, the unit of the texture's distances.
    pub fn diagonal(&self) -> f64 {
        self.voxel().length()
    }

    /// Centre of voxel `(i, j, k)` in object space.
    pub fn centre(&self, i: usize, j: usize, k: usize) -> DVec3 {
        -self.half + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * self.voxel()
    }

    /// Object space to normalized texture coordinates (`[-half, half]` to `[0, 1]`).
    pub fn to_texcoord(&self, x: DVec3) -> DVec3 {
        (x + self.half) / (2.0 * self.half)
    }

    /// Normalized texture coordinates to object space.
    pub fn to_object(&self, p: DVec3) -> DVec3 {
        p * 2.0 * self.half - self.half
    }

    /// Index of voxel `(i, j, k)`, i fastest.
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }
}
