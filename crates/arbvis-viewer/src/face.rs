//! What the viewer shows of a technique besides its picture: its editors in the panel and
//! its legends over the picture. Each technique's scene type implements [`Face`] once,
//! here; [`FACES`] is the viewer's one list of them (the catalog's list, seen from the
//! viewer, which alone knows egui). A technique without a face shows neither.

use std::any::Any;
use std::path::Path;

use egui::TextureId;

use super::clip::ClipEditor;
use super::data::ViewData;
use super::legend::{self, Legend};
use super::transfer::TransferState;
use super::widgets::Widgets;
use arbvis_core::vocab::Fidelity;
use arbvis_techniques::catalog::TechniqueScene;
use arbvis_techniques::scene::Scene;
use arbvis_techniques::techniques::cellproj::CellprojScene;
use arbvis_techniques::techniques::lines::{LineStyle, LinesScene, Width};
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;
use arbvis_techniques::techniques::quad::QuadScene;
use arbvis_techniques::techniques::section::SectionScene;
use arbvis_techniques::techniques::splats::SplatsScene;
use arbvis_techniques::techniques::surface::SurfaceScene;

/// What an editor may read and keep besides the parameters it edits.
pub struct EditContext<'a> {
    /// The scene's fidelity.
    pub fidelity: Fidelity,
    /// The folder the scene's relative paths are read from.
    pub base: &'a Path,
    /// What the panels keep of the prepared data (a cloud's attributes, a mesh's
    /// histogram).
    pub data: &'a ViewData,
    /// Every labelled control.
    pub widgets: &'a mut Widgets,
    /// The clip editor's state.
    pub clip: &'a mut ClipEditor,
    /// The transfer function editor's state.
    pub transfer: &'a mut TransferState,
    /// The scene's layer names, in order (empty for a one-technique scene).
    pub layers: Vec<String>,
    /// The layer being edited: its index and name.
    pub layer: Option<(usize, String)>,
}

/// A technique as the viewer shows it.
pub trait Face {
    /// Draw the technique's editors into `ui`; true when a parameter changed.
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool;
    /// Add the technique's legends (colour bars, keys) for `scene` to `out`; `transfer`
    /// is the transfer function editor's colour strip, where it has one.
    fn legends(
        &self,
        ctx: &egui::Context,
        scene: &Scene,
        data: &mut ViewData,
        transfer: Option<TextureId>,
        out: &mut Vec<Legend>,
    ) {
        let _ = (ctx, scene, data, transfer, out);
    }
}

impl Face for QuadScene {
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        ui.label("Quad colours");
        let mut changed = false;
        for (label, colour) in [("Left", &mut self.left), ("Right", &mut self.right)] {
            ui.horizontal(|ui| {
                ui.label(label);
                let mut c = colour.map(|v| v as f32);
                let r = ui.color_edit_button_rgba_unmultiplied(&mut c);
                if cx.widgets.add(ui, &format!("{label} colour"), &r) && r.changed() {
                    *colour = c.map(|v| v as f64);
                    changed = true;
                }
            });
        }
        changed
    }
}

impl Face for Opacity3dScene {
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        ui.separator();
        super::clip::editor(ui, self, cx.clip, cx.widgets)
    }

    fn legends(
        &self,
        ctx: &egui::Context,
        scene: &Scene,
        data: &mut ViewData,
        _: Option<TextureId>,
        out: &mut Vec<Legend>,
    ) {
        legend::volume_legends(ctx, scene, self, data, out);
    }
}

impl Face for CellprojScene {
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        ui.separator();
        let mesh = cx.data.mesh.as_ref();
        let counts = mesh.map(|m| m.histogram.as_slice());
        let edited = super::transfer::editor(ui, self, cx.base, counts, cx.transfer, cx.widgets);
        ui.separator();
        let range = mesh.map_or([0.0, 1.0], |m| m.range);
        super::isovalues::editor(ui, self, range, cx.widgets) || edited
    }

    fn legends(
        &self,
        _: &egui::Context,
        _: &Scene,
        data: &mut ViewData,
        transfer: Option<TextureId>,
        out: &mut Vec<Legend>,
    ) {
        legend::mesh_legends(self, data, transfer, out);
    }
}

