//! Errors raised by the GL layer: context creation, missing libraries,
//! GL error codes with the Rust source position that caught them, and program
//! compile errors that name the program, line and column.

use std::fmt;

/// Everything that can go wrong below the technique layer.
#[derive(Debug, thiserror::Error)]
pub enum GlError {
    /// No context could be created (EGL/OSMesa/GLX refused).
    #[error("cannot create a GL context ({backend}): {reason}")]
    Context {
        /// Which backend was asked.
        backend: &'static str,
        /// What the platform said.
        reason: String,
    },
    /// A shared library the backend loads at run time is missing.
    #[error("cannot load {library} (tried {tried}): {reason}; {hint}")]
    MissingLibrary {
        /// Human name of the library.
        library: &'static str,
        /// The file names that were tried.
        tried: String,
        /// The loader's message for the last attempt.
        reason: String,
        /// How to install it.
        hint: &'static str,
    },
    /// The driver lacks something a program or target needs.
    #[error("unsupported by this driver: {0}")]
    Unsupported(String),
    /// `glGetError` returned a code after a call made at `file:line`.
    #[error("GL error {name} (0x{code:04X}) after call at {file}:{line}")]
    Gl {
        /// The raw error code.
        code: u32,
        /// Its symbolic name.
        name: &'static str,
        /// Rust source file of the check.
        file: &'static str,
        /// Rust source line of the check.
        line: u32,
    },
    /// The GL could not allocate memory for an object (`GL_OUT_OF_MEMORY`).
    #[error("the GL ran out of memory (GL_OUT_OF_MEMORY) creating {what}, {}; try a smaller \
             size, fewer slices or points, or a coarser grid", arbvis_core::budget::format_bytes(*.bytes))]
    OutOfMemory {
        /// What was being created.
        what: String,
        /// Its size in bytes.
        bytes: u64,
    },
    /// What was asked for is over the memory budget ([`arbvis_core::budget`]).
    #[error(transparent)]
    Budget(#[from] arbvis_core::budget::OverBudget),
    /// A program failed to compile or link.
    #[error(transparent)]
    Compile(#[from] CompileError),
    /// A framebuffer is incomplete.
    #[error("framebuffer incomplete: status 0x{0:04X}")]
    Framebuffer(u32),
    /// An argument outside what the call accepts (e.g. texture data of the wrong length).
    #[error("invalid argument: {0}")]
    Invalid(String),
}

/// A program compile or link failure, positioned in the program text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CompileError {
    /// Program name, e.g. `opacity3d/sum.arbfp`.
    pub program: String,
    /// 1-based line in the program text (1 for the v3o2 strings, which have no newlines).
    pub line: u32,
    /// 1-based column when the driver gave one.
    pub column: Option<u32>,
    /// The driver's message, verbatim (trimmed).
    pub message: String,
    /// The program line the position points at.
    pub source_line: String,
}

impl fmt::Display for CompileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.column {
            Some(c) => write!(f, "{}:{}:{}: ", self.program, self.line, c)?,
            None => write!(f, "{}:{}: ", self.program, self.line)?,
        }
        writeln!(f, "{}", self.message)?;
        write!(f, "  | {}", self.source_line)?;
        if let Some(c) = self.column {
            let pad = (c as usize).saturating_sub(1).min(self.source_line.len());
            write!(f, "\n  | {}^", " ".repeat(pad))?;
        }
        Ok(())
    }
}

impl std::error::Error for CompileError {}

/// Symbolic name of a GL error code.
pub fn error_name(code: u32) -> &'static str {
    match code {
        0x0500 => "GL_INVALID_ENUM",
        0x0501 => "GL_INVALID_VALUE",
        0x0502 => "GL_INVALID_OPERATION",
        0x0503 => "GL_STACK_OVERFLOW",
        0x0504 => "GL_STACK_UNDERFLOW",
        0x0505 => "GL_OUT_OF_MEMORY",
        0x0506 => "GL_INVALID_FRAMEBUFFER_OPERATION",
        _ => "unknown GL error",
    }
}

/// Result alias of the GL layer.
pub type GlResult<T> = Result<T, GlError>;
