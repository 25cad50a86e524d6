//! One `Program` over two kinds: an ARB assembly pair (`!!ARBvp1.0` + `!!ARBfp1.0`,
//! uploaded byte for byte through `glProgramStringARB`) or a GLSL pair.
//!
//! The seeds' `program.local[i]` is set through one call for both:
//! `glProgramLocalParameter4dARB` on the fragment program for ARB (as v3o2 did), element
//! `i` of `uniform vec4 program_local[N]` for GLSL. The vertex stage has the same with
//! `vertex_local`. GLSL samplers named `textureN` are bound to unit N, mirroring ARB's
//! `texture[N]`.

use std::borrow::Cow;
use std::sync::Arc;

use glow::HasContext;

use super::arb;
use super::error::{CompileError, GlError, GlResult};
use super::gpu::Gpu;
use super::position;

/// How many `program.local` slots the one API exposes per stage.
pub const MAX_LOCALS: usize = 24;
/// Texture units whose GLSL samplers (`texture0`..) are bound by name.
pub const MAX_UNITS: u32 = 16;

/// Which kind of program text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProgramKind {
    /// ARB assembly (`GL_ARB_vertex_program` + `GL_ARB_fragment_program`).
    Arb,
    /// GLSL.
    Glsl,
}

impl ProgramKind {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            ProgramKind::Arb => "arb",
            ProgramKind::Glsl => "glsl",
        }
    }
}

/// What the user asked for: a kind, or `auto` (ARB where the driver has it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProgramChoice {
    /// ARB assembly; an error where the driver lacks it.
    Arb,
    /// GLSL.
    Glsl,
    /// ARB when both ARB program extensions are present, GLSL otherwise.
    #[default]
    Auto,
}

impl ProgramChoice {
    /// The kind this choice gives on `gpu`.
    pub fn resolve(self, gpu: &Gpu) -> ProgramKind {
        match self {
            ProgramChoice::Arb => ProgramKind::Arb,
            ProgramChoice::Glsl => ProgramKind::Glsl,
            ProgramChoice::Auto if gpu.caps().has_arb() => ProgramKind::Arb,
            ProgramChoice::Auto => ProgramKind::Glsl,
        }
    }
}

/// A named program text (the name is used in every error message).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramText {
    /// Path-like name, e.g. `opacity3d/sum.arbfp`.
    pub name: Cow<'static, str>,
    /// The text, uploaded exactly as stored.
    pub text: Cow<'static, str>,
}

impl ProgramText {
    /// A program text embedded in the binary.
    pub const fn embedded(name: &'static str, text: &'static str) -> ProgramText {
        ProgramText {
            name: Cow::Borrowed(name),
            text: Cow::Borrowed(text),
        }
    }

    /// A GLSL text with `#define NAME` after its first line (the `#version`), named
    /// `name (NAME)`.
    pub fn with_define(&self, define: &str) -> ProgramText {
        ProgramText {
            name: format!("{} ({define})", self.name).into(),
            text: self
                .text
                .replacen('\n', &format!("\n#define {define}\n"), 1)
                .into(),
        }
    }
}

enum Stages {
    Arb {
        vertex: u32,
        fragment: u32,
    },
    Glsl {
        program: glow::Program,
        fragment_locals: Vec<Option<glow::UniformLocation>>,
        vertex_locals: Vec<Option<glow::UniformLocation>>,
    },
}

/// A compiled vertex + fragment program of either kind; deleted on Drop.
pub struct Program {
    gl: Arc<glow::Context>,
    arb: Option<arb::ArbFns>,
    stages: Stages,
    name: String,
}

