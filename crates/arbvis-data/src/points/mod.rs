//! Point clouds for the point-based rendering of geological sections (seed 004): the
//! cloud itself, its readers (`.dat` text, LAS/LAZ, PLY), the generator of a synthetic
//! geological section, and `arbvis inspect` for point files.
//!
//! # Positions: f32 around an f64 origin
//!
//! The seed rescaled the cloud on import. Here every loader hands f64 coordinates to
//! [`PointCloud::from_parts`], which takes the centre of the bounding box as `origin` and
//! half of the largest extent as `scale` (1 when all points coincide), and stores
//! `local = (p - origin) / scale` as f32: the cloud fits [-1, 1]³ with its longest side
//! spanning it exactly, ready for a GPU buffer. The original coordinate is
//! `origin + scale * local` ([`PointCloud::original`]), exact to about
//! `scale * 2^-24` — 0.03 mm for a 1 km lidar tile, 0.3 mm for 10 km — whatever the
//! offset: georeferenced LAS coordinates of 1e5-1e6 m keep their millimetres because the
//! offset lives in the f64 origin, not in the f32s. Non-finite coordinates are refused by
//! every reader (a NaN position has no place on screen and would poison the bounds).
//!
//! # Attributes
//!
//! Named scalar columns, integer ([`Values::Int`], i32: ids, LAS intensity and
//! classification) or real ([`Values::Float`], f32). The seed's six use the names in
//! [`LAYER`], [`FACIES`] (-999 = [`UNDEFINED_FACIES`]), [`FAULT`] (negative = not on a
//! fault), [`POROSITY`], [`AMPLITUDE`] and [`JOINT_DIP`]. Colours are kept apart as u16 per
//! channel, as LAS stores them (8-bit PLY colours are scaled by 257 so 255 → 65535), and
//! normals when a PLY file has them. Each attribute gets min, max and median on load, as
//! the seed computed them for its colour scales: the median is the element at index
//! `n / 2` of the finite values (the upper median for even counts), found with
//! `select_nth_unstable` on a copy, as C++'s `nth_element` would; NaN and infinities are
//! left out of all three and counted. An attribute whose min equals its max (or that has
//! no finite value) reports [`Stats::zero_range`], which the seed's
//! `value / (max - min)` would divide by zero on.
//!
//! # Limits
//!
//! Files up to [`MAX_FILE_BYTES`] and [`MAX_POINTS`] points are read; the generator
//! makes up to [`section::MAX_SECTION_POINTS`]. A progress bar is drawn on stderr for
//! [`progress::MIN_POINTS`] points or more when stderr is a terminal.

mod cloud;
pub mod copc;
pub mod copc_cache;
mod copc_hierarchy;
pub mod copc_load;
pub mod copc_lod;
pub mod copc_write;
pub mod dat;
pub mod lasfile;
pub mod memory;
pub mod ply;
pub mod plycloud;
pub mod progress;
pub mod section;

use std::path::{Path, PathBuf};

use crate::sniff::Format;
use serde::{Deserialize, Serialize};

pub use cloud::footprint;
pub(crate) use cloud::{decimals_for, fixed};
pub use cloud::{Attribute, CloudParts, PartsError, PointCloud, Stats, Values};

/// Largest point file read (the whole file is read into memory).
pub const MAX_FILE_BYTES: u64 = 8 << 30;

/// Most points read from a file (about 50 bytes each while loading: 5 GB at this limit;
/// the seed's cloud had 570,000 and the benchmarks go to 10-20 million).
pub const MAX_POINTS: u64 = 100_000_000;

