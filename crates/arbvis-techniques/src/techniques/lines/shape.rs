//! The lines' shapes: tubes of a radius in metres (made once), and the shapes that
//! follow the view, made again when the camera or the picture's size changes: ribbons
//! (flat bands turned to face the viewer) and anything as wide as a number of pixels.
//!
//! A width in pixels is exact at every point of a line: the point is projected, moved
//! half the width across the line's direction on the screen, and taken back at its own
//! depth, so the band covers the same pixels at every zoom and keeps the line's depth.
//! A tube in pixels takes at each point the radius that spans half the width there.

use glam::{DMat4, DVec2, DVec3, DVec4};

use serde::{Deserialize, Serialize};

use crate::techniques::surface::prepare::{of_frame_mesh, Prepared};
use crate::techniques::world::World;
use arbvis_core::camera::{Camera, Projection};
use arbvis_data::surface::TriangleMesh;

/// How a line is drawn.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LineStyle {
    /// A tube: rings round the line, lit by the headlight.
    #[default]
    Tube,
    /// A flat band turned to face the viewer, unlit.
    Ribbon,
}

/// A line's width, across it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Width {
    /// In the data's units (metres).
    Metres(f64),
    /// On the picture, at every zoom.
    Pixels(f64),
}

/// How lines are shaped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    /// Tube or ribbon.
    pub style: LineStyle,
    /// Across the line.
    pub width: Width,
    /// Vertices round a tube's ring.
    pub sides: usize,
}

impl Shape {
    /// Whether the shape is made once (tubes in metres) rather than for each view.
    pub fn fixed(&self) -> bool {
        self.style == LineStyle::Tube && matches!(self.width, Width::Metres(_))
    }

    /// Vertices made at each point: a ring of `sides`, or a ribbon's two.
    pub fn vertices_per_point(&self) -> usize {
        match self.style {
            LineStyle::Tube => self.sides,
            LineStyle::Ribbon => 2,
        }
    }
}

/// The lines ready to shape: their points in the object frame of `world`, each with its
/// colour, and their tubes when those do not depend on the view.
#[derive(Debug, Clone)]
pub struct PreparedLines {
    /// Lines of two distinct points or more, in the object frame (no point equal to the
    /// one before it).
    pub lines: Vec<Vec<DVec3>>,
    /// Each point's colour, line after line.
    pub colours: Vec<DVec3>,
    /// The frame every shape of these lines is drawn in.
    pub world: World,
    /// The values the table spans and its colours (the legend), as a surface's.
    pub legend: ([f64; 2], Option<Vec<[u8; 3]>>),
    /// The tubes of a radius in metres, made once; `None` where the shape follows the view.
    pub fixed: Option<Prepared>,
}

impl PreparedLines {
    /// What is drawn for `camera` on a picture of `size` pixels.
    pub fn shaped(&self, shape: Shape, camera: &Camera, size: [u32; 2]) -> Prepared {
        if let Some(fixed) = &self.fixed {
            return fixed.clone();
        }
        let screen = Screen::of(camera, size);
        let mesh = match shape.style {
            LineStyle::Ribbon => ribbons(&self.lines, |p, side| match shape.width {
                Width::Pixels(w) => screen.across(p, side, w / 2.0),
                Width::Metres(w) => {
                    let toward = match camera.projection {
                        Projection::Perspective => camera.eye() - p,
                        Projection::Orthographic => camera.toward_viewer(),
                    };
                    let half = w / 2.0 / self.world.units;
                    p + facing(side, toward) * half
                }
            }),
            LineStyle::Tube => {
                let half = match shape.width {
                    Width::Pixels(w) => w / 2.0,
                    Width::Metres(_) => unreachable!("tubes in metres are made once"),
                };
                tubes(&self.lines, shape.sides, |p| screen.radius(p, half))
            }
        };
        // Each point's vertices (two a ribbon, `sides` a tube) take its colour.
        let colours = per_vertex(&self.colours, shape.vertices_per_point());
        of_frame_mesh(&mesh, &colours, self.legend.clone(), self.world)
    }
}

/// Each point's `value` repeated for its `per_point` vertices.
pub fn per_vertex<T: Copy>(values: &[T], per_point: usize) -> Vec<T> {
    values
        .iter()
        .flat_map(|v| std::iter::repeat_n(*v, per_point))
        .collect()
}

/// The projection of a view onto the picture's pixels, and back.
struct Screen {
    to_clip: DMat4,
    from_clip: DMat4,
    size: DVec2,
}

impl Screen {
    fn of(camera: &Camera, size: [u32; 2]) -> Screen {
        let size = DVec2::new(size[0].max(1) as f64, size[1].max(1) as f64);
        let to_clip = camera.view_projection(size.x / size.y);
        Screen {
            to_clip,
            from_clip: to_clip.inverse(),
            size,
        }
    }

    /// `p` in pixels (x right, y up) and its depth in normalized device coordinates.
    fn project(&self, p: DVec3) -> (DVec2, f64) {
        let c = self.to_clip * p.extend(1.0);
        // Points behind the eye lie outside the scene's depth range; keep them finite.
        let w = if c.w.abs() > 1e-12 { c.w } else { 1e-12 };
        let n = c.truncate() / w;
        ((n.truncate() + 1.0) * 0.5 * self.size, n.z)
    }

    /// The object-frame point at pixel `s` and normalized depth `z`.
    fn unproject(&self, s: DVec2, z: f64) -> DVec3 {
        let n = s / self.size * 2.0 - 1.0;
        let o = self.from_clip * DVec4::new(n.x, n.y, z, 1.0);
        o.truncate() / o.w
    }

