//! Every technique in one list: the `techniques!` line of each makes [`TechniqueScene`]'s
//! variant (its scene parameters, `[technique.NAME]` in TOML) and its [`Registration`]
//! in [`TECHNIQUES`] (name, demos, program pairs), from its type's one [`Technique`]
//! implementation (validation, data paths, memory estimate, defaults, the renderer).
//! What the layers above ask of "the scene's technique" goes through the methods here;
//! code that needs one technique's parameters asks for them by type
//! ([`TechniqueScene::get`]).
//!
//! The catalog sits above the techniques and below the scene: techniques never import it
//! (their renderers take their own parameters through [`crate::techniques::Params`]), so
//! adding a technique is its own folder and one line here.

use crate::error::RenderResult;
use std::any::Any;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::programs::ProgramPair;
use crate::summary::Summary;
use crate::techniques::cellproj::CellprojScene;
use crate::techniques::lines::LinesScene;
use crate::techniques::opacity3d::Opacity3dScene;
use crate::techniques::quad::QuadScene;
use crate::techniques::section::SectionScene;
use crate::techniques::splats::SplatsScene;
use crate::techniques::surface::SurfaceScene;
use crate::techniques::world::World;
pub use crate::techniques::Settings;
use crate::techniques::{Params, ReferenceView, Renderer, Technique};
use arbvis_core::camera::Camera;
use arbvis_core::image::Image;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::volume::Limits;
use arbvis_gl::{GlError, Gpu, ProgramChoice, ProgramKind};

