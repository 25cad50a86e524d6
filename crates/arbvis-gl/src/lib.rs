//! The GL layer — the only module with `unsafe`.
//!
//! Contexts (EGL device/surfaceless and OSMesa offscreen; glutin windows in
//! [`window`]), the ARB program loader, the `Program` abstraction over ARB and GLSL,
//! owned textures, meshes and render targets (each freed on Drop), a state guard, and
//! error checking that names the Rust file and line of the failed call.

// The ground floor, named as the crate root names it (`arbvis_core::budget`, ...).

mod arb;
mod draw;
mod error;
mod gpu;
mod headless;
mod mesh;
pub mod position;
mod precision;
mod program;
mod state;
mod target;
mod texture;
#[cfg(feature = "window")]
pub mod window;

pub use draw::{draw, draw_counted, Blend, DrawCall, Primitive};
pub use error::{error_name, CompileError, GlError, GlResult};
pub use gpu::{renderer_is_software, ArbLimits, Caps, Gpu, Resource};
pub use headless::{Backend, Headless, OSMESA_LIBRARIES};
pub use mesh::{quad_vertices, Mesh};
pub use precision::{EXACT_FILTER, EXACT_INTERPOLATION};
pub use program::{Program, ProgramChoice, ProgramKind, ProgramText, MAX_LOCALS, MAX_UNITS};
pub use state::{SavedState, StateGuard};
pub use target::{clear, read_window, Surface, Target, TargetFormat};
pub use texture::{Extent, Filter, TexelData, TexelFormat, Texture};
