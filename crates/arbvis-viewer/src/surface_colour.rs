//! A surface layer's colour choice in the panel: a constant, its elevation, one of its
//! own vertex properties (read once from its file and kept in egui's memory), or the
//! colours of another layer ("seismic on the horizon"), switched on and off from one
//! drop-down.

use std::path::Path;
use std::sync::Arc;

use arbvis_techniques::techniques::surface::{ColourBy, ColourFrom, SurfaceFile, SurfaceScene};

use super::widgets::Widgets;

/// Where the surface being edited lies: the scene's folder, its layers' names and which
/// of them is this one (index and name), for a one-technique scene none.
pub struct Context<'a> {
    /// The folder the scene's relative paths are read from.
    pub base: &'a Path,
    /// The scene's layer names, in order.
    pub layers: &'a [String],
    /// This layer's index and name.
    pub layer: Option<&'a (usize, String)>,
}

/// What a surface's colour follows.
#[derive(Debug, Clone, PartialEq)]
pub enum ColourChoice {
    /// `colour`.
    Constant,
    /// `colour_by = "elevation"`.
    Elevation,
    /// `colour_by = { property = NAME }`.
    Property(String),
    /// `colour_from = { layer = NAME }`.
    Layer(String),
}

impl ColourChoice {
    /// What `scene` follows now.
    pub fn of(scene: &SurfaceScene) -> ColourChoice {
        match (&scene.colour_from, &scene.colour_by) {
            (Some(from), _) => ColourChoice::Layer(from.layer.clone()),
            (None, None) => ColourChoice::Constant,
            (None, Some(ColourBy::Elevation)) => ColourChoice::Elevation,
            (None, Some(ColourBy::Property(p))) => ColourChoice::Property(p.clone()),
        }
    }

    /// `scene` made to follow this choice (a layer's colours keep `colour_by` for where
    /// the surface lies outside that layer).
    pub fn apply(&self, scene: &mut SurfaceScene) {
        scene.colour_from = None;
        match self {
            ColourChoice::Constant => scene.colour_by = None,
            ColourChoice::Elevation => scene.colour_by = Some(ColourBy::Elevation),
            ColourChoice::Property(p) => scene.colour_by = Some(ColourBy::Property(p.clone())),
            ColourChoice::Layer(l) => scene.colour_from = Some(ColourFrom { layer: l.clone() }),
        }
    }

    fn name(&self) -> String {
        match self {
            ColourChoice::Constant => "constant".into(),
            ColourChoice::Elevation => "elevation".into(),
            ColourChoice::Property(p) => format!("property {p}"),
            ColourChoice::Layer(l) => format!("layer {l}"),
        }
    }
}

/// The choices for `scene`: constant, elevation, each property its file has (and the one
/// it names), each other layer of the scene.
pub fn choices(scene: &SurfaceScene, cx: &Context<'_>, ctx: &egui::Context) -> Vec<ColourChoice> {
    let mut out = vec![ColourChoice::Constant, ColourChoice::Elevation];
    let mut properties = match &scene.file {
        Some(SurfaceFile::Path(p)) => property_names(ctx, &cx.base.join(p)).to_vec(),
        _ => Vec::new(),
    };
    if let Some(ColourBy::Property(p)) = &scene.colour_by {
        if !properties.contains(p) {
            properties.push(p.clone());
        }
    }
    out.extend(properties.into_iter().map(ColourChoice::Property));
    let own = cx.layer.map(|(_, name)| name.as_str());
    let others = cx
        .layers
        .iter()
        .filter(|n| !n.is_empty() && Some(n.as_str()) != own);
    out.extend(others.cloned().map(ColourChoice::Layer));
    if let ColourChoice::Layer(l) = ColourChoice::of(scene) {
        if !out.contains(&ColourChoice::Layer(l.clone())) {
            out.push(ColourChoice::Layer(l));
        }
    }
    out
}

/// The drop-down; true when the choice changed.
pub fn editor(
    ui: &mut egui::Ui,
    scene: &mut SurfaceScene,
    cx: &Context<'_>,
    widgets: &mut Widgets,
) -> bool {
    let options = choices(scene, cx, ui.ctx());
    let names: Vec<String> = options.iter().map(ColourChoice::name).collect();
    let pairs: Vec<(ColourChoice, &str)> = options
        .iter()
        .cloned()
        .zip(names.iter().map(String::as_str))
        .collect();
    let label = match cx.layer {
        Some((index, _)) => format!("layer {index} colour"),
        None => "Surface colour by".into(),
    };
    let mut choice = ColourChoice::of(scene);
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("Colour by");
        changed = widgets.choice(ui, &label, &mut choice, &pairs, 160.0);
    });
    if changed {
        choice.apply(scene);
    }
    changed
}

/// The vertex property names of the surface file at `path` (TSurf, x y z grids), read
/// once per file and kept in egui's memory; none for other formats or a file that does
/// not read (the layer's own error says why).
fn property_names(ctx: &egui::Context, path: &Path) -> Arc<Vec<String>> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
    if !matches!(ext.as_deref(), Some("ts" | "xyz" | "xyt")) {
        return Arc::default();
    }
    let id = egui::Id::NULL.with(("surface properties", path.to_path_buf()));
    if let Some(names) = ctx.data(|d| d.get_temp::<Arc<Vec<String>>>(id)) {
        return names;
    }
    let names: Arc<Vec<String>> = Arc::new(match arbvis_data::surface::read(path) {
        Ok(mesh) => mesh.properties.into_iter().map(|p| p.name).collect(),
        Err(_) => Vec::new(),
    });
    ctx.data_mut(|d| d.insert_temp(id, names.clone()));
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_choice_round_trips_through_the_scene() {
        let mut scene = SurfaceScene::of("f.ts");
        for choice in [
            ColourChoice::Elevation,
            ColourChoice::Property("throw".into()),
            ColourChoice::Layer("F3".into()),
            ColourChoice::Constant,
        ] {
            choice.apply(&mut scene);
            assert_eq!(ColourChoice::of(&scene), choice);
        }
        // A layer's colours keep the property for outside the layer; switched off, the
        // property is what is left.
        ColourChoice::Property("throw".into()).apply(&mut scene);
        ColourChoice::Layer("F3".into()).apply(&mut scene);
        assert_eq!(scene.colour_by, Some(ColourBy::Property("throw".into())));
    }
}
