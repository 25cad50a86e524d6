//! A section layer's slider over its survey's numbers: the survey's axes read once per
//! survey (a store's metadata, or the file) and kept in egui's memory, each cut's first
//! and last number and step.

use std::path::Path;
use std::sync::Arc;

use arbvis_techniques::techniques::section::{prepare::survey_axes, SectionScene};

use super::widgets::Widgets;

/// One axis's numbers: low, high and the step between neighbours (0 for time and depth,
/// which a section takes anywhere between samples).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// The lowest number.
    pub low: f64,
    /// The highest number.
    pub high: f64,
    /// The step a line number moves by.
    pub step: f64,
}

/// The ranges of the survey's sample, crossline and inline axes, None where it does not
/// read.
pub fn ranges(ctx: &egui::Context, scene: &SectionScene, base: &Path) -> Option<[Range; 3]> {
    let key = format!("{:?} {}", scene.volume, base.display());
    let id = egui::Id::NULL.with(("section ranges", key));
    if let Some(kept) = ctx.data(|d| d.get_temp::<Arc<Option<[Range; 3]>>>(id)) {
        return *kept;
    }
    let found = survey_axes(scene, base).ok().map(|axes| {
        std::array::from_fn(|a| {
            let axis = &axes[a];
            let (first, last) = (axis.value(0), axis.value(axis.len.saturating_sub(1)));
            let step = match a {
                0 => 0.0,
                _ if axis.len > 1 => ((last - first) / (axis.len - 1) as f64).abs(),
                _ => 1.0,
            };
            Range {
                low: first.min(last),
                high: first.max(last),
                step,
            }
        })
    });
    ctx.data_mut(|d| d.insert_temp(id, Arc::new(found)));
    found
}

/// A slider for `number` over `range`, recorded as `label`; a line number kept on the
/// survey's steps. True when it changed.
pub fn slider(
    ui: &mut egui::Ui,
    widgets: &mut Widgets,
    label: &str,
    number: &mut f64,
    range: Range,
) -> bool {
    let changed = widgets.slider(ui, label, number, range.low..=range.high, label, false);
    if changed && range.step > 0.0 {
        *number = range.low + ((*number - range.low) / range.step).round() * range.step;
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_f3_crop_gives_its_numbers() {
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/seismic");
        let scene: SectionScene =
            toml::from_str("volume = { segy = \"f3.sgy\" }\ninline = 120\n").unwrap();
        let ctx = egui::Context::default();
        let r = ranges(&ctx, &scene, &base).expect("F3 reads");
        // inspect: samples 0..=296 ms, crosslines 875..=892, inlines 111..=133, step 1.
        let want = [(0.0, 296.0, 0.0), (875.0, 892.0, 1.0), (111.0, 133.0, 1.0)];
        for (got, (low, high, step)) in r.iter().zip(want) {
            assert_eq!((got.low, got.high, got.step), (low, high, step));
        }
        // A survey that does not read has none; the first's are kept in egui's memory.
        let missing: SectionScene =
            toml::from_str("volume = { segy = \"nowhere.sgy\" }\ninline = 120\n").unwrap();
        assert_eq!(ranges(&ctx, &missing, &base), None);
        assert_eq!(ranges(&ctx, &scene, &base), Some(r));
    }
}
