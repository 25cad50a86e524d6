//! Point-based rendering of geological sections (seed 004): every point a `GL_POINT`
//! splat sized by its distance to the eye, its alpha falling off from the centre,
//! blended back to front over the others.
//!
//! # How it works (the CPU part)
//!
//! - **Order** ([`sort`]): transparent splats need back-to-front order (the depth test
//!   would discard what should blend), so each frame the camera moved the points are
//!   sorted by their distance to the eye (orthographic: depth along the view). The
//!   seed sorted its point structs with `std::sort` and a comparator computing both
//!   distances (slow: docs/benchmarks.md, "Figures behind the splats' settings"), then
//!   re-uploaded the whole buffer; kept here as [`sort::SortMethod::Seed`], the
//!   baseline. The fast paths compute one key per point and sort (key, index) pairs
//!   ([`sort::SortMethod::Keys`]) or radix-sort them in parallel
//!   ([`sort::SortMethod::Radix`]), yielding an index buffer to upload instead of the
//!   points; [`sort::SortCache`] skips the sort when the camera did not move. All
//!   methods are stable (ties in index order) and agree.
//! - **Order-independent alternative**: weighted blended OIT (McGuire & Bavoil 2013)
//!   needs no sort; [`oit`] draws it on the GPU (two float targets and a composite),
//!   [`reference::weighted_blended`] composites it on the CPU so its error against
//!   exact order ([`reference::rmse_rgb`]) can be measured.
//! - **Normals** ([`normals`]) for Phong lighting: the seed had CloudCompare estimate
//!   them per layer; here k nearest neighbours (kiddo's k-d tree) and PCA, one tree
//!   per layer id, in parallel; flipped toward the eye at draw time
//!   ([`normals::orient_toward`]).
//! - **Tiles** ([`tiles`], [`tiled`]): `draw = "tiles"` (precise, GLSL) builds, per
//!   frame the camera moved, a back-to-front list of splats per screen tile in parallel
//!   on the CPU and composites each pixel from its tile's list in one gather pass: the
//!   same splats without the per-point setup cost of `GL_POINTS` on software drivers
//!   (far faster than points against VTK's point Gaussian mapper; measured:
//!   docs/benchmarks.md, "Splats").
//! - **Reference** ([`reference`](mod@reference)): the f64 compositing of the same splats (GL's point
//!   clipping, size clamping and point-sprite coverage; the seed's footprints as
//!   written beside precise ones) that the renderer is scored against.
//!
//! The seed's footprint formulas, as written, are 0 (smoothstep) or at their lowest
//! (Gaussian) at the splat centre and largest on the rim, the reverse of the splats it
//! describes; [`reference`](mod@reference)'s doc gives the details and the precise versions.

pub mod edl;
pub mod locals;
pub mod normals;
pub mod oit;
pub mod prepare;
pub mod reference;
pub mod renderer;
pub mod resident;
pub mod scene;
pub mod sort;
pub mod study;
pub mod tiled;
pub mod tiles;

pub use renderer::SplatsRenderer;
pub use scene::SplatsScene;

/// Splats as the catalog lists them: the scene's checks and defaults (`scene.rs`), the
/// renderer (`renderer.rs`).
impl crate::techniques::Technique for SplatsScene {
    const NAME: &'static str = "splats";
    const STUDIES: &'static [(&'static str, &'static str)] = &[
        (
            "splats",
            "splats: every sort method at each cloud size, and frame times per sort choice while the camera turns",
        ),
        (
            "splats-lod",
            "splats of a COPC cloud (--scenes SCENE): each of --budgets' pictures against every point's, and the frame time turning",
        ),
    ];
    const DEMOS: &'static [(&'static str, &'static str)] = &[
        crate::techniques::demo!("splats-section"),
        crate::techniques::demo!("splats-section-precise"),
    ];

    fn validate(
        &self,
        fidelity: arbvis_core::vocab::Fidelity,
        programs: arbvis_gl::ProgramChoice,
    ) -> Result<(), arbvis_core::vocab::FieldError> {
        SplatsScene::validate(self)?;
        self.draw_allowed(fidelity, programs)
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut std::path::PathBuf)) {
        let kind = self.cloud.kind();
        if let Some(p) = self.cloud.path_mut() {
            f(&format!("cloud.{kind}"), p);
        }
    }

    fn memory_estimate(&self, size: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        SplatsScene::memory_estimate(self, size)
    }

    fn unwritten_defaults(
        &mut self,
        written: &dyn Fn(&str) -> bool,
        _: &mut arbvis_core::camera::Camera,
        fidelity: &mut arbvis_core::vocab::Fidelity,
    ) {
        SplatsScene::unwritten_defaults(self, written, fidelity)
    }

    /// Splats a `scale`-th of their size in pixels, so that the smaller picture shows
    /// what the whole one does (and each covers as few of its pixels), and every
    /// `floor(scale)`-th point drawn: a large cloud's cost is its points, not its pixels.
    fn for_interaction(&mut self, scale: f64) {
        self.point_size = (self.point_size / scale.max(1.0)).max(1.0);
        self.stride = (scale.floor() as usize).clamp(1, scene::MAX_STRIDE);
    }

    fn program_pairs() -> Vec<crate::programs::ProgramPair> {
        renderer::program_pairs()
    }

    type Prepared = prepare::PreparedCloud;

    /// The cloud's box in its file's coordinates and units, and its key's ids and ranges.
    fn summary(
        &self,
        (cloud, _, _): &prepare::PreparedCloud,
        base: &std::path::Path,
    ) -> Option<crate::summary::Summary> {
        let units = crate::summary::cloud_units(&self.cloud, base);
        Some(crate::summary::Summary::Cloud(
            crate::summary::CloudSummary::of(cloud, &units),
        ))
    }

    /// Tiles gather every splat of a pixel in one pass over the frame: points draw the
    /// same picture as geometry.
    fn occludable(&mut self) {
        self.draw = scene::DrawChoice::Points;
    }

    /// The cloud in its file's coordinates, framed by its frame (a COPC file's header
    /// box, the same for every cut).
    fn world(
        &self,
        (cloud, _, _): &prepare::PreparedCloud,
    ) -> Option<crate::techniques::world::World> {
        let [lo, hi] = cloud.frame.map(glam::DVec3::from_array);
        Some(crate::techniques::world::World {
            half: ((hi - lo) / (2.0 * cloud.scale)).max(glam::DVec3::splat(1e-9)),
            units: cloud.scale,
            rotation: glam::DQuat::IDENTITY,
            centre: glam::DVec3::from_array(cloud.origin),
        })
    }

    /// The cloud loaded (a COPC cloud's nodes chosen for the first view) and prepared.
    fn prepare(
        &self,
        settings: &crate::techniques::Settings<'_>,
        _: &arbvis_data::volume::Limits,
    ) -> crate::error::RenderResult<prepare::PreparedCloud> {
        SplatsScene::validate(self)?;
        prepare::prepare_for(self, settings.base, Some(&settings.view))
    }

    fn renderer(
        &self,
        gpu: &arbvis_gl::Gpu,
        settings: &crate::techniques::Settings<'_>,
        kind: arbvis_gl::ProgramKind,
        prepared: prepare::PreparedCloud,
    ) -> crate::error::RenderResult<Box<dyn crate::techniques::Renderer>> {
        Ok(Box::new(SplatsRenderer::upload(
            gpu,
            kind,
            settings.fidelity,
            self,
            settings.base,
            Some(settings.view),
            prepared,
        )?))
    }
}
