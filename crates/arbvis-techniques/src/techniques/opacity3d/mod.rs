//! v3o2's 3D opacity (seed `000_7bcb64b2a3c67198.txt`): up to three attribute volumes of
//! one block, each quantized to 0..255 and packed in one RGB 3D texture on unit 0
//! (G primary, B secondary, R tertiary), a 256-entry colour table per attribute on units
//! 2/3/4, twelve coefficients in `program.local[1..3]`, combined by the verbatim sum
//! (eq. 1, a union) or product (eqs. 2-3, an intersection) `!!ARBfp1.0` program, drawn as
//! view-aligned slices back to front with "over" blending.
//!
//! # How it works
//! 1. [`prepare`] (CPU, no GL): load each attribute's volume (SEG-Y, NIfTI, raw,
//!    synthetic), derive the attribute (envelope, phase, ...), quantize, pack RGB, build
//!    the tables.
//! 2. [`renderer`] uploads them and draws with the program of the fidelity and path
//!    ([`programs`]): faithful, the verbatim text on slices ([`slicing`]) perpendicular
//!    to the view direction, far to near; precise, a program generated for the scene
//!    (only the attributes present) either on the same slices or, with
//!    `[technique.opacity3d.raycast]`, as a single-pass GLSL ray caster whose rays
//!    are clipped to the box of the occupied bricks ([`bricks`]; optionally skipping
//!    the empty bricks inside it too) and stop early once opaque.
//!    With `[technique.opacity3d.clip]` ([`clipping`], seed 002) every program has the
//!    clip test composed in (the verbatim ARB text kept byte for byte after the clip's
//!    prologue) and only what lies inside the clip object is drawn.
//! 3. [`reference`] computes the same image on the CPU: the exact emission-absorption
//!    integral in f64 (what precise mode aims at; with a clip, only inside the analytic
//!    clip object), a mirror of precise slicing at the
//!    GPU's sample points, and an emulation of the faithful 8-bit pipeline (what v3o2
//!    showed).
//!
//! # Decisions the seed leaves open (DESIGN §3)
//! - Blending: `SRC_ALPHA, ONE_MINUS_SRC_ALPHA`, back to front (the usual choice for
//!   non-premultiplied slice colours); the target's alpha is therefore not coverage.
//! - Filtering: the volume is LINEAR (interpolate quantized values, then look up: post-
//!   classification); tables are LINEAR by default, so the original addressing
//!   `coord = k/255` into 256 texels blends neighbouring entries (`table_filter`).
//! - Missing attributes (1D / 2D opacity): R (and B) are 0, as Silva did; no table is
//!   built for them. Their coefficients are forced to 0 in a sum (no contribution) and, in
//!   a product, a 1x1 white table is bound with coefficients 1 (neutral).
//! - Precise mode: the levels in 16-bit unorm (k/255 exactly) and f32 tables, texel-centre
//!   lookup, exact 1/3 and a clamp to [0, 1], and each sample's exact opacity
//!   `a' = 1 - (1 - a)^(h / reference)` for the length `h` of ray it stands for, the
//!   reference spacing being one voxel along the longest axis. On slices `h` is computed
//!   per fragment: the spacing along the ray (over the cosine to the view axis in
//!   perspective), and at each end of a ray the piece up to where it enters or leaves the
//!   box, so the slabs tile every chord and the error falls at second order in every view.
//!   The ray caster cuts each chord into equal steps as the reference does.
//!
//! # Extremes (DESIGN §4), each with a test
//! Coefficients 0, 1 and above 1 (faithful: the 8-bit target clamps; precise: clamped in
//! the program); tables with alpha 0 / 1; one slice and thousands; a 1-voxel volume and a
//! 1 x N volume; constant attributes (all quantize to 0); NaN samples (quantize to 0);
//! volumes of different grids (an error naming both).

