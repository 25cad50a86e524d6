//! The GL side of the volume (issue 16): faithful cell projection with a pre-integrated
//! table, and the precise neighbour walk.
//!
//! **Faithful** (ARB or GLSL, RGBA8): every face vertex uploaded once (the isosurfaces'
//! layout); per view change the tetrahedra are ordered back to front on the CPU
//! ([`Sort`]: MPVONC or centroid) and an index buffer lists, in that order, the faces of
//! each that face the viewer. `volume.arbfp` computes `sf`, `sb` and the length with the
//! seed's exit computation and reads the segment from the 3D table ([`super::preint`]),
//! blended `ONE, ONE_MINUS_SRC_ALPHA`. In orthographic views the exit parameters come
//! per vertex as in the seed's orthographic case (`orthographic.arbvp` and
//! `volume_orthographic.arbfp`: 3 varyings instead of 8, 13 fragment instructions
//! instead of 30; the scene's `exit` as for the isosurfaces). No depth test (volume
//! alone) or the isosurfaces' depth (`mode = "both"`, drawn after them).
//!
//! Faithful and both projections leave out the tetrahedra the transfer function keeps
//! clear ([`contributing`], the scene's `active_only`): their fragments could only blend
//! zero.
//!
//! **Precise `table`**: the same projection (GLSL) with the table in float into a float
//! target, and the exit guarded: the nearest plane the ray leaves through (`D·N > 0`),
//! not the seed's smallest positive `t_i`, which takes a far plane when rounding puts a
//! sliver's near exit just behind the entry (single bright pixels, the faithful
//! pictures' speckle). Per vertex (orthographic) with `GUARDED_EXIT`; per fragment from
//! each cell's four corners ([`super::indices::cell_indices`], `volume_cell.frag`): the
//! planes and gradient `flat`, the segment between the last plane the ray enters and
//! the first it leaves, and where three faces face the viewer one triangle (the fourth
//! face) instead of three: 4 vertices per cell instead of 3 per face, a fifth fewer
//! triangles (on NASA's Blunt Fin at 48x32, where the vertex side is the frame, 57-61
//! -> 29 ms on llvmpipe).

//! **Precise** (GLSL, float target): the mesh in textures (face planes, scalar, face
//! neighbours); passes peel the boundary faces through which rays enter the mesh
//! (`volume_peel.frag`, one RGBA32F target each), until a pass finds none (an occlusion
//! query counts its samples) or the scene's `entries` cap; a full-screen pass walks every
//! pixel's ray through the tetrahedra (`volume_walk.frag`) and integrates it exactly,
//! eight entries at a time: a ray entering more often goes on in the next pass from the
//! sum so far (two more RGBA32F targets, ping-pong), so no entry is ever dropped.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::indices::{cell_indices, front_face_indices};
use super::order::{boundary_is_convex, centroid_order, mpvonc_order, neighbours, BOUNDARY};
use super::preint;
use super::prepare::{
    gradient, normal, Prepared, Viewer, CORNER_COMPONENTS, FACES, VERTEX_COMPONENTS,
};
use super::transfer::{Sort, Transfer, VolumeSpec};
use super::Exit;
use crate::camera::Projection;
use crate::gl::ProgramText;
use crate::gl::{
    self, Blend, DrawCall, Extent, Filter, GlError, GlResult, Gpu, Mesh, Program, ProgramKind,
    Surface, Target, TargetFormat, TexelData, TexelFormat, Texture,
};
use crate::programs::{self, ProgramPair};
use crate::techniques::Frame;
use crate::vocab::Fidelity;

/// Texels per row of the precise mode's mesh textures (`ROW` in `volume_walk.frag`).
pub const ROW: usize = 4096;

/// Where the time of the last frame went (milliseconds; CPU clocks, the GL's part
/// measured with `glFinish`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeTimes {
    /// Ordering the tetrahedra (faithful; 0 when the view did not change).
    pub sort_ms: f64,
    /// Building and uploading the index buffer (faithful).
    pub upload_ms: f64,
    /// Cycles MPVONC broke.
    pub cycles: usize,
    /// Tetrahedra drawn (faithful and the projections: those that can add to the
    /// picture, see [`contributing`]; the walk steps through every one).
    pub drawn: usize,
}

/// The faithful program pair: the seed's vertex program and `volume.arbfp` (or GLSL
/// twins); with `per_vertex` the seed's orthographic vertex program (exit parameters per
/// vertex) and `volume_orthographic.arbfp`.
pub fn faithful_pair(kind: ProgramKind, per_vertex: bool) -> ProgramPair {
    use programs::*;
    let (vertex, fragment) = match (kind, per_vertex) {
        (ProgramKind::Arb, false) => (CELLPROJ_PERSPECTIVE_ARBVP, CELLPROJ_VOLUME_ARBFP),
        (ProgramKind::Glsl, false) => (CELLPROJ_PERSPECTIVE_VERT, CELLPROJ_VOLUME_FRAG),
        (ProgramKind::Arb, true) => (
            CELLPROJ_ORTHOGRAPHIC_ARBVP,
            CELLPROJ_VOLUME_ORTHOGRAPHIC_ARBFP,
        ),
        (ProgramKind::Glsl, true) => (
            CELLPROJ_ORTHOGRAPHIC_VERT,
            CELLPROJ_VOLUME_ORTHOGRAPHIC_FRAG,
        ),
    };
    ProgramPair {
        kind,
        vertex,
        fragment,
    }
}

