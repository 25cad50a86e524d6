//! Every technique in one list, where each registers what the layers above need: its
//! scene parameters (a variant of [`TechniqueScene`], `[technique.NAME]` in TOML), how its
//! renderer is built ([`build`]) and the program pairs it can draw with
//! ([`all_program_pairs`], for the compile-everything test).
//!
//! The catalog sits above the techniques and below the scene: techniques never import it
//! (their renderers take their own parameters through [`crate::techniques::Params`]), so
//! adding a technique touches its own folder and this file.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::camera::Projection;
use crate::gl::{GlResult, Gpu, ProgramChoice, ProgramKind};
use crate::programs::ProgramPair;
use crate::techniques::cellproj::{self, CellprojScene};
use crate::techniques::opacity3d::{self, Opacity3dScene};
use crate::techniques::quad::{self, QuadScene};
use crate::techniques::splats::{self, SplatsScene};
use crate::techniques::{Params, Renderer};
use crate::vocab::Fidelity;

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

impl TechniqueScene {
    /// Technique name as written in scenes.
    pub fn name(&self) -> &'static str {
        match self {
            TechniqueScene::Quad(_) => "quad",
            TechniqueScene::Opacity3d(_) => "opacity3d",
            TechniqueScene::Cellproj(_) => "cellproj",
            TechniqueScene::Splats(_) => "splats",
        }
    }

    /// The parameters as a renderer's [`Renderer::update`] takes them.
    pub fn params(&self) -> Params<'_> {
        match self {
            TechniqueScene::Quad(p) => Params::of(p),
            TechniqueScene::Opacity3d(p) => Params::of(&**p),
            TechniqueScene::Cellproj(p) => Params::of(&**p),
            TechniqueScene::Splats(p) => Params::of(&**p),
        }
    }
}

impl TechniqueScene {
    /// The camera a scene without `[camera]` starts from (and the viewer's Reset camera
    /// returns to), where the technique's data asks for another than the default.
    pub fn default_camera(&self) -> Option<crate::camera::Camera> {
        match self {
            TechniqueScene::Opacity3d(p) => p.default_camera(),
            TechniqueScene::Quad(_) | TechniqueScene::Cellproj(_) | TechniqueScene::Splats(_) => {
                None
            }
        }
    }

    /// Defaults that depend on the data a scene names, for the keys its text leaves out
    /// (`written` tells which dotted keys it writes): a survey's three-quarter view where
    /// there is no `[camera]`, a lidar cloud's precise splats, and so on
    /// ([`Opacity3dScene::unwritten_defaults`], [`SplatsScene::unwritten_defaults`]).
    pub fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut crate::camera::Camera,
        fidelity: &mut Fidelity,
    ) {
        match self {
            TechniqueScene::Opacity3d(p) => p.unwritten_defaults(written, camera),
            TechniqueScene::Splats(p) => p.unwritten_defaults(written, fidelity),
            TechniqueScene::Quad(_) | TechniqueScene::Cellproj(_) => {}
        }
    }

    /// The large allocations preparing and drawing it at `size` makes that the scene
    /// alone determines (generated data, grids, lists); files are checked by their loaders.
    pub fn memory_estimate(&self, size: [u32; 2]) -> Vec<crate::budget::Estimate> {
        match self {
            TechniqueScene::Quad(_) => Vec::new(),
            TechniqueScene::Opacity3d(p) => p.memory_estimate(),
            TechniqueScene::Cellproj(p) => p.memory_estimate(),
            TechniqueScene::Splats(p) => p.memory_estimate(size),
        }
    }
}

/// What a renderer needs of the scene besides its own parameters.
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
    /// The first view (camera and image size): what a COPC cloud's nodes are chosen for.
    pub view: crate::points::copc_lod::View,
}

/// Build the renderer for `technique`, with programs of `kind`; nothing else is created.
pub fn build(
    gpu: &Gpu,
    technique: &TechniqueScene,
    settings: &Settings<'_>,
    kind: ProgramKind,
) -> GlResult<Box<dyn Renderer>> {
    let Settings {
        fidelity,
        programs,
        base,
        projection,
        view,
    } = *settings;
    Ok(match technique {
        TechniqueScene::Quad(params) => Box::new(quad::QuadRenderer::new(gpu, kind, params)?),
        TechniqueScene::Opacity3d(params)
            if opacity3d::bricked::store_of(params)
                .map_err(crate::gl::GlError::Data)?
                .is_some() =>
        {
            // Precise draws a store with a GLSL ray caster: `auto` takes GLSL there.
            let kind = if fidelity == crate::vocab::Fidelity::Precise
                && programs == crate::gl::ProgramChoice::Auto
            {
                crate::gl::ProgramKind::Glsl
            } else {
                kind
            };
            Box::new(opacity3d::bricked::BrickedRenderer::new(
                gpu, kind, fidelity, params, base, None,
            )?)
        }
        TechniqueScene::Opacity3d(params) => Box::new(opacity3d::Opacity3dRenderer::new(
            gpu,
            opacity3d::renderer::resolve_kind(gpu, params, fidelity, programs, kind)?,
            fidelity,
            params,
            base,
            projection,
        )?),
        TechniqueScene::Splats(params) => Box::new(splats::SplatsRenderer::new(
            gpu,
            kind,
            fidelity,
            params,
            base,
            Some(view),
        )?),
        TechniqueScene::Cellproj(params) => Box::new(cellproj::CellprojRenderer::new(
            gpu, kind, fidelity, params, base,
        )?),
    })
}

/// Every program pair the techniques can draw with, both kinds (the compile-everything
/// test): each technique lists its own.
pub fn all_program_pairs() -> Vec<ProgramPair> {
    let mut pairs = quad::program_pairs();
    pairs.extend(opacity3d::renderer::program_pairs());
    pairs.extend(cellproj::renderer::program_pairs());
    pairs.extend(splats::renderer::program_pairs());
    pairs
}
