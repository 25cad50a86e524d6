//! The scene model: one technique, its parameters, camera, size, fidelity, program kind
//! and target precision, read from TOML. Technique issues add variants to
//! [`TechniqueScene`]; a renderer builds only what its scene names.

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use crate::catalog::{demos, LayerInfo, LayerTable, TechniqueScene};
use arbvis_core::camera::Camera;
pub use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_gl::{ProgramChoice, TargetFormat};

/// A whole scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SceneText", into = "SceneText")]
pub struct Scene {
    /// Image size in pixels `[width, height]`.
    #[serde(default = "default_size")]
    pub size: [u32; 2],
    /// Faithful or precise.
    #[serde(default)]
    pub fidelity: Fidelity,
    /// ARB, GLSL or auto.
    #[serde(default)]
    pub programs: ProgramChoice,
    /// Colour target; by default RGBA8 when faithful, RGBA32F when precise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<TargetFormat>,
    /// Clear colour, RGBA.
    #[serde(default)]
    pub background: [f32; 4],
    /// Write pictures with a transparent background (straight colour, alpha = coverage)
    /// instead of what the screen shows (opaque, composited over `background`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub transparent: bool,
    /// The camera.
    #[serde(default)]
    pub camera: Camera,
    /// Draw the colour tables (with their value ranges) and keys into offscreen pictures
    /// (`crate::annotate`); off, so that a picture holds the renderer's pixels alone.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub legend: bool,
    /// Draw the box's axes with ticks in the data's own numbers into offscreen pictures.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub axes: bool,
    /// The memory budget this scene asks for (`"16G"`, `"75%"`): taken where neither
    /// `--memory-budget` nor `ARBVIS_MEMORY_BUDGET` sets one ([`arbvis_core::budget`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory_budget: Option<String>,
    /// How to get the scene's data where it is not in the clone (a download or a
    /// conversion command), said when a file the scene reads is missing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data_from: Option<String>,
    /// The technique and its parameters: a one-layer scene's, or a layered scene's first
    /// layer's.
    pub technique: TechniqueScene,
    /// The first layer's name, visibility and placement (the defaults for a
    /// `[technique.NAME]` scene).
    #[serde(skip)]
    pub layer: LayerInfo,
    /// The layers after the first, in order: each its name, visibility, placement and
    /// technique. Empty for a one-layer scene.
    #[serde(skip)]
    pub more_layers: Vec<(LayerInfo, TechniqueScene)>,
    /// Folder that relative data paths are read from: the scene file's folder, or the
    /// current folder for demos and scenes given as text.
    #[serde(skip)]
    pub base: std::path::PathBuf,
}

/// A scene as its text holds it: one technique (`[technique.NAME]`) or layers
/// (`[[layer]]`), read into and written from [`Scene`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneText {
    /// Image size in pixels `[width, height]`.
    #[serde(default = "default_size")]
    size: [u32; 2],
    /// Faithful or precise.
    #[serde(default)]
    fidelity: Fidelity,
    /// ARB, GLSL or auto.
    #[serde(default)]
    programs: ProgramChoice,
    /// Colour target; by default RGBA8 when faithful, RGBA32F when precise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    target: Option<TargetFormat>,
    /// Clear colour, RGBA.
    #[serde(default)]
    background: [f32; 4],
    /// Write pictures with a transparent background (straight colour, alpha = coverage)
    /// instead of what the screen shows (opaque, composited over `background`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    transparent: bool,
    /// The camera.
    #[serde(default)]
    camera: Camera,
    /// Draw the colour tables (with their value ranges) and keys into offscreen pictures
    /// (`crate::annotate`); off, so that a picture holds the renderer's pixels alone.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    legend: bool,
    /// Draw the box's axes with ticks in the data's own numbers into offscreen pictures.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    axes: bool,
    /// The memory budget this scene asks for (`"16G"`, `"75%"`): taken where neither
    /// `--memory-budget` nor `ARBVIS_MEMORY_BUDGET` sets one ([`arbvis_core::budget`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    memory_budget: Option<String>,
    /// How to get the scene's data where it is not in the clone (a download or a
    /// conversion command), said when a file the scene reads is missing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    data_from: Option<String>,
    /// The technique and its parameters (a one-layer scene).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    technique: Option<TechniqueScene>,
    /// The layers, in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    layer: Vec<crate::catalog::LayerTable>,
}

