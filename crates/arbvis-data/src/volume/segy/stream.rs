//! SEG-Y read a column of traces at a time, never the whole file (`arbvis convert`).
//!
//! The headers are read as [`super::read`] reads them. The grid is found without reading
//! every trace header when the file is sorted by inline (the usual post-stack order): the
//! first inline's run of crosslines gives the crossline step and count, the trace count
//! then the inline count, and the first and last trace of every inline are checked
//! against that grid. Every trace read later is checked again (its inline and crossline,
//! bytes 189-196 or those named or detected, must be the ones its place implies), so a file that only looks sorted
//! ends in an error naming the trace and its byte. Any other order is gridded from every
//! trace header (one small read per trace, 12 bytes per trace held), and so is an
//! irregular survey: its grid is the lines the numbers span ([`super::lines`]), and a
//! position without a trace reads as NaN (dead). Pre-stack files (several traces per cell)
//! are refused.

use std::fs::File;
use std::ops::Range;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::grid::Layout;
use super::keys::KeyBytes;
use super::lines::{Lines, TraceGrid};
use super::{headers, SampleFormat, TRACE_HEADER};
use crate::volume::VolumeError;

/// A SEG-Y file opened for reading columns of traces.
#[derive(Debug)]
pub struct SegyStream {
    path: PathBuf,
    file: File,
    layout: Layout,
    /// Revision from bytes 3501-3502.
    pub revision: (u8, u8),
    /// EBCDIC textual header.
    pub ebcdic: bool,
    /// Sample interval in microseconds.
    pub interval_us: u32,
    /// Inline numbers, ascending (axis k).
    pub inlines: Vec<i32>,
    /// Crossline numbers, ascending (axis j).
    pub crosslines: Vec<i32>,
    /// The survey's proportions: one step along samples, crosslines and inlines.
    pub geometry: super::Geometry,
    /// The lines and the trace at each position (none where the survey has no trace).
    pub grid: TraceGrid,
    /// Whether the grid came from the inline-sorted shortcut (else from every header).
    sorted: bool,
}

impl SegyStream {
    /// Open `path`: headers, then the grid (see the module doc), with the inline and
    /// crossline numbers where [`super::keys`] finds them.
    pub fn open(path: &Path) -> Result<SegyStream, VolumeError> {
        SegyStream::open_with(path, KeyBytes::default())
    }

    /// [`SegyStream::open`] with the inline and crossline bytes `named` (else detected).
    pub fn open_with(path: &Path, named: KeyBytes) -> Result<SegyStream, VolumeError> {
        let (file, len) =
            arbvis_core::input::open_regular(path).map_err(|e| VolumeError::io(path, e))?;
        let read_prefix = |n: u64| -> Result<Vec<u8>, VolumeError> {
            let n = n.min(len) as usize;
            let mut b = vec![0u8; n];
            file.read_exact_at(&mut b, 0)
                .map_err(|e| VolumeError::io(path, e))?;
            Ok(b)
        };
        let mut prefix = read_prefix(3600 + TRACE_HEADER as u64)?;
        let mut h = headers(path, &prefix, len)?;
        let need = (h.layout.first_trace + TRACE_HEADER) as u64;
        if need > prefix.len() as u64 && len >= need {
            prefix = read_prefix(need)?;
            h = headers(path, &prefix, len)?;
        }
        let mut s = SegyStream {
            path: path.to_path_buf(),
            file,
            layout: h.layout,
            revision: h.revision,
            ebcdic: h.ebcdic,
            interval_us: h.interval_us,
            inlines: Vec::new(),
            crosslines: Vec::new(),
            geometry: super::geometry::geometry(0, 1, 1, true, &[], |_, _| None),
            grid: TraceGrid::from_keys(vec![(0, 0, 0)]).expect("one trace"),
            sorted: false,
        };
        let l = s.layout;
        s.layout.keys = super::keys::resolve(path, named, l.traces, l.big, |t| {
            let mut h = [0u8; TRACE_HEADER];
            s.file
                .read_exact_at(&mut h, s.offset_of(t))
                .map_err(|e| VolumeError::io(path, e))?;
            Ok(h)
        })?;
        if !s.try_sorted()? {
            s.map_every_trace()?;
        }
        let (nj, nk) = (s.crosslines.len(), s.inlines.len());
        let spread: Vec<(usize, usize)> = s.grid.spread().iter().map(|&(k, j, _)| (k, j)).collect();
        s.geometry =
            super::geometry::geometry(s.interval_us, nj, nk, s.layout.big, &spread, |k, j| {
                let mut h = [0u8; TRACE_HEADER];
                s.file
                    .read_exact_at(&mut h, s.offset_of(s.grid.trace(k, j)?))
                    .ok()
                    .map(|_| h)
            });
        Ok(s)
    }

