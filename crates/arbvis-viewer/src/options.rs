//! What `arbvis view` is asked to show (its own file: the session reads it, and the
//! module that starts the session must not be read back).

use std::path::PathBuf;

use super::script::Script;
use arbvis_techniques::scene::Scene;

/// What `arbvis view` was asked to show.
pub struct ViewerOptions {
    /// The scene.
    pub scene: Scene,
    /// Where it came from (recorded in screenshots).
    pub origin: String,
    /// Folder for screenshots and saved scenes.
    pub screenshot_dir: PathBuf,
    /// UI actions to run, then exit.
    pub script: Option<Script>,
}
