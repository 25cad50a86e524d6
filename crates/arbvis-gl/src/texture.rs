//! Owned textures (1D, 2D, 3D) with explicit formats, filters and units.

use std::sync::Arc;

use glow::HasContext;

use super::error::{GlError, GlResult};
use super::gpu::Gpu;

/// Texel formats the techniques use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TexelFormat {
    /// 3 x u8 (v3o2's packed attribute volume).
    Rgb8,
    /// 4 x u8 (colour tables).
    Rgba8,
    /// 4 x f32.
    Rgba32f,
    /// 1 x f32.
    R32f,
    /// 2 x f32.
    Rg32f,
    /// 1 x u8 (normalized; the era's LUMINANCE8).
    R8,
    /// 3 x f16, filled from u8 data (normalized k/255, converted by GL): filtering in
    /// float instead of 8-bit arithmetic, at 6 bytes per texel.
    Rgb16f,
    /// 4 x f32, filled from u8 data (normalized k/255, converted by GL).
    Rgba32fFromU8,
    /// 1 x 16-bit unorm, filled from u8 data: GL stores k as k·257, which reads back as
    /// k·257/65535 = k/255 exactly (where half floats are 2^-11 off), filtered in float.
    R16FromU8,
    /// 2 x 16-bit unorm from u8 data (see [`TexelFormat::R16FromU8`]).
    Rg16FromU8,
    /// 3 x 16-bit unorm from u8 data (see [`TexelFormat::R16FromU8`]).
    Rgb16FromU8,
    /// 1 x f32 filled from u8 data (k/255 converted by GL): twice the bytes of
    /// [`TexelFormat::R16FromU8`], the same values, and faster to filter on llvmpipe.
    R32fFromU8,
    /// 4 x f16, filled from f32 data (a render target's colour).
    Rgba16f,
    /// 4 x u32, unnormalized (`usampler`, `texelFetch` only), filled from the u32s'
    /// native bytes: records whose words a program reinterprets (`uintBitsToFloat`).
    Rgba32ui,
    /// 1 x u32, unnormalized (see [`TexelFormat::Rgba32ui`]).
    R32ui,
    /// 2 x u32, unnormalized (see [`TexelFormat::Rgba32ui`]).
    Rg32ui,
}

impl TexelFormat {
    /// Bytes per texel.
    pub fn bytes(self) -> usize {
        match self {
            TexelFormat::Rgb8 => 3,
            TexelFormat::Rgba8 => 4,
            TexelFormat::Rgba32f => 16,
            TexelFormat::R32f => 4,
            TexelFormat::Rg32f => 8,
            TexelFormat::R8 => 1,
            TexelFormat::Rgb16f => 6,
            TexelFormat::Rgba32fFromU8 => 16,
            TexelFormat::R16FromU8 => 2,
            TexelFormat::Rg16FromU8 => 4,
            TexelFormat::Rgb16FromU8 => 6,
            TexelFormat::R32fFromU8 => 4,
            TexelFormat::Rgba16f => 8,
            TexelFormat::Rgba32ui => 16,
            TexelFormat::R32ui => 4,
            TexelFormat::Rg32ui => 8,
        }
    }

    /// Bytes per texel of the data handed to GL.
    pub fn source_bytes(self) -> usize {
        match self {
            TexelFormat::Rgb16f => 3,
            TexelFormat::Rgba32fFromU8 => 4,
            TexelFormat::R16FromU8 => 1,
            TexelFormat::Rg16FromU8 => 2,
            TexelFormat::Rgb16FromU8 => 3,
            TexelFormat::R32fFromU8 => 1,
            TexelFormat::Rgba16f => 16,
            other => other.bytes(),
        }
    }

    fn source_kind(self) -> SourceKind {
        match self {
            TexelFormat::Rgba32f
            | TexelFormat::R32f
            | TexelFormat::Rg32f
            | TexelFormat::Rgba16f => SourceKind::F32,
            TexelFormat::Rgba32ui | TexelFormat::R32ui | TexelFormat::Rg32ui => SourceKind::U32,
            _ => SourceKind::U8,
        }
    }

