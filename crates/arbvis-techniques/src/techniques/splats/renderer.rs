//! The GL side of the splats: the point vertices uploaded once, an index buffer holding
//! the back-to-front order of the visible points (rewritten only when the camera moved),
//! or, for the seed's method, the whole vertex buffer re-uploaded in sorted order; one
//! draw of point sprites blended `SRC_ALPHA, ONE_MINUS_SRC_ALPHA` without depth test.
//! `sort = "oit"` draws the visible points in file order through [`OitPass`] instead.
//!
//! Programs: ARB (`splats/splat.arbvp` with `seed.arbfp`, or `precise.arbvp` with
//! `precise.arbfp`) or their GLSL twins, as the scene's `programs` resolves; point
//! sprites work under both (the seed's ARB fragment program reads the sprite coordinate
//! from `fragment.texcoord[0]`).
//!
//! Faithful programs take a fragment's place in its splat from the point sprite's
//! coordinate (`gl_PointCoord`), as the seed did. The precise ones take it from the
//! fragment's window position and the splat's (vertex locals 9 and 10: the viewport,
//! the size range and [`POINT_MARGIN`]), so a precise splat covers the pixels and takes
//! the footprint that [`reference`](super::reference) gives, to f32 rounding: on
//! llvmpipe `gl_PointCoord` is about 2e-3 px off that, which moved rim pixels of a
//! Gaussian of width 0.35 by up to 0.2.

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::edl::{EdlPass, EdlView};
use super::locals;
use super::oit::{z_row, OitPass};
use super::prepare::{
    from_cloud, normals_for, point_size_for_spacing, prepare_for, Prepared, COLOR_A, COLOR_B,
    FLOATS_PER_VERTEX, PHONG, VERTEX_COMPONENTS,
};
use super::reference::{eye_position, view_direction, SplatParams};
use super::resident::{NodeKey, Resident};
use super::scene::{ColourMode, DrawChoice, Kernel, Mode, SortChoice, SplatsScene};
use super::sort::{seed_order, SeedPoint, SortCache, SortMethod, View};
use super::tiled::TilePass;
use super::tiles::{
    place_splats, point_colours, spatial_order, Binner, SpatialPoints, TooManyEntries,
    DEFAULT_MAX_ENTRIES,
};
use crate::programs::{self, ProgramPair};
use arbvis_core::camera::{Camera, Projection};
use arbvis_data::points::copc_lod::View as CloudView;
use arbvis_data::points::PointCloud;
use arbvis_gl::{self, Blend, DrawCall, Gpu, Mesh, Primitive, Program, ProgramKind, Surface};

use crate::techniques::{Frame, Params, Renderer, Streaming};
use arbvis_core::vocab::Fidelity;

mod loading;
use loading::{not_refined, Arrival, Loading, Prepared3};

/// Pixels the precise programs widen a point's size by (half on each side): the
/// rasterizer's square (its centre snapped to fixed point) then holds every pixel whose
/// centre lies in the exact square, and the program decides. Lost only at the top of the
/// size range (255 px), where GL clamps the widened size.
pub const POINT_MARGIN: f64 = 1.0;

/// The program pair of a fidelity and kind.
pub fn program_pair(fidelity: Fidelity, kind: ProgramKind) -> ProgramPair {
    use programs::*;
    let (vertex, fragment) = match (kind, fidelity) {
        (ProgramKind::Arb, Fidelity::Faithful) => (SPLATS_ARBVP, SPLATS_SEED_ARBFP),
        (ProgramKind::Arb, Fidelity::Precise) => (SPLATS_PRECISE_ARBVP, SPLATS_PRECISE_ARBFP),
        (ProgramKind::Glsl, Fidelity::Faithful) => (SPLATS_VERT, SPLATS_SEED_FRAG),
        (ProgramKind::Glsl, Fidelity::Precise) => (SPLATS_PRECISE_VERT, SPLATS_PRECISE_FRAG),
    };
    ProgramPair {
        kind,
        vertex,
        fragment,
    }
}

