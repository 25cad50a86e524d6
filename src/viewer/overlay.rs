//! Drawn over the 3D view (by egui, after the volume; never in screenshots): the volume's
//! bounding box with ticks and numbers along three of its edges in the data's own axes
//! (inline / crossline / time for SEG-Y), the outlines of the sections shown beside the
//! view, and a colour bar per table with the attribute's value range.
//!
//! Decisions: the box is projected with the camera's own matrix for the view's aspect, so
//! it sits exactly on the volume. Each axis is labelled on the one of its four parallel
//! edges that lies farthest out from the box's projected centre (a silhouette edge, so
//! labels fall outside the volume) and is not already labelled; an axis seen end-on (edge
//! shorter than 24 points) gets no labels. Labels are kept 30 points inside the view.

use egui::{Align2, Color32, FontId, Painter, Pos2, Rect, Stroke, Vec2};
use glam::{DVec3, DVec4};

use super::axes::Axis;
use crate::camera::Camera;

/// Colours of the inline, crossline and time-slice section outlines, by fixed axis
/// (0 time slice, 1 crossline, 2 inline).
pub const SECTION_COLOURS: [Color32; 3] = [
    Color32::from_rgb(230, 90, 230),
    Color32::from_rgb(80, 220, 230),
    Color32::from_rgb(240, 220, 60),
];

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

fn corner(half: DVec3, i: usize) -> DVec3 {
    DVec3::new(
        if i & 1 == 0 { -half.x } else { half.x },
        if i & 2 == 0 { -half.y } else { half.y },
        if i & 4 == 0 { -half.z } else { half.z },
    )
}

/// Object-space position of voxel centre `index` along `axis` of `len` voxels.
fn along(half: f64, index: usize, len: usize) -> f64 {
    -half + (index as f64 + 0.5) / len.max(1) as f64 * 2.0 * half
}

/// The bounding box, its axis labels and the section outlines (`sections[a]` = the index
/// of the section at fixed axis `a`, when shown).
pub fn draw_box(
    painter: &Painter,
    p: &Projector,
    half: DVec3,
    axes: &[Axis; 3],
    sections: [Option<usize>; 3],
) {
    let box_stroke = Stroke::new(1.0, Color32::from_rgba_unmultiplied(220, 220, 220, 160));
    let corners: Vec<Pos2> = (0..8).map(|i| p.project(corner(half, i))).collect();
    let centre = p.project(DVec3::ZERO);
    for a in 0..3 {
        let bit = 1 << a;
        for i in (0..8).filter(|i| i & bit == 0) {
            painter.line_segment([corners[i], corners[i | bit]], box_stroke);
        }
    }
    let font = FontId::proportional(11.0);
    let text = Color32::from_gray(230);
    let mut labelled: Vec<(Pos2, Pos2)> = Vec::new();
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
        let mid = e0 + (e1 - e0) * 0.5;
        let dir = (e1 - e0).normalized();
        let mut out = Vec2::new(-dir.y, dir.x);
        if out.dot(mid - centre) < 0.0 {
            out = -out;
        }
        let base = corner(half, start);
        let count = ((e1 - e0).length() / 60.0).floor().clamp(2.0, 6.0) as usize;
        let ticks = axis.ticks(count);
        let widest = ticks
            .iter()
            .map(|&t| axis.label(t).len())
            .max()
            .unwrap_or(0);
        // The name goes beyond the tick labels (about 6.5 points per character across).
        let clear = if out.x.abs() > 0.4 {
            14.0 + 6.5 * widest as f32 * out.x.abs()
        } else {
            22.0
        };
        for t in ticks {
            let mut q = base;
            q[a] = along(half[a], t, axis.len);
            let s = p.project(q);
            painter.line_segment([s, s + out * 5.0], Stroke::new(1.0, text));
            let at = inside(painter.clip_rect(), s + out * 8.0);
            painter.text(at, anchor(out), axis.label(t), font.clone(), text);
        }
        painter.text(
            inside(painter.clip_rect(), mid + out * (clear + 4.0)),
            anchor(out),
            &axis.name,
            FontId::proportional(12.0),
            Color32::from_rgb(255, 230, 160),
        );
    }
    for (a, index) in sections.iter().enumerate() {
        let Some(index) = *index else { continue };
        let (u, w) = super::data::section_axes(a);
        let mut quad = Vec::with_capacity(5);
        for (su, sw) in [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (-1.0, -1.0),
        ] {
            let mut q = DVec3::ZERO;
            q[a] = along(half[a], index, axes[a].len);
            q[u] = su * half[u];
            q[w] = sw * half[w];
            quad.push(p.project(q));
        }
        painter.line(quad, Stroke::new(1.5, SECTION_COLOURS[a]));
    }
}

/// `p` moved at least 30 points inside `r` (labels stay readable at the view's edges).
fn inside(r: Rect, p: Pos2) -> Pos2 {
    let r = r.shrink(30.0);
    if r.is_positive() {
        r.clamp(p)
    } else {
        p
    }
}

/// Text anchor for a label placed in direction `out` from its point.
fn anchor(out: Vec2) -> Align2 {
    let h = if out.x > 0.4 {
        egui::Align::Min
    } else if out.x < -0.4 {
        egui::Align::Max
    } else {
        egui::Align::Center
    };
    let v = if out.y > 0.4 {
        egui::Align::Min
    } else if out.y < -0.4 {
        egui::Align::Max
    } else {
        egui::Align::Center
    };
    Align2([h, v])
}

/// One colour bar: the table's colours, the attribute's name and its value range.
pub struct ColourBar {
    /// `primary: envelope`.
    pub title: String,
    /// The colours as a 256 x 1 texture.
    pub texture: egui::TextureId,
    /// Values at the ends.
    pub range: (String, String),
}

/// Stack `bars` in the view's top-right corner.
pub fn draw_bars(painter: &Painter, view: Rect, bars: &[ColourBar]) {
    let font = FontId::proportional(11.0);
    let (w, h, gap) = (120.0, 10.0, 42.0);
    for (n, bar) in bars.iter().enumerate() {
        let top = view.top() + 22.0 + n as f32 * gap;
        let left = view.right() - 8.0 - w;
        let rect = Rect::from_min_size(Pos2::new(left, top), Vec2::new(w, h));
        painter.rect_filled(rect.expand(1.0), 0.0, Color32::from_gray(90));
        painter.image(
            bar.texture,
            rect,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
        painter.text(
            rect.left_top() - Vec2::new(0.0, 1.0),
            Align2::LEFT_BOTTOM,
            &bar.title,
            font.clone(),
            Color32::from_gray(230),
        );
        painter.text(
            rect.left_bottom() + Vec2::new(0.0, 1.0),
            Align2::LEFT_TOP,
            &bar.range.0,
            font.clone(),
            Color32::from_gray(200),
        );
        painter.text(
            rect.right_bottom() + Vec2::new(0.0, 1.0),
            Align2::RIGHT_TOP,
            &bar.range.1,
            font.clone(),
            Color32::from_gray(200),
        );
    }
}
