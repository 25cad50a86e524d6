//! Owned vertex data: one vertex array object over one interleaved f32 buffer, drawn as
//! triangles. Attribute `i` is generic attribute `i` (ARB `vertex.attrib[i]`, GLSL
//! `layout(location = i)`); attribute 0 provokes the vertex in the compatibility profile.

use std::sync::Arc;

use glow::HasContext;

use super::error::{GlError, GlResult};
use super::gpu::Gpu;

/// An owned VAO + VBO; deleted on Drop.
pub struct Mesh {
    gl: Arc<glow::Context>,
    vao: glow::VertexArray,
    vbo: glow::Buffer,
    floats_per_vertex: usize,
    vertex_count: usize,
    label: String,
}

impl Mesh {
    /// Create a mesh whose vertices have attributes of `components` floats each (in order,
    /// interleaved), filled with `vertices`.
    pub fn new(gpu: &Gpu, label: &str, components: &[usize], vertices: &[f32]) -> GlResult<Mesh> {
        let floats_per_vertex: usize = components.iter().sum();
        if components.is_empty() || components.iter().any(|&c| !(1..=4).contains(&c)) {
            return Err(GlError::Invalid(format!(
                "mesh {label}: attribute sizes {components:?} (each 1..=4)"
            )));
        }
        let gl = gpu.glow().clone();
        // SAFETY: fresh objects; the VAO binding is restored to none.
        let (vao, vbo) = unsafe {
            let vao = gl.create_vertex_array().map_err(GlError::Invalid)?;
            let vbo = gl.create_buffer().map_err(GlError::Invalid)?;
            let prev_vao = gl.get_parameter_vertex_array(glow::VERTEX_ARRAY_BINDING);
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            let stride = (floats_per_vertex * 4) as i32;
            let mut offset = 0;
            for (i, &c) in components.iter().enumerate() {
                gl.enable_vertex_attrib_array(i as u32);
                gl.vertex_attrib_pointer_f32(
                    i as u32,
                    c as i32,
                    glow::FLOAT,
                    false,
                    stride,
                    offset,
                );
                offset += (c * 4) as i32;
            }
            gl.bind_vertex_array(prev_vao);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            (vao, vbo)
        };
        let mut mesh = Mesh {
            gl,
            vao,
            vbo,
            floats_per_vertex,
            vertex_count: 0,
            label: label.to_string(),
        };
        mesh.upload(vertices)?;
        crate::gl_check!(gpu)?;
        gpu.record(
            "buffer",
            format!("vertices {label}"),
            (vertices.len() * 4) as u64,
        );
        Ok(mesh)
    }

    /// Replace the vertices (any count; the buffer is reallocated).
    pub fn update(&mut self, gpu: &Gpu, vertices: &[f32]) -> GlResult<()> {
        self.upload(vertices)?;
        crate::gl_debug_check!(gpu)
    }

    fn upload(&mut self, vertices: &[f32]) -> GlResult<()> {
        if !vertices.len().is_multiple_of(self.floats_per_vertex) {
            return Err(GlError::Invalid(format!(
                "mesh {}: {} floats is not a whole number of {}-float vertices",
                self.label,
                vertices.len(),
                self.floats_per_vertex
            )));
        }
        // SAFETY: f32 slice viewed as bytes; the buffer binding is restored to none.
        unsafe {
            let bytes =
                std::slice::from_raw_parts(vertices.as_ptr().cast::<u8>(), vertices.len() * 4);
            self.gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.vbo));
            self.gl
                .buffer_data_u8_slice(glow::ARRAY_BUFFER, bytes, glow::DYNAMIC_DRAW);
            self.gl.bind_buffer(glow::ARRAY_BUFFER, None);
        }
        self.vertex_count = vertices.len() / self.floats_per_vertex;
        Ok(())
    }

    /// Number of vertices (a multiple of 3 for triangle lists).
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Draw `count` vertices from `first` as triangles (program, target and textures bound).
    pub(crate) fn draw_triangles(&self, first: usize, count: usize) {
        // SAFETY: the range lies within the uploaded vertices (checked by the caller).
        unsafe {
            self.gl.bind_vertex_array(Some(self.vao));
            self.gl
                .draw_arrays(glow::TRIANGLES, first as i32, count as i32);
        }
    }
}

impl Drop for Mesh {
    fn drop(&mut self) {
        // SAFETY: deleted once, on the context that created them.
        unsafe {
            self.gl.delete_vertex_array(self.vao);
            self.gl.delete_buffer(self.vbo);
        }
    }
}
