//! 3D opacity of a survey larger than memory, brick by brick, as 2004's bricked renderers
//! did: a scene whose attribute volumes are `{ store = "survey.zarr" }` draws from the
//! store through the GPU brick cache ([`crate::techniques::opacity3d::brick_cache`]), never loading the survey.
//!
//! # How it works
//! 1. Each frame [`arbvis_data::store::lod`] picks the bricks of the view (screen-space error,
//!    the GPU budget, bricks the tables make transparent left out) and the back-to-front
//!    order of what is resident.
//! 2. Each brick is drawn with the **verbatim** `!!ARBfp1.0` program (sum or product) on
//!    its own RGB8 texture on unit 0 (G primary, B secondary, R tertiary, quantized over
//!    each attribute's range as v3o2 did), tables on units 2/3/4, its slices clipped to
//!    the brick's box.
//! 3. The slice planes are the whole window's ([`super::slicing`]'s rule: `slices` planes
//!    over the window's extent along the view), the same in every brick and at every
//!    level, so the seed's uncorrected opacity means the same everywhere.
//! 4. A brick texture holds its voxels and one voxel of every neighbour (`(B+2)³`), and its
//!    texture coordinates address those voxels where the whole volume's texture would: at
//!    a seam between bricks of one level, linear filtering reads the same voxels either
//!    side, and the slice polygons of two neighbours share their edge vertex for vertex
//!    (each computed from the same box edge, in the same order), so the rasterizer covers
//!    every pixel of a slice exactly once. Drawn at one level this is the unbricked
//!    picture (within the 8-bit filtering's rounding of texture coordinates).
//!
//! # Level transitions
//! Where bricks of two levels meet, each side is its own level's data up to the shared
//! face: the coarse side's border voxels are coarse-level voxels, so the picture steps at
//! the face by the levels' difference (the data's, not a crack: the slices still tile
//! the face exactly, except that a coarse brick's polygon edge meets two or four finer
//! polygons' edges there, whose vertices lie on it within rounding, so a pixel on that
//! line can rarely be drawn twice or missed). Opacity per slice is the seed's, and the
//! spacing is the same, so a level transition changes colours, not opacity scale.
//!
//! # Precise
//! Precise mode draws the store in one pass through a page table: [`super::paged`].
//!
//! # Budget
//! Offscreen (`arbvis render`), a frame waits for the bricks it wants at full quality; when
//! they are more than the GPU budget holds, it draws them in back-to-front batches that
//! fit, evicting as it goes: the same picture, slower. In the viewer (streaming), a frame
//! draws what is resident (stand-ins for what is not), asks for the rest, and refines over
//! the next frames.

use crate::error::RenderResult;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::paged::{PageTable, PagedPass};
use super::prepare::CHANNEL;
use super::programs::faithful_pair;
use super::proxy::{eye, toward_viewer};
use super::renderer::model_view_projection;
use super::slicing::{polygon, EDGES};
use super::textures::{neutral_for, table_texture};
use super::{coefficients, Combine, Opacity3dScene, ATTRIBUTE_NAMES};
use crate::techniques::opacity3d::brick_cache::{BrickCache, Packing};
use crate::techniques::{Frame, Params, Renderer, Streaming};
use arbvis_core::camera::Projection;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::store::lod::{self, BrickId, Pyramid, View};
use arbvis_data::store::Store;
use arbvis_data::volume::quantize::{NoData, Quantization};
use arbvis_data::volume::VolumeSource;
use arbvis_gl::{
    self, Blend, DrawCall, GlError, Gpu, Mesh, Program, ProgramKind, Surface, Texture,
};

/// `[technique.opacity3d.store]`: how a store is streamed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StoreView {
    /// Texture memory for bricks (`"512M"`, `"2G"`); `--gpu-memory` overrides it.
    pub gpu_memory: String,
    /// Largest projected voxel, in pixels, before a finer level is wanted (1: full
    /// quality; the viewer's interactive frames are smaller, hence coarser).
    pub pixels: f64,
    /// Draw this level everywhere instead (an LOD policy for comparisons).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<usize>,
    /// Draw only level-0 voxels `[lo, hi)` (i, j, k), as their own box.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<[[usize; 3]; 2]>,
}

impl Default for StoreView {
    fn default() -> Self {
        StoreView {
            gpu_memory: "512M".into(),
            pixels: 1.0,
            level: None,
            window: None,
        }
    }
}

