//! A guard that saves the GL state the techniques touch and restores it on drop, so a
//! renderer and egui (which leaves scissor, blending and bindings set) can share a context.

use glow::HasContext;

use super::arb;
use super::gpu::Gpu;

/// Saved state; restored when dropped.
pub struct StateGuard<'a> {
    gpu: &'a Gpu,
    saved: SavedState,
}

/// The state a [`StateGuard`] saves, comparable (for tests of state hygiene).
#[derive(Debug, Clone, PartialEq)]
pub struct SavedState {
    blend: bool,
    blend_src_rgb: i32,
    blend_dst_rgb: i32,
    blend_src_alpha: i32,
    blend_dst_alpha: i32,
    depth_test: bool,
    cull_face: bool,
    scissor_test: bool,
    fragment_program: bool,
    vertex_program: bool,
    viewport: [i32; 4],
    program: Option<glow::Program>,
    framebuffer: Option<glow::Framebuffer>,
    vertex_array: Option<glow::VertexArray>,
    active_texture: i32,
}

impl<'a> StateGuard<'a> {
    /// Save the current state.
    pub fn save(gpu: &'a Gpu) -> StateGuard<'a> {
        StateGuard {
            gpu,
            saved: SavedState::read(gpu),
        }
    }
}

impl SavedState {
    /// Read the state a guard would save.
    pub fn read(gpu: &Gpu) -> SavedState {
        let gl = gpu.glow();
        let has_arb = gpu.caps().has_arb();
        // SAFETY: plain queries.
        unsafe {
            let mut viewport = [0i32; 4];
            gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
            SavedState {
                blend: gl.is_enabled(glow::BLEND),
                blend_src_rgb: gl.get_parameter_i32(glow::BLEND_SRC_RGB),
                blend_dst_rgb: gl.get_parameter_i32(glow::BLEND_DST_RGB),
                blend_src_alpha: gl.get_parameter_i32(glow::BLEND_SRC_ALPHA),
                blend_dst_alpha: gl.get_parameter_i32(glow::BLEND_DST_ALPHA),
                depth_test: gl.is_enabled(glow::DEPTH_TEST),
                cull_face: gl.is_enabled(glow::CULL_FACE),
                scissor_test: gl.is_enabled(glow::SCISSOR_TEST),
                fragment_program: has_arb && gl.is_enabled(arb::FRAGMENT_PROGRAM),
                vertex_program: has_arb && gl.is_enabled(arb::VERTEX_PROGRAM),
                viewport,
                program: gl.get_parameter_program(glow::CURRENT_PROGRAM),
                framebuffer: gl.get_parameter_framebuffer(glow::FRAMEBUFFER_BINDING),
                vertex_array: gl.get_parameter_vertex_array(glow::VERTEX_ARRAY_BINDING),
                active_texture: gl.get_parameter_i32(glow::ACTIVE_TEXTURE),
            }
        }
    }
}

fn set(gl: &glow::Context, cap: u32, on: bool) {
    // SAFETY: plain state call.
    unsafe {
        if on {
            gl.enable(cap)
        } else {
            gl.disable(cap)
        }
    }
}

impl Drop for StateGuard<'_> {
    fn drop(&mut self) {
        self.saved.restore(self.gpu);
    }
}

impl SavedState {
    fn restore(&self, gpu: &Gpu) {
        let gl = gpu.glow();
        set(gl, glow::BLEND, self.blend);
        set(gl, glow::DEPTH_TEST, self.depth_test);
        set(gl, glow::CULL_FACE, self.cull_face);
        set(gl, glow::SCISSOR_TEST, self.scissor_test);
        if gpu.caps().has_arb() {
            set(gl, arb::FRAGMENT_PROGRAM, self.fragment_program);
            set(gl, arb::VERTEX_PROGRAM, self.vertex_program);
        }
        // SAFETY: restoring values read from this context.
        unsafe {
            gl.blend_func_separate(
                self.blend_src_rgb as u32,
                self.blend_dst_rgb as u32,
                self.blend_src_alpha as u32,
                self.blend_dst_alpha as u32,
            );
            let [x, y, w, h] = self.viewport;
            gl.viewport(x, y, w, h);
            gl.use_program(self.program);
            gl.bind_framebuffer(glow::FRAMEBUFFER, self.framebuffer);
            gl.bind_vertex_array(self.vertex_array);
            gl.active_texture(self.active_texture as u32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        draw, Backend, Blend, DrawCall, Headless, Mesh, Program, ProgramKind, ProgramText, Surface,
        Target, TargetFormat,
    };

    #[test]
    fn draw_and_clear_leave_state_as_they_found_it() {
        let h = Headless::new(Backend::Egl).unwrap();
        let gpu = h.gpu();
        let gl = gpu.glow();
        // A state unlike what draw() sets: scissor on, odd blend, small viewport.
        // SAFETY: plain state calls on the current context.
        unsafe {
            gl.enable(glow::SCISSOR_TEST);
            gl.enable(glow::BLEND);
            gl.blend_func(glow::ONE, glow::ONE);
            gl.viewport(1, 2, 3, 4);
            gl.active_texture(glow::TEXTURE5);
        }
        let before = SavedState::read(gpu);
        let target = Target::new(gpu, 8, 8, TargetFormat::Rgba8).unwrap();
        // The quad demo's pair, read from the repository's program folder (the program
        // list itself lives a layer up, in arbvis-techniques).
        let vertex = ProgramText::embedded(
            "common/transform.arbvp",
            include_str!("../../../programs/common/transform.arbvp"),
        );
        let fragment = ProgramText::embedded(
            "quad/quad.arbfp",
            include_str!("../../../programs/quad/quad.arbfp"),
        );
        let program = Program::new(gpu, ProgramKind::Arb, &vertex, &fragment).unwrap();
        let mesh = Mesh::new(gpu, "quad", &[4, 4], &crate::quad_vertices()).unwrap();
        target.clear(gpu, [0.0; 4]).unwrap();
        let call = DrawCall {
            blend: Blend::Over,
            primitive: Default::default(),
            ..DrawCall::new(&program, &mesh)
        };
        draw(gpu, Surface::Target(&target), &call).unwrap();
        target.read(gpu).unwrap();
        assert_eq!(SavedState::read(gpu), before);
        crate::gl_check!(gpu).unwrap();
    }
}