/// `volume_integral.glsl` joined before the main of `fragment` (after its `#version`).
pub fn with_integral(fragment: &ProgramText) -> ProgramText {
    let text = &fragment.text;
    let cut = text.find('\n').map_or(0, |i| i + 1);
    ProgramText {
        name: fragment.name.clone(),
        text: format!(
            "{}{}\n{}",
            &text[..cut],
            programs::CELLPROJ_VOLUME_INTEGRAL_GLSL.text,
            &text[cut..]
        )
        .into(),
    }
}

/// The precise pairs: entry layers, the walk, and the projected variant (the integral
/// joined to the last two).
pub fn precise_pairs() -> [ProgramPair; 3] {
    use programs::*;
    [
        ProgramPair {
            kind: ProgramKind::Glsl,
            vertex: CELLPROJ_VOLUME_PEEL_VERT,
            fragment: CELLPROJ_VOLUME_PEEL_FRAG,
        },
        ProgramPair {
            kind: ProgramKind::Glsl,
            vertex: TRANSFORM_VERT,
            fragment: with_integral(&CELLPROJ_VOLUME_WALK_FRAG),
        },
        ProgramPair {
            kind: ProgramKind::Glsl,
            vertex: CELLPROJ_PRECISE_VERT,
            fragment: with_integral(&CELLPROJ_VOLUME_PROJECTED_FRAG),
        },
    ]
}

struct Faithful {
    /// Exit per fragment (perspective, or a scene's `exit = "fragment"`); for precise
    /// `table` the cell program (`volume_cell.frag`), drawn from `corners`.
    program: Program,
    /// Exit per vertex (orthographic; none for the projected precise variant).
    per_vertex: Option<Program>,
    /// Every face's vertices ([`face_mesh`]), made at the first draw that needs them.
    faces: Option<Mesh>,
    /// Precise `table` per fragment: every tetrahedron's corners with its planes
    /// ([`Prepared::corner_vertices`]), made at the first such draw.
    corners: Option<Mesh>,
    /// The pre-integrated table (unit 0), or for the projected precise variant the
    /// transfer function (unit 2).
    table: Texture,
    /// Precise projected: exact integral per fragment.
    exact: bool,
    /// Precise `table`: the pre-integrated table in float.
    float: bool,
    /// `(sf, sb, length)` to texture coordinates: scale and offset.
    map: [[f64; 4]; 2],
    /// The viewer the index buffer was made for, and whether it indexes `corners`.
    built_for: Option<(Viewer, bool)>,
}

struct Precise {
    peel: Program,
    walk: Program,
    boundary: Mesh,
    quad: Mesh,
    tets: Texture,
    neighbours: Texture,
    /// Per tetrahedron (first, count) into `reentry` ([`reentry_candidates`]).
    reentry_offsets: Texture,
    reentry: Texture,
    tf: Texture,
    isos: Texture,
    iso_count: usize,
    /// Up to [`BATCH`] entry layers.
    layers: Vec<Target>,
    /// The sums of earlier batches (ping-pong), made when a view needs them.
    sums: Vec<Target>,
    /// The most entries followed (the scene's `entries`; `None`: every one).
    cap: Option<usize>,
    /// Entry layers the last frame peeled.
    peeled: usize,
}

/// Entry layers one walk pass reads (texture units 4..11 of `volume_walk.frag`).
const BATCH: usize = 8;

/// The volume of a cell-projection scene.
pub struct VolumeRenderer {
    spec: VolumeSpec,
    transfer: Transfer,
    neighbours: Vec<[u32; 4]>,
    convex: bool,
    faithful: Option<Faithful>,
    precise: Option<Precise>,
    times: VolumeTimes,
    tets: usize,
    /// The transfer function changed since its textures were made (remade at the next
    /// draw, so that an edit followed by another before any draw builds one table).
    stale: bool,
    longest: f64,
    /// Precise `table`: the faithful projection with a float table.
    float_table: bool,
    /// The faithful table made before the current one, with its spec: the viewer
    /// alternates a coarse table while the user interacts with the scene's when still,
    /// and swaps them instead of integrating again.
    spare: Option<(VolumeSpec, Texture, [[f64; 4]; 2])>,
    /// The spec the current textures were made for, while they are stale.
    made_for: Option<VolumeSpec>,
    /// Where faithful computes the exit (the scene's `exit`).
    exit: Exit,
    /// Each tetrahedron's scalar range `[min, max]`.
    ranges: Vec<[f64; 2]>,
    /// Draw only the tetrahedra that can add to the picture (the scene's `active_only`).
    active_only: bool,
    /// Per tetrahedron: drawn by the projections ([`contributing`]; all without
    /// `active_only`).
    drawn: Vec<bool>,
}

