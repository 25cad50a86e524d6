//! A colour table's editor: the table's colours as swatches, the histogram of the
//! attribute's quantized values behind, and its alpha drawn as a curve the mouse edits.
//!
//! Mouse: a click on empty space adds a point there; dragging a point moves it (between its
//! neighbours; alpha 0..1); a right click or a double click on a point removes it. The
//! plot's x is the table position 0..1 (quantized value / 255), its y the alpha (1 at the
//! top), so a script's `click-at LABEL FX FY` adds the point `[FX, 1 - FY]`.
//!
//! Decisions: when the scene has no alpha curve (the table's own alpha applies) the first
//! edit starts one from the table's own alpha, simplified to the few points that stay
//! within half an 8-bit level of it, so the picture does not jump. Positions and alphas
//! are rounded to 1/1000 (they are written to scenes). The histogram is drawn on a square-
//! root scale (the zero level of seismic amplitudes would flatten everything else).

use egui::{Color32, Pos2, Rect, Sense, Stroke, Ui, Vec2};

use super::widgets::Widgets;
use arbvis_core::colortable::ColorTable;

/// Points closer than this (points) to the pointer are picked.
const PICK: f32 = 8.0;
/// Height of the swatch strip under the plot.
const SWATCH: f32 = 12.0;

fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// The table's own alpha as a short curve (Douglas-Peucker within half a level).
pub fn curve_from_table(table: &ColorTable) -> Vec<[f64; 2]> {
    let alpha: Vec<f64> = table.entries.iter().map(|e| e[3] as f64 / 255.0).collect();
    let mut keep = vec![false; alpha.len()];
    keep[0] = true;
    keep[alpha.len() - 1] = true;
    let mut stack = vec![(0usize, alpha.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let (mut worst, mut at) = (0.0, a);
        for k in a + 1..b {
            let t = (k - a) as f64 / (b - a) as f64;
            let line = alpha[a] + t * (alpha[b] - alpha[a]);
            let d = (alpha[k] - line).abs();
            if d > worst {
                (worst, at) = (d, k);
            }
        }
        if worst > 0.5 / 255.0 {
            keep[at] = true;
            stack.push((a, at));
            stack.push((at, b));
        }
    }
    keep.iter()
        .enumerate()
        .filter(|(_, &k)| k)
        .map(|(k, _)| [round3(k as f64 / 255.0), round3(alpha[k])])
        .collect()
}

/// Height in texels of a histogram image.
const HISTOGRAM_ROWS: usize = 64;

/// A 256 x 1 texture of a table's colours (opaque), for colour strips under editors and
/// in legends.
pub fn colour_strip(
    ctx: &egui::Context,
    name: impl Into<String>,
    entries: &[[u8; 4]],
    options: egui::TextureOptions,
) -> egui::TextureHandle {
    let pixels = entries
        .iter()
        .map(|e| egui::Color32::from_rgb(e[0], e[1], e[2]))
        .collect();
    ctx.load_texture(name, egui::ColorImage::new([256, 1], pixels), options)
}

/// A histogram of 256 counts as a 256-wide image of grey bars on a clear background
/// (square-root scale), drawn behind the curve as one texture.
pub fn histogram_image(counts: &[u32]) -> egui::ColorImage {
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f32;
    let heights: Vec<usize> = counts
        .iter()
        .map(|&c| ((c as f32 / top).sqrt() * HISTOGRAM_ROWS as f32).round() as usize)
        .collect();
    let mut pixels = vec![Color32::TRANSPARENT; counts.len() * HISTOGRAM_ROWS];
    for (x, &h) in heights.iter().enumerate() {
        for y in HISTOGRAM_ROWS - h.min(HISTOGRAM_ROWS)..HISTOGRAM_ROWS {
            pixels[y * counts.len() + x] = Color32::from_gray(70);
        }
    }
    egui::ColorImage::new([counts.len(), HISTOGRAM_ROWS], pixels)
}

/// What the editor did this frame.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CurveEdit {
    /// The curve changed.
    pub changed: bool,
}

