//! What the panels and overlays know of a mesh or a cloud, told by its technique
//! ([`Summary`], [`crate::techniques::Technique::summary`]) once it is prepared:
//! the box in object space with its axes in the file's coordinates and units, and, for a
//! cloud, the ids (facies, layers, classes) and attribute ranges its key shows.
//!
//! Units: the generated section is in metres (its module says so); a LAS/LAZ file's
//! come from its projection records ([`units`]); `.dat` text, PLY files and
//! meshes say nothing of units, so their axes are plain `x`, `y`, `z`.

use std::collections::BTreeSet;
use std::path::Path;

use glam::DVec3;

pub mod units;

use arbvis_data::points::{PointCloud, PointSource, FACIES, FAULT, LAYER};
use arbvis_data::volume::axes::{span, Axis};
use units::{las_units, Units};

/// Most distinct ids a key lists (beyond, it says how many more there are).
pub const MAX_IDS: usize = 64;

/// A data box: half-extents in object space and the three axes along x, y, z.
#[derive(Debug, Clone, PartialEq)]
pub struct DataBox {
    /// Half-extents in object space (the box is centred on the origin).
    pub half: DVec3,
    /// The axes, in the file's coordinates.
    pub axes: [Axis; 3],
}

/// The box of file coordinates `lo`..`hi` scaled into object space by `scale` (object
/// units per file unit), axes named `x`, `y`, `z` with `units`.
pub fn data_box(lo: [f64; 3], hi: [f64; 3], scale: f64, units: &Units) -> DataBox {
    let name = |a: usize| {
        let unit = if a == 2 {
            &units.vertical
        } else {
            &units.horizontal
        };
        let n = ["x", "y", "z"][a];
        match unit {
            Some(u) => format!("{n} ({u})"),
            None => n.to_string(),
        }
    };
    DataBox {
        half: DVec3::from_array(std::array::from_fn(|a| {
            ((hi[a] - lo[a]) * scale / 2.0).max(1e-9)
        })),
        axes: std::array::from_fn(|a| span(&name(a), lo[a], hi[a])),
    }
}

/// The units of a cloud's source (relative paths from `base`).
pub fn cloud_units(source: &PointSource, base: &Path) -> Units {
    match source {
        PointSource::Section(_) => Units {
            horizontal: Some("m".into()),
            vertical: Some("m".into()),
        },
        PointSource::Las(p) => las_units(&base.join(p)),
        PointSource::Copc(spec) => las_units(&base.join(&spec.path)),
        PointSource::Dat(_) | PointSource::Ply(_) | PointSource::Memory(_) => Units::default(),
    }
}

/// What a cloud's key and box need.
#[derive(Debug, Clone, PartialEq)]
pub struct CloudSummary {
    /// The box and axes.
    pub data_box: DataBox,
    /// Distinct facies ids, ascending (at most [`MAX_IDS`]).
    pub facies: Vec<i32>,
    /// Distinct layer ids, ascending (at most [`MAX_IDS`]).
    pub layers: Vec<i32>,
    /// Distinct classification codes, ascending (at most [`MAX_IDS`]).
    pub classes: Vec<i32>,
    /// Ids beyond [`MAX_IDS`], per list (facies, layers, classes).
    pub more: [usize; 3],
    /// Some point lies on a fault.
    pub faults: bool,
    /// Each attribute's name and finite range.
    pub ranges: Vec<(String, [f64; 2])>,
    /// Lowest and highest z, in the file's units.
    pub elevation: [f64; 2],
}

fn distinct(values: Option<&[i32]>) -> (Vec<i32>, usize) {
    let set: BTreeSet<i32> = values.unwrap_or(&[]).iter().copied().collect();
    let more = set.len().saturating_sub(MAX_IDS);
    (set.into_iter().take(MAX_IDS).collect(), more)
}

