//! Drawn over the 3D view by egui, after the volume (and kept in screenshots): the data's
//! bounding box with ticks and numbers along three of its edges in the file's own axes
//! and units (inline / crossline / time for SEG-Y, millimetres for NIfTI, a cloud's or a
//! mesh's coordinates), and the outlines of the sections shown beside the view. The
//! legends have a margin of their own beside it ([`super::legend`]).
//!
//! Decisions:
//! - Layout, then paint: [`layout_box`] places every line and label and returns the
//!   labels' rectangles, so a check can show that no two overlap and all lie inside the
//!   3D area; [`paint`] draws only what was placed.
//! - The box is projected with the camera's own matrix for the area's aspect, so it sits
//!   exactly on the volume. Each axis is labelled on the one of its four parallel edges
//!   that lies farthest out from the box's projected centre (a silhouette edge, so labels
//!   fall outside the data) and is not already labelled; an axis seen end-on (edge
//!   shorter than 24 points) gets no labels.
//! - Labels never overlap and never leave the area: each label's rectangle is moved
//!   inside the area (not just its anchor: a name at the edge stays whole), the three
//!   axis names are placed first (beyond their tick labels; slid along the edge or
//!   further out when taken), then each axis's end ticks, then its inner ticks; a tick
//!   whose label would come within [`GAP`] of one placed, or within [`SAME_TEXT_GAP`]
//!   of one that says the same, drops its label, so two `0`s at a shared corner
//!   become one.
//! - Text and lines contrast with the background: light on a dark one, dark on a light
//!   one ([`Ink::on`]).

use egui::{Align2, Color32, Painter, Pos2, Rect, Stroke, Vec2};
use glam::{DVec3, DVec4};

use super::layout::overlay_font;
use arbvis_core::camera::Camera;
use arbvis_data::volume::axes::Axis;

/// Colours of the inline, crossline and time-slice section outlines, by fixed axis
/// (0 time slice, 1 crossline, 2 inline).
pub const SECTION_COLOURS: [Color32; 3] = [
    Color32::from_rgb(230, 90, 230),
    Color32::from_rgb(80, 220, 230),
    Color32::from_rgb(240, 220, 60),
];

/// Tick label size (points).
pub const TICK_TEXT: f32 = 12.0;
/// Axis name size (points).
pub const NAME_TEXT: f32 = 13.0;
/// Least distance between two labels (points).
pub const GAP: f32 = 2.0;
/// Least distance between two tick labels that say the same (points).
pub const SAME_TEXT_GAP: f32 = 16.0;

/// Measures text: its size in points at a font size.
pub type Measure<'a> = &'a dyn Fn(&str, f32) -> Vec2;

/// The colours of overlay text and lines on a background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ink {
    /// Numbers and legend text.
    pub text: Color32,
    /// Axis names and legend titles.
    pub name: Color32,
    /// The box's edges.
    pub line: Color32,
    /// Faint frames (legend swatches).
    pub frame: Color32,
}

impl Ink {
    /// Ink that reads on `background` (RGBA, 0..1): light on dark, dark on light.
    pub fn on(background: [f32; 4]) -> Ink {
        let [r, g, b, _] = background;
        if 0.2126 * r + 0.7152 * g + 0.0722 * b < 0.5 {
            Ink {
                text: Color32::from_gray(230),
                name: Color32::from_rgb(255, 230, 160),
                line: Color32::from_rgba_unmultiplied(220, 220, 220, 160),
                frame: Color32::from_gray(110),
            }
        } else {
            Ink {
                text: Color32::from_gray(25),
                name: Color32::from_rgb(110, 50, 0),
                line: Color32::from_rgba_unmultiplied(40, 40, 40, 170),
                // Dark enough that a white swatch (splats' faults) reads as a box.
                frame: Color32::from_gray(70),
            }
        }
    }
}

