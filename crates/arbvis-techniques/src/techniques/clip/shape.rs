//! Clip objects in the volume's object space, with the *clip distance* `c(x)`: positive
//! inside, negative outside, zero on the boundary (the seed's sign: the paper stores
//! "positive inside, negative outside").
//!
//! - Analytic shapes (sphere, box, cylinder, half-space) have exact Euclidean distances.
//!   Box and cylinder carry a rotation, Euler angles in degrees `[x, y, z]` applied about
//!   the fixed axes x first, then y, then z (`R = Rz * Ry * Rx`): a local point is
//!   `R^-1 (x - center)`. The cylinder's axis is its local z.
//! - CSG: union = `max`, intersection = `min`, difference `a - b` = `min(a, -b)`, invert
//!   = `-c`. The result has the right sign everywhere and is exact near most of the
//!   boundary, but away from it it is only a bound (`|c|` at most the true distance; e.g.
//!   inside a union near where two spheres overlap). After the texture's clamp at one
//!   voxel diagonal only the band `|c| < diag` matters, so the bound shows only where the
//!   boundary has a crease (the seam of a union), where values are a little too small in
//!   magnitude and the 0.5 isosurface stays exactly on the boundary.
//! - Meshes: inside by the generalized winding number (see [`super::mesh_field`]).
//! - Masks: a volume thresholded (see [`super::mask_field`]).
//!
//! [`Shape::inside`] is the f64 reference: exact membership of the shape itself, never a
//! texture; [`Shape::distance`] the exact clip distance of analytic shapes (a bound for
//! CSG), `None` when a mesh or mask is involved.

use glam::{DQuat, DVec3};

use super::mask_field::MaskShape;
use super::mesh_field::MeshShape;

/// A clip object, ready to evaluate.
#[derive(Debug, Clone)]
pub enum Shape {
    /// Ball of `radius` around `center`.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius (> 0).
        radius: f64,
    },
    /// Box of `half_size` around `center`, rotated.
    Box {
        /// Centre.
        center: DVec3,
        /// Half the side lengths along the local axes (> 0).
        half_size: DVec3,
        /// Local to object rotation.
        rotation: DQuat,
    },
    /// Capped cylinder along its local z.
    Cylinder {
        /// Centre.
        center: DVec3,
        /// Radius (> 0).
        radius: f64,
        /// Half the height (> 0).
        half_height: f64,
        /// Local to object rotation.
        rotation: DQuat,
    },
    /// Everything behind the plane through `point`: `(x - point) . normal <= 0` (the unit
    /// normal points out of the kept region).
    HalfSpace {
        /// A point of the plane.
        point: DVec3,
        /// Unit outward normal.
        normal: DVec3,
    },
    /// A closed triangle surface.
    Mesh(Box<MeshShape>),
    /// A thresholded volume.
    Mask(Box<MaskShape>),
    /// Inside any.
    Union(Vec<Shape>),
    /// Inside all.
    Intersection(Vec<Shape>),
    /// Inside the first and not the second.
    Difference(Box<Shape>, Box<Shape>),
    /// Outside the shape.
    Invert(Box<Shape>),
}

/// `R = Rz * Ry * Rx` from Euler angles in degrees `[x, y, z]`.
pub fn rotation_from_degrees(degrees: [f64; 3]) -> DQuat {
    let [x, y, z] = degrees.map(f64::to_radians);
    DQuat::from_rotation_z(z) * DQuat::from_rotation_y(y) * DQuat::from_rotation_x(x)
}

impl Shape {
    /// Exact clip distance of analytic shapes (positive inside), a bound for CSG (see the
    /// module doc); `None` when a mesh or mask is part of the shape.
    pub fn distance(&self, p: DVec3) -> Option<f64> {
        Some(match self {
            Shape::Sphere { center, radius } => radius - (p - *center).length(),
            Shape::Box {
                center,
                half_size,
                rotation,
            } => {
                let q = (rotation.inverse() * (p - *center)).abs() - *half_size;
                -(q.max(DVec3::ZERO).length() + q.max_element().min(0.0))
            }
            Shape::Cylinder {
                center,
                radius,
                half_height,
                rotation,
            } => {
                let l = rotation.inverse() * (p - *center);
                let d = glam::DVec2::new(l.truncate().length() - radius, l.z.abs() - half_height);
                -(d.max_element().min(0.0) + d.max(glam::DVec2::ZERO).length())
            }
            Shape::HalfSpace { point, normal } => -(p - *point).dot(*normal),
            Shape::Mesh(_) | Shape::Mask(_) => return None,
            Shape::Union(list) => fold(list, p, f64::max)?,
            Shape::Intersection(list) => fold(list, p, f64::min)?,
            Shape::Difference(a, b) => a.distance(p)?.min(-b.distance(p)?),
            Shape::Invert(a) => -a.distance(p)?,
        })
    }

