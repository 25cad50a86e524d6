//! The sources `arbvis convert` reads, a column at a time (every sample of a rectangle of
//! crosslines and inlines), so that no more than one column per worker is ever held:
//! SEG-Y through [`SegyStream`], uncompressed NIfTI-1 and raw files by offset. A
//! gzip-compressed NIfTI file cannot be read out of order, so it is read whole (held to
//! the memory budget; decompress a large one first).

use std::collections::BTreeMap;
use std::fs::File;
use std::ops::Range;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::meta::SourceMeta;
use super::StoreError;
use crate::volume::raw::RawSpec;
use crate::volume::segy::SegyStream;
use crate::volume::{nifti_file, Endian, SampleType, Volume, VolumeError};

/// A survey read in columns.
#[derive(Debug)]
pub enum Input {
    /// SEG-Y, trace by trace.
    Segy(Box<SegyStream>, SourceMeta),
    /// Samples at fixed offsets of a file (raw, uncompressed NIfTI).
    Flat(Flat),
    /// A volume held whole (gzip NIfTI).
    Memory(Volume, SourceMeta),
    /// An MDIO dataset's default variable, read from its chunks.
    Mdio(Box<super::mdio::Mdio>, Box<super::meta::StoreMeta>),
}

/// A file of samples in i, j, k order from a byte offset.
#[derive(Debug)]
pub struct Flat {
    path: PathBuf,
    file: File,
    offset: u64,
    sample: SampleType,
    big: bool,
    dims: [usize; 3],
    spacing: [f64; 3],
    scaling: Option<(f32, f32)>,
    meta: SourceMeta,
}

fn meta(path: &Path, kind: &str, bytes: u64, facts: Vec<(String, String)>) -> SourceMeta {
    SourceMeta {
        path: path.display().to_string(),
        kind: kind.into(),
        bytes,
        facts: facts.into_iter().collect::<BTreeMap<_, _>>(),
        inlines: None,
        crosslines: None,
        interval_us: None,
        samples: None,
    }
}