/// The splat renderer.
pub struct SplatsRenderer {
    kind: ProgramKind,
    fidelity: Fidelity,
    base: PathBuf,
    cloud: PointCloud,
    normals: Option<(Vec<[f32; 3]>, usize)>,
    params: SplatsScene,
    prepared: Prepared,
    mesh: Mesh,
    program: Program,
    cache: Option<SortCache>,
    seed_points: Vec<SeedPoint>,
    /// `sort = "oit"`'s targets and composite, made at the first frame's size.
    oit: Option<OitPass>,
    /// The view the current order was made for.
    ordered_for: Option<[u64; 4]>,
    /// `draw = "tiles"`: the gather pass and what its textures hold.
    tiles: Option<TileState>,
    /// Time of the last sort (and upload), for the bench and the viewer.
    pub last_sort: Duration,
    /// Time of the last placing, binning and upload of tile lists.
    pub last_bin: Duration,
    /// The view a COPC cloud's nodes were chosen for, and what its cut holds.
    view: Option<CloudView>,
    cut: Option<String>,
    /// Whether the drawn cut is the whole cut of `view` (or its loading failed, said in
    /// `cut`): false while a stage of it is drawn.
    settled: bool,
    /// The scene's point size (a COPC cut's splats may be drawn larger), and the cut's
    /// deepest spacing that sizes them.
    scene_point_size: f64,
    spacing: Option<f64>,
    /// The cut of the view the camera stopped at, being loaded, and how it is handed
    /// over.
    loading: Option<Loading>,
    stages: arbvis_data::points::copc_load::Stages,
    /// Eye-dome lighting's depth target and programs, made at the first frame's size.
    edl: Option<EdlPass>,
    /// A COPC cut's points' sizes over the scene's (precise tiles and points; empty: all 1).
    size_scales: Vec<f32>,
    /// A COPC cut's nodes (key, points) in the cloud's order (empty for other clouds).
    nodes: Vec<(NodeKey, usize)>,
    /// The GPU node cache placing those nodes in the vertex buffer (`None`: the buffer
    /// holds the cloud's vertices in its order).
    resident: Option<Resident>,
    /// Each point's vertex in the cache's buffer (empty without the cache).
    in_buffer: Vec<u32>,
    /// The last placement: nodes uploaded, nodes in the cut, nodes evicted.
    last_upload: Option<[usize; 3]>,
}

/// The tile pass and the frame its uploads were made for.
struct TileState {
    pass: TilePass,
    /// The visible points in spatial order.
    points: SpatialPoints,
    /// The lists' buffers, kept from frame to frame.
    binner: Binner,
    /// Camera matrix, size and order of the uploaded lists.
    lists_for: Option<(Vec<u64>, [u32; 2])>,
    /// The view the uploaded colours were lit for (`Some` of anything when unlit).
    colours_for: Option<[u64; 4]>,
    /// Entries of the uploaded lists, or the entries a frame needed past the bound (it
    /// was drawn as points).
    entries: Result<usize, TooManyEntries>,
}

fn view_bits(view: View) -> [u64; 4] {
    match view {
        View::Eye(e) => [
            0,
            e[0].to_bits() as u64,
            e[1].to_bits() as u64,
            e[2].to_bits() as u64,
        ],
        View::Along(d) => [
            1,
            d[0].to_bits() as u64,
            d[1].to_bits() as u64,
            d[2].to_bits() as u64,
        ],
    }
}

/// A COPC cut's nodes (key, points, in the cloud's order) and its points' size scales.
type CutParts = (Vec<(NodeKey, usize)>, Vec<f32>);

