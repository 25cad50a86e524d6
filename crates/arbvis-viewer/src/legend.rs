//! The legends, in a margin of their own at the 3D view's right (so that no box edge,
//! tick or label of the data ever runs through them): a colour bar per 3D-opacity table
//! with its attribute's range, the transfer function of a cell-projection volume as a
//! colour bar over its scalar's range, the isovalues of cell projection with their colours and
//! values, and the key of a cloud's colours (facies, layers or classes by name, or the
//! property's gradient with its range).
//!
//! Decisions: the margin is at the view's right (legends stacked, as wide as the widest,
//! at most [`MAX_SHARE`] of the view) or along its top (legends side by side, in rows,
//! at most [`MAX_SHARE`] of the height), whichever leaves the 3D picture the longer
//! shorter side: a tall view (a narrow window with the lut 3D panel) puts its colour
//! bars on top. Longer texts are cut with `…`; a key longer than its room is cut with
//! a line saying how many entries are left out. The margin's background is the
//! scene's, so a screenshot shows one picture.

use egui::{Color32, Painter, Pos2, Rect, Stroke, TextureId, Vec2};

use super::data::ViewData;
use super::lut3d;
use super::overlay::{paint_texts, Ink, Measure, Text};
use arbvis_data::points::section::{facies_colour, FACIES_TABLE, PALETTE};
use arbvis_data::points::UNDEFINED_FACIES;
use arbvis_techniques::scene::Scene;
use arbvis_techniques::techniques::cellproj::CellprojScene;
use arbvis_techniques::techniques::cellproj::IsovalueUnits;
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;
pub use arbvis_techniques::techniques::splats::prepare::class_name;
use arbvis_techniques::techniques::splats::prepare::{
    class_colour, COLOR_A, COLOR_B, LAYERS_IN_PALETTE,
};
use arbvis_techniques::techniques::splats::scene::ColourMode;
use arbvis_techniques::techniques::splats::SplatsScene;

/// Padding around and between legends (points).
pub const PAD: f32 = 8.0;
/// Width of a colour bar (points; narrower when the margin is).
pub const BAR_WIDTH: f32 = 120.0;
/// Height of a colour bar.
pub const BAR_HEIGHT: f32 = 10.0;
/// Side of a key's colour swatch.
pub const SWATCH: f32 = 12.0;
/// Title size (points).
pub const TITLE_TEXT: f32 = 12.0;
/// Entry and range size (points).
pub const ENTRY_TEXT: f32 = 12.0;
/// Most of the view's width the margin takes.
pub const MAX_SHARE: f32 = 0.35;

/// One legend.
#[derive(Debug, Clone, PartialEq)]
pub enum Legend {
    /// A colour table as a bar, with the values at its ends.
    Bar {
        /// What it colours (`primary: amplitude`; `\n` starts a line).
        title: String,
        /// The table's colours, a 256 x 1 texture.
        texture: TextureId,
        /// Value at the left end.
        lo: String,
        /// Value at the right end.
        hi: String,
    },
    /// A two-colour gradient with the values at its ends.
    Gradient {
        /// What it colours.
        title: String,
        /// Colour at the left end.
        from: Color32,
        /// Colour at the right end.
        to: Color32,
        /// Value at the left end.
        lo: String,
        /// Value at the right end.
        hi: String,
    },
    /// Colour swatches with names.
    Key {
        /// What the colours mean (`facies`).
        title: String,
        /// Colour and name, in order.
        entries: Vec<(Color32, String)>,
    },
}

/// A shape of a legend.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// A texture stretched over a rectangle.
    Image(Rect, TextureId),
    /// A filled rectangle.
    Fill(Rect, Color32),
    /// A left-to-right gradient.
    Gradient(Rect, Color32, Color32),
    /// An outline.
    Frame(Rect, Color32),
}

/// Where the legends go.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Side {
    /// A margin at the view's right.
    #[default]
    Right,
    /// A band along the view's top.
    Top,
}

