//! arbvis: GPU visualization techniques of the programmable-shader era — v3o2's 3D
//! opacity, isosurfaces by cell projection, multi-resolution clip textures and
//! point-based geological sections — each in a faithful mode (the original programs,
//! 8-bit targets) and a precise mode (corrected maths, float targets).
//!
//! Layers, from the ground up (ARCHITECTURE.md; `tests/layers.rs` keeps them): the
//! vocabulary ([`vocab`], [`budget`], [`input`], [`camera`], [`image`], [`png_io`],
//! [`colortable`], [`progress`]) → data and GL ([`volume`], [`mesh`], [`points`], [`surface`], [`gl`],
//! the only `unsafe`) → [`programs`] → [`techniques`] (CPU preparation, GL renderer, CPU
//! reference) → [`catalog`] → [`scene`] / [`render`] / [`annotate`] → [`study`] → `viewer`.

#![deny(unsafe_code)]

// Test fixtures shared with tests/ (tests/common/hostile_files.rs, included by the LAS
// unit tests) name the crate as `arbvis::`, as an integration test does.
#[cfg(test)]
extern crate self as arbvis;

pub mod annotate;
pub mod budget;
pub mod camera;
pub mod catalog;
pub mod colortable;
#[allow(unsafe_code)] // the one module allowed to call GL and the platform
pub mod gl;
pub mod image;
pub mod info;
pub mod input;
pub mod inspect;
pub mod mesh;
pub mod png_io;
pub mod points;
pub mod programs;
pub mod progress;
pub mod render;
pub mod scene;
pub mod store;
pub mod study;
pub mod surface;
pub mod techniques;
#[cfg(feature = "viewer")]
pub mod viewer;
pub mod vocab;
pub mod volume;