impl Program {
    /// Compile a vertex + fragment pair of `kind`.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        vertex: &ProgramText,
        fragment: &ProgramText,
    ) -> GlResult<Program> {
        let name = format!("{} + {}", vertex.name, fragment.name);
        let stages = match kind {
            ProgramKind::Arb => {
                let vertex = compile_arb(gpu, arb::VERTEX_PROGRAM, vertex)?;
                let fragment =
                    compile_arb(gpu, arb::FRAGMENT_PROGRAM, fragment).inspect_err(|_| {
                        if let Ok(a) = gpu.arb() {
                            a.delete_program(vertex)
                        }
                    })?;
                Stages::Arb { vertex, fragment }
            }
            ProgramKind::Glsl => link_glsl(gpu, vertex, fragment)?,
        };
        let program = Program {
            gl: gpu.glow().clone(),
            arb: gpu.arb().ok().copied(),
            stages,
            name,
        };
        crate::gl_check!(gpu)?;
        gpu.record("program", format!("{} {}", kind.name(), program.name), 0);
        Ok(program)
    }

    /// ARB or GLSL.
    pub fn kind(&self) -> ProgramKind {
        match self.stages {
            Stages::Arb { .. } => ProgramKind::Arb,
            Stages::Glsl { .. } => ProgramKind::Glsl,
        }
    }

    /// Names of the two texts.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Set fragment `program.local[index]` (ARB: `glProgramLocalParameter4dARB`; GLSL:
    /// `program_local[index]`, which the program may leave unused).
    pub fn set_local(&self, gpu: &Gpu, index: usize, v: [f64; 4]) -> GlResult<()> {
        self.set(gpu, index, v, arb::FRAGMENT_PROGRAM)
    }

    /// Set vertex `program.local[index]` (GLSL: `vertex_local[index]`).
    pub fn set_vertex_local(&self, gpu: &Gpu, index: usize, v: [f64; 4]) -> GlResult<()> {
        self.set(gpu, index, v, arb::VERTEX_PROGRAM)
    }

    fn set(&self, gpu: &Gpu, index: usize, v: [f64; 4], stage: u32) -> GlResult<()> {
        if index >= MAX_LOCALS {
            return Err(GlError::Invalid(format!(
                "program.local[{index}] (0..{MAX_LOCALS})"
            )));
        }
        match &self.stages {
            Stages::Arb { vertex, fragment } => {
                let a = gpu.arb()?;
                let id = if stage == arb::VERTEX_PROGRAM {
                    *vertex
                } else {
                    *fragment
                };
                a.bind_program(stage, id);
                a.program_local_4d(stage, index as u32, v);
            }
            Stages::Glsl {
                program,
                fragment_locals,
                vertex_locals,
            } => {
                let locals = if stage == arb::VERTEX_PROGRAM {
                    vertex_locals
                } else {
                    fragment_locals
                };
                if let Some(loc) = &locals[index] {
                    // SAFETY: a live program and one of its uniform locations.
                    unsafe {
                        let prev = self.gl.get_parameter_program(glow::CURRENT_PROGRAM);
                        self.gl.use_program(Some(*program));
                        let f = v.map(|x| x as f32);
                        self.gl.uniform_4_f32(Some(loc), f[0], f[1], f[2], f[3]);
                        self.gl.use_program(prev);
                    }
                }
            }
        }
        crate::gl_debug_check!(gpu)
    }

    /// Set vertex locals 0..3 to the rows of `m` (the transform the vertex programs apply).
    pub fn set_transform(&self, gpu: &Gpu, m: glam::DMat4) -> GlResult<()> {
        let t = m.transpose();
        for (i, row) in [t.x_axis, t.y_axis, t.z_axis, t.w_axis].iter().enumerate() {
            self.set_vertex_local(gpu, i, row.to_array())?;
        }
        Ok(())
    }

    /// Make this program the one that draws (ARB: enable and bind both targets).
    pub(crate) fn bind(&self) {
        // SAFETY: plain state calls with live programs.
        unsafe {
            match &self.stages {
                Stages::Arb { vertex, fragment } => {
                    if let Some(a) = &self.arb {
                        self.gl.use_program(None);
                        self.gl.enable(arb::VERTEX_PROGRAM);
                        self.gl.enable(arb::FRAGMENT_PROGRAM);
                        a.bind_program(arb::VERTEX_PROGRAM, *vertex);
                        a.bind_program(arb::FRAGMENT_PROGRAM, *fragment);
                    }
                }
                Stages::Glsl { program, .. } => self.gl.use_program(Some(*program)),
            }
        }
    }
}

