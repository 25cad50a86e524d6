//! The cell-projection editor: isovalues (add, remove, drag the value, pick the colour),
//! where the exit point is computed, shading, active tetrahedra only, and the table size.
//! Each edit rewrites only the isosurface table (and the active list) on the next frame.

use super::widgets::Widgets;
use crate::techniques::cellproj::{CellprojScene, Exit, Isovalue, MAX_ISOVALUES};

/// Draw the editor; true when something changed.
pub fn editor(ui: &mut egui::Ui, scene: &mut CellprojScene, w: &mut Widgets) -> bool {
    let mut changed = false;
    ui.label("Isovalues (normalized scalar, colour)");
    let mut remove = None;
    for (i, iso) in scene.isovalues.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            changed |= w.drag_value(
                ui,
                &format!("Isovalue {}", i + 1),
                &mut iso.value,
                0.0..=1.0,
                0.002,
            );
            let mut c = iso.color.map(|v| v as f32);
            let r = ui.color_edit_button_rgba_unmultiplied(&mut c);
            if w.add(ui, &format!("Isovalue {} colour", i + 1), &r) && r.changed() {
                iso.color = c.map(|v| v as f64);
                changed = true;
            }
            let r = ui.button("Remove");
            if w.add(ui, &format!("Remove isovalue {}", i + 1), &r) && r.clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove {
        scene.isovalues.remove(i);
        changed = true;
    }
    let r = ui.add_enabled(
        scene.isovalues.len() < MAX_ISOVALUES,
        egui::Button::new("Add isovalue"),
    );
    if w.add(ui, "Add isovalue", &r) && r.clicked() {
        let value = scene
            .isovalues
            .last()
            .map_or(0.5, |i| (i.value + 0.1) % 1.0);
        scene.isovalues.push(Isovalue {
            value,
            color: [1.0, 1.0, 0.0, 1.0],
        });
        changed = true;
    }
    ui.separator();
    ui.horizontal_wrapped(|ui| {
        ui.label("Exit point");
        for (label, exit) in [
            ("auto", Exit::Auto),
            ("per vertex", Exit::Vertex),
            ("per fragment", Exit::Fragment),
        ] {
            let r = ui.radio_value(&mut scene.exit, exit, label);
            changed |= w.add(ui, &format!("Exit {label}"), &r) && r.changed();
        }
    });
    changed |= w.checkbox(ui, "Shading", &mut scene.shading, "Shading (precise)");
    changed |= w.checkbox(
        ui,
        "Active tetrahedra only",
        &mut scene.active_only,
        "Active tetrahedra only",
    );
    changed |= w.slider(
        ui,
        "Table size",
        &mut scene.table_size,
        2..=4096,
        "table size",
        true,
    );
    changed
}
