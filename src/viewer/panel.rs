//! The egui side panel and the GL view area: editors for the scene, program kind,
//! camera, screenshot and save buttons, FPS. Returns what the user asked for; the
//! viewer acts on it. Widget rectangles are recorded by label for scripted clicks.

use std::collections::HashMap;

use egui::{Rect, Sense};

use crate::camera::{Camera, Projection};
use crate::gl::{Caps, ProgramKind};
use crate::scene::{Scene, TechniqueScene};

/// Width of the side panel in points.
pub const PANEL_WIDTH: f32 = 240.0;

/// What the user asked for this frame.
#[derive(Debug, Clone, PartialEq)]
pub enum UiAction {
    /// Switch program kind (rebuilds the renderer).
    SetPrograms(ProgramKind),
    /// Technique parameters changed (resend them).
    ParamsChanged,
    /// Save the GL view as a PNG.
    Screenshot,
    /// Save the scene as TOML.
    SaveScene,
    /// Fidelity changed (rebuilds the renderer).
    SetFidelity,
    /// Write the colour tables as table files.
    SaveTables,
}

/// Pointer input on the GL view, in points.
#[derive(Debug, Clone, Copy, Default)]
pub struct ViewInput {
    /// A drag started here.
    pub drag_start: Option<egui::Pos2>,
    /// The pointer is dragging here.
    pub drag_to: Option<egui::Pos2>,
    /// The drag ended.
    pub drag_end: bool,
    /// Scroll over the view (points; positive = away from the user).
    pub scroll: f32,
}

/// What the panel shows that is not part of the scene.
#[derive(Debug, Default)]
pub struct PanelState {
    /// Frames per second, smoothed.
    pub fps: f64,
    /// Milliseconds per frame, smoothed.
    pub frame_ms: f64,
    /// The last message (screenshot written, error, ...).
    pub status: String,
    /// Program kind in use.
    pub kind: Option<ProgramKind>,
    /// Where each labelled widget was drawn last frame (points).
    pub widgets: HashMap<String, Rect>,
    /// The lut 3D editor's lock check boxes.
    pub locks: [bool; 3],
}

/// Output of one UI pass.
pub struct PanelOutput {
    /// Requests, in the order made.
    pub actions: Vec<UiAction>,
    /// The GL view's rectangle (points).
    pub view: Rect,
    /// Pointer input on the view.
    pub input: ViewInput,
}

/// Build the UI for one frame.
pub fn show(
    ui: &mut egui::Ui,
    scene: &mut Scene,
    state: &mut PanelState,
    caps: &Caps,
) -> PanelOutput {
    let mut actions = Vec::new();
    state.widgets.clear();
    egui::Panel::left("controls")
        .exact_size(PANEL_WIDTH)
        .resizable(false)
        .show(ui, |ui| {
            ui.heading("arbvis");
            ui.label(format!("{} | {}", caps.renderer, caps.version));
            ui.label(format!("FPS: {:.1} ({:.2} ms)", state.fps, state.frame_ms));
            ui.separator();

            ui.label("Programs");
            ui.horizontal(|ui| {
                for (kind, label, enabled) in [
                    (ProgramKind::Arb, "ARB", caps.has_arb()),
                    (ProgramKind::Glsl, "GLSL", true),
                ] {
                    let selected = state.kind == Some(kind);
                    let r = ui.add_enabled(enabled, egui::RadioButton::new(selected, label));
                    state.widgets.insert(label.into(), r.rect);
                    if r.clicked() && !selected {
                        actions.push(UiAction::SetPrograms(kind));
                    }
                }
            });
            ui.separator();

            egui::ScrollArea::vertical()
                .max_height(ui.available_height() * 0.6)
                .show(ui, |ui| {
                    actions.extend(technique_editor(ui, scene, state));
                });
            ui.separator();

            camera_editor(ui, &mut scene.camera, &mut state.widgets);
            ui.separator();

            ui.horizontal(|ui| {
                for (label, action) in [
                    ("Screenshot", UiAction::Screenshot),
                    ("Save scene", UiAction::SaveScene),
                ] {
                    let r = ui.button(label);
                    state.widgets.insert(label.into(), r.rect);
                    if r.clicked() {
                        actions.push(action);
                    }
                }
            });
            if !state.status.is_empty() {
                ui.label(&state.status);
            }
        });

    let mut input = ViewInput::default();
    let view = egui::CentralPanel::default()
        .frame(egui::Frame::NONE)
        .show(ui, |ui| {
            let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::drag());
            let pos = response.interact_pointer_pos();
            if response.drag_started() {
                input.drag_start = pos;
            } else if response.dragged() {
                input.drag_to = pos;
            }
            input.drag_end = response.drag_stopped();
            if response.hovered() {
                input.scroll = ui.input(|i| i.smooth_scroll_delta.y);
            }
            rect
        })
        .inner;
    PanelOutput {
        actions,
        view,
        input,
    }
}

fn technique_editor(ui: &mut egui::Ui, scene: &mut Scene, state: &mut PanelState) -> Vec<UiAction> {
    let mut changed = false;
    let widgets = &mut state.widgets;
    match &mut scene.technique {
        TechniqueScene::Opacity3d(o) => {
            let edit = super::lut3d::editor(ui, o, &mut scene.fidelity, &mut state.locks, widgets);
            let mut actions = Vec::new();
            if edit.fidelity {
                actions.push(UiAction::SetFidelity);
            } else if edit.params {
                actions.push(UiAction::ParamsChanged);
            }
            if edit.save_tables {
                actions.push(UiAction::SaveTables);
            }
            return actions;
        }
        TechniqueScene::Cellproj(c) => {
            changed = super::isovalues::editor(ui, c, widgets);
        }
        TechniqueScene::Quad(q) => {
            ui.label("Quad colours");
            for (label, colour) in [("Left", &mut q.left), ("Right", &mut q.right)] {
                ui.horizontal(|ui| {
                    ui.label(label);
                    let mut c = colour.map(|v| v as f32);
                    let r = ui.color_edit_button_rgba_unmultiplied(&mut c);
                    widgets.insert(format!("{label} colour"), r.rect);
                    if r.changed() {
                        *colour = c.map(|v| v as f64);
                        changed = true;
                    }
                });
            }
        }
    }
    if changed {
        vec![UiAction::ParamsChanged]
    } else {
        Vec::new()
    }
}

fn camera_editor(ui: &mut egui::Ui, camera: &mut Camera, widgets: &mut HashMap<String, Rect>) {
    ui.label("Camera (drag the view to rotate, scroll to zoom)");
    ui.horizontal(|ui| {
        for (p, label) in [
            (Projection::Orthographic, "Orthographic"),
            (Projection::Perspective, "Perspective"),
        ] {
            let r = ui.radio_value(&mut camera.projection, p, label);
            widgets.insert(label.into(), r.rect);
        }
    });
    ui.add(
        egui::Slider::new(&mut camera.zoom, 0.1..=10.0)
            .logarithmic(true)
            .text("zoom"),
    );
    let r = ui.button("Reset camera");
    widgets.insert("Reset camera".into(), r.rect);
    if r.clicked() {
        *camera = Camera::default();
    }
}