/// The seed's layer id attribute (i32, 0..7 in its section).
pub const LAYER: &str = "layer";
/// The seed's facies id attribute (i32; [`UNDEFINED_FACIES`] = undefined).
pub const FACIES: &str = "facies";
/// The seed's fault id attribute (i32; negative = not a fault).
pub const FAULT: &str = "fault";
/// The seed's porosity attribute (f32).
pub const POROSITY: &str = "porosity";
/// The seed's seismic amplitude attribute (f32).
pub const AMPLITUDE: &str = "amplitude";
/// The seed's joint dip attribute (f32, degrees).
pub const JOINT_DIP: &str = "joint_dip";
/// Facies id of points whose rock type is undefined.
pub const UNDEFINED_FACIES: i32 = -999;

/// Errors reading point clouds: each names the file and the position (line and column
/// in text, byte offset in binary) with what was expected and what was found.
#[derive(Debug, thiserror::Error)]
pub enum PointsError {
    /// The file could not be opened or read. (The field is not called `source`: the
    /// message already holds it, and a chain printed with `{:#}` would repeat it.)
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
    /// Binary content that is not what the format requires.
    #[error("{path}: at byte {offset}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// Byte offset of the problem.
        offset: u64,
        /// What was expected and what was found.
        message: String,
    },
    /// Text content that is not what the format requires.
    #[error("{path}: line {line}, column {column}: {message}")]
    Text {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column (characters).
        column: usize,
        /// What was expected and what was found.
        message: String,
    },
    /// A failure inside the LAS/LAZ decoder, with the points it was decoding.
    #[error("{path}: {message}")]
    Decode {
        /// The file.
        path: PathBuf,
        /// What failed, and where.
        message: String,
    },
    /// A valid file this reader does not handle.
    #[error("{path}: {message}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// Parameters (from a scene) that cannot describe a cloud.
    #[error("{0}")]
    Invalid(String),
}

impl PointsError {
    pub(crate) fn format(path: &Path, offset: u64, message: impl Into<String>) -> PointsError {
        PointsError::Format {
            path: path.to_path_buf(),
            offset,
            message: message.into(),
        }
    }
    pub(crate) fn text(
        path: &Path,
        line: usize,
        column: usize,
        message: impl Into<String>,
    ) -> PointsError {
        PointsError::Text {
            path: path.to_path_buf(),
            line,
            column,
            message: message.into(),
        }
    }
    pub(crate) fn io(path: &Path, error: std::io::Error) -> PointsError {
        PointsError::Io {
            path: path.to_path_buf(),
            error,
        }
    }
    pub(crate) fn unsupported(path: &Path, message: impl Into<String>) -> PointsError {
        PointsError::Unsupported {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Read a whole point file (at most [`MAX_FILE_BYTES`], and within the memory budget),
/// naming it in the error.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, PointsError> {
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_file() {
            arbvis_core::budget::check("reading the file", meta.len())
                .map_err(|e| PointsError::unsupported(path, e.to_string()))?;
        }
    }
    arbvis_core::input::read_regular(path, MAX_FILE_BYTES).map_err(|e| PointsError::io(path, e))
}

/// Where a cloud comes from, as written in a scene:
/// `{ dat = { path = "s.dat", columns = { porosity = 7 } } }`, `{ las = "x.laz" }`,
/// `{ ply = "bunny.ply" }`, `{ section = { points = 570000, seed = 1 } }`,
/// `{ copc = { path = "scan.copc.laz", points = 1000000 } }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum PointSource {
    /// The seed's `.dat` text, with its column mapping.
    Dat(dat::DatSpec),
    /// A LAS or LAZ file.
    Las(PathBuf),
    /// A PLY file's vertices.
    Ply(PathBuf),
    /// A COPC file's octree, whole levels from the root within a point budget.
    Copc(copc::CopcSpec),
    /// The generated geological section.
    Section(section::SectionSpec),
    /// A cloud handed over in memory (an `arbvis.Cloud`), by its name ([`memory`]).
    Memory(String),
}

