//! The cell-projection editor: isovalues (add, remove, drag the value, pick the colour),
//! where the exit point is computed, shading, active tetrahedra only, and the table size.
//! Each edit rewrites only the isosurface table (and the active list) on the next frame.

use super::widgets::Widgets;
use arbvis_techniques::techniques::cellproj::{
    CellprojScene, Exit, Isovalue, IsovalueUnits, MAX_ISOVALUES,
};

/// Draw the editor; true when something changed. `range` is the scalar's range in its
/// own units (the values are dragged within it, or within 0..1 where the scene writes
/// them normalized).
pub fn editor(
    ui: &mut egui::Ui,
    scene: &mut CellprojScene,
    range: [f64; 2],
    w: &mut Widgets,
) -> bool {
    let mut changed = false;
    let (lo, hi) = match scene.isovalue_units {
        IsovalueUnits::Data => (range[0], range[1]),
        IsovalueUnits::Normalized => (0.0, 1.0),
    };
    ui.label(match scene.isovalue_units {
        IsovalueUnits::Data => format!(
            "Isovalues (scalar {}..{}, colour)",
            super::lut3d::short(lo),
            super::lut3d::short(hi)
        ),
        IsovalueUnits::Normalized => "Isovalues (normalized scalar 0..1, colour)".to_string(),
    });
    let mut remove = None;
    for (i, iso) in scene.isovalues.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            changed |= w.drag_value(
                ui,
                &format!("Isovalue {}", i + 1),
                &mut iso.value,
                lo..=hi,
                0.002 * (hi - lo).max(f64::MIN_POSITIVE),
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
        // A tenth of the range above the last one (wrapping), else the middle.
        let span = hi - lo;
        let value = scene.isovalues.last().map_or(lo + 0.5 * span, |i| {
            let t = if span > 0.0 {
                (i.value - lo) / span
            } else {
                0.0
            };
            lo + ((t + 0.1) % 1.0) * span
        });
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