pub mod brick_cache;
pub mod brick_ranges;
pub mod bricked;
pub mod bricks;
pub mod changes;
pub mod clipping;
pub mod error;
pub mod locals;
pub mod mirror;
pub mod paged;
pub mod preint;
pub mod prepare;
pub mod programs;
pub mod proxy;
pub mod reference;
pub mod renderer;
pub mod slicing;
pub mod textures;

use serde::{Deserialize, Serialize};

use crate::techniques::clip::ClipSpec;
use arbvis_core::colortable::TableSpec;
pub use arbvis_core::vocab::Interpolation;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::volume::attributes::Attribute;
use arbvis_data::volume::quantize::Quantization;
use arbvis_data::volume::VolumeSource;
use arbvis_gl::{Filter, ProgramChoice};

pub use renderer::Opacity3dRenderer;

/// What 3D opacity prepares: the volume read whole, or for a survey store (read brick by
/// brick by its renderer) only where it lies.
#[derive(Debug)]
pub struct Prepared3d {
    /// The volume, read whole; `None` for a store.
    pub whole: Option<prepare::Prepared>,
    /// A store's place in the world (`None` for a window of it).
    pub store_world: Option<crate::techniques::world::World>,
}

/// Sum (eq. 1) or product (eqs. 2-3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// `C = (C1 R1 + C2 R2 + C3 R3) * 0.3333`: the union of the regions of interest.
    #[default]
    Sum,
    /// `C = C1 R1 * C2 R2 * C3 R3`: their intersection.
    Product,
}

/// One attribute: where its volume comes from, which attribute of it, how it is
/// quantized, its table and its four coefficients.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttributeScene {
    /// The volume.
    pub volume: VolumeSource,
    /// Derived attribute of that volume (amplitude = the samples themselves).
    #[serde(default)]
    pub attribute: Attribute,
    /// Quantization range.
    #[serde(default)]
    pub quantize: Quantization,
    /// Colour table.
    #[serde(default)]
    pub table: TableSpec,
    /// `[Cr, Cg, Cb, Ca]`, nominally in [0, 1].
    #[serde(default = "unit_coefficients")]
    pub coefficients: [f64; 4],
}

fn unit_coefficients() -> [f64; 4] {
    [1.0; 4]
}

/// A survey seen from above and to the side, sample (time) axis down the screen, inlines
/// and crosslines receding: the rotation `scenes/data/f3.toml` was composed with.
pub const SURVEY_VIEW: [f64; 4] = [0.326506, -0.092296, -0.701057, 0.627211];

/// A three-quarter view of a survey ([`SURVEY_VIEW`]), zoomed so that a box of any
/// proportions stays whole at any rotation.
pub(crate) fn survey_camera() -> arbvis_core::camera::Camera {
    arbvis_core::camera::Camera {
        rotation: SURVEY_VIEW,
        // The prepared box's longest half side is 1, so its bounding sphere's radius is at
        // most sqrt(3); with the viewer's 10 % framing margin.
        zoom: 0.9 / 3f64.sqrt(),
        ..Default::default()
    }
}

/// `[technique.opacity3d]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Opacity3dScene {
    /// Sum or product.
    #[serde(default)]
    pub combine: Combine,
    /// Number of view-aligned slices.
    #[serde(default = "default_slices")]
    pub slices: usize,
    /// Filtering of the packed volume.
    #[serde(default = "linear")]
    pub volume_filter: Filter,
    /// Filtering of the colour tables.
    #[serde(default = "linear")]
    pub table_filter: Filter,
    /// Precise mode: where texture filtering and sample positions are computed.
    #[serde(default)]
    pub interpolation: Interpolation,
    /// Opacity correction; by default on when precise, off when faithful (which has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opacity_correction: Option<bool>,
    /// Voxel size along i, j, k, overriding the files' (SEG-Y has no common unit for
    /// time and distance: this sets the box's aspect).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<[f64; 3]>,
    /// How much taller than the file's own proportions the samples' axis is drawn (SEG-Y:
    /// one millisecond of two-way time as one metre, times this); ignored where `spacing`
    /// is set. Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertical_exaggeration: Option<f64>,
    /// The primary attribute (G, table on unit 2).
    pub primary: AttributeScene,
    /// The secondary attribute (B, unit 3); absent for 1D opacity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub secondary: Option<AttributeScene>,
    /// The tertiary attribute (R, unit 4); absent for 1D and 2D opacity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tertiary: Option<AttributeScene>,
    /// Precise mode's single-pass ray caster (`[technique.opacity3d.raycast]`, GLSL);
    /// absent, precise mode slices. Faithful mode always slices.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raycast: Option<Raycast>,
    /// A clip object (`[technique.opacity3d.clip]`, seed 002): only what lies inside it
    /// (outside with `invert`) is drawn.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip: Option<ClipSpec>,
    /// How a survey store is streamed (`[technique.opacity3d.store]`; for attributes whose
    /// volume is `{ store = "..." }`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub store: Option<bricked::StoreView>,
}