/// The one list of techniques: each line is a technique's variant and its parameters'
/// type, which implements [`Technique`] in its own folder. The enum, its conversions,
/// the dispatch below and [`TECHNIQUES`] (demos, program pairs, names) are made from it,
/// so adding a technique is its folder plus one line here.
macro_rules! techniques {
    ($($(#[$doc:meta])* $field:ident => $variant:ident($type:ty)),* $(,)?) => {
        /// Which technique and its parameters; in TOML a `[technique.NAME]` table.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(rename_all = "kebab-case", deny_unknown_fields)]
        pub enum TechniqueScene {
            $($(#[$doc])* $variant(Box<$type>),)*
        }

        $(impl From<$type> for TechniqueScene {
            /// The technique of these parameters.
            fn from(p: $type) -> TechniqueScene {
                TechniqueScene::$variant(Box::new(p))
            }
        })*

        impl TechniqueScene {
            /// The parameters, as the catalog dispatches on them.
            fn technique(&self) -> &dyn AnyTechnique {
                match self {
                    $(TechniqueScene::$variant(p) => &**p,)*
                }
            }

            /// [`TechniqueScene::technique`], to change.
            fn technique_mut(&mut self) -> &mut dyn AnyTechnique {
                match self {
                    $(TechniqueScene::$variant(p) => &mut **p,)*
                }
            }
        }

        /// Every technique, in the catalog's order: what the lists of demos and program
        /// pairs (and the viewer's faces, checked against it) derive from.
        pub const TECHNIQUES: &[Registration] = &[$(Registration::of::<$type>(),)*];

        /// A `[[layer]]` table as a scene's text holds it: its name, visibility and
        /// placement, and one technique's table (`[layer.surface]`), exactly one.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct LayerTable {
            /// The layer's name (in errors, legends and the viewer's list).
            #[serde(default, skip_serializing_if = "String::is_empty")]
            pub name: String,
            /// Drawn or not (a hidden layer stays in the scene's frame).
            #[serde(default = "visible", skip_serializing_if = "is_visible")]
            pub visible: bool,
            /// Added to the data's world coordinates (after `scale`).
            #[serde(default, skip_serializing_if = "is_zero")]
            pub offset: [f64; 3],
            /// The data's world coordinates multiplied by it (above 0).
            #[serde(default = "unit", skip_serializing_if = "is_unit")]
            pub scale: f64,
            $($(#[$doc])*
            #[serde(default, skip_serializing_if = "Option::is_none")]
            pub $field: Option<Box<$type>>,)*
        }

        impl LayerTable {
            /// The layer's name, visibility and placement, and its technique where the
            /// table names exactly one; else the names it holds.
            pub fn split(self) -> Result<(LayerInfo, TechniqueScene), Vec<&'static str>> {
                let info = LayerInfo {
                    name: self.name,
                    visible: self.visible,
                    offset: self.offset,
                    scale: self.scale,
                };
                let mut found = Vec::new();
                $(if let Some(p) = self.$field {
                    found.push(TechniqueScene::$variant(p));
                })*
                match found.len() {
                    1 => Ok((info, found.remove(0))),
                    _ => Err(found.iter().map(TechniqueScene::name).collect()),
                }
            }

            /// The table of a layer.
            pub fn of(info: LayerInfo, technique: TechniqueScene) -> LayerTable {
                let mut table = LayerTable {
                    name: info.name,
                    visible: info.visible,
                    offset: info.offset,
                    scale: info.scale,
                    $($field: None,)*
                };
                match technique {
                    $(TechniqueScene::$variant(p) => table.$field = Some(p),)*
                }
                table
            }
        }
    };
}

/// A layer's name, visibility and hand placement (`world = scale * data + offset`).
#[derive(Debug, Clone, PartialEq)]
pub struct LayerInfo {
    /// Its name (empty: none given).
    pub name: String,
    /// Drawn or not; a hidden layer stays in the scene's frame.
    pub visible: bool,
    /// Added to the data's world coordinates.
    pub offset: [f64; 3],
    /// The data's world coordinates multiplied by it.
    pub scale: f64,
}

impl Default for LayerInfo {
    fn default() -> Self {
        LayerInfo {
            name: String::new(),
            visible: true,
            offset: [0.0; 3],
            scale: 1.0,
        }
    }
}

fn visible() -> bool {
    true
}

fn is_visible(v: &bool) -> bool {
    *v
}

fn is_zero(v: &[f64; 3]) -> bool {
    *v == [0.0; 3]
}

fn unit() -> f64 {
    1.0
}

fn is_unit(v: &f64) -> bool {
    *v == 1.0
}

techniques!(
    /// The full-screen quad demo.
    quad => Quad(QuadScene),
    /// v3o2's 3D opacity (with its clip).
    opacity3d => Opacity3d(Opacity3dScene),
    /// Isosurfaces and volumes of tetrahedral meshes by cell projection.
    cellproj => Cellproj(CellprojScene),
    /// Point-based rendering of geological sections as splats.
    splats => Splats(SplatsScene),
    /// A triangle surface (a horizon, a fault, a body's boundary), a layer beside the others.
    surface => Surface(SurfaceScene),
    /// An inline, crossline or time section of a survey, a plane coloured by a table.
    section => Section(SectionScene),
    /// Polylines and wells as tubes, coloured by a value along them.
    lines => Lines(LinesScene),
);

/// What a technique declares once, read by every list of techniques.
#[derive(Debug, Clone, Copy)]
pub struct Registration {
    /// The name of its scene table, `[technique.NAME]`.
    pub name: &'static str,
    /// Its built-in demos: name and scene text.
    pub demos: &'static [(&'static str, &'static str)],
    /// Every program pair its renderers can draw with, both kinds.
    pub program_pairs: fn() -> Vec<ProgramPair>,
    /// Its `arbvis study` sweeps: name and what each sweeps.
    pub studies: &'static [(&'static str, &'static str)],
}

impl Registration {
    /// Technique `T`'s registration, from its [`Technique`] implementation.
    pub const fn of<T: Technique>() -> Registration {
        Registration {
            name: T::NAME,
            demos: T::DEMOS,
            program_pairs: T::program_pairs,
            studies: T::STUDIES,
        }
    }
}

/// Every built-in demo (name, scene text), technique by technique.
pub fn demos() -> impl Iterator<Item = (&'static str, &'static str)> {
    TECHNIQUES.iter().flat_map(|t| t.demos.iter().copied())
}

/// Every `arbvis study` sweep (name, what it sweeps), technique by technique.
pub fn studies() -> impl Iterator<Item = (&'static str, &'static str)> {
    TECHNIQUES.iter().flat_map(|t| t.studies.iter().copied())
}

/// [`Technique`] with `T` erased, for the catalog's dispatch (one blanket implementation
/// below); keys are relative to the scene's root here.
trait AnyTechnique: Any {
    fn name(&self) -> &'static str;
    fn params(&self) -> Params<'_>;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
    fn validate(&self, fidelity: Fidelity, programs: ProgramChoice) -> Result<(), FieldError>;
    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf));
    fn default_camera(&self) -> Option<Camera>;
    fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut Camera,
        fidelity: &mut Fidelity,
    );
    fn for_interaction(&mut self, scale: f64);
    fn draws_opaque(&self) -> bool;
    fn keeps_place(&self, new: &dyn Any) -> bool;
    fn occludable(&mut self);
    fn memory_estimate(&self, size: [u32; 2]) -> Vec<arbvis_core::budget::Estimate>;
    fn prepare(&self, settings: &Settings<'_>, limits: &Limits) -> RenderResult<PreparedData>;
    fn renderer(
        &self,
        gpu: &Gpu,
        settings: &Settings<'_>,
        kind: ProgramKind,
        prepared: PreparedData,
    ) -> RenderResult<Box<dyn Renderer>>;
    fn reference(
        &self,
        settings: &Settings<'_>,
        limits: &Limits,
        view: &ReferenceView<'_>,
    ) -> RenderResult<Option<Image>>;
    fn summary(&self, prepared: &dyn Any, base: &Path) -> Option<Summary>;
    fn world(&self, prepared: &dyn Any) -> Option<World>;
    fn colours_at(
        &self,
        prepared: &dyn Any,
        points: &[glam::DVec3],
    ) -> Option<Vec<Option<[f64; 3]>>>;
    fn colour_source(&self) -> Option<&str>;
    fn coloured_points(&self, prepared: &dyn Any) -> Vec<glam::DVec3>;
    fn take_colours(&self, prepared: &mut dyn Any, colours: &[Option<[f64; 3]>]);
}

impl<T: Technique> AnyTechnique for T {
    fn name(&self) -> &'static str {
        T::NAME
    }

    fn params(&self) -> Params<'_> {
        Params::of(self)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }

    fn validate(&self, fidelity: Fidelity, programs: ProgramChoice) -> Result<(), FieldError> {
        Technique::validate(self, fidelity, programs)
            .map_err(|e| e.within(&format!("technique.{}", T::NAME)))
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        let within = format!("technique.{}", T::NAME);
        let f = &mut |key: &str, path: &mut PathBuf| f(&format!("{within}.{key}"), path);
        Technique::for_each_data_path(self, f)
    }

    fn default_camera(&self) -> Option<Camera> {
        Technique::default_camera(self)
    }

    fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut Camera,
        fidelity: &mut Fidelity,
    ) {
        Technique::unwritten_defaults(self, written, camera, fidelity)
    }

    fn for_interaction(&mut self, scale: f64) {
        Technique::for_interaction(self, scale)
    }

    fn draws_opaque(&self) -> bool {
        Technique::draws_opaque(self)
    }

    fn keeps_place(&self, new: &dyn Any) -> bool {
        new.downcast_ref::<T>()
            .is_some_and(|new| Technique::keeps_place(self, new))
    }

    fn occludable(&mut self) {
        Technique::occludable(self)
    }

    fn memory_estimate(&self, size: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        Technique::memory_estimate(self, size)
    }

    fn prepare(&self, settings: &Settings<'_>, limits: &Limits) -> RenderResult<PreparedData> {
        Technique::prepare(self, settings, limits).map(|d| Box::new(d) as PreparedData)
    }

    /// [`Technique::renderer`] of `prepared`, which must be `T`'s.
    fn renderer(
        &self,
        gpu: &Gpu,
        settings: &Settings<'_>,
        kind: ProgramKind,
        prepared: PreparedData,
    ) -> RenderResult<Box<dyn Renderer>> {
        let prepared = prepared.downcast::<T::Prepared>().map_err(|_| {
            GlError::Invalid(format!(
                "the {} renderer was given another technique's prepared data",
                T::NAME
            ))
        })?;
        Technique::renderer(self, gpu, settings, kind, *prepared)
    }

    fn reference(
        &self,
        settings: &Settings<'_>,
        limits: &Limits,
        view: &ReferenceView<'_>,
    ) -> RenderResult<Option<Image>> {
        Ok(Technique::reference(
            self,
            &Technique::prepare(self, settings, limits)?,
            view,
        ))
    }

    /// [`Technique::summary`] of `prepared` (none where it is another technique's).
    fn summary(&self, prepared: &dyn Any, base: &Path) -> Option<Summary> {
        Technique::summary(self, prepared.downcast_ref::<T::Prepared>()?, base)
    }

    /// [`Technique::world`] of `prepared` (none where it is another technique's).
    fn world(&self, prepared: &dyn Any) -> Option<World> {
        Technique::world(self, prepared.downcast_ref::<T::Prepared>()?)
    }

    fn colours_at(
        &self,
        prepared: &dyn Any,
        points: &[glam::DVec3],
    ) -> Option<Vec<Option<[f64; 3]>>> {
        Technique::colours_at(self, prepared.downcast_ref::<T::Prepared>()?, points)
    }

    fn colour_source(&self) -> Option<&str> {
        Technique::colour_source(self)
    }

    fn coloured_points(&self, prepared: &dyn Any) -> Vec<glam::DVec3> {
        prepared
            .downcast_ref::<T::Prepared>()
            .map_or_else(Vec::new, |p| Technique::coloured_points(self, p))
    }

    fn take_colours(&self, prepared: &mut dyn Any, colours: &[Option<[f64; 3]>]) {
        if let Some(p) = prepared.downcast_mut::<T::Prepared>() {
            Technique::take_colours(self, p, colours)
        }
    }
}

