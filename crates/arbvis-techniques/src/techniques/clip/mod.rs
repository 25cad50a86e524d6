//! Volume clipping with a multi-resolution clip texture (seed `002_67351ad27c6282b6.txt`,
//! Luo, Xue, Long and Wu, ~2010): a distance-field clip texture (Weiskopf et al. 2003)
//! compressed into an INDEX-DATA pair — a low-resolution INDEX with one texel per block
//! saying outside / inside / boundary, and a DATA texture holding only the boundary
//! blocks at full resolution. This module is the CPU part and the GPU stage ([`stage`]);
//! 3D opacity draws through it ([`crate::techniques::opacity3d::clipping`]).
//!
//! # How it works
//! 1. [`ClipSpec`] (scene, checked by [`scene`]) → [`shape::Shape`]: analytic shapes,
//!    CSG, triangle meshes ([`mesh_field`], from [`arbvis_data::surface`] or generated in
//!    code) and voxel masks ([`mask_field`]), in the volume's object space (the box `[-half, half]`, longest side `[-1, 1]`).
//! 2. [`texture::ClipTexture::build`]: the clip distance of every voxel centre, mapped to
//!    `clamp(0.5 + 0.5 d / diag, 0, 1)` (boundary at 0.5, clamped beyond one voxel
//!    diagonal), in parallel, timed.
//! 3. [`multires::MultiRes::build`]: blocks of `B³`, INDEX `(0,0,0,0)` / `(0,0,0,1)` /
//!    `(r,s,t,0.5)`, extended `(B+2)³` copies packed into DATA, its size within the
//!    driver's `max_3d_texture_size`. The lookup formula a fragment program uses and the
//!    INDEX precision are in that module's doc.
//! 4. CPU emulations of both GPU lookups ([`texture::ClipTexture::sample_single`],
//!    [`multires::MultiRes::sample_multires`], GL texel centres and CLAMP_TO_EDGE) and
//!    the f64 reference [`shape::Shape::inside`] for boundary-error measurements.
//!
//! # Decisions the seed leaves open
//! - Sign and scale: the seed's "positive inside", divided by the voxel diagonal, mapped
//!   by `0.5 + 0.5 d / diag` (the mapping's formula is lost from the text; this one puts
//!   the boundary at 0.5 and reaches 0 / 1 exactly one diagonal away, so a block is
//!   uniform when all its voxels are at least one diagonal from the boundary).
//! - Texel formats for the compression ratio: single-resolution and DATA one byte per
//!   texel (R8, the era's LUMINANCE8), INDEX RGBA32F (16 bytes; 8-bit cannot address the
//!   slots, see [`multires`]). The ratio is also reported for other formats.
//! - Partial blocks are padded by clamping to the edge; DATA slots are arranged in a
//!   near-cubic grid; an empty or full clip has no DATA at all (`data_dims` zero).
//! - The keep/discard decision of the INDEX-DATA lookup equals the single-resolution one
//!   at every point (the values are equal in boundary blocks, and a uniform block's
//!   neighbourhood cannot cross 0.5 because the clip distance is 1-Lipschitz: a voxel
//!   one diagonal from the boundary has neighbours at most one diagonal nearer).
//!
//! # Extremes, each with a test (`tests.rs`)
//! A shape touching the volume border (border voxels are simply inside); `B = 1`; `B` =
//! the volume size (one block); sides not divisible by `B` (37 x 23 x 11: partial blocks);
//! empty and full clips (no DATA at all); more slots than 8 bits address (300 x 300 x 12,
//! `B = 1`); a shape thinner than a voxel (its voxel centres never reach 0.5 by much, so
//! it shows only where lookups fall within its thickness; both textures agree); bad
//! meshes: NaN or empty are errors with position, open ones are decided by the winding
//! number.
//!
//! # Cost and compression (`arbvis study --technique clip` measures them)
//! INDEX-DATA builds in a fraction of the time of the single texture's distance field it
//! starts from. The compression ratio has a floor set by the paper's extended blocks: at
//! B = 8 their copies cost `(10/8)³ = 1.95` times the blocks, so for a sphere of radius
//! 0.35 N at 256³ no block size and no INDEX format reaches the goal of 0.16, and the
//! ratio falls as 1/N, the boundary's blocks lying on a surface (measured:
//! docs/benchmarks.md, "Clipping").

pub mod error;
pub mod fast_winding;
pub mod grid;
pub mod mask_field;
pub mod mesh_field;
pub mod multires;
pub mod scene;
pub mod shape;
pub mod stage;
pub mod stats;
pub mod study;
#[cfg(test)]
mod tests;
pub mod texture;

use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use arbvis_data::volume::VolumeSource;
pub use error::ClipError;
use multires::MultiRes;
use shape::{rotation_from_degrees, Shape};
use texture::{ClipGrid, ClipTexture};

