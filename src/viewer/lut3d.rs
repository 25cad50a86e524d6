//! The "lut 3D" editor of v3o2 (seed Figure 18): which table goes with the primary,
//! secondary and tertiary volume, their twelve coefficients (one lock per table edits its
//! four as one value), sum or product, slice count, fidelity, and each table's alpha
//! curve. Every edit shows on the next frame (coefficients are resent to
//! `program.local[1..3]`).

use std::collections::HashMap;

use egui::Rect;

use crate::colortable::BUILTINS;
use crate::scene::Fidelity;
use crate::techniques::opacity3d::{Combine, Opacity3dScene, MAX_SLICES};

/// What an edit asks of the viewer.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Lut3dEdit {
    /// Parameters changed: resend them.
    pub params: bool,
    /// Fidelity changed: rebuild the renderer.
    pub fidelity: bool,
    /// Write the three tables as files.
    pub save_tables: bool,
}

/// Names of the three attributes, as labelled in the panel.
pub const ROLES: [&str; 3] = ["primary", "secondary", "tertiary"];

fn remember(widgets: &mut HashMap<String, Rect>, label: impl Into<String>, r: &egui::Response) {
    widgets.insert(label.into(), r.rect);
}

/// Draw the editor; `locks` is the per-table lock state (UI only).
pub fn editor(
    ui: &mut egui::Ui,
    o: &mut Opacity3dScene,
    fidelity: &mut Fidelity,
    locks: &mut [bool; 3],
    widgets: &mut HashMap<String, Rect>,
) -> Lut3dEdit {
    let mut edit = Lut3dEdit::default();
    ui.label("lut 3D");
    ui.horizontal(|ui| {
        for (c, label) in [(Combine::Sum, "Sum"), (Combine::Product, "Product")] {
            let r = ui.radio_value(&mut o.combine, c, label);
            remember(widgets, label, &r);
            edit.params |= r.changed();
        }
    });
    ui.horizontal(|ui| {
        for (f, label) in [
            (Fidelity::Faithful, "Faithful"),
            (Fidelity::Precise, "Precise"),
        ] {
            let r = ui.radio_value(fidelity, f, label);
            remember(widgets, label, &r);
            edit.fidelity |= r.changed();
        }
    });
    let r = ui.add(
        egui::Slider::new(&mut o.slices, 1..=MAX_SLICES)
            .logarithmic(true)
            .text("slices"),
    );
    remember(widgets, "slices", &r);
    edit.params |= r.changed();

    for (a, attr) in o.attributes_mut().into_iter().enumerate() {
        let Some(attr) = attr else {
            ui.label(format!("{}: none", ROLES[a]));
            continue;
        };
        let role = ROLES[a];
        egui::CollapsingHeader::new(format!("{role}: {}", attr.attribute.name()))
            .id_salt(role)
            .default_open(a == 0)
            .show(ui, |ui| {
                let current = attr
                    .table
                    .file
                    .as_ref()
                    .map(|f| f.display().to_string())
                    .unwrap_or_else(|| attr.table.builtin.clone());
                let r = egui::ComboBox::from_id_salt(format!("{role} table"))
                    .selected_text(current)
                    .show_ui(ui, |ui| {
                        for name in BUILTINS {
                            if ui
                                .selectable_label(
                                    attr.table.file.is_none() && attr.table.builtin == *name,
                                    *name,
                                )
                                .clicked()
                            {
                                attr.table.builtin = name.to_string();
                                attr.table.file = None;
                                edit.params = true;
                            }
                        }
                    });
                remember(widgets, format!("{role} table"), &r.response);

                let r = ui.checkbox(&mut locks[a], "lock");
                remember(widgets, format!("Lock {role}"), &r);
                if r.changed() && locks[a] {
                    let v = attr.coefficients[0];
                    attr.coefficients = [v; 4];
                    edit.params = true;
                }
                if locks[a] {
                    let mut v = attr.coefficients[0];
                    let r = ui.add(egui::Slider::new(&mut v, 0.0..=1.0).text("C (all four)"));
                    remember(widgets, format!("{role} C"), &r);
                    if r.changed() {
                        attr.coefficients = [v; 4];
                        edit.params = true;
                    }
                } else {
                    for (c, name) in ["Cr", "Cg", "Cb", "Ca"].iter().enumerate() {
                        let r = ui.add(
                            egui::Slider::new(&mut attr.coefficients[c], 0.0..=1.0).text(*name),
                        );
                        remember(widgets, format!("{role} {name}"), &r);
                        edit.params |= r.changed();
                    }
                }

                ui.label("alpha curve (position, alpha)");
                if attr.table.alpha.is_empty() && ui.button("edit alpha").clicked() {
                    attr.table.alpha = vec![[0.0, 0.0], [1.0, 1.0]];
                    edit.params = true;
                }
                let mut remove = None;
                let count = attr.table.alpha.len();
                for (p, point) in attr.table.alpha.iter_mut().enumerate() {
                    ui.horizontal(|ui| {
                        for v in point.iter_mut() {
                            let r = ui.add(egui::DragValue::new(v).range(0.0..=1.0).speed(0.005));
                            edit.params |= r.changed();
                        }
                        if count > 1 && ui.small_button("x").clicked() {
                            remove = Some(p);
                        }
                    });
                }
                if let Some(p) = remove {
                    attr.table.alpha.remove(p);
                    edit.params = true;
                }
                if !attr.table.alpha.is_empty() {
                    if ui.button("add point").clicked() {
                        let last = *attr.table.alpha.last().unwrap_or(&[1.0, 1.0]);
                        attr.table.alpha.push(last);
                        edit.params = true;
                    }
                    // Keep positions ascending while dragging.
                    attr.table.alpha.sort_by(|x, y| x[0].total_cmp(&y[0]));
                }
            });
    }
    let r = ui.button("Save tables");
    remember(widgets, "Save tables", &r);
    edit.save_tables = r.clicked();
    edit
}
