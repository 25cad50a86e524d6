//! Camera and arcball (Shoemake): a rotation about the scene centre, a zoom, and an
//! orthographic or perspective projection. Pure glam, no GL.

use glam::{DMat4, DQuat, DVec2, DVec3};

/// Projection kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Parallel projection (the cell-projection seed's per-vertex exit case).
    #[default]
    Orthographic,
    /// Pinhole perspective.
    Perspective,
}

/// Where the scene is seen from. The scene occupies [-1, 1]³ in world units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Camera {
    /// Orthographic or perspective.
    pub projection: Projection,
    /// Rotation of the scene as a quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
    /// Magnification (1 = the [-1, 1] square fills the shorter side).
    pub zoom: f64,
    /// Vertical field of view in degrees (perspective only).
    pub fov_y_deg: f64,
    /// Where the drawn layer's own frame sits in the scene's (a uniform scale and an
    /// offset, [`Placement`]): set by a layered scene for each of its layers as it draws
    /// them, identity for a one-layer scene; never written in a scene.
    #[serde(skip)]
    pub placement: Placement,
}

/// A layer's own frame placed in the scene's: `scene = scale * rotation * own + offset`.
/// Uniform and rigid, so depth order, angles and proportions are the layer's own; a
/// negative scale mirrors (a survey grid turned the other way round).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Scene units per unit of the layer's frame (above 0).
    pub scale: f64,
    /// The layer's axes turned into the scene's (a survey's sample axis downwards).
    pub rotation: DQuat,
    /// Where the layer's origin lies in the scene's frame.
    pub offset: DVec3,
}

impl Default for Placement {
    fn default() -> Self {
        Placement {
            scale: 1.0,
            rotation: DQuat::IDENTITY,
            offset: DVec3::ZERO,
        }
    }
}

impl Placement {
    /// The matrix from the layer's frame to the scene's.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(DVec3::splat(self.scale), self.rotation, self.offset)
    }

    /// A point of the scene's frame in the layer's.
    pub fn to_own(&self, scene: DVec3) -> DVec3 {
        self.rotation.inverse() * ((scene - self.offset) / self.scale)
    }
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            projection: Projection::Orthographic,
            rotation: [0.0, 0.0, 0.0, 1.0],
            zoom: 1.0,
            fov_y_deg: 30.0,
            placement: Placement::default(),
        }
    }
}

impl Camera {
    /// The rotation as a normalized quaternion (identity when degenerate).
    pub fn quat(&self) -> DQuat {
        let q = DQuat::from_array(self.rotation);
        if q.length_squared() > 1e-12 && q.is_finite() {
            q.normalize()
        } else {
            DQuat::IDENTITY
        }
    }

    /// Model-view matrix: place the layer in the scene, rotate the scene, then
    /// (perspective) move it in front of the eye.
    pub fn view(&self) -> DMat4 {
        let rotate = DMat4::from_quat(self.quat()) * self.placement.matrix();
        match self.projection {
            Projection::Orthographic => rotate,
            Projection::Perspective => {
                DMat4::from_translation(DVec3::new(0.0, 0.0, -self.eye_distance())) * rotate
            }
        }
    }

    /// The unit direction toward the viewer in the drawn layer's frame (the slices'
    /// normal; the opposite of the viewing direction).
    pub fn toward_viewer(&self) -> DVec3 {
        let mirrored = self.placement.scale.signum();
        self.placement.rotation.inverse() * (self.quat().inverse() * DVec3::Z) * mirrored
    }

    /// The eye in the drawn layer's frame (perspective): `R⁻¹ (0, 0, d)` in the scene's,
    /// taken into the layer's by its placement.
    pub fn eye(&self) -> DVec3 {
        let eye = self.quat().inverse() * DVec3::new(0.0, 0.0, self.eye_distance());
        self.placement.to_own(eye)
    }

    /// Distance from the eye to the scene centre in perspective (fits the unit sphere).
    pub fn eye_distance(&self) -> f64 {
        let half = (self.fov_y_deg.clamp(1.0, 170.0).to_radians() / 2.0).tan();
        3f64.sqrt() / half / self.zoom.max(1e-6)
    }