impl CloudSummary {
    /// The summary of `cloud`, whose coordinates are in `units`.
    pub fn of(cloud: &PointCloud, units: &Units) -> CloudSummary {
        let [lo, hi] = cloud.bounds;
        let (facies, f) = distinct(cloud.ints(FACIES));
        let (layers, l) = distinct(cloud.ints(LAYER));
        let (classes, c) = distinct(cloud.ints("classification"));
        CloudSummary {
            data_box: data_box(lo, hi, 1.0 / cloud.scale, units),
            facies,
            layers,
            classes,
            more: [f, l, c],
            faults: cloud.ints(FAULT).is_some_and(|v| v.iter().any(|&x| x >= 0)),
            ranges: cloud
                .attributes
                .iter()
                .map(|a| (a.name.clone(), [a.stats.min, a.stats.max]))
                .collect(),
            elevation: [cloud.frame[0][2], cloud.frame[1][2]],
        }
    }

    /// The finite range of attribute `name`.
    pub fn range(&self, name: &str) -> Option<[f64; 2]> {
        self.ranges
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, r)| *r)
            .filter(|r| r[0].is_finite() && r[1].is_finite())
    }
}

/// What a technique tells its front end's panels of its prepared data
/// ([`crate::techniques::Technique::summary`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Summary {
    /// A cloud's box, ids and ranges (splats).
    Cloud(CloudSummary),
    /// A mesh's box and scalar (cell projection).
    Mesh(MeshSummary),
}

/// What a mesh's key and box need.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSummary {
    /// The box and axes.
    pub data_box: DataBox,
    /// The scalar's name.
    pub scalar: String,
    /// The scalar values mapped to 0 and 1.
    pub range: [f64; 2],
    /// The normalized scalar's histogram, 256 bins (the transfer-function editor's).
    pub histogram: Vec<u32>,
}

/// The histogram of normalized scalars `(v - lo) / (hi - lo)` in 256 bins (values
/// outside the range in the end bins).
pub fn histogram(values: &[f64], range: [f64; 2]) -> Vec<u32> {
    let mut h = vec![0u32; 256];
    let span = range[1] - range[0];
    for &v in values.iter().filter(|v| v.is_finite()) {
        let t = if span > 0.0 {
            (v - range[0]) / span
        } else {
            0.0
        };
        h[(t * 255.0).round().clamp(0.0, 255.0) as usize] += 1;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_data::points::section::{generate, SectionSpec};

    #[test]
    fn a_section_has_metres_and_its_ids() {
        let cloud = generate(&SectionSpec {
            points: 5000,
            seed: 3,
        })
        .unwrap();
        let s = CloudSummary::of(
            &cloud,
            &cloud_units(
                &PointSource::Section(SectionSpec { points: 1, seed: 1 }),
                Path::new("."),
            ),
        );
        let names: Vec<&str> = s.data_box.axes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["x (m)", "y (m)", "z (m)"]);
        // Layers 0..7 all occur in 5000 points (each is about 500 m of 4000).
        assert_eq!(s.layers, (0..8).collect::<Vec<_>>());
        assert!(
            s.facies.contains(&-999) && s.facies.len() >= 4,
            "{:?}",
            s.facies
        );
        assert!(s.faults);
        assert!(s.classes.is_empty());
        // The box: x spans 12 km, the longest side, so its half-extent is 1 in object
        // space; z spans 4 km of it (within the points' spread of a few metres).
        assert!(
            (s.data_box.half.x - 1.0).abs() < 1e-3,
            "{:?}",
            s.data_box.half
        );
        assert!(
            (s.data_box.half.z - 4.0 / 12.0).abs() < 2e-3,
            "{:?}",
            s.data_box.half
        );
        let [lo, hi] = s.range("porosity").unwrap();
        assert!(lo >= 0.0 && hi > lo && hi < 0.05, "{lo} {hi}");
        assert_eq!(s.range("no such"), None);
    }

    #[test]
    fn ids_beyond_the_limit_are_counted() {
        let many: Vec<i32> = (0..100).rev().collect();
        let (ids, more) = distinct(Some(&many));
        assert_eq!((ids.len(), ids[0], more), (MAX_IDS, 0, 100 - MAX_IDS));
        assert_eq!(distinct(None), (vec![], 0));
    }

    #[test]
    fn histogram_bins_normalized_values() {
        // Range 10..20: 10 -> bin 0, 15 -> 127.5 rounds to 128, 25 (beyond) -> 255.
        let h = histogram(&[10.0, 15.0, 15.0, 25.0, f64::NAN], [10.0, 20.0]);
        assert_eq!((h[0], h[128], h[255]), (1, 2, 1));
        assert_eq!(h.iter().sum::<u32>(), 4);
    }
}