impl TechniqueScene {
    /// Technique name as written in scenes.
    pub fn name(&self) -> &'static str {
        self.technique().name()
    }

    /// The parameters as a renderer's [`Renderer::update`] takes them.
    pub fn params(&self) -> Params<'_> {
        self.technique().params()
    }

    /// The parameters, of whichever technique (for a list of capabilities kept above
    /// the catalog, such as the viewer's faces).
    pub fn parameters(&self) -> &dyn Any {
        self.technique().as_any()
    }

    /// [`TechniqueScene::parameters`], to change.
    pub fn parameters_mut(&mut self) -> &mut dyn Any {
        self.technique_mut().as_any_mut()
    }

    /// The parameters as technique `T`'s, where the scene draws `T`.
    pub fn get<T: Technique>(&self) -> Option<&T> {
        self.parameters().downcast_ref::<T>()
    }

    /// The parameters as technique `T`'s to change, where the scene draws `T`.
    pub fn get_mut<T: Technique>(&mut self) -> Option<&mut T> {
        self.parameters_mut().downcast_mut::<T>()
    }

    /// Check values that parse but cannot render at `fidelity` with `programs`; the
    /// error's key is the dotted key from the scene's root.
    pub fn validate(&self, fidelity: Fidelity, programs: ProgramChoice) -> Result<(), FieldError> {
        self.technique().validate(fidelity, programs)
    }

    /// Call `f` on every data file the parameters name, with the dotted key that holds
    /// it (from the scene's root).
    pub fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        self.technique_mut().for_each_data_path(f)
    }

    /// The camera a scene without `[camera]` starts from (and the viewer's Reset camera
    /// returns to), where the technique's data asks for another than the default.
    pub fn default_camera(&self) -> Option<Camera> {
        self.technique().default_camera()
    }

    /// Defaults that depend on the data a scene names, for the keys its text leaves out
    /// (`written` tells which dotted keys it writes): a survey's three-quarter view where
    /// there is no `[camera]`, a lidar cloud's precise splats, and so on.
    pub fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut Camera,
        fidelity: &mut Fidelity,
    ) {
        self.technique_mut()
            .unwritten_defaults(written, camera, fidelity)
    }

    /// The technique as the frames drawn while the user interacts draw it, into an image
    /// of 1/`scale` of each side ([`Technique::for_interaction`]).
    pub fn for_interaction(&self, scale: f64) -> TechniqueScene {
        let mut reduced = self.clone();
        reduced.technique_mut().for_interaction(scale);
        reduced
    }

    /// Whether it draws opaque geometry only ([`Technique::draws_opaque`]).
    pub fn draws_opaque(&self) -> bool {
        self.technique().draws_opaque()
    }

    /// Whether `new` draws the same data in the same place, only differently
    /// ([`Technique::keeps_place`]); false for another technique.
    pub fn keeps_place(&self, new: &TechniqueScene) -> bool {
        self.technique().keeps_place(new.technique().as_any())
    }

    /// The same picture drawn as geometry an opaque layer's depth can hide
    /// ([`Technique::occludable`]).
    pub fn occludable(&self) -> TechniqueScene {
        let mut occludable = self.clone();
        occludable.technique_mut().occludable();
        occludable
    }

    /// The large allocations preparing and drawing it at `size` makes that the scene
    /// alone determines (generated data, grids, lists); files are checked by their loaders.
    pub fn memory_estimate(&self, size: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        self.technique().memory_estimate(size)
    }
}

