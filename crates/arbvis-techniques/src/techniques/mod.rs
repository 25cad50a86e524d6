//! One module per technique, each with the same parts: a `//!` "How it works", the scene
//! parameters, CPU preparation (testable without GL), the renderer, and a CPU reference
//! of the same maths. The seed techniques (`opacity3d`, `cellproj`, `clip`, `splats`)
//! slot in beside `quad`, the foundation's demo.

/// A built-in demo for [`Technique::DEMOS`]: its name and the text of
/// `scenes/demo/NAME.toml`.
macro_rules! demo {
    ($name:literal) => {
        (
            $name,
            include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../scenes/demo/",
                $name,
                ".toml"
            )),
        )
    };
}
pub(crate) use demo;

pub mod annotations;
pub mod cellproj;
pub mod clip;
pub mod lines;
pub mod opacity3d;
pub mod quad;
pub mod rays;
pub mod section;
pub mod splats;
pub mod surface;
pub mod world;

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use std::any::Any;
use std::path::{Path, PathBuf};

use crate::programs::ProgramPair;
use crate::summary::Summary;
use arbvis_core::budget::Estimate;
use arbvis_core::camera::{Camera, Projection};
use arbvis_core::image::Image;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::volume::Limits;
use arbvis_gl::{GlError, Gpu, ProgramChoice, ProgramKind, Surface};

/// What changes from frame to frame.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// The camera.
    pub camera: Camera,
    /// Surface width in pixels.
    pub width: u32,
    /// Surface height in pixels.
    pub height: u32,
}

impl Frame {
    /// Width / height.
    pub fn aspect(&self) -> f64 {
        self.width as f64 / self.height.max(1) as f64
    }
}

/// A technique's long-lived GL state (programs, textures, buffers), drawn once per frame.
/// What only some renderers can do is asked of them as its own small trait
/// ([`Streaming`], [`DrawInParts`]); `dyn Renderer` offers each with a default for the
/// renderers without it ([`Renderer::pending`]-style calls below).
pub trait Renderer {
    /// Draw one frame onto `surface` (already cleared by the caller).
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()>;
    /// Take changed parameters (the viewer's editors); resends what changed. Parameters
    /// of another technique are an error.
    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()>;
    /// The program kind in use.
    fn program_kind(&self) -> ProgramKind;
    /// Whether its surface needs a depth buffer (opaque geometry with a depth test).
    fn needs_depth(&self) -> bool {
        false
    }
    /// Whether it draws opaque geometry with depth only (an opaque surface, an
    /// isosurface): a layered scene draws those first and tests the others against them.
    fn opaque(&self) -> bool {
        false
    }
    /// A line for the viewer about the last frame's CPU work (e.g. the sort time).
    fn status(&self) -> Option<String> {
        None
    }
    /// Labelled facts about what the renderer built, for the viewer's panel (3D
    /// opacity's clip: its last build time and texture memory, labelled
    /// [`clip::stats::LABEL`]); none by default.
    fn facts(&self) -> Vec<(&'static str, String)> {
        Vec::new()
    }
    /// What the picture's legends and axes say (`render --legend --axes`): its colour
    /// tables with their value ranges, keys, and the box's axes in the data's numbers.
    fn annotations(&self) -> annotations::Annotations {
        annotations::Annotations::default()
    }
    /// Its data arriving over frames, where they do ([`Streaming`]).
    fn streaming(&self) -> Option<&dyn Streaming> {
        None
    }
    /// [`Renderer::streaming`], to change.
    fn streaming_mut(&mut self) -> Option<&mut dyn Streaming> {
        None
    }
    /// Its frame drawn in parts, where one frame can be slow ([`DrawInParts`]).
    fn in_parts(&mut self) -> Option<&mut dyn DrawInParts> {
        None
    }
    /// A layered scene's layer `index` takes new parameters through its renderer's
    /// [`Renderer::update`] (a section moved, a colour changed); false where it cannot
    /// (not layered, or a renderer two layers share) and must be built again.
    fn update_layer(&mut self, gpu: &Gpu, index: usize, params: Params<'_>) -> RenderResult<bool> {
        let _ = (gpu, index, params);
        Ok(false)
    }
}

/// A renderer whose data arrive over frames: a survey store's bricks, a COPC cloud's cut
/// for the view where the camera stopped.
pub trait Streaming {
    /// Streaming (the viewer): draw what is at hand and refine over later frames, instead
    /// of waiting for all the data a full-quality frame needs (offscreen renders).
    fn set_streaming(&mut self, streaming: bool) {
        let _ = streaming;
    }
    /// Whether data are still on their way (the viewer keeps drawing).
    fn pending(&self) -> bool;
    /// The user is still at `camera` on an image of `size` (the viewer, once the camera
    /// stops): load what that view needs; true when a new part arrived (the picture must
    /// be drawn again).
    fn settle(&mut self, gpu: &Gpu, camera: &Camera, size: [u32; 2]) -> RenderResult<bool> {
        let _ = (gpu, camera, size);
        Ok(false)
    }
}