/// Why a scene's text holds no drawable technique.
#[derive(Debug, thiserror::Error)]
pub enum LayersError {
    /// Neither `[technique.NAME]` nor `[[layer]]`.
    #[error("a scene needs a [technique.NAME] table or [[layer]] tables")]
    Neither,
    /// Both.
    #[error("a scene has a [technique.NAME] table or [[layer]] tables, not both")]
    Both,
    /// A layer naming no technique or several.
    #[error("layer {index} ({name}) must name exactly one technique's table ([layer.surface], [layer.opacity3d], ...); it names {found}")]
    Techniques {
        /// 0-based.
        index: usize,
        /// Its name or "unnamed".
        name: String,
        /// What it names.
        found: String,
    },
}

impl TryFrom<SceneText> for Scene {
    type Error = LayersError;

    fn try_from(t: SceneText) -> Result<Scene, LayersError> {
        let mut layers = Vec::with_capacity(t.layer.len());
        for (index, table) in t.layer.into_iter().enumerate() {
            let name = table.name.clone();
            layers.push(table.split().map_err(|found| LayersError::Techniques {
                index,
                name: if name.is_empty() {
                    "unnamed".into()
                } else {
                    name
                },
                found: match found.len() {
                    0 => "none".into(),
                    _ => found.join(", "),
                },
            })?);
        }
        let mut layers = layers.into_iter();
        let ((layer, technique), more_layers) = match (t.technique, layers.next()) {
            (Some(_), Some(_)) => return Err(LayersError::Both),
            (None, None) => return Err(LayersError::Neither),
            (Some(technique), None) => ((LayerInfo::default(), technique), Vec::new()),
            (None, Some(first)) => (first, layers.collect()),
        };
        Ok(Scene {
            size: t.size,
            fidelity: t.fidelity,
            programs: t.programs,
            target: t.target,
            background: t.background,
            transparent: t.transparent,
            camera: t.camera,
            legend: t.legend,
            axes: t.axes,
            memory_budget: t.memory_budget,
            data_from: t.data_from,
            technique,
            layer,
            more_layers,
            base: Default::default(),
        })
    }
}

impl From<Scene> for SceneText {
    fn from(s: Scene) -> SceneText {
        let (technique, layer) = if s.is_layered() {
            let first = std::iter::once((s.layer, s.technique));
            let tables = first
                .chain(s.more_layers)
                .map(|(i, t)| LayerTable::of(i, t));
            (None, tables.collect())
        } else {
            (Some(s.technique), Vec::new())
        };
        SceneText {
            size: s.size,
            fidelity: s.fidelity,
            programs: s.programs,
            target: s.target,
            background: s.background,
            transparent: s.transparent,
            camera: s.camera,
            legend: s.legend,
            axes: s.axes,
            memory_budget: s.memory_budget,
            data_from: s.data_from,
            technique,
            layer,
        }
    }
}

impl Scene {
    /// Whether the scene is written as layers: more than one, or one with a name,
    /// hidden or placed by hand.
    pub fn is_layered(&self) -> bool {
        !self.more_layers.is_empty() || self.layer != LayerInfo::default()
    }

    /// Every layer in order: its info and technique (one for a `[technique.NAME]` scene).
    pub fn layers(&self) -> impl Iterator<Item = (&LayerInfo, &TechniqueScene)> {
        std::iter::once((&self.layer, &self.technique))
            .chain(self.more_layers.iter().map(|(i, t)| (i, t)))
    }

    /// [`Scene::layers`], to change.
    pub fn layers_mut(&mut self) -> impl Iterator<Item = (&mut LayerInfo, &mut TechniqueScene)> {
        std::iter::once((&mut self.layer, &mut self.technique))
            .chain(self.more_layers.iter_mut().map(|(i, t)| (i, t)))
    }

    /// Every layer in order, owned (the scene keeps none until [`Scene::set_layers`]).
    pub fn layer_list(&self) -> Vec<(LayerInfo, TechniqueScene)> {
        self.layers().map(|(i, t)| (i.clone(), t.clone())).collect()
    }

    /// Replace the layers by `layers` (at least one: an empty list is refused).
    pub fn set_layers(
        &mut self,
        layers: Vec<(LayerInfo, TechniqueScene)>,
    ) -> Result<(), FieldError> {
        let mut layers = layers.into_iter();
        let (info, technique) = layers
            .next()
            .ok_or_else(|| FieldError::new("layer", "a scene keeps at least one layer"))?;
        self.layer = info;
        self.technique = technique;
        self.more_layers = layers.collect();
        Ok(())
    }