impl crate::techniques::Technique for Opacity3dScene {
    const NAME: &'static str = "opacity3d";
    const STUDIES: &'static [(&'static str, &'static str)] = &[
        (
            "opacity3d",
            "v3o2's 3D opacity: slice counts, targets, opacity correction, program kinds",
        ),
        (
            "clip",
            "volume clipping: clip grid sizes, shapes and block sizes (bytes, ratio, build time), and frame times with no clip, the single texture and INDEX-DATA",
        ),
    ];
    const DEMOS: &'static [(&'static str, &'static str)] = &[
        crate::techniques::demo!("v3o2-sum"),
        crate::techniques::demo!("v3o2-product"),
        crate::techniques::demo!("clip-sphere"),
        crate::techniques::demo!("clip-mesh"),
    ];

    fn validate(&self, _: Fidelity, _: ProgramChoice) -> Result<(), FieldError> {
        Opacity3dScene::validate(self)
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut std::path::PathBuf)) {
        for (attr, name) in self.attributes_mut().into_iter().zip(ATTRIBUTE_NAMES) {
            let Some(attr) = attr else { continue };
            let kind = attr.volume.kind();
            if let Some(p) = attr.volume.path_mut() {
                f(&format!("{name}.volume.{kind}"), p);
            }
            if let Some(p) = &mut attr.table.file {
                f(&format!("{name}.table.file"), p);
            }
        }
        if let Some(clip) = &mut self.clip {
            clip.shape.for_each_path(&mut |p| f("clip.shape", p));
        }
    }

    fn memory_estimate(&self, _: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        Opacity3dScene::memory_estimate(self)
    }

    fn default_camera(&self) -> Option<arbvis_core::camera::Camera> {
        Opacity3dScene::default_camera(self)
    }

    fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut arbvis_core::camera::Camera,
        _: &mut Fidelity,
    ) {
        Opacity3dScene::unwritten_defaults(self, written, camera)
    }

    /// The slice count divided by `scale` (at least one).
    fn for_interaction(&mut self, scale: f64) {
        self.slices = ((self.slices as f64 / scale.max(1.0)) as usize).max(1);
    }

    fn program_pairs() -> Vec<crate::programs::ProgramPair> {
        renderer::program_pairs()
    }

    /// The volume prepared whole; `None` for a survey store, streamed by its renderer.
    type Prepared = Prepared3d;

    fn prepare(
        &self,
        settings: &crate::techniques::Settings<'_>,
        limits: &arbvis_data::volume::Limits,
    ) -> crate::error::RenderResult<Prepared3d> {
        if let Some(store) = bricked::StoreScene::open(self, settings.base)? {
            return Ok(Prepared3d {
                whole: None,
                store_world: store.world()?,
            });
        }
        Opacity3dScene::validate(self)?;
        let whole = prepare::prepare(self, settings.base, limits)?;
        Ok(Prepared3d {
            whole: Some(whole),
            store_world: None,
        })
    }

    /// The primary attribute's colour through its table where each point lies (a
    /// horizon coloured by its survey).
    fn colours_at(
        &self,
        prepared: &Prepared3d,
        points: &[glam::DVec3],
    ) -> Option<Vec<Option<[f64; 3]>>> {
        let p = prepared.whole.as_ref()?;
        Some(points.iter().map(|&x| p.primary_colour_at(x)).collect())
    }

    /// The ray caster runs each ray through the whole box: precise slices instead.
    fn occludable(&mut self) {
        self.raycast = None;
    }

    /// A survey hangs from the origin with its samples downwards (a store as the survey
    /// read whole); other volumes keep their grid's axes, first voxel at the origin. None
    /// for a window of a store.
    fn world(&self, prepared: &Prepared3d) -> Option<crate::techniques::world::World> {
        use crate::techniques::world::World;
        let Some(p) = prepared.whole.as_ref() else {
            return prepared.store_world;
        };
        if self.primary.volume.data_kind() == arbvis_data::sniff::DataKind::Survey {
            return Some(World::of_survey(p.dims, p.size, p.half, p.map.as_ref()));
        }
        Some(World::of_box([0.0; 3], p.size.to_array()))
    }

    /// A survey store is drawn brick by brick ([`bricked::BrickedRenderer`]; precise
    /// with a GLSL ray caster, which `auto` then takes); other volumes whole.
    /// The f64 integral along each pixel's ray ([`reference::reference`], 8 samples per
    /// reference spacing); none for a store (drawn brick by brick) or a clipped scene.
    fn reference(
        &self,
        prepared: &Prepared3d,
        view: &crate::techniques::ReferenceView<'_>,
    ) -> Option<arbvis_core::image::Image> {
        let prepared = prepared.whole.as_ref().filter(|_| self.clip.is_none())?;
        Some(reference::reference(
            prepared,
            self,
            &view.camera,
            view.size,
            view.background,
            8.0,
        ))
    }

    fn renderer(
        &self,
        gpu: &arbvis_gl::Gpu,
        settings: &crate::techniques::Settings<'_>,
        kind: arbvis_gl::ProgramKind,
        prepared: Prepared3d,
    ) -> crate::error::RenderResult<Box<dyn crate::techniques::Renderer>> {
        let fidelity = settings.fidelity;
        let Some(prepared) = prepared.whole else {
            let kind = if fidelity == Fidelity::Precise && settings.programs == ProgramChoice::Auto
            {
                arbvis_gl::ProgramKind::Glsl
            } else {
                kind
            };
            return Ok(Box::new(bricked::BrickedRenderer::new(
                gpu,
                kind,
                fidelity,
                self,
                settings.base,
                None,
            )?));
        };
        let kind = renderer::resolve_kind(gpu, self, fidelity, settings.programs, kind)?;
        Ok(Box::new(Opacity3dRenderer::from_prepared(
            gpu,
            kind,
            fidelity,
            self,
            settings.base,
            prepared,
            settings.projection,
        )?))
    }
}

