//! The GL side of 3D opacity: the packed volume on unit 0, tables on units 2/3/4, and
//! the program of the scene's fidelity and path:
//! - faithful: the verbatim sum or product program on view-aligned slices (RGB8 volume,
//!   RGBA8 tables), the slice mesh rebuilt when the view direction or slice count changes;
//! - precise slicing: the same slices with a program specialized to the scene
//!   ([`super::programs`]), the present attributes only (one in f32, more in 16-bit
//!   unorm: k/255 exactly either way);
//! - precise ray casting (GLSL): the box's far faces, one fragment per pixel marching its
//!   ray, with the brick occupancy of empty-space skipping on unit 5.
//!
//! With a clip ([`super::clipping`]) every program has the clip test composed in and the
//! clip's textures sit on units 7 and 8.

use crate::error::RenderResult;
use std::path::{Path, PathBuf};

use glam::DMat4;

use super::bricks::Bricks;
use super::changes::Changes;
use super::clipping::{self, Clip};
use super::locals;
use super::prepare::{prepare, Prepared};
pub use super::programs::faithful_pair;
use super::programs::{raycast_pair, slicing_pair, InShader, Variant};
use super::proxy::{eye, toward_viewer, Proxy};
use super::textures::unit_filter;
use super::textures::{neutral_for, table_texture, uses_neighbours, volume_texture};
use super::Interpolation;
pub use super::{coefficients, corrected, path, preintegrated, Path3d};
use super::{Combine, Opacity3dScene};
use crate::programs;
use arbvis_core::camera::Projection;
use arbvis_gl::{
    self, Blend, DrawCall, Extent, Filter, GlError, Gpu, Program, ProgramChoice, ProgramKind,
    Surface, TexelData, TexelFormat, Texture,
};

use crate::techniques::clip::stage as clipping_stage;
use crate::techniques::{DrawInParts, Frame, Params, Renderer};
use arbvis_core::vocab::Fidelity;
use arbvis_data::volume::quantize::NoData;

/// Texture unit of the packed volume and of the three tables (unit 1 is v3o2's
/// lighting, unused here).
pub const VOLUME_UNIT: u32 = 0;
/// Units of the primary, secondary and tertiary tables.
pub const TABLE_UNITS: [u32; 3] = [2, 3, 4];
/// Unit of the ray caster's brick occupancy.
pub const BRICK_UNIT: u32 = 5;

/// The whole volume in texture coordinates (the ray caster samples all of it).
const WHOLE: [[f64; 3]; 2] = [[0.0; 3], [1.0; 3]];

/// Voxels per side of the bricks whose box bounds the ray caster's margins (when the
/// scene does not skip with its own): small enough to fit round data closely, large
/// enough that a pass over the volume stays cheap.
const MARGIN_BRICK: usize = 8;
/// Unit of the ray caster's pre-integration table.
pub const PREINT_UNIT: u32 = 6;

/// The ray caster's table on unit 6, if its scene uses one.
pub enum StepTable {
    /// None: point sampling with `pow`, or slicing.
    None,
    /// Pre-integration, `SIZE²` RGBA ([`super::preint::preintegrate`]).
    Preint(Vec<f32>),
    /// One attribute, jittered steps: colour and opacity of a step, `BAKED` RGBA
    /// ([`super::preint::baked`]), used only within its tolerance.
    Baked(Vec<f32>),
}

/// The table a ray-casting scene needs (one attribute only, no clip: a clipped scene
/// point-samples through the clip test).
pub fn step_table(params: &Opacity3dScene, fidelity: Fidelity, prepared: &Prepared) -> StepTable {
    let (Some(r), Some(table)) = (&params.raycast, &prepared.tables[0]) else {
        return StepTable::None;
    };
    if params.clip.is_some() {
        return StepTable::None;
    }
    let one = prepared.count() == 1;
    if path(params, fidelity) != Path3d::Raycast || !one || !corrected(params, fidelity) {
        return StepTable::None;
    }
    let c = coefficients(params)[0];
    let (combine, filter, exponent) =
        (params.combine, params.table_filter, 1.0 / r.steps_per_voxel);
    if r.preintegrate {
        StepTable::Preint(super::preint::preintegrate(
            table, c, combine, filter, exponent,
        ))
    } else if r.jitter && r.bake {
        match super::preint::baked(table, c, combine, filter, exponent) {
            (data, worst) if worst < super::preint::BAKED_TOLERANCE => StepTable::Baked(data),
            _ => StepTable::None,
        }
    } else {
        StepTable::None
    }
}