    /// Move layer `from` to position `to` (both below the count; drawn in the new order).
    pub fn move_layer(&mut self, from: usize, to: usize) -> Result<(), FieldError> {
        let mut layers = self.layer_list();
        if from >= layers.len() || to >= layers.len() {
            return Err(FieldError::new(
                "layer",
                format!("{from} to {to}: the scene has {} layers", layers.len()),
            ));
        }
        let layer = layers.remove(from);
        layers.insert(to, layer);
        self.set_layers(layers)
    }

    /// The dotted key of a technique's `key` (`technique.NAME.rest`, as the catalog
    /// names it) in layer `index`: itself in a one-layer scene, `layer.INDEX.NAME.rest`
    /// in a layered one.
    pub fn layer_key(&self, index: usize, key: &str) -> String {
        match (self.is_layered(), key.strip_prefix("technique.")) {
            (true, Some(rest)) => format!("layer.{index}.{rest}"),
            _ => key.to_string(),
        }
    }
}
/// A data file a scene reads ([`Scene::data_files`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DataFile {
    /// The dotted key that names it, e.g. `technique.opacity3d.primary.volume.segy`.
    pub key: String,
    /// The path as the scene writes it.
    pub written: std::path::PathBuf,
    /// The path as read: against the scene's folder, absolute.
    pub resolved: std::path::PathBuf,
}

impl Scene {
    /// `error` with the scene's `data_from` hint added when a file it reads is missing.
    pub fn explain_missing(&self, error: String) -> String {
        match &self.data_from {
            Some(how) if error.contains("no such file") || error.contains("No such file") => {
                format!("{error}\n  this scene's data is not in the clone: {how}")
            }
            _ => error,
        }
    }
}

fn default_size() -> [u32; 2] {
    [256, 256]
}

/// Errors reading a scene; each names the file and, for syntax, the line and column.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read (not named `source`, so that a `{:#}` chain does not
    /// print the OS error twice).
    #[error("{path}: {error}")]
    Io {
        /// The scene file.
        path: String,
        /// What failed.
        error: std::io::Error,
    },
    /// TOML syntax or a value of the wrong shape.
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// The scene file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The dotted key whose value is of the wrong shape, where the text spells it out.
        key: Option<String>,
        /// What was expected.
        message: String,
    },
    /// Values that parse but cannot be rendered, at the key that holds them.
    #[error("{path}:{line}:{column}: {key}: {message}")]
    Invalid {
        /// The scene file.
        path: String,
        /// 1-based line of the key (or of its nearest table present in the text).
        line: usize,
        /// 1-based column.
        column: usize,
        /// Dotted key, e.g. `technique.opacity3d.slices`.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// No built-in demo of that name.
    #[error("no demo named {0:?}; demos: {demos}", demos = demos().map(|d| d.0).collect::<Vec<_>>().join(", "))]
    UnknownDemo(String),
}