/// Memory per voxel of each generated attribute while it is prepared and drawn: the f32
/// samples, the derived attribute, the quantized levels, the packed texture and its GPU
/// copy; the growth of peak resident memory per voxel with one attribute, faithful and
/// precise alike, rounded up (measured: docs/benchmarks.md, "Memory estimates and work
/// limits").
pub const BYTES_PER_VOXEL: u64 = 12;

impl Opacity3dScene {
    /// The large allocations this scene makes that the scene alone determines (generated
    /// volumes, the clip's grid); volume files are held to the budget by their loaders
    /// once their headers are read.
    pub fn memory_estimate(&self) -> Vec<arbvis_core::budget::Estimate> {
        let mut out = Vec::new();
        let mut grid = None;
        for (name, attribute) in ATTRIBUTE_NAMES.iter().zip(self.attributes()) {
            let Some(a) = attribute else { continue };
            if let Some(voxels) = a.volume.declared_voxels() {
                out.push(arbvis_core::budget::Estimate::of(
                    format!("the {name} attribute's generated volume of {voxels} voxels"),
                    voxels,
                    BYTES_PER_VOXEL,
                ));
            }
            grid = grid.or(a.volume.declared_dims());
        }
        if let Some(clip) = &self.clip {
            if let Some(dims) = clip.resolution.or(grid) {
                out.extend(clip.memory_estimate(dims));
            }
        }
        out
    }
}

