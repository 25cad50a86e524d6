//! How precisely the driver interpolates: texture filtering and attribute interpolation.
//!
//! GL leaves both to the implementation, and precise modes promise f32 rounding.
//!
//! - **Linear filtering.** llvmpipe interpolates in f32; NVIDIA's texture units (as CUDA's
//!   guide says of the same hardware) keep the weights in fixed point with 8 fractional
//!   bits, so a linear fetch can be off by up to half a 256th of the difference between
//!   neighbouring texels: 1e-3 to 1e-2 after a steep colour table. Probe: 256 fetches
//!   between two texels (0 and 1, 16-bit unorm as the precise volumes) at fractions that
//!   use the whole f32 mantissa, so weights of any fixed-point width are seen; the largest
//!   difference from the fraction.
//! - **Attribute interpolation.** A rasterizer that snaps vertices to its sub-pixel grid
//!   and interpolates from the snapped positions (NVIDIA: 1/256 pixel) moves an
//!   interpolated coordinate by up to 1/512 pixel from where the pixel's centre lies on the
//!   true triangle; llvmpipe interpolates from the unsnapped positions. Probe: one
//!   triangle with corners off that grid over a 64 x 4 target, carrying its own NDC
//!   position; the largest difference, in pixels, from the pixel centre's.
//!
//! A result that is not a number counts as coarse.
//!
//! Each is measured once per context, on first use. Precise programs interpolate textures
//! in the shader where the filter is coarse, and take their samples from the pixel's own
//! centre where interpolation is.

use super::draw::{draw, DrawCall};
use super::error::GlResult;
use super::gpu::Gpu;
use super::mesh::Mesh;
use super::program::{Program, ProgramKind, ProgramText};
use super::target::{Surface, Target};
use super::texture::{Extent, Filter, TexelData, TexelFormat, Texture};
use arbvis_core::vocab::TargetFormat;

/// The largest filter error taken as f32 interpolation: an f32 lerp between 0 and 1 is
/// within 6e-8; 8-bit weights are off by up to 2e-3 (1.8e-3 measured), 13-bit ones by up
/// to 6e-5.
pub const EXACT_FILTER: f32 = 1e-5;

/// The largest attribute interpolation error, in pixels, taken as interpolation from the
/// true vertices: f32 rounding of NDC values up to 6 at 32 pixels per unit is within
/// 3e-5 pixel; snapping to 1/256 pixel moves the probe's corners by 1e-3 pixel or more.
pub const EXACT_INTERPOLATION: f32 = 2e-4;

const VERTEX: ProgramText = ProgramText::embedded(
    "gl/precision_probe.vert",
    "#version 330\nlayout(location = 0) in vec4 position;\nout vec2 v_ndc;\n\
     void main() { gl_Position = position; v_ndc = position.xy; }\n",
);

// Filter: for pixel (x, y), u = 0.5 + fract(k * 0.618034 + 0.1234567) with k = x + 64 y,
// a fraction using the whole f32 mantissa; texture coordinate u / 2 puts texel space at
// u, so the exact fetch is u - 0.5 (exact in f32). Interpolation: the pixel centre's NDC
// from gl_FragCoord against the interpolated one, in pixels (the target is 64 x 4).
const FRAGMENT: ProgramText = ProgramText::embedded(
    "gl/precision_probe.frag",
    "#version 330\nuniform sampler2D texture0;\nin vec2 v_ndc;\nout vec4 frag_color;\n\
     void main() {\n    \
     float k = floor(gl_FragCoord.x) + 64.0 * floor(gl_FragCoord.y);\n    \
     float u = 0.5 + fract(k * 0.618034 + 0.1234567);\n    \
     vec2 size = vec2(64.0, 4.0);\n    \
     vec2 off = (v_ndc - (gl_FragCoord.xy * 2.0 / size - 1.0)) * size * 0.5;\n    \
     frag_color = vec4(texture(texture0, vec2(u / 2.0, 0.5)).r, u - 0.5, off);\n}\n",
);

/// The probe's triangle (NDC): corners well outside the target, none on a 1/256-pixel
/// grid of its 64 x 4 pixels.
const CORNERS: [[f32; 2]; 3] = [
    [-1.731_21, -2.919_37],
    [4.127_73, -1.372_59],
    [-1.293_11, 5.461_03],
];

/// The largest errors of linear filtering (between texels 0 and 1) and of attribute
/// interpolation (pixels), measured together.
fn measure(gpu: &Gpu) -> GlResult<(f32, f32)> {
    let program = Program::new(gpu, ProgramKind::Glsl, &VERTEX, &FRAGMENT)?;
    let texels = Texture::new(
        gpu,
        "precision probe 2x1",
        Extent::D2(2, 1),
        TexelFormat::R16FromU8,
        Filter::Linear,
        TexelData::U8(&[0, 255]),
    )?;
    let corners: Vec<f32> = CORNERS
        .iter()
        .flat_map(|&[x, y]| [x, y, 0.0, 1.0])
        .collect();
    let mesh = Mesh::new(gpu, "precision probe triangle", &[4], &corners)?;
    let target = Target::new(gpu, 64, 4, TargetFormat::Rgba32f)?;
    let textures = [(0, &texels)];
    let call = DrawCall {
        textures: &textures,
        ..DrawCall::new(&program, &mesh)
    };
    draw(gpu, Surface::Target(&target), &call)?;
    let image = target.read(gpu)?;
    // `max` would drop a NaN: anything not a number is infinitely coarse.
    let worst = |a: f32, b: f32| if b.is_nan() { f32::INFINITY } else { a.max(b) };
    let (mut filter, mut interpolation) = (0f32, 0f32);
    for p in image.data.chunks_exact(4) {
        filter = worst(filter, (p[0] - p[1]).abs());
        interpolation = worst(worst(interpolation, p[2].abs()), p[3].abs());
    }
    Ok((filter, interpolation))
}

impl Gpu {
    fn precision(&self) -> GlResult<(f32, f32)> {
        if let Some(e) = self.precision_cache().get() {
            return Ok(e);
        }
        // The probe's objects are freed when it returns: leave them out of the log.
        let logged = self.logged_resources();
        let e = measure(self);
        self.forget_resources_after(logged);
        let e = e?;
        self.precision_cache().set(Some(e));
        Ok(e)
    }

    /// The largest error of the driver's `GL_LINEAR` filtering between texels 0 and 1
    /// (see the module docs): f32 rounding on llvmpipe, up to about 1/512 where the
    /// texture units keep 8-bit weights.
    pub fn linear_filter_error(&self) -> GlResult<f32> {
        Ok(self.precision()?.0)
    }

    /// Whether the texture units interpolate to f32 rounding (the error within
    /// [`EXACT_FILTER`]); precise programs interpolate in the shader where they do not.
    pub fn filters_exactly(&self) -> GlResult<bool> {
        Ok(self.linear_filter_error()? <= EXACT_FILTER)
    }

    /// The largest distance, in pixels, between an interpolated coordinate and where the
    /// pixel's centre lies on the true triangle (see the module docs).
    pub fn interpolation_error(&self) -> GlResult<f32> {
        Ok(self.precision()?.1)
    }

    /// Whether attributes interpolate from the true vertices (the error within
    /// [`EXACT_INTERPOLATION`]); precise programs take their samples from the pixel's own
    /// centre where they do not.
    pub fn interpolates_exactly(&self) -> GlResult<bool> {
        Ok(self.interpolation_error()? <= EXACT_INTERPOLATION)
    }
}
