//! arbvis's errors as Python exceptions: `ArbvisError` and below it `SceneError` (a scene
//! that does not parse or validate: `path`, `line`, `column`, `key`), `InputError` (a data
//! file that cannot be read or used: its message names the file and the position),
//! `GLError` (the GL refused) and `RenderError` (anything else while drawing).

use arbvis_techniques::techniques::opacity3d::error::Opacity3dError;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

use arbvis_core::secrets::redact;
use arbvis_gl::GlError;
use arbvis_techniques::error::RenderError as RustRenderError;
use arbvis_techniques::scene::SceneError as RustSceneError;

pyo3::create_exception!(
    arbvis,
    ArbvisError,
    PyException,
    "Every error arbvis raises."
);
pyo3::create_exception!(
    arbvis,
    SceneError,
    ArbvisError,
    "A scene that does not parse or validate; `key` is the dotted key at fault (or None), \
     `path`, `line` and `column` where the scene's text has it."
);
pyo3::create_exception!(
    arbvis,
    InputError,
    ArbvisError,
    "A data file that cannot be read or used; the message names the file and the position."
);
pyo3::create_exception!(
    arbvis,
    GLError,
    ArbvisError,
    "The GL refused: no context, a program that does not compile, out of memory."
);
pyo3::create_exception!(
    arbvis,
    RenderError,
    ArbvisError,
    "Something else went wrong preparing or drawing a picture."
);

pyo3::create_exception!(
    arbvis,
    Cancelled,
    ArbvisError,
    "Work stopped on request (a progress callback returned False); a conversion resumes \
     when run again."
);

/// Add the exception types to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ArbvisError", py.get_type::<ArbvisError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("GLError", py.get_type::<GLError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add("Cancelled", py.get_type::<Cancelled>())?;
    Ok(())
}

/// Where a scene error is: file (or origin), line, column, key.
pub struct At<'a> {
    pub path: Option<&'a str>,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub key: Option<&'a str>,
}

impl<'a> At<'a> {
    /// At `line` and `column` of the scene text `path` (and at `key`, where known).
    pub fn line(path: &'a str, line: usize, column: usize, key: Option<&'a str>) -> At<'a> {
        At {
            path: Some(path),
            line: Some(line),
            column: Some(column),
            key,
        }
    }

    /// At `key` only (or nowhere): a value set from Python, which has no line.
    pub fn key(key: Option<&'a str>) -> At<'a> {
        At {
            path: None,
            line: None,
            column: None,
            key,
        }
    }
}

/// A `SceneError` saying `message`, with its position as attributes.
pub fn scene_error(message: String, at: At<'_>) -> PyErr {
    let err = SceneError::new_err(redact(&message));
    Python::attach(|py| {
        let value = err.value(py);
        let _ = value.setattr("path", at.path);
        let _ = value.setattr("line", at.line);
        let _ = value.setattr("column", at.column);
        let _ = value.setattr("key", at.key);
    });
    err
}

/// An `InputError` saying `e`, any URL's secrets hidden.
pub fn input_error(e: impl std::fmt::Display) -> PyErr {
    InputError::new_err(redact(&e.to_string()))
}

/// A scene's error from the Rust side.
pub fn from_scene(e: RustSceneError) -> PyErr {
    let message = redact(&e.to_string());
    match &e {
        RustSceneError::Io { path, .. } => InputError::new_err(format!("{message} ({path})")),
        RustSceneError::Parse {
            path,
            line,
            column,
            key,
            ..
        } => scene_error(
            message.clone(),
            At::line(path, *line, *column, key.as_deref()),
        ),
        RustSceneError::Invalid {
            path,
            line,
            column,
            key,
            ..
        } => scene_error(message.clone(), At::line(path, *line, *column, Some(key))),
        RustSceneError::UnknownDemo(_) => scene_error(message, At::key(None)),
    }
}

/// A GL error.
pub fn from_gl(e: GlError) -> PyErr {
    GLError::new_err(redact(&e.to_string()))
}

/// A render error: the data layers' as `InputError`, the GL's as `GLError`, parameters as
/// `SceneError` (the key relative to the technique's table), the rest as `RenderError`.
pub fn from_render(e: RustRenderError) -> PyErr {
    let message = redact(&e.to_string());
    match e {
        RustRenderError::Gl(e) => from_gl(e),
        RustRenderError::Volume(_)
        | RustRenderError::Mesh(_)
        | RustRenderError::Points(_)
        | RustRenderError::Store(_)
        | RustRenderError::Surface(_)
        | RustRenderError::Table(_)
        | RustRenderError::Brick(_) => InputError::new_err(message),
        RustRenderError::Technique { source, .. }
            if source
                .downcast_ref::<Opacity3dError>()
                .is_some_and(Opacity3dError::is_input) =>
        {
            InputError::new_err(message)
        }
        RustRenderError::Parameters(field) => scene_error(message, At::key(Some(&field.key))),
        _ => RenderError::new_err(message),
    }
}
