//! `--demo quad`: a full-screen quad drawn by a tiny ARB fragment program and its GLSL
//! twin — the foundation's smallest end-to-end check of contexts, programs, locals,
//! targets and PNG output.
//!
//! # How it works
//! Two triangles cover clip space [-1, 1]² (the camera rotates and zooms them in the
//! viewer; by default they fill the target). Texture coordinate (u, v) runs from (0, 0)
//! at the bottom left to (1, 1) at the top right. The fragment program computes
//! `c = mix(left, right, u)` with `left = program.local[0]`, `right = program.local[1]`,
//! and outputs `(c.rgb * v, c.a)`. [`reference`] computes the same at pixel centres in f64.

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use glam::{DMat4, DVec3};
use serde::{Deserialize, Serialize};

use super::{Frame, Params, Renderer, Settings, Technique};
use crate::programs;
use arbvis_core::image::Image;
use arbvis_gl::{self, DrawCall, GlError, Gpu, Mesh, Program, ProgramKind, Surface};

/// The program local of the left edge's colour (`program.local[0]`).
pub const LEFT_LOCAL: usize = 0;
/// The program local of the right edge's colour (`program.local[1]`).
pub const RIGHT_LOCAL: usize = 1;

/// Parameters of the quad demo.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct QuadScene {
    /// Colour at the left edge (RGBA), `program.local[0]`.
    pub left: [f64; 4],
    /// Colour at the right edge (RGBA), `program.local[1]`.
    pub right: [f64; 4],
}

impl Technique for QuadScene {
    const NAME: &'static str = "quad";
    const DEMOS: &'static [(&'static str, &'static str)] = &[crate::techniques::demo!("quad")];

    fn validate(
        &self,
        _: arbvis_core::vocab::Fidelity,
        _: arbvis_gl::ProgramChoice,
    ) -> Result<(), arbvis_core::vocab::FieldError> {
        Ok(())
    }

    fn program_pairs() -> Vec<programs::ProgramPair> {
        program_pairs()
    }

    type Prepared = ();

    fn prepare(&self, _: &Settings<'_>, _: &arbvis_data::volume::Limits) -> RenderResult<()> {
        Ok(())
    }

    /// The quad's colours at pixel centres (the quad fills the picture; no camera).
    fn reference(
        &self,
        _: &(),
        view: &crate::techniques::ReferenceView<'_>,
    ) -> Option<arbvis_core::image::Image> {
        let [w, h] = view.size;
        Some(reference_image(
            self,
            w,
            h,
            arbvis_gl::TargetFormat::Rgba32f,
        ))
    }

    fn renderer(
        &self,
        gpu: &Gpu,
        _: &Settings<'_>,
        kind: ProgramKind,
        _: (),
    ) -> RenderResult<Box<dyn Renderer>> {
        Ok(Box::new(QuadRenderer::new(gpu, kind, self)?))
    }
}

impl Default for QuadScene {
    fn default() -> Self {
        QuadScene {
            left: [1.0, 0.2, 0.0, 1.0],
            right: [0.0, 0.4, 1.0, 1.0],
        }
    }
}

pub use arbvis_gl::quad_vertices;

/// A mesh of [`quad_vertices`] (attributes 4 + 4), labelled `label`: the full-screen
/// passes' quad.
pub fn quad_mesh(gpu: &Gpu, label: &str) -> GlResult<Mesh> {
    Mesh::new(gpu, label, &[4, 4], &quad_vertices())
}

/// The quad's transform: the camera's rotation and zoom; depth halved so a rotated quad
/// stays inside the clip volume. Identity for the default camera.
pub fn transform(frame: &Frame) -> DMat4 {
    let zoom = frame.camera.zoom.max(1e-6);
    DMat4::from_scale(DVec3::new(zoom, zoom, 0.5)) * DMat4::from_quat(frame.camera.quat())
}

/// The quad demo's GL state.
pub struct QuadRenderer {
    program: Program,
    mesh: Mesh,
}

impl QuadRenderer {
    /// Compile the programs of `kind`, upload the quad, set the colours.
    pub fn new(gpu: &Gpu, kind: ProgramKind, params: &QuadScene) -> RenderResult<QuadRenderer> {
        let pair = programs::with_transform(kind, &programs::QUAD_ARBFP, &programs::QUAD_FRAG);
        let program = Program::new(gpu, kind, &pair.vertex, &pair.fragment)?;
        let mesh = quad_mesh(gpu, "quad")?;
        let renderer = QuadRenderer { program, mesh };
        renderer.set_colours(gpu, params)?;
        Ok(renderer)
    }

    fn set_colours(&self, gpu: &Gpu, params: &QuadScene) -> GlResult<()> {
        if params
            .left
            .iter()
            .chain(&params.right)
            .any(|v| !v.is_finite())
        {
            return Err(GlError::Invalid("quad colours must be finite".into()));
        }
        self.program.set_local(gpu, LEFT_LOCAL, params.left)?;
        self.program.set_local(gpu, RIGHT_LOCAL, params.right)
    }
}

impl Renderer for QuadRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        self.program.set_transform(gpu, transform(frame))?;
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall::new(&self.program, &self.mesh),
        )?)
    }

    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        Ok(self.set_colours(gpu, params.get::<QuadScene>()?)?)
    }

    fn program_kind(&self) -> ProgramKind {
        self.program.kind()
    }
}

/// The program pairs the quad draws with, both kinds.
pub fn program_pairs() -> Vec<programs::ProgramPair> {
    programs::both_kinds(&programs::QUAD_ARBFP, &programs::QUAD_FRAG)
}

/// CPU reference (f64) of the default-camera image at pixel centres, top row first;
/// `clamp` as a normalized (RGBA8) target clamps.
pub fn reference(params: &QuadScene, width: u32, height: u32, clamp: bool) -> Vec<[f64; 4]> {
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        let v = 1.0 - (y as f64 + 0.5) / height as f64;
        for x in 0..width {
            let u = (x as f64 + 0.5) / width as f64;
            let c: [f64; 4] =
                std::array::from_fn(|i| params.left[i] * (1.0 - u) + params.right[i] * u);
            let px = [c[0] * v, c[1] * v, c[2] * v, c[3]];
            out.push(if clamp {
                px.map(|p| p.clamp(0.0, 1.0))
            } else {
                px
            });
        }
    }
    out
}

/// [`reference`] as an [`Image`] of `format`, for comparisons.
pub fn reference_image(
    params: &QuadScene,
    width: u32,
    height: u32,
    format: arbvis_gl::TargetFormat,
) -> Image {
    let clamp = format == arbvis_gl::TargetFormat::Rgba8;
    Image::from_f64_pixels(
        width,
        height,
        format,
        reference(params, width, height, clamp),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_corners() {
        let p = QuadScene {
            left: [1.0, 0.0, 0.0, 1.0],
            right: [0.0, 0.0, 1.0, 0.5],
        };
        let img = reference(&p, 2, 2, true);
        // Top-left pixel centre: u = 0.25, v = 0.75.
        let tl = img[0];
        assert!((tl[0] - 0.75 * 0.75).abs() < 1e-12);
        assert!((tl[2] - 0.25 * 0.75).abs() < 1e-12);
        assert!((tl[3] - 0.875).abs() < 1e-12);
    }

    #[test]
    fn six_vertices_of_eight_floats() {
        assert_eq!(quad_vertices().len(), 6 * 8);
    }
}