impl Scene {
    /// Parse scene text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| {
            let start = e.span().map_or(0, |s| s.start);
            let (line, column) = line_column(text, start);
            SceneError::Parse {
                path: origin.to_string(),
                line,
                column,
                key: key_at(text, start),
                message: parse_message(text, start, e.message()),
            }
        })?;
        let mut scene = scene;
        // Defaults that depend on the data the scene names, for the keys it leaves out.
        if let Ok(written) = text.parse::<toml::Table>() {
            let layered = scene.is_layered();
            let (camera, mut fidelity) = (scene.camera, scene.fidelity);
            let mut cameras = Vec::new();
            for (index, (_, technique)) in scene.layers_mut().enumerate() {
                // A layer's keys are read where its text writes them (`layer.I.NAME...`).
                let written = |key: &str| match key.strip_prefix("technique.") {
                    Some(rest) if layered => is_written(&written, &format!("layer.{index}.{rest}")),
                    _ => is_written(&written, key),
                };
                let mut its_camera = camera;
                technique.unwritten_defaults(&written, &mut its_camera, &mut fidelity);
                cameras.push(its_camera);
            }
            scene.fidelity = fidelity;
            // A one-layer scene takes its technique's camera; a layered scene its own
            // (the world's z up: crate::layered).
            scene.camera = match layered {
                false => cameras[0],
                true if !is_written(&written, "camera") => crate::layered::default_camera(),
                true => scene.camera,
            };
        }
        let checked = longer_arrays(text, &scene).map_or_else(|| scene.validate(), Err);
        checked.map_err(|e| {
            let (line, column) = key_position(text, &e.key);
            SceneError::Invalid {
                path: origin.to_string(),
                line,
                column,
                key: e.key,
                message: arbvis_core::input::shorten(&e.message, MESSAGE_CHARS),
            }
        })?;
        Ok(scene)
    }

    /// Read and parse a scene file (a regular file of at most
    /// [`arbvis_core::input::MAX_SCENE_BYTES`], UTF-8).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let read = arbvis_core::input::read_text(path, arbvis_core::input::MAX_SCENE_BYTES)
            .map_err(|error| SceneError::Io {
                path: path.display().to_string(),
                error,
            })
            .and_then(|text| Scene::parse(&text, &path.display().to_string()));
        let mut scene = read.map_err(|e| data_not_scene(path).unwrap_or(e))?;
        scene.base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(scene)
    }

    /// [`Scene::load`], and every data file it reads found ([`Scene::check_data_files`]):
    /// what the command line does before it renders, views or benches a scene.
    pub fn load_checked(path: &Path) -> Result<Scene, SceneError> {
        let scene = Scene::load(path)?;
        let text = arbvis_core::input::read_text(path, arbvis_core::input::MAX_SCENE_BYTES).ok();
        scene.check_data_files(&path.display().to_string(), text.as_deref())?;
        Ok(scene)
    }

    /// A built-in demo scene.
    pub fn demo(name: &str) -> Result<Scene, SceneError> {
        let (_, text) = demos()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| SceneError::UnknownDemo(name.to_string()))?;
        Scene::parse(text, &format!("demo:{name}"))
    }

    /// The scene as TOML (what the viewer saves).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot serialize: {e}\n"))
    }

    /// Call `f` on every data file the scene names (volumes, table files, clip meshes and
    /// masks, meshes, clouds), with the dotted key that holds it.
    pub fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut std::path::PathBuf)) {
        let layered = self.is_layered();
        for (index, (_, technique)) in self.layers_mut().enumerate() {
            technique.for_each_data_path(&mut |key, path| match key.strip_prefix("technique.") {
                Some(rest) if layered => f(&format!("layer.{index}.{rest}"), path),
                _ => f(key, path),
            });
        }
    }

    /// Every data file the scene reads: its key, the path as written and as resolved
    /// against [`Scene::base`].
    pub fn data_files(&self) -> Vec<DataFile> {
        let mut files = Vec::new();
        let base = self.base.clone();
        self.clone().for_each_data_path(&mut |key, p| {
            files.push(DataFile {
                key: key.to_string(),
                written: p.clone(),
                resolved: match arbvis_data::fetch::resolve(&base, p) {
                    url if arbvis_data::fetch::url_of(&url).is_some() => url,
                    local => std::path::absolute(&local).unwrap_or(local),
                },
            })
        });
        files
    }

    /// The first data file the scene reads that does not exist, as an error naming its
    /// key (at its line in `text`, the scene's own text, where given), the path as
    /// written and as resolved, and the scene's `data_from` hint.
    pub fn check_data_files(&self, origin: &str, text: Option<&str>) -> Result<(), SceneError> {
        // A URL's object is checked when it is read (a 404 names it).
        let missing = self
            .data_files()
            .into_iter()
            .find(|f| arbvis_data::fetch::url_of(&f.resolved).is_none() && !f.resolved.exists());
        let Some(missing) = missing else {
            return Ok(());
        };
        let (line, column) = text.map_or((1, 1), |t| key_position(t, &missing.key));
        let relative = if missing.written.is_absolute() {
            String::new()
        } else {
            " (a scene's data paths are relative to the scene's folder)".to_string()
        };
        Err(SceneError::Invalid {
            path: origin.to_string(),
            line,
            column,
            key: missing.key,
            message: self.explain_missing(format!(
                "no such file: {:?} as written, {} as resolved{relative}",
                missing.written.display().to_string(),
                missing.resolved.display()
            )),
        })
    }

    /// A copy whose relative data paths are made absolute against [`Scene::base`], so it
    /// can be saved anywhere.
    pub fn with_absolute_paths(&self) -> Scene {
        let mut scene = self.clone();
        let base = std::path::absolute(&self.base).unwrap_or_else(|_| self.base.clone());
        scene.for_each_data_path(&mut |_, p| *p = arbvis_data::fetch::resolve(&base, p));
        scene.base = base;
        scene
    }

    /// The colour a frame is cleared to: transparent black for transparent pictures
    /// (colour then accumulates premultiplied), else the background.
    pub fn clear_colour(&self) -> [f32; 4] {
        if self.transparent {
            [0.0; 4]
        } else {
            self.background
        }
    }

    /// A frame as the scene's pictures show it: opaque, or straight colour with
    /// coverage alpha when `transparent`.
    pub fn picture(&self, frame: &arbvis_core::image::Image) -> arbvis_core::image::Image {
        if self.transparent {
            frame.unpremultiplied()
        } else {
            frame.opaque()
        }
    }

    /// The scene's `memory_budget` in bytes, if it names one.
    pub fn memory_budget_bytes(&self) -> Result<Option<u64>, FieldError> {
        self.memory_budget
            .as_deref()
            .map(arbvis_core::budget::parse)
            .transpose()
            .map_err(|m| FieldError::new("memory_budget", m.to_string()))
    }

    /// What a renderer needs of the scene besides its technique's parameters.
    pub fn settings(&self) -> crate::catalog::Settings<'_> {
        crate::catalog::Settings {
            fidelity: self.fidelity,
            programs: self.programs,
            base: &self.base,
            projection: self.camera.projection,
            view: arbvis_core::camera::View::of(&self.camera, self.size),
        }
    }

    /// The large allocations rendering this scene makes that the scene alone determines:
    /// the target, with `read_back` the frame read back and written (f32 RGBA, a flipped
    /// copy, the picture, the PNG's rows), and the technique's generated data.
    pub fn memory_estimate(&self, read_back: bool) -> Vec<arbvis_core::budget::Estimate> {
        use arbvis_core::budget::Estimate;
        let [w, h] = self.size;
        let pixels = w as u64 * h as u64;
        let format = self.target_format();
        let mut out = vec![Estimate::of(
            format!("the {w}x{h} {} target", format.name()),
            pixels,
            format.bytes_per_pixel() + 4,
        )];
        if read_back {
            out.push(Estimate::of(
                format!("reading back and writing the {w}x{h} frame"),
                pixels,
                BYTES_PER_READ_PIXEL,
            ));
        }
        let layered = self.is_layered();
        for (index, (info, technique)) in self.layers().enumerate() {
            let estimates = technique.memory_estimate(self.size).into_iter();
            // A layered scene's estimates say which layer makes them.
            out.extend(estimates.map(|mut e| {
                if layered {
                    e.what = match info.name.as_str() {
                        "" => format!("layer {index}: {}", e.what),
                        name => format!("layer {index} ({name}): {}", e.what),
                    };
                }
                e
            }));
        }
        out
    }

    /// The target precision in effect.
    pub fn target_format(&self) -> TargetFormat {
        self.target.unwrap_or(self.fidelity.default_target())
    }

    /// Check values that parse but cannot be rendered; the error names the key.
    pub fn validate(&self) -> Result<(), FieldError> {
        let [w, h] = self.size;
        if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
            return Err(FieldError::new(
                "size",
                format!("{w}x{h}: each side must be 1..=16384"),
            ));
        }
        if self.background.iter().any(|v| !v.is_finite()) {
            return Err(FieldError::new("background", "must be finite"));
        }
        let zoom = self.camera.zoom;
        if !(zoom.is_finite() && zoom > 0.0 && zoom <= 1e6) {
            return Err(FieldError::new(
                "camera.zoom",
                format!("{zoom}: a magnification above 0 and at most 1e6 (1: the data fills the shorter side)"),
            ));
        }
        if self.camera.rotation.iter().any(|v| !v.is_finite()) {
            return Err(FieldError::new("camera.rotation", "must be finite"));
        }
        self.memory_budget_bytes()?;
        let count = self.layers().count();
        if count > crate::layered::MAX_LAYERS {
            return Err(FieldError::new(
                "layer",
                format!(
                    "{count} layers: a scene holds at most {}",
                    crate::layered::MAX_LAYERS
                ),
            ));
        }
        for (index, (info, technique)) in self.layers().enumerate() {
            validate_layer(info).map_err(|e| e.within(&format!("layer.{index}")))?;
            technique
                .validate(self.fidelity, self.programs)
                .map_err(|e| FieldError::new(self.layer_key(index, &e.key), e.message))?;
        }
        Ok(())
    }
}

