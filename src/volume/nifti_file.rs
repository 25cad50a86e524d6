//! NIfTI-1 (`.nii`, `.nii.gz`) through the `nifti` crate: the first 3D volume, scaled by
//! `scl_slope` / `scl_inter`, spacing from `pixdim`. Errors name the file, and a truncated
//! file says how many voxel bytes arrived of how many the header promised.

use std::path::Path;

use nifti::{NiftiError, NiftiObject, NiftiType, NiftiVolume, ReaderOptions};

use super::{SampleType, Volume, VolumeError};

/// NIfTI-1's header size; voxel data begins at `vox_offset` (usually 352).
const HEADER_BYTES: u64 = 348;

fn error(path: &Path, e: NiftiError, vox_offset: u64) -> VolumeError {
    match e {
        NiftiError::Io(source)
            if source.kind() == std::io::ErrorKind::UnexpectedEof
                || source.to_string().contains("deflate") =>
        {
            let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            VolumeError::format(
                path,
                size,
                format!(
                    "the file ends early ({}): it is truncated; a NIfTI-1 file holds a 348-byte header, then dim x datatype bytes of voxels",
                    source.kind()
                ),
            )
        }
        NiftiError::Io(source) => VolumeError::Io {
            path: path.into(),
            source,
        },
        NiftiError::IncompatibleLength(got, expected) => VolumeError::format(
            path,
            vox_offset + got as u64,
            format!(
                "voxel data ends after {got} of the {expected} bytes the header's dim and datatype promise (data starts at byte {vox_offset} of the {}decompressed stream): the file is truncated",
                if path.to_string_lossy().ends_with(".gz") { "" } else { "un" }
            ),
        ),
        other => VolumeError::format(path, 0, format!("not a readable NIfTI-1 header: {other}")),
    }
}

/// Read the first 3D volume of a NIfTI-1 file.
pub fn read(path: &Path) -> Result<Volume, VolumeError> {
    let object = ReaderOptions::new()
        .read_file(path)
        .map_err(|e| error(path, e, 352))?;
    let header = object.header().clone();
    let vox_offset = header.vox_offset.max(HEADER_BYTES as f32) as u64;
    let volume = object.into_volume();
    let dim = volume.dim().to_vec();
    if dim.len() < 3 && dim.iter().product::<u16>() == 0 {
        return Err(VolumeError::format(
            path,
            40,
            format!("dim {dim:?}: no voxels"),
        ));
    }
    let dims = [
        dim.first().copied().unwrap_or(1) as usize,
        dim.get(1).copied().unwrap_or(1) as usize,
        dim.get(2).copied().unwrap_or(1) as usize,
    ];
    let count = dims[0] * dims[1] * dims[2];
    let sample = match volume.data_type() {
        NiftiType::Uint8 => SampleType::U8,
        NiftiType::Int8 => SampleType::I8,
        NiftiType::Int16 => SampleType::I16,
        NiftiType::Uint16 => SampleType::U16,
        NiftiType::Int32 => SampleType::I32,
        NiftiType::Uint32 => SampleType::U32,
        NiftiType::Float32 => SampleType::F32,
        NiftiType::Float64 => SampleType::F64,
        other => {
            return Err(VolumeError::Unsupported {
                path: path.into(),
                message: format!(
                    "datatype {other:?} (header bytes 70-71) is not a scalar type arbvis reads"
                ),
            })
        }
    };
    let big = header.endianness == nifti::Endianness::Big;
    let raw: Vec<f32> = volume
        .raw_data()
        .chunks_exact(sample.bytes())
        .take(count)
        .map(|b| sample.decode(b, big))
        .collect();
    if raw.len() < count {
        return Err(VolumeError::format(
            path,
            vox_offset + (raw.len() * sample.bytes()) as u64,
            format!("{} voxels of data where dim promises {count}", raw.len()),
        ));
    }
    let (slope, inter) = (header.scl_slope, header.scl_inter);
    let scale = slope != 0.0 && slope.is_finite() && !(slope == 1.0 && inter == 0.0);
    let values: Vec<f32> = raw
        .into_iter()
        .take(count)
        .map(|v| if scale { v * slope + inter } else { v })
        .collect();
    let spacing = [1, 2, 3].map(|a| {
        let p = header.pixdim[a] as f64;
        if p.is_finite() && p > 0.0 {
            p
        } else {
            1.0
        }
    });
    Volume::new(dims, spacing, values).map_err(|m| VolumeError::format(path, 40, m))
}

/// Header facts for `arbvis inspect`.
pub fn describe_header(path: &Path) -> Result<String, VolumeError> {
    let object = ReaderOptions::new()
        .read_file(path)
        .map_err(|e| error(path, e, 352))?;
    let h = object.header();
    Ok(format!(
        "sample type: {:?} ({} bits)\nendianness: {:?}\ndim: {:?}\npixdim: {:?}\nscaling: slope {} intercept {}\n",
        h.data_type().map_err(|e| error(path, e, 0))?,
        h.bitpix,
        h.endianness,
        &h.dim[..=(h.dim[0].min(7) as usize)],
        &h.pixdim[1..4],
        h.scl_slope,
        h.scl_inter
    ))
}
