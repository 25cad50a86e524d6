//! The GL half of `draw = "tiles"`: the [`super::tiles`] lists and the point colours
//! in three textures, composited by `splats/tiles.frag` over the blocks of tiles that
//! hold any splat (quads of whole pixels; the rest of the view would add nothing),
//! blended `ONE, ONE_MINUS_SRC_ALPHA` over the cleared target. GLSL only (ARB fragment
//! programs have no loops). All textures are freed on Drop.

use crate::error::{texture_rows, RenderResult};
use glam::DMat4;

use super::locals;
use super::tiles::TileLists;
use crate::programs;
use arbvis_gl::{
    self, Blend, DrawCall, Extent, GlError, Gpu, Mesh, Program, ProgramKind, Surface, TexelData,
    TexelFormat, Texture,
};

/// Texels per row of the array textures (`ROW` in `tiles.frag`).
pub const ROW: usize = 4096;

/// Tiles per side of the blocks the gather is drawn over.
const BLOCK: u32 = 8;

/// The gather program, the quads of the occupied blocks, and the textures of the
/// current lists and colours.
pub struct TilePass {
    program: Program,
    blocks: Mesh,
    offsets: Option<Texture>,
    entries: Option<Texture>,
    colours: Option<Texture>,
    /// Tile side and tiles across of the lists uploaded last.
    tile: u32,
    across: u32,
}

/// A 2D array texture of at least `texels` texels of `format`, `ROW` wide: `current`
/// when it is big enough, else a new one with a quarter to spare (uninitialized: only
/// what is uploaded is read).
fn array_texture(
    gpu: &Gpu,
    current: Option<Texture>,
    label: &str,
    format: TexelFormat,
    texels: usize,
) -> RenderResult<Texture> {
    let rows = texels.div_ceil(ROW).max(1);
    if let Some(t) = current {
        if let Extent::D2(_, h) = t.extent() {
            if h as usize >= rows {
                return Ok(t);
            }
        }
    }
    texture_rows(gpu, label, texels, ROW)?;
    let max = gpu.caps().max_texture_size.max(1) as usize;
    let rows = (rows + rows / 4).min(max);
    // The old texture is dropped (freed) before the new one is made.
    Ok(Texture::empty_2d(
        gpu,
        label,
        ROW as u32,
        rows as u32,
        format,
    )?)
}

/// Two triangles per occupied rectangle of `lists`, in normalized device coordinates
/// (position x, y, 0, 1 then an unused texture coordinate), for the identity transform.
fn block_vertices(lists: &TileLists) -> Vec<f32> {
    let [w, h] = lists.size.map(|v| v.max(1) as f32);
    let mut v = Vec::new();
    for [x0, y0, x1, y1] in lists.occupied(BLOCK) {
        let (a, b) = (x0 as f32 / w * 2.0 - 1.0, x1 as f32 / w * 2.0 - 1.0);
        let (c, d) = (y0 as f32 / h * 2.0 - 1.0, y1 as f32 / h * 2.0 - 1.0);
        for (x, y) in [(a, c), (b, c), (b, d), (a, c), (b, d), (a, d)] {
            v.extend_from_slice(&[x, y, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        }
    }
    v
}

/// Put `data` (whole texels of `format`) into `slot`'s array texture, grown as needed.
fn upload(
    gpu: &Gpu,
    slot: &mut Option<Texture>,
    label: &str,
    format: TexelFormat,
    data: TexelData<'_>,
) -> RenderResult<()> {
    let words = match data {
        TexelData::U8(d) => d.len() / 4,
        TexelData::F32(d) => d.len(),
        TexelData::U32(d) => d.len(),
    };
    let texels = words * 4 / format.bytes();
    let t = array_texture(gpu, slot.take(), label, format, texels)?;
    t.update_texels(gpu, data)?;
    *slot = Some(t);
    Ok(())
}

impl TilePass {
    /// The program; the blocks and textures come with the first lists and colours.
    pub fn new(gpu: &Gpu) -> RenderResult<TilePass> {
        let program = Program::new(
            gpu,
            ProgramKind::Glsl,
            &programs::TRANSFORM_VERT,
            &programs::SPLATS_TILES_FRAG,
        )?;
        program.set_transform(gpu, DMat4::IDENTITY)?;
        let blocks = Mesh::new(gpu, "splats tile blocks", &[4, 4], &[])?;
        Ok(TilePass {
            program,
            blocks,
            offsets: None,
            entries: None,
            colours: None,
            tile: 1,
            across: 0,
        })
    }

    /// Upload every point's RGBA (by point index).
    pub fn set_colours(&mut self, gpu: &Gpu, colours: &[[f32; 4]]) -> RenderResult<()> {
        let data = TexelData::F32(colours.as_flattened());
        upload(
            gpu,
            &mut self.colours,
            "splat colours",
            TexelFormat::Rgba32f,
            data,
        )
    }

    /// Upload the lists of a frame.
    pub fn set_lists(&mut self, gpu: &Gpu, lists: &TileLists) -> RenderResult<()> {
        let data = TexelData::U32(&lists.offsets);
        upload(
            gpu,
            &mut self.offsets,
            "splat tile offsets",
            TexelFormat::R32ui,
            data,
        )?;
        let data = TexelData::U32(lists.entries.as_flattened());
        upload(
            gpu,
            &mut self.entries,
            "splat tile lists",
            TexelFormat::Rgba32ui,
            data,
        )?;
        self.blocks.update(gpu, &block_vertices(lists))?;
        self.tile = lists.tile;
        self.across = lists.tiles[0];
        Ok(())
    }

    /// Composite the uploaded lists onto `surface` (the frame the lists were made for);
    /// `kernel` is (1 Gaussian / 0 smoothstep, the Gaussian's width).
    pub fn draw(&self, gpu: &Gpu, surface: Surface<'_>, kernel: [f64; 2]) -> RenderResult<()> {
        let (Some(offsets), Some(entries), Some(colours)) =
            (&self.offsets, &self.entries, &self.colours)
        else {
            return Err(GlError::Invalid(
                "splat tiles drawn before lists and colours were uploaded".into(),
            )
            .into());
        };
        if self.blocks.vertex_count() == 0 {
            return Ok(());
        }
        self.program.set_local(
            gpu,
            0,
            [self.tile as f64, self.across as f64, kernel[0], kernel[1]],
        )?;
        // Window coordinates count from the window's corner; the lists from the view's.
        let origin = match surface {
            Surface::Target(_) => [0, 0],
            Surface::Window([x, y, _, _]) => [x, y],
        };
        self.program.set_local(
            gpu,
            locals::SURFACE_ORIGIN,
            [origin[0] as f64, origin[1] as f64, 0.0, 0.0],
        )?;
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(0, offsets), (1, entries), (2, colours)],
                blend: Blend::PremultipliedOver,
                covers_frame: true,
                ..DrawCall::new(&self.program, &self.blocks)
            },
        )?)
    }
}
