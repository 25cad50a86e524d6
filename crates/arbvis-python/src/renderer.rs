//! `arbvis.Renderer`: a scene kept ready to draw ([`arbvis_techniques::session::Offscreen`]:
//! GL context, prepared data, programs, target) on a render thread of its own. A GL
//! context belongs to one thread, and the Python thread that calls may change; so each
//! renderer owns the thread its context lives on, and a call hands it the scene and waits
//! for the picture with the GIL released. Renderers in two Python threads draw at once.

use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use arbvis_core::image::Image;
use arbvis_core::vocab::TargetFormat;
use arbvis_data::volume::Limits;
use arbvis_gl::Backend;
use arbvis_techniques::catalog;
use arbvis_techniques::error::RenderResult;
use arbvis_techniques::scene::Scene;
use arbvis_techniques::session::{FrameBudget, FrameStats, Offscreen};
use arbvis_techniques::techniques::ReferenceView;

use crate::errors;
use crate::scene::PyScene;

/// The backend named `name` (`egl`, `osmesa`).
pub fn backend_named(name: &str) -> PyResult<Backend> {
    match name.to_ascii_lowercase().as_str() {
        "egl" => Ok(Backend::Egl),
        "osmesa" => Ok(Backend::Osmesa),
        _ => Err(PyValueError::new_err(format!(
            "no backend {name:?}: \"egl\" or \"osmesa\""
        ))),
    }
}

/// What the render thread is asked.
enum Job {
    /// Draw the scene (whole, or as an interactive frame within the budget); the picture
    /// (composited as a PNG shows it) back.
    Render(Box<Scene>, bool, Sender<RenderResult<Image>>),
    /// Keep interactive frames to this many milliseconds.
    Budget(f64),
    /// What the last frame drew.
    Stats(Sender<FrameStats>),
}

/// What the render thread says once its context and renderer are made.
struct Ready {
    program_kind: &'static str,
    max_3d_texture_size: i32,
    backend: &'static str,
    renderer: String,
}

/// The render thread: make the session, say so, then draw what is asked until the
/// renderer is dropped.
fn serve(scene: Scene, backend: Backend, ready: Sender<RenderResult<Ready>>, jobs: Receiver<Job>) {
    let mut session = match Offscreen::new(&scene, backend) {
        Ok(s) => s,
        Err(e) => {
            let _ = ready.send(Err(e));
            return;
        }
    };
    let _ = ready.send(Ok(Ready {
        program_kind: session.program_kind().name(),
        max_3d_texture_size: session.caps().max_3d_texture_size,
        backend: session.backend().name(),
        renderer: session.caps().renderer.clone(),
    }));
    while let Ok(job) = jobs.recv() {
        match job {
            Job::Render(scene, interactive, reply) => {
                let frame = match interactive {
                    true => session.render_interactive(&scene),
                    false => session.render(&scene),
                };
                let _ = reply.send(frame.map(|frame| scene.picture(&frame)));
            }
            Job::Stats(reply) => {
                let _ = reply.send(session.stats());
            }
            Job::Budget(ms) => {
                let interactive = std::time::Duration::from_secs_f64(ms / 1e3);
                session.set_budget(FrameBudget {
                    interactive,
                    ..session.budget()
                });
            }
        }
    }
}

/// A renderer of one scene: it keeps its GL context, the prepared data and the programs
/// between frames, so that a render after a change of camera, size or a technique
/// parameter costs a frame, not a process. `render()` draws the scene as it is then.
///
/// Threads: the renderer draws on a thread of its own (a GL context belongs to one
/// thread), and every call waits for it with the GIL released; a renderer may be called
/// from any Python thread, calls from several threads are drawn one after another, a
/// scene being edited in another thread is waited for, `close()` waits for the frames
/// asked before it, and renderers in two Python threads draw at once.
#[pyclass(name = "Renderer", module = "arbvis")]
pub struct PyRenderer {
    scene: Mutex<Py<PyScene>>,
    jobs: Mutex<Option<Sender<Job>>>,
    thread: Mutex<Option<JoinHandle<()>>>,
    program_kind: &'static str,
    max_3d_texture_size: i32,
    backend: &'static str,
    renderer: String,
    budget_ms: Mutex<f64>,
}

/// `mutex` locked (held only for a field's read or swap, never across a wait; a panic
/// that poisoned it left the value whole).
fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

/// Longest wait for a scene that another thread is changing.
const SCENE_WAIT: Duration = Duration::from_secs(30);