/// The legends laid out in their margin.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LegendLayout {
    /// The margin's side.
    pub side: Side,
    /// The margin's width (right) or height (top); 0 without legends.
    pub size: f32,
    /// Bars, swatches and frames.
    pub marks: Vec<Mark>,
    /// Titles, values and names.
    pub texts: Vec<Text>,
    /// Each legend's title and the rectangle it takes (for checks).
    pub boxes: Vec<(String, Rect)>,
}

impl LegendLayout {
    /// What `view` leaves for the 3D picture beside the margin.
    pub fn picture(&self, view: Rect) -> Rect {
        let mut r = view;
        match self.side {
            Side::Right => r.max.x -= self.size,
            Side::Top => r.min.y += self.size,
        }
        r
    }
}

/// `text` cut with `…` to at most `width` points at `size`.
fn fit(text: &str, size: f32, width: f32, measure: Measure<'_>) -> String {
    if measure(text, size).x <= width {
        return text.to_string();
    }
    let chars: Vec<char> = text.chars().collect();
    (0..chars.len())
        .rev()
        .map(|n| format!("{}…", chars[..n].iter().collect::<String>()))
        .find(|t| measure(t, size).x <= width)
        .unwrap_or_default()
}

/// Place `t` (cut to `inner` points) with its top-left corner at `at`.
fn put(
    texts: &mut Vec<Text>,
    t: &str,
    at: Pos2,
    colour: Color32,
    inner: f32,
    measure: Measure<'_>,
) -> Rect {
    let size = ENTRY_TEXT;
    let t = fit(t, size, inner, measure);
    let rect = Rect::from_min_size(at, measure(&t, size));
    texts.push(Text {
        text: t,
        rect,
        size,
        colour,
    });
    rect
}

/// The widest text or bar of `legend` (points).
fn content_width(legend: &Legend, measure: Measure<'_>) -> f32 {
    let w = |t: &str| measure(t, ENTRY_TEXT).x;
    match legend {
        Legend::Bar { title, lo, hi, .. } | Legend::Gradient { title, lo, hi, .. } => title
            .lines()
            .map(w)
            .fold(BAR_WIDTH, f32::max)
            .max(w(lo) + w(hi) + PAD),
        Legend::Key { title, entries } => entries
            .iter()
            .map(|(_, n)| SWATCH + 6.0 + w(n))
            .chain(title.lines().map(w))
            .fold(0.0, f32::max),
    }
}