    fn gl(self) -> (u32, u32, u32) {
        match self {
            TexelFormat::Rgb8 => (glow::RGB8, glow::RGB, glow::UNSIGNED_BYTE),
            TexelFormat::Rgba8 => (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE),
            TexelFormat::Rgba32f => (glow::RGBA32F, glow::RGBA, glow::FLOAT),
            TexelFormat::R32f => (glow::R32F, glow::RED, glow::FLOAT),
            TexelFormat::Rg32f => (glow::RG32F, glow::RG, glow::FLOAT),
            TexelFormat::R8 => (glow::R8, glow::RED, glow::UNSIGNED_BYTE),
            TexelFormat::Rgb16f => (glow::RGB16F, glow::RGB, glow::UNSIGNED_BYTE),
            TexelFormat::Rgba32fFromU8 => (glow::RGBA32F, glow::RGBA, glow::UNSIGNED_BYTE),
            TexelFormat::R16FromU8 => (glow::R16, glow::RED, glow::UNSIGNED_BYTE),
            TexelFormat::Rg16FromU8 => (glow::RG16, glow::RG, glow::UNSIGNED_BYTE),
            TexelFormat::Rgb16FromU8 => (glow::RGB16, glow::RGB, glow::UNSIGNED_BYTE),
            TexelFormat::R32fFromU8 => (glow::R32F, glow::RED, glow::UNSIGNED_BYTE),
            TexelFormat::Rgba16f => (glow::RGBA16F, glow::RGBA, glow::FLOAT),
            TexelFormat::Rgba32ui => (glow::RGBA32UI, glow::RGBA_INTEGER, glow::UNSIGNED_INT),
            TexelFormat::R32ui => (glow::R32UI, glow::RED_INTEGER, glow::UNSIGNED_INT),
            TexelFormat::Rg32ui => (glow::RG32UI, glow::RG_INTEGER, glow::UNSIGNED_INT),
        }
    }

    fn name(self) -> &'static str {
        match self {
            TexelFormat::Rgb8 => "RGB8",
            TexelFormat::Rgba8 => "RGBA8",
            TexelFormat::Rgba32f => "RGBA32F",
            TexelFormat::R32f => "R32F",
            TexelFormat::Rg32f => "RG32F",
            TexelFormat::R8 => "R8",
            TexelFormat::Rgb16f => "RGB16F",
            TexelFormat::Rgba32fFromU8 => "RGBA32F",
            TexelFormat::R16FromU8 => "R16",
            TexelFormat::Rg16FromU8 => "RG16",
            TexelFormat::Rgb16FromU8 => "RGB16",
            TexelFormat::R32fFromU8 => "R32F",
            TexelFormat::Rgba16f => "RGBA16F",
            TexelFormat::Rgba32ui => "RGBA32UI",
            TexelFormat::R32ui => "R32UI",
            TexelFormat::Rg32ui => "RG32UI",
        }
    }
}

/// Texture filtering for both minification and magnification (no mipmaps).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Filter {
    /// `GL_NEAREST`.
    #[default]
    Nearest,
    /// `GL_LINEAR`.
    Linear,
}

/// Texel data to upload.
#[derive(Debug, Clone, Copy)]
pub enum TexelData<'a> {
    /// Bytes for 8-bit formats.
    U8(&'a [u8]),
    /// Floats for float formats.
    F32(&'a [f32]),
    /// Words for the unsigned integer formats.
    U32(&'a [u32]),
}

impl<'a> TexelData<'a> {
    /// The bytes handed to GL, and which kind of source they are.
    fn bytes(self) -> (&'a [u8], SourceKind) {
        match self {
            TexelData::U8(d) => (d, SourceKind::U8),
            TexelData::F32(d) => (bytes_of(d), SourceKind::F32),
            TexelData::U32(d) => (bytes_of(d), SourceKind::U32),
        }
    }
}

/// What a format's source data is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SourceKind {
    U8,
    F32,
    U32,
}

impl SourceKind {
    fn name(self) -> &'static str {
        match self {
            SourceKind::U8 => "u8",
            SourceKind::F32 => "f32",
            SourceKind::U32 => "u32",
        }
    }
}

/// Texture dimensionality and size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extent {
    /// 1D texture of this width.
    D1(u32),
    /// 2D texture.
    D2(u32, u32),
    /// 3D texture.
    D3(u32, u32, u32),
}

impl Extent {
    fn texels(self) -> usize {
        match self {
            Extent::D1(w) => w as usize,
            Extent::D2(w, h) => w as usize * h as usize,
            Extent::D3(w, h, d) => w as usize * h as usize * d as usize,
        }
    }
    fn target(self) -> u32 {
        match self {
            Extent::D1(_) => glow::TEXTURE_1D,
            Extent::D2(..) => glow::TEXTURE_2D,
            Extent::D3(..) => glow::TEXTURE_3D,
        }
    }
}

/// An owned GL texture; deleted on Drop.
pub struct Texture {
    gl: Arc<glow::Context>,
    raw: glow::Texture,
    extent: Extent,
    format: TexelFormat,
}