    /// Projection matrix for `aspect` = width / height; the depth range holds [-√3, √3].
    pub fn projection_matrix(&self, aspect: f64) -> DMat4 {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let (sx, sy) = if aspect >= 1.0 {
            (aspect, 1.0)
        } else {
            (1.0, 1.0 / aspect)
        };
        match self.projection {
            Projection::Orthographic => {
                let z = self.zoom.max(1e-6);
                orthographic_gl(-sx / z, sx / z, -sy / z, sy / z, -2.0, 2.0)
            }
            Projection::Perspective => {
                let d = self.eye_distance();
                let fov = self.fov_y_deg.clamp(1.0, 170.0).to_radians();
                let fov = if aspect >= 1.0 {
                    fov
                } else {
                    2.0 * ((fov / 2.0).tan() * sy).atan()
                };
                perspective_gl(fov, aspect, (d - 2.0).max(1e-3), d + 2.0)
            }
        }
    }

    /// Projection times view.
    pub fn view_projection(&self, aspect: f64) -> DMat4 {
        self.projection_matrix(aspect) * self.view()
    }
}

/// A view: the camera's view-projection over the data's frame, its projection's y scale
/// (`P[1][1]`), and the image size (what a renderer is first built for, and what a COPC
/// cloud's nodes are chosen for).
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Clip from frame coordinates.
    pub view_projection: DMat4,
    /// The projection matrix's `[1][1]`: pixels per unit at clip w = 1, over half the
    /// height.
    pub projection_y: f64,
    /// Image width and height in pixels.
    pub size: [u32; 2],
}

impl View {
    /// The view of `camera` on an image of `size` pixels.
    pub fn of(camera: &Camera, size: [u32; 2]) -> View {
        let aspect = size[0].max(1) as f64 / size[1].max(1) as f64;
        View {
            view_projection: camera.view_projection(aspect),
            projection_y: camera.projection_matrix(aspect).y_axis.y,
            size,
        }
    }
}

