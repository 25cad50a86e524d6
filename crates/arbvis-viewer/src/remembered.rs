//! The viewer's window size, remembered between runs: `window.toml` (`size = [w, h]`, in
//! points) in arbvis's settings folder, `$ARBVIS_CONFIG_DIR`, else `$XDG_CONFIG_HOME/arbvis`,
//! else `~/.config/arbvis`. A scripted run (`--script`: the tests') neither reads nor
//! writes it, so that what it shows depends on nothing a user left behind. A file that
//! cannot be used is passed over with a note on stderr; the size is written atomically.

use std::path::{Path, PathBuf};

use egui::Vec2;

/// The smallest and largest side a remembered size may have (points).
const SIDES: std::ops::RangeInclusive<f32> = 64.0..=16384.0;

/// The settings folder, if there is a home to put it in.
pub fn folder() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(dir) = var("ARBVIS_CONFIG_DIR") {
        return Some(PathBuf::from(dir));
    }
    if let Some(dir) = var("XDG_CONFIG_HOME") {
        return Some(PathBuf::from(dir).join("arbvis"));
    }
    var("HOME").map(|home| PathBuf::from(home).join(".config/arbvis"))
}

/// The window size remembered in `folder`, if any usable one is.
pub fn load(folder: &Path) -> Option<Vec2> {
    let path = folder.join("window.toml");
    let text = arbvis_core::input::read_text(&path, 4096).ok()?;
    match parse(&text) {
        Ok(size) => Some(size),
        Err(e) => {
            eprintln!(
                "arbvis: note: {}: {e}; the window takes the screen's size",
                path.display()
            );
            None
        }
    }
}

/// Why `window.toml` holds no usable size.
#[derive(Debug, thiserror::Error)]
enum Unusable {
    /// Not TOML.
    #[error("{}", .0.message())]
    Toml(#[from] toml::de::Error),
    /// No `size` of two values.
    #[error("expected size = [width, height]")]
    NoSize,
    /// A side that is not a number in [`SIDES`].
    #[error("each side a number of points in {SIDES:?}")]
    Side,
}

fn parse(text: &str) -> Result<Vec2, Unusable> {
    let table: toml::Table = text.parse()?;
    let size = table
        .get("size")
        .and_then(|v| v.as_array())
        .filter(|a| a.len() == 2)
        .ok_or(Unusable::NoSize)?;
    let side = |v: &toml::Value| {
        v.as_float()
            .or_else(|| v.as_integer().map(|i| i as f64))
            .map(|f| f as f32)
            .filter(|f| SIDES.contains(f))
            .ok_or(Unusable::Side)
    };
    Ok(Vec2::new(side(&size[0])?, side(&size[1])?))
}

/// Remember `size` (points) in `folder`, made if missing.
pub fn save(folder: &Path, size: Vec2) -> std::io::Result<()> {
    std::fs::create_dir_all(folder)?;
    let text = format!(
        "# The arbvis viewer's last window size (points); delete to size it to the screen.\nsize = [{}, {}]\n",
        size.x.round(),
        size.y.round()
    );
    arbvis_core::png_io::write_atomic(&folder.join("window.toml"), text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_size_round_trips_and_bad_files_are_passed_over() {
        let dir = std::env::temp_dir().join(format!("arbvis-remembered-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(load(&dir), None, "nothing remembered yet");
        save(&dir, Vec2::new(1211.4, 903.6)).unwrap();
        assert_eq!(load(&dir), Some(Vec2::new(1211.0, 904.0)));
        for bad in [
            "size = [1, 900]",
            "size = [1200]",
            "size = \"big\"",
            "size = [1e9, 900]",
            "no toml at all [",
        ] {
            std::fs::write(dir.join("window.toml"), bad).unwrap();
            assert_eq!(load(&dir), None, "{bad}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
