//! Offscreen render targets: a framebuffer object with one colour texture in RGBA8,
//! RGBA16F or RGBA32F, read back into an [`Image`]. The colour is an owned [`Texture`]
//! ([`Target::color`]), so that a later draw can read what an earlier one rendered
//! (weighted blended transparency's composite does).

use std::sync::Arc;

use glow::HasContext;

use super::error::{GlError, GlResult};
use super::gpu::Gpu;
use super::state::StateGuard;
use super::texture::{TexelFormat, Texture};
use arbvis_core::image::Image;
pub use arbvis_core::vocab::TargetFormat;

/// The texel format of a target's colour texture.
pub(crate) fn texel_format(format: TargetFormat) -> TexelFormat {
    match format {
        TargetFormat::Rgba8 => TexelFormat::Rgba8,
        TargetFormat::Rgba16f => TexelFormat::Rgba16f,
        TargetFormat::Rgba32f => TexelFormat::Rgba32f,
    }
}

/// Where a draw goes.
#[derive(Clone, Copy)]
pub enum Surface<'a> {
    /// An offscreen target (its whole area).
    Target(&'a Target),
    /// The default framebuffer, in the viewport `[x, y, width, height]`.
    Window([i32; 4]),
}

impl Surface<'_> {
    /// Where draws land in window coordinates, `[x, y, width, height]`: the whole target,
    /// or the window's viewport (what maps `gl_FragCoord` back to NDC).
    pub fn rect(&self) -> [f64; 4] {
        match *self {
            Surface::Target(t) => [0.0, 0.0, t.width() as f64, t.height() as f64],
            Surface::Window(v) => v.map(f64::from),
        }
    }
}

/// Clear `surface` (only its viewport, for a window) to `rgba`.
pub fn clear(gpu: &Gpu, surface: Surface<'_>, rgba: [f32; 4]) -> GlResult<()> {
    let _guard = StateGuard::save(gpu);
    let gl = gpu.glow();
    // SAFETY: plain state calls.
    unsafe {
        match surface {
            Surface::Target(t) => {
                t.bind();
                gl.disable(glow::SCISSOR_TEST);
                if t.has_depth() {
                    gl.depth_mask(true);
                    gl.clear_depth_f64(1.0);
                    gl.clear(glow::DEPTH_BUFFER_BIT);
                }
            }
            Surface::Window([x, y, w, h]) => {
                gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                gl.viewport(x, y, w, h);
                gl.enable(glow::SCISSOR_TEST);
                gl.scissor(x, y, w, h);
            }
        }
        gl.color_mask(true, true, true, true);
        gl.clear_color(rgba[0], rgba[1], rgba[2], rgba[3]);
        gl.clear(glow::COLOR_BUFFER_BIT);
    }
    crate::gl_check!(gpu)
}

/// A framebuffer's colour attachment made: its status checked (complete), GL's errors
/// checked, and its bytes recorded as `what` (`target`, `second colour`).
fn completed(
    gpu: &Gpu,
    status: u32,
    what: &str,
    width: u32,
    height: u32,
    format: TargetFormat,
) -> GlResult<()> {
    if status != glow::FRAMEBUFFER_COMPLETE {
        return Err(GlError::Framebuffer(status));
    }
    crate::gl_check!(gpu)?;
    gpu.record(
        "framebuffer",
        format!("{what} {width}x{height} {}", format.name()),
        width as u64 * height as u64 * format.bytes_per_pixel(),
    );
    Ok(())
}

/// An owned framebuffer with one colour texture (or two: a fragment program's outputs 0
/// and 1) and, when asked for, a 24-bit depth buffer; deleted on Drop (the framebuffer
/// first, then the textures it held).
pub struct Target {
    gl: Arc<glow::Context>,
    framebuffer: glow::Framebuffer,
    color: Texture,
    /// The second colour texture (output 1), where there is one.
    second: Option<Texture>,
    depth: Option<glow::Renderbuffer>,
    width: u32,
    height: u32,
    format: TargetFormat,
}

impl Target {
    /// Create a `width` x `height` target of `format`, cleared to transparent black.
    pub fn new(gpu: &Gpu, width: u32, height: u32, format: TargetFormat) -> GlResult<Target> {
        Target::create(gpu, width, height, format, false)
    }

    /// [`Target::new`] with a 24-bit depth buffer (cleared to 1 with the colour).
    pub fn with_depth(
        gpu: &Gpu,
        width: u32,
        height: u32,
        format: TargetFormat,
    ) -> GlResult<Target> {
        Target::create(gpu, width, height, format, true)
    }