impl SplatsRenderer {
    /// Load and prepare the scene's cloud (relative paths from `base`), then upload;
    /// programs of `kind`.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &SplatsScene,
        base: &Path,
        view: Option<CloudView>,
    ) -> RenderResult<SplatsRenderer> {
        params.validate()?;
        let loaded = prepare_for(params, base, view.as_ref())?;
        SplatsRenderer::upload(gpu, kind, fidelity, params, base, view, loaded)
    }

    /// Upload what [`prepare_for`] made for `view` (the viewer prepares it itself to keep
    /// the cloud's summary).
    pub fn upload(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &SplatsScene,
        base: &Path,
        view: Option<CloudView>,
        (cloud, prepared, loaded): Prepared3,
    ) -> RenderResult<SplatsRenderer> {
        // A COPC cut's splats cover its deepest level's spacing.
        let mut sized = params.clone();
        if let (Some(l), Some(v)) = (&loaded, &view) {
            sized.point_size = point_size_for_spacing(params, v, l.spacing);
        }
        let cut = loaded.as_ref().map_or((Vec::new(), Vec::new()), |l| {
            (l.nodes.clone(), l.size_scales.clone())
        });
        let mut r =
            SplatsRenderer::with_nodes(gpu, kind, fidelity, &sized, base, (cloud, prepared, cut))?;
        r.view = view;
        r.scene_point_size = params.point_size;
        r.spacing = loaded.as_ref().map(|l| l.spacing);
        if let Some(l) = loaded {
            r.cut = Some(cut_text(&l, &sized, params.point_size, fidelity));
        }
        Ok(r)
    }

    /// Draw a new cut of the same cloud for `view` (the viewer's refinement): programs,
    /// targets and the vertex buffer are kept, and through the node cache only the nodes
    /// the buffer lacks are uploaded.
    fn replace_cut(
        &mut self,
        gpu: &Gpu,
        (params, prepared_with): (&SplatsScene, Option<&SplatsScene>),
        view: CloudView,
        (cloud, prepared, loaded): Prepared3,
    ) -> RenderResult<()> {
        // Colours, visibility or lighting edited while the cut loaded: prepare it again
        // with the scene as it is now.
        let (cloud, prepared) = match prepared_with {
            Some(then) if then != params => {
                let normals = normals_for(&cloud, params);
                let prepared = from_cloud(&cloud, params, normals)?;
                (cloud, prepared)
            }
            _ => (cloud, prepared),
        };
        let Some(l) = loaded else {
            let base = self.base.clone();
            *self = SplatsRenderer::upload(
                gpu,
                self.kind,
                self.fidelity,
                params,
                &base,
                Some(view),
                (cloud, prepared, None),
            )?;
            return Ok(());
        };
        let sized = SplatsScene {
            point_size: point_size_for_spacing(params, &view, l.spacing),
            ..params.clone()
        };
        self.normals = (sized.lighting && sized.mode == Mode::Surface)
            .then(|| (prepared.normals.clone(), prepared.normal_fallbacks));
        self.cut = Some(cut_text(&l, &sized, params.point_size, self.fidelity));
        self.params = sized;
        self.scene_point_size = params.point_size;
        self.cloud = cloud;
        self.prepared = prepared;
        self.view = Some(view);
        self.spacing = Some(l.spacing);
        self.size_scales = l.size_scales;
        self.nodes = l.nodes;
        self.install(gpu)
    }

    /// How a COPC cut loaded when the camera stops is handed over (the viewer's stages
    /// by default).
    pub fn set_stages(&mut self, stages: arbvis_data::points::copc_load::Stages) {
        self.stages = stages;
    }

    /// Upload a cloud prepared elsewhere.
    pub fn from_prepared(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &SplatsScene,
        base: &Path,
        cloud: PointCloud,
        prepared: Prepared,
    ) -> RenderResult<SplatsRenderer> {
        let cut = (Vec::new(), Vec::new());
        SplatsRenderer::with_nodes(gpu, kind, fidelity, params, base, (cloud, prepared, cut))
    }

    /// [`SplatsRenderer::from_prepared`] of a COPC cut: its `nodes` (in the cloud's
    /// order) placed through the GPU node cache, its points sized by `size_scales`.
    fn with_nodes(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &SplatsScene,
        base: &Path,
        (cloud, prepared, (nodes, size_scales)): (PointCloud, Prepared, CutParts),
    ) -> RenderResult<SplatsRenderer> {
        params.draw_allowed(fidelity, arbvis_gl::ProgramChoice::Auto)?;
        let pair = program_pair(fidelity, kind);
        let program = Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?;
        let mesh = Mesh::new(
            gpu,
            "splats points",
            &VERTEX_COMPONENTS,
            &prepared.vertices(None, &size_scales),
        )?;
        let normals = (params.lighting && params.mode == Mode::Surface)
            .then(|| (prepared.normals.clone(), prepared.normal_fallbacks));
        let mut r = SplatsRenderer {
            kind,
            fidelity,
            base: base.to_path_buf(),
            cloud,
            normals,
            params: params.clone(),
            prepared,
            mesh,
            program,
            cache: None,
            seed_points: Vec::new(),
            oit: None,
            ordered_for: None,
            tiles: None,
            last_sort: Duration::ZERO,
            last_bin: Duration::ZERO,
            view: None,
            cut: None,
            settled: true,
            scene_point_size: params.point_size,
            spacing: None,
            loading: None,
            stages: arbvis_data::points::copc_load::Stages::viewer(),
            edl: None,
            size_scales,
            nodes,
            resident: None,
            in_buffer: Vec::new(),
            last_upload: None,
        };
        r.install(gpu)?;
        Ok(r)
    }

    /// The splats of one frame (tiles, points or OIT), without eye-dome lighting.
    fn draw_splats(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        if self.tiles.is_some() && self.prepare_tiles(gpu, frame)? {
            if let Some(state) = &self.tiles {
                let gaussian = if self.params.kernel == Kernel::Gaussian {
                    1.0
                } else {
                    0.0
                };
                return state
                    .pass
                    .draw(gpu, surface, [gaussian, self.params.gauss_width]);
            }
        }
        // Points (also a tiles frame past the bound on list entries).
        let camera = &frame.camera;
        let view = View::of_camera(camera);
        self.order(gpu, view)?;
        self.program
            .set_transform(gpu, camera.view_projection(frame.aspect()))?;
        let inverse = camera.view().inverse();
        let eye = inverse.transform_point3(glam::DVec3::ZERO);
        let dir = inverse.transform_vector3(glam::DVec3::NEG_Z).normalize();
        let perspective = if camera.projection == Projection::Perspective {
            1.0
        } else {
            0.0
        };
        self.program.set_vertex_local(
            gpu,
            locals::VERTEX_EYE,
            [eye.x, eye.y, eye.z, perspective],
        )?;
        self.program.set_vertex_local(
            gpu,
            locals::VERTEX_VIEW_DIRECTION,
            [dir.x, dir.y, dir.z, 0.0],
        )?;
        self.program
            .set_vertex_local(gpu, locals::VERTEX_Z_ROW, z_row(camera).to_array())?;
        // The viewport in window coordinates (the precise programs' splat positions):
        // OIT draws into its own targets, whose corner is the origin.
        let viewport = match surface {
            Surface::Window(v) if self.params.sort != SortChoice::Oit => v.map(f64::from),
            _ => [0.0, 0.0, frame.width as f64, frame.height as f64],
        };
        self.program
            .set_vertex_local(gpu, locals::VERTEX_VIEWPORT, viewport)?;
        if self.params.sort == SortChoice::Oit {
            let (w, h) = (frame.width, frame.height);
            if !self.oit.as_ref().is_some_and(|o| o.fits(w, h)) {
                self.oit = None;
                self.oit = Some(OitPass::new(gpu, self.kind, w, h)?);
            }
            if let Some(oit) = &self.oit {
                return oit.draw(gpu, &self.program, &self.mesh, surface);
            }
        }
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                blend: Blend::Over,
                primitive: Primitive::Points,
                ..DrawCall::new(&self.program, &self.mesh)
            },
        )?)
    }

    /// The frame's line: points drawn, sort or tiles.
    fn frame_status(&self) -> String {
        let drawn = self.prepared.visible.iter().filter(|v| **v).count();
        if self.params.sort == SortChoice::Oit {
            return format!(
                "{drawn} of {} points drawn; weighted blended OIT (no sort)",
                self.prepared.len()
            );
        }
        let points = format!("{drawn} of {} points drawn", self.prepared.len());
        let sort = format!(
            "last sort ({:?}): {:.1} ms",
            self.params.sort,
            self.last_sort.as_secs_f64() * 1e3
        );
        match &self.tiles {
            None => format!("{points}; {sort}"),
            Some(TileState { entries: Ok(n), .. }) => format!(
                "{points} as tiles of {} px: {n} list entries, placed, binned and ordered \
                 per tile: last lists {:.1} ms",
                self.params.tile,
                self.last_bin.as_secs_f64() * 1e3
            ),
            Some(TileState {
                entries: Err(TooManyEntries(n)),
                ..
            }) => format!(
                "{points}; tiles would need {n} list entries (more than \
                 {DEFAULT_MAX_ENTRIES}): drawn as points; {sort}"
            ),
        }
    }

    /// Set up the ordering of the current `prepared` and `params`, and the constants.
    fn install(&mut self, gpu: &Gpu) -> RenderResult<()> {
        self.cache = match self.params.sort {
            SortChoice::Keys => Some(SortCache::new(SortMethod::Keys)),
            SortChoice::Radix => Some(SortCache::new(SortMethod::Radix)),
            SortChoice::Seed | SortChoice::None | SortChoice::Oit => None,
        };
        self.seed_points = if self.params.sort == SortChoice::Seed {
            SeedPoint::from_positions(&self.prepared.positions)
        } else {
            Vec::new()
        };
        self.ordered_for = None;
        if self.params.sort != SortChoice::Oit {
            self.oit = None;
        }
        self.tiles = match (self.params.draw, self.tiles.take()) {
            (DrawChoice::Points, _) => None,
            (DrawChoice::Tiles, kept) => Some(TileState {
                pass: match kept {
                    Some(t) => t.pass,
                    None => TilePass::new(gpu)?,
                },
                points: SpatialPoints {
                    size_scales: self.size_scales.clone(),
                    ..spatial_order(&self.prepared.positions, &self.prepared.visible)
                },
                binner: Binner::default(),
                lists_for: None,
                colours_for: None,
                entries: Ok(0),
            }),
        };
        self.upload_vertices(gpu)?;
        // Unordered sorts draw the visible points as they are; through the node cache
        // every draw goes through indices (the buffer holds other nodes too).
        let unordered = matches!(self.params.sort, SortChoice::None | SortChoice::Oit);
        if unordered || self.resident.is_some() {
            let visible = self.visible(0..self.prepared.len() as u32);
            self.set_indices(gpu, visible)?;
        }
        self.send_constants(gpu)
    }

    /// The cloud's vertices into the buffer: through the node cache for a COPC cut
    /// (only the nodes it lacks, or whose vertices changed), else whole.
    fn upload_vertices(&mut self, gpu: &Gpu) -> GlResult<()> {
        let vertices = self.prepared.vertices(None, &self.size_scales);
        let f = FLOATS_PER_VERTEX;
        let whole = self.nodes.iter().map(|n| n.1).sum::<usize>() == self.prepared.len();
        // The seed's sort rewrites the buffer in order each time: no cache there. Nor
        // past what GL's signed 32-bit offsets address (an arena of twice a cut of more
        // than about 24 M points).
        let addressable = 2 * vertices.len() * 4 <= i32::MAX as usize;
        if self.nodes.is_empty() || !whole || !addressable || self.params.sort == SortChoice::Seed {
            self.resident = None;
            self.in_buffer.clear();
            self.last_upload = None;
            self.mesh.clear_indices();
            return self.mesh.update(gpu, &vertices);
        }
        let mut slices = Vec::with_capacity(self.nodes.len());
        let mut at = 0;
        for &(key, n) in &self.nodes {
            slices.push((key, &vertices[at * f..(at + n) * f]));
            at += n;
        }
        // The arena starts as large as the first cut (an offline picture needs no more);
        // the first refinement that does not fit lays it out again at twice its cut, so
        // a turn's new nodes fit beside the drawn ones from then on.
        // Taken out while uploading: a failed upload leaves the buffer unknown, and the
        // next cut starts a fresh arena.
        let fresh = self.resident.is_none();
        let mut resident = self
            .resident
            .take()
            .unwrap_or_else(|| Resident::new(self.prepared.len(), f));
        let placed = resident.place(&slices);
        let capacity = resident.capacity();
        self.in_buffer.clear();
        if fresh || placed.rebuilt {
            // Laid out in the cut's order from the start: the cut's vertices, then room
            // (none in a fresh arena, as large as its cut).
            self.mesh.clear_indices();
            if capacity * f == vertices.len() {
                self.mesh.update(gpu, &vertices)?;
            } else {
                let mut all = Vec::with_capacity(capacity * f);
                all.extend_from_slice(&vertices);
                all.resize(capacity * f, 0.0);
                self.mesh.update(gpu, &all)?;
            }
        } else {
            for &k in &placed.uploads {
                self.mesh.update_range(gpu, placed.starts[k], slices[k].1)?;
            }
        }
        self.in_buffer = self
            .nodes
            .iter()
            .zip(&placed.starts)
            .flat_map(|(&(_, n), &start)| (start..start + n).map(|v| v as u32))
            .collect();
        self.last_upload = Some([placed.uploads.len(), self.nodes.len(), placed.evicted]);
        self.resident = Some(resident);
        Ok(())
    }

    /// Draw the points `order` (the cloud's indices) from now on, through the node
    /// cache's placement when there is one.
    fn set_indices(&mut self, gpu: &Gpu, order: Vec<u32>) -> GlResult<()> {
        if self.in_buffer.is_empty() {
            return self.mesh.set_indices(gpu, &order);
        }
        let mapped: Vec<u32> = order.iter().map(|&i| self.in_buffer[i as usize]).collect();
        self.mesh.set_indices(gpu, &mapped)
    }

    /// The prepared cloud.
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    fn visible(&self, order: impl IntoIterator<Item = u32>) -> Vec<u32> {
        order
            .into_iter()
            .filter(|&i| self.prepared.visible[i as usize])
            .collect()
    }

    /// Put the points in back-to-front order for `view` (nothing when it did not move).
    fn order(&mut self, gpu: &Gpu, view: View) -> RenderResult<()> {
        let bits = view_bits(view);
        let unordered = matches!(self.params.sort, SortChoice::None | SortChoice::Oit);
        if self.ordered_for == Some(bits) || unordered {
            return Ok(());
        }
        let t0 = Instant::now();
        if self.params.sort == SortChoice::Seed {
            // The seed's way: the structs sorted with a distance comparator, the whole
            // buffer re-uploaded in that order (hidden points left out).
            let order = seed_order(&mut self.seed_points, view);
            let order = self.visible(order.into_iter().step_by(self.params.stride));
            let vertices = self.prepared.vertices(Some(&order), &self.size_scales);
            self.mesh.update(gpu, &vertices)?;
        } else if let Some(cache) = &mut self.cache {
            let stride = self.params.stride;
            let order: Vec<u32> = cache.order(&self.prepared.positions, view).to_vec();
            let order = self.visible(order.into_iter().step_by(stride));
            self.set_indices(gpu, order)?;
        }
        self.last_sort = t0.elapsed();
        self.ordered_for = Some(bits);
        Ok(())
    }

    /// The splat rules of the precise programs, for placing tiles.
    fn splat_params(&self) -> SplatParams {
        SplatParams {
            point_size: self.params.point_size,
            factor: self.params.factor,
            footprint: super::prepare::footprint(&self.params, self.fidelity),
            size_range: [1.0, 255.0],
        }
    }

    /// Bring the tile pass's colours and lists up to `frame` (nothing that did not
    /// change); `false` when the lists would exceed their bound.
    fn prepare_tiles(&mut self, gpu: &Gpu, frame: &Frame) -> RenderResult<bool> {
        let camera = &frame.camera;
        let size = [frame.width, frame.height];
        let lit = self.params.lighting && self.params.mode == Mode::Surface;
        let view = if lit {
            view_bits(View::of_camera(camera))
        } else {
            [0; 4]
        };
        let matrix: Vec<u64> = camera
            .view_projection(frame.aspect())
            .to_cols_array()
            .iter()
            .map(|v| v.to_bits())
            .collect();
        let params = self.splat_params();
        let Some(state) = &mut self.tiles else {
            return Ok(false);
        };
        let t0 = Instant::now();
        if state.colours_for != Some(view) {
            let colours = point_colours(
                &self.prepared,
                &self.params,
                eye_position(camera),
                view_direction(camera),
            );
            state.pass.set_colours(gpu, &colours)?;
            state.colours_for = Some(view);
        }
        let key = Some((matrix, size));
        if state.lists_for != key {
            let placed = place_splats(&state.points, camera, size, self.params.tile, &params);
            let ordered = self.params.sort != SortChoice::None;
            let binned = state.binner.bin(&placed, DEFAULT_MAX_ENTRIES, ordered);
            state.entries = match binned {
                Ok(()) => {
                    let lists = &state.binner.lists;
                    state.pass.set_lists(gpu, lists)?;
                    Ok(lists.entries.len())
                }
                Err(too_many) => Err(too_many),
            };
            state.lists_for = key;
            self.last_bin = t0.elapsed();
        }
        Ok(state.entries.is_ok())
    }

    fn send_constants(&self, gpu: &Gpu) -> RenderResult<()> {
        let p = &self.params;
        let colour = if p.colour == ColourMode::Property {
            1.0
        } else {
            0.0
        };
        let volume = if p.mode == Mode::Volume { 1.0 } else { 0.0 };
        let [lo, hi] = self.prepared.range;
        let prog = &self.program;
        prog.set_local(gpu, locals::COLOURING, [colour, lo, hi, volume])?;
        prog.set_local(
            gpu,
            locals::GRADIENT_FROM,
            [COLOR_A[0], COLOR_A[1], COLOR_A[2], 1.0],
        )?;
        prog.set_local(
            gpu,
            locals::GRADIENT_TO,
            [COLOR_B[0], COLOR_B[1], COLOR_B[2], 1.0],
        )?;
        let kernel = if p.kernel == Kernel::Gaussian {
            1.0
        } else {
            0.0
        };
        prog.set_local(gpu, locals::KERNEL, [kernel, p.gauss_width, 0.0, 0.0])?;
        prog.set_local(
            gpu,
            locals::TRANSFER,
            [p.volume.threshold, p.volume.range, 0.0, 0.0],
        )?;
        prog.set_local(gpu, locals::OIT_ACCUMULATE, [0.0; 4])?;
        let lighting = if p.lighting && p.mode == Mode::Surface {
            1.0
        } else {
            0.0
        };
        prog.set_vertex_local(
            gpu,
            locals::VERTEX_SIZING,
            [p.point_size, p.factor, lighting, 0.0],
        )?;
        prog.set_vertex_local(gpu, locals::VERTEX_PHONG, PHONG)?;
        let [lo, hi] = self.splat_params().size_range;
        prog.set_vertex_local(gpu, locals::VERTEX_SIZES, [lo, hi, POINT_MARGIN, 0.0])?;
        Ok(())
    }
}