    /// The point `half` pixels from `p` square to the line's direction on the screen
    /// (`side.1`, an object-frame direction), on the side `side.0` (+1 or -1).
    fn across(&self, p: DVec3, side: (f64, DVec3), half: f64) -> DVec3 {
        let (s, z) = self.project(p);
        let ahead = self.project(p + side.1 * 1e-3).0 - s;
        let dir = match ahead.length() > 1e-12 {
            true => ahead / ahead.length(),
            // A line seen end-on: any direction on the screen.
            false => DVec2::X,
        };
        self.unproject(s + dir.perp() * half * side.0, z)
    }

    /// The object-frame length that spans `half` pixels at `p` (across the screen).
    fn radius(&self, p: DVec3, half: f64) -> f64 {
        let (s, z) = self.project(p);
        (self.unproject(s + DVec2::X * half, z) - p).length()
    }
}

/// The unit direction square to the line's direction and to `toward` (the viewer),
/// on the side `side.0`; any square direction where the line points at the viewer.
fn facing(side: (f64, DVec3), toward: DVec3) -> DVec3 {
    let across = side.1.cross(toward);
    match across.length() > 1e-12 {
        true => across.normalize() * side.0,
        false => square_to(side.1) * side.0,
    }
}

/// A unit vector square to `t`.
pub fn square_to(t: DVec3) -> DVec3 {
    let helper = if t.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
    t.cross(helper).normalize()
}

/// The unit direction along a line at its point `i` (from the point before to the one
/// after; the first and last use their one neighbour).
fn tangent(line: &[DVec3], i: usize) -> DVec3 {
    let n = line.len();
    (line[(i + 1).min(n - 1)] - line[i.saturating_sub(1)]).normalize()
}

/// Ribbons: at each point the two corners `corner(p, (±1, tangent))`, joined point to
/// point by two triangles.
fn ribbons(lines: &[Vec<DVec3>], corner: impl Fn(DVec3, (f64, DVec3)) -> DVec3) -> TriangleMesh {
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    for points in lines {
        let first = vertices.len() as u32;
        for (i, p) in points.iter().enumerate() {
            let t = tangent(points, i);
            vertices.push(corner(*p, (-1.0, t)).to_array());
            vertices.push(corner(*p, (1.0, t)).to_array());
        }
        for i in 0..points.len() as u32 - 1 {
            let (a, b, c, d) = (
                first + 2 * i,
                first + 2 * i + 1,
                first + 2 * i + 3,
                first + 2 * i + 2,
            );
            push_quad(&mut triangles, [a, b, c, d]);
        }
    }
    mesh(vertices, triangles)
}

/// The quad `a b c d` (in order round it) as two triangles.
fn push_quad(triangles: &mut Vec<[u32; 3]>, [a, b, c, d]: [u32; 4]) {
    triangles.push([a, b, c]);
    triangles.push([a, c, d]);
}

/// A mesh of `vertices` and `triangles`, without properties.
fn mesh(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> TriangleMesh {
    TriangleMesh {
        vertices,
        triangles,
        properties: Vec::new(),
    }
}

/// Tubes: a ring of `sides` vertices of radius `radius(p)` around each point, square to
/// the line and turned along it by parallel transport, joined ring to ring.
pub fn tubes(lines: &[Vec<DVec3>], sides: usize, radius: impl Fn(DVec3) -> f64) -> TriangleMesh {
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    for points in lines {
        let mut normal = square_to(tangent(points, 0));
        let first = vertices.len() as u32;
        for (i, p) in points.iter().enumerate() {
            let t = tangent(points, i);
            // Parallel transport: the last ring's normal made square to this tangent.
            let moved = normal - t * normal.dot(t);
            normal = if moved.length() > 1e-9 {
                moved.normalize()
            } else {
                square_to(t)
            };
            let binormal = t.cross(normal);
            let r = radius(*p);
            for k in 0..sides {
                let a = k as f64 / sides as f64 * std::f64::consts::TAU;
                vertices.push((*p + (normal * a.cos() + binormal * a.sin()) * r).to_array());
            }
        }
        let sides = sides as u32;
        for i in 0..points.len() as u32 - 1 {
            for k in 0..sides {
                let ring = |r: u32, k: u32| first + r * sides + k % sides;
                let (a, b, c, d) = (
                    ring(i, k),
                    ring(i, k + 1),
                    ring(i + 1, k + 1),
                    ring(i + 1, k),
                );
                push_quad(&mut triangles, [a, b, c, d]);
            }
        }
    }
    mesh(vertices, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    /// Each corner of a ribbon in pixels projects half the width from its point, square
    /// to the line on the picture, at the point's depth.
    #[test]
    fn a_ribbon_in_pixels_projects_half_its_width_from_its_line() {
        let camera = Camera {
            projection: Projection::Perspective,
            rotation: DQuat::from_rotation_y(0.7).to_array(),
            zoom: 1.3,
            ..Default::default()
        };
        let screen = Screen::of(&camera, [97, 61]);
        let line = vec![
            DVec3::new(-1.0, 0.1, 0.0),
            DVec3::new(-0.2, 0.1, 0.1),
            DVec3::new(0.9, -0.3, 0.2),
        ];
        let mesh = ribbons(std::slice::from_ref(&line), |p, side| {
            screen.across(p, side, 2.5)
        });
        for (i, p) in line.iter().enumerate() {
            let (s, z) = screen.project(*p);
            for k in 0..2 {
                let corner = DVec3::from_array(mesh.vertices[2 * i + k]);
                let (c, cz) = screen.project(corner);
                assert!(((c - s).length() - 2.5).abs() < 1e-9, "{i} {k}: {s} {c}");
                assert!((cz - z).abs() < 1e-12, "{i} {k}: depth {z} {cz}");
            }
        }
        assert_eq!(mesh.triangles.len(), 4);
    }
}