/// A layer's hand placement: finite, its scale above 0.
fn validate_layer(info: &LayerInfo) -> Result<(), FieldError> {
    if info.offset.iter().any(|v| !v.is_finite()) {
        return Err(FieldError::new("offset", "must be finite"));
    }
    if !(info.scale.is_finite() && info.scale > 0.0) {
        return Err(FieldError::new(
            "scale",
            format!("{}: a finite factor above 0", info.scale),
        ));
    }
    Ok(())
}

/// The error for a data file given where a scene was expected (a SEG-Y, a mesh, a cloud:
/// what the reader registry recognizes), if `path` is one.
fn data_not_scene(path: &Path) -> Option<SceneError> {
    use std::io::Read;
    // Only a regular file is opened: a FIFO would block the open (what read_text refused).
    if !std::fs::metadata(path).ok()?.is_file() {
        return None;
    }
    let mut head = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .take(4096)
        .read_to_end(&mut head)
        .ok()?;
    let format = arbvis_data::sniff::format(path, &head)?;
    let reads = arbvis_data::sniff::reader(format).reads;
    Some(SceneError::Parse {
        path: path.display().to_string(),
        line: 1,
        column: 1,
        key: None,
        message: format!(
            "this is {reads} data, not a scene (TOML): a scene names it, e.g. `volume = {{ segy = \"...\" }}`, `mesh = {{ file = \"...\" }}` or `cloud = {{ las = \"...\" }}` (docs/scenes.md); `arbvis inspect` describes it"
        ),
    })
}