    /// Exact membership (the f64 reference): true inside or on the boundary.
    pub fn inside(&self, p: DVec3) -> bool {
        match self {
            Shape::Mesh(m) => m.inside(p),
            Shape::Mask(m) => m.inside(p),
            Shape::Union(list) => list.iter().any(|s| s.inside(p)),
            Shape::Intersection(list) => list.iter().all(|s| s.inside(p)),
            Shape::Difference(a, b) => a.inside(p) && !b.strictly_inside(p),
            Shape::Invert(a) => !a.strictly_inside(p),
            _ => self.distance(p).is_some_and(|d| d >= 0.0),
        }
    }

    /// Membership without the boundary (what `Difference` and `Invert` take away).
    fn strictly_inside(&self, p: DVec3) -> bool {
        match self {
            Shape::Mesh(_) | Shape::Mask(_) => self.inside(p),
            Shape::Union(list) => list.iter().any(|s| s.strictly_inside(p)),
            Shape::Intersection(list) => list.iter().all(|s| s.strictly_inside(p)),
            Shape::Difference(a, b) => a.strictly_inside(p) && !b.inside(p),
            Shape::Invert(a) => !a.inside(p),
            _ => self.distance(p).is_some_and(|d| d > 0.0),
        }
    }
}

fn fold(list: &[Shape], p: DVec3, f: fn(f64, f64) -> f64) -> Option<f64> {
    let mut it = list.iter();
    let first = it.next()?.distance(p)?;
    it.try_fold(first, |acc, s| Some(f(acc, s.distance(p)?)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_order_is_x_then_y_then_z() {
        let r = rotation_from_degrees([90.0, 90.0, 0.0]);
        // x first: y -> z; then y: z -> x.
        let v = r * DVec3::Y;
        assert!((v - DVec3::X).length() < 1e-12, "{v}");
        let r = rotation_from_degrees([0.0, 0.0, 90.0]);
        assert!((r * DVec3::X - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn analytic_distances() {
        let s = Shape::Sphere {
            center: DVec3::new(0.1, -0.2, 0.3),
            radius: 0.5,
        };
        assert!((s.distance(DVec3::new(0.1, -0.2, 1.0)).unwrap() + 0.2).abs() < 1e-15);
        let b = Shape::Box {
            center: DVec3::new(0.2, 0.0, 0.0),
            half_size: DVec3::new(0.3, 0.2, 0.1),
            rotation: rotation_from_degrees([0.0, 0.0, 90.0]),
        };
        // Rotated 90 degrees about z: the local x (0.3) runs along object y.
        assert!((b.distance(DVec3::new(0.2, 0.0, 0.0)).unwrap() - 0.1).abs() < 1e-12);
        assert!((b.distance(DVec3::new(0.2, 0.5, 0.0)).unwrap() + 0.2).abs() < 1e-12);
        assert!((b.distance(DVec3::new(0.5, 0.0, 0.0)).unwrap() + 0.1).abs() < 1e-12);
        // Outside a corner: the Euclidean distance to it.
        let d = b
            .distance(DVec3::new(0.2 + 0.2 + 0.3, 0.3 + 0.4, 0.0))
            .unwrap();
        assert!((d + 0.5).abs() < 1e-12, "{d}");
        let c = Shape::Cylinder {
            center: DVec3::ZERO,
            radius: 0.4,
            half_height: 0.25,
            rotation: rotation_from_degrees([90.0, 0.0, 0.0]),
        };
        // Axis along object -y after the x rotation.
        assert!((c.distance(DVec3::new(0.0, 0.3, 0.0)).unwrap() + 0.05).abs() < 1e-12);
        assert!((c.distance(DVec3::new(0.0, 0.0, 0.3)).unwrap() - 0.1).abs() < 1e-12);
        let h = Shape::HalfSpace {
            point: DVec3::new(0.0, 0.0, 0.25),
            normal: DVec3::Z,
        };
        assert_eq!(h.distance(DVec3::new(5.0, 5.0, 0.0)), Some(0.25));
        assert!(h.inside(DVec3::new(0.0, 0.0, 0.25)));
    }

    #[test]
    fn csg_signs_and_boundaries() {
        let a = Shape::Sphere {
            center: DVec3::ZERO,
            radius: 0.5,
        };
        let b = Shape::Sphere {
            center: DVec3::new(0.5, 0.0, 0.0),
            radius: 0.3,
        };
        let diff = Shape::Difference(Box::new(a.clone()), Box::new(b.clone()));
        assert!(!diff.inside(DVec3::new(0.3, 0.0, 0.0)));
        assert!(diff.inside(DVec3::new(0.1, 0.0, 0.0)));
        // The boundary of b belongs to the difference (b's interior is removed).
        assert!(diff.inside(DVec3::new(0.2, 0.0, 0.0)));
        let u = Shape::Union(vec![a.clone(), b.clone()]);
        let d = u.distance(DVec3::new(0.7, 0.0, 0.0)).unwrap();
        assert!((d - 0.1).abs() < 1e-15, "max(-0.2, 0.1): {d}");
        let inv = Shape::Invert(Box::new(a));
        assert!(inv.inside(DVec3::new(0.5, 0.0, 0.0)) && !inv.inside(DVec3::ZERO));
        assert_eq!(Shape::Union(vec![]).distance(DVec3::ZERO), None);
    }
}