/// The program kind a scene draws with: the ray caster is GLSL only, so `auto` gives GLSL
/// there; an explicit `arb` stays (and the renderer says why it cannot). A precise clipped
/// scene on a driver whose texture units filter coarsely also gets GLSL under `auto`: only
/// the GLSL clip test interpolates its values in the shader.
pub fn resolve_kind(
    gpu: &Gpu,
    params: &Opacity3dScene,
    fidelity: Fidelity,
    programs: ProgramChoice,
    kind: ProgramKind,
) -> RenderResult<ProgramKind> {
    if programs != ProgramChoice::Auto {
        return Ok(kind);
    }
    let glsl = path(params, fidelity) == Path3d::Raycast
        || (fidelity == Fidelity::Precise
            && params.clip.is_some()
            && shader_filter(gpu, params, fidelity)?.clip);
    Ok(if glsl { ProgramKind::Glsl } else { kind })
}

/// What a precise program computes itself on `gpu` (nothing when faithful: the era's
/// texture units and rasterizer, whatever their precision).
pub fn shader_filter(
    gpu: &Gpu,
    params: &Opacity3dScene,
    fidelity: Fidelity,
) -> RenderResult<InShader> {
    Ok(match fidelity {
        Fidelity::Faithful => InShader::default(),
        // The probes only where `auto` asks them.
        Fidelity::Precise if params.interpolation != Interpolation::Auto => {
            InShader::for_scene(params, true, true)
        }
        Fidelity::Precise => {
            InShader::for_scene(params, gpu.filters_exactly()?, gpu.interpolates_exactly()?)
        }
    })
}

/// Every pair 3D opacity can draw with: the verbatim faithful programs and their GLSL
/// ports, every specialization of the precise templates, and the clip's prologues composed
/// with the verbatim programs.
pub fn program_pairs() -> Vec<programs::ProgramPair> {
    let mut pairs = Vec::new();
    for combine in [Combine::Sum, Combine::Product] {
        for kind in [ProgramKind::Arb, ProgramKind::Glsl] {
            pairs.push(faithful_pair(kind, combine));
        }
    }
    pairs.extend(super::programs::all_precise_pairs());
    pairs.extend(clipping::all_clip_pairs());
    pairs
}

/// Object space to clip space: the camera's view-projection (the box sits in [-1, 1]³).
pub fn model_view_projection(frame: &Frame) -> DMat4 {
    frame.camera.view_projection(frame.aspect())
}

/// The precise programs' per-pixel points (locals 16-21 of `raycast.frag` and
/// `slice_precise`): window position on `surface` to NDC (scale and offset), and the rows
/// of the inverse view-projection, so that each pixel unprojects its own centre rather
/// than trusting an interpolated coordinate.
pub fn send_pixel_rays(
    gpu: &Gpu,
    program: &Program,
    surface: Surface<'_>,
    frame: &Frame,
) -> RenderResult<()> {
    let [x, y, w, h] = surface.rect();
    let (w, h) = (w.max(1.0), h.max(1.0));
    program.set_local(
        gpu,
        locals::PIXEL_TO_NDC_SCALE,
        [2.0 / w, 2.0 / h, 2.0, 0.0],
    )?;
    program.set_local(
        gpu,
        locals::PIXEL_TO_NDC_OFFSET,
        [-1.0 - 2.0 * x / w, -1.0 - 2.0 * y / h, -1.0, 1.0],
    )?;
    let inverse = model_view_projection(frame).inverse().transpose();
    for (i, row) in [
        inverse.x_axis,
        inverse.y_axis,
        inverse.z_axis,
        inverse.w_axis,
    ]
    .iter()
    .enumerate()
    {
        program.set_local(gpu, locals::INVERSE_MVP + i, row.to_array())?;
    }
    Ok(())
}