/// `[technique.opacity3d.raycast]`: how the precise ray caster samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Raycast {
    /// Samples per reference spacing (one voxel along the longest axis); each ray's chord
    /// is cut into equal steps no longer than that.
    pub steps_per_voxel: f64,
    /// A ray stops once its alpha reaches `1 - termination` (0: never); what it leaves out
    /// is at most that much of what lies behind.
    pub termination: f64,
    /// Voxels per side of the bricks of empty-space skipping (0: no skipping; point
    /// sampling only). Off by default: on the bench scenes few bricks are empty and the
    /// per-brick bookkeeping made frames slower than it saved (measured:
    /// docs/benchmarks.md, "3D opacity: figures behind its settings").
    pub brick: usize,
    /// Pre-integrated classification for a one-attribute scene ([`preint`]); ignored
    /// with several attributes or without opacity correction. Off by default: it wins
    /// where the table has more detail than the data (2 to 3 times less error on random
    /// tables), but on the bench scene's smooth table the data's own curvature dominates
    /// and point sampling reached lower error per millisecond. Ignored with a clip.
    pub preintegrate: bool,
    /// Offset each pixel's steps by a per-pixel fraction of a step (point sampling, no
    /// skipping): where the step divides the voxel spacing (axis-aligned views at 0.5, 1,
    /// 2 steps/voxel) every ray otherwise samples its cells at the same place, and the
    /// error of those settings rises above that of fewer steps.
    pub jitter: bool,
    /// Clip each ray to the box of the bricks where some sample can have alpha above 0
    /// ([`bricks::Bricks::occupied_box`]): the clear margins around the data (the air
    /// around a head, the padding of a survey) are not sampled, and no pixel changes
    /// (every sample left out has alpha 0). Point sampling, with or without jitter.
    pub margins: bool,
    /// With jitter and one attribute: full steps read their colour and opacity from a
    /// table baked for the step (no `pow` per sample), where that table is within 1e-5 of
    /// the exact model ([`preint::baked`]). Ignored with a clip (a clipped scene tests
    /// every sample).
    pub bake: bool,
}

impl Default for Raycast {
    fn default() -> Self {
        Raycast {
            steps_per_voxel: 1.0,
            termination: 1.0 / 4096.0,
            brick: 0,
            preintegrate: false,
            jitter: true,
            margins: true,
            bake: true,
        }
    }
}

/// Most samples per voxel the ray caster accepts.
pub const MAX_STEPS_PER_VOXEL: f64 = 1024.0;

fn default_slices() -> usize {
    256
}

fn linear() -> Filter {
    Filter::Linear
}

/// Largest slice count accepted (a 16k-slice stack is already far past any use).
pub const MAX_SLICES: usize = 16384;

impl Opacity3dScene {
    /// The attributes in texture order: primary, secondary, tertiary.
    pub fn attributes(&self) -> [Option<&AttributeScene>; 3] {
        [
            Some(&self.primary),
            self.secondary.as_ref(),
            self.tertiary.as_ref(),
        ]
    }

    /// Mutable [`Opacity3dScene::attributes`].
    pub fn attributes_mut(&mut self) -> [Option<&mut AttributeScene>; 3] {
        [
            Some(&mut self.primary),
            self.secondary.as_mut(),
            self.tertiary.as_mut(),
        ]
    }

