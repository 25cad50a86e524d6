//! The volume editor of a cell-projection scene (issue 16, item 6): what is drawn
//! (isosurfaces, volume or both), the transfer function as colour swatches per control
//! point and an opacity curve drawn over the scalar's histogram (the lut 3D panel's curve
//! editor), the unit distance, faithful mode's order (centroid or MPVONC; precise mode's
//! order is exact), precise mode's method and the pre-integrated table's size. Each edit
//! goes through the renderer's `update`, which rebuilds only what changed.
//!
//! Decisions: the curve's x is the normalized scalar and its y the opacity value (per
//! unit distance). A scene whose transfer function is a colour table has no control
//! points; the first curve edit turns the table into points (the table's alpha,
//! simplified as the lut 3D editor does, each point with the table's colour there), so
//! the picture does not jump. A point the curve adds takes the colour the function had
//! at its position; a point moved keeps its colour.

use std::path::Path;

use egui::{TextureHandle, TextureOptions, Vec2};

use super::curve;
use super::widgets::Widgets;
use arbvis_core::colortable::ColorTable;
use arbvis_techniques::techniques::cellproj::transfer::{
    Precise, Sort, Transfer, VolumeSpec, MAX_GRID, MAX_POINTS,
};
use arbvis_techniques::techniques::cellproj::{CellprojScene, Mode};

/// Largest side of the pre-integrated table offered (256² x 256 = 2^24 texels, the most
/// a scene may ask for).
const TABLE_MAX: u32 = 256;

/// The editor's textures, kept between frames.
#[derive(Default)]
pub struct TransferState {
    /// The function's colours as a 256-entry strip, and the entries it was made from.
    colours: Option<(Vec<[u8; 4]>, TextureHandle)>,
    /// The scalar's histogram (made once).
    histogram: Option<TextureHandle>,
}

impl TransferState {
    /// The transfer function's colour strip, once the editor has drawn it (the legend's
    /// colour bar in volume mode).
    pub fn colours(&self) -> Option<egui::TextureId> {
        self.colours.as_ref().map(|(_, t)| t.id())
    }
}

impl std::fmt::Debug for TransferState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TransferState")
            .field("colours", &self.colours.is_some())
            .field("histogram", &self.histogram.is_some())
            .finish()
    }
}

/// The transfer function sampled at the 256 positions `k / 255` as a colour table
/// (opacity value as alpha); `None` when its table cannot be built.
pub fn sampled(spec: &VolumeSpec, base: &Path) -> Option<(Transfer, ColorTable)> {
    let transfer = spec.build(base, 1.0).ok()?;
    let entries = (0..256)
        .map(|k| {
            let v = transfer.at(k as f64 / 255.0);
            v.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
        })
        .collect();
    Some((transfer, ColorTable { entries }))
}

/// The control points after the curve editor turned `old`'s `(s, a)` into `curve`: a
/// moved point keeps its colour, an added or rebuilt one takes `colour_at` its position.
pub fn points_from_curve(
    old: &[[f64; 5]],
    curve: &[[f64; 2]],
    colour_at: impl Fn(f64) -> [f64; 3],
) -> Vec<[f64; 5]> {
    let point = |[s, a]: [f64; 2], c: [f64; 3]| [s, c[0], c[1], c[2], a];
    let same = |p: &[f64; 5], q: &[f64; 2]| p[0] == q[0] && p[4] == q[1];
    let fresh = |q: &[f64; 2]| point(*q, colour_at(q[0]));
    if curve.len() == old.len() {
        return old
            .iter()
            .zip(curve)
            .map(|(p, q)| point(*q, [p[1], p[2], p[3]]))
            .collect();
    }
    if curve.len() == old.len() + 1 {
        let at = (0..old.len())
            .find(|&i| !same(&old[i], &curve[i]))
            .unwrap_or(old.len());
        let mut out = old.to_vec();
        out.insert(at, fresh(&curve[at]));
        return out;
    }
    if curve.len() + 1 == old.len() {
        let at = (0..curve.len())
            .find(|&i| !same(&old[i], &curve[i]))
            .unwrap_or(curve.len());
        let mut out = old.to_vec();
        out.remove(at);
        return out;
    }
    curve.iter().map(fresh).collect()
}

