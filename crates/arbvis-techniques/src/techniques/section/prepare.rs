//! A section's CPU side: the survey loaded and its attribute derived (or a store opened,
//! whose planes are read at full resolution as they are needed), the cut found in the
//! survey's numbers, and the plane's samples taken out (blended between the two samples
//! either side of a position between them).

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;

use super::{Cut, SectionScene};
use crate::error::RenderResult;
use crate::techniques::world::World;
use arbvis_core::colortable::ColorTable;
use arbvis_core::vocab::FieldError;
use arbvis_data::store::Store;
use arbvis_data::volume::attributes::derive;
use arbvis_data::volume::axes::{load_with_axes, section_axes, store_axes, Axis, Numbers};
use arbvis_data::volume::quantize::{range, Quantization};
use arbvis_data::volume::segy::geometry::MapFrame;
use arbvis_data::volume::{Limits, Volume, VolumeSource};

/// Where a section's samples come from.
#[derive(Clone)]
pub enum Samples {
    /// The attribute's values over the whole survey, in memory.
    Whole(Volume),
    /// A store (or an MDIO dataset), its attribute's index: each plane read at level 0.
    Store(Arc<Store>, usize),
}

impl std::fmt::Debug for Samples {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Samples::Whole(v) => write!(f, "Whole({:?})", v.dims),
            Samples::Store(s, a) => write!(f, "Store({}, attribute {a})", s.path.display()),
        }
    }
}

/// A section as prepared: the survey, its axes, the table's range and the plane shown.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Where moving the section reads its samples.
    pub samples: Samples,
    /// The survey's voxels (samples, crosslines, inlines).
    pub dims: [usize; 3],
    /// The survey's axes in its own numbers (time, crossline, inline).
    pub axes: [Axis; 3],
    /// The values the table's first and last entries stand for.
    pub range: (f64, f64),
    /// The colour table.
    pub table: ColorTable,
    /// The survey box's half extents in the object frame (as 3D opacity's).
    pub half: DVec3,
    /// Where the object frame lies in the world.
    pub world: World,
    /// The plane shown.
    pub plane: Plane,
}

/// The samples on one section.
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// The voxel axis across the plane.
    pub axis: usize,
    /// Its position along that axis, in voxels (fractional between samples).
    pub position: f64,
    /// Samples across and down ([`section_axes`]).
    pub size: [usize; 2],
    /// The values, across fastest; NaN where there is no data.
    pub values: Vec<f32>,
}

impl Prepared {
    /// The plane at `cut`, or an error naming the key and the survey's range (or the
    /// store's that could not be read).
    pub fn plane_at(&self, cut: Cut) -> RenderResult<Plane> {
        let position = position(&self.axes[cut.axis], cut)?;
        match &self.samples {
            Samples::Whole(volume) => Ok(plane(volume, cut.axis, position)),
            Samples::Store(store, attr) => {
                // The one or two samples either side along the axis, every one across.
                let last = self.dims[cut.axis].saturating_sub(1);
                let first = (position.floor().max(0.0) as usize).min(last);
                let (mut lo, mut hi) = ([0; 3], self.dims);
                lo[cut.axis] = first;
                hi[cut.axis] = (first + 2).min(last + 1);
                let window = store.window(*attr, lo, hi)?;
                let mut p = plane(&window, cut.axis, position - first as f64);
                p.position = position;
                Ok(p)
            }
        }
    }

    /// The values the table spans under `quantize`: a store's from its metadata (min-max
    /// or a range; its percentiles are not computed).
    pub fn range_of(&self, quantize: Quantization) -> RenderResult<(f64, f64)> {
        match &self.samples {
            Samples::Whole(volume) => Ok(range(volume, quantize)?),
            Samples::Store(store, attr) => {
                let meta = &store.meta.attributes[*attr];
                match quantize {
                    Quantization::MinMax => Ok((meta.min.unwrap_or(0.0), meta.max.unwrap_or(0.0))),
                    Quantization::Range([l, h]) => Ok((l, h)),
                    Quantization::Percentile(_) => Err(FieldError::new(
                        "quantize",
                        "percentiles of a store are not computed; use \"min-max\" or { range = [low, high] }",
                    )
                    .into()),
                }
            }
        }
    }

    /// The plane's four corners in the object frame (counter-clockwise: low-low,
    /// high-low, high-high, low-high along across and down) and their texture coordinates.
    pub fn corners(&self) -> [(DVec3, [f64; 2]); 4] {
        let Plane { axis, position, .. } = self.plane;
        let (u, w) = section_axes(axis);
        let n = self.dims[axis].max(1) as f64;
        let at = ((position + 0.5) / n * 2.0 - 1.0) * self.half[axis];
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|st: [f64; 2]| {
            let mut p = DVec3::ZERO;
            p[axis] = at;
            p[u] = (st[0] * 2.0 - 1.0) * self.half[u];
            p[w] = (st[1] * 2.0 - 1.0) * self.half[w];
            (p, st)
        })
    }
}

