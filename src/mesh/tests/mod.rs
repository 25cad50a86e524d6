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

use std::path::PathBuf;

/// A file under `../shared/data/` (see [`crate::input::shared_data`]).
pub fn shared(relative: &str) -> Option<PathBuf> {
    crate::input::shared_data(relative)
}
