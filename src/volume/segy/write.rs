//! A small SEG-Y writer (inline-sorted, one trace per inline/crossline, every sample
//! format, both byte orders, rev 1 or 2): the reader's tests and the fuzz corpus use it.

use super::{SampleFormat, BINARY_HEADER, TEXT_HEADER, TRACE_HEADER};
use crate::volume::Volume;

/// Options for [`write`].
#[derive(Debug, Clone, Copy)]
pub struct WriteOptions {
    /// Sample encoding.
    pub format: SampleFormat,
    /// Byte order.
    pub big_endian: bool,
    /// 1 or 2 (rev 2 writes the byte-order word).
    pub revision: u8,
    /// First inline number.
    pub first_inline: i32,
    /// First crossline number.
    pub first_crossline: i32,
    /// Sample interval, microseconds.
    pub interval_us: u16,
}

/// Encode a volume (axes sample, crossline, inline) as a SEG-Y file, inline-sorted.
pub fn write(volume: &Volume, o: &WriteOptions) -> Vec<u8> {
    let [ns, nx, ni] = volume.dims;
    let mut out = vec![0x40u8; TEXT_HEADER]; // EBCDIC spaces
    let mut bin = vec![0u8; BINARY_HEADER];
    let put16 = |buf: &mut [u8], at: usize, v: u16| {
        let b = if o.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        buf[at..at + 2].copy_from_slice(&b);
    };
    let put32 = |buf: &mut [u8], at: usize, v: u32| {
        let b = if o.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        buf[at..at + 4].copy_from_slice(&b);
    };
    put16(&mut bin, 16, o.interval_us);
    put16(&mut bin, 20, ns as u16);
    put16(&mut bin, 24, o.format.code());
    if o.revision >= 2 {
        put32(&mut bin, 96, 0x0102_0304);
    }
    bin[300] = o.revision;
    put16(&mut bin, 302, 1);
    out.extend_from_slice(&bin);
    for k in 0..ni {
        for j in 0..nx {
            let mut h = vec![0u8; TRACE_HEADER];
            put32(&mut h, 188, (o.first_inline + k as i32) as u32);
            put32(&mut h, 192, (o.first_crossline + j as i32) as u32);
            put16(&mut h, 114, ns as u16);
            put16(&mut h, 116, o.interval_us);
            out.extend_from_slice(&h);
            for i in 0..ns {
                out.extend(
                    o.format
                        .encode(volume.values[volume.index(i, j, k)], o.big_endian),
                );
            }
        }
    }
    out
}

/// A pre-stack file: the volumes of `gathers` (each with its offset, all of one size)
/// interleaved, so that every inline/crossline position holds one trace per offset, in
/// the order given, with the offset in trace bytes 37-40 (nothing for no volume).
pub fn write_prestack(gathers: &[(i32, &Volume)], o: &WriteOptions) -> Vec<u8> {
    let Some((_, first)) = gathers.first() else {
        return Vec::new();
    };
    let files: Vec<Vec<u8>> = gathers.iter().map(|(_, v)| write(v, o)).collect();
    let head = TEXT_HEADER + BINARY_HEADER;
    let trace = TRACE_HEADER + first.dims[0] * o.format.bytes();
    let mut out = files[0][..head].to_vec();
    for t in 0..(files[0].len() - head) / trace {
        for (f, (offset, _)) in files.iter().zip(gathers) {
            let mut tr = f[head + t * trace..][..trace].to_vec();
            let b = if o.big_endian {
                offset.to_be_bytes()
            } else {
                offset.to_le_bytes()
            };
            tr[36..40].copy_from_slice(&b);
            out.extend(tr);
        }
    }
    out
}
