//! NIfTI-1 single files (`.nii`, and gzip-compressed `.nii.gz`, recognised by content):
//! the first 3D volume, scaled by `scl_slope` / `scl_inter`, spacing from `pixdim`.
//!
//! Read by hand rather than through the `nifti` crate: the format is one fixed 348-byte
//! header, and the crate (0.18) loops when an extension declares `esize = 0`, inflates a
//! gzip stream without a bound, holds the volume several times over, and reports every
//! header problem "at byte 0". Here the header is checked field by field (each error names
//! its byte), extensions are skipped by jumping to `vox_offset`, and exactly the bytes the
//! header declares are decoded, streamed in chunks straight into the one f32 copy (or, for
//! `inspect`, into running statistics without holding the volume at all).
//!
//! Decisions: `scl_slope` of 0 or NaN means "no scaling" and a NaN `scl_inter` means 0
//! (as nibabel reads them: it writes NaN for unscaled data); an infinite one is an error.
//! `bitpix` must agree with `datatype`. Header/image pairs (`ni1`, `.hdr` + `.img`) and
//! NIfTI-2 are refused by name.

use std::io::{BufReader, Read};
use std::path::Path;

use super::{Limits, SampleType, Stats, Volume, VolumeError};

/// NIfTI-1's header size.
const HEADER_BYTES: usize = 348;
/// Bytes decoded per step of the stream.
const CHUNK: usize = 1 << 20;

/// What the header says.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Multi-byte fields are big-endian.
    pub big_endian: bool,
    /// `dim[0..8]` as stored.
    pub dim: [i16; 8],
    /// The first 3D volume's size (dims past `dim[0]` are 1).
    pub dims: [usize; 3],
    /// Sample type from `datatype`.
    pub sample: SampleType,
    /// `datatype` code.
    pub datatype: i16,
    /// Voxel size along i, j, k (`pixdim[1..4]`, 1 where not positive and finite).
    pub spacing: [f64; 3],
    /// Byte where voxel data starts.
    pub vox_offset: u64,
    /// Scaling applied to every sample: `v * slope + inter` (None: no scaling).
    pub scaling: Option<(f32, f32)>,
}

