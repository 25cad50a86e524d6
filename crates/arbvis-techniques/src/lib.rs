//! arbvis's techniques — v3o2's 3D opacity, isosurfaces and volumes by cell projection,
//! multi-resolution clip textures and point-based geological sections — each with its CPU
//! preparation, GL renderer and f64 CPU reference ([`techniques`]); the program texts
//! ([`programs`]); the one list of them ([`catalog`]); what can go wrong ([`error`]);
//! scenes ([`scene`]), the one interactive session below every front end ([`session`]),
//! offscreen rendering ([`render`], [`annotate`]), `inspect` and
//! `info`, and the studies ([`study`]).

#![deny(unsafe_code)]

pub mod annotate;
pub mod catalog;
pub mod error;
pub mod info;
pub mod inspect;
pub mod layered;
pub mod programs;
pub mod render;
pub mod scene;
pub mod session;
pub mod study;
pub mod summary;
pub mod techniques;