/// The scene as it is now: a copy taken between edits (another Python thread that is
/// changing it holds it only for the edit; this waits, with the GIL released, instead of
/// failing on the borrow).
fn scene_now(py: Python<'_>, scene: &Py<PyScene>) -> PyResult<Scene> {
    let start = Instant::now();
    loop {
        if let Ok(s) = scene.try_borrow(py) {
            return Ok(s.scene.clone());
        }
        if start.elapsed() > SCENE_WAIT {
            return Err(PyRuntimeError::new_err(
                "the scene has been changing in another thread for 30 s; it could not be read",
            ));
        }
        py.detach(|| std::thread::sleep(Duration::from_micros(200)));
    }
}

impl PyRenderer {
    /// The render thread's inbox, unless the renderer is closed.
    fn jobs(&self) -> PyResult<Sender<Job>> {
        lock(&self.jobs)
            .clone()
            .ok_or_else(|| PyRuntimeError::new_err("the renderer is closed"))
    }
}

#[pymethods]
impl PyRenderer {
    /// Load and prepare `scene`'s data and make its renderer on `backend` (`"egl"`, the
    /// default, or `"osmesa"`).
    #[new]
    #[pyo3(signature = (scene, backend = "egl"))]
    fn new(py: Python<'_>, scene: Py<PyScene>, backend: &str) -> PyResult<PyRenderer> {
        let backend = backend_named(backend)?;
        let first = scene_now(py, &scene)?;
        let (jobs, inbox) = channel();
        let (ready_tx, ready) = channel();
        let thread = std::thread::Builder::new()
            .name("arbvis render".into())
            .spawn(move || serve(first, backend, ready_tx, inbox))
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start a thread: {e}")))?;
        let made = py
            .detach(move || ready.recv())
            .map_err(|_| PyRuntimeError::new_err("the render thread stopped"))?
            .map_err(errors::from_render)?;
        Ok(PyRenderer {
            scene: Mutex::new(scene),
            jobs: Mutex::new(Some(jobs)),
            thread: Mutex::new(Some(thread)),
            program_kind: made.program_kind,
            max_3d_texture_size: made.max_3d_texture_size,
            backend: made.backend,
            renderer: made.renderer,
            budget_ms: Mutex::new(FrameBudget::default().interactive.as_secs_f64() * 1e3),
        })
    }

