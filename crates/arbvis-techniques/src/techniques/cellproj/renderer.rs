//! The GL side of cell projection: the face vertices in one buffer (uploaded once), the
//! isosurface table (faithful) or isovalue list (precise) on unit 0, and the program of
//! the fidelity and exit variant; every frame is one draw with back-face culling and a
//! depth test. Changing isovalues or colours rewrites only the table.

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use std::path::Path;

use super::prepare::{iso_list, iso_table, prepare, Prepared, Viewer, VERTEX_COMPONENTS};
use super::{CellprojScene, Depth, Order};
use crate::programs::{self, ProgramPair};
use crate::techniques::cellproj::locals;
use arbvis_core::camera::Projection;
use arbvis_gl::{
    self, DrawCall, Extent, Filter, GlError, Gpu, Mesh, Program, ProgramKind, ProgramText, Surface,
    TexelData, TexelFormat, Texture,
};

use crate::techniques::{Frame, Params, Renderer};
use arbvis_core::vocab::{Fidelity, Interpolation};

/// Texture unit of the table (faithful) or isovalue list (precise).
pub const TABLE_UNIT: u32 = 0;

/// Ambient term of the precise shading.
pub const AMBIENT: f64 = 0.25;

/// The program variants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// The seed's programs, exit per fragment.
    PerFragment,
    /// The seed's orthographic case, exit per vertex.
    PerVertex,
    /// Precise (GLSL), per fragment.
    Precise,
}

/// The variant a scene draws with for `projection`: precise for precise fidelity; else
/// per vertex where the direction is constant (orthographic) unless the scene says
/// per fragment. Per vertex in perspective is an error (the seed's own caveat).
pub fn variant(
    params: &CellprojScene,
    fidelity: Fidelity,
    projection: Projection,
) -> RenderResult<Variant> {
    if fidelity == Fidelity::Precise {
        return Ok(Variant::Precise);
    }
    let per_vertex = params.exit.per_vertex(projection)?;
    Ok(if per_vertex {
        Variant::PerVertex
    } else {
        Variant::PerFragment
    })
}

/// The precise fragment program writing the entry depth: `precise.frag` with
/// `ENTRY_DEPTH` defined, which leaves out its `gl_FragDepth`.
pub fn entry_depth_fragment(fragment: &ProgramText) -> ProgramText {
    fragment.with_define("ENTRY_DEPTH")
}

/// The program pair of a variant (precise exists only in GLSL: it loops).
pub fn program_pair(variant: Variant, kind: ProgramKind) -> RenderResult<ProgramPair> {
    use programs::*;
    let (vertex, fragment) = match (variant, kind) {
        (Variant::PerFragment, ProgramKind::Arb) => {
            (CELLPROJ_PERSPECTIVE_ARBVP, CELLPROJ_PERSPECTIVE_ARBFP)
        }
        (Variant::PerFragment, ProgramKind::Glsl) => {
            (CELLPROJ_PERSPECTIVE_VERT, CELLPROJ_PERSPECTIVE_FRAG)
        }
        (Variant::PerVertex, ProgramKind::Arb) => {
            (CELLPROJ_ORTHOGRAPHIC_ARBVP, CELLPROJ_ORTHOGRAPHIC_ARBFP)
        }
        (Variant::PerVertex, ProgramKind::Glsl) => {
            (CELLPROJ_ORTHOGRAPHIC_VERT, CELLPROJ_ORTHOGRAPHIC_FRAG)
        }
        (Variant::Precise, _) => (CELLPROJ_PRECISE_VERT, CELLPROJ_PRECISE_FRAG),
    };
    let kind = if variant == Variant::Precise {
        ProgramKind::Glsl
    } else {
        kind
    };
    Ok(ProgramPair {
        kind,
        vertex,
        fragment,
    })
}

pub use super::indices::{eye_and_direction, viewer};

/// The cell-projection renderer.
pub struct CellprojRenderer {
    kind: ProgramKind,
    fidelity: Fidelity,
    params: CellprojScene,
    prepared: Prepared,
    /// [`Order::Mesh`]: every face, drawn through an index list of the active ones;
    /// [`Order::View`]: the active faces of one view, in order.
    mesh: Mesh,
    /// The face vertices on the CPU, kept for [`Order::View`] rebuilds.
    faces: Option<Vec<f32>>,
    /// The tetrahedra drawn (active, or all).
    drawn: Vec<u32>,
    /// The viewer [`Order::View`]'s buffer was built for (`None`: rebuild).
    built_for: Option<Viewer>,
    ranges: Vec<[f64; 2]>,
    table: Texture,
    program: Option<(Variant, Depth, bool, Program)>,
    /// The volume (`mode = "volume"` or `"both"`).
    volume: Option<super::volume::VolumeRenderer>,
    /// Where the scene's files are read from (colour tables).
    base: std::path::PathBuf,
}

