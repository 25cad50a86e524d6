//! CPU preparation of the 3D-opacity data (no GL): load each attribute's volume once per
//! distinct source, derive the attribute, quantize it, pack the three bytes of each voxel
//! as RGB (R tertiary, G primary, B secondary), and build the colour tables.

use std::path::Path;

use glam::DVec3;

use super::{AttributeScene, Opacity3dScene};
use crate::error::RenderResult;
use arbvis_core::colortable::ColorTable;
use arbvis_core::vocab::FieldError;
use arbvis_data::volume::attributes::derive;
use arbvis_data::volume::quantize::{quantize_level, quantize_value, range, NoData, Quantization};
use arbvis_data::volume::{Limits, Volume, VolumeError, VolumeSource};

/// Everything the renderer uploads, and the CPU references read.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Grid size (i, j, k).
    pub dims: [usize; 3],
    /// Half-extents of the box (longest side spans [-1, 1]).
    pub half: DVec3,
    /// The box's sides in the data's own units (dims times spacing): where it lies in a
    /// layered scene's world ([`crate::techniques::world`]).
    pub size: DVec3,
    /// Where a survey's traces lie on the map (its CDP coordinates), where known.
    pub map: Option<arbvis_data::volume::segy::geometry::MapFrame>,
    /// RGB per voxel, i fastest: R tertiary, G primary, B secondary (0 when absent).
    pub packed: Vec<u8>,
    /// Tables of primary, secondary, tertiary (None when the attribute is absent).
    pub tables: [Option<ColorTable>; 3],
    /// Value range each attribute was quantized over.
    pub ranges: [Option<(f64, f64)>; 3],
    /// What NaN ("no data": an irregular survey's dead traces) became in each attribute's
    /// levels: a level its table makes transparent, or level 0 reserved with the table's
    /// entry 0 cleared, so that no data is never drawn.
    pub no_data: [NoData; 3],
}

/// Byte of attribute `a` (0 primary, 1 secondary, 2 tertiary) in a packed RGB texel.
pub const CHANNEL: [usize; 3] = [1, 2, 0];

impl Prepared {
    /// The primary attribute's colour at `p` (object frame) through its table: the
    /// quantized level interpolated trilinearly between the voxel centres around `p`
    /// (clamped at the box's faces), the table linear between its entries; None outside
    /// the box or without a primary table.
    pub fn primary_colour_at(&self, p: DVec3) -> Option<[f64; 3]> {
        let table = self.tables[0].as_ref()?;
        let u = (p + self.half) / (2.0 * self.half);
        if !u.is_finite() || u.min_element() < 0.0 || u.max_element() > 1.0 {
            return None;
        }
        let dims = self.dims.map(|d| d.max(1));
        let c = std::array::from_fn::<f64, 3, _>(|a| {
            (u[a] * dims[a] as f64 - 0.5).clamp(0.0, (dims[a] - 1) as f64)
        });
        let lo = c.map(|x| x.floor() as usize);
        let f: [f64; 3] = std::array::from_fn(|a| c[a] - lo[a] as f64);
        let mut level = 0.0;
        for corner in 0..8 {
            let at: [usize; 3] =
                std::array::from_fn(|a| (lo[a] + (corner >> a & 1)).min(dims[a] - 1));
            let w: f64 = (0..3)
                .map(|a| {
                    if corner >> a & 1 == 1 {
                        f[a]
                    } else {
                        1.0 - f[a]
                    }
                })
                .product();
            let v = at[0] + dims[0] * (at[1] + dims[1] * at[2]);
            level += w * self.byte(v, 0) as f64;
        }
        let k = (level.floor() as usize).min(254);
        let t = level - k as f64;
        let entry = |k: usize| table.entries[k].map(|c| c as f64 / 255.0);
        let (a, b) = (entry(k), entry(k + 1));
        Some(std::array::from_fn(|i| a[i] * (1.0 - t) + b[i] * t))
    }

