//! The session with a headless context of its own: what `arbvis.Renderer` and
//! `arbvis.dask` keep between frames.

use crate::error::RenderResult;
use crate::scene::Scene;
use arbvis_core::image::Image;
use arbvis_gl::{Backend, Caps, Headless, ProgramKind};
use std::time::{Duration, Instant};

use super::{FrameBudget, Mode, Session};

/// A scene kept ready to draw frame after frame: its context and [`Session`]. A changed
/// camera, size, background or technique parameter costs a frame; another technique,
/// fidelity, program choice, target format or data folder a new renderer. Each picture is
/// the one a fresh offscreen render of the scene draws: a new view of streamed data (a
/// COPC cloud's cut, a store's bricks) is loaded before it is drawn.
// Fields drop in order: the session's GL objects before the context.
pub struct Offscreen {
    session: Session,
    headless: Headless,
    /// How long the last frame took, from the scene's changes to the picture read.
    last_frame: Duration,
}

/// What the last frame drew, as `render --stats` says it.
#[derive(Debug, Clone)]
pub struct FrameStats {
    /// Its time: the scene's changes applied, the frame drawn and read back.
    pub frame: Duration,
    /// The renderer's line about it (a store's resident bricks and levels, a cloud's
    /// points), where it has one.
    pub status: Option<String>,
    /// The renderer's facts (the viewer's panel lines: a clip's cost, ...).
    pub facts: Vec<(&'static str, String)>,
}

impl Offscreen {
    /// A context on `backend` and `scene`'s renderer.
    pub fn new(scene: &Scene, backend: Backend) -> RenderResult<Offscreen> {
        let headless = Headless::new(backend)?;
        let gpu = headless.gpu();
        let session = Session::build(gpu, scene, scene.programs.resolve(gpu), true)?;
        Ok(Offscreen {
            session,
            headless,
            last_frame: Duration::ZERO,
        })
    }

    /// Draw `scene` (what changed since the last frame applied first), as the target
    /// holds it: top row first, alpha is coverage.
    pub fn render(&mut self, scene: &Scene) -> RenderResult<Image> {
        let start = Instant::now();
        let gpu = self.headless.gpu();
        self.session.apply(gpu, scene)?;
        self.session.frame(gpu, scene, Mode::Complete)?;
        let image = self.session.read(gpu, scene)?;
        self.last_frame = start.elapsed();
        Ok(image)
    }

    /// Draw `scene` as a frame while the user interacts (a notebook's drag): reduced to
    /// keep within the frame budget ([`Offscreen::set_budget`]), at the scale the last
    /// frames' times chose (from the whole picture down to a tenth of each side), without
    /// waiting for streamed data; the picture as the target holds it, at that scale.
    pub fn render_interactive(&mut self, scene: &Scene) -> RenderResult<Image> {
        let start = Instant::now();
        let gpu = self.headless.gpu();
        self.session.apply(gpu, scene)?;
        self.session.frame(gpu, scene, Mode::Interacting)?;
        let shown = self.session.shown().ok_or_else(|| {
            arbvis_gl::GlError::Invalid("the session drew no interactive picture".into())
        })?;
        let image = shown.read(gpu)?;
        self.last_frame = start.elapsed();
        Ok(image)
    }

    /// What the last frame drew ([`FrameStats`]).
    pub fn stats(&self) -> FrameStats {
        let renderer = self.session.renderer();
        FrameStats {
            frame: self.last_frame,
            status: renderer.status(),
            facts: renderer.facts(),
        }
    }

    /// The frame budget interactive frames keep to.
    pub fn budget(&self) -> FrameBudget {
        self.session.budget()
    }

    /// Keep interactive frames to `budget`.
    pub fn set_budget(&mut self, budget: FrameBudget) {
        self.session.set_budget(budget);
    }

    /// The program kind the renderer draws with.
    pub fn program_kind(&self) -> ProgramKind {
        self.session.renderer().program_kind()
    }

    /// The backend drawing.
    pub fn backend(&self) -> Backend {
        self.headless.backend()
    }

    /// The driver.
    pub fn caps(&self) -> &Caps {
        self.headless.gpu().caps()
    }
}