/// Slack of the active test: the precise programs' crossing slack (2^-16) and a margin
/// for the faithful table's texel-centre rounding (1/512 at 256²) would both be covered
/// by 1/256; the test only saves work, so erring wide costs a few tetrahedra.
const ACTIVE_SLACK: f64 = 1.0 / 256.0;

fn table_texture(gpu: &Gpu, params: &CellprojScene, fidelity: Fidelity) -> GlResult<Texture> {
    match fidelity {
        Fidelity::Faithful => {
            let n = params.table_size;
            Texture::new(
                gpu,
                "cellproj isosurface table (s = sf, t = sb)",
                Extent::D2(n, n),
                TexelFormat::Rgba8,
                Filter::Nearest,
                TexelData::U8(&iso_table(&params.isovalues, n)),
            )
        }
        Fidelity::Precise => {
            let count = params.isovalues.len().max(1) as u32;
            let mut list = iso_list(&params.isovalues);
            list.resize(count as usize * 8, 0.0);
            Texture::new(
                gpu,
                "cellproj isovalues (row 0 colours, row 1 values)",
                Extent::D2(count, 2),
                TexelFormat::Rgba32f,
                Filter::Nearest,
                TexelData::F32(&list),
            )
        }
    }
}

/// The GL mesh of an order, and the CPU copy of the faces [`Order::View`] keeps.
fn face_mesh(
    gpu: &Gpu,
    prepared: &Prepared,
    order: Order,
) -> RenderResult<(Mesh, Option<Vec<f32>>)> {
    let vertices = prepared.face_vertices();
    let label = "cellproj faces (4 per tetrahedron)";
    Ok(match order {
        Order::Mesh => (Mesh::new(gpu, label, &VERTEX_COMPONENTS, &vertices)?, None),
        Order::View => (
            Mesh::new(gpu, label, &VERTEX_COMPONENTS, &[])?,
            Some(vertices),
        ),
    })
}