/// The pre-integrated table: RGBA8 (faithful), or RGBA32F (precise `table`).
fn table_texture(
    gpu: &Gpu,
    tf: &Transfer,
    spec: &VolumeSpec,
    longest: f64,
    float: bool,
) -> GlResult<Texture> {
    let [n, m] = spec.table_size;
    let (nu, mu) = (n as usize, m as usize);
    let (floats, bytes);
    let (format, data) = if float {
        floats = preint::table_f32(tf, nu, mu, longest, spec.build);
        (TexelFormat::Rgba32f, TexelData::F32(&floats))
    } else {
        bytes = preint::table(tf, nu, mu, longest, spec.build);
        (TexelFormat::Rgba8, TexelData::U8(&bytes))
    };
    Texture::new(
        gpu,
        "cellproj volume pre-integrated table (sf, sb, length)",
        Extent::D3(n, n, m),
        format,
        Filter::Linear,
        data,
    )
}

/// `(sf, sb, length)` to the pre-integrated table's texture coordinates: scale and offset
/// (texel centres at both ends).
fn table_map(spec: &VolumeSpec, longest: f64) -> [[f64; 4]; 2] {
    let [n, m] = spec.table_size.map(|v| v as f64);
    [
        [(n - 1.0) / n, (n - 1.0) / n, (m - 1.0) / m / longest, 0.0],
        [0.5 / n, 0.5 / n, 0.5 / m, 0.0],
    ]
}

/// How far past a texel centre (in texels) a table coordinate may land by rounding: the
/// f32 map `s (n-1)/n + 1/2n` and the unit's `u n - 1/2` are off by about `n` ulps of 1,
/// under 1e-4 texel for tables up to 512 wide.
const MARGIN: f64 = 1e-3;

/// Which tetrahedra can add to the picture: those whose scalar range, widened to every
/// texel of the pre-integrated table a lookup inside it may read (the two around each
/// end; [`MARGIN`] for where a coordinate rounds across a texel centre), meets a
/// non-zero attenuation. The others' segments read only texels of zero colour
/// and opacity, whose blend leaves the target as it was in 8 bits and in float, so
/// leaving them out changes no pixel where the exit is right (faithful's exit speckle
/// can put a segment's back outside its cell's range: that speckle goes with the cell).
/// The exact projection reads the transfer function itself: the same widening is
/// conservative for it.
pub fn contributing(ranges: &[[f64; 2]], transfer: &Transfer, table_side: u32) -> Vec<bool> {
    let last = (table_side.max(2) - 1) as f64;
    ranges
        .par_iter()
        .map(|&[lo, hi]| {
            let a = (lo * last - MARGIN).floor().max(0.0) / last;
            let b = (hi * last + MARGIN).ceil().min(last) / last;
            !transfer.clear_on(a.min(lo), b.max(hi))
        })
        .collect()
}

/// The most entry layers the precise walk peels: the scene's cap, one for a convex
/// boundary (a ray enters it once), else every entry the view has (`None`).
fn entry_cap(spec: &VolumeSpec, convex: bool) -> Option<usize> {
    match spec.entries {
        0 if convex => Some(1),
        0 => None,
        e => Some(e as usize),
    }
}

/// Most re-entry candidates kept per tetrahedron (the walk tests each).
const MAX_REENTRY: usize = 64;