/// The voxel position of `cut` on `axis`: a number the axis lists (inline and crossline
/// numbers), or one within a linear axis's span (time or depth, between samples too).
pub fn position(axis: &Axis, cut: Cut) -> Result<f64, FieldError> {
    let len = axis.len.max(1);
    let outside = |what: String| FieldError::new(cut.key, what);
    // A survey that says its vertical axis is time is not cut by depth, nor one in depth
    // by time (a SEG-Y's samples are read as time; plain sample numbers take either).
    let other = match cut.key {
        "time" => Some("depth"),
        "depth" => Some("time"),
        _ => None,
    };
    if let Some(other) = other.filter(|o| axis.name.starts_with(o)) {
        return Err(outside(format!(
            "{} {}: the survey's vertical axis is {} (a SEG-Y's samples are read as time); use {other} = N",
            cut.key, cut.number, axis.name
        )));
    }
    match &axis.numbers {
        Numbers::Listed(numbers) => numbers
            .iter()
            .position(|&v| v == cut.number)
            .map(|i| i as f64)
            .ok_or_else(|| {
                let lo = numbers.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = numbers.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                outside(format!(
                    "{} {} is not one of the survey's {}s ({lo} to {hi}, {len} of them)",
                    cut.key, cut.number, axis.name
                ))
            }),
        Numbers::Linear { start, step } => {
            let t = (cut.number - start) / step;
            let last = (len - 1) as f64;
            // A millionth of a sample: the number written as the axis writes its own.
            if t.is_finite() && t >= -1e-6 && t <= last + 1e-6 {
                Ok(t.clamp(0.0, last))
            } else {
                Err(outside(format!(
                    "{} {}: the survey's {} runs from {} to {}",
                    cut.key,
                    cut.number,
                    axis.name,
                    axis.value(0),
                    axis.value(len - 1)
                )))
            }
        }
        Numbers::Span { lo, hi } => {
            let t = (cut.number - lo) / (hi - lo) * len as f64 - 0.5;
            if t.is_finite() && (0.0..=(len - 1) as f64).contains(&t) {
                Ok(t)
            } else {
                Err(outside(format!(
                    "{} {}: the survey's {} spans {lo} to {hi}",
                    cut.key, cut.number, axis.name
                )))
            }
        }
    }
}

/// The samples of `volume` on the plane at `position` along `axis`: the two samples
/// either side blended linearly (one where it falls on a sample), across fastest.
pub fn plane(volume: &Volume, axis: usize, position: f64) -> Plane {
    let dims = volume.dims;
    let (u, w) = section_axes(axis);
    let last = dims[axis].saturating_sub(1);
    let lo = (position.floor().max(0.0) as usize).min(last);
    let hi = (lo + 1).min(last);
    let f = (position - lo as f64).clamp(0.0, 1.0);
    let mut values = Vec::with_capacity(dims[u] * dims[w]);
    for y in 0..dims[w] {
        for x in 0..dims[u] {
            let at = |k: usize| {
                let mut ijk = [0usize; 3];
                ijk[axis] = k;
                ijk[u] = x;
                ijk[w] = y;
                volume.values[ijk[0] + dims[0] * (ijk[1] + dims[1] * ijk[2])] as f64
            };
            let v = match f {
                0.0 => at(lo),
                _ => at(lo) * (1.0 - f) + at(hi) * f,
            };
            values.push(v as f32);
        }
    }
    Plane {
        axis,
        position,
        size: [dims[u], dims[w]],
        values,
    }
}

/// The survey's axes in its own numbers (time, crossline, inline), as [`prepare`] finds
/// them: a store's from its metadata, a file's by reading it (once; the viewer keeps them
/// to bound its sliders).
pub fn survey_axes(scene: &SectionScene, base: &Path) -> RenderResult<[Axis; 3]> {
    match &scene.volume {
        VolumeSource::Store(path) => {
            let store = Store::open(&arbvis_data::fetch::resolve(base, path))?;
            Ok(store_axes(&store.meta, [[0; 3], store.meta.dims]))
        }
        source => Ok(load_with_axes(source, base, &Limits::default())?.1),
    }
}

