//! A small SEG-Y writer (inline-sorted, one trace per inline/crossline, every sample
//! format, both byte orders, rev 1 or 2): the reader's tests and the fuzz corpus use
//! [`write`]; [`TraceWriter`] streams a survey of any size trace by trace (the store's
//! bench generates its large synthetic survey with it).

use std::io::Write;

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

/// Writes the headers, then one trace at a time, inline-sorted.
pub struct TraceWriter<W: Write> {
    out: W,
    o: WriteOptions,
    samples: usize,
    buf: Vec<u8>,
}

impl WriteOptions {
    fn put16(&self, buf: &mut [u8], at: usize, v: u16) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        buf[at..at + 2].copy_from_slice(&b);
    }
    fn put32(&self, buf: &mut [u8], at: usize, v: u32) {
        let b = if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        };
        buf[at..at + 4].copy_from_slice(&b);
    }
}

impl<W: Write> TraceWriter<W> {
    /// Write the textual and binary headers for traces of `samples` samples (at most
    /// 65535: the binary header's field).
    pub fn new(mut out: W, o: WriteOptions, samples: usize) -> std::io::Result<TraceWriter<W>> {
        out.write_all(&[0x40u8; TEXT_HEADER])?; // EBCDIC spaces
        let mut bin = vec![0u8; BINARY_HEADER];
        o.put16(&mut bin, 16, o.interval_us);
        o.put16(&mut bin, 20, samples as u16);
        o.put16(&mut bin, 24, o.format.code());
        if o.revision >= 2 {
            o.put32(&mut bin, 96, 0x0102_0304);
        }
        bin[300] = o.revision;
        o.put16(&mut bin, 302, 1);
        out.write_all(&bin)?;
        Ok(TraceWriter {
            out,
            o,
            samples,
            buf: Vec::new(),
        })
    }

    /// Write the trace of inline index `k` and crossline index `j` (numbers from the
    /// options' first inline and crossline).
    pub fn trace(&mut self, k: usize, j: usize, samples: &[f32]) -> std::io::Result<()> {
        let o = self.o;
        self.buf.clear();
        self.buf.resize(TRACE_HEADER, 0);
        o.put32(&mut self.buf, 188, (o.first_inline + k as i32) as u32);
        o.put32(&mut self.buf, 192, (o.first_crossline + j as i32) as u32);
        o.put16(&mut self.buf, 114, self.samples as u16);
        o.put16(&mut self.buf, 116, o.interval_us);
        for &v in samples {
            self.buf.extend(o.format.encode(v, o.big_endian));
        }
        self.out.write_all(&self.buf)
    }

    /// The writer, flushed.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Encode a volume (axes sample, crossline, inline) as a SEG-Y file, inline-sorted.
pub fn write(volume: &Volume, o: &WriteOptions) -> Vec<u8> {
    let [ns, nx, ni] = volume.dims;
    let mut w = TraceWriter::new(Vec::new(), *o, ns).expect("writing to memory");
    for k in 0..ni {
        for j in 0..nx {
            let start = volume.index(0, j, k);
            w.trace(k, j, &volume.values[start..start + ns])
                .expect("writing to memory");
        }
    }
    w.finish().expect("writing to memory")
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
