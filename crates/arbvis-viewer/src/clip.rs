//! The clip editor of 3D opacity (`[technique.opacity3d.clip]`), a collapsible "Clip"
//! section: clipping on or off, the shape's kind (sphere, box, cylinder, half-space,
//! torus-mesh), its position, size and rotation (Euler degrees; the normal for a
//! half-space), `invert`, the block side `B` and INDEX-DATA on or off, and what the clip
//! cost when last built (time, texture bytes, compression ratio), from
//! [`arbvis_techniques::techniques::Renderer::facts`].
//!
//! Decisions: clipping switched on restores the clip last switched off, else adds a
//! sphere of radius 0.5 at the centre. A shape the editor cannot edit (a file mesh, a
//! mask, CSG) is kept while the scene is open: it shows read-only with its kind and stays
//! among the kinds (`scene-mesh`, ...) after switching to another. Switching kind keeps
//! the position, a size and the rotation. Each edit changes the scene; the renderer
//! rebuilds the clip on that frame only when the clip changed, never on other frames or
//! other edits (the demo's 64³ clip rebuilds well within a frame on llvmpipe, so a
//! dragged number rebuilds once per frame it changes; measured: docs/benchmarks.md,
//! "Clipping").

use super::widgets::{SetOutcome, Widgets};
use arbvis_techniques::techniques::clip::{ClipSpec, ShapeSpec};
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;

/// Block sides offered for `B`.
pub const BLOCKS: [usize; 4] = [4, 8, 16, 32];
/// Shape kinds the editor makes.
pub const KINDS: [&str; 5] = ["sphere", "box", "cylinder", "half-space", "torus-mesh"];
/// Positions and sizes are edited within this many units of the origin (the volume's box
/// has its longest side `[-1, 1]`).
pub const REACH: f64 = 10.0;
/// Smallest size accepted (sizes must be positive).
pub const MIN_SIZE: f64 = 1e-3;

/// What the editor keeps between frames (not part of the scene).
#[derive(Debug, Default)]
pub struct ClipEditor {
    /// The clip last switched off, restored when switched on.
    disabled: Option<ClipSpec>,
    /// A shape from the scene the editor cannot edit, kept to be chosen again.
    kept: Option<ShapeSpec>,
    /// The clip's cost as last built (the viewer copies it from the renderer's facts).
    pub stats: Option<String>,
}

/// The clip added when clipping is switched on: a sphere of radius 0.5 at the centre.
pub fn default_clip() -> ClipSpec {
    ClipSpec {
        shape: ShapeSpec::Sphere {
            center: [0.0; 3],
            radius: 0.5,
        },
        invert: false,
        block: 8,
        multires: true,
        resolution: None,
    }
}

/// Whether the editor edits `shape`'s parameters (else it is shown read-only).
pub fn editable(shape: &ShapeSpec) -> bool {
    KINDS.contains(&shape.kind())
}

/// The position, a size and the rotation of `shape` (what a change of kind keeps).
fn placement(shape: &ShapeSpec) -> ([f64; 3], f64, [f64; 3]) {
    match shape {
        ShapeSpec::Sphere { center, radius } => (*center, *radius, [0.0; 3]),
        ShapeSpec::Box {
            center,
            half_size,
            rotation,
        } => (
            *center,
            half_size.iter().copied().fold(0.0, f64::max),
            *rotation,
        ),
        ShapeSpec::Cylinder {
            center,
            radius,
            rotation,
            ..
        } => (*center, *radius, *rotation),
        ShapeSpec::HalfSpace { point, .. } => (*point, 0.5, [0.0; 3]),
        ShapeSpec::TorusMesh {
            center,
            major_radius,
            rotation,
            ..
        } => (*center, *major_radius, *rotation),
        ShapeSpec::Mesh {
            position, rotation, ..
        } => (*position, 0.5, *rotation),
        _ => ([0.0; 3], 0.5, [0.0; 3]),
    }
}

/// A shape of `kind` (one of [`KINDS`]) placed where `from` was.
pub fn convert(from: &ShapeSpec, kind: &str) -> ShapeSpec {
    let (center, size, rotation) = placement(from);
    let size = size.clamp(MIN_SIZE, REACH);
    match kind {
        "box" => ShapeSpec::Box {
            center,
            half_size: [size; 3],
            rotation,
        },
        "cylinder" => ShapeSpec::Cylinder {
            center,
            radius: size,
            half_height: size,
            rotation,
        },
        "half-space" => ShapeSpec::HalfSpace {
            point: center,
            normal: [0.0, 0.0, 1.0],
        },
        "torus-mesh" => ShapeSpec::TorusMesh {
            center,
            major_radius: size,
            minor_radius: size * 0.4,
            rotation,
            segments: [48, 24],
        },
        _ => ShapeSpec::Sphere {
            center,
            radius: size,
        },
    }
}

