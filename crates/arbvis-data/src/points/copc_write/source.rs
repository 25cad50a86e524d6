//! What the COPC writer reads: a LAS/LAZ file record by record (its own scales, offsets,
//! extra bytes and coordinate-system VLRs kept), or a cloud that arbvis loads whole (PLY,
//! the seed's `.dat`), whose attributes other than intensity and classification become
//! extra bytes (integers as i32, reals as f32, their names in the Extra Bytes VLR).

use std::path::Path;

use super::records::{convert, output_format, BASE};
use crate::points::lasfile::stream::{CopiedVlr, Records};
use crate::points::{dat, plycloud, FileKind, PointCloud, PointsError, Values};

/// Records of the output format, a batch at a time, with what the header needs.
pub(super) struct Source {
    /// Output point format (6, 7 or 8) and record length.
    pub(super) format: u8,
    pub(super) record: usize,
    /// Scale and offset of x, y, z.
    pub(super) scale: [f64; 3],
    pub(super) offset: [f64; 3],
    /// Points.
    pub(super) count: u64,
    /// Bounds the input declares (a LAS header's; checked as the points pass).
    pub(super) bounds: [[f64; 3]; 2],
    /// VLRs to copy: extra-bytes descriptors, coordinate systems.
    pub(super) vlrs: Vec<CopiedVlr>,
    kind: Kind,
}

enum Kind {
    Las {
        records: Box<Records>,
        from: u8,
        buf: Vec<u8>,
    },
    Cloud {
        cloud: Box<PointCloud>,
        next: usize,
    },
}

/// Points per batch.
const BATCH: u64 = 65_536;

/// The VLRs worth copying: coordinate systems and extra-bytes descriptors.
fn kept(vlr: &CopiedVlr) -> bool {
    (vlr.user_id == "LASF_Projection" && matches!(vlr.record_id, 2111 | 2112 | 34735..=34737))
        || (vlr.user_id == "LASF_Spec" && vlr.record_id == 4)
}

impl Source {
    /// Open `path` as LAS/LAZ (by content or extension), PLY or `.dat`.
    pub(super) fn open(path: &Path) -> Result<Source, PointsError> {
        let io = |e| PointsError::io(path, e);
        let (file, _) = arbvis_core::input::open_regular(path).map_err(io)?;
        let mut head = Vec::new();
        std::io::Read::read_to_end(&mut std::io::Read::take(file, 16), &mut head).map_err(io)?;
        match FileKind::detect(path, &head) {
            FileKind::Las => Source::las(path),
            FileKind::Ply => Source::cloud(plycloud::read(path)?.cloud),
            FileKind::Dat => Source::cloud(dat::read(path, &Default::default())?),
        }
    }

