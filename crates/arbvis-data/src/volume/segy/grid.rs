//! Gridding SEG-Y traces by their inline/crossline numbers (trace bytes 189-196), in any
//! trace order. Post-stack files hold one trace per cell. Pre-stack files hold several
//! (one per source-receiver offset, trace bytes 37-40); the scene then picks one offset
//! (`prestack = { offset = 400 }`) or stacks them (`prestack = "stack"`: the mean of a
//! cell's traces, sample by sample, as segyio's stacking examples do). Without a choice a
//! pre-stack file is refused, naming the offsets it holds. The grid is the lines the
//! numbers span ([`super::lines`]); a position without a trace is dead (NaN).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::keys::{KeyBytes, Keys};
use super::lines::{Duplicate, GridError, TraceGrid};
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
    /// Dead positions (no trace) are NaN.
    pub values: Vec<f32>,
    /// The lines and, per position, the (first) trace there.
    pub grid: TraceGrid,
    /// The distinct offsets the file holds (one entry, usually 0, for post-stack files).
    pub offsets: Vec<i32>,
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
    let hint = if offsets.len() > 1 {
        format!(
            ": a pre-stack or otherwise non-gridded file; it holds offsets {} (trace bytes 37-40): set `prestack = {{ offset = N }}` or `prestack = \"stack\"` on this volume in the scene",
            list(&offsets)
        )
    } else {
        ": a pre-stack or otherwise non-gridded file".to_string()
    };
    let offset_of = |t: u32| header(t as usize) as u64;
    if options.prestack != Prestack::Stack {
        if let Some((&at, ts)) = cells.iter().find(|(_, ts)| ts.len() > 1) {
            let d = Duplicate {
                first: ts[0] as u32,
                second: ts[1] as u32,
                at,
            };
            return Err(GridError::Duplicate(d).into_volume_error(path, &l.keys, offset_of, &hint));
        }
    }
    let trace_grid = TraceGrid::from_keys(
        cells
            .iter()
            .map(|(&(il, xl), ts)| (il, xl, ts[0] as u32))
            .collect(),
    )
    .map_err(|e| e.into_volume_error(path, &l.keys, offset_of, &hint))
    .map_err(|e| with_count_hint(e, l))?;
    let (inlines, crosslines) = (trace_grid.inlines, trace_grid.crosslines);
    let dims = [l.samples, crosslines.count, inlines.count];
    options.limits.check(dims, &path.display().to_string())?;
    let mut values =
        arbvis_core::budget::vec_for::<f32>(l.samples * trace_grid.positions(), "a SEG-Y volume")
            .map_err(|e| VolumeError::Invalid(format!("{}: {e}", path.display())))?;
    values.resize(l.samples * trace_grid.positions(), f32::NAN);
    let width = l.format.bytes();
    for (&(il, xl), traces) in &cells {
        let (Some(k), Some(j)) = (inlines.index(il), crosslines.index(xl)) else {
            unreachable!("every number is on its axis's lines");
        };
        let out = &mut values[(k * dims[1] + j) * l.samples..][..l.samples];
        out.fill(0.0);
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
    Ok(Gridded {
        dims,
        values,
        grid: trace_grid,
        offsets: offsets.into_iter().collect(),
    })
}

/// `e` with what the binary header's sample count makes of the file, where the numbers
/// were no survey's lines: a wrong count reads every trace header after the first from
/// inside the samples.
pub(crate) fn with_count_hint(e: VolumeError, l: &Layout) -> VolumeError {
    match e {
        VolumeError::Unsupported { path, message } if !message.contains("both sit at") => {
            VolumeError::Unsupported {
                path,
                message: format!(
                    "{message}. The binary header declares {} samples per trace of {} (bytes 3221-3222), so the {} bytes after the headers hold {} traces of {} bytes; if that count looks wrong, the header's sample count is",
                    l.header_samples,
                    l.format.name(),
                    l.traces * l.trace_len,
                    l.traces,
                    l.trace_len
                ),
            }
        }
        other => other,
    }
}