impl Face for SplatsScene {
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        ui.separator();
        super::splats::editor(ui, self, cx.fidelity, cx.data.cloud.as_ref(), cx.widgets)
    }

    fn legends(
        &self,
        _: &egui::Context,
        _: &Scene,
        data: &mut ViewData,
        _: Option<TextureId>,
        out: &mut Vec<Legend>,
    ) {
        legend::cloud_legends(self, data, out);
    }
}

impl Face for SurfaceScene {
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        use super::surface_colour::{self, ColourChoice};
        use arbvis_techniques::techniques::surface::Lighting;
        ui.separator();
        ui.label("Surface");
        let place = surface_colour::Context {
            base: cx.base,
            layers: &cx.layers,
            layer: cx.layer.as_ref(),
        };
        let mut changed = surface_colour::editor(ui, self, &place, cx.widgets);
        // The constant colours what the choice leaves uncoloured (vertices without the
        // property, the surface outside the layer it takes colours from).
        if ColourChoice::of(self) != ColourChoice::Elevation {
            ui.horizontal(|ui| {
                ui.label("Colour");
                let mut c = self.colour.map(|v| v as f32);
                let r = ui.color_edit_button_rgb(&mut c);
                if cx.widgets.add(ui, "Surface colour", &r) && r.changed() {
                    self.colour = c.map(|v| v as f64);
                    changed = true;
                }
            });
        }
        let mut lit = self.lighting == Lighting::Phong;
        let r = ui.checkbox(&mut lit, "Lit (headlight)");
        if cx.widgets.add(ui, "Lit", &r) && r.changed() {
            self.lighting = if lit { Lighting::Phong } else { Lighting::None };
            changed = true;
        }
        let r = ui.add(egui::Slider::new(&mut self.opacity, 0.01..=1.0).text("Opacity"));
        changed |= cx.widgets.add(ui, "Opacity", &r) && r.changed();
        changed
    }
}

impl Face for SectionScene {
    /// The cut's number on a slider over the survey's numbers (inline and crossline
    /// numbers step by the survey's step; time and depth anywhere between the first and
    /// last sample), and the opacity. Where the survey does not read, a number box (the
    /// layer's own error says why).
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        ui.separator();
        ui.label("Section");
        let ranges = super::section_range::ranges(ui.ctx(), self, cx.base);
        let mut changed = false;
        for (key, axis, number) in [
            ("Inline", 2, &mut self.inline),
            ("Crossline", 1, &mut self.crossline),
            ("Time (ms)", 0, &mut self.time),
            ("Depth", 0, &mut self.depth),
        ] {
            let Some(n) = number.as_mut() else { continue };
            changed |= match ranges.as_ref().map(|r| r[axis]) {
                Some(range) => super::section_range::slider(ui, cx.widgets, key, n, range),
                None => cx.widgets.drag_value(ui, key, n, f64::MIN..=f64::MAX, 0.25),
            };
        }
        let r = ui.add(egui::Slider::new(&mut self.opacity, 0.01..=1.0).text("Opacity"));
        changed |= cx.widgets.add(ui, "Opacity", &r) && r.changed();
        changed
    }
}