    fn las(path: &Path) -> Result<Source, PointsError> {
        let records = Records::open(path)?;
        let info = &records.info;
        let from = info.point_format;
        let format = output_format(from);
        let extra = info.record_length as usize - BASE[from as usize];
        for a in 0..3 {
            if info.scale[a].is_nan() || info.scale[a] <= 0.0 {
                return Err(PointsError::format(
                    path,
                    131 + 8 * a as u64,
                    format!(
                        "{} scale {}: a COPC file needs a positive scale",
                        ["x", "y", "z"][a],
                        info.scale[a]
                    ),
                ));
            }
        }
        let mut vlrs: Vec<CopiedVlr> = records
            .vlrs
            .iter()
            .filter(|v| kept(v))
            .map(|v| CopiedVlr {
                user_id: v.user_id.clone(),
                record_id: v.record_id,
                description: v.description,
                data: v.data.clone(),
            })
            .collect();
        // The Extra Bytes descriptors must describe the records' extra bytes exactly
        // (readers refuse a file where they do not): more is refused, what they leave
        // undescribed gets "undocumented" descriptors (data type 0).
        let is_extra = |v: &CopiedVlr| v.user_id == "LASF_Spec" && v.record_id == 4;
        let described = vlrs
            .iter()
            .filter(|v| is_extra(v))
            .try_fold(0usize, |sum, v| {
                described_bytes(path, &v.data).map(|n| sum + n)
            })?;
        if described > extra {
            return Err(PointsError::unsupported(
                path,
                format!(
                    "the Extra Bytes descriptors describe {described} bytes, the records hold {extra} after point format {from}'s {}",
                    BASE[from as usize]
                ),
            ));
        }
        if described < extra {
            let mut data = Vec::new();
            let mut left = extra - described;
            while left > 0 {
                let n = left.min(255);
                let mut d = [0u8; 192];
                d[3] = n as u8; // data type 0: `options` is the byte count
                let name = format!("undocumented_{}", extra - left);
                d[4..4 + name.len()].copy_from_slice(name.as_bytes());
                data.extend_from_slice(&d);
                left -= n;
            }
            match vlrs.iter_mut().find(|v| is_extra(v)) {
                Some(v) => v.data.extend_from_slice(&data),
                None => vlrs.push(CopiedVlr {
                    user_id: "LASF_Spec".into(),
                    record_id: 4,
                    description: [0; 32],
                    data,
                }),
            }
        }
        Ok(Source {
            format,
            record: BASE[format as usize] + extra,
            scale: info.scale,
            offset: info.offset,
            count: info.points,
            bounds: info.header_bounds,
            vlrs,
            kind: Kind::Las {
                from,
                records: Box::new(records),
                buf: Vec::new(),
            },
        })
    }

    fn cloud(cloud: PointCloud) -> Result<Source, PointsError> {
        let format = if cloud.rgb.is_some() { 7 } else { 6 };
        let extras = extra_attributes(&cloud);
        let mut descriptors = Vec::new();
        for a in &extras {
            let mut d = [0u8; 192];
            d[2] = match a.values {
                Values::Int(_) => 6,
                Values::Float(_) => 9,
            };
            let name = extra_name(&a.name);
            let name = name.as_bytes();
            d[4..4 + name.len().min(32)].copy_from_slice(&name[..name.len().min(32)]);
            descriptors.extend_from_slice(&d);
        }
        let mut vlrs = Vec::new();
        if !extras.is_empty() {
            let mut description = [0u8; 32];
            description[..11].copy_from_slice(b"extra bytes");
            vlrs.push(CopiedVlr {
                user_id: "LASF_Spec".into(),
                record_id: 4,
                description,
                data: descriptors,
            });
        }
        // Coordinates in steps no coarser than the f32 positions arbvis loaded them
        // into (2^-23 of the half-extent), as a power of ten.
        let step = (cloud.scale * 2f64.powi(-23)).max(1e-9);
        let s = 10f64.powf(step.log10().floor());
        Ok(Source {
            format,
            record: BASE[format as usize] + 4 * extras.len(),
            scale: [s; 3],
            offset: cloud.origin.map(|o| (o / s).round() * s),
            count: cloud.len() as u64,
            bounds: cloud.bounds,
            vlrs,
            kind: Kind::Cloud {
                cloud: Box::new(cloud),
                next: 0,
            },
        })
    }

