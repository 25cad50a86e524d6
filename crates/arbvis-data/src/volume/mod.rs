//! Attribute volumes: one scalar per voxel on a regular grid, from SEG-Y, NIfTI, raw files
//! or a synthetic seismic cube; derived attributes (Hilbert envelope, phase, ...); and the
//! quantization to 0..255 that v3o2 applied before packing.
//!
//! Axes: `dims = [ni, nj, nk]` with `i` fastest in [`Volume::values`]; the renderers map
//! `i, j, k` to texture `s, t, r` and object `x, y, z`. Seismic volumes keep the trace
//! order of the file: `i` = sample (time), `j` = crossline, `k` = inline.

pub mod attributes;
pub mod axes;
pub mod index_data;
pub mod memory;
pub mod nifti_file;
pub mod quantize;
pub mod raw;
pub mod segy;
pub mod synthetic;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// A scalar volume.
#[derive(Debug, Clone, PartialEq)]
pub struct Volume {
    /// Voxels along i (fastest), j, k.
    pub dims: [usize; 3],
    /// Physical size of one voxel along i, j, k (sets the box's aspect).
    pub spacing: [f64; 3],
    /// `ni * nj * nk` samples, i fastest. May hold NaN or infinities from files.
    pub values: Vec<f32>,
    /// Where a survey's traces lie on the map (its CDP coordinates), where its file says.
    pub map: Option<segy::geometry::MapFrame>,
}

impl Volume {
    /// A volume of `dims`, checking that `values` has the right length.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        values: Vec<f32>,
    ) -> Result<Volume, VolumeError> {
        let n = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if n != Some(values.len()) || dims.contains(&0) {
            return Err(VolumeError::Invalid(format!(
                "volume of {}x{}x{} needs as many samples, got {}",
                dims[0],
                dims[1],
                dims[2],
                values.len()
            )));
        }
        Ok(Volume {
            dims,
            spacing,
            values,
            map: None,
        })
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True for no voxels (never, for a volume made by [`Volume::new`]).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Index of voxel `(i, j, k)`.
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Minimum, maximum and mean over the finite samples, and how many were not finite.
    pub fn stats(&self) -> Stats {
        let mut s = Stats::accumulator();
        self.values.iter().for_each(|&v| s.add(v));
        s.finish()
    }

    /// Half-extents of the volume's box in object space: the longest side spans [-1, 1].
    pub fn half_extent(&self) -> [f64; 3] {
        let size: [f64; 3] = std::array::from_fn(|a| {
            let s = self.spacing[a];
            self.dims[a] as f64 * if s.is_finite() && s > 0.0 { s } else { 1.0 }
        });
        let longest = size.iter().copied().fold(0.0, f64::max);
        size.map(|s| s / longest)
    }
}

/// Value statistics of a volume.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    /// Smallest finite sample (+inf when none).
    pub min: f64,
    /// Largest finite sample (-inf when none).
    pub max: f64,
    /// Mean of the finite samples (NaN when none).
    pub mean: f64,
    /// Samples that are NaN or infinite.
    pub non_finite: usize,
}

impl Stats {
    /// Running statistics, fed one sample at a time (for streamed files).
    pub fn accumulator() -> StatsAccumulator {
        StatsAccumulator {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            sum: 0.0,
            finite: 0,
            non_finite: 0,
        }
    }

    /// One line: `values: min .. max .. mean ..` and the count of NaN/inf samples.
    pub fn describe(&self) -> String {
        format!(
            "values: min {} max {} mean {:.6}{}\n",
            self.min,
            self.max,
            self.mean,
            if self.non_finite > 0 {
                format!(" ({} NaN or infinite samples)", self.non_finite)
            } else {
                String::new()
            }
        )
    }
}

/// [`Stats`] being gathered.
#[derive(Debug, Clone)]
pub struct StatsAccumulator {
    min: f64,
    max: f64,
    sum: f64,
    finite: u64,
    non_finite: usize,
}

impl StatsAccumulator {
    /// Count one sample.
    pub fn add(&mut self, v: f32) {
        if v.is_finite() {
            let v = v as f64;
            self.min = self.min.min(v);
            self.max = self.max.max(v);
            self.sum += v;
            self.finite += 1;
        } else {
            self.non_finite += 1;
        }
    }

    /// The statistics so far.
    pub fn finish(&self) -> Stats {
        Stats {
            min: self.min,
            max: self.max,
            mean: if self.finite > 0 {
                self.sum / self.finite as f64
            } else {
                f64::NAN
            },
            non_finite: self.non_finite,
        }
    }
}

