//! SEG-Y (rev 0/1/2) post-stack cubes: 3200-byte textual header, 400-byte binary header,
//! extended textual headers, then traces of a 240-byte header and samples.
//!
//! Sample formats: 1 IBM float, 2 int32, 3 int16, 5 IEEE float, 6 IEEE double, 8 int8,
//! 10 uint32, 11 uint16, 16 uint8. Byte order: big-endian by the standard; little-endian
//! when the rev 2 byte-order word (bytes 3297-3300) says so, or when the format code only
//! makes sense read little-endian (as segyio guesses). Geometry: inline from trace bytes
//! 189-192, crossline from 193-196, or the bytes a scene names or [`keys`] detects; every
//! (inline, crossline) pair must occur exactly once
//! on a full rectangular grid, in any order, or the file is refused as pre-stack or
//! irregular. The volume's axes are sample (i), crossline (j), inline (k).

mod gathers;
pub mod geometry;
mod grid;
pub mod keys;
pub mod lines;
mod source;
mod stream;
mod write;

use std::path::Path;

pub use gathers::{gathers, Gathers};
pub use geometry::Geometry;
pub use grid::{Prestack, ReadOptions};
pub use keys::{KeyBytes, Keys};
pub use lines::{Lines, TraceGrid};
pub use source::SegySource;
pub use stream::SegyStream;
pub use write::{write, write_prestack, TraceWriter, WriteOptions};

use super::{read_file, Volume, VolumeError};

const TEXT_HEADER: usize = 3200;
const BINARY_HEADER: usize = 400;
const TRACE_HEADER: usize = 240;

/// Sample encodings (binary header bytes 3225-3226).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleFormat {
    /// 1: 4-byte IBM hexadecimal float.
    IbmFloat,
    /// 2: 4-byte two's complement integer.
    Int32,
    /// 3: 2-byte two's complement integer.
    Int16,
    /// 5: 4-byte IEEE float.
    IeeeFloat,
    /// 6: 8-byte IEEE float (rev 2).
    IeeeDouble,
    /// 8: 1-byte two's complement integer.
    Int8,
    /// 10: 4-byte unsigned integer (rev 2).
    UInt32,
    /// 11: 2-byte unsigned integer (rev 2).
    UInt16,
    /// 16: 1-byte unsigned integer (rev 2).
    UInt8,
}

impl SampleFormat {
    /// From the binary header's code.
    pub fn from_code(code: u16) -> Option<SampleFormat> {
        Some(match code {
            1 => SampleFormat::IbmFloat,
            2 => SampleFormat::Int32,
            3 => SampleFormat::Int16,
            5 => SampleFormat::IeeeFloat,
            6 => SampleFormat::IeeeDouble,
            8 => SampleFormat::Int8,
            10 => SampleFormat::UInt32,
            11 => SampleFormat::UInt16,
            16 => SampleFormat::UInt8,
            _ => return None,
        })
    }

