//! Surveys larger than memory: a bricked, multi-resolution store in zarr v3 (written with
//! the `zarrs` crate, readable by zarr-python, Dask, xarray and any zarr v3 reader), and
//! what streams it to the GPU.
//!
//! # The store
//! A zarr v3 group (`STORE/zarr.json`) laid out as an MDIO v1 post-stack dataset
//! ([`layout`]), whose attribute `arbvis` ([`StoreMeta`]) holds the survey's dimensions,
//! spacing, brick side, level count, filter, each attribute's value statistics and the
//! source's header facts. Level 0 is the group's variables (`STORE/amplitude`, ...),
//! level `L` the group `STORE/level_L`: one array per attribute and level, shape
//! `[inlines, crosslines, samples]` (zarr's C order: the sample axis fastest, as in
//! [`crate::volume::Volume`]), dimension names `inline, crossline, time` (or `sample`;
//! suffixed `_L` in level `L`), chunks of `B³` voxels (the bricks; `B` = 64 by default),
//! compressed (blosc LZ4 over shuffled bytes by default; `--compression`). Level `L` is `ceil(n / 2^L)` voxels per axis; levels go on until one
//! brick holds the volume. Amplitude is float32 (exactly the source's values); the derived
//! attributes (envelope, phase, frequency) are float16 (11 significant bits, a relative
//! error of 2^-11, far below the 1/255 the colour tables resolve) to halve their disk and
//! read cost. `NAME_range` holds per brick the min and max of its finite samples
//! (`[bricks_k, bricks_j, bricks_i, 2]`, float32; NaN where none is finite), so a brick
//! that the tables make transparent is skipped without reading it. Stores of version 1
//! (`STORE/<attribute>/<level>`, `STORE/<attribute>/range/<level>`) are still read.
//!
//! The filter from one level to the next is a box (the mean of the 2x2x2 voxels, fewer at
//! a far edge of odd size), for every attribute but phase, whose mean wraps wrongly at
//! ±180°: phase keeps the first voxel of each 2x2x2 cell (decimation).
//!
//! # Modules
//! - [`meta`]: the group's attributes; [`check`]: every number in them and every array
//!   checked at open.
//! - [`zarr`]: zarr v3 metadata and chunks read as bounded input (regular files only,
//!   sizes checked, chunks decoded into their known size).
//! - [`input`]: the sources read in columns (SEG-Y, NIfTI, raw), never whole.
//! - [`convert`]: `arbvis convert` (streamed, parallel, resumable; memory bound), with
//!   `columns`: one column of a level made, cut into bricks, written and logged;
//!   `filter`: the level filter and a brick's statistics;
//!   [`progress`]: its lock and progress log.
//! - [`describe`]: `arbvis inspect STORE`.
//! - [`mdio`]: MDIO v1 datasets (written by mdio-python) opened in place as one level.
//! - [`layout`]: the MDIO v1 layout `convert` writes (metadata, coordinates, statistics).
//! - [`reader`]: chunks, bricks with their one-voxel border, and level-0 windows read back.
//! - [`lod`]: which bricks a view needs (screen-space error), in visibility order (no GL).

pub mod check;
mod columns;
pub mod compression;
pub mod convert;
pub mod describe;
mod filter;
pub mod input;
pub mod layout;
pub mod lod;
pub mod mdio;
pub mod meta;
pub mod progress;
pub mod reader;
pub mod zarr;

use std::path::{Path, PathBuf};

pub use meta::StoreMeta;
pub use reader::Store;

/// Errors of the store: each names the store (and the chunk, where one is at fault).
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// A source volume could not be read.
    #[error(transparent)]
    Volume(#[from] crate::volume::VolumeError),
    /// A file of the store could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// A chunk is missing or cannot be decoded.
    #[error(
        "{path}: chunk {chunk:?} (its index along inline, crossline, sample) of {array}: {message}"
    )]
    Chunk {
        /// The chunk's file.
        path: PathBuf,
        /// The array (`amplitude/0`).
        array: String,
        /// The chunk's index `[k, j, i]` in its array's chunk grid (a store's bricks, an
        /// MDIO variable's own chunks).
        chunk: [u64; 3],
        /// What is wrong.
        message: String,
    },
    /// The store's metadata is not what arbvis writes.
    #[error("{path}: {message}")]
    Invalid {
        /// The store.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The conversion was interrupted (Ctrl-C); running it again resumes.
    #[error("{0}")]
    Interrupted(String),
    /// Over the memory budget.
    #[error("{0}")]
    Budget(String),
}

impl StoreError {
    pub(crate) fn io(path: &Path, e: impl std::fmt::Display) -> StoreError {
        StoreError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
    pub(crate) fn invalid(path: &Path, m: impl Into<String>) -> StoreError {
        StoreError::Invalid {
            path: path.to_path_buf(),
            message: m.into(),
        }
    }
}

/// Voxels per axis of level `level` of a volume of `dims`.
pub fn level_dims(dims: [usize; 3], level: usize) -> [usize; 3] {
    dims.map(|d| d.div_ceil(1 << level).max(1))
}

/// Bricks per axis of a level of `dims` voxels.
pub fn brick_counts(dims: [usize; 3], brick: usize) -> [usize; 3] {
    dims.map(|d| d.div_ceil(brick))
}

/// Levels needed until one brick of side `brick` holds the volume.
pub fn level_count(dims: [usize; 3], brick: usize) -> usize {
    let mut levels = 1;
    while level_dims(dims, levels - 1).iter().any(|&d| d > brick) {
        levels += 1;
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_until_one_brick() {
        assert_eq!(level_count([64, 64, 64], 64), 1);
        assert_eq!(level_count([65, 3, 3], 64), 2);
        assert_eq!(level_dims([65, 3, 3], 1), [33, 2, 2]);
        // 1000 x 2000 x 2500 with 64³ bricks: 2500 -> 1250 -> 625 -> 313 -> 157 -> 79 -> 40.
        assert_eq!(level_count([1000, 2000, 2500], 64), 7);
        assert_eq!(brick_counts([1000, 2000, 2500], 64), [16, 32, 40]);
    }
}
