//! What a pre-stack SEG-Y file holds, for `arbvis inspect`: its gathers (the traces at
//! one inline/crossline position, trace bytes 189-196 or those [`super::keys`] finds), their offsets (bytes 37-40),
//! samples and values, and how a scene reads it (one offset, or the stack). A post-stack
//! reader refuses such a file; an inspector describes it.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::keys::{KeyBytes, Keys};
use super::{headers_with_keys, Headers, SampleFormat, TRACE_HEADER};
use crate::volume::VolumeError;

/// The gathers of a SEG-Y file.
#[derive(Debug, Clone, PartialEq)]
pub struct Gathers {
    /// Revision (major, minor).
    pub revision: (u8, u8),
    /// Sample encoding.
    pub format: SampleFormat,
    /// Byte order.
    pub big_endian: bool,
    /// Traces in the file.
    pub traces: usize,
    /// Distinct inline/crossline positions.
    pub gathers: usize,
    /// Fewest and most traces in a gather.
    pub per_gather: (usize, usize),
    /// Each offset and how many traces have it, ascending.
    pub offsets: Vec<(i32, usize)>,
    /// Smallest and largest inline and crossline numbers.
    pub inlines: (i32, i32),
    /// Smallest and largest crossline numbers.
    pub crosslines: (i32, i32),
    /// Samples per trace.
    pub samples: usize,
    /// Sample interval, microseconds.
    pub interval_us: u32,
    /// Smallest and largest finite sample over all traces (`None`: none is finite).
    pub range: Option<(f32, f32)>,
    /// Samples that are NaN or infinite.
    pub non_finite: usize,
    /// The trace-header bytes of the inline and crossline numbers.
    pub keys: Keys,
}

/// Read the headers and every trace of SEG-Y bytes (`path` names the file in errors).
pub fn gathers(path: &Path, bytes: &[u8], keys: KeyBytes) -> Result<Gathers, VolumeError> {
    let Headers {
        layout: l,
        revision,
        interval_us,
        ..
    } = headers_with_keys(path, bytes, keys)?;
    let mut cells: HashMap<(i32, i32), usize> = HashMap::new();
    let mut offsets: BTreeMap<i32, usize> = BTreeMap::new();
    let (mut il, mut xl) = ((i32::MAX, i32::MIN), (i32::MAX, i32::MIN));
    let mut range: Option<(f32, f32)> = None;
    let mut non_finite = 0;
    let width = l.format.bytes();
    for t in 0..l.traces {
        let h = l.first_trace + t * l.trace_len;
        *offsets
            .entry(super::header_i32(bytes, h + 36, l.big))
            .or_default() += 1;
        let key = l.keys.read(&bytes[h..h + TRACE_HEADER], l.big);
        *cells.entry(key).or_default() += 1;
        il = (il.0.min(key.0), il.1.max(key.0));
        xl = (xl.0.min(key.1), xl.1.max(key.1));
        for s in 0..l.samples {
            let v = l
                .format
                .decode(&bytes[h + TRACE_HEADER + s * width..], l.big);
            if v.is_finite() {
                range = Some(range.map_or((v, v), |(a, b)| (a.min(v), b.max(v))));
            } else {
                non_finite += 1;
            }
        }
    }
    let per_gather = cells
        .values()
        .fold((usize::MAX, 0), |(a, b), &n| (a.min(n), b.max(n)));
    Ok(Gathers {
        revision,
        format: l.format,
        big_endian: l.big,
        traces: l.traces,
        gathers: cells.len(),
        per_gather,
        offsets: offsets.into_iter().collect(),
        inlines: il,
        crosslines: xl,
        samples: l.samples,
        interval_us,
        range,
        non_finite,
        keys: l.keys,
    })
}

impl Gathers {
    /// More than one trace at some inline/crossline position.
    pub fn is_prestack(&self) -> bool {
        self.per_gather.1 > 1
    }

    /// What `arbvis inspect` prints for a pre-stack file, one item per line; `path` is
    /// the file as a scene would name it.
    pub fn describe(&self, path: &Path) -> String {
        let shown: Vec<String> = self
            .offsets
            .iter()
            .take(12)
            .map(|(o, n)| format!("{o} ({n} traces)"))
            .collect();
        let more = self.offsets.len().saturating_sub(12);
        let per = if self.per_gather.0 == self.per_gather.1 {
            self.per_gather.0.to_string()
        } else {
            format!("{} to {}", self.per_gather.0, self.per_gather.1)
        };
        let values = match self.range {
            Some((lo, hi)) => format!("[{lo}, {hi}]"),
            None => "no finite sample".into(),
        };
        let first = self.offsets.first().map_or(0, |o| o.0);
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        format!(
            "format: SEG-Y rev {}.{}, pre-stack\nsample type: {}\nendianness: {}\ntraces: {}\ngathers: {} (inline/crossline positions, {}), {per} traces each\ninlines: {}..={}\ncrosslines: {}..={}\noffsets (trace bytes 37-40): {} value{}: {}{}\nsamples: {} per trace, interval {} us, 0..={} ms\nvalues: {values} over all traces{}\na scene reads one offset with volume = {{ segy = {{ path = \"{name}\", prestack = {{ offset = {first} }} }} }}, or the mean of each gather with prestack = \"stack\"\n",
            self.revision.0,
            self.revision.1,
            self.format.name(),
            if self.big_endian { "big-endian" } else { "little-endian" },
            self.traces,
            self.gathers,
            self.keys.describe(),
            self.inlines.0,
            self.inlines.1,
            self.crosslines.0,
            self.crosslines.1,
            self.offsets.len(),
            if self.offsets.len() == 1 { "" } else { "s" },
            shown.join(", "),
            if more > 0 { format!(" and {more} more") } else { String::new() },
            self.samples,
            self.interval_us,
            self.samples.saturating_sub(1) as f64 * self.interval_us as f64 / 1000.0,
            if self.non_finite > 0 {
                format!(", {} NaN or infinite samples", self.non_finite)
            } else {
                String::new()
            },
        )
    }
}
