//! The volume's three axes in the data's own numbers, for the viewer's box labels and
//! sections and the axes of offscreen pictures: SEG-Y gives inline and crossline numbers from the trace headers and time in
//! ms from the sample interval; NIfTI gives millimetres from `pixdim`; raw volumes their
//! scene spacing; the synthetic cube sample / crossline / inline indices.
//!
//! Decisions: the primary attribute's source names the axes (all attributes share one
//! grid). The SEG-Y file is read once more for its headers (the renderer keeps only the
//! quantized voxels); any failure, or a grid that differs from the rendered one, falls back
//! to plain `i`, `j`, `k` indices rather than stopping the viewer. Depth-domain SEG-Y is
//! not told apart from time (the header field that would say so is rarely set): the
//! vertical axis is labelled `time (ms)`.

use std::path::Path;

use crate::volume::segy::{self, ReadOptions};
use crate::volume::{nifti_file, Limits, VolumeSource};

/// The two axes a section at fixed `axis` shows: (across, down).
pub fn section_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2), // time slice: crossline across, inline down
        1 => (2, 0), // crossline section: inline across, time down
        _ => (1, 0), // inline section: crossline across, time down
    }
}

/// The section at `index` along `axis` of a `dims` grid as it shows it: its size (across,
/// down) and its voxels `[i, j, k]`, across fastest, then down ([`section_axes`]).
pub fn section_voxels(
    dims: [usize; 3],
    axis: usize,
    index: usize,
) -> ([usize; 2], impl Iterator<Item = [usize; 3]>) {
    let (u, w) = section_axes(axis);
    let (nu, nw) = (dims[u], dims[w]);
    let voxels = (0..nw).flat_map(move |y| {
        (0..nu).map(move |x| {
            let mut ijk = [0usize; 3];
            ijk[axis] = index;
            ijk[u] = x;
            ijk[w] = y;
            ijk
        })
    });
    ([nu, nw], voxels)
}

/// How an axis numbers its voxels.
#[derive(Debug, Clone, PartialEq)]
pub enum Numbers {
    /// `start + index * step`.
    Linear {
        /// Value at index 0.
        start: f64,
        /// Change per voxel.
        step: f64,
    },
    /// One number per voxel (SEG-Y inline and crossline numbers).
    Listed(Vec<f64>),
    /// A continuous span of file coordinates (a mesh's or a cloud's box): `lo` on the
    /// box's low face, `hi` on its high face.
    Span {
        /// The coordinate at the low face.
        lo: f64,
        /// The coordinate at the high face.
        hi: f64,
    },
}

/// A tick on an axis: where along the box's edge (0 at the low face, 1 at the high
/// face) and its label.
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    /// Fraction of the edge, 0..=1.
    pub at: f64,
    /// The number written there.
    pub label: String,
}

/// One axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// What it is (`inline`, `time (ms)`, `i (mm)`, ...).
    pub name: String,
    /// Voxel count.
    pub len: usize,
    /// Its numbers.
    pub numbers: Numbers,
}

impl Axis {
    /// The number at voxel `index` (clamped into the axis).
    pub fn value(&self, index: usize) -> f64 {
        let index = index.min(self.len.saturating_sub(1));
        match &self.numbers {
            Numbers::Linear { start, step } => start + index as f64 * step,
            Numbers::Listed(v) => v.get(index).copied().unwrap_or(index as f64),
            Numbers::Span { lo, hi } => {
                let n = self.len.saturating_sub(1).max(1) as f64;
                lo + (hi - lo) * index as f64 / n
            }
        }
    }

    /// About `count` ticks: at voxel centres for voxel axes ([`Axis::tick_indices`]),
    /// at round numbers (1, 2 or 5 times a power of ten apart) for a span.
    pub fn ticks(&self, count: usize) -> Vec<Tick> {
        match self.numbers {
            Numbers::Span { lo, hi } => span_ticks(lo, hi, count),
            _ => self
                .tick_indices(count)
                .into_iter()
                .map(|i| Tick {
                    at: (i as f64 + 0.5) / self.len.max(1) as f64,
                    label: self.label(i),
                })
                .collect(),
        }
    }

    /// The number at `index`, written briefly.
    pub fn label(&self, index: usize) -> String {
        let v = self.value(index);
        if v.fract() == 0.0 && v.abs() < 1e9 {
            format!("{}", v as i64)
        } else {
            format!("{v:.1}")
        }
    }

    /// About `count` voxel indices spread evenly from the first to the last.
    pub fn tick_indices(&self, count: usize) -> Vec<usize> {
        let last = self.len.saturating_sub(1);
        let count = count.clamp(2, self.len.max(2));
        let mut t: Vec<usize> = (0..count)
            .map(|n| ((n * last) as f64 / (count - 1) as f64).round() as usize)
            .collect();
        t.dedup();
        t
    }
}

