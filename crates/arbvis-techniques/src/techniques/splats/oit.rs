//! Weighted blended order-independent transparency of the splats on the GPU (McGuire &
//! Bavoil 2013), `sort = "oit"`: no order at all, an approximation of it, computed as
//! [`reference::weighted_blended`](super::reference::weighted_blended) computes it in f64.
//!
//! # How it works
//!
//! 1. **Accumulation**: the splats, in file order, drawn by the splat programs with
//!    `program.local[5].x = 1`, which makes them output `(clamp(c) a w, a w)` with
//!    McGuire & Bavoil's eq. 7 weight `w = a clamp(10 / (1e-5 + (z/5)² + (z/200)⁶),
//!    1e-2, 3e3)` ([`OIT_WEIGHT`], the weight the CPU measurements use), `z` the
//!    distance along the view axis from the eye (perspective) or from the plane 2 units
//!    before the centre (orthographic, where the eye has no position), as the reference's
//!    `z`: `dot(vertex_local[8], p)`, the row [`z_row`] gives. Added (`Blend::Add`) into
//!    an RGBA32F target cleared to 0: f16 would overflow, weights reach 3e3 each.
//! 2. **Revealage**: the same draw with `program.local[5].x = 0` (the splat's `(c, a)`),
//!    blended `ZERO, ONE_MINUS_SRC_ALPHA` (`Blend::Reveal`) into an RGBA32F target
//!    cleared to 1: every channel becomes `Π (1 - a)`.
//! 3. **Composite**: a full-screen quad (`common/transform` + `splats/oit_composite`)
//!    reads both targets' colour textures at its pixel (units 0 and 1, nearest) and
//!    outputs `(accum.rgb / max(accum.a, 1e-5), 1 - R)`, blended `Blend::Over` onto the
//!    surface: `avg (1 - R) + dst R`, alpha `1 - (1 - dst.a) R`, the reference's formula.
//!
//! Two draws of the points rather than one into two colour attachments: the passes
//! need different blend functions, which one draw could only have through per-buffer
//! blending (`glBlendFunci`, GL 4.0) and `ARB_draw_buffers` in the ARB programs; the
//! second draw's cost is measured by [`super::bench`].

use crate::error::RenderResult;
use glam::{DMat4, DVec4};

use super::locals;
use super::reference::OitWeight;
use crate::programs;
use crate::techniques::quad::quad_mesh;
use arbvis_core::camera::{Camera, Projection};
use arbvis_core::vocab::TargetFormat;
use arbvis_gl::{
    self, Blend, DrawCall, Gpu, Mesh, Primitive, Program, ProgramKind, Surface, Target,
};

/// The weight the GPU programs compute (eq. 7), for comparisons with the reference.
pub const OIT_WEIGHT: OitWeight = OitWeight::Eq7;

/// The row `r` with `dot(r, p) = z`, the weight's view distance of object point `p`:
/// `-eye_z` in perspective, `2 - eye_z` in orthographic views (the reference's `z`).
pub fn z_row(camera: &Camera) -> DVec4 {
    let row = -camera.view().row(2);
    match camera.projection {
        Projection::Perspective => row,
        Projection::Orthographic => row + DVec4::new(0.0, 0.0, 0.0, 2.0),
    }
}

/// The two float targets and the composite's program and quad; all freed on Drop.
pub struct OitPass {
    accum: Target,
    reveal: Target,
    composite: Program,
    quad: Mesh,
}

impl OitPass {
    /// Targets of `width` x `height` and the composite program of `kind`.
    pub fn new(gpu: &Gpu, kind: ProgramKind, width: u32, height: u32) -> RenderResult<OitPass> {
        let pair = programs::with_transform(
            kind,
            &programs::SPLATS_OIT_COMPOSITE_ARBFP,
            &programs::SPLATS_OIT_COMPOSITE_FRAG,
        );
        let composite = Program::new(gpu, kind, &pair.vertex, &pair.fragment)?;
        composite.set_transform(gpu, DMat4::IDENTITY)?;
        let quad = quad_mesh(gpu, "splats OIT composite quad")?;
        Ok(OitPass {
            accum: Target::new(gpu, width, height, TargetFormat::Rgba32f)?,
            reveal: Target::new(gpu, width, height, TargetFormat::Rgba32f)?,
            composite,
            quad,
        })
    }

    /// Whether the targets have this size.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        (self.accum.width(), self.accum.height()) == (width, height)
    }

    /// Draw the splats of `mesh` with `program` (a splat program pair) into the two
    /// targets, then composite them onto `surface`.
    pub fn draw(
        &self,
        gpu: &Gpu,
        program: &Program,
        mesh: &Mesh,
        surface: Surface<'_>,
    ) -> RenderResult<()> {
        self.accum.clear(gpu, [0.0; 4])?;
        self.reveal.clear(gpu, [1.0; 4])?;
        let splats = |blend: Blend| DrawCall {
            blend,
            primitive: Primitive::Points,
            ..DrawCall::new(program, mesh)
        };
        program.set_local(gpu, locals::OIT_ACCUMULATE, [1.0, 0.0, 0.0, 0.0])?;
        let drawn = arbvis_gl::draw(gpu, Surface::Target(&self.accum), &splats(Blend::Add));
        program.set_local(gpu, locals::OIT_ACCUMULATE, [0.0; 4])?;
        drawn?;
        arbvis_gl::draw(gpu, Surface::Target(&self.reveal), &splats(Blend::Reveal))?;
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(0, self.accum.color()), (1, self.reveal.color())],
                blend: Blend::Over,
                covers_frame: true,
                ..DrawCall::new(&self.composite, &self.quad)
            },
        )?)
    }
}