/// The 3D-opacity renderer.
pub struct Opacity3dRenderer {
    kind: ProgramKind,
    /// What the precise programs compute themselves (the textures are made for it).
    filter: InShader,
    /// What `program` was built to compute itself (an update that fails half-way can leave
    /// it behind `filter`; the next one rebuilds it).
    program_filter: InShader,
    fidelity: Fidelity,
    base: PathBuf,
    params: Opacity3dScene,
    prepared: Prepared,
    program: Program,
    projection: Projection,
    volume: Texture,
    /// Whether `volume` holds neighbour words ([`uses_neighbours`]).
    neighbours: bool,
    tables: [Option<Texture>; 3],
    neutral: Option<Texture>,
    /// The ray caster's bricks (for skipping or its margins), and their occupancy on
    /// unit [`BRICK_UNIT`] when it skips empty bricks.
    bricks: Option<(Bricks, Option<Texture>)>,
    /// Where the ray caster samples, in texture coordinates (the box of the occupied
    /// bricks, or the whole volume): locals 22 and 23.
    occupied: [[f64; 3]; 2],
    preint: Option<Texture>,
    baked: bool,
    /// The slices or the ray caster's box ([`Proxy`]).
    proxy: Proxy,
    clip: Option<Clip>,
}

impl Opacity3dRenderer {
    /// Load and prepare the scene's data (relative paths from `base`), then upload; the
    /// precise programs are built for `projection` (and rebuilt if a frame's differs).
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &Opacity3dScene,
        base: &Path,
        projection: Projection,
    ) -> RenderResult<Opacity3dRenderer> {
        params.validate()?;
        let prepared = prepare(
            params,
            base,
            &arbvis_data::volume::Limits::for_max_side(gpu.caps().max_3d_texture_size),
        )?;
        Opacity3dRenderer::from_prepared(gpu, kind, fidelity, params, base, prepared, projection)
    }

    /// Upload data prepared elsewhere (tests and benches craft or share volumes).
    pub fn from_prepared(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &Opacity3dScene,
        base: &Path,
        prepared: Prepared,
        projection: Projection,
    ) -> RenderResult<Opacity3dRenderer> {
        params.validate()?;
        let [ni, nj, nk] = prepared.dims;
        let max = gpu.caps().max_3d_texture_size.max(1) as usize;
        if prepared.dims.iter().any(|&d| d > max) {
            return Err(GlError::Unsupported(format!(
                "volume {ni}x{nj}x{nk} exceeds GL_MAX_3D_TEXTURE_SIZE {max}"
            ))
            .into());
        }
        let table = step_table(params, fidelity, &prepared);
        let baked = matches!(table, StepTable::Baked(_));
        let clip = match &params.clip {
            Some(spec) => Some(clipping::build(gpu, spec, base, &prepared, fidelity)?),
            None => None,
        };
        let stage = clip.as_ref().map(|c| &c.stage);
        let program = make_program(
            gpu, kind, fidelity, params, &prepared, projection, baked, stage,
        )?;
        let filter = shader_filter(gpu, params, fidelity)?;
        let neighbours = uses_neighbours(params, fidelity, &prepared);
        let volume = volume_texture(gpu, fidelity, params, &prepared, filter, neighbours)?;
        let mut renderer = Opacity3dRenderer {
            kind,
            filter,
            program_filter: filter,
            fidelity,
            base: base.to_path_buf(),
            params: params.clone(),
            prepared,
            program,
            projection,
            volume,
            neighbours,
            tables: [None, None, None],
            neutral: None,
            bricks: None,
            occupied: WHOLE,
            preint: None,
            baked,
            proxy: Proxy::None,
            clip,
        };
        renderer.build_tables(gpu)?;
        renderer.build_bricks(gpu)?;
        renderer.upload_step_table(gpu, table)?;
        renderer.send_constants(gpu)?;
        Ok(renderer)
    }

    /// The prepared data (for references and the viewer's readouts).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// The clip, if the scene has one (its f64 shape is the reference's predicate).
    pub fn clip(&self) -> Option<&Clip> {
        self.clip.as_ref()
    }

    /// The path this renderer draws with.
    pub fn path(&self) -> Path3d {
        path(&self.params, self.fidelity)
    }

    /// Whether `new`'s tables make the level no data took opaque: the volume is then
    /// quantized again, so that no data stays undrawn ([`NoData::choose`]).
    fn no_data_moves(&self, new: &Opacity3dScene) -> RenderResult<bool> {
        for (a, attr) in new.attributes().into_iter().enumerate() {
            let (Some(attr), NoData::Level(level)) = (attr, self.prepared.no_data[a]) else {
                continue;
            };
            let table = attr.table.build(&self.base)?;
            if table.entries[level as usize][3] != 0 {
                return Ok(true);
            }
        }
        Ok(false)
    }

    fn build_tables(&mut self, gpu: &Gpu) -> RenderResult<()> {
        let names = super::ATTRIBUTE_NAMES;
        for (a, name) in names.iter().enumerate() {
            self.tables[a] = match &self.prepared.tables[a] {
                Some(t) => Some(table_texture(
                    gpu,
                    &format!("opacity3d {name} table"),
                    t,
                    unit_filter(self.params.table_filter, self.filter.tables),
                    self.fidelity,
                )?),
                None => None,
            };
        }
        self.neutral = neutral_for(gpu, &self.tables, self.params.combine, self.fidelity)?;
        Ok(())
    }

    /// The ray caster's table on unit 6 (pre-integration or baked), or none.
    fn upload_step_table(&mut self, gpu: &Gpu, table: StepTable) -> RenderResult<()> {
        let (label, extent, data) = match table {
            StepTable::None => {
                self.preint = None;
                return Ok(());
            }
            StepTable::Preint(data) => {
                let n = super::preint::SIZE as u32;
                (
                    "opacity3d pre-integration table (front x back)",
                    Extent::D2(n, n),
                    data,
                )
            }
            StepTable::Baked(data) => (
                "opacity3d baked step table (colour and opacity of a step)",
                Extent::D1(super::preint::BAKED as u32),
                data,
            ),
        };
        self.preint = Some(Texture::new(
            gpu,
            label,
            extent,
            TexelFormat::Rgba32f,
            Filter::Linear,
            TexelData::F32(&data),
        )?);
        Ok(())
    }

    /// The ray caster's bricks and their occupancy for the current tables: a texture for
    /// empty-space skipping, the occupied box for its margins.
    fn build_bricks(&mut self, gpu: &Gpu) -> RenderResult<()> {
        let preint = preintegrated(&self.params, self.fidelity, self.prepared.count());
        self.occupied = WHOLE;
        let (size, skip, margins) = match (&self.params.raycast, self.path()) {
            (Some(r), Path3d::Raycast) if !preint => {
                let skip = r.brick > 0 && !r.jitter;
                match (skip, r.margins) {
                    (true, m) => (r.brick, true, m),
                    (false, true) => (MARGIN_BRICK, false, true),
                    (false, false) => (0, false, false),
                }
            }
            _ => (0, false, false),
        };
        if size == 0 {
            self.bricks = None;
            return Ok(());
        }
        let bricks = match self.bricks.take() {
            Some((b, _)) if b.size == size => b,
            _ => Bricks::new(&self.prepared, size),
        };
        let occupancy = bricks.occupancy(&self.prepared, &self.params);
        if margins {
            // Nothing visible: a box outside the volume, which no ray meets inside it.
            self.occupied = bricks
                .occupied_box(&self.prepared, &occupancy)
                .unwrap_or([[2.0; 3], [2.0; 3]]);
        }
        let texture = match skip {
            true => {
                let [bi, bj, bk] = bricks.counts.map(|c| c as u32);
                Some(Texture::new(
                    gpu,
                    "opacity3d brick occupancy (empty-space skipping)",
                    Extent::D3(bi, bj, bk),
                    TexelFormat::R8,
                    Filter::Nearest,
                    TexelData::U8(&occupancy),
                )?)
            }
            false => None,
        };
        self.bricks = Some((bricks, texture));
        Ok(())
    }

    fn send_constants(&self, gpu: &Gpu) -> RenderResult<()> {
        for (i, c) in coefficients(&self.params).iter().enumerate() {
            self.program.set_local(gpu, locals::COEFFICIENTS + i, *c)?;
        }
        if let Some(clip) = &self.clip {
            clip.stage.send(gpu, &self.program)?;
        }
        if self.fidelity == Fidelity::Precise {
            let p = &self.program;
            p.set_local(
                gpu,
                locals::LOOKUP,
                [255.0 / 256.0, 0.5 / 256.0, 1.0 / 3.0, 0.0],
            )?;
            let half = self.prepared.half;
            p.set_local(gpu, locals::BOX_SIZE, (2.0 * half).extend(0.0).to_array())?;
            p.set_local(gpu, locals::BOX_HALF, half.extend(0.0).to_array())?;
            if self.filter.volume && self.path() == Path3d::Slicing {
                // slice_precise.arbfp's own trilinear (exact_volume): size and 1 / size.
                let dims = self.prepared.dims.map(|d| d as f64);
                p.set_local(gpu, locals::EXACT_SIZE, [dims[0], dims[1], dims[2], 1.0])?;
                p.set_local(
                    gpu,
                    locals::EXACT_INVERSE_SIZE,
                    [1.0 / dims[0], 1.0 / dims[1], 1.0 / dims[2], 1.0],
                )?;
            }
        }
        Ok(())
    }

    fn update_mesh(&mut self, gpu: &Gpu, frame: &Frame) -> RenderResult<()> {
        let (path, half, slices) = (self.path(), self.prepared.half, self.params.slices);
        Ok(self.proxy.update(gpu, path, half, frame, slices)?)
    }

    /// Precise mode's per-frame locals 4, 8 and 9 (see the program templates).
    fn send_view(&self, gpu: &Gpu, frame: &Frame) -> RenderResult<()> {
        let reference = self.prepared.reference_spacing();
        let (scale, offset) = if corrected(&self.params, self.fidelity) {
            (1.0 / reference, 0.0)
        } else {
            (0.0, 1.0)
        };
        let n = toward_viewer(frame).normalize();
        let perspective = frame.camera.projection == Projection::Perspective;
        let p = &self.program;
        match (self.path(), &self.params.raycast) {
            (Path3d::Raycast, Some(r)) => {
                let step = reference / r.steps_per_voxel;
                p.set_local(gpu, locals::CORRECTION, [scale, step, offset, 0.0])?;
                let ray = if perspective { eye(frame) } else { -n };
                p.set_local(gpu, locals::RAY, ray.extend(0.0).to_array())?;
                let per_unit = match &self.bricks {
                    Some((b, Some(_))) => b.per_unit(&self.prepared),
                    _ => [1.0; 3],
                };
                let stop = 1.0 - r.termination;
                p.set_local(
                    gpu,
                    locals::AXIS,
                    [per_unit[0], per_unit[1], per_unit[2], stop],
                )?;
                let [lo, hi] = self.occupied;
                p.set_local(gpu, locals::OCCUPIED_LOW, [lo[0], lo[1], lo[2], 0.0])?;
                p.set_local(gpu, locals::OCCUPIED_HIGH, [hi[0], hi[1], hi[2], 0.0])?;
            }
            _ => {
                p.set_local(
                    gpu,
                    locals::CORRECTION,
                    [scale, self.proxy.spacing() / 2.0, offset, 0.0],
                )?;
                if perspective {
                    p.set_local(gpu, locals::RAY, eye(frame).extend(0.0).to_array())?;
                    p.set_local(gpu, locals::AXIS, n.extend(0.0).to_array())?;
                } else {
                    // Rays run along -n: per axis its sign and 1 / |component|.
                    let r = -n;
                    let sign = r.to_array().map(|c| if c < 0.0 { -1.0 } else { 1.0 });
                    let inv = r.to_array().map(|c| 1.0 / c.abs().max(1e-20));
                    p.set_local(gpu, locals::RAY, [sign[0], sign[1], sign[2], 0.0])?;
                    p.set_local(gpu, locals::AXIS, [inv[0], inv[1], inv[2], 0.0])?;
                }
            }
        }
        Ok(())
    }
}