impl PointSource {
    /// The reader of the source's file ([`crate::sniff::READERS`]); `None` for the
    /// generated section.
    pub fn reader(&self) -> Option<&'static crate::sniff::Reader> {
        use crate::sniff::reader;
        match self {
            PointSource::Dat(_) => Some(reader(Format::Dat)),
            PointSource::Las(_) => Some(reader(Format::Las)),
            PointSource::Ply(_) => Some(reader(Format::Ply)),
            PointSource::Copc(_) => Some(reader(Format::Copc)),
            PointSource::Section(_) | PointSource::Memory(_) => None,
        }
    }

    /// The kind of data the source yields: its reader's; a cloud from memory is a cloud
    /// (lidar's defaults, as a LAS file's); the generated section is the seed's kind.
    pub fn data_kind(&self) -> crate::sniff::DataKind {
        match self {
            PointSource::Memory(_) => crate::sniff::DataKind::Cloud,
            _ => self
                .reader()
                .map_or(crate::sniff::DataKind::SeedCloud, |r| r.kind),
        }
    }

    /// A COPC file drawn within `points` (Potree's pixel size: nodes under 150 px left).
    pub fn copc(path: impl Into<PathBuf>, points: u64) -> PointSource {
        PointSource::Copc(copc::CopcSpec {
            path: path.into(),
            points,
            min_node_pixels: copc::DEFAULT_MIN_NODE_PIXELS,
        })
    }

    /// Load or generate the cloud; relative paths are taken from `base` (the scene's
    /// folder). A COPC cloud: whole levels from the root within its budget.
    pub fn load(&self, base: &Path) -> Result<PointCloud, PointsError> {
        Ok(self.load_for(base, None)?.0)
    }

    /// [`PointSource::load`], a COPC cloud's nodes chosen for `view` (Potree's policy,
    /// [`copc_lod`]) when there is one; with what a COPC cut holds.
    pub fn load_for(
        &self,
        base: &Path,
        view: Option<&copc_lod::View>,
    ) -> Result<(PointCloud, Option<copc_lod::Loaded>), PointsError> {
        if let Some(url) = self.path().filter(|p| crate::fetch::url_of(p).is_some()) {
            if !matches!(self, PointSource::Copc(_)) {
                return Err(PointsError::io(
                    url,
                    std::io::Error::other(format!(
                        "a {} cloud is read from local disk; from a URL arbvis reads COPC (`cloud = {{ copc = {{ path = \"...\" }} }}`)",
                        self.kind()
                    )),
                ));
            }
        }
        let cloud = match self {
            PointSource::Dat(spec) => dat::read(&base.join(&spec.path), &spec.columns)?,
            PointSource::Las(p) => lasfile::read(&base.join(p))?.cloud,
            PointSource::Ply(p) => plycloud::read(&base.join(p))?.cloud,
            PointSource::Copc(spec) => {
                let (cloud, loaded) = copc_load::load(spec, base, view)?;
                return Ok((cloud, Some(loaded)));
            }
            PointSource::Section(spec) => section::generate(spec)?,
            PointSource::Memory(name) => memory::load(name)?,
        };
        Ok((cloud, None))
    }

    /// The file it names, if any.
    pub fn path(&self) -> Option<&Path> {
        match self {
            PointSource::Dat(spec) => Some(&spec.path),
            PointSource::Copc(spec) => Some(&spec.path),
            PointSource::Las(p) | PointSource::Ply(p) => Some(p),
            PointSource::Section(_) | PointSource::Memory(_) => None,
        }
    }

    /// The scene's word for the kind of source (`las`, `copc`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            PointSource::Dat(_) => "dat",
            PointSource::Las(_) => "las",
            PointSource::Ply(_) => "ply",
            PointSource::Copc(_) => "copc",
            PointSource::Section(_) => "section",
            PointSource::Memory(_) => "memory",
        }
    }

    /// The file it names, if any, for rewriting.
    pub fn path_mut(&mut self) -> Option<&mut PathBuf> {
        match self {
            PointSource::Dat(spec) => Some(&mut spec.path),
            PointSource::Copc(spec) => Some(&mut spec.path),
            PointSource::Las(p) | PointSource::Ply(p) => Some(p),
            PointSource::Section(_) | PointSource::Memory(_) => None,
        }
    }
}