impl StoreView {
    /// Check the values; errors name the key under `store`.
    pub fn validate(&self) -> Result<(), FieldError> {
        arbvis_core::budget::parse(&self.gpu_memory)
            .map_err(|e| FieldError::new("gpu_memory", e.to_string()))?;
        if !(self.pixels.is_finite() && self.pixels > 0.0 && self.pixels <= 1e6) {
            return Err(FieldError::new(
                "pixels",
                format!("{}: must be above 0 and at most 1e6", self.pixels),
            ));
        }
        if let Some(w) = self.window {
            if (0..3).any(|a| w[0][a] >= w[1][a]) {
                return Err(FieldError::new(
                    "window",
                    format!("{w:?}: each lower corner must be below the upper one"),
                ));
            }
        }
        Ok(())
    }
}

/// The store a scene's attributes name, if any (all must name the same one).
pub fn store_of(params: &Opacity3dScene) -> Result<Option<PathBuf>, FieldError> {
    let mixed = || {
        FieldError::new(
            "",
            "every attribute of a scene drawn from a store must name the same store",
        )
    };
    let paths: Vec<Option<&PathBuf>> = params
        .attributes()
        .iter()
        .flatten()
        .map(|a| match &a.volume {
            VolumeSource::Store(p) => Some(p),
            _ => None,
        })
        .collect();
    match paths.first() {
        Some(Some(first)) => {
            if paths.iter().all(|p| *p == Some(*first)) {
                Ok(Some((*first).clone()))
            } else {
                Err(mixed())
            }
        }
        _ if paths.iter().any(Option::is_some) => Err(mixed()),
        _ => Ok(None),
    }
}

/// Most voxels read to learn a store's distribution (16 MiB of f32).
const DISTRIBUTION_VOXELS: usize = 1 << 22;

/// The alpha of the distribution of attribute `index` over `low..high`
/// ([`arbvis_core::colortable::alpha_from_histogram`]), read from the finest level of at
/// most [`DISTRIBUTION_VOXELS`]: level 0 itself where the survey is that small (then the
/// alpha is exactly the survey read whole's), else a level whose voxels are the means of
/// the ones they cover (a narrower distribution: an approximation a store larger than
/// memory cannot avoid). NaN (no data) is left out. A level that cannot be read (a damaged
/// chunk, which streaming reports brick by brick) gives way to the next coarser one;
/// `None` where none can be read (the table keeps its own alpha).
fn alpha_of_store(store: &Store, index: usize, low: f64, high: f64) -> Option<[u8; 256]> {
    let last = store.meta.levels.saturating_sub(1);
    let fits =
        |l: &usize| store.meta.level_dims(*l).iter().product::<usize>() <= DISTRIBUTION_VOXELS;
    let first = (0..last).find(fits).unwrap_or(last);
    let values = (first..=last).find_map(|level| {
        let dims = store.meta.level_dims(level);
        store.region(index, level, [0; 3], dims).ok()
    })?;
    let mut counts = [0u64; 256];
    for &v in values.iter().filter(|v| !v.is_nan()) {
        counts[arbvis_data::volume::quantize::quantize_value(v, low, high) as usize] += 1;
    }
    Some(arbvis_core::colortable::alpha_from_histogram(&counts))
}

/// A scene's store opened: its view settings, the window's pyramid, and per scene
/// attribute the store's attribute index and quantization range (what the renderers and
/// the viewer's sections share).
pub struct StoreScene {
    /// The store.
    pub store: Arc<Store>,
    /// `[technique.opacity3d.store]`.
    pub view: StoreView,
    /// The levels over the window drawn.
    pub pyramid: Pyramid,
    /// Per attribute (primary, secondary, tertiary): store index, low, high.
    pub attributes: [Option<(usize, f64, f64)>; 3],
}

impl StoreScene {
    /// Where the store lies in the world, as the same survey read whole lies (its traces at
    /// their CDP coordinates where the store has them, its samples downwards); `None` for a
    /// window of it (`store.window`: not placed in a layered scene yet).
    pub fn world(&self) -> RenderResult<Option<crate::techniques::world::World>> {
        use crate::techniques::world::World;
        let meta = &self.store.meta;
        if self.pyramid.window != [[0; 3], meta.dims] {
            return Ok(None);
        }
        let [_, nj, nk] = meta.dims;
        let map = self.store.map_coordinates()?.and_then(|xy| {
            arbvis_data::volume::segy::geometry::MapFrame::of_corners(nj, nk, |k, j| {
                let t = k * nj + j;
                Some([*xy[0].get(t)?, *xy[1].get(t)?])
            })
        });
        let size = glam::DVec3::from_array(std::array::from_fn(|a| {
            let s = self.pyramid.spacing[a];
            meta.dims[a] as f64 * if s.is_finite() && s > 0.0 { s } else { 1.0 }
        }));
        let half = self.pyramid.half();
        Ok(Some(World::of_survey(meta.dims, size, half, map.as_ref())))
    }

