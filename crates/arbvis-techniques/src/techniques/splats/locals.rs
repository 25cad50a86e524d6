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

/// The splat vertex programs (`splat`, `precise`; EDL's depth pass the same): the eye in
/// object space, w = 1 in perspective (`cameraPos`).
pub const VERTEX_EYE: usize = 4;
/// The view direction (`viewDir`).
pub const VERTEX_VIEW_DIRECTION: usize = 5;
/// (point size, factor, lighting on) (`sizing`); EDL's depth pass: the image's size.
pub const VERTEX_SIZING: usize = 6;
/// The Phong coefficients (`phong`).
pub const VERTEX_PHONG: usize = 7;
/// The row of the view transform that gives a point's depth (`zRow`).
pub const VERTEX_Z_ROW: usize = 8;
/// The precise programs: the viewport in window coordinates (`viewport`).
pub const VERTEX_VIEWPORT: usize = 9;
/// The precise programs and EDL's depth pass: the clamp of a splat's size in pixels
/// (`sizes`).
pub const VERTEX_SIZES: usize = 10;