/// What a shape the editor cannot edit is, in a line.
fn describe(shape: &ShapeSpec) -> String {
    match shape {
        ShapeSpec::Mesh {
            path,
            position,
            scale,
            rotation,
        } => format!(
            "mesh {} at {position:?}, scale {scale}, rotation {rotation:?} (read-only)",
            path.display()
        ),
        ShapeSpec::Mask { threshold, .. } => {
            format!("mask volume, inside where >= {threshold} (read-only)")
        }
        ShapeSpec::Union(l) | ShapeSpec::Intersection(l) => {
            format!("{} of {} shapes (read-only)", shape.kind(), l.len())
        }
        other => format!("{} (read-only)", other.kind()),
    }
}

/// Three numbers in a row, labelled `{prefix} x`, `{prefix} y`, `{prefix} z`.
fn triple(
    ui: &mut egui::Ui,
    w: &mut Widgets,
    prefix: &str,
    text: &str,
    v: &mut [f64; 3],
    range: std::ops::RangeInclusive<f64>,
    speed: f64,
) -> bool {
    let mut changed = false;
    ui.horizontal_wrapped(|ui| {
        ui.label(text);
        for (c, axis) in v.iter_mut().zip(["x", "y", "z"]) {
            changed |= w.drag_value(ui, &format!("{prefix} {axis}"), c, range.clone(), speed);
        }
    });
    changed
}

/// A size in `MIN_SIZE..=REACH` (or `lo..=hi`), labelled `label`.
fn size(ui: &mut egui::Ui, w: &mut Widgets, label: &str, v: &mut f64, lo: f64, hi: f64) -> bool {
    ui.horizontal(|ui| {
        ui.label(label.trim_start_matches("Clip "));
        w.drag_value(ui, label, v, lo..=hi, 0.005)
    })
    .inner
}

/// The shape's own parameters; true when one changed.
fn shape_editor(ui: &mut egui::Ui, w: &mut Widgets, shape: &mut ShapeSpec) -> bool {
    let pos = -REACH..=REACH;
    let deg = -360.0..=360.0;
    let mut changed = false;
    match shape {
        ShapeSpec::Sphere { center, radius } => {
            changed |= triple(ui, w, "Clip", "centre", center, pos, 0.005);
            changed |= size(ui, w, "Clip radius", radius, MIN_SIZE, REACH);
        }
        ShapeSpec::Box {
            center,
            half_size,
            rotation,
        } => {
            changed |= triple(ui, w, "Clip", "centre", center, pos, 0.005);
            changed |= triple(
                ui,
                w,
                "Clip half",
                "half size",
                half_size,
                MIN_SIZE..=REACH,
                0.005,
            );
            changed |= triple(ui, w, "Clip rotation", "rotation °", rotation, deg, 0.5);
        }
        ShapeSpec::Cylinder {
            center,
            radius,
            half_height,
            rotation,
        } => {
            changed |= triple(ui, w, "Clip", "centre", center, pos, 0.005);
            changed |= size(ui, w, "Clip radius", radius, MIN_SIZE, REACH);
            changed |= size(ui, w, "Clip half height", half_height, MIN_SIZE, REACH);
            changed |= triple(ui, w, "Clip rotation", "rotation °", rotation, deg, 0.5);
        }
        ShapeSpec::HalfSpace { point, normal } => {
            changed |= triple(ui, w, "Clip", "point", point, pos, 0.005);
            let before = *normal;
            if triple(ui, w, "Clip normal", "normal", normal, -1.0..=1.0, 0.01) {
                if normal.iter().all(|c| *c == 0.0) {
                    *normal = before;
                    w.set_outcome(SetOutcome::Refused(
                        "the clip normal must not be zero".into(),
                    ));
                } else {
                    changed = true;
                }
            }
        }
        ShapeSpec::TorusMesh {
            center,
            major_radius,
            minor_radius,
            rotation,
            ..
        } => {
            changed |= triple(ui, w, "Clip", "centre", center, pos, 0.005);
            // The tube stays thinner than the ring (the scene's rule).
            let lo = *minor_radius * 1.001;
            changed |= size(ui, w, "Clip major radius", major_radius, lo, REACH);
            let hi = *major_radius * 0.999;
            changed |= size(ui, w, "Clip minor radius", minor_radius, MIN_SIZE, hi);
            changed |= triple(ui, w, "Clip rotation", "rotation °", rotation, deg, 0.5);
        }
        other => w.text(ui, "Clip shape details", &describe(other)),
    }
    changed
}