/// Round numbers from `lo` to `hi` (and up to half a percent of the span beyond), about
/// `count` of them, labelled with the decimals their step needs.
fn span_ticks(lo: f64, hi: f64, count: usize) -> Vec<Tick> {
    let (a, b) = (lo.min(hi), lo.max(hi));
    let width = b - a;
    if !(width.is_finite() && width > 0.0) {
        return vec![Tick {
            at: 0.5,
            label: number(lo, 0),
        }];
    }
    let raw = width / count.max(2) as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * power);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    // Round numbers within half a percent beyond the ends count (a cloud whose lowest
    // point is -3999.9 m is labelled -4000).
    let slack = width * 0.005;
    let first = ((a - slack) / step).ceil() as i64;
    let last = ((b + slack) / step).floor() as i64;
    (first..=last)
        .map(|k| {
            let v = k as f64 * step;
            Tick {
                at: (v - lo) / (hi - lo),
                label: number(v, decimals),
            }
        })
        .collect()
}

/// `v` with `decimals` decimals, never `-0`.
fn number(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A continuous axis named `name` from `lo` to `hi`.
pub fn span(name: &str, lo: f64, hi: f64) -> Axis {
    Axis {
        name: name.to_string(),
        len: 2,
        numbers: Numbers::Span { lo, hi },
    }
}

fn indices(name: &str, len: usize) -> Axis {
    Axis {
        name: name.to_string(),
        len,
        numbers: Numbers::Linear {
            start: 0.0,
            step: 1.0,
        },
    }
}

fn linear(name: &str, len: usize, step: f64) -> Axis {
    Axis {
        name: name.to_string(),
        len,
        numbers: Numbers::Linear { start: 0.0, step },
    }
}

/// The axes of a volume of `dims` read from `source` (relative paths from `base`).
pub fn describe(source: &VolumeSource, base: &Path, dims: [usize; 3]) -> [Axis; 3] {
    let plain = || {
        [
            indices("i", dims[0]),
            indices("j", dims[1]),
            indices("k", dims[2]),
        ]
    };
    match source {
        VolumeSource::Segy(s) => {
            let options = ReadOptions {
                limits: Limits::default(),
                prestack: s.prestack,
                keys: s.keys,
            };
            match segy::read(&base.join(&s.path), &options) {
                Ok(cube) if cube.volume.dims == dims => segy_axes(&cube),
                _ => plain(),
            }
        }
        // A survey handed over in memory: its axes by index (sample fastest).
        VolumeSource::Memory(_) => [
            indices("sample", dims[0]),
            indices("crossline", dims[1]),
            indices("inline", dims[2]),
        ],
        VolumeSource::Nifti(p) => match nifti_file::read_header(&base.join(p)) {
            Ok(h) if h.dims == dims => {
                [0, 1, 2].map(|a| linear(["i (mm)", "j (mm)", "k (mm)"][a], dims[a], h.spacing[a]))
            }
            _ => plain(),
        },
        VolumeSource::Raw(spec) => [0, 1, 2].map(|a| {
            let s = spec.spacing[a];
            if s.is_finite() && s > 0.0 && s != 1.0 {
                linear(["i", "j", "k"][a], dims[a], s)
            } else {
                indices(["i", "j", "k"][a], dims[a])
            }
        }),
        VolumeSource::Synthetic(_) | VolumeSource::Store(_) => [
            indices("sample", dims[0]),
            indices("crossline", dims[1]),
            indices("inline", dims[2]),
        ],
    }
}

/// The axes of a store's window: the sample axis as the store numbers it (SEG-Y time in
/// ms, an MDIO dataset's time or depth), crossline and inline numbers from the source's
/// first and step; plain indices where it gave none.
pub fn store_axes(meta: &crate::store::meta::StoreMeta, window: [[usize; 3]; 2]) -> [Axis; 3] {
    let len = |a: usize| window[1][a].saturating_sub(window[0][a]);
    let numbered = |name: &str, a: usize, start: f64, step: f64| Axis {
        name: name.to_string(),
        len: len(a),
        numbers: Numbers::Linear {
            start: start + window[0][a] as f64 * step,
            step,
        },
    };
    let s = &meta.source;
    let samples = s.sample_axis();
    let line = |name: &str, plain: &str, a: usize, first_step: Option<[i64; 2]>| match first_step {
        Some([first, step]) => numbered(name, a, first as f64, step as f64),
        None => numbered(plain, a, 0.0, 1.0),
    };
    let plain = samples.unit.is_empty() && s.inlines.is_none() && s.crosslines.is_none();
    let (i, j, k) = if plain {
        ("i".to_string(), "j", "k")
    } else {
        (samples.label(), "crossline", "inline")
    };
    [
        numbered(&i, 0, samples.first, samples.step),
        line("crossline", j, 1, s.crosslines),
        line("inline", k, 2, s.inlines),
    ]
}

/// A SEG-Y cube's axes: time in ms from its sample interval, its crossline and inline
/// numbers from the trace headers.
pub fn segy_axes(cube: &segy::SegyCube) -> [Axis; 3] {
    let dims = cube.volume.dims;
    [
        linear("time (ms)", dims[0], cube.interval_us as f64 / 1000.0),
        Axis {
            name: "crossline".into(),
            len: dims[1],
            numbers: Numbers::Listed(cube.crosslines.iter().map(|&v| v as f64).collect()),
        },
        Axis {
            name: "inline".into(),
            len: dims[2],
            numbers: Numbers::Listed(cube.inlines.iter().map(|&v| v as f64).collect()),
        },
    ]
}

/// Read `source` (relative paths from `base`, within `limits`) and its axes in the data's
/// own numbers, a SEG-Y file once.
pub fn load_with_axes(
    source: &VolumeSource,
    base: &Path,
    limits: &Limits,
) -> Result<(crate::volume::Volume, [Axis; 3]), crate::volume::VolumeError> {
    if let VolumeSource::Segy(s) = source {
        let options = ReadOptions {
            limits: *limits,
            prestack: s.prestack,
            keys: s.keys,
        };
        let cube = segy::read(&base.join(&s.path), &options)?;
        let axes = segy_axes(&cube);
        return Ok((cube.volume, axes));
    }
    let volume = source.load(base, limits)?;
    let axes = describe(source, base, volume.dims);
    Ok((volume, axes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_ticks() {
        let a = Axis {
            name: "inline".into(),
            len: 4,
            numbers: Numbers::Listed(vec![111.0, 112.0, 113.0, 115.0]),
        };
        assert_eq!(a.label(3), "115");
        assert_eq!(a.value(99), 115.0, "clamped");
        assert_eq!(a.tick_indices(3), vec![0, 2, 3]);
        let t = linear("time (ms)", 75, 4.0);
        assert_eq!(t.label(74), "296");
        assert_eq!(t.tick_indices(5), vec![0, 19, 37, 56, 74]);
        // Ticks at voxel centres: voxel 74 of 75 is 74.5 / 75 along the edge.
        let last = t.ticks(5).pop().unwrap();
        assert_eq!((last.at, last.label.as_str()), (74.5 / 75.0, "296"));
        assert_eq!(linear("x", 3, 0.25).label(1), "0.2");
        assert_eq!(indices("i", 1).tick_indices(5), vec![0]);
    }

    #[test]
    fn spans_tick_at_round_numbers() {
        let labels =
            |a: &Axis, n| -> Vec<String> { a.ticks(n).into_iter().map(|t| t.label).collect() };
        // autzen's x in feet: 636,990 .. 638,982 in about 4 ticks: 500 apart.
        let x = span("x (ft)", 636_990.0, 638_982.0);
        assert_eq!(labels(&x, 4), ["637000", "637500", "638000", "638500"]);
        let t = &x.ticks(4)[0];
        assert!((t.at - 10.0 / 1992.0).abs() < 1e-12, "{t:?}");
        // A section's depth, -4000 .. 0 m: five ticks 1000 apart, no "-0".
        let z = span("z (m)", -4000.0, 0.0);
        assert_eq!(labels(&z, 4), ["-4000", "-3000", "-2000", "-1000", "0"]);
        // Small spans get decimals; a reversed span runs from its low face.
        let s = span("s", 0.25, 0.0);
        assert_eq!(labels(&s, 2), ["0.0", "0.2"]);
        // 0.2 lies 0.05 from the high face: a fifth of the way from 0.25 (rounding only).
        assert!((s.ticks(2)[1].at - 0.2).abs() < 1e-12);
        // Round numbers just beyond the ends count: -3999.9 .. -0.1 has -4000 and 0.
        let z = span("z (m)", -3999.9, -0.1);
        assert_eq!(labels(&z, 2), ["-4000", "-2000", "0"]);
        assert!(z.ticks(2)[0].at < 0.0 && z.ticks(2)[0].at > -1e-4);
        // An empty span has one tick in the middle.
        assert_eq!(
            span("e", 3.0, 3.0).ticks(4),
            vec![Tick {
                at: 0.5,
                label: "3".into()
            }]
        );
    }

    #[test]
    fn synthetic_and_missing_files() {
        let s = VolumeSource::Synthetic(Default::default());
        let a = describe(&s, Path::new("."), [64, 32, 16]);
        assert_eq!(a.map(|a| a.name), ["sample", "crossline", "inline"]);
        let missing = VolumeSource::Nifti("no/such.nii".into());
        let a = describe(&missing, Path::new("."), [2, 3, 4]);
        assert_eq!(a.map(|a| a.name), ["i", "j", "k"], "falls back to indices");
    }

    #[test]
    fn segy_axes_from_f3() {
        let path = arbvis_core::input::data_file("seismic/f3.sgy");
        let source = VolumeSource::Segy(segy::SegySource::new(path));
        let a = describe(&source, Path::new("."), [75, 18, 23]);
        assert_eq!(a[0].name, "time (ms)");
        assert_eq!(a[0].label(74), "296", "75 samples at 4 ms");
        assert_eq!(
            (a[1].label(0), a[1].label(17)),
            ("875".into(), "892".into())
        );
        assert_eq!(
            (a[2].label(0), a[2].label(22)),
            ("111".into(), "133".into())
        );
        // A grid that is not the file's falls back to indices.
        assert_eq!(describe(&source, Path::new("."), [75, 18, 22])[2].name, "k");
    }
}
