//! Every technique in one list: [`TechniqueScene`] has a variant per technique (its
//! scene parameters, `[technique.NAME]` in TOML), and each variant's type implements
//! [`Technique`] once (validation, data paths, memory estimate, defaults, program pairs,
//! the renderer). What the layers above ask of "the scene's technique" goes through the
//! methods here, which match the list in one macro; code that needs one technique's
//! parameters asks for them by type ([`TechniqueScene::get`]).
//!
//! The catalog sits above the techniques and below the scene: techniques never import it
//! (their renderers take their own parameters through [`crate::techniques::Params`]), so
//! adding a technique touches its own folder and this file.

use crate::error::RenderResult;
use std::any::Any;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::gl::{GlError, Gpu, ProgramChoice, ProgramKind};
use crate::image::Image;
use crate::programs::ProgramPair;
use crate::techniques::cellproj::CellprojScene;
use crate::techniques::opacity3d::Opacity3dScene;
use crate::techniques::quad::QuadScene;
use crate::techniques::splats::SplatsScene;
pub use crate::techniques::Settings;
use crate::techniques::{Params, ReferenceView, Renderer, Technique};
use crate::vocab::{Fidelity, FieldError};
use crate::volume::Limits;

/// Which technique and its parameters; in TOML a `[technique.NAME]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum TechniqueScene {
    /// The full-screen quad demo.
    Quad(QuadScene),
    /// v3o2's 3D opacity (boxed: it is much larger than the other variants).
    Opacity3d(Box<Opacity3dScene>),
    /// Isosurfaces of tetrahedral meshes by cell projection.
    Cellproj(Box<CellprojScene>),
    /// Point-based rendering of geological sections as splats.
    Splats(Box<SplatsScene>),
}

macro_rules! from_parameters {
    ($($variant:ident($type:ty) => $wrap:expr),*) => {$(
        impl From<$type> for TechniqueScene {
            /// The technique of these parameters.
            fn from(p: $type) -> TechniqueScene {
                TechniqueScene::$variant($wrap(p))
            }
        }
    )*};
}

from_parameters!(
    Quad(QuadScene) => std::convert::identity,
    Opacity3d(Opacity3dScene) => Box::new,
    Cellproj(CellprojScene) => Box::new,
    Splats(SplatsScene) => Box::new
);

/// `$body` with `$p` bound to the parameters of whichever technique `$scene` holds (`&T`,
/// or `&mut T` with `mut`): the one place that lists the variants for the methods below.
macro_rules! each_technique {
    ($scene:expr, |$p:ident| $body:expr) => {
        match $scene {
            TechniqueScene::Quad($p) => $body,
            TechniqueScene::Opacity3d(boxed) => {
                let $p = &**boxed;
                $body
            }
            TechniqueScene::Cellproj(boxed) => {
                let $p = &**boxed;
                $body
            }
            TechniqueScene::Splats(boxed) => {
                let $p = &**boxed;
                $body
            }
        }
    };
    ($scene:expr, |mut $p:ident| $body:expr) => {
        match $scene {
            TechniqueScene::Quad($p) => $body,
            TechniqueScene::Opacity3d(boxed) => {
                let $p = &mut **boxed;
                $body
            }
            TechniqueScene::Cellproj(boxed) => {
                let $p = &mut **boxed;
                $body
            }
            TechniqueScene::Splats(boxed) => {
                let $p = &mut **boxed;
                $body
            }
        }
    };
}

/// The technique's name and its [`Technique`] implementation's answer, for a `T` known
/// only by the trait.
fn name_of<T: Technique>(_: &T) -> &'static str {
    T::NAME
}

