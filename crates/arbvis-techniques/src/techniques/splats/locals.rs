//! The program locals of the splats' programs (`programs/splats/`), named as the
//! programs' comments name them.

/// The splat programs (`seed`, `precise`): (colour from the property's gradient: 1, or
/// the point's colour: 0; the property's min; its max; volume mode: 1).
pub const COLOURING: usize = 0;
/// The gradient's first colour (`colorA`).
pub const GRADIENT_FROM: usize = 1;
/// The gradient's second colour (`colorB`).
pub const GRADIENT_TO: usize = 2;
/// (kernel: 1 Gaussian, 0 smoothstep; the Gaussian's width).
pub const KERNEL: usize = 3;
/// Volume mode's transfer function: (threshold, range).
pub const TRANSFER: usize = 4;
/// (1 in weighted blended OIT's accumulation pass, else 0).
pub const OIT_ACCUMULATE: usize = 5;
/// Eye-dome lighting's shading (`edl.frag`): (strength, radius in pixels).
pub const EDL_SHADING: usize = 0;
/// `edl.frag` and `tiles.frag`: the surface's lower-left corner in window pixels.
pub const SURFACE_ORIGIN: usize = 1;
