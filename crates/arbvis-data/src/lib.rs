//! arbvis's data layer, no GL: [`volume`]s (SEG-Y, NIfTI, raw, synthetic, seismic
//! attributes), tetrahedral [`mesh`]es (VTK legacy and XML, gmsh), [`points`] (seed `.dat`,
//! LAS/LAZ, PLY, COPC read and written), triangle [`surface`]s (OBJ, STL, PLY) and
//! [`store`]s (surveys larger than memory: MDIO on zarr, written and read).

#![deny(unsafe_code)]

// Test fixtures shared with tests/ (tests/it/common/hostile_files.rs, included by the LAS
// unit tests) name the library as `arbvis::`, as an integration test does.
#[cfg(test)]
extern crate self as arbvis;

// The ground floor, named as the crate root names it (`arbvis_core::budget`, ...).

pub mod fetch;
pub mod le;
pub mod lines;
pub mod memory;
pub mod mesh;
pub mod points;
pub mod sniff;
pub mod store;
pub mod surface;
pub mod volume;