impl CellprojRenderer {
    /// Load and prepare the scene's mesh (relative paths from `base`), then upload.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &CellprojScene,
        base: &Path,
    ) -> RenderResult<CellprojRenderer> {
        params.validate()?;
        let prepared = prepare(params, base)?;
        CellprojRenderer::upload(gpu, kind, fidelity, params, prepared, base)
    }

    /// Upload a mesh prepared elsewhere (tests craft meshes in memory).
    pub fn from_prepared(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &CellprojScene,
        prepared: Prepared,
    ) -> RenderResult<CellprojRenderer> {
        CellprojRenderer::upload(gpu, kind, fidelity, params, prepared, Path::new("."))
    }

    /// Upload `prepared`, the scene's relative paths (a transfer function's table file)
    /// read from `base`.
    pub fn upload(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &CellprojScene,
        prepared: Prepared,
        base: &Path,
    ) -> RenderResult<CellprojRenderer> {
        // Everything below works on normalized scalars and isovalues.
        let params = &params.normalized(prepared.scalar_range);
        let (mesh, faces) = if params.mode.isosurfaces() {
            face_mesh(gpu, &prepared, params.order)?
        } else {
            let label = "cellproj faces (none: volume only)";
            (Mesh::new(gpu, label, &VERTEX_COMPONENTS, &[])?, None)
        };
        let table = table_texture(gpu, params, fidelity)?;
        let mut renderer = CellprojRenderer {
            kind,
            fidelity,
            params: params.clone(),
            ranges: prepared.ranges(),
            prepared,
            mesh,
            faces,
            drawn: Vec::new(),
            built_for: None,
            table,
            program: None,
            volume: None,
            base: base.to_path_buf(),
        };
        renderer.select_active(gpu)?;
        renderer.build_volume(gpu)?;
        Ok(renderer)
    }

    /// (Re)build the volume when the scene draws one.
    fn build_volume(&mut self, gpu: &Gpu) -> RenderResult<()> {
        self.volume = None;
        if !self.params.mode.volume() {
            return Ok(());
        }
        let spec = self.params.volume_spec();
        let transfer = spec.build(&self.base, self.prepared.scale)?;
        let isos = if self.params.mode == super::Mode::Both {
            self.params.isovalues.clone()
        } else {
            Vec::new()
        };
        let mut volume = super::volume::VolumeRenderer::new(
            gpu,
            self.kind,
            self.fidelity,
            &spec,
            transfer,
            &self.prepared,
            &isos,
        )?
        .with_exit(self.params.exit);
        volume.set_active_only(self.params.active_only);
        self.volume = Some(volume);
        Ok(())
    }

    /// The volume's renderer, when the scene draws one.
    pub fn volume(&self) -> Option<&super::volume::VolumeRenderer> {
        self.volume.as_ref()
    }

    /// Choose the tetrahedra to draw (the active ones, or all): an index list for
    /// [`Order::Mesh`]; for [`Order::View`] the next draw rebuilds its buffer.
    fn select_active(&mut self, gpu: &Gpu) -> RenderResult<()> {
        self.drawn = if !self.params.mode.isosurfaces() {
            Vec::new()
        } else if self.params.active_only {
            Prepared::active_tets(&self.ranges, &self.params.isovalues, ACTIVE_SLACK)
        } else {
            (0..self.prepared.tets.len() as u32).collect()
        };
        self.built_for = None;
        if self.params.order == Order::Mesh {
            let indices: Vec<u32> = self
                .drawn
                .iter()
                .flat_map(|&t| t * 12..t * 12 + 12)
                .collect();
            self.mesh.set_indices(gpu, &indices)?;
        }
        Ok(())
    }

    /// For [`Order::View`], rebuild the face buffer when the viewer moved.
    fn build_view(&mut self, gpu: &Gpu, frame: &Frame) -> RenderResult<()> {
        let Some(faces) = &self.faces else {
            return Ok(());
        };
        let viewer = viewer(frame);
        if self.built_for != Some(viewer) {
            let data = self.prepared.view_faces(faces, &self.drawn, viewer);
            self.mesh.update(gpu, &data)?;
            self.built_for = Some(viewer);
        }
        Ok(())
    }

    /// Tetrahedra drawn now.
    pub fn drawn_tets(&self) -> usize {
        self.drawn.len()
    }

    /// Vertices the last draw sent (12 per tetrahedron in mesh order; in view order
    /// only the faces that may face the viewer).
    pub fn drawn_vertices(&self) -> usize {
        self.mesh.draw_count()
    }

    /// The prepared mesh (for references and readouts).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// The program for `variant`, compiled on first use (a scene switching projection
    /// compiles the other one once).
    fn program(&mut self, gpu: &Gpu, variant: Variant) -> RenderResult<&Program> {
        let depth = self.params.depth;
        let pixel_rays = variant == Variant::Precise
            && match self.params.interpolation {
                Interpolation::Auto => !gpu.interpolates_exactly()?,
                Interpolation::Hardware => false,
                Interpolation::Shader => true,
            };
        let key = Some((variant, depth, pixel_rays));
        if self.program.as_ref().map(|(v, d, r, _)| (*v, *d, *r)) != key {
            let pair = program_pair(variant, self.kind)?;
            let mut fragment = if variant == Variant::Precise && depth == Depth::Entry {
                entry_depth_fragment(&pair.fragment)
            } else {
                pair.fragment
            };
            if pixel_rays {
                fragment = fragment.with_define("PIXEL_RAYS");
            }
            let program = Program::new(gpu, pair.kind, &pair.vertex, &fragment)?;
            self.program = Some((variant, depth, pixel_rays, program));
        }
        Ok(&self.program.as_ref().expect("set above").3)
    }
}

