//! The viewer's layout: controls on the left (programs, fidelity, the technique's editor
//! or, for 3D opacity, the clip editor, camera, view options, screenshot and save), the
//! lut 3D editor on the right (3D opacity), the inline / crossline / time-slice sections
//! below, and the 3D view in the middle with the box, axis labels and colour bars drawn
//! over it. Returns what the user asked for; the viewer acts on it. Every control is recorded by label in [`Widgets`] for scripts.
//!
//! Shortcuts: Home resets the camera, F12 takes a screenshot.

use egui::{Rect, RichText, Sense, Vec2};

use super::data::ViewData;
use super::face::{self, face_mut, EditContext};
use super::layout::{self, overlay_font};
use super::legend;
use super::lut3d;
use super::overlay::{self, Ink, Projector, SECTION_COLOURS};
use super::widgets::Widgets;
use arbvis_core::camera::Projection;
use arbvis_core::vocab::Fidelity;
use arbvis_data::volume::axes::section_axes;
use arbvis_gl::{Caps, ProgramKind};
use arbvis_techniques::scene::Scene;
use arbvis_techniques::session::InteractiveQuality;
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;
use arbvis_techniques::techniques::splats::SplatsScene;

/// What the user asked for this frame.
#[derive(Debug, Clone, PartialEq)]
pub enum UiAction {
    /// Switch program kind (rebuilds the renderer).
    SetPrograms(ProgramKind),
    /// Technique parameters changed (resend them).
    ParamsChanged,
    /// Save the 3D view as a PNG.
    Screenshot,
    /// Save the scene as TOML.
    SaveScene,
    /// Fidelity changed (rebuilds the renderer).
    SetFidelity,
    /// Write the colour tables as table files.
    SaveTables,
    /// Back to the default camera, framing the volume.
    ResetCamera,
    /// Zoom so that the whole volume is in view at any rotation.
    FitVolume,
}

/// Pointer input on the 3D view, in points.
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

/// Which sections are shown, of which attribute, where.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionsState {
    /// Shown below the view.
    pub show: bool,
    /// Attribute (0 primary, 1 secondary, 2 tertiary).
    pub attribute: usize,
    /// Voxel index of the section at each fixed axis (0 time slice, 1 crossline, 2 inline).
    pub index: [usize; 3],
}

/// What the panel shows that is not part of the scene.
#[derive(Debug)]
pub struct PanelState {
    /// UI frames per second, smoothed.
    pub fps: f64,
    /// Milliseconds per UI frame, smoothed.
    pub frame_ms: f64,
    /// What the volume costs (full and interactive pictures).
    pub volume_info: String,
    /// The last message (screenshot written, error, ...).
    pub status: String,
    /// Program kind in use.
    pub kind: Option<ProgramKind>,
    /// Every labelled control.
    pub widgets: Widgets,
    /// The lut 3D editor's lock check boxes.
    pub locks: [bool; 3],
    /// How the volume is drawn while the user interacts.
    pub quality: InteractiveQuality,
    /// The sections.
    pub sections: SectionsState,
    /// Draw the box, axis labels and legends over the view.
    pub overlay: bool,
    /// What the overlay placed last frame: each label's and legend's text and rectangle
    /// (points), for a script's `check layout`.
    pub overlay_items: Vec<(String, Rect)>,
    /// The clip editor's state (3D opacity).
    pub clip: super::clip::ClipEditor,
    /// The transfer-function editor's textures (cell-projection volumes).
    pub transfer: super::transfer::TransferState,
}

impl Default for PanelState {
    fn default() -> Self {
        PanelState {
            fps: 0.0,
            frame_ms: 0.0,
            volume_info: String::new(),
            status: String::new(),
            kind: None,
            widgets: Widgets::default(),
            locks: [false; 3],
            quality: InteractiveQuality::default(),
            sections: SectionsState {
                show: true,
                attribute: 0,
                index: [0; 3],
            },
            overlay: true,
            overlay_items: Vec::new(),
            clip: super::clip::ClipEditor::default(),
            transfer: Default::default(),
        }
    }
}

