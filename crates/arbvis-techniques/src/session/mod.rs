//! One interactive session below every front end (the viewer, `arbvis.Renderer`,
//! `arbvis.dask`, `bench`): a scene's renderer and the picture it keeps, brought up to
//! date frame after frame.
//!
//! A front end hands the session the scene as it is now and says how the frame is wanted
//! ([`Mode`]); the session applies what changed (a parameter through
//! [`Renderer::update`], a new renderer where the technique, fidelity, programs, target
//! or data folder changed), loads what a new view needs where the data stream (a store's
//! bricks, a COPC cloud's cut for the view: [`crate::techniques::Streaming`]), and draws
//! reduced within the frame budget while the user interacts, in full-quality parts when
//! still, or whole now. No front end draws, settles or downcasts a renderer itself.
//! [`Offscreen`] is the session with a headless context of its own.

mod offscreen;
pub mod picture;

pub use offscreen::{FrameStats, Offscreen};
pub use picture::{FrameBudget, InteractiveQuality, Key, Pending, Picture};

use std::time::Duration;

use crate::error::RenderResult;
use crate::scene::Scene;
use crate::techniques::Renderer;
use arbvis_gl::{Gpu, ProgramKind, Target};

/// How a frame is wanted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// The camera or a parameter is moving: reduced, within the frame budget.
    Interacting,
    /// Still: the full-quality picture, in parts across frames, streaming data drawn as
    /// it arrives.
    Still,
    /// The full-quality picture now, of the data at hand (a screenshot).
    Now,
    /// The full-quality picture now, after every datum the view needs has arrived: what
    /// a fresh offscreen render of the scene draws (Python, Dask, `render`).
    Complete,
}

/// How long [`Mode::Complete`] waits between two looks at a loader.
const POLL: Duration = Duration::from_millis(2);

/// A scene's renderer and its kept picture.
pub struct Session {
    renderer: Box<dyn Renderer>,
    picture: Picture,
    /// Bumped whenever the renderer or its parameters change (part of the picture's key).
    generation: u64,
    /// The scene the renderer was last brought up to date with.
    scene: Scene,
    /// Whether pictures are cleared to the scene's clear colour (transparent black for a
    /// transparent scene, as files show it) rather than its background (a window).
    as_files: bool,
    /// How frames are drawn while the user interacts.
    pub quality: InteractiveQuality,
}

impl Session {
    /// A session over `renderer`, built for `scene`; `as_files`: pictures as `render`
    /// writes them (a transparent scene on transparent black), else as a window shows
    /// them (on the background).
    pub fn new(renderer: Box<dyn Renderer>, scene: &Scene, as_files: bool) -> Session {
        Session {
            renderer,
            picture: Picture::default(),
            generation: 0,
            scene: scene.clone(),
            as_files,
            quality: InteractiveQuality::default(),
        }
    }

    /// `scene`'s renderer with programs of `kind` (through the catalog), in a session.
    pub fn build(
        gpu: &Gpu,
        scene: &Scene,
        kind: ProgramKind,
        as_files: bool,
    ) -> RenderResult<Session> {
        Ok(Session::new(
            build_renderer(gpu, scene, kind)?,
            scene,
            as_files,
        ))
    }

    /// The renderer (its status, annotations, program kind, capabilities).
    pub fn renderer(&self) -> &dyn Renderer {
        &*self.renderer
    }

    /// Draw with `renderer` from now on (another program kind, fidelity or data).
    pub fn replace_renderer(&mut self, renderer: Box<dyn Renderer>) {
        self.renderer = renderer;
        self.changed();
    }

    /// Draw the next frame afresh even where nothing changed (a benchmark times each).
    pub fn redraw(&mut self) {
        self.picture.refine();
    }

    /// The renderer or its parameters changed: the kept picture no longer shows them.
    fn changed(&mut self) {
        self.generation += 1;
    }

    /// The frame budget the session holds interactive frames to.
    pub fn budget(&self) -> FrameBudget {
        self.picture.budget
    }

