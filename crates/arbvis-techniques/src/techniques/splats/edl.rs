//! Eye-dome lighting (`edl = STRENGTH`, precise): shading for clouds without normals, as
//! CloudCompare and Potree give it. A depth pass draws every point as a round sprite of
//! its splat's size into a float target with a depth buffer, the nearest view distance
//! kept per pixel (`splats/edl_depth.*`); then `splats/edl.frag` compares each pixel's
//! distance with its 8 neighbours' at `radius` pixels (log2 differences where the
//! neighbour is nearer) and multiplies the splats' picture by `exp(-300 strength
//! response)`. Pixels without a point are left as they are. GLSL only; the target and
//! programs are freed on Drop.

use crate::error::RenderResult;
use glam::{DMat4, DVec4};

use super::locals;
use crate::programs;
use arbvis_gl::{
    self, Blend, DrawCall, Gpu, Mesh, Primitive, Program, ProgramKind, Surface, Target,
    TargetFormat,
};

/// Pixels from a pixel to the neighbours it is compared with (Boucheny's 1.4, rounded
/// per direction).
pub const RADIUS: f64 = 1.4;

/// The depth pass's target and the two programs.
pub struct EdlPass {
    depth: Target,
    depth_program: Program,
    shade: Program,
    quad: Mesh,
}

/// What the depth pass needs of the view and the splats (the precise programs' locals).
pub struct EdlView {
    /// Clip from the cloud's frame.
    pub transform: DMat4,
    /// The eye (xyz) and 1 in perspective, 0 in orthographic.
    pub eye: DVec4,
    /// The view-distance row (`oit::z_row`).
    pub z_row: DVec4,
    /// Point size, factor; smallest and largest size.
    pub size: [f64; 2],
    pub size_range: [f64; 2],
}

impl EdlPass {
    /// A pass for frames of `width` x `height`.
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> RenderResult<EdlPass> {
        let depth_program = Program::new(
            gpu,
            ProgramKind::Glsl,
            &programs::SPLATS_EDL_DEPTH_VERT,
            &programs::SPLATS_EDL_DEPTH_FRAG,
        )?;
        let pair = programs::with_transform(
            ProgramKind::Glsl,
            &programs::SPLATS_EDL_FRAG,
            &programs::SPLATS_EDL_FRAG,
        );
        let shade = Program::new(gpu, ProgramKind::Glsl, &pair.vertex, &pair.fragment)?;
        shade.set_transform(gpu, DMat4::IDENTITY)?;
        Ok(EdlPass {
            depth: Target::with_depth(gpu, width, height, TargetFormat::Rgba32f)?,
            depth_program,
            shade,
            quad: crate::techniques::quad::quad_mesh(gpu, "splats EDL quad")?,
        })
    }

    /// Whether the target has this size.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        (self.depth.width(), self.depth.height()) == (width, height)
    }

    /// Draw the points of `mesh` into the depth target, then shade `surface` (which holds
    /// the splats' picture) with `strength`.
    pub fn draw(
        &self,
        gpu: &Gpu,
        mesh: &Mesh,
        view: &EdlView,
        strength: f64,
        surface: Surface<'_>,
    ) -> RenderResult<()> {
        self.depth.clear(gpu, [0.0; 4])?;
        let p = &self.depth_program;
        p.set_transform(gpu, view.transform)?;
        p.set_vertex_local(gpu, locals::VERTEX_EYE, view.eye.to_array())?;
        p.set_vertex_local(
            gpu,
            locals::VERTEX_SIZING,
            [view.size[0], view.size[1], 0.0, 0.0],
        )?;
        p.set_vertex_local(gpu, locals::VERTEX_Z_ROW, view.z_row.to_array())?;
        p.set_vertex_local(
            gpu,
            locals::VERTEX_SIZES,
            [view.size_range[0], view.size_range[1], 0.0, 0.0],
        )?;
        arbvis_gl::draw(
            gpu,
            Surface::Target(&self.depth),
            &DrawCall {
                primitive: Primitive::Points,
                depth_test: true,
                ..DrawCall::new(p, mesh)
            },
        )?;
        let origin = match surface {
            Surface::Target(_) => [0.0, 0.0],
            Surface::Window([x, y, _, _]) => [x as f64, y as f64],
        };
        self.shade
            .set_local(gpu, locals::EDL_SHADING, [strength, RADIUS, 0.0, 0.0])?;
        self.shade.set_local(
            gpu,
            locals::SURFACE_ORIGIN,
            [origin[0], origin[1], 0.0, 0.0],
        )?;
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(0, self.depth.color())],
                blend: Blend::Multiply,
                covers_frame: true,
                ..DrawCall::new(&self.shade, &self.quad)
            },
        )?)
    }
}
