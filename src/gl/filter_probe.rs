//! How finely the driver's texture units interpolate.
//!
//! GL leaves the precision of `GL_LINEAR` filtering to the implementation. llvmpipe
//! interpolates in f32; NVIDIA's texture units (as CUDA's guide says of the same hardware)
//! keep the weights in fixed point with 8 fractional bits, so a linear fetch can be off by
//! up to half a 256th of the difference between neighbouring texels: 1e-3 to 1e-2 after a
//! steep colour table, where precise modes promise f32 rounding. The probe measures it
//! once per context: 64 fetches between two texels (0 and 1, 16-bit unorm as the precise
//! volumes) at fractions that are exact in f32 and not multiples of 1/256; the largest
//! difference from the fraction is the filter's error. Precise programs interpolate in
//! the shader (`texelFetch` and f32 `mix`) where it is larger than [`EXACT_FILTER`].

use super::draw::{draw, DrawCall};
use super::error::GlResult;
use super::gpu::Gpu;
use super::mesh::Mesh;
use super::program::{Program, ProgramKind, ProgramText};
use super::target::{Surface, Target};
use super::texture::{Extent, Filter, TexelData, TexelFormat, Texture};
use crate::vocab::TargetFormat;

/// The largest filter error taken as f32 interpolation: an f32 lerp between 0 and 1 is
/// within 6e-8; 8-bit weights are off by at least 1.8e-3 at the probe's fractions.
pub const EXACT_FILTER: f32 = 1e-5;

/// Fetches in the probe (one per pixel of a 64 x 1 target).
const FETCHES: u32 = 64;

const VERTEX: ProgramText = ProgramText::embedded(
    "gl/filter_probe.vert",
    "#version 330\nlayout(location = 0) in vec4 position;\nvoid main() { gl_Position = position; }\n",
);

// Fraction f = (k + 47/128) / 64 for pixel k: exact in f32, 1.47/256 past a multiple of
// 1/256 (whether a unit rounds or truncates its weights, it is seen). The texture
// coordinate (0.5 + f) / 2 puts texel space at 0.5 + f, so the exact fetch is f.
const FRAGMENT: ProgramText = ProgramText::embedded(
    "gl/filter_probe.frag",
    "#version 330\nuniform sampler2D texture0;\nout vec4 frag_color;\nvoid main() {\n    \
     float f = (floor(gl_FragCoord.x) + 0.3671875) / 64.0;\n    \
     frag_color = vec4(texture(texture0, vec2((0.5 + f) / 2.0, 0.5)).r, f, 0.0, 1.0);\n}\n",
);

impl Gpu {
    /// The largest error of the driver's `GL_LINEAR` filtering between texels 0 and 1,
    /// measured on first use (see the module docs): f32 rounding on llvmpipe, up to about
    /// 1/512 where the texture units keep 8-bit weights.
    pub fn linear_filter_error(&self) -> GlResult<f32> {
        if let Some(e) = self.filter_error_cache().get() {
            return Ok(e);
        }
        // The probe's objects are freed when it returns: leave them out of the log.
        let logged = self.logged_resources();
        let e = measure(self);
        self.forget_resources_after(logged);
        let e = e?;
        self.filter_error_cache().set(Some(e));
        Ok(e)
    }

    /// Whether the texture units interpolate to f32 rounding (the error within
    /// [`EXACT_FILTER`]); precise programs interpolate in the shader where they do not.
    pub fn filters_exactly(&self) -> GlResult<bool> {
        Ok(self.linear_filter_error()? <= EXACT_FILTER)
    }
}

/// Measure the largest error of the driver's linear filtering (see the module docs).
fn measure(gpu: &Gpu) -> GlResult<f32> {
    let program = Program::new(gpu, ProgramKind::Glsl, &VERTEX, &FRAGMENT)?;
    let texels = Texture::new(
        gpu,
        "filter probe 2x1",
        Extent::D2(2, 1),
        TexelFormat::R16FromU8,
        Filter::Linear,
        TexelData::U8(&[0, 255]),
    )?;
    let quad: Vec<f32> = [
        [-1.0, -1.0],
        [1.0, -1.0],
        [1.0, 1.0],
        [-1.0, -1.0],
        [1.0, 1.0],
        [-1.0, 1.0],
    ]
    .iter()
    .flat_map(|&[x, y]| [x, y, 0.0, 1.0])
    .collect();
    let mesh = Mesh::new(gpu, "filter probe quad", &[4], &quad)?;
    let target = Target::new(gpu, FETCHES, 1, TargetFormat::Rgba32f)?;
    let textures = [(0, &texels)];
    let call = DrawCall {
        textures: &textures,
        ..DrawCall::new(&program, &mesh)
    };
    draw(gpu, Surface::Target(&target), &call)?;
    let image = target.read(gpu)?;
    Ok(image
        .data
        .chunks_exact(4)
        .map(|p| (p[0] - p[1]).abs())
        .fold(0.0, f32::max))
}