    /// Quantized value of attribute `a` at voxel index `v`.
    pub fn byte(&self, v: usize, a: usize) -> u8 {
        self.packed[v * 3 + CHANNEL[a]]
    }

    /// Number of attributes present.
    pub fn count(&self) -> usize {
        self.tables.iter().filter(|t| t.is_some()).count()
    }

    /// Which attributes are present (primary, secondary, tertiary).
    pub fn present(&self) -> [bool; 3] {
        self.tables.each_ref().map(Option::is_some)
    }

    /// The present attributes' levels only, interleaved in attribute order (the precise
    /// volume: one channel per attribute the scene has).
    pub fn present_levels(&self) -> Vec<u8> {
        let channels: Vec<usize> = (0..3)
            .filter(|&a| self.tables[a].is_some())
            .map(|a| CHANNEL[a])
            .collect();
        self.packed
            .chunks_exact(3)
            .flat_map(|texel| channels.iter().map(move |&c| texel[c]))
            .collect()
    }

    /// The one present attribute's levels as the ray caster's neighbour words (tag
    /// `neighbours` of `programs/opacity3d/raycast.frag`): texel (i, j, k) holds the 2x2x2
    /// levels from (i, j, k) to (i+1, j+1, k+1), clamped to the last voxel as
    /// CLAMP_TO_EDGE reads them, one byte each from the low byte up: word 0 the plane k at
    /// (i, j), (i+1, j), (i, j+1), (i+1, j+1), word 1 the plane k+1 alike. One texel fetch
    /// a sample instead of the eight of a linear read: llvmpipe gathers every texel of a
    /// filtered read lane by lane, and that gather was most of a ray caster step.
    pub fn neighbour_words(&self) -> Vec<u32> {
        let levels = self.present_levels();
        let [ni, nj, nk] = self.dims;
        let at = |i: usize, j: usize, k: usize| -> u32 {
            levels[i.min(ni - 1) + ni * (j.min(nj - 1) + nj * k.min(nk - 1))] as u32
        };
        let plane = |i, j, k| {
            at(i, j, k) | at(i + 1, j, k) << 8 | at(i, j + 1, k) << 16 | at(i + 1, j + 1, k) << 24
        };
        let mut words = Vec::with_capacity(2 * levels.len());
        for k in 0..nk {
            for j in 0..nj {
                for i in 0..ni {
                    words.push(plane(i, j, k));
                    words.push(plane(i, j, k + 1));
                }
            }
        }
        words
    }

    /// Object-space spacing that table alphas are defined for (precise mode's opacity
    /// correction): one voxel along the longest axis.
    pub fn reference_spacing(&self) -> f64 {
        let longest = (0..3)
            .max_by(|&a, &b| self.half[a].total_cmp(&self.half[b]))
            .unwrap_or(0);
        2.0 * self.half[longest] / self.dims[longest] as f64
    }
}

/// Pack quantized attributes (all of one length) into RGB.
pub fn pack(quantized: [Option<&[u8]>; 3], voxels: usize) -> Vec<u8> {
    let mut packed = vec![0u8; voxels * 3];
    for (a, q) in quantized.iter().enumerate() {
        if let Some(q) = q {
            for (v, &b) in q.iter().enumerate() {
                packed[v * 3 + CHANNEL[a]] = b;
            }
        }
    }
    packed
}