    /// Open the store `params` names (relative to `base`), if it names one.
    pub fn open(params: &Opacity3dScene, base: &Path) -> RenderResult<Option<StoreScene>> {
        let Some(path) = store_of(params)? else {
            return Ok(None);
        };
        let store = Arc::new(Store::open(&arbvis_data::fetch::resolve(base, &path))?);
        let view = params.store.clone().unwrap_or_default();
        let meta = &store.meta;
        let window = view.window.unwrap_or([[0; 3], meta.dims]);
        if (0..3).any(|a| window[1][a] > meta.dims[a]) {
            return Err(FieldError::new(
                "store.window",
                format!(
                    "{window:?} reaches beyond the survey's {:?} voxels",
                    meta.dims
                ),
            )
            .into());
        }
        let pyramid = Pyramid {
            dims: meta.dims,
            brick: meta.brick,
            levels: meta.levels,
            window,
            spacing: params.spacing_for(meta.spacing),
        };
        let mut attributes = [None; 3];
        for (a, attr) in params.attributes().iter().enumerate() {
            let Some(attr) = attr else { continue };
            let index = store.attribute_index(attr.attribute.name()).map_err(|e| {
                super::error::Opacity3dError::of_attribute(e.into(), ATTRIBUTE_NAMES[a])
            })?;
            let am = &meta.attributes[index];
            let (low, high) = match attr.quantize {
                Quantization::MinMax => (am.min.unwrap_or(0.0), am.max.unwrap_or(0.0)),
                Quantization::Range([l, h]) => (l, h),
                Quantization::Percentile(_) => {
                    return Err(FieldError::new(
                        format!("{}.quantize", ATTRIBUTE_NAMES[a]),
                        "percentiles of a store are not computed; use \"min-max\" or { range = [low, high] }",
                    )
                    .into())
                }
            };
            attributes[a] = Some((index, low, high));
        }
        Ok(Some(StoreScene {
            store,
            view,
            pyramid,
            attributes,
        }))
    }
}

/// Time a streaming frame spends uploading what has arrived, a time rather than a count
/// of bricks (a brick of 66³ RGB8 is 0.86 MB, quick to upload on llvmpipe): the frame
/// stays interactive, and once the camera stops a frame takes in everything the loader
/// has read since the last one, where a small fixed count a frame made the full picture
/// take many frames (measured: docs/benchmarks.md, "Figures behind the store's settings").
const UPLOAD_TIME: std::time::Duration = std::time::Duration::from_millis(30);

/// The bricked 3D-opacity renderer.
pub struct BrickedRenderer {
    kind: ProgramKind,
    fidelity: Fidelity,
    /// Precise: the one-pass ray caster through the page table.
    paged: Option<PagedPass>,
    base: PathBuf,
    params: Opacity3dScene,
    view: StoreView,
    pyramid: Pyramid,
    cache: BrickCache,
    program: Program,
    tables: [Option<Texture>; 3],
    neutral: Option<Texture>,
    /// Per level, per brick (i fastest), per attribute: the levels its samples can read.
    levels: Vec<Vec<[(u8, u8); 3]>>,
    table_alpha: [Option<Vec<u8>>; 3],
    /// What NaN ("no data": dead traces) became in each attribute's levels; where level 0
    /// is reserved for it, the table's entry 0 is cleared, so no data is transparent.
    no_data: [NoData; 3],
    /// Per attribute, the alpha of the store's own distribution over its range (for a
    /// table that takes its alpha from the data, as a survey read whole does).
    data_alpha: [Option<[u8; 256]>; 3],
    mesh: Option<Mesh>,
    streaming: bool,
    last: (usize, usize, usize),
}