    /// Defaults for a survey (a primary volume whose reader yields one: SEG-Y, a store, an
    /// MDIO dataset) where the scene's text leaves the key out (`written` tells which
    /// dotted keys it writes):
    /// - no `[camera]`: a three-quarter view from above with time running down the
    ///   screen ([`SURVEY_VIEW`]), zoomed so that a box of any proportions stays whole at
    ///   any rotation;
    /// - one attribute and no `combine`: `product`, whose absent attributes read as a
    ///   neutral 1 (the sum program divides the one colour by 3);
    /// - no `quantize`, where the survey is read whole (not a store, which quantizes by
    ///   the ranges it keeps): the 1st to 99th percentiles, so that a few spikes do not
    ///   squeeze every other amplitude into the table's middle.
    pub fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        camera: &mut arbvis_core::camera::Camera,
    ) {
        if self.primary.volume.data_kind() != arbvis_data::sniff::DataKind::Survey {
            return;
        }
        if !written("camera") {
            *camera = survey_camera();
        }
        let one = self.secondary.is_none() && self.tertiary.is_none();
        if one && !written("technique.opacity3d.combine") {
            self.combine = Combine::Product;
        }
        if matches!(self.primary.volume, VolumeSource::Store(_)) {
            return;
        }
        let names = ATTRIBUTE_NAMES;
        for (attr, name) in self.attributes_mut().into_iter().zip(names) {
            let Some(attr) = attr else { continue };
            if !written(&format!("technique.opacity3d.{name}.quantize")) {
                attr.quantize = Quantization::Percentile([1.0, 99.0]);
            }
        }
    }

    /// The camera a survey's scene starts from (and the viewer's Reset camera returns
    /// to); `None` for other volumes, which keep [`arbvis_core::camera::Camera::default`].
    pub fn default_camera(&self) -> Option<arbvis_core::camera::Camera> {
        (self.primary.volume.data_kind() == arbvis_data::sniff::DataKind::Survey)
            .then(survey_camera)
    }

    /// The voxel size drawn: the scene's `spacing`, else the file's with the samples'
    /// axis stretched by `vertical_exaggeration`.
    pub fn spacing_for(&self, file_spacing: [f64; 3]) -> [f64; 3] {
        self.spacing.unwrap_or_else(|| {
            let [s, j, k] = file_spacing;
            [s * self.vertical_exaggeration.unwrap_or(1.0), j, k]
        })
    }

    /// Check values that parse but cannot render; the error names the key.
    pub fn validate(&self) -> Result<(), FieldError> {
        if !(1..=MAX_SLICES).contains(&self.slices) {
            return Err(FieldError::new(
                "slices",
                format!("slices = {}: must be 1..={MAX_SLICES}", self.slices),
            ));
        }
        if let Some(s) = self.spacing {
            if s.iter().any(|v| !v.is_finite() || *v <= 0.0) {
                return Err(FieldError::new(
                    "spacing",
                    format!("{s:?}: must be positive"),
                ));
            }
        }
        if let Some(e) = self.vertical_exaggeration {
            if !(e.is_finite() && e > 0.0 && e <= 1000.0) {
                return Err(FieldError::new(
                    "vertical_exaggeration",
                    format!("{e}: must be positive, at most 1000"),
                ));
            }
        }
        if let Some(r) = &self.raycast {
            if !(r.steps_per_voxel > 0.0 && r.steps_per_voxel <= MAX_STEPS_PER_VOXEL) {
                return Err(FieldError::new(
                    "raycast.steps_per_voxel",
                    format!(
                        "{}: must be above 0 and at most {MAX_STEPS_PER_VOXEL}",
                        r.steps_per_voxel
                    ),
                ));
            }
            if !(0.0..1.0).contains(&r.termination) {
                return Err(FieldError::new(
                    "raycast.termination",
                    format!("{}: must be in [0, 1)", r.termination),
                ));
            }
            if r.brick > 256 {
                return Err(FieldError::new(
                    "raycast.brick",
                    format!("{}: must be at most 256 (0: no skipping)", r.brick),
                ));
            }
        }
        if let Some(clip) = &self.clip {
            clip.validate().map_err(|e| e.within("clip"))?;
        }
        if let Some(store) = &self.store {
            store.validate().map_err(|e| e.within("store"))?;
        }
        for (name, a) in ATTRIBUTE_NAMES.iter().zip(self.attributes()) {
            if let Some(a) = a {
                if a.coefficients.iter().any(|c| !c.is_finite() || *c < 0.0) {
                    return Err(FieldError::new(
                        format!("{name}.coefficients"),
                        format!("{:?}: must be finite and not negative", a.coefficients),
                    ));
                }
                a.table
                    .validate()
                    .map_err(|e| e.within(&format!("{name}.table")))?;
                a.volume
                    .validate()
                    .map_err(|e| e.within(&format!("{name}.volume")))?;
            }
        }
        Ok(())
    }
}

