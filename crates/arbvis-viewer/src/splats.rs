//! The splat editor: layers and classification codes shown or hidden, colour mode and
//! property (the cloud's own attributes), faults and undefined facies,
//! point size and factor, kernel and its width, lighting (per-layer normals), sort
//! method, points or tiles (precise only), the tile size and eye-dome lighting, and volume mode's transfer
//! function. The frame, sort and tile-list times show in the panel's status line.

use super::legend::class_name;
use super::widgets::Widgets;
use arbvis_core::vocab::Fidelity;
use arbvis_data::points::PointSource;
use arbvis_techniques::summary::CloudSummary;
use arbvis_techniques::techniques::splats::scene::{
    ColourMode, DrawChoice, Kernel, Mode, SortChoice,
};
use arbvis_techniques::techniques::splats::SplatsScene;

/// Layer ids with a toggle (the seed's sections have layers 0..7).
pub const LAYERS: i32 = 8;

/// Properties offered when the cloud is not known (the seed's sections').
const SEED_PROPERTIES: [&str; 3] = ["porosity", "amplitude", "joint_dip"];

/// Draw the editor for a scene of `fidelity` (its cloud summarised by `cloud`, where
/// loaded); true when something changed.
pub fn editor(
    ui: &mut egui::Ui,
    scene: &mut SplatsScene,
    fidelity: Fidelity,
    cloud: Option<&CloudSummary>,
    w: &mut Widgets,
) -> bool {
    // Layers, facies and faults are the geological sections' (the seed's `.dat` and the
    // generated one); a lidar or scanned cloud has classes, colours and intensity instead.
    let section = matches!(scene.cloud, PointSource::Section(_) | PointSource::Dat(_));
    let mut changed = shown(ui, scene, cloud, section, w);
    changed |= colouring(ui, scene, cloud, section, w);
    ui.separator();
    changed |= footprints(ui, scene, fidelity, section, w);
    ui.separator();
    changed |= volume_mode(ui, scene, w);
    changed
}

/// Which classes (and, for a section, layers, undefined facies and faults) are shown.
fn shown(
    ui: &mut egui::Ui,
    scene: &mut SplatsScene,
    cloud: Option<&CloudSummary>,
    section: bool,
    w: &mut Widgets,
) -> bool {
    let mut changed = false;
    // The classes the cloud holds, and any the scene hides (a COPC cut may not hold them).
    let mut classes: Vec<i32> = cloud.map_or(Vec::new(), |c| c.classes.clone());
    classes.extend(scene.hide_classes.iter().copied());
    classes.sort_unstable();
    classes.dedup();
    if !classes.is_empty() {
        ui.label("Classes shown");
        ui.horizontal_wrapped(|ui| {
            for class in classes {
                let (label, text) = (format!("Class {class}"), class_name(class));
                changed |= shown_toggle(ui, w, &mut scene.hide_classes, class, &label, &text);
            }
        });
    }
    if section {
        ui.label("Layers shown");
        ui.horizontal_wrapped(|ui| {
            for layer in 0..LAYERS {
                let (label, text) = (format!("Layer {layer}"), layer.to_string());
                changed |= shown_toggle(ui, w, &mut scene.hide_layers, layer, &label, &text);
            }
        });
        changed |= w.checkbox(
            ui,
            "Hide undefined facies",
            &mut scene.hide_undefined,
            "Hide undefined facies (-999)",
        );
        changed |= w.checkbox(
            ui,
            "Faults in white",
            &mut scene.faults_white,
            "Faults in white",
        );
    }
    changed
}

/// What the colour says: the mode (a section's, or a lidar cloud's) and the property.
fn colouring(
    ui: &mut egui::Ui,
    scene: &mut SplatsScene,
    cloud: Option<&CloudSummary>,
    section: bool,
    w: &mut Widgets,
) -> bool {
    let mut changed = false;
    let modes: &[(ColourMode, &str)] = if section {
        &[
            (ColourMode::Facies, "facies"),
            (ColourMode::Layer, "layer"),
            (ColourMode::Property, "property"),
            (ColourMode::Elevation, "elevation"),
        ]
    } else {
        &[
            (ColourMode::Rgb, "rgb"),
            (ColourMode::Intensity, "intensity"),
            (ColourMode::Classification, "classification"),
            (ColourMode::Elevation, "elevation"),
            (ColourMode::Property, "property"),
            (ColourMode::Layer, "layer"),
        ]
    };
    ui.horizontal_wrapped(|ui| {
        ui.label("Colour by");
        changed |= w.choice(ui, "Colour", &mut scene.colour, modes, 120.0);
    });
    let mut property = scene.property.clone();
    // The cloud's own attributes (a LAS file's intensity, GPS time, extra bytes, ...).
    let names: Vec<String> = match cloud {
        Some(c) => c.ranges.iter().map(|(n, _)| n.clone()).collect(),
        None => SEED_PROPERTIES.iter().map(|n| n.to_string()).collect(),
    };
    let properties: Vec<(String, &str)> = names.iter().map(|n| (n.clone(), n.as_str())).collect();
    ui.horizontal_wrapped(|ui| {
        ui.label("Property");
        if w.choice(ui, "Property", &mut property, &properties, 120.0) {
            scene.property = property;
            changed = true;
        }
    });
    changed
}