/// Place one legend with its top-left corner at (`x`, `y`), `inner` points wide, above
/// `bottom` (a key is cut with "… N more"); returns where it ends.
#[allow(clippy::too_many_arguments)]
fn place(
    out: &mut LegendLayout,
    legend: &Legend,
    x: f32,
    mut y: f32,
    inner: f32,
    bottom: f32,
    ink: Ink,
    measure: Measure<'_>,
) -> f32 {
    let (Legend::Bar { title, .. } | Legend::Gradient { title, .. } | Legend::Key { title, .. }) =
        legend;
    let top = y;
    let line = measure("Ag", ENTRY_TEXT).y;
    for part in title.lines() {
        y = put(
            &mut out.texts,
            part,
            Pos2::new(x, y),
            ink.name,
            inner,
            measure,
        )
        .bottom();
    }
    if !title.is_empty() {
        y += 3.0;
    }
    let bar = Rect::from_min_size(Pos2::new(x, y), Vec2::new(BAR_WIDTH.min(inner), BAR_HEIGHT));
    let ends = match legend {
        Legend::Bar {
            texture, lo, hi, ..
        } => Some((Mark::Image(bar, *texture), lo, hi)),
        Legend::Gradient {
            from, to, lo, hi, ..
        } => Some((Mark::Gradient(bar, *from, *to), lo, hi)),
        Legend::Key { .. } => None,
    };
    if let Some((mark, lo, hi)) = ends {
        out.marks.push(Mark::Frame(bar.expand(1.0), ink.frame));
        out.marks.push(mark);
        y = bar.bottom() + 2.0;
        let hw = measure(hi, ENTRY_TEXT).x.min(inner);
        put(
            &mut out.texts,
            hi,
            Pos2::new(bar.right() - hw, y),
            ink.text,
            inner,
            measure,
        );
        // The low end's value, cut short of the high end's.
        let room = (bar.width() - hw - PAD).max(0.0);
        y = put(&mut out.texts, lo, Pos2::new(x, y), ink.text, room, measure).bottom();
    }
    if let Legend::Key { entries, .. } = legend {
        for (n, (colour, name)) in entries.iter().enumerate() {
            let left = entries.len() - n;
            // Room for this line, and for a "more" line unless it is the last.
            let need = if left > 1 { 2.0 * (line + 2.0) } else { line };
            if y + need > bottom {
                put(
                    &mut out.texts,
                    &format!("… {left} more"),
                    Pos2::new(x, y),
                    ink.text,
                    inner,
                    measure,
                );
                y += line + 2.0;
                break;
            }
            let mut at = x;
            if *colour != Color32::TRANSPARENT {
                let s = Rect::from_min_size(
                    Pos2::new(x, y + (line - SWATCH) / 2.0),
                    Vec2::splat(SWATCH),
                );
                out.marks.push(Mark::Fill(s, *colour));
                out.marks.push(Mark::Frame(s, ink.frame));
                at += SWATCH + 6.0;
            }
            put(
                &mut out.texts,
                name,
                Pos2::new(at, y),
                ink.text,
                x + inner - at,
                measure,
            );
            y += line + 2.0;
        }
    }
    out.boxes.push((
        title.clone(),
        Rect::from_min_max(Pos2::new(x, top), Pos2::new(x + inner, y)),
    ));
    y
}

/// The legends stacked in a margin at the right of `view`.
fn right_margin(view: Rect, legends: &[Legend], ink: Ink, measure: Measure<'_>) -> LegendLayout {
    let mut out = LegendLayout {
        side: Side::Right,
        ..LegendLayout::default()
    };
    let content = legends
        .iter()
        .map(|l| content_width(l, measure))
        .fold(0.0, f32::max);
    out.size = (content + 2.0 * PAD)
        .ceil()
        .min((MAX_SHARE * view.width()).floor());
    let inner = out.size - 2.0 * PAD;
    let x = view.right() - out.size + PAD;
    let bottom = view.bottom() - PAD;
    let line = measure("Ag", ENTRY_TEXT).y;
    let mut y = view.top() + PAD;
    for legend in legends {
        if y + 2.0 * line > bottom {
            break;
        }
        y = place(&mut out, legend, x, y, inner, bottom, ink, measure) + 1.5 * PAD;
    }
    out
}

/// The legends side by side (in rows) in a band along the top of `view`, at most
/// [`MAX_SHARE`] of its height.
fn top_band(view: Rect, legends: &[Legend], ink: Ink, measure: Measure<'_>) -> LegendLayout {
    let mut out = LegendLayout {
        side: Side::Top,
        ..LegendLayout::default()
    };
    let bottom = view.top() + (MAX_SHARE * view.height()).floor() - PAD;
    let line = measure("Ag", ENTRY_TEXT).y;
    let (mut x, mut y, mut row_end) = (view.left() + PAD, view.top() + PAD, view.top() + PAD);
    for legend in legends {
        let inner = content_width(legend, measure)
            .ceil()
            .min(view.width() - 2.0 * PAD);
        if x + inner > view.right() - PAD && x > view.left() + PAD {
            (x, y) = (view.left() + PAD, row_end + PAD);
        }
        if y + 2.0 * line > bottom {
            break;
        }
        let end = place(&mut out, legend, x, y, inner, bottom, ink, measure);
        row_end = row_end.max(end);
        x += inner + 2.0 * PAD;
    }
    out.size = (row_end - view.top() + PAD).ceil();
    out
}