/// Where a ray that leaves the mesh may enter it again at once: for each tetrahedron
/// with a boundary face, the other tetrahedra with a boundary face that share a vertex
/// with one of its boundary faces (at most [`MAX_REENTRY`], nearest first by index
/// distance kept as found). A ray grazing the boundary past an edge leaves through one
/// and re-enters through another within a hair, and the rasterized entry layers can
/// miss that re-entry (the entry face covers a sliver of the pixel); the walk tests these
/// instead. Returns (first, count) per tetrahedron and the list.
fn reentry_candidates(prepared: &Prepared, neighbours: &[[u32; 4]]) -> (Vec<u32>, Vec<u32>) {
    let n = neighbours.len();
    // Boundary tetrahedra around each vertex of a boundary face.
    let mut around: std::collections::HashMap<u32, Vec<u32>> = Default::default();
    let boundary_vertices = |t: usize| {
        let row = neighbours[t];
        let mut v: Vec<u32> = (0..4)
            .filter(|&k| row[k] == BOUNDARY)
            .flat_map(|k| FACES[k].0.map(|i| prepared.tets[t][i]))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    for t in 0..n {
        for v in boundary_vertices(t) {
            around.entry(v).or_default().push(t as u32);
        }
    }
    let mut offsets = vec![0u32; 2 * n];
    let mut list = Vec::new();
    for t in 0..n {
        let mut found: Vec<u32> = boundary_vertices(t)
            .iter()
            .flat_map(|v| around[v].iter().copied())
            .filter(|&c| c as usize != t)
            .collect();
        found.sort_unstable();
        found.dedup();
        found.truncate(MAX_REENTRY);
        offsets[2 * t] = list.len() as u32;
        offsets[2 * t + 1] = found.len() as u32;
        list.extend(found);
    }
    (offsets, list)
}

/// The four faces of every tetrahedron, as the faithful and projected paths draw them.
fn face_mesh(gpu: &Gpu, prepared: &Prepared) -> GlResult<Mesh> {
    Mesh::new(
        gpu,
        "cellproj volume faces (4 per tetrahedron)",
        &VERTEX_COMPONENTS,
        &prepared.face_vertices(),
    )
}

/// Every tetrahedron's four corners with its planes, as precise `table` draws them per
/// fragment.
fn corner_mesh(gpu: &Gpu, prepared: &Prepared) -> GlResult<Mesh> {
    Mesh::new(
        gpu,
        "cellproj volume cell corners (4 per tetrahedron)",
        &CORNER_COMPONENTS,
        &prepared.corner_vertices(),
    )
}

/// The transfer function as a float texture of its control points (see [`tf_texels`]).
fn tf_texture(gpu: &Gpu, transfer: &Transfer) -> GlResult<Texture> {
    Texture::new(
        gpu,
        "cellproj volume transfer function",
        Extent::D2(transfer.s.len() as u32, 2),
        TexelFormat::Rgba32f,
        Filter::Nearest,
        TexelData::F32(&tf_texels(transfer)),
    )
}

/// The transfer function as `count x 2` RGBA32F texels (row 0 colour and opacity value,
/// row 1 positions).
fn tf_texels(tf: &Transfer) -> Vec<f32> {
    let mut v: Vec<f32> = tf.rgba.iter().flat_map(|c| c.map(|x| x as f32)).collect();
    v.extend(tf.s.iter().flat_map(|&s| [s as f32, 0.0, 0.0, 0.0]));
    v
}

fn rows_texture(
    gpu: &Gpu,
    label: &str,
    format: TexelFormat,
    data: TexelData<'_>,
    texels: usize,
) -> GlResult<Texture> {
    let rows = texels.div_ceil(ROW).max(1);
    if rows > gpu.caps().max_texture_size.max(1) as usize {
        return Err(GlError::Data(format!(
            "{label}: {texels} texels need {rows} rows of {ROW}, more than GL_MAX_TEXTURE_SIZE"
        )));
    }
    let texture = Texture::empty_2d(gpu, label, ROW as u32, rows as u32, format)?;
    texture.update_texels(gpu, data)?;
    Ok(texture)
}

impl VolumeRenderer {
    /// Build what `fidelity` draws with.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        spec: &VolumeSpec,
        transfer: Transfer,
        prepared: &Prepared,
        isovalues: &[super::Isovalue],
    ) -> GlResult<VolumeRenderer> {
        let neighbours = neighbours(&prepared.tets);
        let convex = boundary_is_convex(prepared, &neighbours);
        let mut r = VolumeRenderer {
            spec: spec.clone(),
            transfer,
            neighbours,
            convex,
            faithful: None,
            precise: None,
            times: VolumeTimes::default(),
            tets: prepared.tets.len(),
            stale: false,
            longest: prepared.longest_edge().max(1e-12),
            float_table: false,
            spare: None,
            made_for: None,
            exit: Exit::Auto,
            ranges: prepared.ranges(),
            active_only: true,
            drawn: Vec::new(),
        };
        r.select_drawn();
        match fidelity {
            Fidelity::Faithful => r.faithful = Some(r.build_faithful(gpu, kind)?),
            Fidelity::Precise if spec.precise == super::transfer::Precise::Projected => {
                r.faithful = Some(r.build_projected(gpu)?)
            }
            Fidelity::Precise if spec.precise == super::transfer::Precise::Table => {
                r.float_table = true;
                r.faithful = Some(r.build_faithful(gpu, ProgramKind::Glsl)?)
            }
            Fidelity::Precise => r.precise = Some(r.build_precise(gpu, prepared, isovalues)?),
        }
        Ok(r)
    }

    /// Where faithful computes the exit parameters (default: per vertex for orthographic
    /// cameras, per fragment for perspective ones, as the isosurfaces).
    pub fn with_exit(mut self, exit: Exit) -> VolumeRenderer {
        self.exit = exit;
        self
    }

    /// Draw only the tetrahedra that can add to the picture (the default), or every one
    /// as the seed did.
    pub fn set_active_only(&mut self, active_only: bool) {
        if active_only != self.active_only {
            self.active_only = active_only;
            self.select_drawn();
        }
    }

    /// Recompute [`VolumeRenderer::drawn`]'s set for the current transfer function; the
    /// next faithful draw rebuilds its index buffer when it changed.
    fn select_drawn(&mut self) {
        let drawn = match self.active_only {
            true => contributing(&self.ranges, &self.transfer, self.spec.table_size[0]),
            false => vec![true; self.ranges.len()],
        };
        if drawn != self.drawn {
            self.drawn = drawn;
            if let Some(f) = &mut self.faithful {
                f.built_for = None;
            }
        }
    }

    fn build_faithful(&self, gpu: &Gpu, kind: ProgramKind) -> GlResult<Faithful> {
        let pair = faithful_pair(kind, true);
        let per_vertex = match self.float_table {
            // Precise `table` guards the exit (see `volume_orthographic.frag`); faithful
            // is the seed's.
            true => Program::new(
                gpu,
                pair.kind,
                &pair.vertex.with_define("GUARDED_EXIT"),
                &pair.fragment.with_define("GUARDED_EXIT"),
            )?,
            false => Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?,
        };
        let program = match self.float_table {
            true => Program::new(
                gpu,
                ProgramKind::Glsl,
                &programs::CELLPROJ_VOLUME_CELL_VERT,
                &programs::CELLPROJ_VOLUME_CELL_FRAG,
            )?,
            false => {
                let pair = faithful_pair(kind, false);
                Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?
            }
        };
        let per_vertex = Some(per_vertex);
        let float = kind == ProgramKind::Glsl && self.float_table;
        let table = table_texture(gpu, &self.transfer, &self.spec, self.longest, float)?;
        let map = table_map(&self.spec, self.longest);
        Ok(Faithful {
            program,
            per_vertex,
            faces: None,
            corners: None,
            table,
            exact: false,
            float,
            map,
            built_for: None,
        })
    }

    fn build_projected(&self, gpu: &Gpu) -> GlResult<Faithful> {
        let pair = &precise_pairs()[2];
        let program = Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?;
        let table = tf_texture(gpu, &self.transfer)?;
        Ok(Faithful {
            program,
            per_vertex: None,
            faces: None,
            corners: None,
            table,
            exact: true,
            float: true,
            map: [[0.0; 4]; 2],
            built_for: None,
        })
    }

    fn build_precise(
        &self,
        gpu: &Gpu,
        prepared: &Prepared,
        isovalues: &[super::Isovalue],
    ) -> GlResult<Precise> {
        let [peel, walk, _] = precise_pairs();
        let peel = Program::new(gpu, peel.kind, &peel.vertex, &peel.fragment)?;
        let walk = Program::new(gpu, walk.kind, &walk.vertex, &walk.fragment)?;
        walk.set_transform(gpu, glam::DMat4::IDENTITY)?;
        let n = prepared.tets.len();
        let data: Vec<f32> = (0..n)
            .into_par_iter()
            .flat_map_iter(|t| {
                let (p, s) = prepared.tet(t);
                let mut v = Vec::with_capacity(20);
                for (f, _) in FACES {
                    let nrm = normal(p[f[0]], p[f[1]], p[f[2]]);
                    v.extend([nrm.x, nrm.y, nrm.z, nrm.dot(p[f[0]])]);
                }
                let g = gradient(p, s);
                v.extend([g.x, g.y, g.z, s[0] - g.dot(p[0])]);
                v.into_iter().map(|x| x as f32)
            })
            .collect();
        let tets = rows_texture(
            gpu,
            "cellproj volume tetrahedra (4 planes, scalar)",
            TexelFormat::Rgba32f,
            TexelData::F32(&data),
            n * 5,
        )?;
        let nb: Vec<u32> = self.neighbours.iter().flatten().copied().collect();
        let neighbours = rows_texture(
            gpu,
            "cellproj volume neighbours",
            TexelFormat::Rgba32ui,
            TexelData::U32(&nb),
            n,
        )?;
        let (offsets, list) = reentry_candidates(prepared, &self.neighbours);
        let reentry_offsets = rows_texture(
            gpu,
            "cellproj volume re-entry candidates (first, count) per tetrahedron",
            TexelFormat::Rg32ui,
            TexelData::U32(&offsets),
            n,
        )?;
        let reentry = rows_texture(
            gpu,
            "cellproj volume re-entry candidates",
            TexelFormat::R32ui,
            TexelData::U32(&list),
            list.len(),
        )?;
        let tf = tf_texture(gpu, &self.transfer)?;
        let iso_count = isovalues.len();
        let mut list = super::prepare::iso_list(isovalues);
        list.resize(iso_count.max(1) * 8, 0.0);
        let isos = Texture::new(
            gpu,
            "cellproj volume isovalues",
            Extent::D2(iso_count.max(1) as u32, 2),
            TexelFormat::Rgba32f,
            Filter::Nearest,
            TexelData::F32(&list),
        )?;
        let mut boundary = Vec::new();
        for (t, row) in self.neighbours.iter().enumerate() {
            let (p, _) = prepared.tet(t);
            for (k, &m) in row.iter().enumerate() {
                if m == BOUNDARY {
                    // The face's plane as the tetrahedra texture holds it, so the entry
                    // layers intersect the pixel's ray with it exactly.
                    let f = FACES[k].0;
                    let nrm = normal(p[f[0]], p[f[1]], p[f[2]]);
                    let plane = [nrm.x, nrm.y, nrm.z, nrm.dot(p[f[0]])].map(|v| v as f32);
                    for &c in &f {
                        boundary.extend([p[c].x as f32, p[c].y as f32, p[c].z as f32, t as f32]);
                        boundary.extend(plane);
                    }
                }
            }
        }
        let boundary = Mesh::new(gpu, "cellproj volume boundary faces", &[3, 1, 4], &boundary)?;
        let quad: Vec<f32> = [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
        ]
        .iter()
        .flat_map(|&(x, y)| [x, y, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        .collect();
        let quad = Mesh::new(gpu, "cellproj volume full-screen quad", &[4, 4], &quad)?;
        let cap = entry_cap(&self.spec, self.convex);
        Ok(Precise {
            peel,
            walk,
            boundary,
            quad,
            tets,
            neighbours,
            reentry_offsets,
            reentry,
            tf,
            isos,
            iso_count,
            layers: Vec::new(),
            sums: Vec::new(),
            cap,
            peeled: 0,
        })
    }

    /// A new transfer function, unit distance, table size or order with the same mesh,
    /// fidelity and method: only what depends on them is remade, the textures at the
    /// next draw (the viewer's edits).
    pub fn set_transfer(&mut self, spec: &VolumeSpec, transfer: Transfer) {
        if spec.sort != self.spec.sort {
            if let Some(f) = &mut self.faithful {
                f.built_for = None;
            }
        }
        self.transfer = transfer;
        if let Some(p) = &mut self.precise {
            p.cap = entry_cap(spec, self.convex);
        }
        // The spec the textures were made for moves aside with them (see `refresh`).
        if !self.stale {
            self.made_for = Some(std::mem::replace(&mut self.spec, spec.clone()));
        }
        self.spec = spec.clone();
        self.stale = true;
    }

    /// Whether `old` and `new` differ only in what [`VolumeRenderer::set_transfer`] takes.
    pub fn transfer_only(old: &VolumeSpec, new: &VolumeSpec) -> bool {
        old.precise == new.precise
    }

    fn refresh(&mut self, gpu: &Gpu) -> GlResult<()> {
        if !self.stale {
            return Ok(());
        }
        let made_for = self.made_for.take();
        self.stale = false;
        // Before the early return: `set_active_only` may have chosen the set for an
        // edit that was then undone.
        self.select_drawn();
        if made_for.as_ref() == Some(&self.spec) {
            // Changed and changed back before a draw: the textures are right.
            return Ok(());
        }
        if let Some(f) = &mut self.faithful {
            if f.exact {
                f.table = tf_texture(gpu, &self.transfer)?;
            } else {
                let (table, map) = match self.spare.take() {
                    Some((spec, table, map)) if spec == self.spec => (table, map),
                    _ => (
                        table_texture(gpu, &self.transfer, &self.spec, self.longest, f.float)?,
                        table_map(&self.spec, self.longest),
                    ),
                };
                let old_table = std::mem::replace(&mut f.table, table);
                let old_map = std::mem::replace(&mut f.map, map);
                self.spare = made_for.map(|spec| (spec, old_table, old_map));
            }
        }
        if let Some(p) = &mut self.precise {
            p.tf = tf_texture(gpu, &self.transfer)?;
        }
        Ok(())
    }

    /// Whether the mesh's boundary is convex (one entry per ray).
    pub fn convex(&self) -> bool {
        self.convex
    }

    /// The last frame's CPU times.
    pub fn times(&self) -> VolumeTimes {
        self.times
    }

    /// The face neighbours (for orders and tests).
    pub fn neighbours(&self) -> &[[u32; 4]] {
        &self.neighbours
    }

    /// Entry layers the precise walk peeled for the last frame (the most entries of any
    /// ray, within the scene's cap).
    pub fn entries(&self) -> usize {
        self.precise.as_ref().map_or(0, |p| p.peeled)
    }

    /// Draw onto `surface` (the isosurfaces' depth already there in `mode = "both"`).
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        prepared: &Prepared,
        depth_test: bool,
    ) -> GlResult<()> {
        self.refresh(gpu)?;
        if self.faithful.is_some() {
            self.draw_faithful(gpu, surface, frame, prepared, depth_test)
        } else {
            self.times.drawn = self.tets;
            self.draw_precise(gpu, surface, frame, prepared)
        }
    }

    /// The back-to-front order of the scene's sort for `viewer`.
    pub fn order(&mut self, prepared: &Prepared, viewer: Viewer) -> Vec<u32> {
        match self.spec.sort {
            Sort::Centroid => {
                let all: Vec<u32> = (0..prepared.tets.len() as u32).collect();
                centroid_order(prepared, &all, viewer)
            }
            Sort::Mpvonc => {
                let (order, stats) = mpvonc_order(prepared, &self.neighbours, viewer);
                self.times.cycles = stats.cycles_broken;
                order
            }
        }
    }

    fn draw_faithful(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        prepared: &Prepared,
        depth_test: bool,
    ) -> GlResult<()> {
        let v = viewer(frame);
        let per_vertex = match self.faithful.as_ref().expect("faithful").per_vertex {
            Some(_) => self
                .exit
                .per_vertex(frame.camera.projection)
                .map_err(GlError::Data)?,
            None => false,
        };
        // Precise `table` per fragment draws each cell from its corners, one triangle
        // for three front faces where nothing depth-tests the faces' own depth.
        let cells = self.float_table && !per_vertex;
        let f = self.faithful.as_mut().expect("faithful");
        match cells {
            true if f.corners.is_none() => f.corners = Some(corner_mesh(gpu, prepared)?),
            false if f.faces.is_none() => f.faces = Some(face_mesh(gpu, prepared)?),
            _ => {}
        }
        if f.built_for != Some((v, cells)) {
            let t0 = Instant::now();
            let mut order = self.order(prepared, v);
            order.retain(|&t| self.drawn[t as usize]);
            self.times.drawn = order.len();
            let t1 = Instant::now();
            let f = self.faithful.as_mut().expect("faithful");
            let (mesh, indices) = match cells {
                true => (
                    &mut f.corners,
                    cell_indices(prepared, &order, v, !depth_test),
                ),
                false => (&mut f.faces, front_face_indices(prepared, &order, v)),
            };
            mesh.as_mut()
                .expect("made above")
                .set_indices(gpu, &indices)?;
            f.built_for = Some((v, cells));
            self.times.sort_ms = (t1 - t0).as_secs_f64() * 1e3;
            self.times.upload_ms = t1.elapsed().as_secs_f64() * 1e3;
        } else {
            self.times.sort_ms = 0.0;
            self.times.upload_ms = 0.0;
        }
        let f = self.faithful.as_ref().expect("faithful");
        let mvp = frame.camera.view_projection(frame.aspect());
        let (eye, dir) = eye_and_direction(frame);
        let perspective = frame.camera.projection == Projection::Perspective;
        let per_vertex = f.per_vertex.as_ref().filter(|_| per_vertex);
        let program = per_vertex.unwrap_or(&f.program);
        program.set_transform(gpu, mvp)?;
        if f.exact {
            let w = if perspective { 1.0 } else { 0.0 };
            program.set_local(gpu, 4, [eye.x, eye.y, eye.z, w])?;
            program.set_local(gpu, 5, [dir.x, dir.y, dir.z, 0.0])?;
            let points = self.transfer.s.len() as f64;
            program.set_local(gpu, 6, [points, 1.0 / self.transfer.unit, 0.0, 0.0])?;
        } else if cells {
            let eye = match perspective {
                true => eye.extend(1.0),
                false => dir.extend(0.0),
            };
            program.set_local(gpu, 0, f.map[0])?;
            program.set_local(gpu, 1, f.map[1])?;
            program.set_local(gpu, 2, eye.to_array())?;
        } else {
            // Per vertex: D, normalized (the length is then t). Per fragment: the seed's
            // eye; for a parallel view 10^6 box units back, so `vertex - EyePos` is D.
            let local = match (per_vertex, perspective) {
                (Some(_), _) => [dir.x, dir.y, dir.z, 0.0],
                (None, true) => [eye.x, eye.y, eye.z, 1.0],
                (None, false) => (-dir * 1.0e6).extend(1.0).to_array(),
            };
            program.set_vertex_local(gpu, 4, local)?;
            program.set_local(gpu, 0, f.map[0])?;
            program.set_local(gpu, 1, f.map[1])?;
        }
        let unit = if f.exact { 2 } else { 0 };
        let mesh = match cells {
            true => &f.corners,
            false => &f.faces,
        };
        let mesh = mesh.as_ref().expect("made above");
        gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(unit, &f.table)],
                blend: Blend::PremultipliedOver,
                depth_test,
                cull_back: true,
                ..DrawCall::new(program, mesh)
            },
        )
    }

    fn draw_precise(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        prepared: &Prepared,
    ) -> GlResult<()> {
        let (w, h) = (frame.width, frame.height);
        let convex = self.convex;
        let p = self.precise.as_mut().expect("precise");
        let pool = p.cap.map_or(BATCH, |c| c.min(BATCH));
        let sized = |t: &[Target]| t.first().is_some_and(|l| l.width() == w && l.height() == h);
        if !sized(&p.layers) || p.layers.len() != pool {
            p.layers.clear();
            p.sums.clear();
            for _ in 0..pool {
                p.layers
                    .push(Target::with_depth(gpu, w, h, TargetFormat::Rgba32f)?);
            }
        }
        let mvp = frame.camera.view_projection(frame.aspect());
        let inv = mvp.inverse().transpose();
        let rows = [inv.x_axis, inv.y_axis, inv.z_axis, inv.w_axis].map(|r| r.to_array());
        p.peel.set_transform(gpu, mvp)?;
        for (i, row) in rows.iter().enumerate() {
            p.peel.set_local(gpu, i, *row)?;
            p.walk.set_local(gpu, i, *row)?;
        }
        p.peel.set_local(gpu, 4, [w as f64, h as f64, 0.0, 0.0])?;
        let corner = match surface {
            Surface::Target(_) => [0.0, 0.0],
            Surface::Window([x, y, _, _]) => [x as f64, y as f64],
        };
        let eye_tet = match frame.camera.projection {
            Projection::Perspective => {
                locate(prepared, eye_and_direction(frame).0).map_or(-1.0, |t| t as f64)
            }
            Projection::Orthographic => -1.0,
        };
        let s = &self.spec;
        let locals = [
            self.transfer.s.len() as f64,
            p.iso_count as f64,
            s.termination,
        ];
        let inv_unit = 1.0 / self.transfer.unit;
        // Every boundary face at most once per ray: no more layers than that.
        let most = p
            .cap
            .unwrap_or(usize::MAX)
            .min(p.boundary.draw_count() / 3 + 1);
        p.peeled = 0;
        let mut batch = 0;
        loop {
            // Peel up to BATCH entry layers; layer 0 of a later batch reads the previous
            // batch's last (the pool's last), which it overwrites only at its own end.
            let mut n = 0;
            while n < p.layers.len() && p.peeled < most {
                let k = n;
                p.layers[k].clear(gpu, [-1.0, -1.0, 0.0, 0.0])?;
                let after = p.peeled > 0;
                p.peel
                    .set_local(gpu, 5, [after as u8 as f64, 0.0, 0.0, 0.0])?;
                let previous = if k > 0 { k - 1 } else { p.layers.len() - 1 };
                let textures: Vec<(u32, &Texture)> = if after {
                    vec![(3, p.layers[previous].color())]
                } else {
                    Vec::new()
                };
                let call = DrawCall {
                    textures: &textures,
                    depth_test: true,
                    cull_back: true,
                    ..DrawCall::new(&p.peel, &p.boundary)
                };
                // Without a cap the layers go on until one is empty; with one (a convex
                // boundary's single layer), no count is needed.
                let target = Surface::Target(&p.layers[k]);
                if p.cap.is_none() {
                    if gl::draw_counted(gpu, target, &call)? == 0 {
                        break;
                    }
                } else {
                    gl::draw(gpu, target, &call)?;
                }
                n += 1;
                p.peeled += 1;
            }
            // The last batch: fewer than a full pool, or at the cap.
            let last = n < p.layers.len() || p.peeled >= most;
            if !last && p.sums.is_empty() {
                for _ in 0..2 {
                    p.sums.push(Target::new(gpu, w, h, TargetFormat::Rgba32f)?);
                }
            }
            let (sum_in, sum_out) = (batch % 2, (batch + 1) % 2);
            let eye = if batch == 0 { eye_tet } else { -1.0 };
            // The surface's corner for the last pass; the sums are targets of their own.
            let at = if last { corner } else { [0.0, 0.0] };
            p.walk
                .set_local(gpu, 4, [w as f64, h as f64, at[0], at[1]])?;
            p.walk
                .set_local(gpu, 5, [locals[0], locals[1], locals[2], eye])?;
            p.walk.set_local(
                gpu,
                6,
                [
                    n as f64,
                    inv_unit,
                    self.tets as f64 + 16.0,
                    (batch > 0) as u8 as f64,
                ],
            )?;
            // Re-entries exist only where the boundary is not one convex body, and are
            // looked for only in a single pass (see volume_walk.frag).
            let search = last && batch == 0 && !convex;
            p.walk
                .set_local(gpu, 7, [search as u8 as f64, 0.0, 0.0, 0.0])?;
            let mut textures: Vec<(u32, &Texture)> = vec![
                (0, &p.tets),
                (1, &p.neighbours),
                (2, &p.tf),
                (3, &p.isos),
                (13, &p.reentry_offsets),
                (14, &p.reentry),
            ];
            for (k, l) in p.layers[..n].iter().enumerate() {
                textures.push((4 + k as u32, l.color()));
            }
            if batch > 0 {
                textures.push((12, p.sums[sum_in].color()));
            }
            if last {
                return gl::draw(
                    gpu,
                    surface,
                    &DrawCall {
                        textures: &textures,
                        blend: Blend::PremultipliedOver,
                        ..DrawCall::new(&p.walk, &p.quad)
                    },
                );
            }
            p.sums[sum_out].clear(gpu, [0.0; 4])?;
            gl::draw(
                gpu,
                Surface::Target(&p.sums[sum_out]),
                &DrawCall {
                    textures: &textures,
                    ..DrawCall::new(&p.walk, &p.quad)
                },
            )?;
            batch += 1;
        }
    }
}