/// Build the renderer for `technique`, with programs of `kind`; nothing else is created.
pub fn build(
    gpu: &Gpu,
    technique: &TechniqueScene,
    settings: &Settings<'_>,
    kind: ProgramKind,
) -> RenderResult<Box<dyn Renderer>> {
    // Prepared within the GL's largest 3D texture; nothing else is created.
    let limits = Limits::for_max_side(gpu.caps().max_3d_texture_size);
    let technique = technique.technique();
    let prepared = technique.prepare(settings, &limits)?;
    technique.renderer(gpu, settings, kind, prepared)
}

/// A technique's prepared data ([`Technique::Prepared`]), boxed, so that a caller that
/// keeps it (the viewer, between renderers of another program kind) need not name the
/// technique that made it.
pub type PreparedData = Box<dyn Any>;

/// The f64 CPU reference of `technique`'s picture for `view`, where it has one: its data
/// prepared (within `limits`), then [`Technique::reference`].
pub fn reference(
    technique: &TechniqueScene,
    settings: &Settings<'_>,
    limits: &Limits,
    view: &ReferenceView<'_>,
) -> RenderResult<Option<Image>> {
    technique.technique().reference(settings, limits, view)
}

/// Check `technique`'s parameters, then load and prepare its data within `limits`
/// ([`Technique::prepare`]).
pub fn prepare(
    technique: &TechniqueScene,
    settings: &Settings<'_>,
    limits: &Limits,
) -> RenderResult<PreparedData> {
    technique.technique().prepare(settings, limits)
}