/// Lay out `legends` beside `view`: in a margin at its right or a band along its top,
/// whichever leaves the 3D picture the longer shorter side (the camera fits the data
/// to it), as long as every legend fits.
pub fn layout(view: Rect, legends: &[Legend], ink: Ink, measure: Measure<'_>) -> LegendLayout {
    if legends.is_empty() {
        return LegendLayout::default();
    }
    let right = right_margin(view, legends, ink, measure);
    let top = top_band(view, legends, ink, measure);
    let side = |l: &LegendLayout| {
        let r = l.picture(view);
        r.width().min(r.height())
    };
    if top.boxes.len() >= right.boxes.len() && side(&top) > side(&right) {
        top
    } else {
        right
    }
}

/// Draw laid-out legends.
pub fn paint(painter: &Painter, layout: &LegendLayout) {
    let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
    for mark in &layout.marks {
        match mark {
            Mark::Image(r, t) => {
                painter.image(*t, *r, uv, Color32::WHITE);
            }
            Mark::Fill(r, c) => {
                painter.rect_filled(*r, 0.0, *c);
            }
            Mark::Frame(r, c) => {
                painter.rect_stroke(*r, 0.0, Stroke::new(1.0, *c), egui::StrokeKind::Outside);
            }
            Mark::Gradient(r, a, b) => {
                let mut mesh = egui::Mesh::default();
                for (p, c) in [
                    (r.left_top(), *a),
                    (r.right_top(), *b),
                    (r.right_bottom(), *b),
                    (r.left_bottom(), *a),
                ] {
                    mesh.colored_vertex(p, c);
                }
                mesh.add_triangle(0, 1, 2);
                mesh.add_triangle(0, 2, 3);
                painter.add(egui::Shape::mesh(mesh));
            }
        }
    }
    paint_texts(painter, &layout.texts);
}

fn rgb(c: [u8; 3]) -> Color32 {
    Color32::from_rgb(c[0], c[1], c[2])
}

fn unit(c: [f64; 3]) -> Color32 {
    let b = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    Color32::from_rgb(b(c[0]), b(c[1]), b(c[2]))
}

/// 3D opacity: a colour bar per attribute, over its value range.
pub(crate) fn volume_legends(
    ctx: &egui::Context,
    scene: &Scene,
    o: &Opacity3dScene,
    data: &mut ViewData,
    out: &mut Vec<Legend>,
) {
    let ranges = data.volume.as_ref().map(|v| v.prepared.ranges);
    for (a, attr) in o.attributes().into_iter().enumerate() {
        let (Some(attr), Some(Some((lo, hi)))) = (attr, ranges.map(|r| r[a])) else {
            continue;
        };
        if let Some((_, texture)) = data.table(ctx, scene, a) {
            out.push(Legend::Bar {
                title: format!("{}: {}", lut3d::ROLES[a], attr.attribute.name()),
                texture: texture.id(),
                lo: lut3d::short(lo),
                hi: lut3d::short(hi),
            });
        }
    }
}

/// Cell projection: the transfer function's bar (volume mode) and the isovalues as keys.
pub(crate) fn mesh_legends(
    c: &CellprojScene,
    data: &ViewData,
    transfer: Option<TextureId>,
    out: &mut Vec<Legend>,
) {
    let (name, [lo, hi]) = data
        .mesh
        .as_ref()
        .map_or((String::from("scalar"), [0.0, 1.0]), |m| {
            (m.scalar.clone(), m.range)
        });
    // Each isovalue in the scalar's units, and normalized beside it where the
    // scene writes them so.
    let mut isos = c.isovalues.clone();
    isos.sort_by(|a, b| a.value.total_cmp(&b.value));
    let normalized = c.isovalue_units == IsovalueUnits::Normalized;
    let plain = lo == 0.0 && hi == 1.0;
    let entries = isos
        .iter()
        .map(|i| {
            let raw = if normalized {
                lo + i.value * (hi - lo)
            } else {
                i.value
            };
            let label = if plain || !normalized {
                lut3d::short(raw)
            } else {
                format!("{:.3} = {}", i.value, lut3d::short(raw))
            };
            (unit([i.color[0], i.color[1], i.color[2]]), label)
        })
        .collect();
    if let (true, Some(texture)) = (c.mode.volume(), transfer) {
        out.push(Legend::Bar {
            title: format!("volume: {name}"),
            texture,
            lo: lut3d::short(lo),
            hi: lut3d::short(hi),
        });
    }
    if c.mode.isosurfaces() {
        out.push(Legend::Key {
            title: format!("isovalues\nof {name}"),
            entries,
        });
    }
}