/// A clip shape as written in a scene, e.g. `{ sphere = { center = [0, 0, 0], radius =
/// 0.5 } }`. Coordinates are the volume's object space; rotations Euler degrees
/// `[x, y, z]` applied x, then y, then z.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// A ball.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// A box.
    Box {
        /// Centre.
        center: [f64; 3],
        /// Half the side lengths along its own axes.
        half_size: [f64; 3],
        /// Euler degrees.
        #[serde(default)]
        rotation: [f64; 3],
    },
    /// A capped cylinder along its own z.
    Cylinder {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
        /// Half the height.
        half_height: f64,
        /// Euler degrees.
        #[serde(default)]
        rotation: [f64; 3],
    },
    /// Everything on the side of the plane the normal points away from.
    HalfSpace {
        /// A point of the plane.
        point: [f64; 3],
        /// Outward normal (any length but zero).
        normal: [f64; 3],
    },
    /// A triangle surface file (OBJ, STL), placed by `position + R (scale v)`.
    Mesh {
        /// The file (relative to the scene's folder).
        path: PathBuf,
        /// Translation.
        #[serde(default)]
        position: [f64; 3],
        /// Uniform scale.
        #[serde(default = "one")]
        scale: f64,
        /// Euler degrees.
        #[serde(default)]
        rotation: [f64; 3],
    },
    /// A closed triangle mesh generated in code (no file): a torus around its own z
    /// axis, placed by `center + R v` ([`scene::torus`]).
    TorusMesh {
        /// Centre.
        center: [f64; 3],
        /// Radius of the ring (to the tube's centre).
        major_radius: f64,
        /// Radius of the tube (below `major_radius`).
        minor_radius: f64,
        /// Euler degrees.
        #[serde(default)]
        rotation: [f64; 3],
        /// Segments around the ring and around the tube.
        #[serde(default = "torus_segments")]
        segments: [usize; 2],
    },
    /// A volume thresholded: `value >= threshold` is inside.
    Mask {
        /// The mask volume (stretched over the clipped volume's box).
        volume: VolumeSource,
        /// Threshold.
        threshold: f64,
    },
    /// Inside any.
    Union(Vec<ShapeSpec>),
    /// Inside all.
    Intersection(Vec<ShapeSpec>),
    /// Inside the first, outside the second.
    Difference(Box<[ShapeSpec; 2]>),
}

fn one() -> f64 {
    1.0
}

fn torus_segments() -> [usize; 2] {
    [48, 24]
}

/// Deepest CSG nesting accepted.
pub const MAX_DEPTH: usize = 32;

/// `[technique.clip]`'s clip: the shape and how its texture is built.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipSpec {
    /// The clip object.
    pub shape: ShapeSpec,
    /// Keep the outside instead.
    #[serde(default)]
    pub invert: bool,
    /// Block side `B` of the INDEX-DATA texture.
    #[serde(default = "default_block")]
    pub block: usize,
    /// Build the INDEX-DATA texture (else only the single-resolution one).
    #[serde(default = "yes")]
    pub multires: bool,
    /// Clip grid `[ni, nj, nk]`; the volume's grid by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<[usize; 3]>,
}

fn default_block() -> usize {
    8
}

fn yes() -> bool {
    true
}

/// Memory per clip-grid voxel while the clip is built and drawn: the shape's f32
/// distances, the 8-bit or float single texture and its GPU copy; the growth of peak
/// resident memory per voxel, with room left for float DATA (measured:
/// docs/benchmarks.md, "Memory estimates and work limits").
pub const BYTES_PER_CLIP_VOXEL: u64 = 12;

/// Memory per INDEX-DATA block besides the distance field: the INDEX texel (RGBA32F) on
/// the CPU and the GPU, the block's class while it is sorted, and the DATA of boundary
/// blocks; the growth per block, rounded up (measured: docs/benchmarks.md, "Memory
/// estimates and work limits").
pub const BYTES_PER_BLOCK: u64 = 48;

impl ClipSpec {
    /// The large allocations of a clip on a `dims` grid (the scene's `resolution`, or
    /// the volume's): the distance field and, with `multires`, the INDEX texture. DATA
    /// depends on how many blocks meet the boundary: its builder checks the budget once it
    /// has counted them.
    pub fn memory_estimate(&self, dims: [usize; 3]) -> Vec<arbvis_core::budget::Estimate> {
        use arbvis_core::budget::Estimate;
        let grid = self.resolution.unwrap_or(dims);
        let voxels = grid.iter().fold(1u64, |a, &d| a.saturating_mul(d as u64));
        let mut out = vec![Estimate::of(
            format!("the clip's {grid:?} grid"),
            voxels,
            BYTES_PER_CLIP_VOXEL,
        )];
        if self.multires {
            let b = self.block.max(1);
            let blocks = grid
                .iter()
                .fold(1u64, |a, &d| a.saturating_mul(d.div_ceil(b) as u64));
            out.push(Estimate::of(
                format!("the INDEX texture of {blocks} blocks of {b}³"),
                blocks,
                BYTES_PER_BLOCK,
            ));
        }
        out
    }
}