/// Output of one UI pass.
pub struct PanelOutput {
    /// Requests, in the order made.
    pub actions: Vec<UiAction>,
    /// The 3D picture's rectangle (points).
    pub view: Rect,
    /// The whole view: the 3D picture and the legends' margin at its right (points).
    pub shown: Rect,
    /// Pointer input on the view.
    pub input: ViewInput,
    /// Something the volume depends on was edited this frame (camera included).
    pub edited: bool,
}

/// Build the UI for one frame.
pub fn show(
    ui: &mut egui::Ui,
    scene: &mut Scene,
    data: &mut ViewData,
    state: &mut PanelState,
    caps: &Caps,
) -> PanelOutput {
    let mut actions = Vec::new();
    state.widgets.begin_frame();
    let camera_before = scene.camera;
    let opacity3d = scene.technique.get::<Opacity3dScene>().is_some();
    let sections_shown = opacity3d && state.sections.show && data.section_grid().is_some();
    let sizes = layout::panels(ui.max_rect().size(), opacity3d, sections_shown);

    egui::Panel::left("controls")
        .exact_size(sizes.left)
        .resizable(false)
        .show(ui, |ui| {
            let out = egui::ScrollArea::vertical().show(ui, |ui| {
                controls(ui, scene, data, state, caps, &mut actions);
            });
            state.widgets.note_scroll(ui, "left panel", &out);
        });

    if opacity3d {
        egui::Panel::right("lut 3D")
            .exact_size(sizes.right)
            .resizable(false)
            .show(ui, |ui| {
                // The editor's width leaves room for the vertical scroll bar, which is
                // solid (always shown when the panel overflows) and takes its own width.
                let width = ui.available_width() - ui.spacing().scroll.allocated_width();
                let out = egui::ScrollArea::both().show(ui, |ui| {
                    let e =
                        lut3d::editor(ui, width, scene, data, &mut state.locks, &mut state.widgets);
                    if e.params {
                        actions.push(UiAction::ParamsChanged);
                    }
                    if e.save_tables {
                        actions.push(UiAction::SaveTables);
                    }
                });
                state.widgets.note_scroll(ui, "lut 3D panel", &out);
            });
        if sections_shown {
            egui::Panel::bottom("sections")
                .exact_size(sizes.bottom)
                .resizable(false)
                .show(ui, |ui| sections(ui, scene, data, state));
        }
    }

    let mut input = ViewInput::default();
    let (view, shown) = egui::CentralPanel::default()
        .frame(egui::Frame::NONE)
        .show(ui, |ui| {
            let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::drag());
            let view = if state.overlay {
                draw_overlay(ui, rect, scene, data, state)
            } else {
                state.overlay_items.clear();
                rect
            };
            state.widgets.record(ui, "3D view", view, true);
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
            (view, rect)
        })
        .inner;

    // Shortcuts (only when no text field has the keyboard).
    if !ui.ctx().egui_wants_keyboard_input() {
        use egui::{Key, Modifiers};
        if ui.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Home)) {
            actions.push(UiAction::ResetCamera);
            state.widgets.hit("key Home");
        }
        if ui.input_mut(|i| i.consume_key(Modifiers::NONE, Key::F12)) {
            actions.push(UiAction::Screenshot);
            state.widgets.hit("key F12");
        }
    }
    let edited = scene.camera != camera_before
        || actions.iter().any(|a| {
            matches!(
                a,
                UiAction::ParamsChanged | UiAction::ResetCamera | UiAction::FitVolume
            )
        });
    PanelOutput {
        actions,
        view,
        shown,
        input,
        edited,
    }
}