    /// Hold interactive frames to `budget`.
    pub fn set_budget(&mut self, budget: FrameBudget) {
        self.picture.budget = budget;
    }

    /// The kept picture's measures (full and interactive times, parts, scale).
    pub fn picture(&self) -> &Picture {
        &self.picture
    }

    /// Bring the renderer up to date with `scene`: new parameters through
    /// [`Renderer::update`]; a new renderer where it cannot take them (another
    /// technique, fidelity, program choice, target format or data folder).
    pub fn apply(&mut self, gpu: &Gpu, scene: &Scene) -> RenderResult<()> {
        if self.update_layers(gpu, scene)? {
            self.scene = scene.clone();
            return Ok(());
        }
        let old = &self.scene;
        // A layered scene's renderer is rebuilt when any layer but the first changes.
        let same_renderer = old.technique.name() == scene.technique.name()
            && old.more_layers == scene.more_layers
            && old.layer == scene.layer
            // A layered scene's first layer too: layers may take each other's colours.
            && (!scene.is_layered() || old.technique == scene.technique)
            && old.fidelity == scene.fidelity
            && old.programs == scene.programs
            && old.target_format() == scene.target_format()
            && old.base == scene.base;
        if !same_renderer {
            let kind = scene.programs.resolve(gpu);
            self.renderer = build_renderer(gpu, scene, kind)?;
            self.changed();
        } else if old.technique != scene.technique {
            self.renderer.update(gpu, scene.technique.params())?;
            self.changed();
        }
        self.scene = scene.clone();
        Ok(())
    }

    /// A layered scene whose layers changed only in ways their renderers take in place
    /// (a section moved: a frame, not a build; [`crate::layered::changes_in_place`]):
    /// given them, true; false where the scene must be built again.
    fn update_layers(&mut self, gpu: &Gpu, scene: &Scene) -> RenderResult<bool> {
        let old = &self.scene;
        let same_settings = old.fidelity == scene.fidelity
            && old.programs == scene.programs
            && old.target_format() == scene.target_format()
            && old.base == scene.base;
        if !(old.is_layered() && scene.is_layered() && same_settings) {
            return Ok(false);
        }
        let (was, is): (Vec<_>, Vec<_>) = (old.layers().collect(), scene.layers().collect());
        let Some(changes) = crate::layered::changes_in_place(&was, &is) else {
            return Ok(false);
        };
        for (index, technique) in &changes {
            if !self
                .renderer
                .update_layer(gpu, *index, technique.params())?
            {
                return Ok(false);
            }
        }
        if !changes.is_empty() {
            self.changed();
        }
        Ok(true)
    }

    /// Take `scene`'s parameters (an editor changed them in place): through
    /// [`Renderer::update`], the renderer kept.
    pub fn params_changed(&mut self, gpu: &Gpu, scene: &Scene) -> RenderResult<()> {
        self.renderer.update(gpu, scene.technique.params())?;
        self.scene = scene.clone();
        self.changed();
        Ok(())
    }

    /// The key of `scene`'s picture in this session.
    pub fn key(&self, scene: &Scene) -> Key {
        let background = match self.as_files {
            true => scene.clear_colour(),
            false => scene.background,
        };
        Key::of(scene, self.generation, background)
    }

    /// Draw `scene` (its renderer already up to date: [`Session::apply`]) as `mode`
    /// wants it; returns what is left to do.
    pub fn frame(&mut self, gpu: &Gpu, scene: &Scene, mode: Mode) -> RenderResult<Pending> {
        let interacting = mode == Mode::Interacting;
        // A store's bricks keep arriving: draw the full picture again until none is due.
        if self.renderer.pending() && !interacting {
            self.picture.refine();
        }
        // Still: load what this view needs (a COPC cloud's cut on a thread, the cut it
        // has drawn until the new one arrives).
        if !interacting && self.renderer.settle(gpu, &scene.camera, scene.size)? {
            self.picture.refine();
        }
        if mode == Mode::Complete && self.settle_all(gpu, scene)? {
            self.picture.refine();
        }
        let key = self.key(scene);
        let sync = matches!(mode, Mode::Now | Mode::Complete);
        let layers: Vec<&crate::scene::TechniqueScene> = scene.layers().map(|(_, t)| t).collect();
        self.picture.update(
            gpu,
            &mut *self.renderer,
            &layers,
            &key,
            interacting,
            self.quality,
            sync,
        )
    }