/// Errors reading volumes: each names the file, a byte offset where one applies, and what
/// was expected there.
#[derive(Debug, thiserror::Error)]
pub enum VolumeError {
    /// The file could not be opened or read.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
    /// The content is not what the format requires.
    #[error("{path}: at byte {offset}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// Byte offset of the problem.
        offset: u64,
        /// What was expected and what was found.
        message: String,
    },
    /// The file is valid but cannot be used here (e.g. a pre-stack or irregular SEG-Y).
    #[error("{path}: {message}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// Parameters (from a scene) that cannot describe a volume.
    #[error("{0}")]
    Invalid(String),
}

impl VolumeError {
    pub(crate) fn format(path: &Path, offset: u64, message: impl Into<String>) -> VolumeError {
        VolumeError::Format {
            path: path.to_path_buf(),
            offset,
            message: message.into(),
        }
    }
    pub(crate) fn io(path: &Path, error: std::io::Error) -> VolumeError {
        VolumeError::Io {
            path: path.to_path_buf(),
            error,
        }
    }
}

/// Sample types of raw files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SampleType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// IEEE 754 single.
    F32,
    /// IEEE 754 double.
    F64,
}

impl SampleType {
    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            SampleType::U8 | SampleType::I8 => 1,
            SampleType::U16 | SampleType::I16 => 2,
            SampleType::U32 | SampleType::I32 | SampleType::F32 => 4,
            SampleType::F64 => 8,
        }
    }

    /// Decode one sample from exactly [`SampleType::bytes`] bytes.
    pub fn decode(self, b: &[u8], big_endian: bool) -> f32 {
        macro_rules! num {
            ($t:ty) => {{
                let a = b.try_into().expect("caller passes bytes() bytes");
                if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            SampleType::U8 => b[0] as f32,
            SampleType::I8 => b[0] as i8 as f32,
            SampleType::U16 => num!(u16) as f32,
            SampleType::I16 => num!(i16) as f32,
            SampleType::U32 => num!(u32) as f32,
            SampleType::I32 => num!(i32) as f32,
            SampleType::F32 => num!(f32),
            SampleType::F64 => num!(f64) as f32,
        }
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            SampleType::U8 => "u8",
            SampleType::I8 => "i8",
            SampleType::U16 => "u16",
            SampleType::I16 => "i16",
            SampleType::U32 => "u32",
            SampleType::I32 => "i32",
            SampleType::F32 => "f32",
            SampleType::F64 => "f64",
        }
    }
}

/// Byte order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Endian {
    /// Least significant byte first.
    #[default]
    Little,
    /// Most significant byte first (SEG-Y's standard order).
    Big,
}

/// Where a volume comes from, as written in a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum VolumeSource {
    /// A SEG-Y file (rev 0-2), gridded from its trace headers; pre-stack files with an
    /// offset or stacked.
    Segy(segy::SegySource),
    /// A NIfTI-1 file (`.nii` or `.nii.gz`); the first 3D volume.
    Nifti(PathBuf),
    /// A headerless file described in the scene.
    Raw(raw::RawSpec),
    /// The built-in seismic-like cube.
    Synthetic(synthetic::SyntheticSpec),
    /// A bricked multi-resolution store made by `arbvis convert` (3D opacity streams it
    /// brick by brick; it is never loaded whole).
    Store(PathBuf),
    /// A survey handed over in memory (an `arbvis.Volume`), by its name ([`memory`]).
    Memory(String),
}

/// What a volume may hold, checked against the dimensions a file or scene declares
/// *before* its samples are read or generated (the GL's 3D texture limit, passed down by
/// the renderer, and a voxel budget).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest side in voxels (`GL_MAX_3D_TEXTURE_SIZE`).
    pub max_side: usize,
    /// Largest voxel count.
    pub max_voxels: u64,
}

impl Default for Limits {
    /// Without a GL at hand: 16384 per side (what the largest drivers allow) and 2^31
    /// voxels (8 GiB of f32 samples).
    fn default() -> Self {
        Limits {
            max_side: 16384,
            max_voxels: 1 << 31,
        }
    }
}

impl Limits {
    /// The limits on a GL whose `GL_MAX_3D_TEXTURE_SIZE` is `max_3d_texture_size`.
    pub fn for_max_side(max_3d_texture_size: i32) -> Limits {
        Limits {
            max_side: max_3d_texture_size.max(1) as usize,
            ..Default::default()
        }
    }