impl Renderer for CellprojRenderer {
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{rgb8, Annotations, Legend};
        let [lo, hi] = self.prepared.scalar_range;
        let name = &self.prepared.scalar_name;
        let mut legends = Vec::new();
        if self.params.mode.volume() {
            if let Ok(transfer) = self.params.volume_spec().build(&self.base, 1.0) {
                legends.push(Legend::Bar {
                    title: format!("volume: {name}"),
                    colours: (0..256)
                        .map(|k| rgb8(transfer.at(k as f64 / 255.0)))
                        .collect(),
                    low: lo,
                    high: hi,
                });
            }
        }
        if self.params.mode.isosurfaces() && !self.params.isovalues.is_empty() {
            // The renderer holds them normalized; the key says the scalar's own values.
            let keys = self
                .params
                .sorted_isovalues()
                .iter()
                .map(|i| {
                    let value = lo + i.value * (hi - lo);
                    (rgb8(i.color), arbvis_core::vocab::significant(value))
                })
                .collect();
            legends.push(Legend::Keys {
                title: format!("isovalues: {name}"),
                keys,
            });
        }
        let [lo, hi] = self.prepared.bounds;
        let axes = std::array::from_fn(|a| {
            arbvis_data::volume::axes::span(["x", "y", "z"][a], lo[a], hi[a])
        });
        Annotations {
            legends,
            axes: Some(crate::techniques::annotations::BoxAxes::new(
                self.prepared.half.to_array(),
                axes,
            )),
        }
    }

    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        // Precise scenes drawing both find the isosurfaces in the volume's walk.
        let both_in_walk = self.fidelity == Fidelity::Precise
            && self.params.mode == super::Mode::Both
            && self.params.volume_spec().precise == super::transfer::Precise::Walk;
        if !self.params.mode.isosurfaces() || both_in_walk {
            return self.draw_volume(gpu, surface, frame);
        }
        let variant = variant(&self.params, self.fidelity, frame.camera.projection)?;
        let mvp = frame.camera.view_projection(frame.aspect());
        let (eye, dir) = eye_and_direction(frame);
        let perspective = frame.camera.projection == Projection::Perspective;
        let count = self.params.isovalues.len() as f64;
        let shading = self.params.shading && self.fidelity == Fidelity::Precise;
        let program = self.program(gpu, variant)?;
        program.set_transform(gpu, mvp)?;
        match variant {
            Variant::PerFragment => {
                // The seed's Cg assumes a perspective eye; for a parallel view the eye
                // goes 10^6 box units back, so `vertex - EyePos` is the view direction.
                let eye = if perspective { eye } else { -dir * 1.0e6 };
                program.set_vertex_local(gpu, locals::EYE, [eye.x, eye.y, eye.z, 1.0])?
            }
            Variant::PerVertex => {
                program.set_vertex_local(gpu, locals::EYE, [dir.x, dir.y, dir.z, 0.0])?
            }
            Variant::Precise => {
                let t = mvp.transpose();
                for (i, row) in [t.x_axis, t.y_axis, t.z_axis, t.w_axis].iter().enumerate() {
                    program.set_local(gpu, locals::MVP_ROWS + i, row.to_array())?;
                }
                let w = if perspective { 1.0 } else { 0.0 };
                program.set_local(gpu, locals::EYE, [eye.x, eye.y, eye.z, w])?;
                program.set_local(gpu, locals::VIEW_DIRECTION, [dir.x, dir.y, dir.z, 0.0])?;
                let on = if shading { 1.0 } else { 0.0 };
                program.set_local(gpu, locals::ISOSURFACES, [count, on, AMBIENT, 0.0])?;
                // Each pixel's own ray: the inverse transform and window position to NDC.
                let inv = mvp.inverse().transpose();
                for (i, row) in [inv.x_axis, inv.y_axis, inv.z_axis, inv.w_axis]
                    .iter()
                    .enumerate()
                {
                    program.set_local(gpu, locals::INVERSE_MVP + i, row.to_array())?;
                }
                let [x, y, w, h] = surface.rect();
                let (w, h) = (w.max(1.0), h.max(1.0));
                program.set_local(
                    gpu,
                    11,
                    [2.0 / w, 2.0 / h, -1.0 - 2.0 * x / w, -1.0 - 2.0 * y / h],
                )?;
            }
        }
        if self.params.isovalues.is_empty() {
            return self.draw_volume(gpu, surface, frame);
        }
        self.build_view(gpu, frame)?;
        let program = &self.program.as_ref().expect("compiled above").3;
        arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(TABLE_UNIT, &self.table)],
                depth_test: true,
                cull_back: true,
                primitive: Default::default(),
                ..DrawCall::new(program, &self.mesh)
            },
        )?;
        self.draw_volume(gpu, surface, frame)
    }

    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let new = params.get::<CellprojScene>()?;
        new.validate()?;
        let new = &new.normalized(self.prepared.scalar_range);
        if new.mesh != self.params.mesh || new.scalars != self.params.scalars {
            return Err(
                GlError::Invalid("a new mesh or scalar needs a new renderer".into()).into(),
            );
        }
        let table_changed =
            new.isovalues != self.params.isovalues || new.table_size != self.params.table_size;
        let active_changed =
            new.isovalues != self.params.isovalues || new.active_only != self.params.active_only;
        let order_changed = new.order != self.params.order;
        let volume_changed = new.mode != self.params.mode
            || new.volume != self.params.volume
            || (new.mode == super::Mode::Both && new.isovalues != self.params.isovalues);
        // An edit of the transfer function alone keeps the mesh's textures and programs.
        let transfer_only = volume_changed
            && self.volume.is_some()
            && new.mode == self.params.mode
            && (new.mode != super::Mode::Both || new.isovalues == self.params.isovalues)
            && super::volume::VolumeRenderer::transfer_only(
                &self.params.volume_spec(),
                &new.volume_spec(),
            );
        let iso_mesh_changed = new.mode.isosurfaces() != self.params.mode.isosurfaces();
        self.params = new.clone();
        if iso_mesh_changed && !order_changed {
            (self.mesh, self.faces) = face_mesh(gpu, &self.prepared, self.params.order)?;
            self.select_active(gpu)?;
        }
        if transfer_only {
            let spec = self.params.volume_spec();
            let transfer = spec.build(&self.base, self.prepared.scale)?;
            if let Some(v) = &mut self.volume {
                v.set_transfer(&spec, transfer);
            }
        } else if volume_changed {
            self.build_volume(gpu)?;
        }
        if order_changed {
            (self.mesh, self.faces) = face_mesh(gpu, &self.prepared, self.params.order)?;
        }
        if table_changed {
            self.table = table_texture(gpu, &self.params, self.fidelity)?;
        }
        if active_changed || order_changed {
            self.select_active(gpu)?;
        }
        if let Some(v) = &mut self.volume {
            v.set_active_only(self.params.active_only);
        }
        Ok(())
    }

    fn program_kind(&self) -> ProgramKind {
        match self.fidelity {
            Fidelity::Precise => ProgramKind::Glsl,
            Fidelity::Faithful => self.kind,
        }
    }

    fn needs_depth(&self) -> bool {
        true
    }

    /// Isosurfaces are opaque; a volume is not.
    fn opaque(&self) -> bool {
        self.volume.is_none()
    }

    fn status(&self) -> Option<String> {
        let v = self.volume.as_ref()?;
        let t = v.times();
        Some(format!(
            "volume: {} tetrahedra drawn, sort {:.1} ms, indices {:.1} ms, {} cycles broken",
            t.drawn, t.sort_ms, t.upload_ms, t.cycles
        ))
    }
}

