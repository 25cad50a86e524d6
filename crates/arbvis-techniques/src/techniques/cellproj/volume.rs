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
//! triangles, which shortens frames that llvmpipe's vertex side bounds (measured:
//! docs/benchmarks.md, "Against VTK at its best (2026-11-26)").

//! **Precise** (GLSL, float target): the mesh in textures (face planes, scalar, face
//! neighbours); passes peel the boundary faces through which rays enter the mesh
//! (`volume_peel.frag`, one RGBA32F target each), until a pass finds none (an occlusion
//! query counts its samples) or the scene's `entries` cap; a full-screen pass walks every
//! pixel's ray through the tetrahedra (`volume_walk.frag`) and integrates it exactly,
//! eight entries at a time: a ray entering more often goes on in the next pass from the
//! sum so far (two more RGBA32F targets, ping-pong), so no entry is ever dropped.

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use std::time::Instant;

use rayon::prelude::*;

use super::indices::{cell_indices, eye_and_direction, front_face_indices, viewer};
use super::order::{boundary_is_convex, centroid_order, mpvonc_order, neighbours};
use super::preint;
use super::prepare::{Prepared, Viewer, CORNER_COMPONENTS, VERTEX_COMPONENTS};
use super::transfer::{Sort, Transfer, VolumeSpec};
use super::Exit;
use crate::programs::{self, ProgramPair};
use crate::techniques::cellproj::locals;
use crate::techniques::Frame;
use arbvis_core::camera::Projection;
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{
    self, Blend, DrawCall, Extent, Filter, Gpu, Mesh, Program, ProgramKind, Surface, TexelData,
    TexelFormat, Texture,
};

mod grid;
mod walk;
use grid::GridCaster;
pub use grid::{grid_pair, resample, Resampled};
use walk::{entry_cap, tf_texture, Precise};
pub use walk::{precise_pairs, with_integral};

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

/// Precise `table` per fragment: each cell from its corners (`volume_cell.vert`, `.frag`).
pub fn cell_pair() -> ProgramPair {
    ProgramPair {
        kind: ProgramKind::Glsl,
        vertex: programs::CELLPROJ_VOLUME_CELL_VERT,
        fragment: programs::CELLPROJ_VOLUME_CELL_FRAG,
    }
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

/// The volume of a cell-projection scene.
pub struct VolumeRenderer {
    spec: VolumeSpec,
    transfer: Transfer,
    neighbours: Vec<[u32; 4]>,
    convex: bool,
    faithful: Option<Faithful>,
    precise: Option<Precise>,
    grid: Option<GridCaster>,
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
    ) -> RenderResult<VolumeRenderer> {
        let neighbours = neighbours(&prepared.tets);
        let convex = boundary_is_convex(prepared, &neighbours);
        let mut r = VolumeRenderer {
            spec: spec.clone(),
            transfer,
            neighbours,
            convex,
            faithful: None,
            precise: None,
            grid: None,
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
            Fidelity::Precise if spec.precise == super::transfer::Precise::Grid => {
                r.grid = Some(GridCaster::new(gpu, prepared, spec, &r.transfer)?)
            }
            Fidelity::Precise => {
                r.precise = Some(Precise::new(
                    gpu,
                    prepared,
                    &r.neighbours,
                    spec,
                    &r.transfer,
                    r.convex,
                    isovalues,
                )?)
            }
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

    fn build_faithful(&self, gpu: &Gpu, kind: ProgramKind) -> RenderResult<Faithful> {
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
            true => {
                let pair = cell_pair();
                Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?
            }
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

    fn build_projected(&self, gpu: &Gpu) -> RenderResult<Faithful> {
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
        old.precise == new.precise && old.grid == new.grid && old.grid_steps == new.grid_steps
    }

    fn refresh(&mut self, gpu: &Gpu) -> RenderResult<()> {
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
        if let Some(g) = &mut self.grid {
            g.set_transfer(gpu, &self.spec, &self.transfer)?;
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
    ) -> RenderResult<()> {
        self.refresh(gpu)?;
        if self.faithful.is_some() {
            self.draw_faithful(gpu, surface, frame, prepared, depth_test)
        } else if let Some(g) = &self.grid {
            self.times.drawn = self.tets;
            g.draw(gpu, surface, frame, &self.spec)
        } else {
            self.times.drawn = self.tets;
            let p = self.precise.as_mut().expect("precise");
            p.draw(gpu, surface, frame, prepared, &self.spec, &self.transfer)
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
    ) -> RenderResult<()> {
        let v = viewer(frame);
        let per_vertex = match self.faithful.as_ref().expect("faithful").per_vertex {
            Some(_) => self.exit.per_vertex(frame.camera.projection)?,
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
            program.set_local(gpu, locals::EYE, [eye.x, eye.y, eye.z, w])?;
            program.set_local(gpu, locals::VIEW_DIRECTION, [dir.x, dir.y, dir.z, 0.0])?;
            let points = self.transfer.s.len() as f64;
            program.set_local(
                gpu,
                locals::TRANSFER,
                [points, 1.0 / self.transfer.unit, 0.0, 0.0],
            )?;
        } else if cells {
            let eye = match perspective {
                true => eye.extend(1.0),
                false => dir.extend(0.0),
            };
            program.set_local(gpu, locals::TABLE_SCALE, f.map[0])?;
            program.set_local(gpu, locals::TABLE_OFFSET, f.map[1])?;
            program.set_local(gpu, locals::CELL_EYE, eye.to_array())?;
        } else {
            // Per vertex: D, normalized (the length is then t). Per fragment: the seed's
            // eye; for a parallel view 10^6 box units back, so `vertex - EyePos` is D.
            let local = match (per_vertex, perspective) {
                (Some(_), _) => [dir.x, dir.y, dir.z, 0.0],
                (None, true) => [eye.x, eye.y, eye.z, 1.0],
                (None, false) => (-dir * 1.0e6).extend(1.0).to_array(),
            };
            program.set_vertex_local(gpu, locals::EYE, local)?;
            program.set_local(gpu, locals::TABLE_SCALE, f.map[0])?;
            program.set_local(gpu, locals::TABLE_OFFSET, f.map[1])?;
        }
        let unit = if f.exact { 2 } else { 0 };
        let mesh = match cells {
            true => &f.corners,
            false => &f.faces,
        };
        let mesh = mesh.as_ref().expect("made above");
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(unit, &f.table)],
                blend: Blend::PremultipliedOver,
                depth_test,
                cull_back: true,
                ..DrawCall::new(program, mesh)
            },
        )?)
    }
}