    /// [`Target::new`] with a second colour texture of the same format, written by a
    /// fragment program's output 1 (`layout(location = 1)`), cleared with the first:
    /// what one pass leaves for the next beside its colour.
    pub fn with_second_color(
        gpu: &Gpu,
        width: u32,
        height: u32,
        format: TargetFormat,
    ) -> GlResult<Target> {
        let mut target = Target::create(gpu, width, height, format, false)?;
        let second = Texture::render_target(gpu, width, height, texel_format(format))?;
        // SAFETY: a live framebuffer gains a live texture; the binding is restored.
        let status = unsafe {
            let gl = &target.gl;
            let prev_fb = gl.get_parameter_framebuffer(glow::FRAMEBUFFER_BINDING);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(target.framebuffer));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT1,
                glow::TEXTURE_2D,
                Some(second.raw()),
                0,
            );
            gl.draw_buffers(&[glow::COLOR_ATTACHMENT0, glow::COLOR_ATTACHMENT1]);
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
            gl.bind_framebuffer(glow::FRAMEBUFFER, prev_fb);
            status
        };
        target.second = Some(second);
        completed(gpu, status, "second colour", width, height, format)?;
        Ok(target)
    }

    /// [`Target::new`], or [`Target::with_depth`] when `with_depth`.
    pub fn create(
        gpu: &Gpu,
        width: u32,
        height: u32,
        format: TargetFormat,
        with_depth: bool,
    ) -> GlResult<Target> {
        if width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(GlError::Invalid(format!(
                "target size {width}x{height} (each side 1..=16384)"
            )));
        }
        let gl = gpu.glow().clone();
        let color = Texture::render_target(gpu, width, height, texel_format(format))?;
        // SAFETY: fresh objects; the previous framebuffer binding is restored.
        let (framebuffer, depth, status) = unsafe {
            let prev_fb = gl.get_parameter_framebuffer(glow::FRAMEBUFFER_BINDING);
            let framebuffer = gl.create_framebuffer().map_err(GlError::Invalid)?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(framebuffer));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(color.raw()),
                0,
            );
            let depth = if with_depth {
                let rb = match gl.create_renderbuffer() {
                    Ok(rb) => rb,
                    Err(e) => {
                        gl.bind_framebuffer(glow::FRAMEBUFFER, prev_fb);
                        gl.delete_framebuffer(framebuffer);
                        return Err(GlError::Invalid(e));
                    }
                };
                gl.bind_renderbuffer(glow::RENDERBUFFER, Some(rb));
                gl.renderbuffer_storage(
                    glow::RENDERBUFFER,
                    glow::DEPTH_COMPONENT24,
                    width as i32,
                    height as i32,
                );
                gl.bind_renderbuffer(glow::RENDERBUFFER, None);
                gl.framebuffer_renderbuffer(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    glow::RENDERBUFFER,
                    Some(rb),
                );
                Some(rb)
            } else {
                None
            };
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            gl.clear_color(0.0, 0.0, 0.0, 0.0);
            gl.clear_depth_f64(1.0);
            gl.clear(glow::COLOR_BUFFER_BIT | glow::DEPTH_BUFFER_BIT);
            gl.bind_framebuffer(glow::FRAMEBUFFER, prev_fb);
            (framebuffer, depth, status)
        };
        let target = Target {
            gl,
            framebuffer,
            color,
            second: None,
            depth,
            width,
            height,
            format,
        };
        completed(gpu, status, "target", width, height, format)?;
        if with_depth {
            gpu.record(
                "renderbuffer",
                format!("depth {width}x{height} 24-bit"),
                width as u64 * height as u64 * 4,
            );
        }
        Ok(target)
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Colour precision.
    pub fn format(&self) -> TargetFormat {
        self.format
    }

    /// The colour texture, to be read by a later draw (not while drawing into it).
    pub fn color(&self) -> &Texture {
        &self.color
    }

    /// The second colour texture ([`Target::with_second_color`]), if it has one.
    pub fn second_color(&self) -> Option<&Texture> {
        self.second.as_ref()
    }

    /// Whether it has a depth buffer.
    pub fn has_depth(&self) -> bool {
        self.depth.is_some()
    }

    /// Read the depth buffer (window depth in [0, 1], 1 = nothing drawn), top row first;
    /// `None` without one.
    pub fn read_depth(&self, gpu: &Gpu) -> GlResult<Option<Vec<f32>>> {
        if self.depth.is_none() {
            return Ok(None);
        }
        let _guard = super::state::StateGuard::save(gpu);
        let (w, h) = (self.width as usize, self.height as usize);
        let mut bottom_up = vec![0f32; w * h];
        // SAFETY: the buffer holds exactly w*h floats.
        unsafe {
            self.gl
                .bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.framebuffer));
            self.gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
            let bytes = std::slice::from_raw_parts_mut(
                bottom_up.as_mut_ptr().cast::<u8>(),
                bottom_up.len() * 4,
            );
            self.gl.read_pixels(
                0,
                0,
                w as i32,
                h as i32,
                glow::DEPTH_COMPONENT,
                glow::FLOAT,
                glow::PixelPackData::Slice(Some(bytes)),
            );
        }
        crate::gl_check!(gpu)?;
        Ok(Some(
            bottom_up.chunks_exact(w).rev().flatten().copied().collect(),
        ))
    }

    /// Bind for drawing and set the viewport to the whole target.
    pub(crate) fn bind(&self) {
        // SAFETY: plain state calls with a live framebuffer.
        unsafe {
            self.gl
                .bind_framebuffer(glow::FRAMEBUFFER, Some(self.framebuffer));
            self.gl
                .viewport(0, 0, self.width as i32, self.height as i32);
        }
    }

    /// Clear to `rgba`.
    pub fn clear(&self, gpu: &Gpu, rgba: [f32; 4]) -> GlResult<()> {
        clear(gpu, Surface::Target(self), rgba)
    }

    /// Read the whole target, top row first. RGBA8 keeps its bytes exactly (as `k/255`).
    pub fn read(&self, gpu: &Gpu) -> GlResult<Image> {
        let _guard = super::state::StateGuard::save(gpu);
        // SAFETY: plain state call with a live framebuffer.
        unsafe {
            self.gl
                .bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.framebuffer));
        }
        read_bound(
            gpu,
            [0, 0, self.width as i32, self.height as i32],
            self.format,
        )
    }
}