impl Input {
    /// Open `path`: raw when `raw` describes it, NIfTI by extension (`.nii`, `.nii.gz`),
    /// else SEG-Y.
    pub fn open(
        path: &Path,
        raw: Option<&RawSpec>,
        segy_keys: crate::volume::segy::KeyBytes,
    ) -> Result<Input, StoreError> {
        let path = &crate::fetch::local_or_url(path);
        let folder = crate::fetch::probe_folder(path)
            .map_err(|e| StoreError::invalid(path, e.to_string()))?;
        if folder && raw.is_none() {
            let Some(flavour) = super::mdio::flavour(path)? else {
                if !crate::fetch::exists(&path.join("zarr.json")) {
                    return Err(StoreError::invalid(path, super::check::not_v3(path)));
                }
                return Err(StoreError::invalid(
                    path,
                    "a folder that is not an MDIO dataset: convert reads SEG-Y, NIfTI, raw files and MDIO datasets",
                ));
            };
            let (meta, mdio) = super::mdio::open_flavour(path, &flavour)?;
            return Ok(Input::Mdio(Box::new(mdio), Box::new(meta)));
        }
        let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        if let Some(spec) = raw {
            spec.validate()
                .map_err(|e| VolumeError::Invalid(format!("{}: {}", path.display(), e.message)))?;
            let (file, flen) =
                arbvis_core::input::open_regular(path).map_err(|e| VolumeError::io(path, e))?;
            let need = spec.dims.iter().map(|&d| d as u64).product::<u64>()
                * spec.sample.bytes() as u64
                + spec.offset;
            if flen != need {
                return Err(VolumeError::format(
                    path,
                    flen.min(need),
                    format!("the file has {flen} bytes but the raw description needs {need}"),
                )
                .into());
            }
            let facts = vec![
                ("sample type".to_string(), spec.sample.name().to_string()),
                ("offset".to_string(), spec.offset.to_string()),
            ];
            return Ok(Input::Flat(Flat {
                path: path.into(),
                file,
                offset: spec.offset,
                sample: spec.sample,
                big: spec.endian == Endian::Big,
                dims: spec.dims,
                spacing: spec.spacing,
                scaling: None,
                meta: meta(path, "raw", flen, facts),
            }));
        }
        let name = path.to_string_lossy().to_lowercase();
        if name.ends_with(".nii") || name.ends_with(".nii.gz") {
            let header = nifti_file::read_header(path)?;
            let facts: Vec<(String, String)> = header
                .describe()
                .lines()
                .filter_map(|l| l.split_once(": "))
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect();
            let (file, flen) =
                arbvis_core::input::open_regular(path).map_err(|e| VolumeError::io(path, e))?;
            let mut magic = [0u8; 2];
            let gzip = file.read_exact_at(&mut magic, 0).is_ok() && magic == [0x1f, 0x8b];
            if gzip {
                let bytes = header.count().saturating_mul(4);
                arbvis_core::budget::check(
                    format!(
                        "{} (gzip NIfTI is read whole; decompress it to convert in columns)",
                        path.display()
                    ),
                    bytes,
                )
                .map_err(|e| StoreError::Budget(e.to_string()))?;
                let limits = crate::volume::Limits {
                    max_side: usize::MAX,
                    max_voxels: u64::MAX,
                };
                let v = nifti_file::read(path, &limits)?;
                return Ok(Input::Memory(v, meta(path, "NIfTI-1 (gzip)", flen, facts)));
            }
            if flen < header.vox_offset + header.data_bytes() {
                return Err(VolumeError::format(
                    path,
                    flen,
                    format!(
                        "the file ends before the {} bytes of voxel data that dim and datatype declare from byte {}: it is truncated",
                        header.data_bytes(),
                        header.vox_offset
                    ),
                )
                .into());
            }
            return Ok(Input::Flat(Flat {
                path: path.into(),
                file,
                offset: header.vox_offset,
                sample: header.sample,
                big: header.big_endian,
                dims: header.dims,
                spacing: header.spacing,
                scaling: header.scaling,
                meta: meta(path, "NIfTI-1", flen, facts),
            }));
        }
        let s = SegyStream::open_with(path, segy_keys)?;
        let mut m = meta(path, "SEG-Y", len, s.describe());
        let step = |l: &crate::volume::segy::Lines| [l.first as i64, l.step];
        m.inlines = Some(step(&s.grid.inlines));
        m.crosslines = Some(step(&s.grid.crosslines));
        m.interval_us = Some(s.interval_us);
        Ok(Input::Segy(Box::new(s), m))
    }

    /// Whether the input gives map coordinates per trace (SEG-Y's CDP x and y, an MDIO
    /// dataset's `cdp_x` and `cdp_y`).
    pub fn has_coordinates(&self) -> bool {
        match self {
            Input::Segy(..) => true,
            Input::Mdio(m, _) => m.cdp.is_some(),
            _ => false,
        }
    }

    /// Voxels along i, j, k.
    pub fn dims(&self) -> [usize; 3] {
        match self {
            Input::Segy(s, _) => s.dims(),
            Input::Flat(f) => f.dims,
            Input::Memory(v, _) => v.dims,
            Input::Mdio(_, m) => m.dims,
        }
    }

    /// Voxel size (SEG-Y: the survey's proportions, `volume::segy::geometry`).
    pub fn spacing(&self) -> [f64; 3] {
        match self {
            Input::Segy(s, _) => s.geometry.spacing,
            Input::Flat(f) => f.spacing,
            Input::Memory(v, _) => v.spacing,
            Input::Mdio(_, m) => m.spacing,
        }
    }

    /// The source's description for the store.
    pub fn source_meta(&self) -> SourceMeta {
        match self {
            Input::Segy(_, m) => m.clone(),
            Input::Flat(f) => f.meta.clone(),
            Input::Memory(_, m) => m.clone(),
            Input::Mdio(_, m) => m.source.clone(),
        }
    }

