//! arbvis: GPU visualization techniques of the programmable-shader era — v3o2's 3D
//! opacity, isosurfaces by cell projection, multi-resolution clip textures and
//! point-based geological sections — each in a faithful mode (the original programs,
//! 8-bit targets) and a precise mode (corrected maths, float targets).
//!
//! This library names the workspace's crates, which are its layers from the ground up
//! (ARCHITECTURE.md; `tests/it/layers.rs` keeps the imports inside them one way):
//! `arbvis-core` (the vocabulary: [`vocab`], [`budget`], [`input`], [`camera`], [`image`],
//! [`png_io`], [`colortable`], [`progress`]) → `arbvis-gl` ([`gl`], the only `unsafe`) and
//! `arbvis-data` ([`volume`], [`mesh`], [`points`], [`surface`], [`store`]) →
//! `arbvis-techniques` ([`programs`] → [`techniques`] → [`catalog`] → [`scene`] /
//! [`render`] / [`annotate`] / [`inspect`] / [`info`] → [`study`]) → `arbvis-viewer`
//! (`viewer`) → the command line (`src/main.rs`).

#![deny(unsafe_code)]

pub use arbvis_core::{budget, camera, colortable, image, input, png_io, progress, secrets, vocab};
pub use arbvis_data::{fetch, lines, mesh, points, store, surface, volume};
pub use arbvis_gl as gl;
pub use arbvis_gl::{gl_check, gl_check_alloc, gl_debug_check};
pub use arbvis_techniques::{
    annotate, catalog, info, inspect, layered, programs, render, scene, session, study, techniques,
};
#[cfg(feature = "viewer")]
pub use arbvis_viewer as viewer;