/// CPU memory per pixel of a frame read back and written: f32 RGBA as read (16 bytes),
/// flipped to top-down (16), the picture made from it (16), and the PNG's 16-bit rows (8).
/// With the target's bytes added, this sum stays above the measured growth of peak
/// resident memory per pixel, faithful and precise (measured: docs/benchmarks.md, "Memory
/// estimates and work limits").
pub const BYTES_PER_READ_PIXEL: u64 = 56;

/// Longest message quoted from a scene error (a 50 MB key must not reach the terminal).
const MESSAGE_CHARS: usize = 300;

/// Line and column of the dotted `key` in `text`, or of its longest prefix that the text
/// spells out (a value left at its default has no position of its own).
/// An array in the scene text with more values than its field holds (`size = [32, 32,
/// 5]`, a quaternion where Euler degrees are read): the TOML reader fills fixed-size
/// fields from the first values and drops the rest without a word, so the parsed scene,
/// written back, is compared with the text and the first longer array is an error.
fn longer_arrays(text: &str, scene: &Scene) -> Option<FieldError> {
    let original: toml::Table = text.parse().ok()?;
    let parsed = toml::Value::try_from(scene).ok()?;
    compare_lengths(&toml::Value::Table(original), &parsed, "")
}

fn compare_lengths(original: &toml::Value, parsed: &toml::Value, key: &str) -> Option<FieldError> {
    use toml::Value::{Array, Table};
    match (original, parsed) {
        (Array(a), Array(b)) => {
            if a.len() > b.len() {
                return Some(FieldError::new(
                    key,
                    format!(
                        "{} values where {} are read (the rest would be ignored)",
                        a.len(),
                        b.len()
                    ),
                ));
            }
            a.iter()
                .zip(b)
                .find_map(|(x, y)| compare_lengths(x, y, key))
        }
        (Table(a), Table(b)) => a.iter().find_map(|(k, v)| {
            let sub = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            b.get(k).and_then(|w| compare_lengths(v, w, &sub))
        }),
        _ => None,
    }
}

fn key_position(text: &str, key: &str) -> (usize, usize) {
    use toml::de::{DeTable, DeValue};
    let Ok(root) = DeTable::parse(text) else {
        return (1, 1);
    };
    let mut table = root.get_ref();
    let mut at = 0;
    let mut parts = key.split('.').peekable();
    while let Some(part) = parts.next() {
        let Some((k, v)) = table.get_key_value(part) else {
            break;
        };
        at = k.span().start;
        let mut value = v.get_ref();
        // An array of tables (`[[layer]]`) is entered by the index that follows.
        if let (DeValue::Array(items), Some(i)) =
            (value, parts.peek().and_then(|p| p.parse::<usize>().ok()))
        {
            parts.next();
            match items.get(i) {
                Some(item) => {
                    at = item.span().start;
                    value = item.get_ref();
                }
                None => break,
            }
        }
        match value {
            DeValue::Table(t) => table = t,
            _ => break,
        }
    }
    line_column(text, at)
}

