//! `Gpu`: one current GL context seen through glow, the ARB entry points, the
//! driver's capabilities, and the log of every resource created (for `--stats`).

use std::cell::{Cell, RefCell};
use std::ffi::{c_void, CStr};
use std::rc::Rc;
use std::sync::Arc;

use glow::HasContext;

use super::arb::{self, ArbFns};
use super::error::{error_name, GlError, GlResult};

/// Check `glGetError` and return `Err(GlError::Gl)` naming this Rust file and line.
/// Drains every queued error and reports the first.
#[macro_export]
macro_rules! gl_check {
    ($gpu:expr) => {
        $gpu.check_errors(file!(), line!())
    };
}

/// [`gl_check!`] after creating `what` of `bytes` bytes: `GL_OUT_OF_MEMORY` becomes
/// [`GlError::OutOfMemory`] naming them.
#[macro_export]
macro_rules! gl_check_alloc {
    ($gpu:expr, $what:expr, $bytes:expr) => {
        $gpu.check_allocation(file!(), line!(), $what, $bytes)
    };
}

/// Like [`gl_check!`] in debug builds; nothing in release builds (for per-draw paths).
#[macro_export]
macro_rules! gl_debug_check {
    ($gpu:expr) => {{
        #[cfg(debug_assertions)]
        let r = $gpu.check_errors(file!(), line!());
        #[cfg(not(debug_assertions))]
        let r: $crate::GlResult<()> = {
            let _ = &$gpu;
            Ok(())
        };
        r
    }};
}

/// Native limits of one ARB program target (`arbvis info`).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct ArbLimits {
    /// `GL_MAX_PROGRAM_NATIVE_INSTRUCTIONS_ARB`.
    pub native_instructions: i32,
    /// `GL_MAX_PROGRAM_NATIVE_TEMPORARIES_ARB`.
    pub native_temporaries: i32,
    /// `GL_MAX_PROGRAM_NATIVE_TEX_INDIRECTIONS_ARB` (fragment programs only; 0 for vertex).
    pub native_tex_indirections: i32,
    /// `GL_MAX_PROGRAM_LOCAL_PARAMETERS_ARB`.
    pub local_parameters: i32,
}

/// What the driver is and can do.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Caps {
    /// `GL_VENDOR`.
    pub vendor: String,
    /// `GL_RENDERER`.
    pub renderer: String,
    /// `GL_VERSION`.
    pub version: String,
    /// "compatibility", "core" or "unknown" (from `GL_CONTEXT_PROFILE_MASK`).
    pub profile: String,
    /// `GL_ARB_fragment_program` is advertised.
    pub arb_fragment_program: bool,
    /// `GL_ARB_vertex_program` is advertised.
    pub arb_vertex_program: bool,
    /// The renderer is a software rasterizer (llvmpipe, softpipe, swrast, ...).
    pub software: bool,
    /// ARB fragment program native limits (zeros when absent).
    pub fragment_limits: ArbLimits,
    /// ARB vertex program native limits (zeros when absent).
    pub vertex_limits: ArbLimits,
    /// `GL_MAX_TEXTURE_IMAGE_UNITS`.
    pub max_texture_units: i32,
    /// `GL_MAX_3D_TEXTURE_SIZE`.
    pub max_3d_texture_size: i32,
    /// `GL_MAX_TEXTURE_SIZE` (2D).
    pub max_texture_size: i32,
}

impl Caps {
    /// Both ARB program extensions are present (what `--programs auto` asks).
    pub fn has_arb(&self) -> bool {
        self.arb_fragment_program && self.arb_vertex_program
    }
}

/// Whether a `GL_RENDERER` string names a software rasterizer. (`hardware_accelerated()`
/// says true for llvmpipe, so the string is the only reliable sign.)
pub fn renderer_is_software(renderer: &str) -> bool {
    let r = renderer.to_ascii_lowercase();
    [
        "llvmpipe",
        "softpipe",
        "swrast",
        "software",
        "lavapipe",
        "swiftshader",
    ]
    .iter()
    .any(|s| r.contains(s))
}