impl BrickedRenderer {
    /// Open the store the scene names and set up the cache (`gpu_memory` overrides the
    /// scene's budget).
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &Opacity3dScene,
        base: &Path,
        gpu_memory: Option<u64>,
    ) -> RenderResult<BrickedRenderer> {
        params.validate()?;
        if fidelity == Fidelity::Precise && kind == ProgramKind::Arb {
            return Err(GlError::Unsupported(
                "a store in precise mode is drawn by a ray caster through its page table, which is GLSL only (ARB fragment programs have no loops): use programs = \"glsl\" or fidelity = \"faithful\"".into(),
            ).into());
        }
        if params.clip.is_some() {
            return Err(
                GlError::Unsupported("a clip object on a store is not supported".into()).into(),
            );
        }
        let StoreScene {
            store,
            view,
            pyramid,
            attributes,
        } = StoreScene::open(params, base)?
            .ok_or_else(|| GlError::Invalid("the scene names no store".into()))?;
        let meta = &store.meta;
        let mut channels = [None; 3];
        let mut attrs = [None; 3];
        let mut no_data_of = [NoData::Absent; 3];
        let scene_attrs = params.attributes();
        for (a, at) in attributes.iter().enumerate() {
            if let Some((index, low, high)) = *at {
                // NaN takes a level the table makes transparent (see `NoData`).
                let alpha: Vec<u8> = match scene_attrs[a] {
                    Some(attr) => attr
                        .table
                        .build(base)?
                        .entries
                        .iter()
                        .map(|e| e[3])
                        .collect(),
                    None => Vec::new(),
                };
                let no_data = NoData::choose(store.may_hold_nan(index), &alpha);
                channels[CHANNEL[a]] = Some((index, low, high, no_data));
                attrs[a] = Some((index, low, high, no_data));
                no_data_of[a] = no_data;
            }
        }
        let budget = match gpu_memory {
            Some(b) => b,
            None => arbvis_core::budget::parse(&view.gpu_memory)?,
        };
        let cache = match fidelity {
            Fidelity::Faithful => BrickCache::new(
                store.clone(),
                Packing { channels },
                budget,
                params.volume_filter,
            ),
            Fidelity::Precise => {
                let bricks = (0..meta.levels)
                    .map(|l| meta.brick_counts(l).iter().product::<usize>())
                    .sum();
                BrickCache::atlas(
                    store.clone(),
                    Packing { channels },
                    budget,
                    params.volume_filter,
                    gpu.caps().max_3d_texture_size.max(1) as usize,
                    bricks,
                )
            }
        };
        // Which levels each brick may hold: what lets `draw` leave out clear bricks.
        let levels = super::brick_ranges::brick_ranges(&store, &attrs)?;
        let data_alpha = attrs.map(|at| {
            at.and_then(|(index, low, high, _)| alpha_of_store(&store, index, low, high))
        });
        let pair = faithful_pair(kind, params.combine);
        let program = Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?;
        let paged = match fidelity {
            Fidelity::Precise => Some(PagedPass::new(gpu, params)?),
            Fidelity::Faithful => None,
        };
        let mut r = BrickedRenderer {
            kind,
            fidelity,
            paged,
            base: base.to_path_buf(),
            params: params.clone(),
            view,
            pyramid,
            cache,
            program,
            tables: [None, None, None],
            neutral: None,
            levels,
            table_alpha: [None, None, None],
            no_data: no_data_of,
            data_alpha,
            mesh: None,
            streaming: false,
            last: (0, 0, 0),
        };
        r.build_tables(gpu)?;
        for (i, c) in coefficients(&r.params).iter().enumerate() {
            r.program
                .set_local(gpu, super::locals::COEFFICIENTS + i, *c)?;
        }
        Ok(r)
    }

    fn build_tables(&mut self, gpu: &Gpu) -> RenderResult<()> {
        for (a, attr) in self.params.attributes().into_iter().enumerate() {
            match attr {
                Some(attr) => {
                    let mut t = attr.table.build(&self.base)?;
                    // A store is a survey: its table's alpha from its data, as the
                    // survey read whole takes it, unless the table says otherwise.
                    if let Some(alpha) = self.data_alpha[a] {
                        if attr.table.wants_alpha_from_data(true) {
                            for (entry, alpha) in t.entries.iter_mut().zip(alpha) {
                                entry[3] = alpha;
                            }
                        }
                    }
                    if self.no_data[a] == NoData::Reserved {
                        t.entries[0] = [0; 4];
                    }
                    self.table_alpha[a] = Some(t.entries.iter().map(|e| e[3]).collect());
                    self.tables[a] = Some(table_texture(
                        gpu,
                        &format!("opacity3d {} table", ATTRIBUTE_NAMES[a]),
                        &t,
                        self.params.table_filter,
                        self.fidelity,
                    )?);
                }
                None => {
                    self.table_alpha[a] = None;
                    self.tables[a] = None;
                }
            }
        }
        self.neutral = neutral_for(gpu, &self.tables, self.params.combine, self.fidelity)?;
        Ok(())
    }

    /// Whether brick `id` can show anything under the tables and coefficients (alpha 0
    /// leaves the target unchanged under SRC_ALPHA blending, so skipping is exact).
    fn visible(&self, id: BrickId) -> bool {
        let counts = self.pyramid.counts(id.level as usize);
        let at = id.c[0] as usize + counts[0] * (id.c[1] as usize + counts[1] * id.c[2] as usize);
        let Some(ranges) = self.levels.get(id.level as usize).and_then(|l| l.get(at)) else {
            return true;
        };
        let c = coefficients(&self.params);
        let most = |a: usize| -> f64 {
            match &self.table_alpha[a] {
                // Linear tables read up to one entry past the level.
                Some(alpha) => {
                    let (lo, hi) = ranges[a];
                    let top = alpha[lo as usize..=(hi as usize + 1).min(255)]
                        .iter()
                        .copied()
                        .max()
                        .unwrap_or(0);
                    c[a][3] * top as f64
                }
                None => match self.params.combine {
                    Combine::Sum => 0.0,
                    Combine::Product => 1.0,
                },
            }
        };
        match self.params.combine {
            Combine::Sum => (0..3).any(|a| most(a) > 0.0),
            Combine::Product => (0..3).all(|a| most(a) > 0.0),
        }
    }

    fn view_of(&self, frame: &Frame) -> View {
        View {
            mvp: model_view_projection(frame),
            size: [frame.width, frame.height],
            eye: (frame.camera.projection == Projection::Perspective).then(|| eye(frame)),
            toward: toward_viewer(frame),
        }
    }

    /// Ask the loader for the roots and `wanted` (coarse first: the top level stands in
    /// for everything until finer arrives); returns how many of `wanted` are still to come
    /// (not resident, not failed: a failed brick never comes).
    fn ask_for(&mut self, wanted: &[BrickId]) -> usize {
        let missing = wanted
            .iter()
            .filter(|&&id| !self.cache.is_resident(id) && !self.cache.has_failed(id))
            .count();
        let mut ask: Vec<BrickId> = self.pyramid.roots();
        ask.extend(wanted.iter().copied());
        self.cache.request(&ask);
        missing
    }

    /// Bricks a streaming frame may want: the slots less the roots (always asked for, the
    /// stand-ins of last resort) and an eighth for the resident ancestors that stand in
    /// while the wanted bricks load. Wanting every slot livelocked: each arriving brick
    /// evicted another one the frame wanted (seen on an 18 GB survey at 1280x800).
    fn streaming_room(&self) -> usize {
        let capacity = self.cache.capacity();
        let roots = self.pyramid.roots().len();
        capacity.saturating_sub(roots + capacity / 8).max(1)
    }

    /// The bricks a full-quality frame wants, back to front.
    fn wanted(&self, view: &View, max_bricks: usize) -> Vec<BrickId> {
        let visible = |id: BrickId| self.visible(id);
        match self.view.level {
            Some(level) => {
                let level = level.min(self.pyramid.levels - 1) as u8;
                lod::wanted(&self.pyramid, view, f64::INFINITY, usize::MAX, &visible)
                    .into_iter()
                    .flat_map(|root| descend(&self.pyramid, root, level))
                    .filter(|&b| view.sees(self.pyramid.object_box(b)) && self.visible(b))
                    .collect()
            }
            None => lod::wanted(&self.pyramid, view, self.view.pixels, max_bricks, &visible),
        }
    }

    /// Slice polygons of the bricks `order` (back to front) as one vertex array, with the
    /// vertex range of each brick.
    fn slices(&self, frame: &Frame, order: &[BrickId]) -> (Vec<f32>, Vec<(usize, usize)>) {
        let n = toward_viewer(frame).normalize_or_zero();
        let h = self.pyramid.half();
        let depths: Vec<f64> = (0..8).map(|i| corner([-h, h], i).dot(n)).collect();
        let t_min = depths.iter().copied().fold(f64::INFINITY, f64::min);
        let t_max = depths.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let count = self.params.slices.max(1);
        let spacing = (t_max - t_min) / count as f64;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let mut out = Vec::new();
        let mut ranges = Vec::with_capacity(order.len());
        if n == DVec3::ZERO || spacing <= 0.0 {
            return (out, vec![(0, 0); order.len()]);
        }
        let b = self.pyramid.brick as f64;
        let win = self.pyramid.window;
        let nwin = DVec3::from_array(std::array::from_fn(|a| (win[1][a] - win[0][a]) as f64));
        let lo_win = DVec3::from_array(win[0].map(|x| x as f64));
        for &id in order {
            let start = out.len() / 8;
            let bx = self.pyramid.object_box(id);
            let d: Vec<f64> = (0..8).map(|i| corner(bx, i).dot(n)).collect();
            let (lo, hi) = (
                d.iter().copied().fold(f64::INFINITY, f64::min),
                d.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            );
            let first = ((lo - t_min) / spacing - 0.5).ceil().max(0.0) as usize;
            let last = (((hi - t_min) / spacing - 0.5).floor()).min(count as f64 - 1.0);
            let scale = (1u64 << id.level) as f64;
            let origin = DVec3::from_array(id.c.map(|c| c as f64 * b - 1.0));
            let tc = |p: DVec3| {
                let v0 = (p + h) / (2.0 * h) * nwin + lo_win;
                (v0 / scale - origin) / (b + 2.0)
            };
            if last >= 0.0 {
                for i in first..=last as usize {
                    let t = t_min + (i as f64 + 0.5) * spacing;
                    let poly = cut(bx, &d, t, u, v);
                    for k in 1..poly.len().saturating_sub(1) {
                        for q in [0, k, k + 1] {
                            let p = poly[q];
                            let t = tc(p);
                            out.extend_from_slice(&[
                                p.x as f32, p.y as f32, p.z as f32, 1.0, t.x as f32, t.y as f32,
                                t.z as f32, 1.0,
                            ]);
                        }
                    }
                }
            }
            ranges.push((start, out.len() / 8 - start));
        }
        (out, ranges)
    }

    fn draw_bricks(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        order: &[BrickId],
    ) -> RenderResult<()> {
        let (vertices, ranges) = self.slices(frame, order);
        if vertices.is_empty() {
            return Ok(());
        }
        match &mut self.mesh {
            Some(m) if m.vertex_count() >= vertices.len() / 8 => m.update(gpu, &vertices)?,
            _ => self.mesh = Some(Mesh::new(gpu, "store brick slices", &[4, 4], &vertices)?),
        }
        self.program
            .set_transform(gpu, model_view_projection(frame))?;
        for (&id, &(first, count)) in order.iter().zip(&ranges) {
            if count == 0 {
                continue;
            }
            let mut textures: Vec<(u32, &Texture)> = Vec::with_capacity(4);
            let Some(volume) = self.cache.texture(id) else {
                continue;
            };
            textures.push((super::renderer::VOLUME_UNIT, volume));
            for (a, t) in self.tables.iter().enumerate() {
                match (t, &self.neutral) {
                    (Some(t), _) | (None, Some(t)) => {
                        textures.push((super::renderer::TABLE_UNITS[a], t))
                    }
                    (None, None) => {}
                }
            }
            let Some(mesh) = &self.mesh else { break };
            arbvis_gl::draw(
                gpu,
                surface,
                &DrawCall {
                    range: Some((first, count)),
                    textures: &textures,
                    blend: Blend::Over,
                    ..DrawCall::new(&self.program, mesh)
                },
            )?;
        }
        Ok(())
    }

    /// Precise: one pass through the page table over what is resident (streaming), or
    /// over the full cut, chosen to fit the atlas (offscreen).
    fn draw_paged(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        view: &View,
    ) -> RenderResult<()> {
        let capacity = self.cache.capacity();
        self.cache.begin_frame();
        let drawn = if self.streaming {
            self.cache.receive(gpu, UPLOAD_TIME)?;
            let wanted = self.wanted(view, self.streaming_room());
            // The page table may overlap: each missing brick's nearest resident ancestor
            // stands in for it alone (finer resident bricks overwrite its pages), where
            // the painter's cut must give up every brick under a stand-in.
            let mut order: Vec<BrickId> = Vec::with_capacity(wanted.len());
            let mut stand_ins: HashSet<BrickId> = HashSet::new();
            for &id in &wanted {
                if self.cache.is_resident(id) {
                    order.push(id);
                    continue;
                }
                let mut a = self.pyramid.parent(id);
                while let Some(p) = a {
                    if self.cache.is_resident(p) {
                        stand_ins.insert(p);
                        break;
                    }
                    a = self.pyramid.parent(p);
                }
            }
            order.extend(stand_ins);
            let missing = self.ask_for(&wanted);
            self.last = (wanted.len(), order.len(), missing);
            order
        } else {
            let wanted = self.wanted(view, capacity);
            if wanted.len() > capacity {
                return Err(super::error::Opacity3dError::GpuBudget {
                    bricks: wanted.len(),
                    capacity,
                }
                .into());
            }
            self.cache.ensure(gpu, &wanted)?;
            if let Some(e) = wanted.iter().find_map(|&id| self.cache.error(id)) {
                return Err(e.into());
            }
            self.last = (wanted.len(), wanted.len(), 0);
            wanted
        };
        let Some((_, grid)) = self.cache.atlas_texture() else {
            return Ok(());
        };
        let cache = &mut self.cache;
        let table = PageTable::build(&self.pyramid, grid, &drawn, &mut |id| cache.slot(id));
        let mut tables: Vec<(u32, &Texture)> = Vec::with_capacity(3);
        for (a, t) in self.tables.iter().enumerate() {
            if let Some(t) = t {
                tables.push((super::renderer::TABLE_UNITS[a], t));
            }
        }
        let (Some(paged), Some(atlas)) = (&mut self.paged, self.cache.atlas_texture()) else {
            return Ok(());
        };
        paged.draw(
            gpu,
            surface,
            frame,
            &self.params,
            &self.pyramid,
            atlas,
            &table,
            &tables,
        )
    }

    /// The cache's counts.
    pub fn cache_stats(&self) -> crate::techniques::opacity3d::brick_cache::CacheStats {
        self.cache.stats()
    }
}