/// What [`ClipSpec::build`] makes.
#[derive(Debug, Clone)]
pub struct ClipTextures {
    /// The shape (the f64 reference).
    pub shape: Shape,
    /// The single-resolution texture.
    pub single: ClipTexture,
    /// The INDEX-DATA texture, when asked for.
    pub multires: Option<MultiRes>,
}

impl ShapeSpec {
    /// Build the shape: load files (relative to `base`), check parameters. `half` is the
    /// clipped volume's half-extent (masks span it).
    pub fn build(&self, base: &Path, half: [f64; 3]) -> Result<Shape, ClipError> {
        // One set of checks: the scene's (every parameter, nesting depth, empty lists).
        self.validate()
            .map_err(|e| ClipError::Invalid(e.to_string()))?;
        self.build_checked(base, half)
    }

    fn build_checked(&self, base: &Path, half: [f64; 3]) -> Result<Shape, ClipError> {
        let v = DVec3::from_array;
        Ok(match self {
            ShapeSpec::Sphere { center, radius } => Shape::Sphere {
                center: v(*center),
                radius: *radius,
            },
            ShapeSpec::Box {
                center,
                half_size,
                rotation,
            } => Shape::Box {
                center: v(*center),
                half_size: v(*half_size),
                rotation: rotation_from_degrees(*rotation),
            },
            ShapeSpec::Cylinder {
                center,
                radius,
                half_height,
                rotation,
            } => Shape::Cylinder {
                center: v(*center),
                radius: *radius,
                half_height: *half_height,
                rotation: rotation_from_degrees(*rotation),
            },
            ShapeSpec::HalfSpace { point, normal } => {
                let n = v(*normal);
                Shape::HalfSpace {
                    point: v(*point),
                    normal: n / n.length(),
                }
            }
            ShapeSpec::Mesh {
                path,
                position,
                scale,
                rotation,
            } => {
                let file = base.join(path);
                let mesh = arbvis_data::surface::read(&file)?;
                Shape::Mesh(Box::new(mesh_field::MeshShape::placed(
                    &file,
                    &mesh,
                    v(*position),
                    DVec3::splat(*scale),
                    rotation_from_degrees(*rotation),
                )?))
            }
            ShapeSpec::TorusMesh {
                center,
                major_radius,
                minor_radius,
                rotation,
                segments,
            } => {
                let mesh = scene::torus(*major_radius, *minor_radius, *segments)?;
                Shape::Mesh(Box::new(mesh_field::MeshShape::new(
                    &mesh,
                    v(*center),
                    DVec3::ONE,
                    rotation_from_degrees(*rotation),
                )))
            }
            ShapeSpec::Mask { volume, threshold } => {
                let volume = volume.load(base, &arbvis_data::volume::Limits::default())?;
                Shape::Mask(Box::new(mask_field::MaskShape::new(
                    &volume, *threshold, half,
                )))
            }
            ShapeSpec::Union(list) | ShapeSpec::Intersection(list) => {
                let shapes = list
                    .iter()
                    .map(|s| s.build_checked(base, half))
                    .collect::<Result<Vec<_>, _>>()?;
                if matches!(self, ShapeSpec::Union(_)) {
                    Shape::Union(shapes)
                } else {
                    Shape::Intersection(shapes)
                }
            }
            ShapeSpec::Difference(pair) => Shape::Difference(
                Box::new(pair[0].build_checked(base, half)?),
                Box::new(pair[1].build_checked(base, half)?),
            ),
        })
    }
}

impl ClipSpec {
    /// The clip grid for a volume of `volume_dims` with half-extents `half`.
    pub fn grid(&self, volume_dims: [usize; 3], half: [f64; 3]) -> Result<ClipGrid, ClipError> {
        ClipGrid::new(self.resolution.unwrap_or(volume_dims), half)
    }

    /// The shape with `invert` applied.
    pub fn shape(&self, base: &Path, half: [f64; 3]) -> Result<Shape, ClipError> {
        let shape = self.shape.build(base, half)?;
        Ok(if self.invert {
            Shape::Invert(Box::new(shape))
        } else {
            shape
        })
    }

    /// Build everything for a volume of `volume_dims` and half-extents `half` (see
    /// [`arbvis_data::volume::Volume::half_extent`]); the DATA texture stays within
    /// `max_3d_texture_size` texels per side.
    pub fn build(
        &self,
        base: &Path,
        volume_dims: [usize; 3],
        half: [f64; 3],
        max_3d_texture_size: usize,
    ) -> Result<ClipTextures, ClipError> {
        let grid = self.grid(volume_dims, half)?;
        let shape = self.shape(base, half)?;
        let single = ClipTexture::build(&shape, &grid);
        let multires = if self.multires {
            Some(MultiRes::build(&single, self.block, max_3d_texture_size)?)
        } else {
            None
        };
        Ok(ClipTextures {
            shape,
            single,
            multires,
        })
    }
}