/// The attributes' names in scenes, in texture order.
pub const ATTRIBUTE_NAMES: [&str; 3] = ["primary", "secondary", "tertiary"];

/// How a scene is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path3d {
    /// View-aligned slices (faithful, or precise without `raycast`).
    Slicing,
    /// Precise single-pass ray casting (GLSL).
    Raycast,
}

/// The path `params` asks for at `fidelity`.
pub fn path(params: &Opacity3dScene, fidelity: Fidelity) -> Path3d {
    if fidelity == Fidelity::Precise && params.raycast.is_some() {
        Path3d::Raycast
    } else {
        Path3d::Slicing
    }
}

/// Whether the ray caster pre-integrates: one attribute, opacity correction on,
/// `raycast.preintegrate`
/// and no clip (whole steps would skip the per-sample clip test).
pub fn preintegrated(params: &Opacity3dScene, fidelity: Fidelity, attributes: usize) -> bool {
    path(params, fidelity) == Path3d::Raycast
        && attributes == 1
        && params.clip.is_none()
        && corrected(params, fidelity)
        && params.raycast.is_some_and(|r| r.preintegrate)
}

/// The coefficient vectors sent to `program.local[1..3]`: the scene's for present
/// attributes; for absent ones 0 in a sum and 1 in a product (neutral either way).
pub fn coefficients(params: &Opacity3dScene) -> [[f64; 4]; 3] {
    let absent = match params.combine {
        Combine::Sum => [0.0; 4],
        Combine::Product => [1.0; 4],
    };
    params
        .attributes()
        .map(|a| a.map_or(absent, |a| a.coefficients))
}

/// Whether opacity correction is on (by default when precise).
pub fn corrected(params: &Opacity3dScene, fidelity: Fidelity) -> bool {
    params
        .opacity_correction
        .unwrap_or(fidelity == Fidelity::Precise)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_raycast(text: &str) -> Result<(), FieldError> {
        let scene = crate::scene::Scene::demo("v3o2-sum").unwrap();
        let crate::scene::TechniqueScene::Opacity3d(mut params) = scene.technique else {
            unreachable!()
        };
        params.raycast =
            Some(toml::from_str(text).map_err(|e| FieldError::new("toml", e.to_string()))?);
        params.validate()
    }

    #[test]
    fn raycast_options_are_checked() {
        assert!(with_raycast("").is_ok());
        assert!(with_raycast("steps_per_voxel = 0.25\ntermination = 0.0\nbrick = 0").is_ok());
        for (text, key) in [
            ("steps_per_voxel = 0.0", "raycast.steps_per_voxel"),
            ("steps_per_voxel = nan", "raycast.steps_per_voxel"),
            ("steps_per_voxel = 1e9", "raycast.steps_per_voxel"),
            ("termination = 1.0", "raycast.termination"),
            ("termination = -0.1", "raycast.termination"),
            ("brick = 1000", "raycast.brick"),
        ] {
            let e = with_raycast(text).unwrap_err();
            assert_eq!(e.key, key, "{text}");
        }
        assert!(
            with_raycast("bricks = 4").is_err(),
            "unknown keys are errors"
        );
    }
}