/// Every brick of `level` under `root`.
fn descend(pyr: &Pyramid, root: BrickId, level: u8) -> Vec<BrickId> {
    if root.level <= level {
        return vec![root];
    }
    pyr.children(root)
        .into_iter()
        .flat_map(|c| descend(pyr, c, level))
        .collect()
}

fn corner(b: [DVec3; 2], i: usize) -> DVec3 {
    DVec3::new(
        if i & 1 == 0 { b[0].x } else { b[1].x },
        if i & 2 == 0 { b[0].y } else { b[1].y },
        if i & 4 == 0 { b[0].z } else { b[1].z },
    )
}

/// The polygon where the plane `n·p = t` meets box `b` (`d` = `n·corner`), counter-
/// clockwise about `n = u × v`. Vertices are computed from absolute corners, lower corner
/// first, so two boxes sharing an edge give that edge's crossing bit for bit.
fn cut(b: [DVec3; 2], d: &[f64], t: f64, u: DVec3, v: DVec3) -> Vec<DVec3> {
    let mut points: Vec<DVec3> = Vec::with_capacity(6);
    for &(a, c) in &EDGES {
        let (da, dc) = (d[a] - t, d[c] - t);
        if (da < 0.0) != (dc < 0.0) {
            let s = da / (da - dc);
            let (pa, pc) = (corner(b, a), corner(b, c));
            points.push((pa + (pc - pa) * s).clamp(b[0], b[1]));
        }
    }
    polygon(points, 1e-12, u, v)
}

