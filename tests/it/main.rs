//! The integration tests, one binary (`cargo test --test it`; one module per former test
//! file, e.g. `cargo test --test it hostile::`). One binary links the crate once, where
//! twenty took most of the test build's time. `tests/fuzz.rs` stays its own binary: it
//! installs a capping global allocator, a silent panic hook and a process-wide memory
//! budget, which must not reach the other tests.

mod common;

mod annotate;
mod cellproj;
mod cellproj_entries;
mod cellproj_grid;
mod cellproj_volume;
mod checks;
mod cli;
mod clip;
mod copc;
mod copc_faults;
mod copc_lod;
mod copc_pages;
mod copc_stages;
mod copc_write;
mod copclib;
mod data;
mod docs;
mod first_picture;
mod horizons;
mod hostile;
mod irregular;
mod isovalue_units;
mod layered;
mod layers;
mod lines;
mod lines_width;
mod mdio;
mod mdio_flavours;
mod mdio_positions;
mod mdio_v0;
mod opacity3d;
mod opacity3d_precise;
mod pictures;
mod programs;
mod quad;
mod remote;
mod remote_secrets;
mod section;
mod segy_keys;
mod session;
mod splats;
mod splats_edl;
mod splats_tiles;
mod store;
mod store_hostile;
mod v3o2_verbatim;
mod viewer;
mod viewer_screen;