impl Texture {
    /// Create and fill a texture; clamp-to-edge wrapping, `filter` both ways.
    pub fn new(
        gpu: &Gpu,
        label: &str,
        extent: Extent,
        format: TexelFormat,
        filter: Filter,
        data: TexelData<'_>,
    ) -> GlResult<Texture> {
        let expected = extent.texels() * format.source_bytes();
        let (bytes, kind) = data.bytes();
        if bytes.len() != expected || kind != format.source_kind() {
            return Err(GlError::Invalid(format!(
                "texture {label}: {extent:?} {} needs {expected} bytes of {} data, got {} bytes of {}",
                format.name(),
                format.source_kind().name(),
                bytes.len(),
                kind.name()
            )));
        }
        Texture::create(gpu, label, extent, format, filter, Some(bytes))
    }

    /// A 3D texture of `dims` texels of `format` whose texels are filled later
    /// ([`Texture::update_region`]): no copy of zeros in memory first.
    pub fn empty_3d(
        gpu: &Gpu,
        label: &str,
        dims: [usize; 3],
        format: TexelFormat,
        filter: Filter,
    ) -> GlResult<Texture> {
        let [w, h, d] = dims.map(|v| v as u32);
        Texture::create(gpu, label, Extent::D3(w, h, d), format, filter, None)
    }