fn controls(
    ui: &mut egui::Ui,
    scene: &mut Scene,
    data: &ViewData,
    state: &mut PanelState,
    caps: &Caps,
    actions: &mut Vec<UiAction>,
) {
    ui.heading("arbvis");
    ui.label(RichText::new(format!("{} | {}", caps.renderer, caps.version)).small());
    ui.label(format!(
        "UI: {:.1} fps ({:.1} ms)",
        state.fps, state.frame_ms
    ));
    ui.separator();
    programs_and_fidelity(ui, scene, state, caps, actions);
    technique_editors(ui, scene, data, state, actions);
    ui.separator();
    view_options(ui, scene, state, actions);
    ui.separator();
    let w = &mut state.widgets;
    ui.horizontal_wrapped(|ui| {
        if w.button(ui, "Screenshot") {
            actions.push(UiAction::Screenshot);
        }
        if w.button(ui, "Save scene") {
            actions.push(UiAction::SaveScene);
        }
    });
    if !state.status.is_empty() {
        // Recorded for scripts (`print Status`).
        w.status_text(ui, "Status", &state.status);
    }
    // Lines whose length and count change from frame to frame come last, below every
    // control: the frame times wrap to two lines on a slow machine and the renderer's
    // status appears a frame late, and above the controls either would move them between
    // the frame a click is aimed and the frame it lands.
    if !state.volume_info.is_empty() {
        // The renderer's own lines (a COPC cut, its node cache), recorded for scripts.
        w.status_text(ui, "Renderer", &state.volume_info);
    }
    // A remote store's or cloud's requests in flight (the loader threads fetch; the
    // frames go on): redrawn while they last, so the line follows them.
    if let Some(loading) = arbvis_data::fetch::status() {
        w.status_text(ui, "Loading", &loading);
        ui.ctx()
            .request_repaint_after(std::time::Duration::from_millis(200));
    }
}