/// Prepare from volumes already in memory: each present attribute's volume, its
/// quantization and its table. All volumes must share one grid. NaN samples (no data)
/// take a level the table makes transparent ([`NoData`]).
pub fn from_volumes(
    attributes: [Option<(&Volume, Quantization, ColorTable)>; 3],
) -> RenderResult<Prepared> {
    let first = attributes[0]
        .as_ref()
        .ok_or_else(|| FieldError::new("primary", "the primary attribute is required"))?
        .0;
    let names = super::ATTRIBUTE_NAMES;
    let mut quantized: [Option<Vec<u8>>; 3] = Default::default();
    let mut ranges = [None; 3];
    let mut tables: [Option<ColorTable>; 3] = Default::default();
    let mut no_data = [NoData::Absent; 3];
    for (a, attr) in attributes.into_iter().enumerate() {
        let Some((volume, how, mut table)) = attr else {
            continue;
        };
        if volume.dims != first.dims {
            return Err(VolumeError::Invalid(format!(
                "the {} volume is {:?} but the primary is {:?}: all attributes must share one grid",
                names[a], volume.dims, first.dims
            ))
            .into());
        }
        let (low, high) = range(volume, how)
            .map_err(|e| super::error::Opacity3dError::of_attribute(e.into(), names[a]))?;
        let alpha: Vec<u8> = table.entries.iter().map(|e| e[3]).collect();
        no_data[a] = NoData::choose(volume.values.iter().any(|v| v.is_nan()), &alpha);
        if no_data[a] == NoData::Reserved {
            table.entries[0] = [0; 4];
        }
        let levels = volume
            .values
            .iter()
            .map(|&v| quantize_level(v, low, high, no_data[a]))
            .collect();
        ranges[a] = Some((low, high));
        quantized[a] = Some(levels);
        tables[a] = Some(table);
    }
    let packed = pack([0, 1, 2].map(|a| quantized[a].as_deref()), first.len());
    Ok(Prepared {
        dims: first.dims,
        half: DVec3::from_array(first.half_extent()),
        size: DVec3::from_array(std::array::from_fn(|a| {
            let s = first.spacing[a];
            first.dims[a] as f64 * if s.is_finite() && s > 0.0 { s } else { 1.0 }
        })),
        map: first.map,
        packed,
        tables,
        ranges,
        no_data,
    })
}

/// The table's alpha from the distribution of `volume`'s levels over its quantization
/// range ([`arbvis_core::colortable::alpha_from_histogram`]); NaN samples (no data) are left out.
fn alpha_from_data(volume: &Volume, how: Quantization) -> Result<[u8; 256], VolumeError> {
    let (low, high) = range(volume, how)?;
    let mut counts = [0u64; 256];
    for &v in volume.values.iter().filter(|v| !v.is_nan()) {
        counts[quantize_value(v, low, high) as usize] += 1;
    }
    Ok(arbvis_core::colortable::alpha_from_histogram(&counts))
}