/// The kinds of point file, told from the content (`LASF`, `ply`) and else the
/// extension (`.las`, `.laz`, `.ply`; anything else is read as `.dat` text).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// LAS or LAZ.
    Las,
    /// PLY.
    Ply,
    /// Whitespace-separated text, one point per line.
    Dat,
}

impl FileKind {
    /// The kind of `bytes` named `path` ([`crate::sniff::point_format`]; COPC is LAS).
    pub fn detect(path: &Path, bytes: &[u8]) -> FileKind {
        match crate::sniff::point_format(path, bytes) {
            Format::Copc | Format::Las => FileKind::Las,
            Format::Ply => FileKind::Ply,
            _ => FileKind::Dat,
        }
    }
}

/// `arbvis inspect` for point files: format and version, point count, bounds in the
/// file's coordinates, the origin and scale chosen, and every attribute with its min,
/// max, median and NaN count. `.dat` files are read with the default columns.
pub fn inspect(path: &Path) -> Result<String, PointsError> {
    // A COPC file is described from its header and hierarchy, without decoding a point.
    // From a URL only COPC is read (its first block read once, by the open).
    let remote = crate::fetch::url_of(path).is_some();
    let mut head = Vec::new();
    if !remote {
        let (file, _) =
            arbvis_core::input::open_regular(path).map_err(|e| PointsError::io(path, e))?;
        std::io::Read::read_to_end(&mut std::io::Read::take(file, 512), &mut head)
            .map_err(|e| PointsError::io(path, e))?;
    }
    if remote || crate::sniff::point_format(path, &head) == Format::Copc {
        let c = copc::Copc::open(path)?;
        return Ok(format!(
            "{}\nformat: COPC (LAZ 1.4, point format {}, {}-byte records), {} points\n{}",
            path.display(),
            c.format.0,
            c.format.1,
            c.points,
            c.describe()?
        ));
    }
    let bytes = read_file(path)?;
    let (format, cloud) = match FileKind::detect(path, &bytes) {
        FileKind::Las => {
            let las = lasfile::parse_owned(path, bytes)?;
            (las.info.describe(), las.cloud)
        }
        FileKind::Ply => {
            let ply = plycloud::parse(path, &bytes)?;
            (ply.describe_format(), ply.cloud)
        }
        FileKind::Dat => {
            let columns = dat::DatColumns::default();
            (
                format!(
                    "format: .dat text, {} values per line (default columns)\n",
                    columns.count
                ),
                dat::parse(path, &bytes, &columns)?,
            )
        }
    };
    Ok(format!("{}\n{format}{}", path.display(), cloud.describe()))
}

/// What the `las`/`laz` decoder reported: its own error, or a panic caught on corrupt data.
#[derive(Debug, thiserror::Error)]
pub enum DecoderError {
    /// An error the decoder returned.
    #[error("{0}")]
    Las(#[from] las::Error),
    /// A panic inside the decoder, with the start of its message.
    #[error("the decoder failed on corrupt data ({0})")]
    Panicked(String),
}

/// Run a `las`/`laz` call, turning a panic into an error. `laz` asserts on
/// some corrupt compressed streams (e.g. `assert!(sym < (1 << 16))` in its arithmetic
/// decoder) where it could return an error; the checks above cannot foresee what an
/// arithmetic-coded stream decodes to, so this is the last guard: the decoder that
/// panicked is dropped with the error, never reused.
pub(crate) fn guarded<T>(f: impl FnOnce() -> las::Result<T>) -> Result<T, DecoderError> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(result) => result.map_err(DecoderError::Las),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(DecoderError::Panicked(arbvis_core::input::shorten(
                &what, 80,
            )))
        }
    }
}

#[cfg(test)]
mod tests;