/// The parser's message, shortened, with a hint for the commonest slip: a bare word
/// where TOML needs a quoted string (`fidelity = faithful`).
fn parse_message(text: &str, start: usize, message: &str) -> String {
    let rest = text.get(start..).unwrap_or("");
    let word: String = rest
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
        .collect();
    let bare = !word.is_empty()
        && word.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && !matches!(word.as_str(), "true" | "false" | "inf" | "nan")
        && text[..start].trim_end().ends_with('=');
    let message = arbvis_core::input::shorten(message.trim(), MESSAGE_CHARS);
    // serde's words for a table that picks one of several things given more than one:
    // [technique] (one technique) or a choice such as `colour_by = { property = ... }`.
    if message.contains("wanted exactly 1 element, more than 1 element") {
        let line_start = text[..start.min(text.len())]
            .rfind('\n')
            .map_or(0, |p| p + 1);
        let line = text[line_start..].trim_start();
        if line.starts_with("[technique") || line.starts_with("technique") {
            let tables: Vec<String> = crate::catalog::TECHNIQUES
                .iter()
                .map(|t| format!("[technique.{}]", t.name))
                .collect();
            return format!(
                "a scene draws one technique: [technique] holds one table (one of {}); draw each dataset in a scene of its own, or as [[layer]]s of one",
                tables.join(", ")
            );
        }
        return "a table that picks one of several choices has more than one key: give one (check its spelling)".into();
    }
    if bare {
        format!("{message} (a word must be quoted: \"{word}\")")
    } else {
        message
    }
}

/// The dotted key whose value holds byte `at` of scene `text`: the table header in force
/// and the key of the line (or of the nearest line above with one, for an array spread over
/// lines); a header's own name where `at` is on it. What a wrong-shaped value's error names.
fn key_at(text: &str, at: usize) -> Option<String> {
    let at = at.min(text.len());
    let line_start = text[..at].rfind('\n').map_or(0, |p| p + 1);
    let header = |l: &str| {
        let l = l.trim();
        l.starts_with('[')
            .then(|| l.trim_matches(|c| c == '[' || c == ']').trim().to_string())
    };
    let mut lines = text[..line_start].lines().rev();
    let this = text[line_start..].lines().next().unwrap_or("");
    if let Some(h) = header(this) {
        return Some(h);
    }
    let mut key = this
        .split_once('=')
        .filter(|(k, _)| line_start + k.len() < at)
        .map(|(k, _)| k.trim().trim_matches('"').to_string());
    let mut table = None;
    for l in lines.by_ref() {
        if let Some(h) = header(l) {
            table = Some(h);
            break;
        }
        if key.is_none() {
            key = l
                .split_once('=')
                .map(|(k, _)| k.trim().trim_matches('"').to_string());
        }
    }
    let table = table.map(|t| in_array_of_tables(&text[..line_start], t));
    match (table, key) {
        (Some(t), Some(k)) => Some(format!("{t}.{k}")),
        (None, Some(k)) => Some(k),
        (Some(t), None) => Some(t),
        (None, None) => None,
    }
}

/// Table `t` (`layer.surface`) with the index of the array of tables it lies in
/// (`layer.1.surface`): `[[layer]]` headers counted in `before`, the text above it.
fn in_array_of_tables(before: &str, t: String) -> String {
    let arrays = before.lines().filter_map(|l| {
        let l = l.trim();
        l.strip_prefix("[[")?.strip_suffix("]]").map(str::trim)
    });
    let Some(name) = arrays
        .clone()
        .rfind(|a| t == *a || t.starts_with(&format!("{a}.")))
    else {
        return t;
    };
    let index = arrays.filter(|a| *a == name).count().saturating_sub(1);
    match t.strip_prefix(name) {
        Some(rest) => format!("{name}.{index}{rest}"),
        None => t,
    }
}

/// Whether the scene's text writes the dotted `key` (`camera`, `technique.opacity3d.combine`).
fn is_written(table: &toml::Table, key: &str) -> bool {
    let mut parts = key.split('.');
    let Some(first) = parts.next() else {
        return false;
    };
    let mut value = table.get(first);
    for part in parts {
        value = value.and_then(|v| match (v, part.parse::<usize>()) {
            (toml::Value::Array(a), Ok(i)) => a.get(i),
            _ => v.as_table().and_then(|t| t.get(part)),
        });
    }
    value.is_some()
}

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1;
    (line, column)
}