/// The program for a fidelity, path and projection, with `clip`'s test composed in.
#[allow(clippy::too_many_arguments)]
fn make_program(
    gpu: &Gpu,
    kind: ProgramKind,
    fidelity: Fidelity,
    params: &Opacity3dScene,
    prepared: &Prepared,
    projection: Projection,
    baked: bool,
    clip: Option<&clipping_stage::ClipStage>,
) -> RenderResult<Program> {
    let preint = preintegrated(params, fidelity, prepared.count());
    let variant = Variant {
        combine: params.combine,
        present: prepared.present(),
        projection,
        skip: params.raycast.is_some_and(|r| r.brick > 0 && !r.jitter) && !preint,
        preint,
        jitter: params.raycast.is_some_and(|r| r.jitter) && !preint,
        baked,
        paged: false,
        neighbours: uses_neighbours(params, fidelity, prepared),
        filter: shader_filter(gpu, params, fidelity)?,
    };
    let pair = match (fidelity, path(params, fidelity)) {
        (Fidelity::Faithful, _) => faithful_pair(kind, params.combine),
        (Fidelity::Precise, Path3d::Slicing) => slicing_pair(kind, variant),
        (Fidelity::Precise, Path3d::Raycast) => {
            if kind == ProgramKind::Arb {
                return Err(GlError::Unsupported(
                    "the precise ray caster is GLSL only (ARB fragment programs have no \
                     loops): use programs = \"glsl\" or \"auto\""
                        .into(),
                )
                .into());
            }
            raycast_pair(variant)
        }
    };
    let pair = match clip {
        Some(stage) => {
            let exact = pair.kind == ProgramKind::Glsl && variant.filter.clip;
            clipping::compose(pair, stage, path(params, fidelity), exact)?
        }
        None => pair,
    };
    Ok(Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?)
}