/// One GL resource created through this `Gpu`.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Resource {
    /// "texture", "buffer", "framebuffer", "program", ...
    pub kind: &'static str,
    /// What it is for, e.g. `opacity3d volume 64x64x64 RGB8`.
    pub label: String,
    /// Bytes of storage it holds (0 for objects without storage).
    pub bytes: u64,
}

/// A current GL context with everything the wrappers need.
pub struct Gpu {
    gl: Arc<glow::Context>,
    arb: Option<ArbFns>,
    caps: Caps,
    resources: Rc<RefCell<Vec<Resource>>>,
    /// The filter and interpolation errors ([`super::precision`]), measured on first use.
    precision: Cell<Option<(f32, f32)>>,
    /// Whether draws without a depth test of their own are tested against the depth
    /// already drawn, without writing it ([`Gpu::set_occluded`]).
    occluded: Cell<bool>,
}

impl Gpu {
    /// While `occluded`, a draw that does not test depth itself is tested (`LESS`)
    /// against the depth the surface holds, without writing it, unless it covers the
    /// frame ([`crate::DrawCall::covers_frame`]): how a layered scene draws its
    /// translucent layers behind and in front of its opaque ones.
    pub fn set_occluded(&self, occluded: bool) {
        self.occluded.set(occluded);
    }

    /// Whether draws are occluded by the depth drawn ([`Gpu::set_occluded`]).
    pub fn occluded(&self) -> bool {
        self.occluded.get()
    }

    /// Wrap the context that is current on this thread; `loader` is its `get_proc_address`.
    pub fn from_loader(mut loader: impl FnMut(&CStr) -> *const c_void) -> GlResult<Gpu> {
        // SAFETY: the caller made a context current on this thread and `loader`
        // resolves that context's entry points.
        let gl = unsafe { glow::Context::from_loader_function_cstr(&mut loader) };
        let arb_fns = ArbFns::load(&mut loader);
        let caps = query_caps(&gl, arb_fns.as_ref());
        let gpu = Gpu {
            gl: Arc::new(gl),
            arb: if caps.has_arb() { arb_fns } else { None },
            caps,
            resources: Rc::default(),
            precision: Cell::new(None),
            occluded: Cell::new(false),
        };
        gl_check!(gpu)?;
        Ok(gpu)
    }

    /// glow's context (shared with egui_glow in the viewer).
    pub fn glow(&self) -> &Arc<glow::Context> {
        &self.gl
    }

    /// ARB entry points, when the driver has both ARB program extensions.
    pub(crate) fn arb(&self) -> GlResult<&ArbFns> {
        self.arb.as_ref().ok_or_else(|| {
            GlError::Unsupported(
                "GL_ARB_fragment_program / GL_ARB_vertex_program (use --programs glsl)".into(),
            )
        })
    }

    /// The driver's capabilities.
    pub fn caps(&self) -> &Caps {
        &self.caps
    }

    /// [`super::precision`]'s measurements, once made.
    pub(super) fn precision_cache(&self) -> &Cell<Option<(f32, f32)>> {
        &self.precision
    }

    /// How many resources the log holds, and dropping those after the first `n` (for a
    /// measurement whose objects are gone when it returns).
    pub(super) fn logged_resources(&self) -> usize {
        self.resources.borrow().len()
    }

    pub(super) fn forget_resources_after(&self, n: usize) {
        self.resources.borrow_mut().truncate(n);
    }

    /// Drain `glGetError`; the first error becomes `Err`, naming `file:line`.
    pub fn check_errors(&self, file: &'static str, line: u32) -> GlResult<()> {
        let mut first = None;
        for _ in 0..16 {
            // SAFETY: glGetError has no preconditions.
            let code = unsafe { self.gl.get_error() };
            if code == glow::NO_ERROR {
                break;
            }
            first.get_or_insert(code);
        }
        match first {
            None => Ok(()),
            Some(code) => Err(GlError::Gl {
                code,
                name: error_name(code),
                file,
                line,
            }),
        }
    }