/// Draw the editor for `curve` (the scene's alpha points) over `table`'s swatches (the
/// texture `colours`) and the `histogram` image ([`histogram_image`]); recorded as
/// `label` (the plot area).
#[allow(clippy::too_many_arguments)]
pub fn editor(
    ui: &mut Ui,
    widgets: &mut Widgets,
    label: &str,
    curve: &mut Vec<[f64; 2]>,
    table: &ColorTable,
    colours: egui::TextureId,
    histogram: Option<egui::TextureId>,
    size: Vec2,
) -> CurveEdit {
    let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
    let plot = Rect::from_min_max(rect.min, Pos2::new(rect.max.x, rect.max.y - SWATCH - 2.0));
    let swatch = Rect::from_min_max(Pos2::new(rect.min.x, rect.max.y - SWATCH), rect.max);
    widgets.record(ui, label, plot, ui.is_enabled());
    if widgets.focus.as_deref() == Some(label) && !ui.clip_rect().contains_rect(rect) {
        response.scroll_to_me(Some(egui::Align::Center));
    }
    let to_screen = |p: [f64; 2]| {
        Pos2::new(
            plot.left() + p[0] as f32 * plot.width(),
            plot.bottom() - p[1] as f32 * plot.height(),
        )
    };
    let from_screen = |s: Pos2| {
        [
            round3(((s.x - plot.left()) / plot.width()).clamp(0.0, 1.0) as f64),
            round3(((plot.bottom() - s.y) / plot.height()).clamp(0.0, 1.0) as f64),
        ]
    };
    let nearest = |curve: &[[f64; 2]], s: Pos2| {
        curve
            .iter()
            .enumerate()
            .map(|(i, p)| (i, to_screen(*p).distance(s)))
            .filter(|(_, d)| *d <= PICK)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };

    let mut edit = CurveEdit::default();
    let drag_id = response.id.with("dragged point");
    if response.drag_started() {
        let origin = ui.input(|i| i.pointer.press_origin());
        if let Some(i) = origin.and_then(|o| nearest(curve, o)) {
            ui.data_mut(|d| d.insert_temp(drag_id, i));
        }
    }
    let dragged: Option<usize> = ui.data(|d| d.get_temp(drag_id));
    if let (Some(i), Some(pos)) = (dragged, response.interact_pointer_pos()) {
        if response.dragged() && i < curve.len() {
            let mut p = from_screen(pos);
            let lo = if i > 0 { curve[i - 1][0] } else { 0.0 };
            let hi = curve.get(i + 1).map_or(1.0, |q| q[0]);
            p[0] = p[0].clamp(lo, hi);
            if curve[i] != p {
                curve[i] = p;
                edit.changed = true;
            }
        }
    }
    if response.drag_stopped() {
        ui.data_mut(|d| d.remove::<usize>(drag_id));
    }
    if let Some(pos) = response.interact_pointer_pos() {
        let remove = response.secondary_clicked() || response.double_clicked();
        if remove {
            if let Some(i) = nearest(curve, pos) {
                curve.remove(i);
                edit.changed = true;
            }
        } else if response.clicked() && nearest(curve, pos).is_none() {
            if curve.is_empty() {
                *curve = curve_from_table(table);
            }
            let p = from_screen(pos);
            let at = curve.partition_point(|q| q[0] < p[0]);
            if curve.get(at).is_some_and(|q| q[0] == p[0]) {
                curve[at] = p;
            } else {
                curve.insert(at, p);
            }
            edit.changed = true;
        }
    }
    if edit.changed {
        widgets.hit(label);
    }

    // Drawing: background, histogram, swatches, the table's alpha, the points.
    let painter = ui.painter_at(rect);
    painter.rect_filled(plot, 2.0, Color32::from_gray(24));
    if let Some(h) = histogram {
        painter.image(
            h,
            plot,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
    }
    painter.image(
        colours,
        swatch,
        Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
        Color32::WHITE,
    );
    let alpha: Vec<Pos2> = table
        .entries
        .iter()
        .enumerate()
        .map(|(k, e)| to_screen([k as f64 / 255.0, e[3] as f64 / 255.0]))
        .collect();
    let colour = if curve.is_empty() {
        Color32::from_gray(150)
    } else {
        Color32::WHITE
    };
    painter.line(alpha, Stroke::new(1.5, colour));
    for (i, p) in curve.iter().enumerate() {
        let r = if dragged == Some(i) { 5.0 } else { 4.0 };
        painter.circle_filled(to_screen(*p), r, Color32::from_rgb(255, 200, 60));
    }
    let hint = if curve.is_empty() {
        "table alpha: click to edit"
    } else {
        "click: add · drag: move · right/double click: remove"
    };
    // Wrapped to the plot's width: a narrow plot (the cell-projection panel's) would
    // cut a line it cannot hold.
    let grey = Color32::from_gray(160);
    let galley = painter.layout(
        hint.to_string(),
        super::layout::overlay_font(super::layout::MIN_TEXT),
        grey,
        (plot.width() - 8.0).max(40.0),
    );
    painter.galley(plot.left_top() + Vec2::new(4.0, 2.0), galley, grey);
    let _ = response.on_hover_text(label);
    edit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_alpha_becomes_a_short_curve_within_half_a_level() {
        for name in ["seismic", "grey", "magma"] {
            let table = ColorTable::builtin(name).unwrap();
            let curve = curve_from_table(&table);
            assert!(curve.len() <= 4, "{name}: {curve:?}");
            let mut rebuilt = table.clone();
            rebuilt.set_alpha_curve(&curve).unwrap();
            for (a, b) in table.entries.iter().zip(&rebuilt.entries) {
                assert!(
                    (a[3] as i32 - b[3] as i32).abs() <= 1,
                    "{name}: {a:?} vs {b:?}"
                );
            }
        }
        let seismic = curve_from_table(&ColorTable::builtin("seismic").unwrap());
        let image = histogram_image(&[0, 4, 1, 16]);
        assert_eq!(image.size, [4, HISTOGRAM_ROWS]);
        let column = |x: usize| {
            (0..HISTOGRAM_ROWS)
                .filter(|y| image.pixels[y * 4 + x] != Color32::TRANSPARENT)
                .count()
        };
        assert_eq!(
            [column(0), column(1), column(2), column(3)],
            [0, 32, 16, 64]
        );
        assert_eq!(seismic.first(), Some(&[0.0, 1.0]));
        assert_eq!(seismic.last(), Some(&[1.0, 1.0]));
    }
}
