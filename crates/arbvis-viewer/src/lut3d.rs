//! The "lut 3D" editor of v3o2 (seed Figure 18), all of it visible at once: which table
//! goes with the primary, secondary and tertiary volume and their twelve coefficients in
//! one grid (a lock per table: when ticked, editing any of its four coefficients sets all
//! four, as the seed's check boxes do), sum or product, the slice count, and under it one
//! table editor per attribute (swatches, histogram, alpha curve; see [`super::curve`]).
//! Every edit shows on the next frame (coefficients are resent to `program.local[1..3]`).
//!
//! Labels (for scripts): `Sum`, `Product`, `slices`, `ROLE table`, `Lock ROLE`,
//! `ROLE Cr` / `Cg` / `Cb` / `Ca`, `ROLE alpha` (the curve), `Save tables`, where ROLE
//! is `primary`, `secondary` or `tertiary`.

use egui::{Color32, RichText, Vec2};

use super::curve;
use super::data::ViewData;
use super::widgets::Widgets;
use arbvis_core::colortable::BUILTINS;
use arbvis_techniques::scene::Scene;
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;
use arbvis_techniques::techniques::opacity3d::{Combine, MAX_SLICES};

/// Width of the editor's panel in points: the grid and curves fit without clipping.
pub const WIDTH: f32 = 430.0;

/// The panel width (points) under which the coefficients get a grid of their own.
pub const GRID_WIDTH: f32 = 400.0;

/// Names of the three attributes, as labelled in the panel.
pub const ROLES: [&str; 3] = ["primary", "secondary", "tertiary"];

/// The coefficient names, in `program.local` order.
pub const COEFFICIENTS: [&str; 4] = ["Cr", "Cg", "Cb", "Ca"];

/// What an edit asks of the viewer.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Lut3dEdit {
    /// Parameters changed: resend them.
    pub params: bool,
    /// Write the three tables as files.
    pub save_tables: bool,
}