    /// Append the next batch of output records to `out`; returns how many (0 at the end).
    pub(super) fn next(&mut self, out: &mut Vec<u8>) -> Result<u64, PointsError> {
        match &mut self.kind {
            Kind::Las { records, from, buf } => {
                buf.clear();
                let n = records.next(BATCH, buf)?;
                let len = records.info.record_length as usize;
                for r in buf.chunks_exact(len) {
                    convert(*from, self.format, r, out);
                }
                Ok(n)
            }
            Kind::Cloud { cloud, next } => {
                let end = (*next + BATCH as usize).min(cloud.len());
                let extras = extra_attributes(cloud);
                let class = cloud.ints("classification");
                let intensity = cloud.ints("intensity");
                for i in *next..end {
                    let p = cloud.original(i).expect("in range");
                    for (a, p) in p.into_iter().enumerate() {
                        let v = ((p - self.offset[a]) / self.scale[a]).round();
                        out.extend_from_slice(
                            &(v.clamp(i32::MIN as f64, i32::MAX as f64) as i32).to_le_bytes(),
                        );
                    }
                    let intensity = intensity.map_or(0, |v| v[i].clamp(0, 65535) as u16);
                    out.extend_from_slice(&intensity.to_le_bytes());
                    out.extend_from_slice(&[0x11, 0]); // return 1 of 1
                    out.push(class.map_or(0, |v| v[i].clamp(0, 255) as u8));
                    out.extend_from_slice(&[0; 13]); // user data, angle, source, GPS time
                    if let Some(rgb) = &cloud.rgb {
                        for c in rgb[i] {
                            out.extend_from_slice(&c.to_le_bytes());
                        }
                    }
                    for a in &extras {
                        match &a.values {
                            Values::Int(v) => out.extend_from_slice(&v[i].to_le_bytes()),
                            Values::Float(v) => out.extend_from_slice(&v[i].to_le_bytes()),
                        }
                    }
                }
                let n = (end - *next) as u64;
                *next = end;
                Ok(n)
            }
        }
    }

    /// Back to the first point.
    pub(super) fn rewind(&mut self) -> Result<(), PointsError> {
        match &mut self.kind {
            Kind::Las { records, .. } => records.rewind(),
            Kind::Cloud { next, .. } => {
                *next = 0;
                Ok(())
            }
        }
    }
}

/// A loaded cloud's attributes written as extra bytes: all but integer intensity and
/// classification (LAS fields of their own).
fn extra_attributes(cloud: &PointCloud) -> Vec<&crate::points::Attribute> {
    cloud
        .attributes
        .iter()
        .filter(|a| {
            !(matches!(a.name.as_str(), "intensity" | "classification")
                && matches!(a.values, Values::Int(_)))
        })
        .collect()
}

/// The name an attribute takes in the Extra Bytes VLR: `_extra` after a name of a LAS
/// dimension (laspy refuses an extra dimension named like a standard one).
fn extra_name(name: &str) -> String {
    const LAS: [&str; 24] = [
        "x",
        "y",
        "z",
        "intensity",
        "return_number",
        "number_of_returns",
        "synthetic",
        "key_point",
        "withheld",
        "overlap",
        "scanner_channel",
        "scan_direction_flag",
        "edge_of_flight_line",
        "classification",
        "user_data",
        "scan_angle",
        "point_source_id",
        "gps_time",
        "red",
        "green",
        "blue",
        "nir",
        "classification_flags",
        "bit_fields",
    ];
    if LAS.contains(&name.to_lowercase().as_str()) {
        format!("{name}_extra")
    } else {
        name.to_string()
    }
}

/// Bytes of the record the Extra Bytes descriptors in `data` (192 bytes each) describe.
fn described_bytes(path: &Path, data: &[u8]) -> Result<usize, PointsError> {
    if !data.len().is_multiple_of(192) {
        return Err(PointsError::unsupported(
            path,
            format!(
                "the Extra Bytes record holds {} bytes, not a multiple of its 192-byte descriptors",
                data.len()
            ),
        ));
    }
    let size = |t: u8| -> Option<usize> {
        Some(match t {
            1 | 2 => 1,
            3 | 4 => 2,
            5 | 6 | 9 => 4,
            7 | 8 | 10 => 8,
            _ => return None,
        })
    };
    data.chunks_exact(192)
        .enumerate()
        .map(|(k, d)| match d[2] {
            0 => Ok(d[3] as usize),
            t @ 1..=10 => Ok(size(t).unwrap_or(0)),
            t @ 11..=20 => Ok(2 * size(t - 10).unwrap_or(0)),
            t @ 21..=30 => Ok(3 * size(t - 20).unwrap_or(0)),
            t => Err(PointsError::unsupported(
                path,
                format!("extra bytes descriptor {k}: data type {t} is not LAS 1.4's"),
            )),
        })
        .sum()
}