impl Target {
    /// Copy the whole target into `[x, y, width, height]` of the window's back buffer
    /// (`glBlitFramebuffer`): pixel for pixel when the sizes agree, else scaled with
    /// linear filtering. The viewer keeps its volume image in a target and shows it so.
    pub fn blit_to_window(&self, gpu: &Gpu, [x, y, w, h]: [i32; 4]) -> GlResult<()> {
        let _guard = super::state::StateGuard::save(gpu);
        let (sw, sh) = (self.width as i32, self.height as i32);
        let filter = if (sw, sh) == (w, h) {
            glow::NEAREST
        } else {
            glow::LINEAR
        };
        // SAFETY: plain state calls and a blit between live framebuffers.
        unsafe {
            self.gl
                .bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.framebuffer));
            self.gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
            self.gl.disable(glow::SCISSOR_TEST);
            self.gl.blit_framebuffer(
                0,
                0,
                sw,
                sh,
                x,
                y,
                x + w,
                y + h,
                glow::COLOR_BUFFER_BIT,
                filter,
            );
        }
        crate::gl_check!(gpu)
    }
}

/// Read `[x, y, width, height]` of the window's back buffer as RGBA8 (screenshots).
pub fn read_window(gpu: &Gpu, rect: [i32; 4]) -> GlResult<Image> {
    let _guard = super::state::StateGuard::save(gpu);
    // SAFETY: plain state calls on the default framebuffer.
    unsafe {
        gpu.glow().bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        gpu.glow().read_buffer(glow::BACK);
    }
    read_bound(gpu, rect, TargetFormat::Rgba8)
}

fn read_bound(gpu: &Gpu, [x, y, w, h]: [i32; 4], format: TargetFormat) -> GlResult<Image> {
    if w <= 0 || h <= 0 {
        return Err(GlError::Invalid(format!("read of {w}x{h} pixels")));
    }
    let gl = gpu.glow();
    let (wu, hu) = (w as usize, h as usize);
    let mut data = vec![0f32; wu * hu * 4];
    // SAFETY: the buffers hold exactly w*h*4 values of the type asked for.
    unsafe {
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        if format == TargetFormat::Rgba8 {
            let mut bytes = vec![0u8; wu * hu * 4];
            gl.read_pixels(
                x,
                y,
                w,
                h,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut bytes)),
            );
            for (d, b) in data.iter_mut().zip(&bytes) {
                *d = *b as f32 / 255.0;
            }
        } else {
            let bytes =
                std::slice::from_raw_parts_mut(data.as_mut_ptr().cast::<u8>(), data.len() * 4);
            gl.read_pixels(
                x,
                y,
                w,
                h,
                glow::RGBA,
                glow::FLOAT,
                glow::PixelPackData::Slice(Some(bytes)),
            );
        }
    }
    crate::gl_check!(gpu)?;
    Ok(Image::from_bottom_up(w as u32, h as u32, format, data))
}

impl Drop for Target {
    fn drop(&mut self) {
        // SAFETY: deleted once, on the context that created them.
        unsafe {
            self.gl.delete_framebuffer(self.framebuffer);
            if let Some(rb) = self.depth {
                self.gl.delete_renderbuffer(rb);
            }
        }
    }
}