/// Load, derive (or open the store), find the cut and take its plane.
pub fn prepare(scene: &SectionScene, base: &Path, limits: &Limits) -> RenderResult<Prepared> {
    let cut = scene.cut()?;
    let (samples, axes, spacing, map) = match &scene.volume {
        VolumeSource::Store(path) => {
            let store = Arc::new(Store::open(&arbvis_data::fetch::resolve(base, path))?);
            let attr = store.attribute_index(scene.attribute.name())?;
            let meta = &store.meta;
            let axes = store_axes(meta, [[0; 3], meta.dims]);
            let [_, nj, nk] = meta.dims;
            let map = store.map_coordinates()?.and_then(|xy| {
                MapFrame::of_corners(nj, nk, |k, j| {
                    let t = k * nj + j;
                    Some([*xy[0].get(t)?, *xy[1].get(t)?])
                })
            });
            let spacing = meta.spacing;
            (Samples::Store(store, attr), axes, spacing, map)
        }
        source => {
            let (loaded, axes) = load_with_axes(source, base, limits)?;
            let volume = derive(&loaded, scene.attribute);
            let (spacing, map) = (volume.spacing, volume.map);
            (Samples::Whole(volume), axes, spacing, map)
        }
    };
    let dims: [usize; 3] = std::array::from_fn(|a| axes[a].len);
    let table = scene
        .table
        .build(base)
        .map_err(|e| FieldError::new("table", e.to_string()))?;
    let size = DVec3::from_array(std::array::from_fn(|a| {
        let s = spacing[a];
        dims[a] as f64 * if s.is_finite() && s > 0.0 { s } else { 1.0 }
    }));
    let half = size / size.max_element();
    let world = match scene.volume.data_kind() {
        arbvis_data::sniff::DataKind::Survey => World::of_survey(dims, size, half, map.as_ref()),
        _ => World::of_box([0.0; 3], size.to_array()),
    };
    let mut prepared = Prepared {
        samples,
        dims,
        axes,
        range: (0.0, 0.0),
        table,
        half,
        world,
        plane: Plane {
            axis: cut.axis,
            position: 0.0,
            size: [0, 0],
            values: Vec::new(),
        },
    };
    prepared.range = prepared.range_of(scene.quantize)?;
    prepared.plane = prepared.plane_at(cut)?;
    Ok(prepared)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cut(axis: usize, number: f64) -> Cut {
        Cut {
            axis,
            number,
            key: ["time", "crossline", "inline"][axis],
        }
    }

    #[test]
    fn listed_numbers_are_found_exactly_and_others_refused_with_the_range() {
        let inlines = Axis {
            name: "inline".into(),
            len: 4,
            numbers: Numbers::Listed(vec![101.0, 103.0, 105.0, 107.0]),
        };
        assert_eq!(position(&inlines, cut(2, 105.0)).unwrap(), 2.0);
        let e = position(&inlines, cut(2, 104.0)).unwrap_err();
        assert_eq!(e.key, "inline");
        assert!(e.message.contains("101 to 107"), "{}", e.message);
    }

    #[test]
    fn times_fall_between_samples_and_outside_the_trace_are_refused() {
        let time = Axis {
            name: "time (ms)".into(),
            len: 5,
            numbers: Numbers::Linear {
                start: 0.0,
                step: 4.0,
            },
        };
        assert_eq!(position(&time, cut(0, 6.0)).unwrap(), 1.5);
        assert_eq!(position(&time, cut(0, 16.0)).unwrap(), 4.0);
        let e = position(&time, cut(0, 16.5)).unwrap_err();
        assert!(e.message.contains("runs from 0 to 16"), "{}", e.message);
        assert!(position(&time, cut(0, -0.1)).is_err());
        // A depth cut of a survey in time, a time cut of one in depth: refused by key.
        let depth_cut = Cut {
            key: "depth",
            ..cut(0, 6.0)
        };
        let e = position(&time, depth_cut).unwrap_err().to_string();
        assert!(e.contains("depth") && e.contains("use time = N"), "{e}");
        let depth = Axis {
            name: "depth (m)".into(),
            ..time.clone()
        };
        assert_eq!(position(&depth, depth_cut).unwrap(), 1.5);
        let e = position(&depth, cut(0, 6.0)).unwrap_err().to_string();
        assert!(e.contains("use depth = N"), "{e}");
    }

    #[test]
    fn a_plane_blends_the_samples_either_side_in_the_order_the_viewer_shows_them() {
        // Odd sizes and distinct values: a swapped axis or stride shows.
        let dims = [3, 4, 5];
        let values: Vec<f32> = (0..60).map(|v| (v * 7 % 61) as f32).collect();
        let volume = Volume::new(dims, [1.0; 3], values.clone()).unwrap();
        let at = |i: usize, j: usize, k: usize| values[i + 3 * (j + 4 * k)];
        // Inline section (axis 2): crossline across, time down.
        let p = plane(&volume, 2, 3.0);
        assert_eq!(p.size, [4, 3]);
        assert_eq!(p.values[1 + 4 * 2], at(2, 1, 3));
        // A time slice a quarter of the way from sample 1 to 2: crossline across, inline down.
        let p = plane(&volume, 0, 1.25);
        assert_eq!(p.size, [4, 5]);
        let want = at(1, 3, 4) as f64 * 0.75 + at(2, 3, 4) as f64 * 0.25;
        assert!((p.values[3 + 4 * 4] as f64 - want).abs() < 1e-5);
        // Crossline section (axis 1): inline across, time down.
        let p = plane(&volume, 1, 2.0);
        assert_eq!(p.size, [5, 3]);
        // Inline 4 across, time 1 down (rows of 5).
        assert_eq!(p.values[5 + 4], at(1, 2, 4));
    }
}