impl Header {
    /// Samples of the first 3D volume.
    pub fn count(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    /// Bytes of the first 3D volume.
    pub fn data_bytes(&self) -> u64 {
        self.count() * self.sample.bytes() as u64
    }

    /// Header facts for `arbvis inspect`, one per line.
    pub fn describe(&self) -> String {
        let n = (self.dim[0].clamp(0, 7) as usize) + 1;
        format!(
            "sample type: {} (datatype {})\nendianness: {}\ndim: {:?}\nvoxel data at byte {}\nscaling: {}\n",
            self.sample.name(),
            self.datatype,
            if self.big_endian { "big" } else { "little" },
            &self.dim[..n],
            self.vox_offset,
            match self.scaling {
                Some((s, i)) => format!("value * {s} + {i}"),
                None => "none".into(),
            }
        )
    }
}

fn field_i16(h: &[u8], at: usize, big: bool) -> i16 {
    let a = [h[at], h[at + 1]];
    if big {
        i16::from_be_bytes(a)
    } else {
        i16::from_le_bytes(a)
    }
}

fn field_f32(h: &[u8], at: usize, big: bool) -> f32 {
    let a = [h[at], h[at + 1], h[at + 2], h[at + 3]];
    if big {
        f32::from_be_bytes(a)
    } else {
        f32::from_le_bytes(a)
    }
}

/// Check a 348-byte header field by field.
pub fn parse_header(path: &Path, h: &[u8]) -> Result<Header, VolumeError> {
    let err = |at: usize, m: String| VolumeError::format(path, at as u64, m);
    if h.len() < HEADER_BYTES {
        return Err(err(
            h.len(),
            format!(
                "the file ends after {} bytes, inside the 348-byte NIfTI-1 header: it is truncated",
                h.len()
            ),
        ));
    }
    let size = [h[0], h[1], h[2], h[3]];
    let big = match (i32::from_le_bytes(size), i32::from_be_bytes(size)) {
        (348, _) => false,
        (_, 348) => true,
        (540, _) | (_, 540) => {
            return Err(VolumeError::Unsupported {
                path: path.into(),
                message: "a NIfTI-2 file (sizeof_hdr 540); arbvis reads NIfTI-1".into(),
            })
        }
        (n, _) => {
            return Err(err(
                0,
                format!(
                    "sizeof_hdr is {n}; a NIfTI-1 header starts with 348 (in either byte order)"
                ),
            ))
        }
    };
    match &h[344..348] {
        b"n+1\0" => {}
        b"ni1\0" => {
            return Err(VolumeError::Unsupported {
                path: path.into(),
                message: "a NIfTI-1 header/image pair (magic \"ni1\", .hdr + .img); arbvis reads single .nii files".into(),
            })
        }
        other => {
            return Err(err(
                344,
                format!("magic {other:?}: a single-file NIfTI-1 says \"n+1\\0\""),
            ))
        }
    }
    let dim: [i16; 8] = std::array::from_fn(|i| field_i16(h, 40 + 2 * i, big));
    if !(1..=7).contains(&dim[0]) {
        return Err(err(40, format!("dim[0] = {}: must be 1..=7", dim[0])));
    }
    if let Some(i) = (1..=dim[0] as usize).find(|&i| dim[i] < 1) {
        return Err(err(
            40 + 2 * i,
            format!(
                "dim[{i}] = {}: each used dimension must be at least 1",
                dim[i]
            ),
        ));
    }
    let dims: [usize; 3] = std::array::from_fn(|a| {
        if a < dim[0] as usize {
            dim[a + 1] as usize
        } else {
            1
        }
    });
    let datatype = field_i16(h, 70, big);
    let sample = match datatype {
        2 => SampleType::U8,
        4 => SampleType::I16,
        8 => SampleType::I32,
        16 => SampleType::F32,
        64 => SampleType::F64,
        256 => SampleType::I8,
        512 => SampleType::U16,
        768 => SampleType::U32,
        other => {
            let name = match other {
                1 => "binary",
                32 => "complex64",
                128 => "RGB24",
                1024 => "int64",
                1280 => "uint64",
                1536 => "float128",
                1792 => "complex128",
                2048 => "complex256",
                2304 => "RGBA32",
                _ => "unknown",
            };
            return Err(VolumeError::Unsupported {
                path: path.into(),
                message: format!(
                    "datatype {other} ({name}, header byte 70): arbvis reads uint8, int8, int16, uint16, int32, uint32, float32 and float64"
                ),
            });
        }
    };
    let bitpix = field_i16(h, 72, big);
    if bitpix as usize != sample.bytes() * 8 {
        return Err(err(
            72,
            format!(
                "bitpix = {bitpix} but datatype {datatype} ({}) has {} bits",
                sample.name(),
                sample.bytes() * 8
            ),
        ));
    }
    let spacing = [1, 2, 3].map(|a| {
        let p = field_f32(h, 76 + 4 * a, big) as f64;
        if p.is_finite() && p > 0.0 {
            p
        } else {
            1.0
        }
    });
    let offset = field_f32(h, 108, big);
    if !(offset.is_finite() && offset.fract() == 0.0 && (352.0..4.0e9).contains(&offset)) {
        return Err(err(
            108,
            format!("vox_offset = {offset}: a whole number of bytes from 352 (after the header and its extension flag) was expected"),
        ));
    }
    let (slope, inter) = (field_f32(h, 112, big), field_f32(h, 116, big));
    if slope.is_infinite() {
        return Err(err(
            112,
            format!("scl_slope = {slope}: must be finite (0 or NaN: no scaling)"),
        ));
    }
    if inter.is_infinite() {
        return Err(err(116, format!("scl_inter = {inter}: must be finite")));
    }
    let inter = if inter.is_nan() { 0.0 } else { inter };
    let scaling = (slope != 0.0 && !slope.is_nan() && !(slope == 1.0 && inter == 0.0))
        .then_some((slope, inter));
    Ok(Header {
        big_endian: big,
        dim,
        dims,
        sample,
        datatype,
        spacing,
        vox_offset: offset as u64,
        scaling,
    })
}

/// Open the voxel stream: the file's bytes, inflated when they start with gzip's magic.
fn stream<'a>(bytes: impl Read + 'a, gzip: bool) -> Box<dyn Read + 'a> {
    if gzip {
        Box::new(flate2::read::MultiGzDecoder::new(bytes))
    } else {
        Box::new(bytes)
    }
}

