//! The store's description, the group attribute `arbvis` of `STORE/zarr.json`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::volume::attributes::Attribute;

/// Format name in [`StoreMeta::format`].
pub const FORMAT: &str = "arbvis bricked multi-resolution survey";
/// Version of the layout `arbvis convert` writes: 2, the MDIO v1 layout (level 0 as the
/// group's own variables, coarser levels in `level_N` groups). Version 1 (every level
/// under `ATTRIBUTE/LEVEL`) is still read.
pub const VERSION: u32 = 2;

/// The layout versions arbvis reads.
pub const VERSIONS: [u32; 2] = [1, 2];

/// The group attribute `arbvis`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoreMeta {
    /// [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// Voxels along sample (i), crossline (j), inline (k) at level 0.
    pub dims: [usize; 3],
    /// Voxel size along i, j, k.
    pub spacing: [f64; 3],
    /// Brick (chunk) side in voxels.
    pub brick: usize,
    /// Number of levels (level 0 is the survey).
    pub levels: usize,
    /// The filter from one level to the next, in words.
    pub filter: String,
    /// The attributes stored, amplitude first.
    pub attributes: Vec<AttributeMeta>,
    /// Where the survey came from.
    pub source: SourceMeta,
    /// Codec of the chunks, in words.
    pub compression: String,
    /// True once every chunk and range of every level is written.
    pub complete: bool,
    /// Where the levels were added beside an MDIO dataset's own arrays: the dataset's
    /// variable that is level 0 of amplitude, read in place.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source_variable: Option<String>,
}

/// One stored attribute.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AttributeMeta {
    /// Name as in scenes (`amplitude`, `envelope`, `phase`, `frequency`).
    pub name: String,
    /// Zarr data type (`float32`, `float16`).
    pub dtype: String,
    /// Smallest finite sample of level 0 (null until the conversion ends).
    pub min: Option<f64>,
    /// Largest finite sample.
    pub max: Option<f64>,
    /// Mean of the finite samples.
    pub mean: Option<f64>,
    /// Samples that are NaN or infinite.
    pub non_finite: u64,
}

impl AttributeMeta {
    /// The attribute.
    pub fn attribute(&self) -> Option<Attribute> {
        crate::volume::attributes::by_name(&self.name)
    }
}

/// The source file and what its headers said.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceMeta {
    /// The file as given to `arbvis convert`.
    pub path: String,
    /// `SEG-Y`, `NIfTI-1`, `raw`.
    pub kind: String,
    /// Its length in bytes.
    pub bytes: u64,
    /// Header facts, by name (inlines, crosslines, sample interval, format, ...).
    pub facts: BTreeMap<String, String>,
    /// Inline numbers along k: first, step (SEG-Y).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inlines: Option<[i64; 2]>,
    /// Crossline numbers along j: first, step (SEG-Y).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crosslines: Option<[i64; 2]>,
    /// Sample interval in microseconds (SEG-Y).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval_us: Option<u32>,
    /// The sample axis as the source numbers it, where it says more than `interval_us`
    /// (an MDIO dataset's time or depth coordinate: its first value, a depth domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<SampleAxis>,
}

/// The sample axis's domain and numbers: sample `i` is at `first + i * step` `unit`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleAxis {
    /// `time`, `depth` or `sample` (MDIO's dimension name).
    pub domain: String,
    /// `ms`, `m`, or empty for plain sample numbers.
    pub unit: String,
    /// The first sample's coordinate.
    pub first: f64,
    /// The spacing of samples.
    pub step: f64,
}

impl SampleAxis {
    /// `time (ms)`, `depth (m)` or `sample`.
    pub fn label(&self) -> String {
        if self.unit.is_empty() {
            self.domain.clone()
        } else {
            format!("{} ({})", self.domain, self.unit)
        }
    }
}

impl SourceMeta {
    /// The sample axis: as given, else time in ms from the sample interval (SEG-Y starts
    /// at 0), else plain sample numbers.
    pub fn sample_axis(&self) -> SampleAxis {
        if let Some(s) = &self.samples {
            return s.clone();
        }
        match self.interval_us {
            Some(us) => SampleAxis {
                domain: "time".into(),
                unit: "ms".into(),
                first: 0.0,
                step: us as f64 / 1000.0,
            },
            None => SampleAxis {
                domain: "sample".into(),
                unit: String::new(),
                first: 0.0,
                step: 1.0,
            },
        }
    }
}

impl StoreMeta {
    /// The zarr path of attribute `attr`'s level `level` (`/amplitude`, `/level_1/amplitude`;
    /// version 1: `/amplitude/0`).
    pub fn array_path(&self, attr: usize, level: usize) -> String {
        let name = &self.attributes[attr].name;
        match (self.version, level) {
            (1, _) => format!("/{name}/{level}"),
            (_, 0) => format!("/{name}"),
            (_, l) => format!("/level_{l}/{name}"),
        }
    }

    /// The zarr path of the per-brick ranges of `attr` at `level` (`/amplitude_range`,
    /// `/level_1/amplitude_range`; version 1: `/amplitude/range/0`).
    pub fn range_path(&self, attr: usize, level: usize) -> String {
        let name = &self.attributes[attr].name;
        match (self.version, level) {
            (1, _) => format!("/{name}/range/{level}"),
            (_, 0) => format!("/{name}_range"),
            (_, l) => format!("/level_{l}/{name}_range"),
        }
    }

    /// The name of the sample axis: `time` or `depth` where the source says (SEG-Y's
    /// sample interval, an MDIO dataset's dimension), else `sample`.
    pub fn domain(&self) -> String {
        self.source.sample_axis().domain
    }

    /// The attribute named `name`, and its position.
    pub fn attribute(&self, name: &str) -> Option<(usize, &AttributeMeta)> {
        self.attributes
            .iter()
            .enumerate()
            .find(|(_, a)| a.name == name)
    }

    /// Voxels per axis of `level`.
    pub fn level_dims(&self, level: usize) -> [usize; 3] {
        super::level_dims(self.dims, level)
    }

    /// Bricks per axis of `level`.
    pub fn brick_counts(&self, level: usize) -> [usize; 3] {
        super::brick_counts(self.level_dims(level), self.brick)
    }

    /// Half-extents of the survey's box in object space (longest side spans [-1, 1]), as
    /// [`crate::volume::Volume::half_extent`].
    pub fn half_extent(&self) -> [f64; 3] {
        let size: [f64; 3] = std::array::from_fn(|a| {
            let s = self.spacing[a];
            self.dims[a] as f64 * if s.is_finite() && s > 0.0 { s } else { 1.0 }
        });
        let longest = size.iter().copied().fold(0.0, f64::max);
        size.map(|s| s / longest)
    }
}