    /// [`Gpu::check_errors`] after an allocation: `GL_OUT_OF_MEMORY` names what was being
    /// created and its size.
    pub fn check_allocation(
        &self,
        file: &'static str,
        line: u32,
        what: impl FnOnce() -> String,
        bytes: u64,
    ) -> GlResult<()> {
        match self.check_errors(file, line) {
            Err(GlError::Gl {
                code: glow::OUT_OF_MEMORY,
                ..
            }) => Err(GlError::OutOfMemory {
                what: what(),
                bytes,
            }),
            other => other,
        }
    }

    /// Record a created resource (kept for the life of the `Gpu`, for `--stats`).
    pub(crate) fn record(&self, kind: &'static str, label: impl Into<String>, bytes: u64) {
        self.resources.borrow_mut().push(Resource {
            kind,
            label: label.into(),
            bytes,
        });
    }

    /// Every resource created so far, in creation order.
    pub fn resources(&self) -> Vec<Resource> {
        self.resources.borrow().clone()
    }

    /// Block until the GPU has finished all submitted work (for timing).
    pub fn finish(&self) {
        // SAFETY: glFinish has no preconditions.
        unsafe { self.gl.finish() };
    }
}

fn query_caps(gl: &glow::Context, arb_fns: Option<&ArbFns>) -> Caps {
    // SAFETY: plain queries on the current context.
    unsafe {
        let exts = gl.supported_extensions();
        let profile_mask = gl.get_parameter_i32(glow::CONTEXT_PROFILE_MASK);
        let profile = if profile_mask & glow::CONTEXT_COMPATIBILITY_PROFILE_BIT as i32 != 0 {
            "compatibility"
        } else if profile_mask & glow::CONTEXT_CORE_PROFILE_BIT as i32 != 0 {
            "core"
        } else {
            "unknown"
        };
        let renderer = gl.get_parameter_string(glow::RENDERER);
        let arb_fragment_program = exts.contains("GL_ARB_fragment_program");
        let arb_vertex_program = exts.contains("GL_ARB_vertex_program");
        let limits = |target: u32, enabled: bool| match (enabled, arb_fns) {
            (true, Some(f)) => ArbLimits {
                native_instructions: f.get_programiv(target, arb::MAX_NATIVE_INSTRUCTIONS),
                native_temporaries: f.get_programiv(target, arb::MAX_NATIVE_TEMPORARIES),
                native_tex_indirections: if target == arb::FRAGMENT_PROGRAM {
                    f.get_programiv(target, arb::MAX_NATIVE_TEX_INDIRECTIONS)
                } else {
                    0
                },
                local_parameters: f.get_programiv(target, arb::MAX_LOCAL_PARAMETERS),
            },
            _ => ArbLimits::default(),
        };
        let caps = Caps {
            vendor: gl.get_parameter_string(glow::VENDOR),
            software: renderer_is_software(&renderer),
            renderer,
            version: gl.get_parameter_string(glow::VERSION),
            profile: profile.into(),
            arb_fragment_program,
            arb_vertex_program,
            fragment_limits: limits(arb::FRAGMENT_PROGRAM, arb_fragment_program),
            vertex_limits: limits(arb::VERTEX_PROGRAM, arb_vertex_program),
            max_texture_units: gl.get_parameter_i32(glow::MAX_TEXTURE_IMAGE_UNITS),
            max_3d_texture_size: gl.get_parameter_i32(glow::MAX_3D_TEXTURE_SIZE),
            max_texture_size: gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE),
        };
        // Queries of absent enums may have queued errors; they say nothing about later calls.
        while gl.get_error() != glow::NO_ERROR {}
        caps
    }
}