impl Renderer for SplatsRenderer {
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use super::prepare::{class_colour, class_name, COLOR_A, COLOR_B};
        use super::scene::ColourMode;
        use crate::techniques::annotations::{Annotations, Legend};
        let c = &self.cloud;
        let ramp = |a: [f64; 3], b: [f64; 3]| -> Vec<[u8; 3]> {
            (0..256)
                .map(|k| {
                    let t = k as f64 / 255.0;
                    std::array::from_fn(|i| ((a[i] + t * (b[i] - a[i])) * 255.0).round() as u8)
                })
                .collect()
        };
        let [lo, hi] = c.frame;
        let legend = match self.params.colour {
            ColourMode::Classification => c.attribute("classification").map(|a| {
                let mut classes: Vec<i32> = (0..a.values.len())
                    .filter_map(|i| a.values.get(i).map(|v| v as i32))
                    .collect();
                classes.sort_unstable();
                classes.dedup();
                Legend::Keys {
                    title: "classification".into(),
                    keys: classes
                        .into_iter()
                        .map(|k| (class_colour(k), class_name(k)))
                        .collect(),
                }
            }),
            ColourMode::Elevation => Some(Legend::Bar {
                title: "elevation".into(),
                colours: ramp(COLOR_A, COLOR_B),
                low: lo[2],
                high: hi[2],
            }),
            ColourMode::Intensity => c.attribute("intensity").map(|a| Legend::Bar {
                title: "intensity".into(),
                colours: ramp([0.0; 3], [1.0; 3]),
                low: 0.0,
                high: a.stats.max.max(1.0),
            }),
            _ => None,
        };
        // The box the cloud is framed by, in the file's coordinates.
        let half = std::array::from_fn(|a| ((hi[a] - lo[a]) / (2.0 * c.scale)).max(1e-9));
        let axes = std::array::from_fn(|a| {
            arbvis_data::volume::axes::span(["x", "y", "z"][a], lo[a], hi[a])
        });
        Annotations {
            legends: legend.into_iter().collect(),
            axes: Some(crate::techniques::annotations::BoxAxes::new(half, axes)),
        }
    }

    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        self.draw_splats(gpu, surface, frame)?;
        if self.params.edl > 0.0 {
            let (w, h) = (frame.width, frame.height);
            if !self.edl.as_ref().is_some_and(|e| e.fits(w, h)) {
                self.edl = None;
                self.edl = Some(EdlPass::new(gpu, w, h)?);
            }
            let camera = &frame.camera;
            let eye = camera.view().inverse().transform_point3(glam::DVec3::ZERO);
            let perspective = f64::from(u8::from(camera.projection == Projection::Perspective));
            let view = EdlView {
                transform: camera.view_projection(frame.aspect()),
                eye: eye.extend(perspective),
                z_row: z_row(camera),
                size: [self.params.point_size, self.params.factor],
                size_range: self.splat_params().size_range,
            };
            if let Some(edl) = &self.edl {
                edl.draw(gpu, &self.mesh, &view, self.params.edl, surface)?;
            }
        }
        Ok(())
    }
    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let asked = params.get::<SplatsScene>()?;
        asked.validate()?;
        asked.draw_allowed(self.fidelity, arbvis_gl::ProgramChoice::Auto)?;
        // A COPC cut keeps its splats sized from its spacing over the scene's size.
        let mut sized = asked.clone();
        if let (Some(v), Some(spacing)) = (&self.view, self.spacing) {
            if asked.cloud == self.params.cloud {
                self.scene_point_size = asked.point_size;
                sized.point_size = point_size_for_spacing(asked, v, spacing);
            }
        }
        let new = &sized;
        let p = &self.params;
        if new.cloud != p.cloud {
            *self = SplatsRenderer::new(
                gpu,
                self.kind,
                self.fidelity,
                new,
                &self.base.clone(),
                self.view,
            )?;
            return Ok(());
        }
        let lit = |s: &SplatsScene| (s.lighting && s.mode == Mode::Surface, s.normals_k);
        if lit(new) != lit(p) {
            self.normals = normals_for(&self.cloud, new);
        }
        let rebuild = new.colour != p.colour
            || new.property != p.property
            || new.faults_white != p.faults_white
            || new.hide_layers != p.hide_layers
            || new.hide_classes != p.hide_classes
            || new.hide_undefined != p.hide_undefined
            || lit(new) != lit(p)
            || new.sort != p.sort
            || new.draw != p.draw
            || new.tile != p.tile;
        if new.stride != p.stride {
            // The same view drawn with more or fewer points: ordered again.
            self.ordered_for = None;
        }
        self.params = new.clone();
        if rebuild {
            self.prepared = from_cloud(&self.cloud, new, self.normals.clone())?;
            return self.install(gpu);
        }
        // Tiles bake sizes into the lists and the transfer function into the colours.
        if let Some(state) = &mut self.tiles {
            state.lists_for = None;
            state.colours_for = None;
        }
        self.send_constants(gpu)
    }

    fn program_kind(&self) -> ProgramKind {
        self.program.kind()
    }

    fn status(&self) -> Option<String> {
        let mut line = self.frame_status();
        if let (Some([uploaded, nodes, evicted]), Some(r)) = (self.last_upload, &self.resident) {
            line = format!(
                "node cache: {uploaded} of the cut's {nodes} nodes uploaded, {evicted} evicted; {} nodes resident in room for {} points\n{line}",
                r.len(),
                r.capacity()
            );
        }
        Some(match &self.cut {
            Some(cut) => format!("{cut}\n{line}"),
            None => line,
        })
    }

    fn streaming(&self) -> Option<&dyn Streaming> {
        Some(self)
    }

    fn streaming_mut(&mut self) -> Option<&mut dyn Streaming> {
        Some(self)
    }
}

