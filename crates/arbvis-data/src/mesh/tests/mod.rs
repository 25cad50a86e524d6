//! Tests of the mesh data layer.

mod cells;
mod fixtures;
mod formats;
mod generated;
mod hostile;
mod hostile_files;
mod issue17;
mod mutation;
mod real_files;
