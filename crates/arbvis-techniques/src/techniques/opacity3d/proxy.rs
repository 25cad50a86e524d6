//! The geometry a 3D opacity frame is drawn on, one kind per drawing path: v3o2's
//! view-aligned slices (remade when the view direction or the slice count changes, and
//! drawn in parts, a run of slices each), or the box's far faces for the ray caster (made
//! once; one fragment per pixel marches the ray).

use glam::DVec3;

use super::slicing::slice_box;
use super::Path3d;
use crate::techniques::Frame;
use arbvis_gl::{GlResult, Gpu, Mesh};

/// The view a slice mesh was made for: the direction toward the viewer (its bits) and the
/// slice count.
type SliceKey = ([u64; 3], usize);

/// The drawn geometry of the current path.
#[derive(Default)]
pub enum Proxy {
    /// Nothing made yet (or dropped with the program it was drawn with).
    #[default]
    None,
    /// View-aligned slices, back to front.
    Slices {
        /// The triangles.
        mesh: Mesh,
        /// The view they were made for.
        key: SliceKey,
        /// The vertex at the end of each slice (for drawing in parts).
        ends: Vec<usize>,
        /// The distance between slices, in box units.
        spacing: f64,
    },
    /// The box's far faces.
    Box(Mesh),
}

impl Proxy {
    /// Make what `path` draws for `frame` on a box of half extents `half` (`slices`
    /// slices), keeping what is already right.
    pub fn update(
        &mut self,
        gpu: &Gpu,
        path: Path3d,
        half: DVec3,
        frame: &Frame,
        slices: usize,
    ) -> GlResult<()> {
        if path == Path3d::Raycast {
            if !matches!(self, Proxy::Box(_)) {
                let vertices = far_faces(half);
                *self = Proxy::Box(Mesh::new(gpu, "opacity3d box", &[4, 4], &vertices)?);
            }
            return Ok(());
        }
        let dir = toward_viewer(frame);
        let key = (dir.to_array().map(f64::to_bits), slices);
        if matches!(self, Proxy::Slices { key: k, .. } if *k == key) {
            return Ok(());
        }
        let made = slice_box(half, dir, slices);
        let vertices = made.triangle_vertices();
        let slice_ends: Vec<usize> = made
            .polygons
            .iter()
            .scan(0, |end, p| {
                *end += 3 * p.positions.len().saturating_sub(2);
                Some(*end)
            })
            .collect();
        match self {
            Proxy::Slices {
                mesh,
                key: k,
                ends,
                spacing,
            } => {
                mesh.update(gpu, &vertices)?;
                (*k, *ends, *spacing) = (key, slice_ends, made.spacing);
            }
            _ => {
                *self = Proxy::Slices {
                    mesh: Mesh::new(gpu, "opacity3d slices", &[4, 4], &vertices)?,
                    key,
                    ends: slice_ends,
                    spacing: made.spacing,
                }
            }
        }
        Ok(())
    }

    /// The mesh to draw, once made.
    pub fn mesh(&self) -> Option<&Mesh> {
        match self {
            Proxy::None => None,
            Proxy::Slices { mesh, .. } | Proxy::Box(mesh) => Some(mesh),
        }
    }

    /// The vertex at the end of each slice (none for the box: one part).
    pub fn slice_ends(&self) -> &[usize] {
        match self {
            Proxy::Slices { ends, .. } => ends,
            _ => &[],
        }
    }

    /// The distance between slices (0 for the box).
    pub fn spacing(&self) -> f64 {
        match self {
            Proxy::Slices { spacing, .. } => *spacing,
            _ => 0.0,
        }
    }
}

/// Direction toward the viewer in object space (the slices' normal).
pub fn toward_viewer(frame: &Frame) -> DVec3 {
    frame.camera.toward_viewer()
}

/// The eye in object space (perspective).
pub fn eye(frame: &Frame) -> DVec3 {
    frame.camera.eye()
}

/// The box `[-half, half]` as 12 triangles wound clockwise seen from outside, so that
/// with back faces culled only the far side of the box is drawn (one fragment per pixel);
/// vertices `[position xyzw, texcoord xyzw]`.
pub fn far_faces(half: DVec3) -> Vec<f32> {
    let mut out = Vec::with_capacity(36 * 8);
    for axis in 0..3 {
        for side in [-1.0, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f64, b: f64| {
                let mut p = DVec3::ZERO;
                p[axis] = side;
                p[u] = a;
                p[v] = b;
                p
            };
            // (u, v, axis) is right-handed: u then v is counter-clockwise seen from +axis.
            let mut quad = [
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            ];
            if side > 0.0 {
                quad.reverse();
            }
            for i in [0, 1, 2, 0, 2, 3] {
                let t = (quad[i] + 1.0) / 2.0;
                let p = quad[i] * half;
                out.extend_from_slice(&[
                    p.x as f32, p.y as f32, p.z as f32, 1.0, t.x as f32, t.y as f32, t.z as f32,
                    1.0,
                ]);
            }
        }
    }
    out
}