    /// Check `dims` declared by `what` (a file or a scene value).
    pub fn check(&self, dims: [usize; 3], what: &str) -> Result<(), VolumeError> {
        let voxels = dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d as u64));
        let side = dims.iter().copied().max().unwrap_or(0);
        if dims.contains(&0) {
            return Err(VolumeError::Invalid(format!(
                "{what}: dimensions {dims:?} hold no voxels"
            )));
        }
        if side > self.max_side {
            return Err(VolumeError::Invalid(format!(
                "{what}: dimensions {dims:?} exceed the largest 3D texture side, {} (GL_MAX_3D_TEXTURE_SIZE)",
                self.max_side
            )));
        }
        if let Some(n) = voxels {
            // The samples as f32 (the loaders' output); derived attributes and textures are
            // estimated by the technique that makes them.
            arbvis_core::budget::check(
                format!("{what}: {n} samples of {dims:?} as f32"),
                arbvis_core::budget::times(n, 4),
            )
            .map_err(|e| VolumeError::Invalid(e.to_string()))?;
        }
        match voxels {
            Some(n) if n <= self.max_voxels => Ok(()),
            _ => Err(VolumeError::Invalid(format!(
                "{what}: dimensions {dims:?} exceed the limit of {} voxels",
                self.max_voxels
            ))),
        }
    }
}

impl VolumeSource {
    /// The voxel count the source declares without reading anything (a generated
    /// volume's size); `None` for files, whose loaders check their headers.
    pub fn declared_voxels(&self) -> Option<u64> {
        match self {
            VolumeSource::Synthetic(spec) => Some(
                spec.size
                    .iter()
                    .fold(1u64, |a, &d| a.saturating_mul(d as u64)),
            ),
            _ => None,
        }
    }

    /// The dimensions a generated volume will have (`None` for files).
    pub fn declared_dims(&self) -> Option<[usize; 3]> {
        match self {
            VolumeSource::Synthetic(spec) => Some(spec.size),
            _ => None,
        }
    }

    /// Read the volume; relative paths are taken from `base` (the scene's folder). The
    /// dimensions are checked against `limits` before any sample is read.
    pub fn load(&self, base: &Path, limits: &Limits) -> Result<Volume, VolumeError> {
        match self {
            VolumeSource::Segy(s) => {
                let options = segy::ReadOptions {
                    limits: *limits,
                    prestack: s.prestack,
                    keys: s.keys,
                };
                Ok(segy::read(&base.join(&s.path), &options)?.volume)
            }
            VolumeSource::Nifti(p) => nifti_file::read(&base.join(p), limits),
            VolumeSource::Raw(spec) => raw::read(base, spec, limits),
            VolumeSource::Synthetic(spec) => synthetic::amplitude(spec, limits),
            VolumeSource::Memory(name) => memory::load(name, limits),
            VolumeSource::Store(p) => Err(VolumeError::Unsupported {
                path: base.join(p),
                message: "a store is never loaded whole: only 3D opacity's attribute volumes stream one, brick by brick (give the same store as each attribute's volume of an opacity3d scene)".into(),
            }),
        }
    }

    /// Check the scene values that can be checked without reading files.
    pub fn validate(&self) -> Result<(), arbvis_core::vocab::FieldError> {
        match self {
            VolumeSource::Synthetic(spec) => spec.validate().map_err(|e| e.within("synthetic")),
            VolumeSource::Raw(spec) => spec.validate().map_err(|e| e.within("raw")),
            VolumeSource::Segy(s) => s.keys.validate().map_err(|e| e.within("segy")),
            VolumeSource::Nifti(_) | VolumeSource::Store(_) | VolumeSource::Memory(_) => Ok(()),
        }
    }

