//! The clip as a scene value: checks that name the key ([`ClipSpec::validate`], run when
//! a scene is parsed, so an error points at its line and column), the files a clip names
//! (for saving scenes with absolute paths), and the triangle meshes generated in code
//! ([`torus`], the `torus-mesh` shape: a mesh clip that needs no file).

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use super::texture::MAX_CLIP_VOXELS;
use super::{ClipSpec, ShapeSpec, MAX_DEPTH};
use arbvis_core::vocab::FieldError;
use arbvis_data::surface::{SurfaceError, TriangleMesh};

/// Largest block side accepted (one block of 512³ is already the largest clip grid).
pub const MAX_BLOCK: usize = 512;
/// Most segments along either circle of a generated torus.
pub const MAX_TORUS_SEGMENTS: usize = 1024;

fn finite(key: String, v: &[f64]) -> Result<(), FieldError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(FieldError::new(key, format!("{v:?}: must be finite")))
    }
}

fn positive(key: String, v: &[f64]) -> Result<(), FieldError> {
    if v.iter().all(|x| x.is_finite() && *x > 0.0) {
        Ok(())
    } else {
        Err(FieldError::new(key, format!("{v:?}: must be positive")))
    }
}

impl ShapeSpec {
    /// The scene key of this shape's kind (`sphere`, `union`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            ShapeSpec::Sphere { .. } => "sphere",
            ShapeSpec::Box { .. } => "box",
            ShapeSpec::Cylinder { .. } => "cylinder",
            ShapeSpec::HalfSpace { .. } => "half-space",
            ShapeSpec::Mesh { .. } => "mesh",
            ShapeSpec::TorusMesh { .. } => "torus-mesh",
            ShapeSpec::Mask { .. } => "mask",
            ShapeSpec::Union(_) => "union",
            ShapeSpec::Intersection(_) => "intersection",
            ShapeSpec::Difference(_) => "difference",
        }
    }

    /// Check what can be checked without reading files; the error's key is relative to
    /// the shape (`sphere.radius`; inside a CSG list the list's key, the item in the
    /// message, since a position inside an array has no key).
    pub fn validate(&self) -> Result<(), FieldError> {
        self.validate_at(0)
    }

    fn validate_at(&self, depth: usize) -> Result<(), FieldError> {
        let kind = self.kind();
        let key = |field: &str| format!("{kind}.{field}");
        if depth > MAX_DEPTH {
            return Err(FieldError::new(
                kind,
                format!("clip shapes nested deeper than {MAX_DEPTH}"),
            ));
        }
        match self {
            ShapeSpec::Sphere { center, radius } => {
                finite(key("center"), center)?;
                positive(key("radius"), &[*radius])
            }
            ShapeSpec::Box {
                center,
                half_size,
                rotation,
            } => {
                finite(key("center"), center)?;
                finite(key("rotation"), rotation)?;
                positive(key("half_size"), half_size)
            }
            ShapeSpec::Cylinder {
                center,
                radius,
                half_height,
                rotation,
            } => {
                finite(key("center"), center)?;
                finite(key("rotation"), rotation)?;
                positive(key("radius"), &[*radius])?;
                positive(key("half_height"), &[*half_height])
            }
            ShapeSpec::HalfSpace { point, normal } => {
                finite(key("point"), point)?;
                finite(key("normal"), normal)?;
                let length = normal.iter().map(|c| c * c).sum::<f64>().sqrt();
                if !(length > 0.0 && length.is_finite()) {
                    return Err(FieldError::new(
                        key("normal"),
                        "must not be zero (and its length must be finite)",
                    ));
                }
                Ok(())
            }
            ShapeSpec::Mesh {
                path,
                position,
                scale,
                rotation,
            } => {
                if path.as_os_str().is_empty() {
                    return Err(FieldError::new(key("path"), "must name a file"));
                }
                finite(key("position"), position)?;
                finite(key("rotation"), rotation)?;
                positive(key("scale"), &[*scale])
            }
            ShapeSpec::TorusMesh {
                center,
                major_radius,
                minor_radius,
                rotation,
                segments,
            } => {
                finite(key("center"), center)?;
                finite(key("rotation"), rotation)?;
                positive(key("major_radius"), &[*major_radius])?;
                positive(key("minor_radius"), &[*minor_radius])?;
                if minor_radius >= major_radius {
                    return Err(FieldError::new(
                        key("minor_radius"),
                        format!("{minor_radius}: must be below major_radius {major_radius}"),
                    ));
                }
                if segments
                    .iter()
                    .any(|s| !(3..=MAX_TORUS_SEGMENTS).contains(s))
                {
                    return Err(FieldError::new(
                        key("segments"),
                        format!("{segments:?}: each must be 3..={MAX_TORUS_SEGMENTS}"),
                    ));
                }
                Ok(())
            }
            ShapeSpec::Mask { volume, threshold } => {
                if threshold.is_nan() {
                    return Err(FieldError::new(key("threshold"), "must not be NaN"));
                }
                volume.validate().map_err(|e| e.within(&key("volume")))
            }
            ShapeSpec::Union(list) | ShapeSpec::Intersection(list) => {
                if list.is_empty() {
                    return Err(FieldError::new(kind, "needs at least one shape"));
                }
                for (i, s) in list.iter().enumerate() {
                    s.validate_at(depth + 1)
                        .map_err(|e| FieldError::new(kind, format!("shape {}: {e}", i + 1)))?;
                }
                Ok(())
            }
            ShapeSpec::Difference(pair) => {
                for (i, s) in pair.iter().enumerate() {
                    s.validate_at(depth + 1)
                        .map_err(|e| FieldError::new(kind, format!("shape {}: {e}", i + 1)))?;
                }
                Ok(())
            }
        }
    }

    /// Call `f` on every file path the shape names (meshes, mask volumes).
    pub fn for_each_path(&mut self, f: &mut impl FnMut(&mut PathBuf)) {
        match self {
            ShapeSpec::Mesh { path, .. } => f(path),
            ShapeSpec::Mask { volume, .. } => {
                if let Some(p) = volume.path_mut() {
                    f(p)
                }
            }
            ShapeSpec::Union(list) | ShapeSpec::Intersection(list) => {
                list.iter_mut().for_each(|s| s.for_each_path(f))
            }
            ShapeSpec::Difference(pair) => pair.iter_mut().for_each(|s| s.for_each_path(f)),
            _ => {}
        }
    }
}