    /// Draw the scene (or `scene`, which becomes the renderer's) as it is now: an
    /// `(height, width, 4)` numpy array, top row first, as a PNG of it would show it;
    /// `uint8` for an 8-bit target (faithful), `float32` for a float one (precise), handed
    /// to numpy without a copy. `interactive=True` draws a frame as while the user drags:
    /// within `budget_ms`, at a scale the last frames' times chose (down to a tenth of each
    /// side: a smaller array), without waiting for streamed data.
    #[pyo3(signature = (scene = None, interactive = false))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        scene: Option<Py<PyScene>>,
        interactive: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Some(s) = scene {
            *lock(&self.scene) = s;
        }
        let current = lock(&self.scene).clone_ref(py);
        let scene = scene_now(py, &current)?;
        let (reply, picture) = channel();
        // The inbox's copy goes before the wait, so that close() ends the thread once the
        // frames asked are drawn.
        self.jobs()?
            .send(Job::Render(Box::new(scene), interactive, reply))
            .map_err(|_| PyRuntimeError::new_err("the render thread stopped"))?;
        let image = py
            .detach(move || picture.recv())
            .map_err(|_| PyRuntimeError::new_err("the render thread stopped"))?
            .map_err(errors::from_render)?;
        Ok(to_array(py, image))
    }

    /// The f64 CPU reference of the scene's picture as it is now (float32, as `render()`
    /// shows a picture), computed on the CPU with the GIL released: the yardstick the
    /// precise modes are measured against. None where the technique has none (splats,
    /// isosurfaces alone, a survey store, a clipped 3D opacity scene, a layered scene:
    /// the exact composite of several layers is not built yet).
    fn reference<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        // A closed renderer draws nothing more, its reference neither.
        self.jobs()?;
        let current = lock(&self.scene).clone_ref(py);
        let scene = scene_now(py, &current)?;
        if scene.is_layered() {
            return Ok(None);
        }
        let limits = Limits::for_max_side(self.max_3d_texture_size);
        let image = py
            .detach(|| {
                let background = scene.clear_colour().map(f64::from);
                let view = ReferenceView {
                    camera: scene.camera,
                    size: scene.size,
                    background,
                    base: &scene.base,
                };
                catalog::reference(&scene.technique, &scene.settings(), &limits, &view)
                    .map(|image| image.map(|i| scene.picture(&i)))
            })
            .map_err(errors::from_render)?;
        Ok(image.map(|i| to_array(py, i)))
    }

    /// What the last `render()` drew, as `arbvis render --stats` says it: a dict of
    /// `frame_ms` (the scene's changes applied, the frame drawn and read back), `status`
    /// (the renderer's line: a store's resident bricks and levels, a cloud's points; or
    /// None) and `facts` (labelled lines, e.g. a clip's cost). Before a frame, `frame_ms`
    /// is 0.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let (reply, answer) = channel();
        self.jobs()?
            .send(Job::Stats(reply))
            .map_err(|_| PyRuntimeError::new_err("the render thread stopped"))?;
        let stats = py
            .detach(move || answer.recv())
            .map_err(|_| PyRuntimeError::new_err("the render thread stopped"))?;
        let out = pyo3::types::PyDict::new(py);
        out.set_item("frame_ms", stats.frame.as_secs_f64() * 1e3)?;
        out.set_item("status", stats.status)?;
        let facts = pyo3::types::PyDict::new(py);
        for (label, line) in stats.facts {
            facts.set_item(label, line)?;
        }
        out.set_item("facts", facts)?;
        Ok(out)
    }

    /// Milliseconds an interactive frame may take (default 66: 15 frames per second).
    #[getter]
    fn budget_ms(&self) -> f64 {
        *lock(&self.budget_ms)
    }

    #[setter]
    fn set_budget_ms(&self, ms: f64) -> PyResult<()> {
        if !(ms.is_finite() && ms > 0.0) {
            return Err(PyValueError::new_err(format!(
                "budget_ms {ms}: a positive number of milliseconds"
            )));
        }
        self.jobs()?
            .send(Job::Budget(ms))
            .map_err(|_| PyRuntimeError::new_err("the render thread stopped"))?;
        *lock(&self.budget_ms) = ms;
        Ok(())
    }

    /// The scene this renderer draws.
    #[getter]
    fn scene(&self, py: Python<'_>) -> Py<PyScene> {
        lock(&self.scene).clone_ref(py)
    }

    /// The program kind it draws with (`"arb"` or `"glsl"`).
    #[getter]
    fn program_kind(&self) -> &'static str {
        self.program_kind
    }

    /// The backend (`"egl"` or `"osmesa"`).
    #[getter]
    fn backend(&self) -> &'static str {
        self.backend
    }

    /// The driver's renderer string (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    #[getter]
    fn driver(&self) -> String {
        self.renderer.clone()
    }

    /// Free the context, data and thread now (also done when the renderer is collected),
    /// once the frames other threads asked for are drawn; later calls say it is closed.
    fn close(&self, py: Python<'_>) {
        *lock(&self.jobs) = None;
        let thread = lock(&self.thread).take();
        if let Some(thread) = thread {
            py.detach(|| {
                let _ = thread.join();
            });
        }
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __exit__(
        &self,
        py: Python<'_>,
        _exc_type: &Bound<'_, PyAny>,
        _exc: &Bound<'_, PyAny>,
        _tb: &Bound<'_, PyAny>,
    ) {
        self.close(py);
    }

    fn __repr__(&self) -> String {
        format!(
            "<arbvis.Renderer {} programs on {} ({})>",
            self.program_kind, self.backend, self.renderer
        )
    }
}

impl Drop for PyRenderer {
    fn drop(&mut self) {
        // The thread ends when its inbox closes; it never takes the GIL, so waiting for it
        // here cannot deadlock.
        *lock(&self.jobs) = None;
        if let Some(thread) = lock(&self.thread).take() {
            let _ = thread.join();
        }
    }
}

/// `image` as a numpy array `(height, width, 4)`: its floats moved in without a copy for
/// a float target, rounded to bytes for an 8-bit one.
fn to_array(py: Python<'_>, image: Image) -> Bound<'_, PyAny> {
    let shape = (image.height as usize, image.width as usize, 4);
    match image.format {
        TargetFormat::Rgba8 => {
            let array = Array3::from_shape_vec(shape, image.to_rgba8()).expect("4 values a pixel");
            array.into_pyarray(py).into_any()
        }
        _ => {
            let array = Array3::from_shape_vec(shape, image.data).expect("4 values a pixel");
            array.into_pyarray(py).into_any()
        }
    }
}
