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

/// A file under `../shared/data/`, or `None` with "SKIPPED" (a failure when
/// `ARBVIS_NO_SKIP=1`).
pub fn shared(relative: &str) -> Option<PathBuf> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(relative);
    if path.exists() {
        return Some(path);
    }
    if std::env::var_os("ARBVIS_NO_SKIP").is_some_and(|v| v == "1") {
        panic!("ARBVIS_NO_SKIP=1 but {} is missing", path.display());
    }
    eprintln!(
        "SKIPPED: {} is missing (no ../shared/data in this clone)",
        path.display()
    );
    None
}
