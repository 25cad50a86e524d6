//! One draw call: a program, a mesh, textures on named units, a blend mode, into a
//! target or the window's framebuffer. GL state is saved before and restored after.

use glow::HasContext;

use super::error::{GlError, GlResult};
use super::gpu::Gpu;
use super::mesh::Mesh;
use super::program::Program;
use super::state::StateGuard;
use super::target::Surface;
use super::texture::Texture;

/// How fragments combine with the target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Blend {
    /// Fragments replace the target.
    #[default]
    Replace,
    /// Back-to-front "over" of non-premultiplied colour: `SRC_ALPHA, ONE_MINUS_SRC_ALPHA`
    /// for colour, `ONE, ONE_MINUS_SRC_ALPHA` for alpha, so that the target's alpha is
    /// coverage (colour is what v3o2's blend gave; alpha makes the frame usable as a
    /// transparent picture).
    Over,
    /// Back-to-front "over" of premultiplied colour: `ONE, ONE_MINUS_SRC_ALPHA`.
    PremultipliedOver,
    /// Sum: `ONE, ONE` (weighted blended transparency's accumulation).
    Add,
    /// Product of transmittances: `ZERO, ONE_MINUS_SRC_ALPHA` on every channel (weighted
    /// blended transparency's revealage).
    Reveal,
    /// Product of colours: `ZERO, SRC_COLOR` (a shade laid over a picture).
    Multiply,
}

/// What the vertices make.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Primitive {
    /// Triangle lists.
    #[default]
    Triangles,
    /// Point sprites: the program sets the size (`gl_PointSize`, ARB `result.pointsize`);
    /// the fragment gets its position in the sprite (`gl_PointCoord`, or
    /// `fragment.texcoord[0]` for ARB programs).
    Points,
}

/// Everything one draw needs.
pub struct DrawCall<'a> {
    /// The program pair.
    pub program: &'a Program,
    /// The vertices (triangles).
    pub mesh: &'a Mesh,
    /// First element and element count (vertices, or indices when the mesh has them);
    /// `None` draws all.
    pub range: Option<(usize, usize)>,
    /// Textures and the units they go on.
    pub textures: &'a [(u32, &'a Texture)],
    /// Blending.
    pub blend: Blend,
    /// Depth test `LESS` with depth writes (the surface needs a depth buffer).
    pub depth_test: bool,
    /// Cull back faces (counter-clockwise triangles face the viewer).
    pub cull_back: bool,
    /// Triangles or point sprites.
    pub primitive: Primitive,
    /// A pass over the whole frame (a full-screen composite), never occluded by depth
    /// ([`Gpu::set_occluded`]).
    pub covers_frame: bool,
}

impl<'a> DrawCall<'a> {
    /// All of `mesh` as triangles with `program`: no textures, no blending, no depth
    /// test, no culling; change what differs with struct update syntax.
    pub fn new(program: &'a Program, mesh: &'a Mesh) -> DrawCall<'a> {
        DrawCall {
            program,
            mesh,
            range: None,
            textures: &[],
            blend: Blend::Replace,
            depth_test: false,
            cull_back: false,
            primitive: Primitive::Triangles,
            covers_frame: false,
        }
    }

    /// A layer's sheet: opaque, replacing what is drawn and depth tested (depth writes
    /// are the target's), so a layered scene's other layers meet it; translucent,
    /// premultiplied over what is drawn without a depth test of its own (a layered scene
    /// tests it against its opaque layers).
    pub fn sheet(self, translucent: bool) -> DrawCall<'a> {
        DrawCall {
            blend: match translucent {
                true => Blend::PremultipliedOver,
                false => Blend::Replace,
            },
            depth_test: !translucent,
            ..self
        }
    }
}

/// Draw `call` onto `surface` and count the samples that passed every test (an
/// occlusion query: `SAMPLES_PASSED`); waits for the GL to finish the draw.
pub fn draw_counted(gpu: &Gpu, surface: Surface<'_>, call: &DrawCall<'_>) -> GlResult<u64> {
    /// The query, deleted on every path out.
    struct Query<'g>(&'g glow::Context, glow::Query);
    impl Drop for Query<'_> {
        fn drop(&mut self) {
            // SAFETY: the query was created on this context and is not in use.
            unsafe { self.0.delete_query(self.1) };
        }
    }
    let gl = gpu.glow();
    // SAFETY: plain object creation.
    let query = Query(gl, unsafe { gl.create_query() }.map_err(GlError::Invalid)?);
    // SAFETY: one query of this target active at a time (begun and ended here).
    unsafe { gl.begin_query(glow::SAMPLES_PASSED, query.1) };
    let drawn = draw(gpu, surface, call);
    // SAFETY: as above.
    unsafe { gl.end_query(glow::SAMPLES_PASSED) };
    drawn?;
    // SAFETY: the query has ended; QUERY_RESULT waits for it.
    let samples = unsafe { gl.get_query_parameter_u32(query.1, glow::QUERY_RESULT) };
    crate::gl_debug_check!(gpu)?;
    Ok(samples as u64)
}

