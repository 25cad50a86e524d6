//! `arbvis.Scene`: a scene read from a file, TOML text or a dict, its values read and
//! written as Python values by dotted key. Every change goes through the same parser and
//! validation as a scene file, so a bad value raises the `SceneError` a file would, with
//! its key.

use std::path::PathBuf;

use std::sync::Arc;

use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use arbvis_techniques::scene::Scene;

use crate::cloud::PyCloud;
use crate::errors::{self, At};
use crate::mesh::PyMesh;
use crate::volume::PyVolume;

/// `json.loads(text)`.
pub fn json_loads<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// A Python value as JSON (`json.dumps`), for the scene's parser.
fn json_of(value: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    let py = value.py();
    // NaN and infinities are no TOML a scene file could hold: json's ValueError says so.
    let options = pyo3::types::PyDict::new(py);
    options.set_item("allow_nan", false)?;
    // numpy's numbers and arrays (np.float32(2), np.array([...]), np.int64 sizes) as the
    // Python numbers and lists they hold.
    options.set_item(
        "default",
        py.import("arbvis._memory")?.getattr("json_default")?,
    )?;
    let text: String = py
        .import("json")?
        .call_method("dumps", (value,), Some(&options))?
        .extract()?;
    serde_json::from_str(&text)
        .map_err(|e| errors::scene_error(format!("not a value a scene holds: {e}"), At::key(None)))
}

/// Data handed over in memory that a scene holds.
pub type Kept = Arc<dyn std::any::Any + Send + Sync>;

/// `value` with every `arbvis.Volume`, `arbvis.Cloud` and `arbvis.Mesh` in it (at any depth of dicts, lists and tuples)
/// replaced by the table that names it (`{"memory": NAME}`); each such volume is kept in
/// `kept`, so that the scene holds it as long as the scene lives.
fn naming_volumes<'py>(
    value: &Bound<'py, PyAny>,
    kept: &mut Vec<Kept>,
) -> PyResult<Bound<'py, PyAny>> {
    let py = value.py();
    let named = |name: &str| -> PyResult<Bound<'py, PyAny>> {
        let table = PyDict::new(py);
        table.set_item("memory", name)?;
        Ok(table.into_any())
    };
    if let Ok(v) = value.cast::<PyVolume>() {
        let v = v.get();
        kept.push(v.volume.clone());
        return named(&v.name);
    }
    if let Ok(c) = value.cast::<PyCloud>() {
        let c = c.get();
        kept.push(c.cloud.clone());
        return named(&c.name);
    }
    if let Ok(m) = value.cast::<PyMesh>() {
        let m = m.get();
        kept.push(m.mesh.clone());
        return named(&m.name);
    }
    if let Ok(s) = value.cast::<crate::surface::PySurface>() {
        let s = s.get();
        kept.push(s.surface.clone());
        return named(&s.name);
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let out = PyDict::new(py);
        for (k, v) in d.iter() {
            out.set_item(k, naming_volumes(&v, kept)?)?;
        }
        return Ok(out.into_any());
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'py, PyAny>> = value
            .try_iter()?
            .map(|v| naming_volumes(&v?, kept))
            .collect::<PyResult<_>>()?;
        return Ok(PyList::new(py, items)?.into_any());
    }
    Ok(value.clone())
}

/// The scene as a JSON tree.
fn tree_of(scene: &Scene) -> serde_json::Value {
    serde_json::to_value(scene).expect("a scene serializes")
}

/// A scene from a JSON tree, read as TOML text is (the same errors); `key`, the one
/// changed, names a value of the wrong shape.
fn scene_of(tree: &serde_json::Value, base: PathBuf, key: Option<&str>) -> PyResult<Scene> {
    let bad = |message: String| {
        let message = match key {
            Some(k) => format!("{k}: {message}"),
            None => message,
        };
        errors::scene_error(message, At::key(key))
    };
    let value = toml_of(tree).map_err(|e| bad(e.to_string()))?;
    let text = toml::to_string(&value).map_err(|e| bad(e.to_string()))?;
    match Scene::parse(&text, "scene") {
        Ok(mut scene) => {
            scene.base = base;
            Ok(scene)
        }
        // A value of the wrong shape: the parser's message, at the key changed.
        Err(arbvis_techniques::scene::SceneError::Parse {
            message, key: at, ..
        }) => match (key, at) {
            // A whole scene given (from_dict): the key the parser found.
            (None, Some(at)) => Err(errors::scene_error(
                format!("{at}: {message}"),
                At::key(Some(&at)),
            )),
            _ => Err(bad(message)),
        },
        Err(arbvis_techniques::scene::SceneError::Invalid {
            key: at, message, ..
        }) => Err(errors::scene_error(
            format!("{at}: {message}"),
            At::key(Some(&at)),
        )),
        Err(e) => Err(errors::from_scene(e)),
    }
}