    /// The binary header's code.
    pub fn code(self) -> u16 {
        match self {
            SampleFormat::IbmFloat => 1,
            SampleFormat::Int32 => 2,
            SampleFormat::Int16 => 3,
            SampleFormat::IeeeFloat => 5,
            SampleFormat::IeeeDouble => 6,
            SampleFormat::Int8 => 8,
            SampleFormat::UInt32 => 10,
            SampleFormat::UInt16 => 11,
            SampleFormat::UInt8 => 16,
        }
    }

    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            SampleFormat::Int8 | SampleFormat::UInt8 => 1,
            SampleFormat::Int16 | SampleFormat::UInt16 => 2,
            SampleFormat::IeeeDouble => 8,
            _ => 4,
        }
    }

    /// Human name.
    pub fn name(self) -> &'static str {
        match self {
            SampleFormat::IbmFloat => "IBM float (1)",
            SampleFormat::Int32 => "int32 (2)",
            SampleFormat::Int16 => "int16 (3)",
            SampleFormat::IeeeFloat => "IEEE float (5)",
            SampleFormat::IeeeDouble => "IEEE double (6)",
            SampleFormat::Int8 => "int8 (8)",
            SampleFormat::UInt32 => "uint32 (10)",
            SampleFormat::UInt16 => "uint16 (11)",
            SampleFormat::UInt8 => "uint8 (16)",
        }
    }

    /// Decode one sample.
    pub fn decode(self, b: &[u8], big: bool) -> f32 {
        let u32_of = |b: &[u8]| {
            let a = [b[0], b[1], b[2], b[3]];
            if big {
                u32::from_be_bytes(a)
            } else {
                u32::from_le_bytes(a)
            }
        };
        let u16_of = |b: &[u8]| {
            let a = [b[0], b[1]];
            if big {
                u16::from_be_bytes(a)
            } else {
                u16::from_le_bytes(a)
            }
        };
        match self {
            SampleFormat::IbmFloat => ibm_to_f32(u32_of(b)),
            SampleFormat::Int32 => u32_of(b) as i32 as f32,
            SampleFormat::Int16 => u16_of(b) as i16 as f32,
            SampleFormat::IeeeFloat => f32::from_bits(u32_of(b)),
            SampleFormat::IeeeDouble => {
                let a: [u8; 8] = b[..8].try_into().expect("8 bytes");
                (if big {
                    f64::from_be_bytes(a)
                } else {
                    f64::from_le_bytes(a)
                }) as f32
            }
            SampleFormat::Int8 => b[0] as i8 as f32,
            SampleFormat::UInt32 => u32_of(b) as f32,
            SampleFormat::UInt16 => u16_of(b) as f32,
            SampleFormat::UInt8 => b[0] as f32,
        }
    }

    /// Decode a trace's samples (`out.len()` of them) from `b`: [`SampleFormat::decode`]
    /// for each, with the common formats in loops of their own (a conversion decodes
    /// every sample of a survey).
    pub fn decode_trace(self, b: &[u8], big: bool, out: &mut [f32]) {
        let w = self.bytes();
        let b = &b[..out.len() * w];
        match (self, big) {
            (SampleFormat::IeeeFloat, true) => {
                for (o, s) in out.iter_mut().zip(b.chunks_exact(4)) {
                    *o = f32::from_be_bytes([s[0], s[1], s[2], s[3]]);
                }
            }
            (SampleFormat::IeeeFloat, false) => {
                for (o, s) in out.iter_mut().zip(b.chunks_exact(4)) {
                    *o = f32::from_le_bytes([s[0], s[1], s[2], s[3]]);
                }
            }
            (SampleFormat::IbmFloat, true) => {
                for (o, s) in out.iter_mut().zip(b.chunks_exact(4)) {
                    *o = ibm_to_f32(u32::from_be_bytes([s[0], s[1], s[2], s[3]]));
                }
            }
            (SampleFormat::Int16, true) => {
                for (o, s) in out.iter_mut().zip(b.chunks_exact(2)) {
                    *o = i16::from_be_bytes([s[0], s[1]]) as f32;
                }
            }
            _ => {
                for (o, s) in out.iter_mut().zip(b.chunks_exact(w)) {
                    *o = self.decode(s, big);
                }
            }
        }
    }

    /// Encode one sample (for writing test files); integers round and saturate.
    pub fn encode(self, v: f32, big: bool) -> Vec<u8> {
        let order4 = |x: u32| {
            if big {
                x.to_be_bytes().to_vec()
            } else {
                x.to_le_bytes().to_vec()
            }
        };
        let order2 = |x: u16| {
            if big {
                x.to_be_bytes().to_vec()
            } else {
                x.to_le_bytes().to_vec()
            }
        };
        let r = v.round();
        match self {
            SampleFormat::IbmFloat => order4(f32_to_ibm(v)),
            SampleFormat::Int32 => order4(r as i32 as u32),
            SampleFormat::Int16 => order2(r as i16 as u16),
            SampleFormat::IeeeFloat => order4(v.to_bits()),
            SampleFormat::IeeeDouble => {
                let d = v as f64;
                if big {
                    d.to_be_bytes().to_vec()
                } else {
                    d.to_le_bytes().to_vec()
                }
            }
            SampleFormat::Int8 => vec![r as i8 as u8],
            SampleFormat::UInt32 => order4(r as u32),
            SampleFormat::UInt16 => order2(r as u16),
            SampleFormat::UInt8 => vec![r as u8],
        }
    }
}