/// Splats: the colouring's classes as keys, or its gradient, and the faults' white.
pub(crate) fn cloud_legends(sp: &SplatsScene, data: &ViewData, out: &mut Vec<Legend>) {
    let Some(s) = &data.cloud else { return };
    let fault = (sp.faults_white && s.faults).then(|| (Color32::WHITE, "fault".to_string()));
    let key = |title: &str, mut entries: Vec<(Color32, String)>, more: usize| {
        if more > 0 {
            entries.push((Color32::TRANSPARENT, format!("and {more} more ids")));
        }
        entries.extend(fault.clone());
        Legend::Key {
            title: title.to_string(),
            entries,
        }
    };
    let gradient = |title: &str, from, to, range: Option<[f64; 2]>| {
        let [lo, hi] = range.unwrap_or([0.0, 0.0]);
        Legend::Gradient {
            title: title.to_string(),
            from,
            to,
            lo: lut3d::short(lo),
            hi: lut3d::short(hi),
        }
    };
    match sp.colour {
        ColourMode::Facies => {
            let entries = s
                .facies
                .iter()
                .filter(|&&f| !(sp.hide_undefined && f == UNDEFINED_FACIES))
                .map(|&f| {
                    let name = FACIES_TABLE
                        .iter()
                        .find(|(id, _, _)| *id == f)
                        .map_or(format!("facies {f}"), |(_, n, _)| format!("{n} ({f})"));
                    (rgb(facies_colour(f)), name)
                })
                .collect();
            out.push(key("facies", entries, s.more[0]));
        }
        ColourMode::Layer => {
            let entries = s
                .layers
                .iter()
                .filter(|l| !sp.hide_layers.contains(l))
                .map(|&l| {
                    let c = PALETTE[l.rem_euclid(LAYERS_IN_PALETTE) as usize];
                    (rgb(c), format!("layer {l}"))
                })
                .collect();
            out.push(key("layers", entries, s.more[1]));
        }
        ColourMode::Classification => {
            let entries = s
                .classes
                .iter()
                .filter(|c| !sp.hide_classes.contains(c))
                .map(|&c| (rgb(class_colour(c)), class_name(c)))
                .collect();
            out.push(key("classes", entries, s.more[2]));
        }
        ColourMode::Property => {
            out.push(gradient(
                &sp.property,
                unit(COLOR_A),
                unit(COLOR_B),
                s.range(&sp.property),
            ));
        }
        ColourMode::Elevation => {
            out.push(gradient(
                "elevation",
                unit(COLOR_A),
                unit(COLOR_B),
                Some(s.elevation),
            ));
        }
        ColourMode::Intensity => {
            let max = s.range("intensity").map_or(1.0, |r| r[1].max(1.0));
            out.push(gradient(
                "intensity",
                Color32::BLACK,
                Color32::WHITE,
                Some([0.0, max]),
            ));
        }
        ColourMode::Rgb => {}
    }
    if !matches!(
        sp.colour,
        ColourMode::Facies | ColourMode::Layer | ColourMode::Classification
    ) {
        if let Some(f) = fault {
            out.push(Legend::Key {
                title: String::new(),
                entries: vec![f],
            });
        }
    }
}

#[cfg(test)]
mod tests;