/// The eye in object space (perspective) and the unit view direction (both cameras).
pub fn eye_and_direction(frame: &Frame) -> (DVec3, DVec3) {
    let inverse = frame.camera.view().inverse();
    let eye = inverse.transform_point3(DVec3::ZERO);
    let dir = inverse.transform_vector3(DVec3::NEG_Z).normalize();
    (eye, dir)
}

/// The viewer of a frame, in object space (what [`Order::View`] sorts and culls for).
pub fn viewer(frame: &Frame) -> Viewer {
    let (eye, dir) = eye_and_direction(frame);
    match frame.camera.projection {
        Projection::Orthographic => Viewer::Parallel(dir),
        Projection::Perspective => Viewer::Eye(eye),
    }
}

/// The tetrahedron holding `point` (barycentric test with a 1e-12 tolerance), if any.
pub fn locate(prepared: &Prepared, point: DVec3) -> Option<usize> {
    let (lo, hi) = (-prepared.half - 1e-9, prepared.half + 1e-9);
    if point.cmplt(lo).any() || point.cmpgt(hi).any() {
        return None;
    }
    (0..prepared.tets.len()).into_par_iter().find_first(|&t| {
        let (p, _) = prepared.tet(t);
        FACES.iter().all(|(f, _)| {
            let n = normal(p[f[0]], p[f[1]], p[f[2]]);
            n != DVec3::ZERO && n.dot(point - p[f[0]]) <= 1e-12
        })
    })
}