/// IBM System/360 single float: sign, 7-bit base-16 exponent biased by 64, 24-bit fraction.
///
/// The value is `fraction x 2^(4 exponent - 280)`, exact in f64 (a 24-bit fraction, a
/// power of two within f64's normal range), then rounded once to f32; no branch and no
/// `powi`, so a trace decodes several samples at a time.
#[inline]
pub fn ibm_to_f32(bits: u32) -> f32 {
    let exponent = ((bits >> 24) & 0x7f) as i64;
    let fraction = (bits & 0x00ff_ffff) as f64;
    // 2^(4 exponent - 280) from its f64 bits: biased exponent 4 e - 280 + 1023 > 0.
    let scale = f64::from_bits(((4 * exponent + 743) as u64) << 52);
    let magnitude = fraction * scale;
    let signed = f64::from_bits(magnitude.to_bits() | (((bits >> 31) as u64) << 63));
    signed as f32
}

/// The IBM float nearest to `v` (truncating the fraction, as most writers do); zero for
/// NaN, saturating for out-of-range values.
pub fn f32_to_ibm(v: f32) -> u32 {
    if v == 0.0 || !v.is_finite() {
        return 0;
    }
    let sign = if v < 0.0 { 0x8000_0000 } else { 0 };
    let mut m = (v as f64).abs();
    let mut e = 64i32;
    while m >= 1.0 {
        m /= 16.0;
        e += 1;
    }
    while m < 1.0 / 16.0 {
        m *= 16.0;
        e -= 1;
    }
    if e > 127 {
        return sign | 0x7fff_ffff;
    }
    if e < 0 {
        return 0;
    }
    let fraction = ((m * 16_777_216.0) as u32).min(0x00ff_ffff);
    sign | ((e as u32) << 24) | fraction
}

/// A gridded SEG-Y cube and what its headers said.
#[derive(Debug, Clone)]
pub struct SegyCube {
    /// The samples; axes sample, crossline, inline.
    pub volume: Volume,
    /// Revision from bytes 3501-3502 (major, minor).
    pub revision: (u8, u8),
    /// Sample encoding.
    pub format: SampleFormat,
    /// Byte order of the file.
    pub big_endian: bool,
    /// Textual header encoding: true for EBCDIC.
    pub ebcdic: bool,
    /// Sample interval in microseconds.
    pub interval_us: u32,
    /// Inline numbers, ascending (the grid's lines, gaps included).
    pub inlines: Vec<i32>,
    /// Crossline numbers, ascending (the grid's lines, gaps included).
    pub crosslines: Vec<i32>,
    /// The grid: its lines and steps, and which positions hold a trace (the rest are
    /// dead, NaN in the volume).
    pub grid: TraceGrid,
    /// Number of traces.
    pub traces: usize,
    /// The distinct source-receiver offsets of the traces (trace bytes 37-40).
    pub offsets: Vec<i32>,
    /// The trace-header bytes the inline and crossline numbers were read from.
    pub keys: Keys,
    /// The survey's proportions (the volume's spacing) and where they came from.
    pub geometry: Geometry,
}

impl SegyCube {
    /// What `arbvis inspect` prints about the headers.
    pub fn describe(&self) -> String {
        let offsets = match self.offsets.as_slice() {
            [one] => format!("{one} (one value)"),
            v => {
                let even = v
                    .windows(2)
                    .all(|w| w[1] as i64 - w[0] as i64 == v[1] as i64 - v[0] as i64);
                let step = if even {
                    format!("step {}", v[1] as i64 - v[0] as i64)
                } else {
                    "uneven steps".to_string()
                };
                format!("{}..={} ({} values, {step})", v[0], v[v.len() - 1], v.len())
            }
        };
        let ns = self.volume.dims[0];
        format!(
            "format: SEG-Y rev {}.{} (bytes 3501-3502), textual header {}\nsample type: {}\nendianness: {}\ntraces: {}\ninline/crossline numbers: {}\ninlines: {}\ncrosslines: {}\n{}\noffsets: {}\nsamples: {} per trace, interval {} us, 0..={} ms\n{}\n",
            self.revision.0,
            self.revision.1,
            if self.ebcdic { "EBCDIC" } else { "ASCII" },
            self.format.name(),
            if self.big_endian { "big-endian" } else { "little-endian" },
            self.traces,
            self.keys.describe(),
            self.grid.inlines.describe(),
            self.grid.crosslines.describe(),
            self.grid.describe(),
            offsets,
            ns,
            self.interval_us,
            (ns.saturating_sub(1)) as f64 * self.interval_us as f64 / 1000.0,
            self.geometry.describe(),
        )
    }
}