/// What the panels show of what [`prepare`] made for `technique` (data files relative to
/// `base`), where the technique tells ([`Technique::summary`]).
pub fn summary(
    technique: &TechniqueScene,
    prepared: &PreparedData,
    base: &Path,
) -> Option<Summary> {
    technique.technique().summary(prepared.as_ref(), base)
}

/// Where what [`prepare`] made for `technique` lies in the world frame a scene's layers
/// share ([`Technique::world`]).
pub fn world(technique: &TechniqueScene, prepared: &PreparedData) -> Option<World> {
    technique.technique().world(prepared.as_ref())
}

/// A layer coloured by another: the layer it names, where it does
/// ([`Technique::colour_source`]).
pub fn colour_source(technique: &TechniqueScene) -> Option<&str> {
    technique.technique().colour_source()
}

/// The points of `prepared` that take another layer's colours, in its object frame.
pub fn coloured_points(technique: &TechniqueScene, prepared: &PreparedData) -> Vec<glam::DVec3> {
    technique.technique().coloured_points(prepared.as_ref())
}

/// The colours `technique` shows at `points` of its object frame (None outside).
pub fn colours_at(
    technique: &TechniqueScene,
    prepared: &PreparedData,
    points: &[glam::DVec3],
) -> Option<Vec<Option<[f64; 3]>>> {
    technique.technique().colours_at(prepared.as_ref(), points)
}

/// `prepared` takes `colours` for its [`coloured_points`].
pub fn take_colours(
    technique: &TechniqueScene,
    prepared: &mut PreparedData,
    colours: &[Option<[f64; 3]>],
) {
    technique
        .technique()
        .take_colours(prepared.as_mut(), colours)
}

/// The renderer of what [`prepare`] made for `technique`, with programs of `kind`.
pub fn renderer(
    technique: &TechniqueScene,
    gpu: &Gpu,
    settings: &Settings<'_>,
    kind: ProgramKind,
    prepared: PreparedData,
) -> RenderResult<Box<dyn Renderer>> {
    technique
        .technique()
        .renderer(gpu, settings, kind, prepared)
}

/// Every program pair the techniques can draw with, both kinds (the compile-everything
/// test): each technique lists its own.
pub fn all_program_pairs() -> Vec<ProgramPair> {
    TECHNIQUES
        .iter()
        .flat_map(|t| (t.program_pairs)())
        .collect()
}