/// Parse `WxH` (e.g. `256x256`).
pub fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{s:?}: expected WIDTHxHEIGHT, e.g. 256x256"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|n| (1..=16384).contains(n))
            .ok_or_else(|| format!("{s:?}: each side must be a whole number in 1..=16384"))
    };
    Ok([parse(w)?, parse(h)?])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_longer_than_their_field_are_errors() {
        let (_, base) = demos().find(|(n, _)| *n == "clip-sphere").unwrap();
        for (from, to, key) in [
            ("size = [256, 256]", "size = [256, 256, 5]", "size"),
            (
                "rotation = [0.326506, -0.092296, -0.701057, 0.627211]",
                "rotation = [0.326506, -0.092296, -0.701057, 0.627211, 1.0]",
                "camera.rotation",
            ),
            (
                "coefficients = [1.0, 1.0, 1.0, 0.8]",
                "coefficients = [1.0, 1.0, 1.0, 0.8, 2.0]",
                "technique.opacity3d.primary.coefficients",
            ),
        ] {
            assert!(base.contains(from), "{from} not in\n{base}");
            let text = base.replacen(from, to, 1);
            let e = Scene::parse(&text, "s.toml").unwrap_err().to_string();
            assert!(e.contains(key) && e.contains("values where"), "{e}");
            assert!(e.starts_with("s.toml:"), "{e}");
        }
        // Every demo and data scene, written back, has nothing longer than it reads.
        for (name, _) in demos() {
            Scene::parse(&Scene::demo(name).unwrap().to_toml(), name).unwrap();
        }
    }

    #[test]
    fn every_demo_parses() {
        for (name, _) in demos() {
            Scene::demo(name).unwrap();
        }
    }

    #[test]
    fn a_wrong_shaped_value_names_its_dotted_key() {
        let key = |text: &str| match Scene::parse(text, "x.toml") {
            Err(SceneError::Parse { key, .. }) => key,
            other => panic!("expected a parse error, got {other:?}"),
        };
        assert_eq!(
            key("[technique.quad]\nleft = 5\n").as_deref(),
            Some("technique.quad.left")
        );
        assert_eq!(
            key("size = \"big\"\n[technique.quad]\n").as_deref(),
            Some("size")
        );
        assert_eq!(
            key("[camera]\nrotation = [\n  0.1,\n  \"x\",\n  0.0, 1.0]\n[technique.quad]\n")
                .as_deref(),
            Some("camera.rotation")
        );
        assert_eq!(
            key("[technique.opacity3d.primary]\nvolume = { segy = 5 }\n").as_deref(),
            Some("technique.opacity3d.primary.volume")
        );
    }

    #[test]
    fn unknown_key_names_line_and_column() {
        let text = "size = [64, 64]\nbogus = 1\n[technique.quad]\n";
        match Scene::parse(text, "x.toml") {
            Err(SceneError::Parse {
                line,
                column,
                message,
                ..
            }) => {
                assert_eq!((line, column), (2, 1), "{message}");
                assert!(message.contains("bogus"), "{message}");
            }
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn bad_size_is_rejected() {
        let text = "background = [0.0, 0.0, 0.0, 1.0]\nsize = [0, 64]\n[technique.quad]\n";
        match Scene::parse(text, "x") {
            Err(
                e @ SceneError::Invalid {
                    line: 2, column: 1, ..
                },
            ) => {
                assert!(e.to_string().starts_with("x:2:1: size: 0x64"), "{e}")
            }
            other => panic!("expected an invalid size at 2:1, got {other:?}"),
        }
    }

    #[test]
    fn errors_after_parsing_point_at_the_key() {
        let text = "size = [64, 64]\n[technique.opacity3d]\ncombine = \"sum\"\n  slices = 0\n[technique.opacity3d.primary]\nvolume = { synthetic = { size = [8, 8, 8] } }\n";
        let e = Scene::parse(text, "s.toml").unwrap_err().to_string();
        assert!(
            e.starts_with("s.toml:4:3: technique.opacity3d.slices: slices = 0"),
            "{e}"
        );
    }

    #[test]
    fn a_bare_word_gets_a_hint_and_long_keys_are_shortened() {
        let e = Scene::parse("fidelity = faithful\n[technique.quad]\n", "a.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("a.toml:1:12:") && e.contains("\"faithful\""),
            "{e}"
        );
        let long = format!("{} = 1\n[technique.quad]\n", "k".repeat(100_000));
        let e = Scene::parse(&long, "b.toml").unwrap_err().to_string();
        assert!(
            e.len() < 2000 && e.contains("more characters"),
            "{}",
            e.len()
        );
    }

    #[test]
    fn round_trips_through_toml() {
        let scene = Scene::demo("quad").unwrap();
        assert_eq!(Scene::parse(&scene.to_toml(), "again").unwrap(), scene);
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("320x240"), Ok([320, 240]));
        assert!(parse_size("320").is_err());
        assert!(parse_size("0x5").is_err());
        assert!(parse_size("axb").is_err());
    }
}