/// Projects object space onto the view.
pub struct Projector {
    mvp: glam::DMat4,
    view: Rect,
}

impl Projector {
    /// For `camera` drawing into `view` (points).
    pub fn new(camera: &Camera, view: Rect) -> Projector {
        let aspect = view.width() as f64 / view.height().max(1.0) as f64;
        Projector {
            mvp: camera.view_projection(aspect),
            view,
        }
    }

    /// Where object-space `p` lands in the view (points).
    pub fn project(&self, p: DVec3) -> Pos2 {
        let c = self.mvp * DVec4::new(p.x, p.y, p.z, 1.0);
        let w = if c.w.abs() > 1e-12 { c.w } else { 1e-12 };
        let (x, y) = (c.x / w, c.y / w);
        Pos2::new(
            self.view.left() + ((x + 1.0) / 2.0) as f32 * self.view.width(),
            self.view.top() + ((1.0 - y) / 2.0) as f32 * self.view.height(),
        )
    }
}

/// A placed text: drawn with its rectangle's top-left corner at `rect.min`.
#[derive(Debug, Clone, PartialEq)]
pub struct Text {
    /// What it says.
    pub text: String,
    /// Where (points).
    pub rect: Rect,
    /// Font size (points).
    pub size: f32,
    /// Colour.
    pub colour: Color32,
}

/// Everything [`paint`] draws of the box.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BoxLayout {
    /// Box edges and tick marks.
    pub lines: Vec<([Pos2; 2], Stroke)>,
    /// Section outlines.
    pub outlines: Vec<(Vec<Pos2>, Stroke)>,
    /// Axis names and tick labels.
    pub texts: Vec<Text>,
}

fn corner(half: DVec3, i: usize) -> DVec3 {
    DVec3::new(
        if i & 1 == 0 { -half.x } else { half.x },
        if i & 2 == 0 { -half.y } else { half.y },
        if i & 4 == 0 { -half.z } else { half.z },
    )
}

/// Object-space position of voxel centre `index` along an axis of `len` voxels.
fn along(half: f64, index: usize, len: usize) -> f64 {
    -half + (index as f64 + 0.5) / len.max(1) as f64 * 2.0 * half
}

/// `r` moved to lie inside `area` (its top-left corner kept in when it is larger).
pub fn moved_inside(r: Rect, area: Rect) -> Rect {
    let shift = |lo: f32, hi: f32, min: f32, max: f32| {
        let d = (max - hi).min(0.0);
        if lo + d < min {
            min - lo
        } else {
            d
        }
    };
    r.translate(Vec2::new(
        shift(r.left(), r.right(), area.left(), area.right()),
        shift(r.top(), r.bottom(), area.top(), area.bottom()),
    ))
}

/// Text anchor for a label placed in direction `out` from its point.
fn anchor(out: Vec2) -> Align2 {
    let pick = |v: f32| {
        if v > 0.4 {
            egui::Align::Min
        } else if v < -0.4 {
            egui::Align::Max
        } else {
            egui::Align::Center
        }
    };
    Align2([pick(out.x), pick(out.y)])
}

/// Labels placed so far, kept apart by [`GAP`].
struct Placed(Vec<Rect>);

impl Placed {
    fn free(&self, r: Rect) -> bool {
        self.0.iter().all(|q| !q.expand(GAP).intersects(r))
    }
}

/// One axis's labelled edge.
struct Plan {
    axis: usize,
    mid: Pos2,
    dir: Vec2,
    out: Vec2,
    /// Tick point on the edge and its label.
    ticks: Vec<(Pos2, String)>,
}