    /// Samples, crosslines, inlines.
    pub fn dims(&self) -> [usize; 3] {
        [
            self.layout.samples,
            self.crosslines.len(),
            self.inlines.len(),
        ]
    }

    /// Sample encoding.
    pub fn format(&self) -> SampleFormat {
        self.layout.format
    }

    /// Byte order.
    pub fn big_endian(&self) -> bool {
        self.layout.big
    }

    /// Number of traces.
    pub fn traces(&self) -> usize {
        self.layout.traces
    }

    /// Bytes of one trace (header and samples).
    pub fn trace_bytes(&self) -> usize {
        self.layout.trace_len
    }

    fn offset_of(&self, t: usize) -> u64 {
        self.layout.first_trace as u64 + t as u64 * self.layout.trace_len as u64
    }

    /// (inline, crossline, offset) of trace `t`.
    fn key(&self, t: usize) -> Result<(i32, i32, i32), VolumeError> {
        let mut h = [0u8; TRACE_HEADER];
        self.file
            .read_exact_at(&mut h, self.offset_of(t))
            .map_err(|e| VolumeError::io(&self.path, e))?;
        let big = self.layout.big;
        let (il, xl) = self.layout.keys.read(&h, big);
        Ok((il, xl, super::header_i32(&h, 36, big)))
    }