impl Opacity3dRenderer {
    /// Draw the slices `slices` (indices back to front; the end may run past the last),
    /// or, on the ray caster's path, the whole box.
    fn draw_slices(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        slices: std::ops::Range<usize>,
    ) -> RenderResult<()> {
        let projection = frame.camera.projection;
        if self.fidelity == Fidelity::Precise && projection != self.projection {
            self.program = make_program(
                gpu,
                self.kind,
                self.fidelity,
                &self.params,
                &self.prepared,
                projection,
                self.baked,
                self.clip.as_ref().map(|c| &c.stage),
            )?;
            self.projection = projection;
            self.send_constants(gpu)?;
        }
        self.update_mesh(gpu, frame)?;
        let ends = self.proxy.slice_ends();
        let vertex = |s: usize| match s.checked_sub(1) {
            Some(i) => ends.get(i).or(ends.last()).copied().unwrap_or(0),
            None => 0,
        };
        let (first, end) = (vertex(slices.start), vertex(slices.end));
        self.program
            .set_transform(gpu, model_view_projection(frame))?;
        if self.fidelity == Fidelity::Precise {
            self.send_view(gpu, frame)?;
            send_pixel_rays(gpu, &self.program, surface, frame)?;
        }
        let mut textures: Vec<(u32, &Texture)> = vec![(VOLUME_UNIT, &self.volume)];
        for (a, t) in self.tables.iter().enumerate() {
            match (t, &self.neutral) {
                (Some(t), _) | (None, Some(t)) => textures.push((TABLE_UNITS[a], t)),
                (None, None) => {}
            }
        }
        if let Some((_, Some(t))) = &self.bricks {
            textures.push((BRICK_UNIT, t));
        }
        if let Some(t) = &self.preint {
            textures.push((PREINT_UNIT, t));
        }
        if let Some(clip) = &self.clip {
            textures.extend(clip.stage.textures());
        }
        let Some(mesh) = self.proxy.mesh() else {
            return Ok(());
        };
        let raycast = self.path() == Path3d::Raycast;
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                range: (!raycast).then_some((first, end.saturating_sub(first))),
                textures: &textures,
                blend: if raycast {
                    Blend::PremultipliedOver
                } else {
                    Blend::Over
                },
                cull_back: raycast,
                // Each ray runs the whole box: in a layered scene it is not cut by an
                // opaque layer's depth (docs/scenes.md, Layers).
                covers_frame: raycast,
                primitive: Default::default(),
                ..DrawCall::new(&self.program, mesh)
            },
        )?)
    }
}

