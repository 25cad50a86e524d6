//! Gridding SEG-Y traces by their inline/crossline numbers (trace bytes 189-196), in any
//! trace order. Post-stack files hold one trace per cell. Pre-stack files hold several
//! (one per source-receiver offset, trace bytes 37-40); the scene then picks one offset
//! (`prestack = { offset = 400 }`) or stacks them (`prestack = "stack"`: the mean of a
//! cell's traces, sample by sample, as segyio's stacking examples do). Without a choice a
//! pre-stack file is refused, naming the offsets it holds.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::keys::{KeyBytes, Keys};
use super::{SampleFormat, TRACE_HEADER};
use crate::volume::{Limits, VolumeError};

/// What to do with several traces at one inline/crossline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Prestack {
    /// Refuse (a post-stack reader's answer): the error lists the offsets found.
    #[default]
    Refuse,
    /// Keep only the traces of this offset (trace bytes 37-40).
    Offset(i32),
    /// Average every trace of a cell.
    Stack,
}

/// How to read a SEG-Y file: the limits the volume must fit, the pre-stack choice, and
/// the trace-header bytes of the inline and crossline numbers.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReadOptions {
    /// Checked before the samples are decoded.
    pub limits: Limits,
    /// Several traces per cell.
    pub prestack: Prestack,
    /// The inline and crossline bytes a scene names (else detected).
    pub keys: KeyBytes,
}

/// Where the traces sit in the file.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub first_trace: usize,
    pub trace_len: usize,
    pub traces: usize,
    pub samples: usize,
    pub format: SampleFormat,
    pub big: bool,
    /// Samples per trace as the binary header declares them (bytes 3221-3222).
    pub header_samples: usize,
    /// The trace-header bytes of the inline and crossline numbers.
    pub keys: Keys,
}

/// The gridded samples.
pub(super) struct Gridded {
    pub dims: [usize; 3],
    pub values: Vec<f32>,
    pub inlines: Vec<i32>,
    pub crosslines: Vec<i32>,
    /// The distinct offsets the file holds (one entry, usually 0, for post-stack files).
    pub offsets: Vec<i32>,
    /// The header offsets of the traces at the grid's corners (inline index, crossline
    /// index) = (0, 0), (0, last), (last, 0), for the survey's geometry.
    pub corners: [usize; 3],
}

/// Offsets as a short list for messages.
fn list(values: &BTreeSet<i32>) -> String {
    let shown: Vec<String> = values.iter().take(12).map(i32::to_string).collect();
    let more = values.len().saturating_sub(12);
    if more > 0 {
        format!("{} and {more} more", shown.join(", "))
    } else {
        shown.join(", ")
    }
}

pub(super) fn grid(
    path: &Path,
    bytes: &[u8],
    l: &Layout,
    options: &ReadOptions,
) -> Result<Gridded, VolumeError> {
    let header = |t: usize| l.first_trace + t * l.trace_len;
    let mut cells: BTreeMap<(i32, i32), Vec<usize>> = BTreeMap::new();
    let mut offsets = BTreeSet::new();
    for t in 0..l.traces {
        let h = header(t);
        let offset = super::header_i32(bytes, h + 36, l.big);
        offsets.insert(offset);
        if let Prestack::Offset(o) = options.prestack {
            if offset != o {
                continue;
            }
        }
        let key = l.keys.read(&bytes[h..h + TRACE_HEADER], l.big);
        cells.entry(key).or_default().push(t);
    }
    if cells.is_empty() {
        return Err(VolumeError::Unsupported {
            path: path.into(),
            message: format!(
                "no trace has the offset the scene asks for ({:?}); offsets in the file (trace bytes 37-40): {}",
                options.prestack,
                list(&offsets)
            ),
        });
    }
    if options.prestack != Prestack::Stack {
        if let Some((key, ts)) = cells.iter().find(|(_, ts)| ts.len() > 1) {
            let hint = if offsets.len() > 1 {
                format!(
                    "; it holds offsets {} (trace bytes 37-40): set `prestack = {{ offset = N }}` or `prestack = \"stack\"` on this volume in the scene",
                    list(&offsets)
                )
            } else {
                String::new()
            };
            return Err(VolumeError::Unsupported {
                path: path.into(),
                message: format!(
                    "traces {} and {} (bytes {} and {}) both sit at inline {} crossline {} ({}): a pre-stack or otherwise non-gridded file{hint}",
                    ts[0] + 1,
                    ts[1] + 1,
                    header(ts[0]),
                    header(ts[1]),
                    key.0,
                    key.1,
                    l.keys.describe()
                ),
            });
        }
    }
    let mut inlines: Vec<i32> = cells.keys().map(|k| k.0).collect();
    inlines.dedup();
    let mut crosslines: Vec<i32> = cells.keys().map(|k| k.1).collect();
    crosslines.sort_unstable();
    crosslines.dedup();
    if inlines.len() * crosslines.len() != cells.len() {
        return Err(VolumeError::Unsupported {
            path: path.into(),
            message: format!(
                "{} traces at {} inline/crossline positions do not fill the grid of {} inlines x {} crosslines (inline {}..={}, crossline {}..={}; the numbers at {}): an irregular survey that arbvis cannot grid. The binary header declares {} samples per trace of {} (bytes 3221-3222), so the {} bytes after the headers hold {} traces of {} bytes; if that count looks wrong, the header's sample count is",
                l.traces,
                cells.len(),
                inlines.len(),
                crosslines.len(),
                inlines[0],
                inlines[inlines.len() - 1],
                crosslines[0],
                crosslines[crosslines.len() - 1],
                l.keys.describe(),
                l.header_samples,
                l.format.name(),
                l.traces * l.trace_len,
                l.traces,
                l.trace_len
            ),
        });
    }
    let dims = [l.samples, crosslines.len(), inlines.len()];
    options.limits.check(dims, &path.display().to_string())?;
    let mut values = vec![0f32; l.samples * cells.len()];
    let width = l.format.bytes();
    for (k, &il) in inlines.iter().enumerate() {
        for (j, &xl) in crosslines.iter().enumerate() {
            let traces = &cells[&(il, xl)];
            let out = &mut values[(k * dims[1] + j) * l.samples..][..l.samples];
            for &t in traces {
                let start = header(t) + TRACE_HEADER;
                for (s, v) in out.iter_mut().enumerate() {
                    *v += l.format.decode(&bytes[start + s * width..], l.big);
                }
            }
            if traces.len() > 1 {
                let n = traces.len() as f32;
                out.iter_mut().for_each(|v| *v /= n);
            }
        }
    }
    let corner = |k: usize, j: usize| header(cells[&(inlines[k], crosslines[j])][0]);
    let corners = [
        corner(0, 0),
        corner(0, crosslines.len() - 1),
        corner(inlines.len() - 1, 0),
    ];
    Ok(Gridded {
        dims,
        values,
        inlines,
        crosslines,
        offsets: offsets.into_iter().collect(),
        corners,
    })
}