/// The 4-byte integer at byte `at` of a header, in the file's byte order.
pub(crate) fn header_i32(bytes: &[u8], at: usize, big: bool) -> i32 {
    let a = [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
    if big {
        i32::from_be_bytes(a)
    } else {
        i32::from_le_bytes(a)
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    big: bool,
}

impl Reader<'_> {
    fn u16(&self, at: usize) -> u16 {
        let a = [self.bytes[at], self.bytes[at + 1]];
        if self.big {
            u16::from_be_bytes(a)
        } else {
            u16::from_le_bytes(a)
        }
    }
    fn i32(&self, at: usize) -> i32 {
        let a = self.bytes[at..at + 4].try_into().expect("4 bytes");
        if self.big {
            i32::from_be_bytes(a)
        } else {
            i32::from_le_bytes(a)
        }
    }
    fn u32(&self, at: usize) -> u32 {
        self.i32(at) as u32
    }
}

/// Read and grid a SEG-Y file (the whole file is read: its length bounds the memory).
pub fn read(path: &Path, options: &ReadOptions) -> Result<SegyCube, VolumeError> {
    let bytes = read_file(path, u64::MAX)?;
    parse(path, &bytes, options)
}

/// What the binary header and the file's length say, before any trace is gridded.
#[derive(Debug, Clone)]
pub(crate) struct Headers {
    pub layout: grid::Layout,
    pub revision: (u8, u8),
    pub ebcdic: bool,
    pub interval_us: u32,
}

/// Parse SEG-Y bytes; `path` names the file in errors.
pub fn parse(path: &Path, bytes: &[u8], options: &ReadOptions) -> Result<SegyCube, VolumeError> {
    let h = headers_with_keys(path, bytes, options.keys)?;
    let layout = h.layout;
    let grid::Gridded {
        dims,
        values,
        grid,
        offsets,
    } = grid::grid(path, bytes, &layout, options)?;
    // Spacing: the survey's proportions (geometry.rs), from live traces.
    let spread: Vec<(usize, usize)> = grid.spread().iter().map(|&(k, j, _)| (k, j)).collect();
    let geometry = geometry::geometry(
        h.interval_us,
        dims[1],
        dims[2],
        layout.big,
        &spread,
        |k, j| {
            let at = layout.first_trace + grid.trace(k, j)? * layout.trace_len;
            bytes[at..at + TRACE_HEADER].try_into().ok()
        },
    );
    let mut volume = Volume::new(dims, geometry.spacing, values)?;
    volume.map = geometry.map;
    Ok(SegyCube {
        volume,
        revision: h.revision,
        format: layout.format,
        big_endian: layout.big,
        ebcdic: h.ebcdic,
        interval_us: h.interval_us,
        inlines: grid.inlines.numbers(),
        crosslines: grid.crosslines.numbers(),
        grid,
        traces: layout.traces,
        offsets,
        keys: layout.keys,
        geometry,
    })
}

/// [`headers`] of a whole file in `bytes`, with the inline and crossline bytes resolved
/// ([`keys::resolve`]: those named, else detected from the first traces).
pub(crate) fn headers_with_keys(
    path: &Path,
    bytes: &[u8],
    named: KeyBytes,
) -> Result<Headers, VolumeError> {
    let mut h = headers(path, bytes, bytes.len() as u64)?;
    let l = h.layout;
    h.layout.keys = keys::resolve(path, named, l.traces, l.big, |t| {
        let at = l.first_trace + t * l.trace_len;
        Ok(bytes[at..at + TRACE_HEADER]
            .try_into()
            .expect("the layout holds whole traces"))
    })?;
    Ok(h)
}

/// Read the textual, binary and extended headers from `bytes` (the start of a file of
/// `len` bytes, holding at least the first trace's header when the file has one) and
/// check the trace layout against `len`.
pub(crate) fn headers(path: &Path, bytes: &[u8], len: u64) -> Result<Headers, VolumeError> {
    let bin = TEXT_HEADER;
    if bytes.len() < TEXT_HEADER + BINARY_HEADER {
        return Err(VolumeError::format(
            path,
            bytes.len() as u64,
            format!(
                "file ends after {} bytes; a SEG-Y file starts with a 3200-byte textual and a 400-byte binary header",
                bytes.len()
            ),
        ));
    }
    let be = Reader { bytes, big: true };
    let le = Reader { bytes, big: false };
    // Byte order: the rev 2 byte-order word, else whichever order gives a known format.
    let big = match be.u32(bin + 96) {
        0x0102_0304 => true,
        0x0403_0201 => false,
        _ => {
            SampleFormat::from_code(be.u16(bin + 24)).is_some()
                || SampleFormat::from_code(le.u16(bin + 24)).is_none()
        }
    };
    let r = if big { be } else { le };
    let code = r.u16(bin + 24);
    let format = SampleFormat::from_code(code).ok_or_else(|| {
        VolumeError::format(
            path,
            (bin + 24) as u64,
            format!("sample format code {code} is not one of 1, 2, 3, 5, 6, 8, 10, 11, 16"),
        )
    })?;
    let revision = (bytes[bin + 300], bytes[bin + 301]);
    let declared_samples = r.u16(bin + 20) as usize;
    let mut samples = declared_samples;
    if samples == 0 && revision.0 >= 2 {
        samples = r.u32(bin + 68) as usize;
    }
    let mut interval_us = r.u16(bin + 16) as u32;
    let extended = r.u16(bin + 304) as i16;
    if extended < 0 {
        return Err(VolumeError::Unsupported {
            path: path.into(),
            message: format!(
                "a variable number of extended textual headers ({extended} at byte 3505) is not supported"
            ),
        });
    }
    let first_trace = TEXT_HEADER + BINARY_HEADER + extended as usize * TEXT_HEADER;
    if samples == 0 {
        // Fall back on the first trace header's count (bytes 115-116).
        if bytes.len() >= first_trace + TRACE_HEADER {
            samples = r.u16(first_trace + 114) as usize;
        }
        if samples == 0 {
            return Err(VolumeError::format(
                path,
                (bin + 20) as u64,
                "samples per trace is 0 in the binary header and in the first trace header",
            ));
        }
    }
    if interval_us == 0 && bytes.len() >= first_trace + TRACE_HEADER {
        interval_us = r.u16(first_trace + 116) as u32;
    }
    let trace_len = TRACE_HEADER + samples * format.bytes();
    let data = len.checked_sub(first_trace as u64).ok_or_else(|| {
        VolumeError::format(
            path,
            len,
            format!("file ends before the first trace, which the headers place at byte {first_trace} ({extended} extended textual headers)"),
        )
    })?;
    let tl = trace_len as u64;
    if data % tl != 0 {
        let whole = data / tl;
        let start = first_trace as u64 + whole * tl;
        return Err(VolumeError::format(
            path,
            len,
            format!(
                "file ends inside trace {} (which starts at byte {start}): each trace is {trace_len} bytes (240-byte header + {samples} samples of {}), {} bytes are missing; the file is truncated or its headers are wrong",
                whole + 1,
                format.name(),
                tl - (data - whole * tl)
            ),
        ));
    }
    let traces = usize::try_from(data / tl).unwrap_or(usize::MAX);
    if traces == 0 {
        return Err(VolumeError::format(
            path,
            first_trace as u64,
            "no traces after the headers",
        ));
    }
    Ok(Headers {
        layout: grid::Layout {
            first_trace,
            trace_len,
            traces,
            samples,
            format,
            big,
            header_samples: declared_samples,
            keys: Keys::default(),
        },
        revision,
        ebcdic: bytes[0] == 0xC3 || bytes[0] == 0x40,
        interval_us,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook formula, `(-1)^s fraction / 2^24 x 16^(e - 64)` in f64.
    fn ibm_by_the_book(bits: u32) -> f32 {
        let sign = if bits >> 31 == 1 { -1.0 } else { 1.0 };
        let exponent = ((bits >> 24) & 0x7f) as i32 - 64;
        let fraction = (bits & 0x00ff_ffff) as f64 / 16_777_216.0;
        (sign * fraction * 16f64.powi(exponent)) as f32
    }

    #[test]
    fn ibm_decoding_is_the_textbook_formula_bit_for_bit() {
        // Every sign and exponent (f32 overflow, underflow to subnormals and zero
        // included) with fractions at the edges and 200 random ones each.
        let mut seed = 0x9e37_79b9u32;
        for high in 0..=0xffu32 {
            let mut fractions = vec![0, 1, 0x0f_ffff, 0x10_0000, 0x7f_ffff, 0xff_ffff];
            for _ in 0..200 {
                seed ^= seed << 13;
                seed ^= seed >> 17;
                seed ^= seed << 5;
                fractions.push(seed & 0xff_ffff);
            }
            for f in fractions {
                let bits = high << 24 | f;
                assert_eq!(
                    ibm_to_f32(bits).to_bits(),
                    ibm_by_the_book(bits).to_bits(),
                    "{bits:#010x}"
                );
            }
        }
    }

    #[test]
    fn ibm_known_values() {
        // -118.625 is 0xC276A000 (the classic example of IBM's own documentation).
        assert_eq!(ibm_to_f32(0xC276_A000), -118.625);
        assert_eq!(f32_to_ibm(-118.625), 0xC276_A000);
        assert_eq!(ibm_to_f32(0x4110_0000), 1.0);
        assert_eq!(ibm_to_f32(0), 0.0);
        for v in [1.0f32, 0.5, 3.25, -1e-3, 12345.678, 1e30] {
            let back = ibm_to_f32(f32_to_ibm(v));
            // IBM keeps 21 to 24 significant bits (hex normalization): relative 2^-20.
            assert!(((back - v) / v).abs() < 1e-6, "{v} -> {back}");
        }
    }

    fn options(format: SampleFormat) -> WriteOptions {
        WriteOptions {
            format,
            big_endian: true,
            revision: 1,
            first_inline: 1,
            first_crossline: 1,
            interval_us: 4000,
        }
    }

    /// `v` as read back from a written file: the writer puts no CDP coordinates, so the
    /// geometry assumes its bins; a sample is its interval in ms as metres.
    fn as_read(v: &Volume, interval_us: u16) -> Volume {
        Volume {
            spacing: [
                interval_us as f64 / 1000.0,
                geometry::ASSUMED_BIN_M,
                geometry::ASSUMED_BIN_M,
            ],
            ..v.clone()
        }
    }

    fn cube() -> Volume {
        let dims = [5, 3, 4];
        let values = (0..60).map(|n| n as f32 - 20.0).collect();
        Volume::new(dims, [1.0; 3], values).unwrap()
    }

    #[test]
    fn round_trips_every_format_and_order() {
        let v = cube();
        for code in [1, 2, 3, 5, 6, 8, 10, 11, 16] {
            let format = SampleFormat::from_code(code).unwrap();
            for big_endian in [true, false] {
                for revision in [1, 2] {
                    let o = WriteOptions {
                        format,
                        big_endian,
                        revision,
                        first_inline: 100,
                        first_crossline: 7,
                        interval_us: 2000,
                    };
                    let unsigned = matches!(code, 10 | 11 | 16);
                    let mut src = v.clone();
                    if unsigned {
                        src.values.iter_mut().for_each(|x| *x += 20.0);
                    }
                    let cube = parse(
                        Path::new("mem.sgy"),
                        &write(&src, &o),
                        &ReadOptions::default(),
                    )
                    .unwrap();
                    assert_eq!(
                        cube.volume,
                        as_read(&src, o.interval_us),
                        "format {code} big {big_endian} rev {revision}"
                    );
                    assert_eq!(cube.big_endian, big_endian);
                    assert_eq!(cube.format, format);
                    assert_eq!(cube.inlines, vec![100, 101, 102, 103]);
                    assert_eq!(cube.crosslines, vec![7, 8, 9]);
                }
            }
        }
    }

    #[test]
    fn any_trace_order_grids_the_same() {
        let v = cube();
        let o = options(SampleFormat::IeeeFloat);
        let bytes = write(&v, &o);
        // Swap the first and last traces.
        let trace = TRACE_HEADER + 5 * 4;
        let mut swapped = bytes.clone();
        let (a, b) = (3600, 3600 + 11 * trace);
        swapped[a..a + trace].copy_from_slice(&bytes[b..b + trace]);
        swapped[b..b + trace].copy_from_slice(&bytes[a..a + trace]);
        assert_eq!(
            parse(Path::new("m"), &swapped, &ReadOptions::default())
                .unwrap()
                .volume,
            as_read(&v, o.interval_us)
        );
    }

    #[test]
    fn prestack_and_irregular_and_truncated_are_refused() {
        let v = cube();
        let o = options(SampleFormat::Int16);
        let bytes = write(&v, &o);
        let trace = TRACE_HEADER + 5 * 2;
        // Trace 2 claims trace 1's position: a second offset at one CDP.
        let mut prestack = bytes.clone();
        prestack[3600 + trace + 192..3600 + trace + 196].copy_from_slice(&1i32.to_be_bytes());
        let e = parse(Path::new("p.sgy"), &prestack, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("pre-stack") && e.contains("p.sgy"), "{e}");
        // Drop the last trace: an irregular survey, its last position dead (NaN).
        let c = parse(
            Path::new("i.sgy"),
            &bytes[..bytes.len() - trace],
            &ReadOptions::default(),
        )
        .unwrap();
        assert_eq!(c.volume.dims, v.dims);
        let [ni, nj, nk] = v.dims;
        let dead = &c.volume.values[ni * (nj * nk - 1)..];
        assert!(dead.iter().all(|x| x.is_nan()), "{dead:?}");
        assert_eq!(c.grid.live, nj * nk - 1);
        assert!(
            c.describe().contains("11 live traces, 1 dead"),
            "{}",
            c.describe()
        );
        // Cut inside a trace.
        let e = parse(
            Path::new("t.sgy"),
            &bytes[..bytes.len() - 3],
            &ReadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("truncated") && e.contains("trace 12"), "{e}");
        // Headers only.
        assert!(parse(Path::new("h"), &bytes[..100], &ReadOptions::default()).is_err());
        // Unknown format code.
        let mut bad = bytes.clone();
        bad[3224..3226].copy_from_slice(&[0, 99]);
        bad[3225] = 99;
        bad[3224] = 0;
        let e = parse(Path::new("f"), &bad, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("at byte 3224"), "{e}");
    }

    /// Two cubes as one pre-stack file: every cell holds a trace of offset 100 (from
    /// `a`) and one of offset 300 (from `b`), interleaved.
    fn prestack_file(a: &Volume, b: &Volume) -> Vec<u8> {
        write_prestack(&[(100, a), (300, b)], &options(SampleFormat::IeeeFloat))
    }

    #[test]
    fn inspect_describes_a_prestack_file_and_how_a_scene_reads_it() {
        let a = cube();
        let mut b = cube();
        b.values.iter_mut().for_each(|v| *v = *v * 3.0 + 1.0);
        let dir = std::env::temp_dir().join(format!("arbvis-prestack-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("gathers.sgy");
        std::fs::write(&path, prestack_file(&a, &b)).unwrap();
        let g = gathers(&path, &std::fs::read(&path).unwrap(), KeyBytes::default()).unwrap();
        assert!(g.is_prestack());
        // The cube is 5 samples x 3 crosslines x 4 inlines: 12 gathers of 2 traces;
        // values -20..=39 (a) and -59..=118 (b = 3a + 1).
        assert_eq!((g.traces, g.gathers, g.per_gather), (24, 12, (2, 2)));
        assert_eq!(g.offsets, [(100, 12), (300, 12)]);
        assert_eq!((g.inlines, g.crosslines), ((1, 4), (1, 3)));
        assert_eq!(g.range, Some((-59.0, 118.0)));
        let s = crate::volume::inspect(&path).unwrap();
        for want in [
            "format: SEG-Y rev 1.0, pre-stack",
            "traces: 24\n",
            "gathers: 12 (inline/crossline positions, trace bytes 189 and 193 (detected: SEG-Y rev 1's inline and crossline numbers)), 2 traces each",
            "offsets (trace bytes 37-40): 2 values: 100 (12 traces), 300 (12 traces)",
            "samples: 5 per trace, interval 4000 us, 0..=16 ms",
            "values: [-59, 118] over all traces",
            "prestack = { offset = 100 }",
            "prestack = \"stack\"",
        ] {
            assert!(s.contains(want), "missing {want:?} in\n{s}");
        }
        // A post-stack file is still described as a cube.
        std::fs::write(&path, write(&a, &options(SampleFormat::IeeeFloat))).unwrap();
        let s = crate::volume::inspect(&path).unwrap();
        assert!(s.contains("dimensions (i, j, k): 5 x 3 x 4"), "{s}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn prestack_files_pick_an_offset_or_stack() {
        let a = cube();
        let mut b = cube();
        b.values.iter_mut().for_each(|v| *v = *v * 3.0 + 1.0);
        let bytes = prestack_file(&a, &b);
        let e = parse(Path::new("g.sgy"), &bytes, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("offsets 100, 300") && e.contains("prestack"),
            "{e}"
        );
        let pick = |prestack| ReadOptions {
            prestack,
            ..Default::default()
        };
        let near = parse(Path::new("g"), &bytes, &pick(Prestack::Offset(100))).unwrap();
        assert_eq!(near.volume, as_read(&a, 4000));
        assert_eq!(near.offsets, vec![100, 300]);
        let far = parse(Path::new("g"), &bytes, &pick(Prestack::Offset(300))).unwrap();
        assert_eq!(far.volume, as_read(&b, 4000));
        let stack = parse(Path::new("g"), &bytes, &pick(Prestack::Stack)).unwrap();
        for (s, (x, y)) in stack
            .volume
            .values
            .iter()
            .zip(a.values.iter().zip(&b.values))
        {
            assert_eq!(*s, (x + y) / 2.0);
        }
        let e = parse(Path::new("g"), &bytes, &pick(Prestack::Offset(200)))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("offsets in the file") && e.contains("100, 300"),
            "{e}"
        );
    }

    #[test]
    fn extreme_line_numbers_and_wrong_sample_counts_are_told_plainly() {
        let v = Volume::new([2, 2, 2], [1.0; 3], vec![1.0; 8]).unwrap();
        let o = WriteOptions {
            first_inline: i32::MIN,
            ..options(SampleFormat::IeeeFloat)
        };
        let mut bytes = write(&v, &o);
        // Move the second inline to i32::MAX: the step is 2^32 - 1, not a wrapped -1.
        let trace = TRACE_HEADER + 8;
        for t in [2, 3] {
            bytes[3600 + t * trace + 188..][..4].copy_from_slice(&i32::MAX.to_be_bytes());
        }
        let c = parse(Path::new("x"), &bytes, &ReadOptions::default()).unwrap();
        assert!(
            c.describe()
                .contains("-2147483648..=2147483647 (2 values, step 4294967295)"),
            "{}",
            c.describe()
        );
        // A header declaring 60,000 samples: the file holds two traces that long, on a
        // grid of two positions of four, whose volume is refused for its size, said.
        let v = Volume::new([4, 10, 10], [1.0; 3], vec![1.0; 400]).unwrap();
        let mut bytes = write(&v, &options(SampleFormat::UInt8));
        bytes[3220..3222].copy_from_slice(&60000u16.to_be_bytes());
        // Pad so that whole 60,240-byte traces fit: 100 traces of 244 bytes = 24,400,
        // plus 95,600 bytes of padding = two such traces.
        bytes.resize(3600 + 2 * 60240, 0);
        let e = parse(Path::new("s.sgy"), &bytes, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("[60000, 2, 2]"), "{e}");
        // Numbers read from inside the samples are no survey's lines: refused with what
        // the header's count makes of the file.
        let mut bytes = write(&v, &options(SampleFormat::UInt8));
        bytes[3220..3222].copy_from_slice(&20u16.to_be_bytes());
        bytes.resize(3600 + 94 * 260, 0);
        let n = bytes.len();
        for (q, b) in bytes[3600 + 260..n].iter_mut().enumerate() {
            *b = (q * 7919 % 251) as u8;
        }
        let e = parse(Path::new("s.sgy"), &bytes, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("declares 20 samples per trace") && e.contains("traces of 260 bytes"),
            "{e}"
        );
    }
}