impl Renderer for BrickedRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        let view = self.view_of(frame);
        if self.paged.is_some() {
            return self.draw_paged(gpu, surface, frame, &view);
        }
        if self.streaming {
            self.cache.begin_frame();
            self.cache.receive(gpu, UPLOAD_TIME)?;
            let wanted = self.wanted(&view, self.streaming_room());
            let resident = |id: BrickId| self.cache.is_resident(id);
            let (order, _) = lod::drawable(&self.pyramid, &view, &wanted, &resident);
            let missing = self.ask_for(&wanted);
            for &id in &order {
                self.cache.touch(id);
            }
            self.last = (wanted.len(), order.len(), missing);
            return self.draw_bricks(gpu, surface, frame, &order);
        }
        // Offscreen: the full-quality cut, in batches the budget holds.
        let wanted = self.wanted(&view, usize::MAX);
        let set: HashSet<BrickId> = wanted.iter().copied().collect();
        let order = lod::back_to_front(&self.pyramid, &view, &set);
        self.last = (wanted.len(), order.len(), 0);
        for batch in order.chunks(self.cache.capacity()) {
            self.cache.begin_frame();
            self.cache.ensure(gpu, batch)?;
            if let Some(e) = batch.iter().find_map(|&id| self.cache.error(id)) {
                return Err(e.into());
            }
            self.draw_bricks(gpu, surface, frame, batch)?;
        }
        Ok(())
    }

    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let new = params.get::<Opacity3dScene>()?;
        new.validate()?;
        let data = |p: &Opacity3dScene| {
            (
                p.attributes()
                    .map(|a| a.map(|a| (a.volume.clone(), a.attribute, a.quantize))),
                p.volume_filter,
                p.store.clone(),
                p.spacing,
            )
        };
        if data(&self.params) != data(new) {
            let streaming = self.streaming;
            *self =
                BrickedRenderer::new(gpu, self.kind, self.fidelity, new, &self.base.clone(), None)?;
            self.streaming = streaming;
            return Ok(());
        }
        let combine_changed = new.combine != self.params.combine;
        self.params = new.clone();
        self.build_tables(gpu)?;
        if let Some(paged) = &mut self.paged {
            paged.program_for(gpu, &self.params)?;
            return Ok(());
        }
        if combine_changed {
            let pair = faithful_pair(self.kind, self.params.combine);
            self.program = Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?;
        }
        for (i, c) in coefficients(&self.params).iter().enumerate() {
            self.program
                .set_local(gpu, super::locals::COEFFICIENTS + i, *c)?;
        }
        Ok(())
    }

    fn program_kind(&self) -> ProgramKind {
        match self.paged {
            Some(_) => ProgramKind::Glsl,
            None => self.program.kind(),
        }
    }

    fn status(&self) -> Option<String> {
        let s = self.cache.stats();
        let levels: Vec<String> = s
            .per_level
            .iter()
            .enumerate()
            .filter(|(_, &n)| n > 0)
            .map(|(l, n)| format!("L{l}: {n}"))
            .collect();
        let mut line = format!(
            "bricks: {} resident of {} slots ({}), {:.1} MB; {} drawn, {} wanted",
            s.resident,
            s.capacity,
            levels.join(", "),
            s.bytes as f64 / 1e6,
            self.last.1,
            self.last.0,
        );
        if self.last.2 > 0 || s.loading > 0 {
            line += &format!("; loading {} ({} not yet resident)", s.loading, self.last.2);
        }
        if let Some(e) = s.first_error {
            line += &format!("; {} bricks failed: {e}", s.failed);
        }
        Some(line)
    }

    fn streaming(&self) -> Option<&dyn Streaming> {
        Some(self)
    }

    fn streaming_mut(&mut self) -> Option<&mut dyn Streaming> {
        Some(self)
    }
}