    /// Bytes of input a column of `traces` traces stands for (progress).
    pub fn bytes_per_trace(&self) -> u64 {
        match self {
            Input::Segy(s, _) => s.trace_bytes() as u64,
            Input::Flat(f) => (f.dims[0] * f.sample.bytes()) as u64,
            Input::Memory(v, _) => (v.dims[0] * 4) as u64,
            Input::Mdio(_, m) => (m.dims[0] * 4) as u64,
        }
    }

    /// Whether each trace of crosslines `j` and inlines `k` is live (crossline fastest),
    /// where the input knows it: a SEG-Y survey's grid (a position without a trace is
    /// dead), an MDIO dataset's `trace_mask`. `None` for the others, whose traces are
    /// live unless every sample is NaN.
    pub fn live(&self, j: Range<usize>, k: Range<usize>) -> Option<Vec<bool>> {
        let cells = k.flat_map(|kk| j.clone().map(move |jj| (kk, jj)));
        match self {
            Input::Segy(s, _) => Some(
                cells
                    .map(|(kk, jj)| s.grid.trace(kk, jj).is_some())
                    .collect(),
            ),
            Input::Mdio(m, meta) => m
                .live
                .as_ref()
                .map(|l| cells.map(|(kk, jj)| l[kk * meta.dims[1] + jj]).collect()),
            Input::Flat(_) | Input::Memory(..) => None,
        }
    }

    /// Every sample of crosslines `j` and inlines `k`, sample fastest, into `out`; for
    /// SEG-Y also each trace's CDP x and y into `coordinates` (crossline fastest).
    pub fn read_column(
        &self,
        j: Range<usize>,
        k: Range<usize>,
        out: &mut [f32],
        coordinates: Option<&mut [[f64; 2]]>,
    ) -> Result<(), StoreError> {
        match self {
            Input::Segy(s, _) => Ok(s.read_column_with_coordinates(j, k, out, coordinates)?),
            Input::Mdio(m, meta) => {
                if let (Some(cdp), Some(c)) = (&m.cdp, coordinates) {
                    let nj = meta.dims[1];
                    let traces = k
                        .clone()
                        .flat_map(|kk| j.clone().map(move |jj| kk * nj + jj));
                    for (t, at) in traces.zip(c.iter_mut()) {
                        *at = [cdp[0][t], cdp[1][t]];
                    }
                }
                m.column(meta.dims, j, k, out)
                    .map_err(|f| f.into_error(&m.variable()))
            }
            Input::Flat(f) => f.read_column(j, k, out),
            Input::Memory(v, _) => {
                let ni = v.dims[0];
                let mut at = 0;
                for kk in k {
                    let start = v.index(0, j.start, kk);
                    let n = ni * j.len();
                    out[at..at + n].copy_from_slice(&v.values[start..start + n]);
                    at += n;
                }
                Ok(())
            }
        }
    }
}

impl Flat {
    fn read_column(
        &self,
        j: Range<usize>,
        k: Range<usize>,
        out: &mut [f32],
    ) -> Result<(), StoreError> {
        let [ni, nj, _] = self.dims;
        let width = self.sample.bytes();
        let n = ni * j.len();
        let mut buf = vec![0u8; n * width];
        let mut at = 0;
        for kk in k {
            let first = (kk * nj + j.start) * ni;
            let byte = self.offset + (first * width) as u64;
            self.file
                .read_exact_at(&mut buf, byte)
                .map_err(|e| StoreError::from(VolumeError::io(&self.path, e)))?;
            for (d, b) in out[at..at + n].iter_mut().zip(buf.chunks_exact(width)) {
                let v = self.sample.decode(b, self.big);
                *d = match self.scaling {
                    Some((s, i)) => v * s + i,
                    None => v,
                };
            }
            at += n;
        }
        Ok(())
    }
}