/// Lay out the box of half-extents `half` with `axes` in `area` (the 3D view without
/// the legends' margin): edges, ticks, labels and the outlines of the `sections` shown
/// (`sections[a]` = the index of the section at fixed axis `a`).
pub fn layout_box(
    p: &Projector,
    area: Rect,
    half: DVec3,
    axes: &[Axis; 3],
    sections: [Option<usize>; 3],
    ink: Ink,
    measure: Measure<'_>,
) -> BoxLayout {
    let mut out = BoxLayout::default();
    let box_stroke = Stroke::new(1.0, ink.line);
    let corners: Vec<Pos2> = (0..8).map(|i| p.project(corner(half, i))).collect();
    let centre = p.project(DVec3::ZERO);
    for a in 0..3 {
        let bit = 1 << a;
        for i in (0..8).filter(|i| i & bit == 0) {
            out.lines.push(([corners[i], corners[i | bit]], box_stroke));
        }
    }
    let plans = plan_axes(&corners, centre, half, axes, p);
    let mut placed = Placed(Vec::new());
    let inside = area.shrink(GAP);
    // Where every tick label would go: names keep clear of them when they can.
    let tick_rects: Vec<Rect> = plans
        .iter()
        .flat_map(|plan| {
            plan.ticks.iter().map(|(s, label)| {
                let r =
                    anchor(plan.out).anchor_size(*s + plan.out * 8.0, measure(label, TICK_TEXT));
                moved_inside(r, inside)
            })
        })
        .collect();
    // Names first: beyond their axis's tick labels, slid along the edge or further out
    // when the place is taken (by a name, else by a tick label).
    for plan in &plans {
        let size = measure(&axes[plan.axis].name, NAME_TEXT);
        let band = plan
            .ticks
            .iter()
            .map(|(s, label)| {
                let r =
                    anchor(plan.out).anchor_size(*s + plan.out * 8.0, measure(label, TICK_TEXT));
                [
                    r.left_top(),
                    r.right_top(),
                    r.left_bottom(),
                    r.right_bottom(),
                ]
                .iter()
                .map(|c| (*c - plan.mid).dot(plan.out))
                .fold(8.0f32, f32::max)
            })
            .fold(8.0f32, f32::max);
        let candidates: Vec<Rect> = [0.0, 16.0, 32.0]
            .iter()
            .flat_map(|further| {
                [0.0, 1.0, -1.0, 2.0, -2.0, 3.0, -3.0].map(|slide| {
                    let at = plan.mid
                        + plan.out * (band + 10.0 + further)
                        + plan.dir * slide * size.x.max(size.y * 2.0) * 0.6;
                    moved_inside(anchor(plan.out).anchor_size(at, size), inside)
                })
            })
            .filter(|r| placed.free(*r) && inside.contains_rect(*r))
            .collect();
        let clear = |r: &&Rect| tick_rects.iter().all(|t| !t.expand(GAP).intersects(**r));
        let chosen = candidates.iter().find(clear).or(candidates.first());
        if let Some(&r) = chosen {
            placed.0.push(r);
            out.texts.push(Text {
                text: axes[plan.axis].name.clone(),
                rect: r,
                size: NAME_TEXT,
                colour: ink.name,
            });
        }
    }
    // Then the ticks: each axis's ends, then its inner ticks.
    for plan in &plans {
        let n = plan.ticks.len();
        let order = [0, n.saturating_sub(1)]
            .into_iter()
            .chain(1..n.saturating_sub(1));
        let mut seen = vec![false; n];
        for k in order {
            if seen[k] {
                continue;
            }
            seen[k] = true;
            let (s, label) = &plan.ticks[k];
            out.lines
                .push(([*s, *s + plan.out * 5.0], Stroke::new(1.0, ink.text)));
            let size = measure(label, TICK_TEXT);
            let r = moved_inside(
                anchor(plan.out).anchor_size(*s + plan.out * 8.0, size),
                inside,
            );
            // The same number close by (two axes' `0` at their shared corner) is one.
            let repeated = out
                .texts
                .iter()
                .any(|t| t.text == *label && t.rect.expand(SAME_TEXT_GAP).intersects(r));
            if placed.free(r) && inside.contains_rect(r) && !repeated {
                placed.0.push(r);
                out.texts.push(Text {
                    text: label.clone(),
                    rect: r,
                    size: TICK_TEXT,
                    colour: ink.text,
                });
            }
        }
    }
    for (a, index) in sections.iter().enumerate() {
        let Some(index) = *index else { continue };
        let (u, w) = arbvis_data::volume::axes::section_axes(a);
        let quad = [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (-1.0, -1.0),
        ]
        .iter()
        .map(|&(su, sw)| {
            let mut q = DVec3::ZERO;
            q[a] = along(half[a], index, axes[a].len);
            q[u] = su * half[u];
            q[w] = sw * half[w];
            p.project(q)
        })
        .collect();
        out.outlines
            .push((quad, Stroke::new(1.5, SECTION_COLOURS[a])));
    }
    out
}