impl Streaming for SplatsRenderer {
    fn pending(&self) -> bool {
        self.loading.is_some()
    }

    fn settle(&mut self, gpu: &Gpu, camera: &Camera, size: [u32; 2]) -> RenderResult<bool> {
        if self.cut.is_none() {
            return Ok(false);
        }
        let view = CloudView::of(camera, size);
        let same = |v: &CloudView| {
            v.size == view.size && v.view_projection.abs_diff_eq(view.view_projection, 1e-12)
        };
        let params = SplatsScene {
            point_size: self.scene_point_size,
            ..self.params.clone()
        };
        // The next stage of the cut being loaded replaces the drawn one: one stage a
        // frame, in order, each upload a frame's work (the loader hands them over at
        // most every `Stages::every`).
        if let Some(loading) = &self.loading {
            let (view, then, still) = (loading.view, loading.params.clone(), same(&loading.view));
            let why = match loading.poll() {
                Arrival::Waiting if still => return Ok(false),
                Arrival::Waiting => None,
                Arrival::Stage(loaded, whole) => {
                    // The rest is not waited for when it is whole, or the camera moved on
                    // (a stage drawn for a view the camera comes back to is loaded again).
                    if whole || !still {
                        self.loading = None;
                    }
                    self.replace_cut(gpu, (&params, Some(&then)), view, *loaded)?;
                    self.settled = whole;
                    return Ok(true);
                }
                // A node that cannot be read (a damaged file), or a loader that died:
                // the drawn cut stays, and the status line says why the view was not
                // refined.
                Arrival::Failed(e) => Some(e.to_string()),
                Arrival::Ended => Some("the loader stopped before the whole cut".to_string()),
            };
            self.loading = None;
            if let Some(why) = why {
                self.cut = Some(not_refined(self.cut.as_deref().unwrap_or(""), &why));
                self.view = Some(view);
                self.settled = true;
                return Ok(true);
            }
        }
        if self.settled && self.view.as_ref().is_some_and(same) {
            return Ok(false);
        }
        // Load the new view's cut on a thread; the drawn one stays until its first stage
        // arrives.
        self.loading = Some(Loading::start(
            view,
            params,
            self.base.clone(),
            &self.stages,
        ));
        Ok(false)
    }
}