    /// Wait until the data `scene`'s view needs have all arrived (the whole cut of a
    /// COPC cloud for this camera); true when something new arrived.
    fn settle_all(&mut self, gpu: &Gpu, scene: &Scene) -> RenderResult<bool> {
        let mut arrived = false;
        loop {
            let new = self.renderer.settle(gpu, &scene.camera, scene.size)?;
            arrived |= new;
            if !self.renderer.pending() {
                if new {
                    continue;
                }
                return Ok(arrived);
            }
            if !new {
                std::thread::sleep(POLL);
            }
        }
    }

    /// The full-quality picture of `scene`, if it is the one kept.
    pub fn full_picture(&self, scene: &Scene) -> Option<&Target> {
        self.picture.full(&self.key(scene))
    }

    /// The picture kept (full or reduced), to show.
    pub fn shown(&self) -> Option<&Target> {
        self.picture.shown()
    }

    /// The full-quality picture of `scene` read back as the target holds it (top row
    /// first, alpha the coverage), with the legends and axes the scene asks for; after a
    /// [`Mode::Now`] or [`Mode::Complete`] frame.
    pub fn read(&self, gpu: &Gpu, scene: &Scene) -> RenderResult<arbvis_core::image::Image> {
        let target = self
            .full_picture(scene)
            .ok_or_else(|| arbvis_gl::GlError::Invalid("the session drew no picture".into()))?;
        let mut image = target.read(gpu)?;
        let show = crate::annotate::Show {
            legend: scene.legend,
            axes: scene.axes,
        };
        if show.legend || show.axes {
            let annotations = self.renderer.annotations();
            crate::annotate::draw(&mut image, &scene.camera, &annotations, show)?;
        }
        Ok(image)
    }
}

impl Session {
    /// `scene`'s full-quality picture as `render` writes it (opaque, or a transparent
    /// scene's straight colour with coverage alpha): the kept picture where it was cleared
    /// as a file is, else drawn now onto a target of its own (a window's session keeps
    /// its pictures on the background).
    pub fn file_picture(
        &mut self,
        gpu: &Gpu,
        scene: &Scene,
    ) -> RenderResult<arbvis_core::image::Image> {
        if self.as_files || !scene.transparent {
            self.frame(gpu, scene, Mode::Now)?;
            let target = self.full_picture(scene);
            if let Some(t) = target {
                return Ok(scene.picture(&t.read(gpu)?));
            }
        }
        let [w, h] = scene.size;
        let depth = self.renderer.needs_depth();
        let target = Target::create(gpu, w, h, scene.target_format(), depth)?;
        target.clear(gpu, scene.clear_colour())?;
        let frame = crate::techniques::Frame {
            camera: scene.camera,
            width: w,
            height: h,
        };
        self.renderer
            .draw(gpu, arbvis_gl::Surface::Target(&target), &frame)?;
        Ok(scene.picture(&target.read(gpu)?))
    }
}

/// Build the renderer `scene` names, with programs of `kind`, within the memory budget.
fn build_renderer(gpu: &Gpu, scene: &Scene, kind: ProgramKind) -> RenderResult<Box<dyn Renderer>> {
    arbvis_core::budget::check_estimates(
        &format!("this {} scene", scene.technique.name()),
        &scene.memory_estimate(true),
    )?;
    let layers: Vec<_> = scene.layers().collect();
    crate::layered::build_any(gpu, &layers, &scene.settings(), kind)
}