/// The TOML value of a JSON tree: a null in an array is `nan` (a numpy array's NaN crosses
/// JSON as null: a value of none where a scene takes one, refused by key elsewhere), a
/// null in a table no key.
fn toml_of(json: &serde_json::Value) -> Result<toml::Value, toml::ser::Error> {
    use serde_json::Value as J;
    Ok(match json {
        // A null stands only in an array here (a table's null keys are left out below).
        J::Null => toml::Value::Float(f64::NAN),
        J::Array(items) => toml::Value::Array(
            items
                .iter()
                .map(toml_of)
                .collect::<Result<_, toml::ser::Error>>()?,
        ),
        J::Object(map) => toml::Value::Table(
            map.iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| Ok((k.clone(), toml_of(v)?)))
                .collect::<Result<_, toml::ser::Error>>()?,
        ),
        other => toml::Value::try_from(other)?,
    })
}

/// `m` as a row-major numpy array.
fn matrix(py: Python<'_>, m: glam::DMat4) -> Bound<'_, numpy::PyArray2<f64>> {
    let rows: Vec<Vec<f64>> = (0..4).map(|r| m.row(r).to_array().to_vec()).collect();
    numpy::PyArray2::from_vec2(py, &rows).expect("four rows of four")
}

/// The value at dotted `key` in `tree` (a number indexes an array: `layer.1.surface`).
fn at<'t>(tree: &'t serde_json::Value, key: &str) -> Option<&'t serde_json::Value> {
    key.split('.')
        .try_fold(tree, |node, part| match (node, part.parse::<usize>()) {
            (serde_json::Value::Array(items), Ok(i)) => items.get(i),
            _ => node.get(part),
        })
}

/// Put `value` at dotted `key` in `tree` (tables made on the way); `None` removes it.
fn put(tree: &mut serde_json::Value, key: &str, value: Option<serde_json::Value>) -> PyResult<()> {
    let parts: Vec<&str> = key.split('.').collect();
    let (last, path) = parts.split_last().expect("split gives one part at least");
    let mut node = tree;
    for part in path {
        node = match (node, part.parse::<usize>()) {
            (serde_json::Value::Array(items), Ok(i)) => {
                let count = items.len();
                items.get_mut(i).ok_or_else(|| {
                    PyKeyError::new_err(format!("{key}: {i} is past the {count} there are"))
                })?
            }
            (node, _) => node
                .as_object_mut()
                .ok_or_else(|| PyKeyError::new_err(format!("{key}: {part} is inside a value")))?
                .entry(part.to_string())
                .or_insert_with(|| serde_json::Value::Object(Default::default())),
        };
    }
    let map = node
        .as_object_mut()
        .ok_or_else(|| PyKeyError::new_err(format!("{key}: not inside a table")))?;
    match value {
        Some(v) => {
            map.insert(last.to_string(), v);
        }
        None => {
            map.remove(*last);
        }
    }
    Ok(())
}

/// A scene: what to draw (the technique and its parameters) and how (size, fidelity,
/// programs, camera). Read one with `Scene.load(path)`, `Scene.from_toml(text)`,
/// `Scene.from_dict(d)` or `Scene.demo(name)`; read and change any value by its dotted
/// key (`scene["camera.zoom"] = 1.5`), or through the properties below. Each change is
/// validated as a scene file is (a bad value raises `SceneError` naming the key).
#[pyclass(name = "Scene", module = "arbvis")]
#[derive(Clone)]
pub struct PyScene {
    /// The scene.
    pub scene: Scene,
    /// The data in memory it was given (`arbvis.Volume`, `Cloud`, `Mesh`), held while it
    /// lives.
    pub kept: Vec<Kept>,
}

/// The scene's layers as `[[layer]]` tables (a one-technique scene's one table).
fn layer_tables(scene: &Scene) -> Vec<serde_json::Value> {
    let tree = tree_of(scene);
    match (tree.get("layer"), tree.get("technique")) {
        (Some(serde_json::Value::Array(layers)), _) => layers.clone(),
        (_, Some(technique)) => vec![technique.clone()],
        _ => Vec::new(),
    }
}