impl CellprojRenderer {
    fn draw_volume(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        let depth = self.params.mode == super::Mode::Both;
        match &mut self.volume {
            Some(v) => v.draw(gpu, surface, frame, &self.prepared, depth),
            None => Ok(()),
        }
    }
}

/// Every pair cell projection draws with: the faithful ports (per-fragment and per-vertex
/// exit) in ARB and GLSL, and the precise GLSL pair.
pub fn program_pairs() -> Vec<ProgramPair> {
    use programs::*;
    [
        (
            ProgramKind::Arb,
            CELLPROJ_PERSPECTIVE_ARBVP,
            CELLPROJ_PERSPECTIVE_ARBFP,
        ),
        (
            ProgramKind::Glsl,
            CELLPROJ_PERSPECTIVE_VERT,
            CELLPROJ_PERSPECTIVE_FRAG,
        ),
        (
            ProgramKind::Arb,
            CELLPROJ_ORTHOGRAPHIC_ARBVP,
            CELLPROJ_ORTHOGRAPHIC_ARBFP,
        ),
        (
            ProgramKind::Glsl,
            CELLPROJ_ORTHOGRAPHIC_VERT,
            CELLPROJ_ORTHOGRAPHIC_FRAG,
        ),
        (
            ProgramKind::Glsl,
            CELLPROJ_PRECISE_VERT,
            CELLPROJ_PRECISE_FRAG,
        ),
    ]
    .map(|(kind, vertex, fragment)| ProgramPair {
        kind,
        vertex,
        fragment,
    })
    .into_iter()
    .chain([
        super::volume::faithful_pair(ProgramKind::Arb, false),
        super::volume::faithful_pair(ProgramKind::Glsl, false),
        super::volume::faithful_pair(ProgramKind::Arb, true),
        super::volume::faithful_pair(ProgramKind::Glsl, true),
        super::volume::cell_pair(),
        super::volume::grid_pair(),
    ])
    .chain(super::volume::precise_pairs())
    .collect()
}