impl Drop for Program {
    fn drop(&mut self) {
        match &self.stages {
            Stages::Arb { vertex, fragment } => {
                if let Some(a) = &self.arb {
                    a.delete_program(*vertex);
                    a.delete_program(*fragment);
                }
            }
            // SAFETY: deleted once, on the context that created it.
            Stages::Glsl { program, .. } => unsafe { self.gl.delete_program(*program) },
        }
    }
}

fn compile_arb(gpu: &Gpu, target: u32, text: &ProgramText) -> GlResult<u32> {
    let a = gpu.arb()?;
    let gl = gpu.glow();
    // Errors queued by earlier calls must not be blamed on this program.
    crate::gl_check!(gpu)?;
    let id = a.gen_program();
    a.bind_program(target, id);
    a.program_string(target, text.text.as_bytes());
    // SAFETY: glGetError has no preconditions.
    let code = unsafe { gl.get_error() };
    let error_position = arb::ArbFns::error_position(gl);
    if code == glow::NO_ERROR && error_position == -1 {
        a.bind_program(target, 0);
        return Ok(id);
    }
    let message = a.get_string(arb::PROGRAM_ERROR_STRING).trim().to_string();
    a.bind_program(target, 0);
    a.delete_program(id);
    let pos = position::from_message(&message)
        .unwrap_or_else(|| position::from_byte_offset(&text.text, error_position.max(0) as usize));
    Err(compile_error(text, pos, message))
}

fn compile_error(text: &ProgramText, pos: position::Position, message: String) -> GlError {
    let pos = position::with_quoted_column(pos, &message, &text.text);
    GlError::Compile(CompileError {
        program: text.name.to_string(),
        line: pos.line,
        column: pos.column,
        message,
        source_line: position::source_line(&text.text, pos.line),
    })
}

fn link_glsl(gpu: &Gpu, vertex: &ProgramText, fragment: &ProgramText) -> GlResult<Stages> {
    let gl = gpu.glow();
    // SAFETY: fresh shader and program objects, deleted on every error path.
    unsafe {
        let compile = |stage: u32, text: &ProgramText| -> GlResult<glow::Shader> {
            let shader = gl.create_shader(stage).map_err(GlError::Invalid)?;
            gl.shader_source(shader, &text.text);
            gl.compile_shader(shader);
            if gl.get_shader_compile_status(shader) {
                return Ok(shader);
            }
            let log = gl.get_shader_info_log(shader).trim().to_string();
            gl.delete_shader(shader);
            let pos = position::from_message(&log).unwrap_or(position::Position {
                line: 1,
                column: None,
            });
            Err(compile_error(text, pos, log))
        };
        let vs = compile(glow::VERTEX_SHADER, vertex)?;
        let fs = compile(glow::FRAGMENT_SHADER, fragment).inspect_err(|_| gl.delete_shader(vs))?;
        let program = gl.create_program().map_err(GlError::Invalid)?;
        gl.attach_shader(program, vs);
        gl.attach_shader(program, fs);
        gl.link_program(program);
        gl.detach_shader(program, vs);
        gl.detach_shader(program, fs);
        gl.delete_shader(vs);
        gl.delete_shader(fs);
        if !gl.get_program_link_status(program) {
            let log = gl.get_program_info_log(program).trim().to_string();
            gl.delete_program(program);
            return Err(compile_error(
                fragment,
                position::Position {
                    line: 1,
                    column: None,
                },
                format!("link failed: {log}"),
            ));
        }
        let prev = gl.get_parameter_program(glow::CURRENT_PROGRAM);
        gl.use_program(Some(program));
        for unit in 0..MAX_UNITS {
            if let Some(loc) = gl.get_uniform_location(program, &format!("texture{unit}")) {
                gl.uniform_1_i32(Some(&loc), unit as i32);
            }
        }
        gl.use_program(prev);
        let locals = |name: &str| {
            (0..MAX_LOCALS)
                .map(|i| gl.get_uniform_location(program, &format!("{name}[{i}]")))
                .collect::<Vec<_>>()
        };
        Ok(Stages::Glsl {
            program,
            fragment_locals: locals("program_local"),
            vertex_locals: locals("vertex_local"),
        })
    }
}