/// A renderer that can spread a slow frame over several UI frames.
pub trait DrawInParts {
    /// Draw part `part` of `parts` of the frame: parts `0..parts` drawn in order leave
    /// exactly what [`Renderer::draw`] leaves.
    fn draw_part(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        part: usize,
        parts: usize,
    ) -> RenderResult<()>;
}

/// Each capability asked of any renderer, with what a renderer without it does.
impl<'a> dyn Renderer + 'a {
    /// Part `part` of `parts` of the frame ([`DrawInParts`]); a renderer without parts
    /// draws everything as part 0.
    pub fn draw_part(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        part: usize,
        parts: usize,
    ) -> RenderResult<()> {
        match self.in_parts() {
            Some(renderer) => renderer.draw_part(gpu, surface, frame, part, parts),
            None if part == 0 => self.draw(gpu, surface, frame),
            None => Ok(()),
        }
    }

    /// [`Streaming::set_streaming`]; nothing for a renderer that does not stream.
    pub fn set_streaming(&mut self, streaming: bool) {
        if let Some(renderer) = self.streaming_mut() {
            renderer.set_streaming(streaming);
        }
    }

    /// [`Streaming::pending`]; false for a renderer that does not stream.
    pub fn pending(&self) -> bool {
        self.streaming().is_some_and(|r| r.pending())
    }

    /// [`Streaming::settle`]; false (nothing new) for a renderer that does not stream.
    pub fn settle(&mut self, gpu: &Gpu, camera: &Camera, size: [u32; 2]) -> RenderResult<bool> {
        match self.streaming_mut() {
            Some(renderer) => renderer.settle(gpu, camera, size),
            None => Ok(false),
        }
    }
}