/// Each splat's footprint: size, kernel, lighting, sort, and (precise) points or tiles
/// and eye-dome lighting.
fn footprints(
    ui: &mut egui::Ui,
    scene: &mut SplatsScene,
    fidelity: Fidelity,
    section: bool,
    w: &mut Widgets,
) -> bool {
    let mut changed = false;
    changed |= w.slider(
        ui,
        "Point size",
        &mut scene.point_size,
        1.0..=64.0,
        "point size",
        true,
    );
    changed |= w.slider(ui, "Factor", &mut scene.factor, 0.1..=10.0, "factor", true);
    ui.horizontal_wrapped(|ui| {
        ui.label("Kernel");
        for (k, label) in [
            (Kernel::Gaussian, "Gaussian"),
            (Kernel::Smoothstep, "smoothstep"),
        ] {
            changed |= w.radio(ui, label, &mut scene.kernel, k);
        }
    });
    changed |= w.slider(
        ui,
        "Gaussian width",
        &mut scene.gauss_width,
        0.0..=2.0,
        "width",
        false,
    );
    changed |= w.checkbox(
        ui,
        "Lighting",
        &mut scene.lighting,
        if section {
            "Lighting (normals per layer)"
        } else {
            "Lighting (estimated normals)"
        },
    );
    ui.horizontal_wrapped(|ui| {
        ui.label("Sort");
        for (s, label) in [
            (SortChoice::Radix, "radix"),
            (SortChoice::Keys, "keys"),
            (SortChoice::Seed, "seed"),
            (SortChoice::None, "none"),
        ] {
            let r = ui.radio_value(&mut scene.sort, s, label);
            changed |= w.add(ui, &format!("Sort {label}"), &r) && r.changed();
        }
    });
    // Tiles composite the precise footprints: faithful mode draws the original points.
    let precise = fidelity == Fidelity::Precise;
    if !precise {
        w.text(
            ui,
            "Draw needs precise",
            "Points or tiles: precise mode only (faithful draws the original points)",
        );
    }
    ui.add_enabled_ui(precise, |ui| {
        ui.horizontal_wrapped(|ui| {
            ui.label("Draw");
            for (d, label) in [(DrawChoice::Points, "points"), (DrawChoice::Tiles, "tiles")] {
                let r = ui.radio_value(&mut scene.draw, d, label);
                changed |= w.add(ui, &format!("Draw {label}"), &r) && r.changed();
            }
        });
        changed |= w.slider(ui, "Tile size", &mut scene.tile, 1..=16, "tile (px)", false);
        changed |= w.slider(
            ui,
            "Eye-dome lighting",
            &mut scene.edl,
            0.0..=5.0,
            "eye-dome",
            false,
        );
    });
    changed
}

/// Volume mode: the property as density, its threshold and range.
fn volume_mode(ui: &mut egui::Ui, scene: &mut SplatsScene, w: &mut Widgets) -> bool {
    let mut changed = false;
    let mut volume = scene.mode == Mode::Volume;
    if w.checkbox(
        ui,
        "Volume mode",
        &mut volume,
        "Volume mode (property as density)",
    ) {
        scene.mode = if volume { Mode::Volume } else { Mode::Surface };
        changed = true;
    }
    if !volume {
        w.text(
            ui,
            "Threshold needs volume mode",
            "Threshold and range: in volume mode only",
        );
    }
    ui.add_enabled_ui(volume, |ui| {
        ui.horizontal_wrapped(|ui| {
            ui.label("Threshold");
            changed |= w.drag_value(
                ui,
                "Threshold",
                &mut scene.volume.threshold,
                -1e9..=1e9,
                0.0005,
            );
            ui.label("± range");
            changed |= w.drag_value(ui, "Range", &mut scene.volume.range, 0.0..=1e9, 0.0005);
        });
    });
    changed
}

/// A checkbox (widget `label`, showing `text`) ticked while `id` is not in `hidden`
/// (kept sorted); true when toggled.
fn shown_toggle(
    ui: &mut egui::Ui,
    w: &mut Widgets,
    hidden: &mut Vec<i32>,
    id: i32,
    label: &str,
    text: &str,
) -> bool {
    let mut shown = !hidden.contains(&id);
    if !w.checkbox(ui, label, &mut shown, text) {
        return false;
    }
    hidden.retain(|&h| h != id);
    if !shown {
        hidden.push(id);
        hidden.sort_unstable();
    }
    true
}