impl TechniqueScene {
    /// Technique name as written in scenes.
    pub fn name(&self) -> &'static str {
        each_technique!(self, |p| name_of(p))
    }

    /// The parameters as a renderer's [`Renderer::update`] takes them.
    pub fn params(&self) -> Params<'_> {
        each_technique!(self, |p| Params::of(p))
    }

    /// The parameters, of whichever technique (for a list of capabilities kept above
    /// the catalog, such as the viewer's faces).
    pub fn parameters(&self) -> &dyn Any {
        each_technique!(self, |p| p as &dyn Any)
    }

    /// [`TechniqueScene::parameters`], to change.
    pub fn parameters_mut(&mut self) -> &mut dyn Any {
        each_technique!(self, |mut p| p as &mut dyn Any)
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
        let within = format!("technique.{}", self.name());
        each_technique!(self, |p| Technique::validate(p, fidelity, programs))
            .map_err(|e| e.within(&within))
    }

    /// Call `f` on every data file the parameters name, with the dotted key that holds
    /// it (from the scene's root).
    pub fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        let within = format!("technique.{}", self.name());
        let f = &mut |key: &str, path: &mut PathBuf| f(&format!("{within}.{key}"), path);
        each_technique!(self, |mut p| Technique::for_each_data_path(p, f))
    }

    /// The camera a scene without `[camera]` starts from (and the viewer's Reset camera
    /// returns to), where the technique's data asks for another than the default.
    pub fn default_camera(&self) -> Option<Camera> {
        each_technique!(self, |p| Technique::default_camera(p))
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
        each_technique!(self, |mut p| Technique::unwritten_defaults(
            p, written, camera, fidelity
        ))
    }

    /// The technique as the frames drawn while the user interacts draw it, at
    /// 1/`divisor` of the image's resolution ([`Technique::for_interaction`]).
    pub fn for_interaction(&self, scale: f64) -> TechniqueScene {
        let mut reduced = self.clone();
        each_technique!(&mut reduced, |mut p| Technique::for_interaction(p, scale));
        reduced
    }

    /// The large allocations preparing and drawing it at `size` makes that the scene
    /// alone determines (generated data, grids, lists); files are checked by their loaders.
    pub fn memory_estimate(&self, size: [u32; 2]) -> Vec<crate::budget::Estimate> {
        each_technique!(self, |p| Technique::memory_estimate(p, size))
    }
}

/// Build the renderer for `technique`, with programs of `kind`; nothing else is created.
pub fn build(
    gpu: &Gpu,
    technique: &TechniqueScene,
    settings: &Settings<'_>,
    kind: ProgramKind,
) -> RenderResult<Box<dyn Renderer>> {
    each_technique!(technique, |p| Technique::build(p, gpu, settings, kind))
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
    fn of<T: Technique>(
        t: &T,
        settings: &Settings<'_>,
        limits: &Limits,
        view: &ReferenceView<'_>,
    ) -> RenderResult<Option<Image>> {
        Ok(t.reference(&t.prepare(settings, limits)?, view))
    }
    each_technique!(technique, |p| of(p, settings, limits, view))
}

/// Check `technique`'s parameters, then load and prepare its data within `limits`
/// ([`Technique::prepare`]).
pub fn prepare(
    technique: &TechniqueScene,
    settings: &Settings<'_>,
    limits: &Limits,
) -> RenderResult<PreparedData> {
    each_technique!(technique, |p| Technique::prepare(p, settings, limits)
        .map(|d| Box::new(d) as PreparedData))
}

/// The renderer of what [`prepare`] made for `technique`, with programs of `kind`.
pub fn renderer(
    technique: &TechniqueScene,
    gpu: &Gpu,
    settings: &Settings<'_>,
    kind: ProgramKind,
    prepared: PreparedData,
) -> RenderResult<Box<dyn Renderer>> {
    each_technique!(technique, |p| renderer_of(p, gpu, settings, kind, prepared))
}

/// [`Technique::renderer`] of `prepared`, which must be `T`'s.
fn renderer_of<T: Technique>(
    technique: &T,
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
    technique.renderer(gpu, settings, kind, *prepared)
}

/// Every program pair the techniques can draw with, both kinds (the compile-everything
/// test): each technique lists its own.
pub fn all_program_pairs() -> Vec<ProgramPair> {
    let mut pairs = QuadScene::program_pairs();
    pairs.extend(Opacity3dScene::program_pairs());
    pairs.extend(CellprojScene::program_pairs());
    pairs.extend(SplatsScene::program_pairs());
    pairs
}