/// Execute `call` on `surface`; the state the draw set is restored afterwards.
pub fn draw(gpu: &Gpu, surface: Surface<'_>, call: &DrawCall<'_>) -> GlResult<()> {
    let (first, count) = call.range.unwrap_or((0, call.mesh.draw_count()));
    if first + count > call.mesh.draw_count() {
        return Err(GlError::Invalid(format!(
            "draw range {first}+{count} exceeds {} elements",
            call.mesh.draw_count()
        )));
    }
    let _guard = StateGuard::save(gpu);
    let gl = gpu.glow();
    match surface {
        Surface::Target(t) => t.bind(),
        // SAFETY: plain state calls.
        Surface::Window([x, y, w, h]) => unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.viewport(x, y, w, h);
        },
    }
    // SAFETY: plain state calls.
    unsafe {
        if call.depth_test {
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
        } else if gpu.occluded() && !call.covers_frame {
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(false);
        } else {
            gl.disable(glow::DEPTH_TEST);
        }
        if call.cull_back {
            gl.enable(glow::CULL_FACE);
            gl.cull_face(glow::BACK);
            gl.front_face(glow::CCW);
        } else {
            gl.disable(glow::CULL_FACE);
        }
        gl.disable(glow::SCISSOR_TEST);
        gl.color_mask(true, true, true, true);
        match call.blend {
            Blend::Replace => gl.disable(glow::BLEND),
            Blend::Over => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func_separate(
                    glow::SRC_ALPHA,
                    glow::ONE_MINUS_SRC_ALPHA,
                    glow::ONE,
                    glow::ONE_MINUS_SRC_ALPHA,
                );
            }
            Blend::PremultipliedOver => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func(glow::ONE, glow::ONE_MINUS_SRC_ALPHA);
            }
            Blend::Add => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func(glow::ONE, glow::ONE);
            }
            Blend::Reveal => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func(glow::ZERO, glow::ONE_MINUS_SRC_ALPHA);
            }
            Blend::Multiply => {
                gl.enable(glow::BLEND);
                gl.blend_equation(glow::FUNC_ADD);
                gl.blend_func(glow::ZERO, glow::SRC_COLOR);
            }
        }
        let points = call.primitive == Primitive::Points;
        for cap in [glow::PROGRAM_POINT_SIZE, super::arb::POINT_SPRITE] {
            if points {
                gl.enable(cap);
            } else {
                gl.disable(cap);
            }
        }
    }
    for (unit, texture) in call.textures {
        texture.bind(*unit);
    }
    let points = call.primitive == Primitive::Points;
    let coord_replace = |on: bool| {
        if let (Ok(a), crate::ProgramKind::Arb) = (gpu.arb(), call.program.kind()) {
            // SAFETY: plain state calls; unit 0 is where ARB programs read the sprite.
            unsafe {
                let prev = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
                gl.active_texture(glow::TEXTURE0);
                a.coord_replace(on);
                gl.active_texture(prev);
            }
        }
    };
    if points {
        coord_replace(true);
    }
    call.program.bind();
    if count > 0 {
        let mode = if points {
            glow::POINTS
        } else {
            glow::TRIANGLES
        };
        call.mesh.draw_elements(mode, first, count);
    }
    // SAFETY: a plain state call: depth writes back on (an occluded draw turned them
    // off; a depth clear honours the mask).
    unsafe { gl.depth_mask(true) };
    if points {
        coord_replace(false);
        // SAFETY: plain state calls.
        unsafe {
            gl.disable(glow::PROGRAM_POINT_SIZE);
            gl.disable(super::arb::POINT_SPRITE);
        }
    }
    for (unit, texture) in call.textures {
        texture.unbind(*unit);
    }
    crate::gl_debug_check!(gpu)
}