/// One technique, implemented once by its scene parameters' type (`[technique.NAME]` in
/// TOML): what the scene, the catalog and the layers above need of it. The catalog
/// (`crate::catalog`, above the techniques) is the one list of the implementors; nothing
/// else names that list, and a technique names none of the others.
pub trait Technique: Any + Sized {
    /// The technique's name as written in scenes.
    const NAME: &'static str;
    /// Its built-in demos, name and scene text ([`demo!`] reads one from `scenes/demo/`).
    const DEMOS: &'static [(&'static str, &'static str)];
    /// Its `arbvis study` sweeps: the name `--technique` takes and what it sweeps (the
    /// runner is the command line's, which alone holds their arguments).
    const STUDIES: &'static [(&'static str, &'static str)] = &[];
    /// Check values that parse but cannot render, in a scene drawn at `fidelity` with
    /// `programs`; the error's key is relative to `[technique.NAME]`.
    fn validate(&self, fidelity: Fidelity, programs: ProgramChoice) -> Result<(), FieldError>;
    /// Call `f` on every data file the parameters name, with its key relative to
    /// `[technique.NAME]` (e.g. `primary.volume.file`).
    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        let _ = f;
    }
    /// The large allocations preparing and drawing it at `size` makes that the
    /// parameters alone determine (generated data, grids, lists); files are held to the
    /// budget by their loaders.
    fn memory_estimate(&self, size: [u32; 2]) -> Vec<Estimate> {
        let _ = size;
        Vec::new()
    }
    /// The camera a scene without `[camera]` starts from (and the viewer's Reset camera
    /// returns to), where the data asks for another than the default.
    fn default_camera(&self) -> Option<Camera> {
        None
    }
    /// Defaults that depend on the data the parameters name, for the keys a scene's text
    /// leaves out (`written` tells which dotted keys it writes, from the scene's root).
    fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut Camera,
        fidelity: &mut Fidelity,
    ) {
        let _ = (written, camera, fidelity);
    }
    /// Cheaper parameters of the same picture for the frames drawn while the user
    /// interacts, into an image of 1/`scale` of each side (the session's frame budget:
    /// `scale` from 1 to 10); by default the same parameters.
    fn for_interaction(&mut self, scale: f64) {
        let _ = scale;
    }
    /// Whether its parameters draw opaque geometry only (an opaque surface,
    /// isosurfaces): a layered scene draws those first, and the others against their depth.
    fn draws_opaque(&self) -> bool {
        false
    }
    /// Whether `new` (other parameters of this technique) draws the same data in the same
    /// place, only differently (a section at another inline, a surface's colour): a layered
    /// scene's renderer then takes it through [`Renderer::update`] instead of being built
    /// again. False by default.
    fn keeps_place(&self, new: &Self) -> bool {
        let _ = new;
        false
    }
    /// Parameters of the same picture drawn as geometry an opaque layer's depth can hide
    /// (not a pass over the whole frame), for a layered scene with opaque layers; by
    /// default the same parameters.
    fn occludable(&mut self) {}
    /// Every program pair its renderers can draw with, both kinds (the
    /// compile-everything test).
    fn program_pairs() -> Vec<ProgramPair>;
    /// What the CPU makes before the renderer: the data loaded, derived and laid out (no
    /// GL; `()` where there is nothing).
    type Prepared: Any;
    /// Check the parameters, then load and prepare the data (relative paths from
    /// `settings.base`) within `limits`.
    fn prepare(&self, settings: &Settings<'_>, limits: &Limits) -> RenderResult<Self::Prepared>;
    /// The renderer of what [`Technique::prepare`] made, with programs of `kind`
    /// (`settings.programs` resolved).
    fn renderer(
        &self,
        gpu: &Gpu,
        settings: &Settings<'_>,
        kind: ProgramKind,
        prepared: Self::Prepared,
    ) -> RenderResult<Box<dyn Renderer>>;
    /// The f64 CPU reference of the picture `prepared` draws for `view` (RGBA32F, alpha
    /// the coverage, over the view's background), where the technique has one: the
    /// yardstick its precise mode is measured against. None by default.
    fn reference(&self, prepared: &Self::Prepared, view: &ReferenceView<'_>) -> Option<Image> {
        let _ = (prepared, view);
        None
    }
    /// What a front end's panels and overlays show of `prepared` (data files relative to
    /// `base`): its box in the file's coordinates, a cloud's key, a mesh's scalar. None by
    /// default.
    fn summary(&self, prepared: &Self::Prepared, base: &Path) -> Option<Summary> {
        let _ = (prepared, base);
        None
    }
    /// Where `prepared`'s object frame lies in the world frame a scene's layers share
    /// ([`world::World`]); none for a technique without a place (the quad), which a
    /// layered scene refuses.
    fn world(&self, prepared: &Self::Prepared) -> Option<world::World> {
        let _ = prepared;
        None
    }
    /// The colour it shows at each of `points` (its object frame), None outside its data:
    /// what another layer coloured by this one takes (a survey's primary attribute
    /// through its table). None where the technique has no colour at a point.
    fn colours_at(
        &self,
        prepared: &Self::Prepared,
        points: &[glam::DVec3],
    ) -> Option<Vec<Option<[f64; 3]>>> {
        let _ = (prepared, points);
        None
    }
    /// The layer whose colours it takes where it lies (`colour_from`), if any.
    fn colour_source(&self) -> Option<&str> {
        None
    }
    /// Its points to colour (object frame), and takes their colours (None: outside the
    /// source, kept as it was): a layer coloured by another ([`Technique::colour_source`]).
    fn coloured_points(&self, prepared: &Self::Prepared) -> Vec<glam::DVec3> {
        let _ = prepared;
        Vec::new()
    }
    /// Take the colours of [`Technique::coloured_points`].
    fn take_colours(&self, prepared: &mut Self::Prepared, colours: &[Option<[f64; 3]>]) {
        let _ = (prepared, colours);
    }
}

/// What a reference picture is computed for ([`Technique::reference`]).
#[derive(Debug, Clone, Copy)]
pub struct ReferenceView<'a> {
    /// The camera.
    pub camera: Camera,
    /// `[width, height]` in pixels.
    pub size: [u32; 2],
    /// The colour the picture is composited over.
    pub background: [f64; 4],
    /// The folder relative data paths (tables) are read from.
    pub base: &'a Path,
}

/// What a renderer needs of the scene besides its technique's parameters.
#[derive(Debug, Clone, Copy)]
pub struct Settings<'a> {
    /// Faithful or precise.
    pub fidelity: Fidelity,
    /// The program kind the scene asked for (`auto` resolved to `kind` by the caller).
    pub programs: ProgramChoice,
    /// The folder relative data paths are read from.
    pub base: &'a Path,
    /// The camera's projection when the renderer is built.
    pub projection: Projection,
    /// The first view (camera and image size), for data that is cut to the view (a COPC
    /// cloud's nodes).
    pub view: arbvis_core::camera::View,
}

/// Some technique's parameters; a renderer takes its own with [`Params::get`].
#[derive(Clone, Copy)]
pub struct Params<'a> {
    params: &'a dyn Any,
    name: &'static str,
}

impl<'a> Params<'a> {
    /// Wrap one technique's parameters.
    pub fn of<T: Technique>(params: &'a T) -> Params<'a> {
        Params {
            params,
            name: T::NAME,
        }
    }

    /// The parameters as technique `T`'s, or an error naming both techniques.
    pub fn get<T: Technique>(&self) -> GlResult<&'a T> {
        self.params.downcast_ref::<T>().ok_or_else(|| {
            GlError::Invalid(format!("{} renderer given a {} scene", T::NAME, self.name))
        })
    }
}