impl PyScene {
    /// The scene with `layers` as its `[[layer]]` tables, validated.
    fn set_layer_tables(&mut self, _: Python<'_>, layers: Vec<serde_json::Value>) -> PyResult<()> {
        let mut tree = tree_of(&self.scene);
        let map = tree.as_object_mut().expect("a scene is a table");
        map.remove("technique");
        map.insert("layer".into(), serde_json::Value::Array(layers));
        self.scene = scene_of(&tree, self.scene.base.clone(), None)?;
        Ok(())
    }

    /// Turn the scene's rotation by `degrees` about `axis` of the screen (eye space).
    fn turn(&mut self, axis: glam::DVec3, degrees: f64) -> PyResult<()> {
        if !degrees.is_finite() {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{degrees} degrees: a finite angle"
            )));
        }
        let turn = glam::DQuat::from_axis_angle(axis, degrees.to_radians());
        let q = (turn * self.scene.camera.quat()).normalize();
        self.scene.camera.rotation = q.to_array();
        Ok(())
    }
}

#[pymethods]
impl PyScene {
    /// Read a scene file; its relative data paths are read from its folder, and every
    /// data file it names must exist.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyScene> {
        let scene = py
            .detach(|| Scene::load_checked(&path))
            .map_err(errors::from_scene)?;
        Ok(PyScene {
            scene,
            kept: Vec::new(),
        })
    }

    /// A scene from TOML text; relative data paths are read from `base` (the current
    /// folder by default).
    #[staticmethod]
    #[pyo3(signature = (text, base = None))]
    fn from_toml(text: &str, base: Option<PathBuf>) -> PyResult<PyScene> {
        let mut scene = Scene::parse(text, "scene").map_err(errors::from_scene)?;
        scene.base = base.unwrap_or_default();
        Ok(PyScene {
            scene,
            kept: Vec::new(),
        })
    }

    /// A scene from a dict shaped as the TOML (`{"size": [256, 256], "technique":
    /// {"quad": {...}}}`); relative data paths are read from `base`.
    #[staticmethod]
    #[pyo3(signature = (d, base = None))]
    fn from_dict(d: &Bound<'_, PyAny>, base: Option<PathBuf>) -> PyResult<PyScene> {
        if !d.is_instance_of::<pyo3::types::PyDict>() {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "expected a dict shaped as a scene's TOML, got {}",
                d.get_type().name()?
            )));
        }
        let mut kept = Vec::new();
        let tree = json_of(&naming_volumes(d, &mut kept)?)?;
        let scene = scene_of(&tree, base.unwrap_or_default(), None)?;
        Ok(PyScene { scene, kept })
    }

    /// A built-in demo scene (`arbvis render --demo NAME`).
    #[staticmethod]
    fn demo(name: &str) -> PyResult<PyScene> {
        let scene = Scene::demo(name).map_err(errors::from_scene)?;
        Ok(PyScene {
            scene,
            kept: Vec::new(),
        })
    }

    /// The scene as TOML text (what a scene file holds).
    fn to_toml(&self) -> String {
        self.scene.to_toml()
    }

    /// The scene as a dict shaped as the TOML.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_loads(py, &tree_of(&self.scene).to_string())
    }

    /// The value at dotted `key` (`"technique.opacity3d.primary.coefficients"`).
    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let tree = tree_of(&self.scene);
        let value = at(&tree, key).ok_or_else(|| PyKeyError::new_err(key.to_string()))?;
        json_loads(py, &value.to_string())
    }

    /// Set the value at dotted `key`, validated as a scene file is; `None` removes it
    /// (its default applies). An `arbvis.Volume`, `Cloud` or `Mesh` stands wherever a volume,
    /// cloud or mesh file is named.
    fn __setitem__(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut tree = tree_of(&self.scene);
        let mut kept = Vec::new();
        let value = if value.is_none() {
            None
        } else {
            Some(json_of(&naming_volumes(value, &mut kept)?)?)
        };
        put(&mut tree, key, value)?;
        self.scene = scene_of(&tree, self.scene.base.clone(), Some(key))?;
        self.kept.extend(kept);
        Ok(())
    }

    /// The layers, in drawing order, each a dict shaped as its `[[layer]]` table (a
    /// copy: change them by dotted key, `scene["layer.1.surface.opacity"] = 0.5`). A
    /// one-technique scene is one layer.
    #[getter]
    fn layers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_loads(
            py,
            &serde_json::Value::Array(layer_tables(&self.scene)).to_string(),
        )
    }

    /// Add a layer drawing `technique` with `params` (a dict shaped as its table, where an
    /// `arbvis.Volume`, `Cloud` or `Mesh` stands for a data file), at the end or at
    /// `index`; `name`, `visible`, `offset` and `scale` as in a `[[layer]]` table.
    /// Validated as a scene file is: a bad value raises `SceneError` naming
    /// `layer.INDEX....`.
    #[pyo3(signature = (technique, params = None, *, name = None, visible = true, offset = None, scale = None, index = None))]
    #[allow(clippy::too_many_arguments)]
    fn add_layer(
        &mut self,
        py: Python<'_>,
        technique: &str,
        params: Option<&Bound<'_, PyAny>>,
        name: Option<String>,
        visible: bool,
        offset: Option<[f64; 3]>,
        scale: Option<f64>,
        index: Option<usize>,
    ) -> PyResult<()> {
        let mut kept = Vec::new();
        let params = match params {
            Some(p) => json_of(&naming_volumes(p, &mut kept)?)?,
            None => serde_json::json!({}),
        };
        let mut table = serde_json::Map::new();
        if let Some(name) = name {
            table.insert("name".into(), name.into());
        }
        if !visible {
            table.insert("visible".into(), false.into());
        }
        if let Some(offset) = offset {
            table.insert("offset".into(), serde_json::json!(offset));
        }
        if let Some(scale) = scale {
            table.insert("scale".into(), serde_json::json!(scale));
        }
        table.insert(technique.to_string(), params);
        let mut layers = layer_tables(&self.scene);
        let index = index.unwrap_or(layers.len()).min(layers.len());
        layers.insert(index, serde_json::Value::Object(table));
        self.set_layer_tables(py, layers)?;
        self.kept.extend(kept);
        Ok(())
    }

    /// Remove layer `index` (a scene keeps one at least).
    fn remove_layer(&mut self, py: Python<'_>, index: usize) -> PyResult<()> {
        let mut layers = layer_tables(&self.scene);
        if index >= layers.len() || layers.len() == 1 {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "layer {index} of {}: a scene keeps one layer at least",
                layers.len()
            )));
        }
        layers.remove(index);
        self.set_layer_tables(py, layers)
    }

    /// Move layer `from_index` to `to_index` (the drawing order of translucent layers).
    fn move_layer(&mut self, from_index: usize, to_index: usize) -> PyResult<()> {
        self.scene
            .move_layer(from_index, to_index)
            .map_err(|e| pyo3::exceptions::PyIndexError::new_err(e.to_string()))
    }

    /// Whether the scene holds a value at dotted `key`.
    fn __contains__(&self, key: &str) -> bool {
        at(&tree_of(&self.scene), key).is_some()
    }

    /// The technique's name (`quad`, `opacity3d`, `cellproj`, `splats`).
    #[getter]
    fn technique(&self) -> &'static str {
        self.scene.technique.name()
    }

    /// The technique's parameters as a dict (a copy: change them with
    /// `scene["technique.NAME.KEY"] = value` or `scene.params = d`).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let key = format!("technique.{}", self.scene.technique.name());
        self.__getitem__(py, &key)
    }

    #[setter]
    fn set_params(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let key = format!("technique.{}", self.scene.technique.name());
        self.__setitem__(&key, value)
    }

    /// Image size `(width, height)` in pixels.
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.scene.size[0], self.scene.size[1])
    }

    #[setter]
    fn set_size(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.__setitem__("size", value)
    }

    /// `"faithful"` (the original programs, 8-bit targets) or `"precise"`.
    #[getter]
    fn fidelity(&self) -> &'static str {
        self.scene.fidelity.name()
    }

    #[setter]
    fn set_fidelity(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.__setitem__("fidelity", value)
    }

    /// `"arb"`, `"glsl"` or `"auto"`.
    #[getter]
    fn programs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.__getitem__(py, "programs")
    }

    #[setter]
    fn set_programs(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.__setitem__("programs", value)
    }

    /// The camera's rotation as a quaternion `(x, y, z, w)`.
    #[getter]
    fn rotation(&self) -> (f64, f64, f64, f64) {
        let [x, y, z, w] = self.scene.camera.rotation;
        (x, y, z, w)
    }

    #[setter]
    fn set_rotation(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.__setitem__("camera.rotation", value)
    }

    /// The camera's magnification (1: the [-1, 1] square fills the shorter side).
    #[getter]
    fn zoom(&self) -> f64 {
        self.scene.camera.zoom
    }

    #[setter]
    fn set_zoom(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.__setitem__("camera.zoom", value)
    }

    /// `"orthographic"` or `"perspective"`.
    #[getter]
    fn projection<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.__getitem__(py, "camera.projection")
    }

    #[setter]
    fn set_projection(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.__setitem__("camera.projection", value)
    }

    /// The folder relative data paths are read from.
    #[getter]
    fn base(&self) -> PathBuf {
        self.scene.base.clone()
    }

    #[setter]
    fn set_base(&mut self, base: PathBuf) {
        self.scene.base = base;
    }

    fn __repr__(&self) -> String {
        let [w, h] = self.scene.size;
        format!(
            "<arbvis.Scene {} {w}x{h} {}>",
            self.scene.technique.name(),
            self.scene.fidelity.name(),
        )
    }

    fn __eq__(&self, other: &PyScene) -> bool {
        self.scene == other.scene
    }

    /// Turn the camera `degrees` about the screen's vertical axis (VTK's azimuth: positive
    /// moves the eye to the right around the data).
    fn azimuth(&mut self, degrees: f64) -> PyResult<()> {
        self.turn(glam::DVec3::Y, -degrees)
    }

    /// Turn the camera `degrees` about the screen's horizontal axis (VTK's elevation:
    /// positive moves the eye up over the data).
    fn elevation(&mut self, degrees: f64) -> PyResult<()> {
        self.turn(glam::DVec3::X, degrees)
    }

    /// The camera the scene's data gets when its file names none (a survey's
    /// three-quarter view, ...), else the default one; the projection kept.
    fn reset_camera(&mut self) {
        let projection = self.scene.camera.projection;
        self.scene.camera = self.scene.technique.default_camera().unwrap_or_default();
        self.scene.camera.projection = projection;
    }

    /// The camera's view matrix (4 x 4, row-major numpy): the scene's frame (the data in
    /// [-1, 1] along its longest side) to eye space.
    fn view_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        matrix(py, self.scene.camera.view())
    }

    /// The projection matrix (4 x 4, row-major) for the scene's size: eye space to clip
    /// space, as GL's.
    fn projection_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        let [w, h] = self.scene.size;
        matrix(py, self.scene.camera.projection_matrix(w as f64 / h as f64))
    }

    /// Where points of the scene's frame (an (N, 3) array) fall in the picture: (N, 2)
    /// pixel positions, x right and y down from the top-left corner, as `render()`'s
    /// array indexes them (`image[int(y), int(x)]`).
    fn to_pixels<'py>(
        &self,
        py: Python<'py>,
        points: numpy::PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        use numpy::PyUntypedArrayMethods;
        if points.shape().get(1) != Some(&3) {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "points are an (N, 3) array, got {:?}",
                points.shape()
            )));
        }
        let [w, h] = self.scene.size.map(f64::from);
        let m = self.scene.camera.view_projection(w / h);
        let xyz = points.as_slice().map_err(errors::input_error)?;
        let out: Vec<Vec<f64>> = xyz
            .chunks_exact(3)
            .map(|p| {
                let c = m * glam::DVec4::new(p[0], p[1], p[2], 1.0);
                let (x, y) = (c.x / c.w, c.y / c.w);
                vec![(x + 1.0) / 2.0 * w, (1.0 - y) / 2.0 * h]
            })
            .collect();
        numpy::PyArray2::from_vec2(py, &out).map_err(errors::input_error)
    }

    /// The scene's picture as PNG bytes, what a notebook or a report shows for a scene:
    /// drawn offscreen (EGL) by a renderer made for this call on a thread of its own.
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyBytes>> {
        let scene = self.scene.clone();
        let drawn = py.detach(move || {
            std::thread::spawn(move || {
                use arbvis_techniques::session::Offscreen;
                let mut session = Offscreen::new(&scene, arbvis_gl::Backend::Egl)?;
                let frame = session.render(&scene)?;
                Ok::<_, arbvis_techniques::error::RenderError>(scene.picture(&frame))
            })
            .join()
        });
        let image = drawn
            .map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the render thread panicked"))?
            .map_err(errors::from_render)?;
        let png =
            arbvis_core::png_io::encode_png("scene", &image, &[]).map_err(errors::input_error)?;
        Ok(pyo3::types::PyBytes::new(py, &png))
    }

    fn __copy__(&self) -> PyScene {
        self.clone()
    }
}