impl Face for LinesScene {
    /// Tubes or ribbons, their width in metres or pixels, and their colour where there
    /// is no value.
    fn editors(&mut self, ui: &mut egui::Ui, cx: &mut EditContext<'_>) -> bool {
        ui.separator();
        ui.label("Lines");
        let styles = [(LineStyle::Tube, "tube"), (LineStyle::Ribbon, "ribbon")];
        let mut changed = cx
            .widgets
            .choice(ui, "Lines style", &mut self.style, &styles, 90.0);
        // The width's unit; a new unit starts from a width a line is seen at.
        let mut pixels = matches!(self.width(), Width::Pixels(_));
        if cx
            .widgets
            .checkbox(ui, "Width in pixels", &mut pixels, "Width in pixels")
        {
            self.width = Some(match pixels {
                true => Width::Pixels(4.0),
                false => Width::Metres(2.0 * self.radius),
            });
            changed = true;
        }
        let (mut w, range, text) = match self.width() {
            Width::Metres(w) => (w, 0.5..=500.0, "Width (m)"),
            Width::Pixels(w) => (w, 1.0..=64.0, "Width (px)"),
        };
        if cx
            .widgets
            .slider(ui, "Lines width", &mut w, range, text, true)
        {
            self.width = Some(match pixels {
                true => Width::Pixels(w),
                false => Width::Metres(w),
            });
            changed = true;
        }
        ui.horizontal(|ui| {
            ui.label("Colour");
            let mut c = self.colour.map(|v| v as f32);
            let r = ui.color_edit_button_rgb(&mut c);
            if cx.widgets.add(ui, "Lines colour", &r) && r.changed() {
                self.colour = c.map(|v| v as f64);
                changed = true;
            }
        });
        changed
    }
}

/// The face of parameters of type `T`, if `parameters` are.
fn face_of<T: Face + Any>(parameters: &dyn Any) -> Option<&dyn Face> {
    parameters.downcast_ref::<T>().map(|t| t as &dyn Face)
}

/// [`face_of`], to change.
fn face_of_mut<T: Face + Any>(parameters: &mut dyn Any) -> Option<&mut dyn Face> {
    parameters.downcast_mut::<T>().map(|t| t as &mut dyn Face)
}

/// How one technique's face is found in its parameters: to read, and to change.
type FaceLookup = (
    fn(&dyn Any) -> Option<&dyn Face>,
    fn(&mut dyn Any) -> Option<&mut dyn Face>,
);

/// Every technique's face: the viewer's one list, checked against the catalog's
/// [`arbvis_techniques::catalog::TECHNIQUES`] by a test (egui lives only up here).
const FACES: &[FaceLookup] = &[
    (face_of::<QuadScene>, face_of_mut::<QuadScene>),
    (face_of::<Opacity3dScene>, face_of_mut::<Opacity3dScene>),
    (face_of::<CellprojScene>, face_of_mut::<CellprojScene>),
    (face_of::<SplatsScene>, face_of_mut::<SplatsScene>),
    (face_of::<SurfaceScene>, face_of_mut::<SurfaceScene>),
    (face_of::<SectionScene>, face_of_mut::<SectionScene>),
    (face_of::<LinesScene>, face_of_mut::<LinesScene>),
];

/// The face of the scene's technique.
pub fn face(technique: &TechniqueScene) -> Option<&dyn Face> {
    FACES.iter().find_map(|(of, _)| of(technique.parameters()))
}

/// [`face`], to edit.
pub fn face_mut(technique: &mut TechniqueScene) -> Option<&mut dyn Face> {
    let index = FACES
        .iter()
        .position(|(of, _)| of(technique.parameters()).is_some())?;
    (FACES[index].1)(technique.parameters_mut())
}

/// The legends of `scene`'s technique, from what its panels keep in `data`.
pub fn legends(
    ctx: &egui::Context,
    scene: &Scene,
    data: &mut ViewData,
    transfer: Option<TextureId>,
) -> Vec<Legend> {
    let mut out = Vec::new();
    if let Some(f) = face(&scene.technique) {
        f.legends(ctx, scene, data, transfer, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_technique_has_a_face_found_both_ways() {
        for technique in arbvis_techniques::catalog::TECHNIQUES {
            // A technique without a demo could not be checked here.
            assert!(
                !technique.demos.is_empty(),
                "{} has no demo",
                technique.name
            );
            for (name, _) in technique.demos {
                let mut scene = Scene::demo(name).unwrap();
                assert_eq!(scene.technique.name(), technique.name, "{name}");
                assert!(face(&scene.technique).is_some(), "{name}");
                assert!(face_mut(&mut scene.technique).is_some(), "{name}");
            }
        }
        assert_eq!(FACES.len(), arbvis_techniques::catalog::TECHNIQUES.len());
    }
}
