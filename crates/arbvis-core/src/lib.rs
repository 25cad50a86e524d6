//! arbvis's ground floor: the vocabulary every layer above shares — [`vocab`] (a scene
//! value that cannot be used, with its dotted key; fidelity; target formats), the memory
//! [`budget`], bounded [`input`], the [`camera`], [`image`]s and their comparisons,
//! [`png_io`] (atomic writes, locks), [`colortable`]s and [`progress`] bars. No GL, no data
//! formats.

#![deny(unsafe_code)]

pub mod budget;
pub mod camera;
pub mod colortable;
pub mod image;
pub mod input;
pub mod png_io;
pub mod progress;
pub mod secrets;
pub mod vocab;