    /// The inline-sorted grid, if the headers agree with it.
    fn try_sorted(&mut self) -> Result<bool, VolumeError> {
        let traces = self.layout.traces;
        let (il0, xl0, off0) = self.key(0)?;
        let mut nx = 1;
        let mut xl_step = 0i64;
        while nx < traces {
            let (il, xl, off) = self.key(nx)?;
            if il != il0 {
                break;
            }
            let step = xl as i64 - xl0 as i64;
            if off != off0 || step == 0 || (nx > 1 && step != xl_step * nx as i64) {
                return Ok(false);
            }
            if nx == 1 {
                xl_step = step;
            }
            nx += 1;
        }
        if !traces.is_multiple_of(nx) {
            return Ok(false);
        }
        let ni = traces / nx;
        let il_step = if ni > 1 {
            self.key(nx)?.0 as i64 - il0 as i64
        } else {
            1
        };
        if il_step == 0 || (nx > 1 && xl_step == 0) {
            return Ok(false);
        }
        let xl_step = if nx > 1 { xl_step } else { 1 };
        for k in 0..ni {
            let il = il0 as i64 + k as i64 * il_step;
            for t in [k * nx, k * nx + nx - 1] {
                let (a, b, off) = self.key(t)?;
                let xl = xl0 as i64 + (t - k * nx) as i64 * xl_step;
                if a as i64 != il || b as i64 != xl || off != off0 {
                    return Ok(false);
                }
            }
        }
        let line = |first: i32, step: i64, n: usize| -> Option<Vec<i32>> {
            let mut v: Vec<i32> = (0..n)
                .map(|q| i32::try_from(first as i64 + q as i64 * step).ok())
                .collect::<Option<_>>()?;
            v.sort_unstable();
            Some(v)
        };
        match (line(il0, il_step, ni), line(xl0, xl_step, nx)) {
            (Some(inlines), Some(crosslines)) => {
                let lines = |v: &[i32], step: i64| Lines {
                    first: v[0],
                    step: step.abs(),
                    count: v.len(),
                    present: v.len(),
                };
                let (inline_up, crossline_up) = (il_step > 0, xl_step > 0);
                self.grid = TraceGrid::full(
                    lines(&inlines, il_step),
                    lines(&crosslines, xl_step),
                    |k, j| {
                        // Trace `kf * nx + jf`, reversed where the file's numbers descend.
                        let kf = if inline_up { k } else { ni - 1 - k };
                        let jf = if crossline_up { j } else { nx - 1 - j };
                        (kf * nx + jf) as u32
                    },
                );
                self.inlines = inlines;
                self.crosslines = crosslines;
                self.sorted = true;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// Grid from every trace header (any order, any outline).
    fn map_every_trace(&mut self) -> Result<(), VolumeError> {
        let traces = self.layout.traces;
        arbvis_core::budget::check("the trace map of a SEG-Y file", traces as u64 * 16)
            .map_err(|e| VolumeError::Invalid(format!("{}: {e}", self.path.display())))?;
        let mut keys = Vec::with_capacity(traces);
        for t in 0..traces {
            let (il, xl, _) = self.key(t)?;
            keys.push((il, xl, t as u32));
        }
        self.grid = TraceGrid::from_keys(keys).map_err(|e| {
            e.into_volume_error(
                &self.path,
                &self.layout.keys,
                |t| self.offset_of(t as usize),
                ": a pre-stack or otherwise non-gridded file, which `arbvis convert` does not take (stack it first)",
            )
        })
        .map_err(|e| super::grid::with_count_hint(e, &self.layout))?;
        self.inlines = self.grid.inlines.numbers();
        self.crosslines = self.grid.crosslines.numbers();
        Ok(())
    }

    /// The trace of cell `(k, j)`, if the survey has one there.
    fn trace_of(&self, k: usize, j: usize) -> Option<usize> {
        self.grid.trace(k, j)
    }

    /// Read the traces of crosslines `j` and inlines `k` into `out` (sample fastest, then
    /// crossline, then inline; `samples * j.len() * k.len()` values). Consecutive traces
    /// are read in one request; every trace's header is checked against its cell.
    pub fn read_column(
        &self,
        j: Range<usize>,
        k: Range<usize>,
        out: &mut [f32],
    ) -> Result<(), VolumeError> {
        self.read_column_with_coordinates(j, k, out, None)
    }

    /// [`SegyStream::read_column`], and each trace's CDP x and y (bytes 181-188, scaled by
    /// the coordinate scalar of bytes 71-72) into `coordinates` (crossline fastest).
    pub fn read_column_with_coordinates(
        &self,
        j: Range<usize>,
        k: Range<usize>,
        out: &mut [f32],
        mut coordinates: Option<&mut [[f64; 2]]>,
    ) -> Result<(), VolumeError> {
        let ns = self.layout.samples;
        let tl = self.layout.trace_len;
        let (big, format) = (self.layout.big, self.layout.format);
        let mut buf: Vec<u8> = Vec::new();
        let mut at = 0;
        for kk in k.clone() {
            let mut jj = j.start;
            while jj < j.end {
                // A dead position (no trace): no data.
                let Some(first) = self.trace_of(kk, jj) else {
                    out[at..at + ns].fill(f32::NAN);
                    if let Some(c) = coordinates.as_deref_mut() {
                        c[at / ns] = [f64::NAN; 2];
                    }
                    at += ns;
                    jj += 1;
                    continue;
                };
                // A run of cells whose traces follow each other in the file (either way).
                let mut n = 1;
                let next = |q: usize| {
                    (jj + q < j.end)
                        .then(|| self.trace_of(kk, jj + q))
                        .flatten()
                };
                let up = next(1) == Some(first + 1);
                let down = first > 0 && next(1) == Some(first - 1);
                while let Some(t) = next(n) {
                    if (up && t == first + n) || (down && t + n == first) {
                        n += 1;
                    } else {
                        break;
                    }
                }
                let lo = if down { first + 1 - n } else { first };
                buf.resize(n * tl, 0);
                self.file
                    .read_exact_at(&mut buf, self.offset_of(lo))
                    .map_err(|e| VolumeError::io(&self.path, e))?;
                for q in 0..n {
                    let cell = jj + q;
                    let t = if down { first - q } else { first + q };
                    let trace = &buf[(t - lo) * tl..][..tl];
                    let (il, xl) = self.layout.keys.read(trace, big);
                    if il != self.inlines[kk] || xl != self.crosslines[cell] {
                        return Err(VolumeError::format(
                            &self.path,
                            self.offset_of(t) + self.layout.keys.iline as u64 - 1,
                            format!(
                                "trace {} holds inline {il} crossline {xl} ({}) where the grid read from the headers expects inline {} crossline {}: the file is not in one inline-sorted order",
                                t + 1,
                                self.layout.keys.describe(),
                                self.inlines[kk],
                                self.crosslines[cell]
                            ),
                        ));
                    }
                    if let Some(c) = coordinates.as_deref_mut() {
                        let s = i16::from_be_bytes(if big {
                            [trace[70], trace[71]]
                        } else {
                            [trace[71], trace[70]]
                        }) as f64;
                        let scale = match s {
                            s if s < 0.0 => 1.0 / -s,
                            s if s > 0.0 => s,
                            _ => 1.0,
                        };
                        c[at / ns + q] = [
                            super::header_i32(trace, 180, big) as f64 * scale,
                            super::header_i32(trace, 184, big) as f64 * scale,
                        ];
                    }
                    let dst = &mut out[at + q * ns..][..ns];
                    format.decode_trace(&trace[TRACE_HEADER..], big, dst);
                }
                at += n * ns;
                jj += n;
            }
        }
        Ok(())
    }

    /// What the headers say, one fact per line (as `arbvis inspect` prints them).
    pub fn describe(&self) -> Vec<(String, String)> {
        vec![
            (
                "format".into(),
                format!("SEG-Y rev {}.{}", self.revision.0, self.revision.1),
            ),
            (
                "textual header".into(),
                if self.ebcdic { "EBCDIC" } else { "ASCII" }.into(),
            ),
            ("sample type".into(), self.layout.format.name().into()),
            (
                "endianness".into(),
                if self.layout.big {
                    "big-endian"
                } else {
                    "little-endian"
                }
                .into(),
            ),
            ("traces".into(), self.layout.traces.to_string()),
            (
                "inline/crossline numbers".into(),
                self.layout.keys.describe(),
            ),
            ("inlines".into(), self.grid.inlines.describe()),
            ("crosslines".into(), self.grid.crosslines.describe()),
            (
                "grid".into(),
                self.grid
                    .describe()
                    .trim_start_matches("grid: ")
                    .to_string(),
            ),
            ("samples per trace".into(), self.layout.samples.to_string()),
            ("sample interval (us)".into(), self.interval_us.to_string()),
            (
                "geometry".into(),
                self.geometry.describe().replace('\n', "; "),
            ),
            (
                "trace order".into(),
                if self.sorted {
                    "inline-sorted"
                } else {
                    "gridded from every trace header"
                }
                .into(),
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::super::{write, WriteOptions};
    use super::*;
    use crate::volume::Volume;

    fn cube() -> Volume {
        let dims = [7, 5, 4];
        let values = (0..140).map(|n| (n as f32 * 0.37).sin() * 100.0).collect();
        Volume::new(dims, [1.0; 3], values).unwrap()
    }

    fn columns_equal_the_volume(s: &SegyStream, v: &Volume) {
        assert_eq!(s.dims(), v.dims);
        // Uneven column shapes: j 1..4, k 2..4.
        let mut out = vec![0f32; 7 * 3 * 2];
        s.read_column(1..4, 2..4, &mut out).unwrap();
        let mut n = 0;
        for k in 2..4 {
            for j in 1..4 {
                for i in 0..7 {
                    assert_eq!(out[n], v.values[v.index(i, j, k)], "{i} {j} {k}");
                    n += 1;
                }
            }
        }
    }

    #[test]
    fn sorted_and_shuffled_files_read_the_same_columns() {
        let v = cube();
        let o = WriteOptions {
            format: super::super::SampleFormat::IeeeFloat,
            big_endian: true,
            revision: 1,
            first_inline: 10,
            first_crossline: 3,
            interval_us: 4000,
        };
        let dir = std::env::temp_dir().join(format!("arbvis-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let sorted = dir.join("sorted.sgy");
        let bytes = write(&v, &o);
        std::fs::write(&sorted, &bytes).unwrap();
        let s = SegyStream::open(&sorted).unwrap();
        assert!(s.sorted);
        assert_eq!(s.inlines, vec![10, 11, 12, 13]);
        columns_equal_the_volume(&s, &v);
        // Reverse the trace order: the grid comes from every header.
        let tl = 240 + 7 * 4;
        let mut shuffled = bytes[..3600].to_vec();
        for t in (0..20).rev() {
            shuffled.extend_from_slice(&bytes[3600 + t * tl..][..tl]);
        }
        let path = dir.join("reversed.sgy");
        std::fs::write(&path, &shuffled).unwrap();
        let s = SegyStream::open(&path).unwrap();
        columns_equal_the_volume(&s, &v);
        // Swap two traces inside the second inline: the sorted check passes at the ends
        // of each inline, and the read names the trace that breaks the order.
        let mut swapped = bytes.clone();
        let (a, b) = (3600 + 6 * tl, 3600 + 7 * tl);
        let ta = bytes[a..a + tl].to_vec();
        swapped[a..a + tl].copy_from_slice(&bytes[b..b + tl]);
        swapped[b..b + tl].copy_from_slice(&ta);
        let path = dir.join("swapped.sgy");
        std::fs::write(&path, &swapped).unwrap();
        let s = SegyStream::open(&path).unwrap();
        let mut out = vec![0f32; 7 * 5 * 4];
        let e = s.read_column(0..5, 0..4, &mut out).unwrap_err().to_string();
        assert!(
            e.contains("swapped.sgy")
                && e.contains("trace 7 holds inline 11 crossline 5")
                && e.contains("expects inline 11 crossline 4"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