/// Prepare a scene: load each distinct source once (its size checked against `limits`
/// before loading), derive, quantize, pack, build tables.
pub fn prepare(scene: &Opacity3dScene, base: &Path, limits: &Limits) -> RenderResult<Prepared> {
    let mut loaded: Vec<(VolumeSource, Volume)> = Vec::new();
    let mut derived: [Option<Volume>; 3] = Default::default();
    let mut tables: [Option<ColorTable>; 3] = Default::default();
    let names = super::ATTRIBUTE_NAMES;
    for (a, attr) in scene.attributes().into_iter().enumerate() {
        let Some(AttributeScene {
            volume,
            attribute,
            table,
            ..
        }) = attr
        else {
            continue;
        };
        let index = match loaded.iter().position(|(s, _)| s == volume) {
            Some(i) => i,
            None => {
                let v = volume.load(base, limits)?;
                loaded.push((volume.clone(), v));
                loaded.len() - 1
            }
        };
        let mut volume = derive(&loaded[index].1, *attribute);
        volume.spacing = scene.spacing_for(volume.spacing);
        derived[a] = Some(volume);
        tables[a] = Some(table.build(base).map_err(|source| {
            super::error::Opacity3dError::AttributeTable {
                attribute: names[a],
                source,
            }
        })?);
    }
    // Alpha from each attribute's own distribution, where its table asks for it.
    let attrs = scene.attributes();
    for (a, attr) in attrs.into_iter().enumerate() {
        let (Some(attr), Some(volume), Some(table)) = (attr, &derived[a], &mut tables[a]) else {
            continue;
        };
        let survey = attr.volume.data_kind() == arbvis_data::sniff::DataKind::Survey;
        if attr.table.wants_alpha_from_data(survey) {
            let alpha = alpha_from_data(volume, attr.quantize)
                .map_err(|e| super::error::Opacity3dError::of_attribute(e.into(), names[a]))?;
            for (entry, alpha) in table.entries.iter_mut().zip(alpha) {
                entry[3] = alpha;
            }
        }
    }
    let inputs: [Option<(&Volume, Quantization, ColorTable)>; 3] =
        std::array::from_fn(|a| match (&derived[a], &tables[a], attrs[a]) {
            (Some(v), Some(t), Some(s)) => Some((v, s.quantize, t.clone())),
            _ => None,
        });
    from_volumes(inputs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packs_g_primary_b_secondary_r_tertiary() {
        let p = pack([Some(&[10, 11]), Some(&[20, 21]), Some(&[30, 31])], 2);
        assert_eq!(p, vec![30, 10, 20, 31, 11, 21]);
        let two = pack([Some(&[10]), Some(&[20]), None], 1);
        assert_eq!(two, vec![0, 10, 20], "2D opacity leaves R at 0");
    }

    #[test]
    fn neighbour_words_hold_each_voxels_2x2x2_levels_clamped_at_the_far_edges() {
        // Odd sizes and distinct levels: a swapped axis or a missed clamp shows.
        let dims = [3, 2, 5];
        let n = dims[0] * dims[1] * dims[2];
        let levels: Vec<u8> = (0..n).map(|v| (v * 37 % 251) as u8).collect();
        let prepared = Prepared {
            dims,
            half: DVec3::ONE,
            size: DVec3::ONE,
            map: None,
            packed: pack([Some(&levels), None, None], n),
            tables: [Some(ColorTable::builtin("grey").unwrap()), None, None],
            ranges: [None; 3],
            no_data: [NoData::Absent; 3],
        };
        let words = prepared.neighbour_words();
        assert_eq!(words.len(), 2 * n);
        let level =
            |i: usize, j: usize, k: usize| levels[i.min(2) + 3 * (j.min(1) + 2 * k.min(4))] as u32;
        for k in 0..5 {
            for j in 0..2 {
                for i in 0..3 {
                    let t = 2 * (i + 3 * (j + 2 * k));
                    for (w, kk) in [(words[t], k), (words[t + 1], k + 1)] {
                        let bytes = [w & 255, w >> 8 & 255, w >> 16 & 255, w >> 24];
                        let want = [
                            level(i, j, kk),
                            level(i + 1, j, kk),
                            level(i, j + 1, kk),
                            level(i + 1, j + 1, kk),
                        ];
                        assert_eq!(bytes, want, "texel ({i}, {j}, {k}), plane {kk}");
                    }
                }
            }
        }
    }

    #[test]
    fn present_levels_keep_the_present_attributes_in_order() {
        let grey = ColorTable::builtin("grey").unwrap();
        let prepared = Prepared {
            dims: [2, 1, 1],
            half: DVec3::ONE,
            size: DVec3::ONE,
            map: None,
            packed: pack([Some(&[10, 11]), None, Some(&[30, 31])], 2),
            tables: [Some(grey.clone()), None, Some(grey)],
            ranges: [None; 3],
            no_data: [NoData::Absent; 3],
        };
        assert_eq!(prepared.present(), [true, false, true]);
        assert_eq!(prepared.present_levels(), vec![10, 30, 11, 31]);
    }

    #[test]
    fn grids_must_match() {
        let a = Volume::new([2, 2, 2], [1.0; 3], vec![0.0; 8]).unwrap();
        let b = Volume::new([2, 2, 1], [1.0; 3], vec![0.0; 4]).unwrap();
        let grey = ColorTable::builtin("grey").unwrap();
        let e = from_volumes([
            Some((&a, Quantization::MinMax, grey.clone())),
            Some((&b, Quantization::MinMax, grey)),
            None,
        ])
        .unwrap_err();
        let e = e.to_string();
        assert!(e.contains("secondary") && e.contains("one grid"), "{e}");
    }
}