impl Renderer for Opacity3dRenderer {
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{colours, Annotations, Legend};
        let p = &self.prepared;
        let legends = self
            .params
            .attributes()
            .into_iter()
            .enumerate()
            .filter_map(|(a, attr)| {
                let (attr, table, (low, high)) = (attr?, p.tables[a].as_ref()?, p.ranges[a]?);
                Some(Legend::Bar {
                    title: format!("{}: {}", super::ATTRIBUTE_NAMES[a], attr.attribute.name()),
                    colours: colours(&table.entries),
                    low,
                    high,
                })
            })
            .collect();
        let axes =
            arbvis_data::volume::axes::describe(&self.params.primary.volume, &self.base, p.dims);
        Annotations {
            legends,
            axes: Some(crate::techniques::annotations::BoxAxes::new(
                p.half.to_array(),
                axes,
            )),
        }
    }

    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        self.draw_slices(gpu, surface, frame, 0..usize::MAX)
    }

    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let new = params.get::<Opacity3dScene>()?;
        new.validate()?;
        let old = std::mem::replace(&mut self.params, new.clone());
        let changes = Changes::between(&old, new);
        if changes.data || self.no_data_moves(new)? {
            let prepared = prepare(
                new,
                &self.base,
                &arbvis_data::volume::Limits::for_max_side(gpu.caps().max_3d_texture_size),
            )?;
            *self = Opacity3dRenderer::from_prepared(
                gpu,
                self.kind,
                self.fidelity,
                new,
                &self.base.clone(),
                prepared,
                self.projection,
            )?;
            return Ok(());
        }
        self.filter = shader_filter(gpu, new, self.fidelity)?;
        if changes.tables {
            for (a, attr) in new.attributes().into_iter().enumerate() {
                if let Some(attr) = attr {
                    let mut table = attr.table.build(&self.base)?;
                    if self.prepared.no_data[a] == NoData::Reserved {
                        table.entries[0] = [0; 4];
                    }
                    self.prepared.tables[a] = Some(table);
                }
            }
            self.build_tables(gpu)?;
        }
        self.build_bricks(gpu)?;
        if changes.clip {
            let built = match &new.clip {
                Some(spec) => {
                    clipping::build(gpu, spec, &self.base, &self.prepared, self.fidelity).map(Some)
                }
                None => Ok(None),
            };
            match built {
                Ok(clip) => self.clip = clip,
                Err(e) => {
                    // Keep the clip drawn with and remember it, so the next update with the
                    // new clip tries again.
                    self.params.clip = old.clip.clone();
                    return Err(e);
                }
            }
        }
        let neighbours = uses_neighbours(new, self.fidelity, &self.prepared);
        let volume_changed = neighbours != self.neighbours;
        if volume_changed {
            let (fidelity, filter) = (self.fidelity, self.filter);
            self.volume = volume_texture(gpu, fidelity, new, &self.prepared, filter, neighbours)?;
            self.neighbours = neighbours;
        }
        let table = step_table(new, self.fidelity, &self.prepared);
        let baked = matches!(table, StepTable::Baked(_));
        if changes.program
            || baked != self.baked
            || volume_changed
            || changes.clip
            || self.program_filter != self.filter
        {
            self.baked = baked;
            self.program_filter = self.filter;
            self.program = make_program(
                gpu,
                self.kind,
                self.fidelity,
                new,
                &self.prepared,
                self.projection,
                baked,
                self.clip.as_ref().map(|c| &c.stage),
            )?;
            self.proxy = Proxy::None;
        }
        self.upload_step_table(gpu, table)?;
        self.send_constants(gpu)
    }

    fn program_kind(&self) -> ProgramKind {
        self.program.kind()
    }

    fn facts(&self) -> Vec<(&'static str, String)> {
        let clip = self.clip.as_ref();
        clip.map(|c| (crate::techniques::clip::stats::LABEL, c.stats.line()))
            .into_iter()
            .collect()
    }

    fn in_parts(&mut self) -> Option<&mut dyn DrawInParts> {
        Some(self)
    }
}

impl DrawInParts for Opacity3dRenderer {
    /// Part `part` of `parts` is the `part`-th run of consecutive slices, back to front.
    fn draw_part(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        part: usize,
        parts: usize,
    ) -> RenderResult<()> {
        self.update_mesh(gpu, frame)?;
        let n = self.proxy.slice_ends().len();
        let parts = parts.clamp(1, n.max(1));
        if part >= parts {
            return Ok(());
        }
        let slices = part * n / parts..(part + 1) * n / parts;
        self.draw_slices(gpu, surface, frame, slices)
    }
}