    /// The scene's word for the kind of source (`segy`, `store`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            VolumeSource::Segy(_) => "segy",
            VolumeSource::Nifti(_) => "nifti",
            VolumeSource::Raw(_) => "raw",
            VolumeSource::Synthetic(_) => "synthetic",
            VolumeSource::Store(_) => "store",
            VolumeSource::Memory(_) => "memory",
        }
    }

    /// The file it names, if any, for rewriting.
    pub fn path_mut(&mut self) -> Option<&mut PathBuf> {
        match self {
            VolumeSource::Segy(s) => Some(&mut s.path),
            VolumeSource::Nifti(p) => Some(p),
            VolumeSource::Raw(spec) => Some(&mut spec.path),
            VolumeSource::Store(p) => Some(p),
            VolumeSource::Synthetic(_) | VolumeSource::Memory(_) => None,
        }
    }

    /// The file it names, if any.
    pub fn path(&self) -> Option<&Path> {
        match self {
            VolumeSource::Segy(s) => Some(&s.path),
            VolumeSource::Nifti(p) => Some(p),
            VolumeSource::Raw(spec) => Some(&spec.path),
            VolumeSource::Store(p) => Some(p),
            VolumeSource::Synthetic(_) | VolumeSource::Memory(_) => None,
        }
    }
}

/// `arbvis inspect` for volumes: what the loaders see in `path`, the format chosen from
/// the content (gzip or NIfTI's magic) and the extension; anything else is read as SEG-Y.
pub fn inspect(path: &Path) -> Result<String, VolumeError> {
    inspect_with(path, segy::KeyBytes::default())
}

/// [`inspect`] with a SEG-Y file's inline and crossline bytes named (`inspect --iline 9
/// --xline 21`); each one not named is detected.
pub fn inspect_with(path: &Path, keys: segy::KeyBytes) -> Result<String, VolumeError> {
    let name = path.to_string_lossy().to_lowercase();
    if name.ends_with(".nii") || name.ends_with(".nii.gz") {
        return Ok(format!(
            "{}\n{}",
            path.display(),
            nifti_file::inspect(path)?
        ));
    }
    // The headers and the trace grid first, as `convert` checks them (milliseconds, the
    // traces unread): a file whose headers do not fit it fails here, and a file too large
    // to read whole is described from them alone.
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    match segy::SegyStream::open_with(path, keys) {
        Ok(stream) if len > INSPECT_WHOLE_MAX => {
            let facts: String = stream
                .describe()
                .iter()
                .map(|(k, v)| format!("{k}: {v}\n"))
                .collect();
            let [i, j, k] = stream.dims();
            return Ok(format!(
                "{}\n{facts}dimensions (i, j, k): {i} x {j} x {k}\nstatistics: not computed for a file over {} (they read every sample; `arbvis convert` computes them into a store, which `arbvis inspect STORE` shows)\n",
                path.display(),
                arbvis_core::budget::format_bytes(INSPECT_WHOLE_MAX)
            ));
        }
        Err(e) if len > INSPECT_WHOLE_MAX => return Err(e),
        _ => {}
    }
    let bytes = read_file(path, u64::MAX)?;
    let options = segy::ReadOptions {
        keys,
        ..Default::default()
    };
    match segy::parse(path, &bytes, &options) {
        Ok(s) => {
            // Dead positions (no trace) are NaN but no sample of the file: the statistics
            // are the live traces', and their non-finite count the file's own.
            let mut stats = s.volume.stats();
            stats.non_finite -= (s.grid.positions() - s.grid.live) * s.volume.dims[0];
            Ok(format!(
                "{}\n{}{}",
                path.display(),
                s.describe(),
                describe_with(&s.volume, stats)
            ))
        }
        // A pre-stack file cannot be gridded as one cube without a choice: describe its
        // gathers and say how a scene makes that choice.
        Err(e) => match segy::gathers(path, &bytes, keys) {
            Ok(g) if g.is_prestack() => Ok(format!("{}\n{}", path.display(), g.describe(path))),
            _ => Err(e),
        },
    }
}

/// Largest SEG-Y file `inspect` reads whole (for its statistics).
pub const INSPECT_WHOLE_MAX: u64 = 1 << 30;

/// Dimensions and value statistics, one item per line.
pub fn describe(v: &Volume) -> String {
    describe_with(v, v.stats())
}

/// [`describe`] with the statistics given.
fn describe_with(v: &Volume, stats: Stats) -> String {
    format!(
        "dimensions (i, j, k): {} x {} x {} = {} samples\nspacing: {} x {} x {}\n{}",
        v.dims[0],
        v.dims[1],
        v.dims[2],
        v.len(),
        v.spacing[0],
        v.spacing[1],
        v.spacing[2],
        stats.describe()
    )
}

/// Read a whole regular file of at most `max_bytes`, naming it in the error.
pub(crate) fn read_file(path: &Path, max_bytes: u64) -> Result<Vec<u8>, VolumeError> {
    arbvis_core::input::read_regular(path, max_bytes).map_err(|e| VolumeError::io(path, e))
}