/// Draw the editor; true when the scene changed. `counts` is the scalar's histogram.
pub fn editor(
    ui: &mut egui::Ui,
    scene: &mut CellprojScene,
    base: &Path,
    counts: Option<&[u32]>,
    state: &mut TransferState,
    w: &mut Widgets,
) -> bool {
    let mut changed = false;
    ui.horizontal_wrapped(|ui| {
        ui.label("Draw");
        for (mode, label) in [
            (Mode::Isosurfaces, "isosurfaces"),
            (Mode::Volume, "volume"),
            (Mode::Both, "both"),
        ] {
            let r = ui.radio_value(&mut scene.mode, mode, label);
            changed |= w.add(ui, &format!("Mode {label}"), &r) && r.changed();
        }
    });
    if !scene.mode.volume() {
        return changed;
    }
    let spec = scene.volume.get_or_insert_with(VolumeSpec::default);
    ui.add(
        egui::Label::new("Volume: opacity per unit distance over the scalar's histogram").wrap(),
    );
    let Some((transfer, table)) = sampled(spec, base) else {
        ui.label("the transfer function's table cannot be built");
        return changed;
    };
    let ctx = ui.ctx().clone();
    if state
        .colours
        .as_ref()
        .is_none_or(|(e, _)| *e != table.entries)
    {
        let texture = curve::colour_strip(
            &ctx,
            "transfer colours",
            &table.entries,
            TextureOptions::LINEAR,
        );
        state.colours = Some((table.entries.clone(), texture));
    }
    if state.histogram.is_none() {
        if let Some(counts) = counts {
            let image = curve::histogram_image(counts);
            state.histogram =
                Some(ctx.load_texture("transfer histogram", image, TextureOptions::NEAREST));
        }
    }
    let colours = state.colours.as_ref().map(|(_, t)| t.id());
    let width = ui.available_width().min(230.0);
    if let Some(colours) = colours {
        let mut line: Vec<[f64; 2]> = spec.points.iter().map(|p| [p[0], p[4]]).collect();
        let e = curve::editor(
            ui,
            w,
            "TF opacity",
            &mut line,
            &table,
            colours,
            state.histogram.as_ref().map(|t| t.id()),
            Vec2::new(width, 96.0),
        );
        if e.changed && line.len() <= MAX_POINTS {
            let at = |s: f64| {
                let c = transfer.at(s);
                [c[0], c[1], c[2]].map(|v| (v * 1000.0).round() / 1000.0)
            };
            spec.points = points_from_curve(&spec.points, &line, at);
            changed = true;
        }
    }
    // A swatch per control point, said as such.
    ui.horizontal_wrapped(|ui| {
        ui.label("Point colours");
        for (i, p) in spec.points.iter_mut().enumerate() {
            let mut c = [p[1] as f32, p[2] as f32, p[3] as f32];
            let r = ui.color_edit_button_rgb(&mut c);
            if w.add(ui, &format!("TF point {} colour", i + 1), &r) && r.changed() {
                p[1..4].copy_from_slice(&c.map(f64::from));
                changed = true;
            }
        }
    });
    changed |= settings(ui, spec, w);
    changed
}

/// The volume's settings beside its curve: unit distance, the faithful and precise
/// orders, the table's and the grid's sizes.
fn settings(ui: &mut egui::Ui, spec: &mut VolumeSpec, w: &mut Widgets) -> bool {
    let mut changed = false;
    ui.horizontal_wrapped(|ui| {
        ui.label("Unit distance").on_hover_text(
            "the length (in the mesh's units) over which an opacity of 1 absorbs fully",
        );
        changed |= w.drag_value(
            ui,
            "Unit distance",
            &mut spec.unit_distance,
            1e-4..=1e4,
            0.01,
        );
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("Order (faithful)");
        for (sort, label) in [(Sort::Centroid, "centroid"), (Sort::Mpvonc, "MPVONC")] {
            changed |= w.radio(ui, &format!("Order {label}"), &mut spec.sort, sort);
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("Exact order (precise)");
        for (p, label) in [
            (Precise::Walk, "walk"),
            (Precise::Projected, "projected"),
            (Precise::Table, "table"),
            (Precise::Grid, "grid"),
        ] {
            changed |= w.radio(ui, &format!("Precise {label}"), &mut spec.precise, p);
        }
    });
    let [n, m] = &mut spec.table_size;
    changed |= w.slider(
        ui,
        "Volume table sf sb",
        n,
        2..=TABLE_MAX,
        "table sf, sb",
        true,
    );
    changed |= w.slider(
        ui,
        "Volume table length",
        m,
        2..=TABLE_MAX,
        "table length",
        true,
    );
    if spec.precise == Precise::Grid {
        changed |= w.slider(
            ui,
            "Volume grid points",
            &mut spec.grid,
            2..=MAX_GRID,
            "grid points (longest side)",
            true,
        );
        changed |= w.slider(
            ui,
            "Volume grid steps",
            &mut spec.grid_steps,
            0.25..=16.0,
            "steps per grid spacing",
            true,
        );
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_edits_keep_or_make_colours() {
        let red = |_: f64| [1.0, 0.0, 0.0];
        let old = [[0.0, 0.1, 0.2, 0.3, 0.0], [1.0, 0.7, 0.8, 0.9, 0.6]];
        // Moved: colours kept.
        let moved = points_from_curve(&old, &[[0.0, 0.0], [0.9, 0.4]], red);
        assert_eq!(moved[1], [0.9, 0.7, 0.8, 0.9, 0.4]);
        // Added in the middle: the new point takes the function's colour there.
        let added = points_from_curve(&old, &[[0.0, 0.0], [0.25, 0.5], [1.0, 0.6]], |s| {
            [s, 0.5, 0.0]
        });
        assert_eq!(added[1], [0.25, 0.25, 0.5, 0.0, 0.5]);
        assert_eq!((added[0], added[2]), (old[0], old[1]));
        // Removed: the other keeps its colour.
        assert_eq!(points_from_curve(&old, &[[1.0, 0.6]], red), vec![old[1]]);
        // From a table (no points) to three: each from the function.
        let made = points_from_curve(&[], &[[0.0, 0.0], [0.5, 0.75], [1.0, 1.0]], red);
        assert_eq!(made[1], [0.5, 1.0, 0.0, 0.0, 0.75]);
    }

    #[test]
    fn the_sampled_table_is_the_function() {
        let spec = VolumeSpec {
            points: vec![[0.0, 0.0, 0.0, 1.0, 0.0], [1.0, 1.0, 0.0, 0.0, 0.8]],
            ..VolumeSpec::default()
        };
        let (_, table) = sampled(&spec, Path::new(".")).unwrap();
        // Entry 51 is s = 0.2: colour (0.2, 0, 0.8), opacity 0.16 -> 51, 0, 204, 41.
        assert_eq!(table.entries[51], [51, 0, 204, 41]);
        assert_eq!(table.entries[255], [255, 0, 0, 204]);
    }
}
