//! What a peer (e.g. `benches/peers/vtk_volume.py`) needs to render a 3D-opacity scene as
//! arbvis does, written by `arbvis bench --export DIR`: the quantized levels of each
//! present attribute (`levels_NAME.u8`, u8, i fastest: the values both systems read), its
//! table (`table_NAME.u8`, 256 x RGBA u8), and `scene.json` with the box, the camera in
//! the peer's terms (position, focal point, view up, parallel scale or view angle), the
//! size, background, reference spacing and combination. With `--score` the reference
//! image sits beside them (`reference.f32`, RGB f32 little-endian, top row first).

use std::path::Path;

use anyhow::{Context, Result};
use glam::DVec3;
use serde::Serialize;

use crate::scene::Scene;
use crate::techniques::opacity3d::prepare::Prepared;
use crate::techniques::opacity3d::renderer::coefficients;
use crate::techniques::opacity3d::Opacity3dScene;
use crate::techniques::opacity3d::ATTRIBUTE_NAMES;
use arbvis_core::camera::Projection;

#[derive(Serialize)]
struct CameraJson {
    projection: &'static str,
    position: [f64; 3],
    focal_point: [f64; 3],
    view_up: [f64; 3],
    /// Half the view's height in object units (orthographic).
    parallel_scale: f64,
    /// Vertical view angle in degrees (perspective).
    view_angle: f64,
}

#[derive(Serialize)]
struct AttributeJson {
    name: &'static str,
    levels: String,
    table: String,
    coefficients: [f64; 4],
}

#[derive(Serialize)]
struct SceneJson {
    dims: [usize; 3],
    /// The box spans [-half, half] in object units.
    half: [f64; 3],
    size: [u32; 2],
    background: [f32; 4],
    /// One voxel along the longest axis: the length a table alpha is the opacity of.
    reference_spacing: f64,
    combine: String,
    volume_filter: String,
    table_filter: String,
    attributes: Vec<AttributeJson>,
    camera: CameraJson,
    reference: &'static str,
    oversample: f64,
}

/// The camera as a peer sets it up (object space: the box is `[-half, half]`).
fn camera_json(scene: &Scene) -> CameraJson {
    let c = &scene.camera;
    let q = c.quat().inverse();
    let toward_viewer = q * DVec3::Z;
    let up = q * DVec3::Y;
    let [w, h] = scene.size;
    let aspect = w as f64 / h.max(1) as f64;
    // The projection matrix spans [-1, 1] (over the zoom) along the shorter side.
    let sy = if aspect >= 1.0 { 1.0 } else { 1.0 / aspect };
    let fov = c.fov_y_deg.clamp(1.0, 170.0).to_radians();
    let fov = if aspect >= 1.0 {
        fov
    } else {
        2.0 * ((fov / 2.0).tan() * sy).atan()
    };
    let (projection, distance) = match c.projection {
        Projection::Orthographic => ("orthographic", 10.0),
        Projection::Perspective => ("perspective", c.eye_distance()),
    };
    CameraJson {
        projection,
        position: (toward_viewer * distance).to_array(),
        focal_point: [0.0; 3],
        view_up: up.to_array(),
        parallel_scale: sy / c.zoom.max(1e-6),
        view_angle: fov.to_degrees(),
    }
}