/// `glOrtho`'s matrix (right-handed eye space, depth to [-1, 1]).
pub fn orthographic_gl(l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> DMat4 {
    DMat4::from_cols_array(&[
        2.0 / (r - l),
        0.0,
        0.0,
        0.0,
        0.0,
        2.0 / (t - b),
        0.0,
        0.0,
        0.0,
        0.0,
        -2.0 / (f - n),
        0.0,
        -(r + l) / (r - l),
        -(t + b) / (t - b),
        -(f + n) / (f - n),
        1.0,
    ])
}

/// `gluPerspective`'s matrix (vertical field of view in radians).
pub fn perspective_gl(fov_y: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    let f = 1.0 / (fov_y / 2.0).tan();
    DMat4::from_cols_array(&[
        f / aspect,
        0.0,
        0.0,
        0.0,
        0.0,
        f,
        0.0,
        0.0,
        0.0,
        0.0,
        (far + near) / (near - far),
        -1.0,
        0.0,
        0.0,
        2.0 * far * near / (near - far),
        0.0,
    ])
}

/// Arcball dragging: maps window points to the unit sphere and composes rotations.
#[derive(Debug, Clone, Copy, Default)]
pub struct Arcball {
    start: Option<(DVec3, DQuat)>,
}

impl Arcball {
    /// Map a window point (pixels, y down) in a `size` window onto the arcball sphere.
    pub fn sphere_point(p: DVec2, size: DVec2) -> DVec3 {
        let r = size.x.min(size.y).max(1.0) / 2.0;
        let x = (p.x - size.x / 2.0) / r;
        let y = (size.y / 2.0 - p.y) / r;
        let d2 = x * x + y * y;
        if d2 <= 1.0 {
            DVec3::new(x, y, (1.0 - d2).sqrt())
        } else {
            DVec3::new(x, y, 0.0) / d2.sqrt()
        }
    }

    /// Start a drag at window point `p` with the camera's current rotation.
    pub fn begin(&mut self, camera: &Camera, p: DVec2, size: DVec2) {
        self.start = Some((Self::sphere_point(p, size), camera.quat()));
    }

    /// Continue the drag to `p`, updating the camera's rotation.
    pub fn drag(&mut self, camera: &mut Camera, p: DVec2, size: DVec2) {
        if let Some((from, q0)) = self.start {
            let to = Self::sphere_point(p, size);
            let q = DQuat::from_rotation_arc(from, to) * q0;
            camera.rotation = q.normalize().to_array();
        }
    }

    /// End the drag.
    pub fn end(&mut self) {
        self.start = None;
    }

    /// Whether a drag is under way.
    pub fn dragging(&self) -> bool {
        self.start.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_orthographic_maps_unit_square_to_clip_square() {
        let m = Camera::default().view_projection(1.0);
        let p = m.project_point3(DVec3::new(1.0, -1.0, 0.0));
        assert!((p - DVec3::new(1.0, -1.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn wide_aspect_keeps_square_pixels() {
        let m = Camera::default().view_projection(2.0);
        let p = m.project_point3(DVec3::new(1.0, 1.0, 0.0));
        assert!((p.x - 0.5).abs() < 1e-12 && (p.y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn arcball_drag_right_rotates_about_y() {
        let size = DVec2::new(200.0, 200.0);
        let mut cam = Camera::default();
        let mut ball = Arcball::default();
        ball.begin(&cam, DVec2::new(100.0, 100.0), size);
        ball.drag(&mut cam, DVec2::new(150.0, 100.0), size);
        let q = cam.quat();
        let (axis, angle) = q.to_axis_angle();
        assert!((axis - DVec3::Y).length() < 1e-9, "axis {axis}");
        assert!((angle - 0.5f64.asin()).abs() < 1e-9, "angle {angle}");
    }

    #[test]
    fn degenerate_rotation_is_identity() {
        let cam = Camera {
            rotation: [0.0, 0.0, 0.0, 0.0],
            ..Camera::default()
        };
        assert_eq!(cam.quat(), DQuat::IDENTITY);
    }

    #[test]
    fn perspective_keeps_scene_in_depth_range() {
        let cam = Camera {
            projection: Projection::Perspective,
            ..Camera::default()
        };
        let m = cam.view_projection(1.0);
        for z in [-1.0, 1.0] {
            let p = m.project_point3(DVec3::new(0.0, 0.0, z));
            assert!(p.z > -1.0 && p.z < 1.0, "z {z} -> {}", p.z);
        }
    }
}

#[cfg(test)]
mod placement_tests {
    use super::*;

    /// A placed layer's eye and viewing direction, taken back to the scene's frame, are
    /// the unplaced camera's, for odd placements in both projections.
    #[test]
    fn a_placed_layer_sees_the_scenes_eye_and_direction() {
        let placements = [
            Placement::default(),
            Placement {
                scale: 0.37,
                rotation: DQuat::from_euler(glam::EulerRot::XYZ, 0.7, -0.2, 2.1),
                offset: DVec3::new(0.21, -0.53, 0.11),
            },
            Placement {
                scale: 3.9,
                rotation: DQuat::from_rotation_y(-std::f64::consts::FRAC_PI_2),
                offset: DVec3::new(-1.0, 0.0, 0.4),
            },
            // Mirrored.
            Placement {
                scale: -0.8,
                rotation: DQuat::from_euler(glam::EulerRot::ZXY, 0.3, 0.1, -1.2),
                offset: DVec3::new(0.5, 0.25, -0.75),
            },
        ];
        for projection in [Projection::Perspective, Projection::Orthographic] {
            let unplaced = Camera {
                projection,
                rotation: DQuat::from_euler(glam::EulerRot::YXZ, 1.1, -0.4, 0.3).to_array(),
                zoom: 1.7,
                ..Camera::default()
            };
            for placement in placements {
                let placed = Camera {
                    placement,
                    ..unplaced
                };
                let m = placement.matrix();
                // f64 arithmetic on values of order 10: 1e-12.
                let eye = m.transform_point3(placed.eye());
                assert!((eye - unplaced.eye()).length() < 1e-12, "{placement:?}");
                let toward = m.transform_vector3(placed.toward_viewer()) / placement.scale.abs();
                assert!((toward - unplaced.toward_viewer()).length() < 1e-12);
                let p = DVec3::new(0.3, -0.8, 0.5);
                let a = placed.view_projection(1.3).project_point3(p);
                let b = unplaced
                    .view_projection(1.3)
                    .project_point3(m.transform_point3(p));
                assert!((a - b).length() < 1e-12);
                assert!((placement.to_own(m.transform_point3(p)) - p).length() < 1e-12);
            }
        }
    }
}
