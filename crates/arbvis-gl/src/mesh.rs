//! Owned vertex data: one vertex array object over one interleaved f32 buffer, drawn as
//! triangles, optionally through a u32 index buffer (a subset or an order of the
//! vertices, replaceable without touching them). Attribute `i` is generic attribute `i`
//! (ARB `vertex.attrib[i]`, GLSL `layout(location = i)`); attribute 0 provokes the vertex
//! in the compatibility profile.

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
    /// The index buffer and its length, when the mesh draws through indices.
    indices: Option<(glow::Buffer, usize)>,
    label: String,
}

/// `values` viewed as their bytes (native order, as GL reads them).
fn f32_bytes(values: &[f32]) -> &[u8] {
    // SAFETY: any f32 is 4 initialised bytes; u8 has no alignment; the length covers
    // exactly the slice.
    unsafe {
        std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), std::mem::size_of_val(values))
    }
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
            indices: None,
            label: label.to_string(),
        };
        mesh.upload(vertices)?;
        crate::gl_check_alloc!(
            gpu,
            || format!("the vertex buffer of {label}"),
            std::mem::size_of_val(vertices) as u64
        )?;
        gpu.record(
            "buffer",
            format!("vertices {label}"),
            (vertices.len() * 4) as u64,
        );
        Ok(mesh)
    }

    /// Replace the vertices (any count; the buffer is reallocated). A buffer that grows
    /// is checked for the driver's out-of-memory error, as a new one is.
    pub fn update(&mut self, gpu: &Gpu, vertices: &[f32]) -> GlResult<()> {
        let grows = vertices.len() / self.floats_per_vertex > self.vertex_count;
        self.upload(vertices)?;
        if grows {
            let label = &self.label;
            crate::gl_check_alloc!(
                gpu,
                || format!("the vertex buffer of {label}"),
                std::mem::size_of_val(vertices) as u64
            )
        } else {
            crate::gl_debug_check!(gpu)
        }
    }

    /// Overwrite the vertices from `first` on with `vertices` (within the buffer: it
    /// keeps its size and the other vertices).
    pub fn update_range(&mut self, gpu: &Gpu, first: usize, vertices: &[f32]) -> GlResult<()> {
        let f = self.floats_per_vertex;
        let count = vertices.len() / f;
        let offset = i32::try_from(first * f * 4);
        if !vertices.len().is_multiple_of(f) || first + count > self.vertex_count || offset.is_err()
        {
            return Err(GlError::Invalid(format!(
                "mesh {}: {} floats at vertex {first} do not fit its {} vertices of {f} floats",
                self.label,
                vertices.len(),
                self.vertex_count
            )));
        }
        // Inside the buffer (checked above).
        self.write(vertices, offset.ok());
        crate::gl_debug_check!(gpu)
    }

    /// Write `vertices` into the vertex buffer: at byte `offset` of the buffer as it is,
    /// or (`None`) as its whole new content.
    fn write(&self, vertices: &[f32], offset: Option<i32>) {
        // SAFETY: the caller keeps a sub-range inside the buffer; the buffer binding is
        // restored to none.
        unsafe {
            let bytes = f32_bytes(vertices);
            self.gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.vbo));
            match offset {
                Some(at) => self
                    .gl
                    .buffer_sub_data_u8_slice(glow::ARRAY_BUFFER, at, bytes),
                None => self
                    .gl
                    .buffer_data_u8_slice(glow::ARRAY_BUFFER, bytes, glow::DYNAMIC_DRAW),
            }
            self.gl.bind_buffer(glow::ARRAY_BUFFER, None);
        }
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
        self.write(vertices, None);
        self.vertex_count = vertices.len() / self.floats_per_vertex;
        Ok(())
    }

    /// Number of vertices (a multiple of 3 for triangle lists).
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Draw through `indices` from now on (each below [`Mesh::vertex_count`]); the
    /// index buffer is created on first use and replaced after.
    pub fn set_indices(&mut self, gpu: &Gpu, indices: &[u32]) -> GlResult<()> {
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= self.vertex_count) {
            return Err(GlError::Invalid(format!(
                "mesh {}: index {bad} beyond its {} vertices",
                self.label, self.vertex_count
            )));
        }
        let created = self.indices.is_none();
        // SAFETY: a u32 slice viewed as bytes; bound through this mesh's VAO, whose
        // binding is restored to none.
        unsafe {
            let ebo = match self.indices {
                Some((ebo, _)) => ebo,
                None => self.gl.create_buffer().map_err(GlError::Invalid)?,
            };
            let bytes =
                std::slice::from_raw_parts(indices.as_ptr().cast::<u8>(), indices.len() * 4);
            let prev_vao = self
                .gl
                .get_parameter_vertex_array(glow::VERTEX_ARRAY_BINDING);
            self.gl.bind_vertex_array(Some(self.vao));
            self.gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ebo));
            self.gl
                .buffer_data_u8_slice(glow::ELEMENT_ARRAY_BUFFER, bytes, glow::DYNAMIC_DRAW);
            self.gl.bind_vertex_array(prev_vao);
            self.indices = Some((ebo, indices.len()));
        }
        if created {
            gpu.record(
                "buffer",
                format!("indices {}", self.label),
                (indices.len() * 4) as u64,
            );
        }
        crate::gl_check!(gpu)
    }

    /// Draw the vertices in order again (the index buffer is deleted).
    pub fn clear_indices(&mut self) {
        if let Some((ebo, _)) = self.indices.take() {
            // SAFETY: deleted once; the VAO is not drawn through it any more.
            unsafe { self.gl.delete_buffer(ebo) };
        }
    }

    /// Elements a draw walks: the indices when there are some, else the vertices.
    pub fn draw_count(&self) -> usize {
        self.indices.map_or(self.vertex_count, |(_, n)| n)
    }

    /// Draw `count` elements from `first` as `mode` (`glow::TRIANGLES` or `glow::POINTS`;
    /// program, target and textures bound): vertices, or indices when the mesh has them.
    pub(crate) fn draw_elements(&self, mode: u32, first: usize, count: usize) {
        // SAFETY: the range lies within the elements (checked by the caller); indices
        // were checked against the vertices when set.
        unsafe {
            self.gl.bind_vertex_array(Some(self.vao));
            match self.indices {
                Some(_) => self.gl.draw_elements(
                    mode,
                    count as i32,
                    glow::UNSIGNED_INT,
                    (first * 4) as i32,
                ),
                None => self.gl.draw_arrays(mode, first as i32, count as i32),
            }
        }
    }
}

impl Drop for Mesh {
    fn drop(&mut self) {
        // SAFETY: deleted once, on the context that created them.
        unsafe {
            self.gl.delete_vertex_array(self.vao);
            self.gl.delete_buffer(self.vbo);
            if let Some((ebo, _)) = self.indices {
                self.gl.delete_buffer(ebo);
            }
        }
    }
}

/// Two triangles over clip space [-1, 1]² (the full-screen passes' quad): position
/// (x, y, z, w) then texture coordinate (u, v, 0, 1), (0, 0) at the bottom left.
pub fn quad_vertices() -> Vec<f32> {
    let corner = |x: f32, y: f32| [x, y, 0.0, 1.0, (x + 1.0) / 2.0, (y + 1.0) / 2.0, 0.0, 1.0];
    [
        (-1.0, -1.0),
        (1.0, -1.0),
        (1.0, 1.0),
        (-1.0, -1.0),
        (1.0, 1.0),
        (-1.0, 1.0),
    ]
    .iter()
    .flat_map(|&(x, y)| corner(x, y))
    .collect()
}