impl Streaming for BrickedRenderer {
    fn set_streaming(&mut self, streaming: bool) {
        self.streaming = streaming;
    }

    fn pending(&self) -> bool {
        self.streaming && self.last.2 > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbouring_bricks_share_their_slice_edges_bit_for_bit() {
        // Two boxes sharing the face x = 0.1 (as two bricks' object boxes), an oblique
        // plane: the vertices on the shared face are the same f64 values in both.
        let a = [DVec3::new(-0.7, -0.3, -0.2), DVec3::new(0.1, 0.35, 0.4)];
        let b = [DVec3::new(0.1, -0.3, -0.2), DVec3::new(0.9, 0.35, 0.4)];
        let n = DVec3::new(0.31, -0.52, 0.79).normalize();
        let (u, v) = (
            n.any_orthonormal_vector(),
            n.cross(n.any_orthonormal_vector()),
        );
        for t in [-0.2, -0.05, 0.0, 0.13, 0.3] {
            let da: Vec<f64> = (0..8).map(|i| corner(a, i).dot(n)).collect();
            let db: Vec<f64> = (0..8).map(|i| corner(b, i).dot(n)).collect();
            let pa = cut(a, &da, t, u, v);
            let pb = cut(b, &db, t, u, v);
            let on = |p: &DVec3| p.x == 0.1;
            let mut sa: Vec<[u64; 3]> = pa
                .iter()
                .filter(|p| on(p))
                .map(|p| p.to_array().map(f64::to_bits))
                .collect();
            let mut sb: Vec<[u64; 3]> = pb
                .iter()
                .filter(|p| on(p))
                .map(|p| p.to_array().map(f64::to_bits))
                .collect();
            sa.sort_unstable();
            sb.sort_unstable();
            assert_eq!(sa, sb, "plane {t}");
            // The plane crosses the shared face in a segment: two vertices each side.
            assert_eq!(sa.len(), 2, "plane {t}: {pa:?}");
        }
    }
}