/// Write the peer's files into `dir` (created if needed).
pub fn write(dir: &Path, scene: &Scene, prepared: &Prepared, oversample: f64) -> Result<()> {
    let Some(params) = scene.technique.get::<Opacity3dScene>() else {
        anyhow::bail!("--export needs a 3D-opacity or cell-projection volume scene");
    };
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let voxels = prepared.dims.iter().product::<usize>();
    let coeff = coefficients(params);
    let mut attributes = Vec::new();
    for (a, name) in ATTRIBUTE_NAMES.iter().enumerate() {
        let Some(table) = &prepared.tables[a] else {
            continue;
        };
        let levels: Vec<u8> = (0..voxels).map(|v| prepared.byte(v, a)).collect();
        let levels_file = format!("levels_{name}.u8");
        let table_file = format!("table_{name}.u8");
        arbvis_core::png_io::write_atomic(&dir.join(&levels_file), &levels)?;
        arbvis_core::png_io::write_atomic(&dir.join(&table_file), &table.texels())?;
        attributes.push(AttributeJson {
            name,
            levels: levels_file,
            table: table_file,
            coefficients: coeff[a],
        });
    }
    let json = SceneJson {
        dims: prepared.dims,
        half: prepared.half.to_array(),
        size: scene.size,
        background: scene.background,
        reference_spacing: prepared.reference_spacing(),
        combine: format!("{:?}", params.combine).to_lowercase(),
        volume_filter: format!("{:?}", params.volume_filter).to_lowercase(),
        table_filter: format!("{:?}", params.table_filter).to_lowercase(),
        attributes,
        camera: camera_json(scene),
        reference: "reference.f32",
        oversample,
    };
    let text = serde_json::to_string_pretty(&json)?;
    arbvis_core::png_io::write_atomic(&dir.join("scene.json"), text.as_bytes())?;
    Ok(())
}

#[derive(Serialize)]
struct MeshJson {
    points: usize,
    tets: usize,
    /// Object-space points (f64 xyz), tetrahedra (u32 x 4), normalized point scalars (f64).
    points_file: &'static str,
    tets_file: &'static str,
    scalars_file: &'static str,
    /// Transfer function control points `[s, r, g, b, a]` over the normalized scalar.
    transfer: Vec<[f64; 5]>,
    /// VTK's scalar opacity unit distance, in the exported (object) units.
    unit_distance: f64,
    size: [u32; 2],
    background: [f32; 4],
    camera: CameraJson,
    reference: &'static str,
}

/// Write a cell-projection volume scene for a peer (`benches/peers/vtk_unstructured.py`):
/// the prepared mesh in object units, its scalars, the transfer function, the camera
/// and the reference's RGB.
pub fn write_cellproj(
    dir: &Path,
    scene: &Scene,
    prepared: &crate::techniques::cellproj::prepare::Prepared,
    tf: &crate::techniques::cellproj::transfer::Transfer,
    reference_rgb: &[f32],
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let points: Vec<u8> = prepared
        .points
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let tets: Vec<u8> = prepared
        .tets
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let scalars: Vec<u8> = prepared
        .scalars
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let rgb: Vec<u8> = reference_rgb.iter().flat_map(|v| v.to_le_bytes()).collect();
    arbvis_core::png_io::write_atomic(&dir.join("points.f64"), &points)?;
    arbvis_core::png_io::write_atomic(&dir.join("tets.u32"), &tets)?;
    arbvis_core::png_io::write_atomic(&dir.join("scalars.f64"), &scalars)?;
    arbvis_core::png_io::write_atomic(&dir.join("reference.f32"), &rgb)?;
    let json = MeshJson {
        points: prepared.points.len(),
        tets: prepared.tets.len(),
        points_file: "points.f64",
        tets_file: "tets.u32",
        scalars_file: "scalars.f64",
        transfer: tf
            .s
            .iter()
            .zip(&tf.rgba)
            .map(|(s, c)| [*s, c[0], c[1], c[2], c[3]])
            .collect(),
        unit_distance: tf.unit,
        size: scene.size,
        background: scene.background,
        camera: camera_json(scene),
        reference: "reference.f32",
    };
    let text = serde_json::to_string_pretty(&json)?;
    arbvis_core::png_io::write_atomic(&dir.join("scene.json"), text.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_of_the_bench_scene_looks_down_the_time_axis() {
        let text = include_str!("../../../../scenes/bench/cube256-amplitude.toml");
        let scene = Scene::parse(text, "bench").unwrap();
        let c = camera_json(&scene);
        // +i (the time axis) points toward the viewer, +j stays up.
        assert!((c.position[0] - 10.0).abs() < 1e-9, "{:?}", c.position);
        assert!(c.position[1].abs() < 1e-9 && c.position[2].abs() < 1e-9);
        assert!((c.view_up[1] - 1.0).abs() < 1e-9, "{:?}", c.view_up);
        assert_eq!(c.parallel_scale, 1.0);
    }
}