    fn create(
        gpu: &Gpu,
        label: &str,
        extent: Extent,
        format: TexelFormat,
        filter: Filter,
        bytes: Option<&[u8]>,
    ) -> GlResult<Texture> {
        let gl = gpu.glow().clone();
        let target = extent.target();
        let (internal, fmt, ty) = format.gl();
        let gl_filter = match filter {
            Filter::Nearest => glow::NEAREST,
            Filter::Linear => glow::LINEAR,
        } as i32;
        // SAFETY: sizes checked by the callers (or no data: GL allocates); the texture is bound to its own target only while
        // being filled, and the previous binding of unit 0's target is restored.
        let raw = unsafe {
            let raw = gl.create_texture().map_err(GlError::Invalid)?;
            let binding = match extent {
                Extent::D1(_) => glow::TEXTURE_BINDING_1D,
                Extent::D2(..) => glow::TEXTURE_BINDING_2D,
                Extent::D3(..) => glow::TEXTURE_BINDING_3D,
            };
            let prev_active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            gl.active_texture(glow::TEXTURE0);
            let prev = gl.get_parameter_texture(binding);
            gl.bind_texture(target, Some(raw));
            gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
            let src = glow::PixelUnpackData::Slice(bytes);
            match extent {
                Extent::D1(w) => {
                    gl.tex_image_1d(target, 0, internal as i32, w as i32, 0, fmt, ty, src)
                }
                Extent::D2(w, h) => gl.tex_image_2d(
                    target,
                    0,
                    internal as i32,
                    w as i32,
                    h as i32,
                    0,
                    fmt,
                    ty,
                    src,
                ),
                Extent::D3(w, h, d) => gl.tex_image_3d(
                    target,
                    0,
                    internal as i32,
                    w as i32,
                    h as i32,
                    d as i32,
                    0,
                    fmt,
                    ty,
                    src,
                ),
            }
            gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, gl_filter);
            gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, gl_filter);
            for wrap in [
                glow::TEXTURE_WRAP_S,
                glow::TEXTURE_WRAP_T,
                glow::TEXTURE_WRAP_R,
            ] {
                gl.tex_parameter_i32(target, wrap, glow::CLAMP_TO_EDGE as i32);
            }
            gl.bind_texture(target, prev);
            gl.active_texture(prev_active);
            raw
        };
        let texture = Texture {
            gl,
            raw,
            extent,
            format,
        };
        let bytes = (extent.texels() * format.bytes()) as u64;
        crate::gl_check_alloc!(gpu, || format!("texture {label} {extent:?}"), bytes)?;
        gpu.record(
            "texture",
            format!("{label} {extent:?} {}", format.name()),
            bytes,
        );
        Ok(texture)
    }

    /// An uninitialized `width` x `height` 2D texture of `format` to fill later
    /// ([`Texture::update_texels`]): no copy of zeros in memory first.
    pub fn empty_2d(
        gpu: &Gpu,
        label: &str,
        width: u32,
        height: u32,
        format: TexelFormat,
    ) -> GlResult<Texture> {
        let texture = Texture::render_target(gpu, width, height, format)?;
        gpu.record(
            "texture",
            format!("{label} {:?} {}", texture.extent, format.name()),
            (width as u64) * (height as u64) * format.bytes() as u64,
        );
        Ok(texture)
    }

    /// An uninitialized `width` x `height` 2D texture of `format` (immutable storage,
    /// nearest filtering, clamp to edge) to render into: a [`super::Target`]'s colour,
    /// which records it among the resources (this does not).
    pub(crate) fn render_target(
        gpu: &Gpu,
        width: u32,
        height: u32,
        format: TexelFormat,
    ) -> GlResult<Texture> {
        let gl = gpu.glow().clone();
        let (internal, _, _) = format.gl();
        // SAFETY: a fresh texture, bound to unit 0's 2D target only while being set up;
        // the previous binding and active unit are restored.
        let raw = unsafe {
            let prev_active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            gl.active_texture(glow::TEXTURE0);
            let prev = gl.get_parameter_texture(glow::TEXTURE_BINDING_2D);
            let raw = gl.create_texture().map_err(GlError::Invalid)?;
            gl.bind_texture(glow::TEXTURE_2D, Some(raw));
            gl.tex_storage_2d(glow::TEXTURE_2D, 1, internal, width as i32, height as i32);
            for (name, value) in [
                (glow::TEXTURE_MIN_FILTER, glow::NEAREST),
                (glow::TEXTURE_MAG_FILTER, glow::NEAREST),
                (glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE),
                (glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE),
            ] {
                gl.tex_parameter_i32(glow::TEXTURE_2D, name, value as i32);
            }
            gl.bind_texture(glow::TEXTURE_2D, prev);
            gl.active_texture(prev_active);
            raw
        };
        let texture = Texture {
            gl,
            raw,
            extent: Extent::D2(width, height),
            format,
        };
        crate::gl_check_alloc!(
            gpu,
            || format!("a {width}x{height} {} texture", format.name()),
            width as u64 * height as u64 * format.bytes() as u64
        )?;
        Ok(texture)
    }

    /// The GL name (to attach to a framebuffer).
    pub(crate) fn raw(&self) -> glow::Texture {
        self.raw
    }

    /// Replace all texels (same size and format).
    pub fn update(&self, gpu: &Gpu, data: &[u8]) -> GlResult<()> {
        let expected = self.extent.texels() * self.format.source_bytes();
        if data.len() != expected {
            return Err(GlError::Invalid(format!(
                "texture update needs {expected} bytes, got {}",
                data.len()
            )));
        }
        let (internal, fmt, ty) = self.format.gl();
        let gl = &self.gl;
        let target = self.extent.target();
        // SAFETY: size checked; the texture is bound on unit 0 only while filled (unbound
        // after), and the active unit is restored.
        unsafe {
            let prev_active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(target, Some(self.raw));
            gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
            let src = glow::PixelUnpackData::Slice(Some(data));
            match self.extent {
                // glow has no glTexSubImage1D: re-specify the (same-size) image.
                Extent::D1(w) => {
                    gl.tex_image_1d(target, 0, internal as i32, w as i32, 0, fmt, ty, src)
                }
                Extent::D2(w, h) => {
                    gl.tex_sub_image_2d(target, 0, 0, 0, w as i32, h as i32, fmt, ty, src)
                }
                Extent::D3(w, h, d) => gl.tex_sub_image_3d(
                    target, 0, 0, 0, 0, w as i32, h as i32, d as i32, fmt, ty, src,
                ),
            }
            gl.bind_texture(target, None);
            gl.active_texture(prev_active);
        }
        crate::gl_check!(gpu)
    }

    /// Replace all texels (same size and format) from typed data.
    pub fn update_data(&self, gpu: &Gpu, data: TexelData<'_>) -> GlResult<()> {
        let (bytes, kind) = data.bytes();
        if kind != self.format.source_kind() {
            return Err(GlError::Invalid(format!(
                "texture update: {} data for a {} texture",
                kind.name(),
                self.format.source_kind().name()
            )));
        }
        self.update(gpu, bytes)
    }

    /// Replace the box of `size` texels at `offset` of a 3D texture (a brick atlas's slot)
    /// with `data`, i fastest.
    pub fn update_region(
        &self,
        gpu: &Gpu,
        offset: [usize; 3],
        size: [usize; 3],
        data: &[u8],
    ) -> GlResult<()> {
        let Extent::D3(w, h, d) = self.extent else {
            return Err(GlError::Invalid(format!(
                "update_region on a {:?} texture",
                self.extent
            )));
        };
        let dims = [w as usize, h as usize, d as usize];
        let expected = size.iter().product::<usize>() * self.format.source_bytes();
        if data.len() != expected || (0..3).any(|a| offset[a] + size[a] > dims[a]) {
            return Err(GlError::Invalid(format!(
                "texture region update: {size:?} texels at {offset:?} in {dims:?} need {expected} bytes, got {}",
                data.len()
            )));
        }
        let (_, fmt, ty) = self.format.gl();
        let gl = &self.gl;
        // SAFETY: region and size checked above; the texture is bound on unit 0 only while
        // filled (unbound after), and the active unit is restored.
        unsafe {
            let prev_active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_3D, Some(self.raw));
            gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
            let [x, y, z] = offset.map(|v| v as i32);
            let [sw, sh, sd] = size.map(|v| v as i32);
            let src = glow::PixelUnpackData::Slice(Some(data));
            gl.tex_sub_image_3d(glow::TEXTURE_3D, 0, x, y, z, sw, sh, sd, fmt, ty, src);
            gl.bind_texture(glow::TEXTURE_3D, None);
            gl.active_texture(prev_active);
        }
        crate::gl_check!(gpu)
    }

    /// Replace the first texels of a 2D texture, row after row, with `data` (whole
    /// texels of its format; the last row may be partial): what a texture used as a
    /// growing array needs each frame.
    pub fn update_texels(&self, gpu: &Gpu, data: TexelData<'_>) -> GlResult<()> {
        let Extent::D2(w, h) = self.extent else {
            return Err(GlError::Invalid(format!(
                "update_texels on a {:?} texture",
                self.extent
            )));
        };
        let (bytes, kind) = data.bytes();
        let texel = self.format.source_bytes();
        let row = w as usize * texel;
        let fits = bytes.len() <= row * h as usize;
        if kind != self.format.source_kind() || bytes.len() % texel != 0 || !fits {
            return Err(GlError::Invalid(format!(
                "texture update: {} bytes of {} are not whole {texel}-byte texels of {} within {w} x {h}",
                bytes.len(),
                kind.name(),
                self.format.source_kind().name()
            )));
        }
        let (whole, part) = bytes.split_at(bytes.len() / row * row);
        let (_, fmt, ty) = self.format.gl();
        let gl = &self.gl;
        // SAFETY: sizes checked above (whole rows, then one partial row below them); the
        // texture is bound on unit 0 only while filled (unbound after), and the active
        // unit is restored.
        unsafe {
            let prev_active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(self.raw));
            gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
            let rows = (whole.len() / row) as i32;
            for (y, height, width, src) in [
                (0, rows, w as i32, whole),
                (rows, 1, (part.len() / texel) as i32, part),
            ] {
                if src.is_empty() {
                    continue;
                }
                let src = glow::PixelUnpackData::Slice(Some(src));
                gl.tex_sub_image_2d(glow::TEXTURE_2D, 0, 0, y, width, height, fmt, ty, src);
            }
            gl.bind_texture(glow::TEXTURE_2D, None);
            gl.active_texture(prev_active);
        }
        crate::gl_check!(gpu)
    }

    /// Size and dimensionality.
    pub fn extent(&self) -> Extent {
        self.extent
    }

    /// Bind to texture unit `unit` (unit's active binding for this texture's target).
    pub(crate) fn bind(&self, unit: u32) {
        // SAFETY: plain state calls with a live texture.
        unsafe {
            self.gl.active_texture(glow::TEXTURE0 + unit);
            self.gl.bind_texture(self.extent.target(), Some(self.raw));
        }
    }

    /// Unbind this texture's target on `unit`.
    pub(crate) fn unbind(&self, unit: u32) {
        // SAFETY: plain state calls.
        unsafe {
            self.gl.active_texture(glow::TEXTURE0 + unit);
            self.gl.bind_texture(self.extent.target(), None);
        }
    }
}

impl Drop for Texture {
    fn drop(&mut self) {
        // SAFETY: deleted once, on the context that created it.
        unsafe { self.gl.delete_texture(self.raw) };
    }
}

/// Plain numbers (`f32`, `u32`: every bit pattern valid, no padding) as bytes.
fn bytes_of<T: PlainNumber>(d: &[T]) -> &[u8] {
    // SAFETY: T is f32 or u32 (sealed below): no padding, every byte initialized, and u8
    // has alignment 1.
    unsafe { std::slice::from_raw_parts(d.as_ptr().cast(), std::mem::size_of_val(d)) }
}

/// The element types [`bytes_of`] accepts.
trait PlainNumber: Copy {}
impl PlainNumber for f32 {}
impl PlainNumber for u32 {}