/// Every pair the splats draw with: the seed's and the precise programs as points (ARB
/// and GLSL), the OIT composite, and the tiles' gather.
pub fn program_pairs() -> Vec<ProgramPair> {
    use programs::*;
    let mut pairs: Vec<ProgramPair> = [
        (ProgramKind::Arb, SPLATS_ARBVP, SPLATS_SEED_ARBFP),
        (ProgramKind::Arb, SPLATS_PRECISE_ARBVP, SPLATS_PRECISE_ARBFP),
        (ProgramKind::Glsl, SPLATS_VERT, SPLATS_SEED_FRAG),
        (ProgramKind::Glsl, SPLATS_PRECISE_VERT, SPLATS_PRECISE_FRAG),
        (ProgramKind::Glsl, TRANSFORM_VERT, SPLATS_TILES_FRAG),
    ]
    .map(|(kind, vertex, fragment)| ProgramPair {
        kind,
        vertex,
        fragment,
    })
    .into();
    pairs.extend(both_kinds(
        &SPLATS_OIT_COMPOSITE_ARBFP,
        &SPLATS_OIT_COMPOSITE_FRAG,
    ));
    pairs
}

/// A COPC cut's line: what it holds and how its splats are sized.
/// Precise programs (tiles and points) scale each point by its size scale; faithful
/// ones draw one size.
fn cut_text(
    l: &arbvis_data::points::copc_lod::Loaded,
    sized: &SplatsScene,
    scene_size: f64,
    fidelity: Fidelity,
) -> String {
    format!(
        "{}; splats of point size {:.1} (the scene's {scene_size:.1}){}",
        l.describe,
        sized.point_size,
        if fidelity == Fidelity::Precise {
            ", larger where coarser levels stand in for missing ones"
        } else {
            ""
        }
    )
}