/// Read the header from the stream, skip to `vox_offset`, and hand the first volume's
/// samples (scaled) to `each`, chunk by chunk. `limits` is checked before any voxel is
/// read; a stream that ends early is an error saying how much arrived.
fn decode(
    path: &Path,
    mut input: Box<dyn Read + '_>,
    gzip: bool,
    limits: &Limits,
    mut each: impl FnMut(&Header, &[f32]) -> Result<(), VolumeError>,
) -> Result<Header, VolumeError> {
    let stream_name = if gzip { "decompressed stream" } else { "file" };
    let io = |e: std::io::Error, at: u64| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof || gzip {
            VolumeError::format(
                path,
                at,
                format!("the {stream_name} ends or breaks off here ({e}): the file is truncated or corrupt"),
            )
        } else {
            VolumeError::io(path, e)
        }
    };
    let mut head = Vec::with_capacity(HEADER_BYTES);
    (&mut input)
        .take(HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| io(e, 0))?;
    let header = parse_header(path, &head)?;
    limits.check(header.dims, &path.display().to_string())?;
    let skip = header.vox_offset - HEADER_BYTES as u64;
    let skipped = std::io::copy(&mut (&mut input).take(skip), &mut std::io::sink())
        .map_err(|e| io(e, HEADER_BYTES as u64))?;
    if skipped < skip {
        return Err(VolumeError::format(
            path,
            HEADER_BYTES as u64 + skipped,
            format!(
                "the {stream_name} ends before vox_offset {} (header byte 108): the file is truncated or vox_offset is wrong",
                header.vox_offset
            ),
        ));
    }
    let width = header.sample.bytes();
    let total = header.data_bytes();
    let mut done = 0u64;
    let mut chunk = vec![0u8; CHUNK - CHUNK % width];
    let mut values = Vec::with_capacity(chunk.len() / width);
    while done < total {
        let want = ((total - done) as usize).min(chunk.len());
        let got = read_full(&mut input, &mut chunk[..want])
            .map_err(|e| io(e, header.vox_offset + done))?;
        if got < want {
            return Err(VolumeError::format(
                path,
                header.vox_offset + done + got as u64,
                format!(
                    "voxel data ends after {} of the {total} bytes that dim and datatype declare (data starts at byte {} of the {stream_name}): the file is truncated",
                    done + got as u64,
                    header.vox_offset
                ),
            ));
        }
        values.clear();
        values.extend(chunk[..want].chunks_exact(width).map(|b| {
            let v = header.sample.decode(b, header.big_endian);
            match header.scaling {
                Some((s, i)) => v * s + i,
                None => v,
            }
        }));
        each(&header, &values)?;
        done += want as u64;
    }
    Ok(header)
}