/// Which edge each axis is labelled on, its outward direction and its ticks.
fn plan_axes(
    corners: &[Pos2],
    centre: Pos2,
    half: DVec3,
    axes: &[Axis; 3],
    p: &Projector,
) -> Vec<Plan> {
    let mut labelled: Vec<(Pos2, Pos2)> = Vec::new();
    let mut plans = Vec::new();
    for (a, axis) in axes.iter().enumerate() {
        let bit = 1 << a;
        // The outermost of the four edges along this axis that does not lie on an edge
        // already labelled (two axes can project onto one screen line).
        let mid = |k: usize| corners[k] + (corners[k | bit] - corners[k]) * 0.5;
        let mut edges: Vec<usize> = (0..8).filter(|i| i & bit == 0).collect();
        edges.sort_by(|&i, &j| {
            (mid(j) - centre)
                .length()
                .total_cmp(&(mid(i) - centre).length())
        });
        let free = |k: usize| {
            let (p, q) = (corners[k], corners[k | bit]);
            !labelled.iter().any(|&(a, b): &(Pos2, Pos2)| {
                let near = |x: Pos2, y: Pos2| x.distance(y) < 12.0;
                (near(p, a) && near(q, b))
                    || (near(p, b) && near(q, a))
                    || near(mid(k), a + (b - a) * 0.5)
            })
        };
        let Some(start) = edges.iter().copied().find(|&k| free(k)) else {
            continue;
        };
        labelled.push((corners[start], corners[start | bit]));
        let (e0, e1) = (corners[start], corners[start | bit]);
        if (e1 - e0).length() < 24.0 {
            continue;
        }
        let m = e0 + (e1 - e0) * 0.5;
        let dir = (e1 - e0).normalized();
        let mut out = Vec2::new(-dir.y, dir.x);
        if out.dot(m - centre) < 0.0 {
            out = -out;
        }
        let base = corner(half, start);
        let count = ((e1 - e0).length() / 60.0).floor().clamp(2.0, 6.0) as usize;
        let ticks = axis
            .ticks(count)
            .into_iter()
            .map(|t| {
                let mut q = base;
                q[a] = -half[a] + t.at * 2.0 * half[a];
                (p.project(q), t.label)
            })
            .collect();
        plans.push(Plan {
            axis: a,
            mid: m,
            dir,
            out,
            ticks,
        });
    }
    plans
}

/// Draw a laid-out box.
pub fn paint(painter: &Painter, layout: &BoxLayout) {
    for (segment, stroke) in &layout.lines {
        painter.line_segment(*segment, *stroke);
    }
    for (line, stroke) in &layout.outlines {
        painter.line(line.clone(), *stroke);
    }
    paint_texts(painter, &layout.texts);
}

/// Draw placed texts.
pub fn paint_texts(painter: &Painter, texts: &[Text]) {
    for t in texts {
        painter.text(
            t.rect.min,
            Align2::LEFT_TOP,
            &t.text,
            overlay_font(t.size),
            t.colour,
        );
    }
}

#[cfg(test)]
mod tests;