/// The program kind (ARB where the driver has it) and the fidelity.
fn programs_and_fidelity(
    ui: &mut egui::Ui,
    scene: &mut Scene,
    state: &mut PanelState,
    caps: &Caps,
    actions: &mut Vec<UiAction>,
) {
    let w = &mut state.widgets;
    ui.horizontal_wrapped(|ui| {
        ui.label("Programs");
        for (kind, label, enabled) in [
            (ProgramKind::Arb, "ARB", caps.has_arb()),
            (ProgramKind::Glsl, "GLSL", true),
        ] {
            let selected = state.kind == Some(kind);
            let r = ui.add_enabled(enabled, egui::RadioButton::new(selected, label));
            if w.add(ui, label, &r) && r.clicked() && !selected {
                actions.push(UiAction::SetPrograms(kind));
            }
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("Fidelity");
        for (f, label) in [
            (Fidelity::Faithful, "Faithful"),
            (Fidelity::Precise, "Precise"),
        ] {
            if w.radio(ui, label, &mut scene.fidelity, f) {
                // Tiles are precise only: faithful draws the seed's points.
                if let Some(sp) = scene.technique.get_mut::<SplatsScene>() {
                    if f == Fidelity::Faithful {
                        sp.draw = arbvis_techniques::techniques::splats::scene::DrawChoice::Points;
                    }
                }
                actions.push(UiAction::SetFidelity);
            }
        }
    });
}

/// The scene's technique's own editors.
fn technique_editors(
    ui: &mut egui::Ui,
    scene: &mut Scene,
    data: &ViewData,
    state: &mut PanelState,
    actions: &mut Vec<UiAction>,
) {
    let base = scene.base.clone();
    let mut cx = EditContext {
        fidelity: scene.fidelity,
        base: &base,
        data,
        widgets: &mut state.widgets,
        clip: &mut state.clip,
        transfer: &mut state.transfer,
        layers: scene.layers().map(|(info, _)| info.name.clone()).collect(),
        layer: None,
    };
    if scene.is_layered() {
        if layer_editors(ui, scene, &mut cx) {
            actions.push(UiAction::ParamsChanged);
        }
        return;
    }
    if let Some(face) = face_mut(&mut scene.technique) {
        if face.editors(ui, &mut cx) {
            actions.push(UiAction::ParamsChanged);
        }
    }
}

/// A layered scene's layers: each one's visibility, its place in the order, and its
/// technique's editors (folded); true when something changed.
fn layer_editors(ui: &mut egui::Ui, scene: &mut Scene, cx: &mut EditContext<'_>) -> bool {
    ui.separator();
    ui.label("Layers (drawn opaque first, then in this order)");
    let count = scene.layers().count();
    let mut changed = false;
    let mut moved = None;
    for (index, (info, technique)) in scene.layers_mut().enumerate() {
        let name = match info.name.as_str() {
            "" => format!("layer {index}: {}", technique.name()),
            n => format!("layer {index}: {n} ({})", technique.name()),
        };
        ui.horizontal(|ui| {
            let r = ui.checkbox(&mut info.visible, "");
            changed |= cx.widgets.add(ui, &format!("{name} visible"), &r) && r.changed();
            let up = ui.add_enabled(index > 0, egui::Button::new("^"));
            if cx.widgets.add(ui, &format!("{name} up"), &up) && up.clicked() {
                moved = Some((index, index - 1));
            }
            let down = ui.add_enabled(index + 1 < count, egui::Button::new("v"));
            if cx.widgets.add(ui, &format!("{name} down"), &down) && down.clicked() {
                moved = Some((index, index + 1));
            }
            // Long names end in an ellipsis rather than widen the panel.
            ui.add(egui::Label::new(&name).truncate());
        });
        if let Some(face) = face_mut(technique) {
            cx.layer = Some((index, info.name.clone()));
            let label = format!("{name} settings");
            // Shown as "settings" under the layer's row; recorded by the whole label.
            let r = egui::CollapsingHeader::new("settings")
                .id_salt(("layer", index))
                .show(ui, |ui| changed |= face.editors(ui, cx));
            // Recorded, so that a script opens it as a user does (`click ... settings`).
            cx.widgets.add(ui, &label, &r.header_response);
        }
    }
    if let Some((from, to)) = moved {
        changed |= scene.move_layer(from, to).is_ok();
    }
    changed
}

/// The camera, the interactive quality and what is drawn over the picture.
fn view_options(
    ui: &mut egui::Ui,
    scene: &mut Scene,
    state: &mut PanelState,
    actions: &mut Vec<UiAction>,
) {
    let w = &mut state.widgets;
    ui.label("Camera: drag the view to turn, scroll to zoom");
    ui.horizontal_wrapped(|ui| {
        for (p, label) in [
            (Projection::Orthographic, "Orthographic"),
            (Projection::Perspective, "Perspective"),
        ] {
            w.radio(ui, label, &mut scene.camera.projection, p);
        }
    });
    w.slider(ui, "zoom", &mut scene.camera.zoom, 0.1..=10.0, "zoom", true);
    ui.horizontal_wrapped(|ui| {
        if w.button(ui, "Reset camera") {
            actions.push(UiAction::ResetCamera);
        }
        if w.button(ui, "Fit volume") {
            actions.push(UiAction::FitVolume);
        }
    });
    ui.separator();

    ui.horizontal_wrapped(|ui| {
        ui.label("Interactive quality");
        w.choice(
            ui,
            "Interactive quality",
            &mut state.quality,
            &InteractiveQuality::ALL,
            80.0,
        );
    });
    ui.label(
        RichText::new("while dragging or editing: fewer slices and pixels; refined when still")
            .small()
            .weak(),
    );
    w.checkbox(
        ui,
        "Box and labels",
        &mut state.overlay,
        "Box, axes and legends",
    );
    if scene.technique.get::<Opacity3dScene>().is_some() {
        w.checkbox(ui, "Sections", &mut state.sections.show, "Sections");
    }
    w.checkbox(
        ui,
        "Transparent screenshots",
        &mut scene.transparent,
        "Transparent screenshots",
    );
}

/// The three sections of one attribute, each with its index slider.
fn sections(ui: &mut egui::Ui, scene: &Scene, data: &mut ViewData, state: &mut PanelState) {
    let Some(grid) = data.section_grid() else {
        return;
    };
    let axes = &grid.axes;
    let dims = grid.dims;
    let half = grid.half;
    let present: Vec<(usize, &str)> = grid.present.iter().map(|&a| (a, lut3d::ROLES[a])).collect();
    let w = &mut state.widgets;
    ui.horizontal_wrapped(|ui| {
        ui.label("Sections of");
        w.choice(
            ui,
            "Section attribute",
            &mut state.sections.attribute,
            &present,
            90.0,
        );
        ui.label(RichText::new("in the same table, opaque").small().weak());
    });
    let ctx = ui.ctx().clone();
    let column = (ui.available_width() - 16.0) / 3.0;
    let height = ui.available_height() - 64.0;
    ui.columns(3, |cols| {
        // Inline, crossline, time slice: fixed axes 2, 1, 0.
        for (col, a) in cols.iter_mut().zip([2usize, 1, 0]) {
            let index = &mut state.sections.index[a];
            *index = (*index).min(dims[a] - 1);
            let label = format!("{} section", axes[a].name);
            col.horizontal(|ui| {
                ui.colored_label(SECTION_COLOURS[a], "■");
                ui.label(format!("{} {}", axes[a].name, axes[a].label(*index)));
            });
            col.spacing_mut().slider_width = (column - 60.0).max(40.0);
            w.slider(col, &label, index, 0..=dims[a] - 1, "", false);
            let (u, wv) = section_axes(a);
            let (ex, ey) = (2.0 * half[u] as f32, 2.0 * half[wv] as f32);
            let s = (column / ex).min(height / ey).max(0.0);
            if let Some(t) = data.section(&ctx, scene, a, *index, state.sections.attribute) {
                let size = Vec2::new(ex * s, ey * s);
                let r = col.add(egui::Image::new((t.id(), size)));
                // Under the pointer: the voxel's numbers and the trace's map position.
                let text = match r.hover_pos() {
                    Some(p) => {
                        let f = (p - r.rect.min) / r.rect.size();
                        grid.point(a, *index, f.x, f.y)
                    }
                    None => format!("{} across, {} down", axes[u].name, axes[wv].name),
                };
                r.on_hover_text(text);
            }
        }
    });
}

/// Draw the legends in their margin at the right of `rect` and the box over the rest;
/// returns the rest, the 3D picture's rectangle.
fn draw_overlay(
    ui: &egui::Ui,
    rect: Rect,
    scene: &Scene,
    data: &mut ViewData,
    state: &mut PanelState,
) -> Rect {
    let ctx = ui.ctx().clone();
    let painter = ui.painter_at(rect);
    let measure = |t: &str, size: f32| {
        painter
            .layout_no_wrap(t.to_string(), overlay_font(size), egui::Color32::WHITE)
            .size()
    };
    let ink = Ink::on(scene.background);
    let legends = face::legends(&ctx, scene, data, state.transfer.colours());
    let placed = legend::layout(rect, &legends, ink, &measure);
    let view = placed.picture(rect);
    legend::paint(&painter, &placed);
    let mut items: Vec<(String, Rect)> = placed
        .boxes
        .iter()
        .map(|(t, r)| (format!("legend {t}"), *r))
        .collect();
    items.extend(
        placed
            .texts
            .iter()
            .map(|t| (format!("legend text {}", t.text), t.rect)),
    );
    if let Some(b) = data.data_box() {
        let shown = state.sections.show && data.section_grid().is_some();
        let sections = [0, 1, 2].map(|a| shown.then_some(state.sections.index[a]));
        let laid = overlay::layout_box(
            &Projector::new(&scene.camera, view),
            view,
            b.half,
            &b.axes,
            sections,
            ink,
            &measure,
        );
        overlay::paint(&ui.painter_at(view), &laid);
        items.extend(
            laid.texts
                .iter()
                .map(|t| (format!("label {}", t.text), t.rect)),
        );
    }
    state.overlay_items = items;
    view
}