/// Fill `buf` as far as the stream allows; returns the bytes read.
fn read_full(input: &mut dyn Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match input.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Parse NIfTI-1 bytes (plain or gzip) in memory; `path` names them in errors.
pub fn parse(path: &Path, bytes: &[u8], limits: &Limits) -> Result<Volume, VolumeError> {
    let gzip = bytes.starts_with(&[0x1f, 0x8b]);
    read_from(path, stream(bytes, gzip), gzip, limits)
}

fn read_from(
    path: &Path,
    input: Box<dyn Read + '_>,
    gzip: bool,
    limits: &Limits,
) -> Result<Volume, VolumeError> {
    let mut values: Vec<f32> = Vec::new();
    let header = decode(path, input, gzip, limits, |header, chunk| {
        if values.capacity() == 0 {
            // Sized once, from dims the limits accepted and data that has begun to arrive.
            let count = usize::try_from(header.count()).unwrap_or(usize::MAX);
            values.try_reserve_exact(count).map_err(|_| {
                VolumeError::Invalid(format!(
                    "{}: cannot allocate {count} samples",
                    path.display()
                ))
            })?;
        }
        values.extend_from_slice(chunk);
        Ok(())
    })?;
    Volume::new(header.dims, header.spacing, values)
        .map_err(|m| VolumeError::format(path, 40, m.to_string()))
}

fn open(path: &Path) -> Result<(Box<dyn Read>, bool), VolumeError> {
    let (file, _) = arbvis_core::input::open_regular(path).map_err(|e| VolumeError::io(path, e))?;
    let mut reader = BufReader::new(file);
    let mut magic = [0u8; 2];
    let n = read_full(&mut reader, &mut magic).map_err(|e| VolumeError::io(path, e))?;
    let gzip = n == 2 && magic == [0x1f, 0x8b];
    let input = std::io::Cursor::new(magic[..n].to_vec()).chain(reader);
    Ok((stream(input, gzip), gzip))
}

/// Read the first 3D volume of a NIfTI-1 file; its size is checked against `limits`
/// before any voxel is read.
pub fn read(path: &Path, limits: &Limits) -> Result<Volume, VolumeError> {
    let (input, gzip) = open(path)?;
    read_from(path, input, gzip, limits)
}

/// The header alone: its first 348 bytes (inflated when gzip), no voxel read (the viewer
/// labels its axes in millimetres from it).
pub fn read_header(path: &Path) -> Result<Header, VolumeError> {
    let (mut input, _) = open(path)?;
    let mut h = vec![0u8; HEADER_BYTES];
    let n = read_full(&mut input, &mut h).map_err(|e| VolumeError::io(path, e))?;
    parse_header(path, &h[..n])
}

/// `arbvis inspect`: header facts and value statistics, streamed (the volume is never
/// held, so a small `.nii.gz` of a huge volume costs one chunk of memory).
pub fn inspect(path: &Path) -> Result<String, VolumeError> {
    let (input, gzip) = open(path)?;
    let mut stats = Stats::accumulator();
    let inspect_limits = Limits {
        max_side: i16::MAX as usize,
        max_voxels: u64::MAX,
    };
    let header = decode(path, input, gzip, &inspect_limits, |_, chunk| {
        chunk.iter().for_each(|&v| stats.add(v));
        Ok(())
    })?;
    let [ni, nj, nk] = header.dims;
    Ok(format!(
        "format: NIfTI-1{}\n{}dimensions (i, j, k): {ni} x {nj} x {nk} = {} samples\nspacing: {} x {} x {}\n{}",
        if gzip { " (gzip)" } else { "" },
        header.describe(),
        header.count(),
        header.spacing[0],
        header.spacing[1],
        header.spacing[2],
        stats.finish().describe()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little-endian NIfTI-1 file: header, 4-byte extension flag, then `data`.
    pub(crate) fn file(dims: [i16; 3], datatype: i16, bitpix: i16, data: &[u8]) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        h[0..4].copy_from_slice(&348i32.to_le_bytes());
        let dim = [3, dims[0], dims[1], dims[2], 1, 1, 1, 1];
        for (i, d) in dim.iter().enumerate() {
            h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
        }
        h[70..72].copy_from_slice(&datatype.to_le_bytes());
        h[72..74].copy_from_slice(&bitpix.to_le_bytes());
        for a in 0..4 {
            h[76 + 4 * a..80 + 4 * a].copy_from_slice(&1f32.to_le_bytes());
        }
        h[108..112].copy_from_slice(&352f32.to_le_bytes());
        h[344..348].copy_from_slice(b"n+1\0");
        h.extend_from_slice(data);
        h
    }

    fn p() -> &'static Path {
        Path::new("t.nii")
    }

    #[test]
    fn reads_samples_with_scaling() {
        let mut f = file([2, 3, 1], 4, 16, &[1, 0, 2, 0, 3, 0, 4, 0, 255, 255, 6, 0]);
        f[112..116].copy_from_slice(&2f32.to_le_bytes());
        f[116..120].copy_from_slice(&0.5f32.to_le_bytes());
        let v = parse(p(), &f, &Limits::default()).unwrap();
        assert_eq!(v.dims, [2, 3, 1]);
        assert_eq!(v.values, vec![2.5, 4.5, 6.5, 8.5, -1.5, 12.5]);
        // NaN slope: no scaling (nibabel's way of writing unscaled data).
        f[112..116].copy_from_slice(&f32::NAN.to_le_bytes());
        let v = parse(p(), &f, &Limits::default()).unwrap();
        assert_eq!(v.values[0], 1.0);
    }

    #[test]
    fn each_bad_field_names_its_byte() {
        let good = file([2, 2, 2], 2, 8, &[7; 8]);
        let cases: Vec<(usize, Vec<u8>, &str)> = vec![
            (
                0,
                347i32.to_le_bytes().to_vec(),
                "at byte 0: sizeof_hdr is 347",
            ),
            (344, b"xyz\0".to_vec(), "at byte 344"),
            (40, 0i16.to_le_bytes().to_vec(), "at byte 40: dim[0] = 0"),
            (
                44,
                (-3i16).to_le_bytes().to_vec(),
                "at byte 44: dim[2] = -3",
            ),
            (72, 16i16.to_le_bytes().to_vec(), "at byte 72: bitpix = 16"),
            (
                108,
                1e30f32.to_le_bytes().to_vec(),
                "at byte 108: vox_offset",
            ),
            (108, 352.5f32.to_le_bytes().to_vec(), "at byte 108"),
            (
                112,
                f32::INFINITY.to_le_bytes().to_vec(),
                "at byte 112: scl_slope",
            ),
            (
                116,
                f32::NEG_INFINITY.to_le_bytes().to_vec(),
                "at byte 116: scl_inter",
            ),
        ];
        for (at, patch, expect) in cases {
            let mut f = good.clone();
            f[at..at + patch.len()].copy_from_slice(&patch);
            let e = parse(p(), &f, &Limits::default()).unwrap_err().to_string();
            assert!(e.contains(expect), "patch at {at}: {e}");
        }
        let mut f = good.clone();
        f[70..72].copy_from_slice(&128i16.to_le_bytes());
        let e = parse(p(), &f, &Limits::default()).unwrap_err().to_string();
        assert!(e.contains("RGB24"), "{e}");
    }

    #[test]
    fn offsets_and_sizes_beyond_the_data_are_errors() {
        // vox_offset past the end of the file.
        let mut f = file([2, 2, 2], 2, 8, &[7; 8]);
        f[108..112].copy_from_slice(&4096f32.to_le_bytes());
        let e = parse(p(), &f, &Limits::default()).unwrap_err().to_string();
        assert!(e.contains("before vox_offset 4096"), "{e}");
        // A header declaring 1024^3 voxels with 8 bytes of data: refused by the limits
        // (a GL with 512 per side) before anything is allocated, else truncated.
        let f = file([1024, 1024, 1024], 2, 8, &[7; 8]);
        let small = Limits {
            max_side: 512,
            max_voxels: 1 << 31,
        };
        let e = parse(p(), &f, &small).unwrap_err().to_string();
        assert!(e.contains("GL_MAX_3D_TEXTURE_SIZE"), "{e}");
        let e = parse(p(), &f, &Limits::default()).unwrap_err().to_string();
        assert!(e.contains("ends after 8 of the 1073741824 bytes"), "{e}");
    }

    #[test]
    fn an_extension_of_size_zero_is_skipped() {
        // The nifti crate looped on this: extension flag set, esize = 0.
        let mut f = file([2, 1, 1], 2, 8, &[0; 8]);
        f[348] = 1;
        f[108..112].copy_from_slice(&360f32.to_le_bytes());
        f.truncate(352);
        f.extend_from_slice(&[0; 8]); // esize 0, ecode 0
        f.extend_from_slice(&[5, 6]);
        assert_eq!(
            parse(p(), &f, &Limits::default()).unwrap().values,
            vec![5.0, 6.0]
        );
    }

    #[test]
    fn a_small_gzip_of_a_huge_volume_inspects_in_bounded_memory() {
        use std::io::Write;
        let dir = std::env::temp_dir().join(format!("arbvis-nifti-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("big.nii.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(&file([256, 256, 64], 2, 8, &[])).unwrap();
        let zeros = vec![0u8; 1 << 20];
        for _ in 0..4 {
            enc.write_all(&zeros).unwrap();
        }
        std::fs::write(&path, enc.finish().unwrap()).unwrap();
        let text = inspect(&path).unwrap();
        assert!(text.contains("256 x 256 x 64 = 4194304 samples"), "{text}");
        assert!(text.contains("min 0 max 0"), "{text}");
    }
}