impl ClipSpec {
    /// Check what can be checked without reading files; keys relative to the clip table.
    pub fn validate(&self) -> Result<(), FieldError> {
        self.shape.validate().map_err(|e| e.within("shape"))?;
        if !(1..=MAX_BLOCK).contains(&self.block) {
            return Err(FieldError::new(
                "block",
                format!("{}: must be 1..={MAX_BLOCK}", self.block),
            ));
        }
        if let Some(r) = self.resolution {
            let count = r.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
            if r.contains(&0) || count.is_none_or(|n| n > MAX_CLIP_VOXELS) {
                return Err(FieldError::new(
                    "resolution",
                    format!(
                        "{r:?}: each side must be at least 1 and the grid at most {MAX_CLIP_VOXELS} voxels"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A closed torus around the z axis through the origin: `segments[0]` quads around the
/// ring, `segments[1]` around the tube, counter-clockwise seen from outside (outward).
pub fn torus(
    major_radius: f64,
    minor_radius: f64,
    segments: [usize; 2],
) -> Result<TriangleMesh, SurfaceError> {
    let [nu, nv] = segments;
    let mut vertices = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let (su, cu) = (TAU * i as f64 / nu as f64).sin_cos();
        for j in 0..nv {
            let (sv, cv) = (TAU * j as f64 / nv as f64).sin_cos();
            let r = major_radius + minor_radius * cv;
            vertices.push([r * cu, r * su, minor_radius * sv]);
        }
    }
    let at = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    // d/du x d/dv points outward, so (i, j), (i+1, j), (i+1, j+1), (i, j+1) is
    // counter-clockwise seen from outside.
    let quads = (0..nu).flat_map(|i| {
        (0..nv).map(move |j| [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)])
    });
    TriangleMesh::from_indexed(Path::new("generated torus"), vertices, quads)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::clip::mesh_field::MeshShape;
    use glam::{DQuat, DVec3};

    #[test]
    fn the_generated_torus_is_closed_and_holds_its_tube() {
        let mesh = torus(0.6, 0.25, [24, 12]).unwrap();
        assert!(arbvis_data::surface::inspect(&mesh).is_closed());
        let shape = MeshShape::new(&mesh, DVec3::ZERO, DVec3::ONE, DQuat::IDENTITY);
        assert!(shape.inside(DVec3::new(0.6, 0.0, 0.0)));
        assert!(shape.inside(DVec3::new(0.0, -0.7, 0.1)));
        assert!(!shape.inside(DVec3::ZERO), "the hole");
        assert!(!shape.inside(DVec3::new(0.0, 0.0, 0.5)));
        // Outward: the winding number is +1 inside.
        assert!((shape.winding_number(DVec3::new(0.6, 0.0, 0.0)) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn bad_values_name_their_key() {
        let spec = |text: &str| -> ClipSpec { toml::from_str(text).unwrap() };
        let key = |text: &str| spec(text).validate().unwrap_err().key;
        let ok = "shape = { sphere = { center = [0.0, 0.0, 0.0], radius = 0.5 } }";
        assert!(spec(ok).validate().is_ok());
        assert_eq!(key(&format!("{ok}\nblock = 0")), "block");
        assert_eq!(key(&format!("{ok}\nresolution = [2, 0, 2]")), "resolution");
        assert_eq!(
            key("shape = { sphere = { center = [0.0, nan, 0.0], radius = 0.5 } }"),
            "shape.sphere.center"
        );
        assert_eq!(
            key("shape = { torus-mesh = { center = [0.0, 0.0, 0.0], major_radius = 0.5, minor_radius = 0.2, segments = [2, 8] } }"),
            "shape.torus-mesh.segments"
        );
        let nested = "shape = { difference = [{ sphere = { center = [0.0, 0.0, 0.0], radius = 0.5 } }, { box = { center = [0.0, 0.0, 0.0], half_size = [1.0, -1.0, 1.0] } }] }";
        let e = spec(nested).validate().unwrap_err();
        assert_eq!(e.key, "shape.difference");
        assert!(e.message.contains("shape 2: box.half_size"), "{e}");
        assert_eq!(key("shape = { mesh = { path = \"\" } }"), "shape.mesh.path");
    }
}