/// Draw the "Clip" section; true when the scene's clip changed.
pub fn editor(
    ui: &mut egui::Ui,
    scene: &mut Opacity3dScene,
    state: &mut ClipEditor,
    w: &mut Widgets,
) -> bool {
    let header = egui::CollapsingHeader::new("Clip")
        .default_open(scene.clip.is_some())
        .show(ui, |ui| body(ui, scene, state, w));
    w.add(ui, "Clip", &header.header_response);
    header.body_returned.unwrap_or(false)
}

fn body(
    ui: &mut egui::Ui,
    scene: &mut Opacity3dScene,
    state: &mut ClipEditor,
    w: &mut Widgets,
) -> bool {
    let mut changed = false;
    let mut on = scene.clip.is_some();
    if w.checkbox(ui, "Clip enabled", &mut on, "Clip (keep what is inside)")
        && on != scene.clip.is_some()
    {
        if on {
            scene.clip = Some(state.disabled.take().unwrap_or_else(default_clip));
        } else {
            state.disabled = scene.clip.take();
        }
        changed = true;
    }
    let Some(clip) = &mut scene.clip else {
        return changed;
    };
    if !editable(&clip.shape) && state.kept.as_ref() != Some(&clip.shape) {
        state.kept = Some(clip.shape.clone());
    }
    let kept = state.kept.as_ref().map(|s| format!("scene-{}", s.kind()));
    let mut options: Vec<(String, &str)> = KINDS.iter().map(|k| (k.to_string(), *k)).collect();
    if let Some(k) = &kept {
        options.push((k.clone(), k.as_str()));
    }
    let mut kind = if editable(&clip.shape) {
        clip.shape.kind().to_string()
    } else {
        kept.clone().unwrap_or_default()
    };
    ui.horizontal_wrapped(|ui| {
        ui.label("Shape");
        if w.choice(ui, "Clip shape", &mut kind, &options, 120.0) {
            let shape = match (&state.kept, kept.as_deref()) {
                (Some(s), Some(k)) if k == kind => s.clone(),
                _ => convert(&clip.shape, &kind),
            };
            if shape != clip.shape {
                clip.shape = shape;
                changed = true;
            }
        }
    });
    changed |= shape_editor(ui, w, &mut clip.shape);
    changed |= w.checkbox(
        ui,
        "Clip invert",
        &mut clip.invert,
        "Invert (keep the outside)",
    );
    changed |= w.checkbox(
        ui,
        "Clip multires",
        &mut clip.multires,
        "INDEX-DATA (multi-resolution)",
    );
    let mut blocks: Vec<usize> = BLOCKS.to_vec();
    if !blocks.contains(&clip.block) {
        blocks.push(clip.block);
    }
    let names: Vec<String> = blocks.iter().map(|b| b.to_string()).collect();
    let options: Vec<(usize, &str)> = blocks
        .iter()
        .copied()
        .zip(names.iter().map(String::as_str))
        .collect();
    ui.add_enabled_ui(clip.multires, |ui| {
        ui.horizontal_wrapped(|ui| {
            ui.label("Block B");
            changed |= w.choice(ui, "Clip block", &mut clip.block, &options, 60.0);
        });
    });
    if let Some(r) = clip.resolution {
        ui.label(format!(
            "clip grid {}x{}x{} (from the scene)",
            r[0], r[1], r[2]
        ));
    }
    let line = match &state.stats {
        Some(s) => s.clone(),
        None => "not built yet".to_string(),
    };
    w.text(ui, arbvis_techniques::techniques::clip::stats::LABEL, &line);
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_of_kind_keeps_the_placement() {
        let sphere = ShapeSpec::Sphere {
            center: [0.1, 0.2, 0.3],
            radius: 0.4,
        };
        for kind in KINDS {
            let s = convert(&sphere, kind);
            assert_eq!(s.kind(), kind);
            assert!(s.validate().is_ok(), "{s:?}");
            assert_eq!(placement(&s).0, [0.1, 0.2, 0.3]);
        }
        assert_eq!(convert(&convert(&sphere, "box"), "sphere"), sphere);
        assert!(default_clip().validate().is_ok());
        let mesh = ShapeSpec::Mesh {
            path: "cow.obj".into(),
            position: [1.0, 0.0, 0.0],
            scale: 1.0,
            rotation: [0.0, 90.0, 0.0],
        };
        assert!(!editable(&mesh));
        assert!(describe(&mesh).starts_with("mesh cow.obj at [1.0, 0.0, 0.0]"));
        assert_eq!(
            convert(&mesh, "cylinder"),
            ShapeSpec::Cylinder {
                center: [1.0, 0.0, 0.0],
                radius: 0.5,
                half_height: 0.5,
                rotation: [0.0, 90.0, 0.0]
            }
        );
    }
}