/// Draw the editor `width` points wide (the panel's; the curves take it, the grid may
/// scroll sideways); `locks` is the per-table lock state (UI only).
pub fn editor(
    ui: &mut egui::Ui,
    width: f32,
    scene: &mut Scene,
    data: &mut ViewData,
    locks: &mut [bool; 3],
    widgets: &mut Widgets,
) -> Lut3dEdit {
    let mut edit = Lut3dEdit::default();
    let ctx = ui.ctx().clone();
    // Tables first (they borrow the scene immutably).
    let tables: [Option<(arbvis_core::colortable::ColorTable, egui::TextureId)>; 3] =
        std::array::from_fn(|a| data.table(&ctx, scene, a).map(|(t, x)| (t.clone(), x.id())));
    let Some(o) = scene.technique.get_mut::<Opacity3dScene>() else {
        return edit;
    };
    ui.heading("lut 3D");
    ui.horizontal_wrapped(|ui| {
        ui.label("combination:");
        edit.params |= widgets.radio(ui, "Sum", &mut o.combine, Combine::Sum);
        edit.params |= widgets.radio(ui, "Product", &mut o.combine, Combine::Product);
        ui.label(match o.combine {
            Combine::Sum => "(union)",
            Combine::Product => "(intersection)",
        });
    });
    edit.params |= widgets.slider(ui, "slices", &mut o.slices, 1..=MAX_SLICES, "slices", true);
    ui.add_space(4.0);

    // A narrow panel stacks the tables and locks over the coefficients.
    let parts: &[(bool, bool)] = if width < GRID_WIDTH {
        &[(true, false), (false, true)]
    } else {
        &[(true, true)]
    };
    for (g, &(tables, coefficients)) in parts.iter().enumerate() {
        egui::Grid::new(("lut3d coefficients", g))
            .spacing([6.0, 4.0])
            .striped(true)
            .show(ui, |ui| {
                ui.label("");
                if tables {
                    ui.label("table");
                    ui.label("lock");
                }
                if coefficients {
                    for c in COEFFICIENTS {
                        ui.label(c);
                    }
                }
                ui.end_row();
                for (a, attr) in o.attributes_mut().into_iter().enumerate() {
                    let role = ROLES[a];
                    ui.label(role);
                    let Some(attr) = attr else {
                        ui.label(RichText::new("none").weak());
                        ui.end_row();
                        continue;
                    };
                    if tables {
                        edit.params |= table_and_lock(ui, role, attr, &mut locks[a], widgets);
                    }
                    if coefficients {
                        for (c, name) in COEFFICIENTS.iter().enumerate() {
                            let mut v = attr.coefficients[c];
                            let label = format!("{role} {name}");
                            if widgets.drag_value(ui, &label, &mut v, 0.0..=4.0, 0.005) {
                                if locks[a] {
                                    attr.coefficients = [v; 4];
                                } else {
                                    attr.coefficients[c] = v;
                                }
                                edit.params = true;
                            }
                        }
                    }
                    ui.end_row();
                }
            });
        ui.add_space(2.0);
    }
    ui.label(
        RichText::new("a ticked lock edits the table's four coefficients as one value")
            .small()
            .weak(),
    );
    ui.separator();

    let width = width.min(WIDTH - 20.0);
    for (a, attr) in o.attributes_mut().into_iter().enumerate() {
        let (Some(attr), Some((table, texture))) = (attr, &tables[a]) else {
            continue;
        };
        let role = ROLES[a];
        let range = data
            .volume
            .as_ref()
            .and_then(|v| v.prepared.ranges[a])
            .map(|(lo, hi)| format!("{} .. {}", short(lo), short(hi)))
            .unwrap_or_default();
        ui.horizontal_wrapped(|ui| {
            ui.label(RichText::new(format!("{role}: {}", attr.attribute.name())).strong());
            ui.label(RichText::new(range).weak());
        });
        let histogram = data.histogram(&ctx, a);
        let e = curve::editor(
            ui,
            widgets,
            &format!("{role} alpha"),
            &mut attr.table.alpha,
            table,
            *texture,
            histogram,
            Vec2::new(width, 96.0),
        );
        edit.params |= e.changed;
        ui.add_space(6.0);
    }
    ui.horizontal_wrapped(|ui| {
        edit.save_tables = widgets.button(ui, "Save tables");
        ui.label(
            RichText::new("writes arbvis-table-ROLE.table")
                .small()
                .color(Color32::GRAY),
        );
    });
    edit
}

/// An attribute's table choice and lock check box (grid cells); true when changed.
fn table_and_lock(
    ui: &mut egui::Ui,
    role: &str,
    attr: &mut arbvis_techniques::techniques::opacity3d::AttributeScene,
    lock: &mut bool,
    widgets: &mut Widgets,
) -> bool {
    let mut changed = false;
    // The table the scene gives: a file, colours written out, or a built-in.
    let own = match (&attr.table.file, attr.table.colors.len()) {
        (Some(f), _) => Some(format!("file {}", f.display())),
        (None, n) if n > 0 => Some(format!("{n} colours")),
        _ => None,
    };
    let mut name = own.clone().unwrap_or_else(|| attr.table.builtin.clone());
    let mut options: Vec<(String, &str)> = BUILTINS.iter().map(|b| (b.to_string(), *b)).collect();
    if let Some(own) = &own {
        options.push((own.clone(), own.as_str()));
    }
    if widgets.choice(ui, &format!("{role} table"), &mut name, &options, 90.0)
        && own.as_ref() != Some(&name)
    {
        attr.table.builtin = name.clone();
        attr.table.file = None;
        attr.table.colors.clear();
        changed = true;
    }
    if widgets.checkbox(ui, &format!("Lock {role}"), lock, "") && *lock {
        attr.coefficients = [attr.coefficients[0]; 4];
        changed = true;
    }
    changed
}

/// A value for a range label: integers plainly, others with 4 significant digits.
pub fn short(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e9 {
        format!("{}", v as i64)
    } else {
        format!("{v:.4}")
    }
}
