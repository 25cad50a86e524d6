//! `arbvis inspect FILE`: pick the reader from the file's first bytes and its extension,
//! and print what that reader sees. A file no reader takes is named for what it looks
//! like, with the list of what `inspect` reads.

use std::io::Read;
use std::path::Path;

/// Errors of `inspect`: the reader's own, or a file no reader takes.
#[derive(Debug, thiserror::Error)]
pub enum InspectError {
    /// The file could not be opened.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// What failed.
        error: std::io::Error,
    },
    /// A volume reader's error.
    #[error(transparent)]
    Volume(#[from] arbvis_data::volume::VolumeError),
    /// A mesh reader's error.
    #[error(transparent)]
    Mesh(#[from] arbvis_data::mesh::MeshError),
    /// A point-cloud reader's error.
    #[error(transparent)]
    Points(#[from] arbvis_data::points::PointsError),
    /// A surface reader's error.
    #[error(transparent)]
    Surface(#[from] arbvis_data::surface::SurfaceError),
    /// A store's error.
    #[error(transparent)]
    Store(#[from] arbvis_data::store::StoreError),
    /// A URL that could not be asked (unreachable, refused, redirected in a loop).
    #[error("{path}: {message}")]
    Remote {
        /// The URL.
        path: String,
        /// Why, with the request that failed.
        message: String,
    },
    /// Not a format arbvis reads.
    #[error("{path}: {what}; arbvis inspect reads {reads}", reads = arbvis_data::sniff::reads())]
    Unknown {
        /// The file.
        path: String,
        /// What the first bytes look like.
        what: String,
    },
}

/// What a file's first bytes look like, for a file no reader takes.
pub fn looks_like(head: &[u8]) -> String {
    let magic: &[(&[u8], &str)] = &[
        (b"\x89PNG", "a PNG image"),
        (b"\x1f\x8b", "gzip-compressed data"),
        (b"PK\x03\x04", "a ZIP archive"),
        (b"%PDF", "a PDF document"),
        (b"\x7fELF", "an executable (ELF)"),
        (b"\xff\xd8\xff", "a JPEG image"),
    ];
    if let Some((_, what)) = magic.iter().find(|(m, _)| head.starts_with(m)) {
        return format!("it looks like {what}");
    }
    if head.is_empty() {
        return "the file is empty".into();
    }
    let text = head
        .iter()
        .take(512)
        .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace());
    if text {
        let first = String::from_utf8_lossy(head)
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty())
            .unwrap_or("")
            .to_string();
        return format!(
            "it looks like text starting with {:?}",
            arbvis_core::input::shorten(&first, 40)
        );
    }
    format!(
        "binary data of no known format (starts {:02x?})",
        &head[..head.len().min(8)]
    )
}

/// `arbvis inspect`.
pub fn inspect(path: &Path) -> Result<String, InspectError> {
    inspect_with(path, arbvis_data::volume::segy::KeyBytes::default())
}

/// [`inspect`] with a SEG-Y file's inline and crossline bytes named (each one not named
/// is detected); a URL's password or signature is hidden in what it says.
pub fn inspect_with(
    path: &Path,
    segy_keys: arbvis_data::volume::segy::KeyBytes,
) -> Result<String, InspectError> {
    describe(path, segy_keys).map(|text| arbvis_core::secrets::redact(&text))
}

/// What [`inspect_with`] says, secrets and all.
fn describe(
    path: &Path,
    segy_keys: arbvis_data::volume::segy::KeyBytes,
) -> Result<String, InspectError> {
    let io = |error| InspectError::Io {
        path: path.display().to_string(),
        error,
    };
    let path = &arbvis_data::fetch::local_or_url(path);
    if arbvis_data::fetch::url_of(path).is_some() {
        return inspect_remote(path);
    }
    if path.is_dir() {
        // A zarr v3 root, or a zarr v2 one (an MDIO dataset, v0 or v1, written with it).
        if std::fs::symlink_metadata(path.join("zarr.json")).is_ok()
            || path.join(".zgroup").is_file()
            || arbvis_data::store::mdio::is_mdio_v0(path)
        {
            return Ok(arbvis_data::store::describe::describe(path)?);
        }
        return Err(InspectError::Unknown {
            path: path.display().to_string(),
            what: "a folder without zarr.json or .zgroup (not a store or an MDIO dataset)".into(),
        });
    }
    let (file, _) = arbvis_core::input::open_regular(path).map_err(io)?;
    let mut head = Vec::new();
    file.take(4096).read_to_end(&mut head).map_err(io)?;
    // The reader the registry picks, by the kind of data it yields.
    use arbvis_data::sniff::{format, reader, DataKind};
    match format(path, &head).map(|f| reader(f).kind) {
        Some(DataKind::Survey | DataKind::Volume) => {
            Ok(arbvis_data::volume::inspect_with(path, segy_keys)?)
        }
        Some(DataKind::Mesh) => Ok(arbvis_data::mesh::inspect(path)?),
        Some(DataKind::Cloud | DataKind::SeedCloud) => Ok(arbvis_data::points::inspect(path)?),
        Some(DataKind::Surface) => Ok(format!(
            "{}\n{}\n",
            path.display(),
            arbvis_data::surface::describe_file(path)?
        )),
        Some(DataKind::Lines) => Ok(format!(
            "{}\n{}",
            path.display(),
            arbvis_data::lines::describe_file(path)?
        )),
        None => Err(InspectError::Unknown {
            path: path.display().to_string(),
            what: looks_like(&head),
        }),
    }
}

/// `arbvis inspect` of a URL: a store (a zarr group or an MDIO dataset) or a COPC cloud.
fn inspect_remote(path: &Path) -> Result<String, InspectError> {
    let name = path.to_string_lossy().to_ascii_lowercase();
    // The object's name, without a pre-signed URL's query.
    let name = name.split('?').next().unwrap_or("");
    if name.ends_with(".laz") || name.ends_with(".las") {
        return Ok(arbvis_data::points::inspect(path)?);
    }
    if arbvis_data::fetch::probe_folder(path).map_err(|e| InspectError::Remote {
        path: path.display().to_string(),
        message: e.to_string(),
    })? {
        return Ok(arbvis_data::store::describe::describe(path)?);
    }
    Err(InspectError::Unknown {
        path: path.display().to_string(),
        what: "no zarr.json, .zgroup or .zarray there, and not a .copc.laz file: from a URL arbvis reads stores (zarr v3, MDIO) and COPC clouds".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn other_files_are_named_for_what_they_look_like() {
        let dir = std::env::temp_dir().join(format!("arbvis-inspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let toml = dir.join("Cargo.toml");
        std::fs::write(&toml, "[package]\nname = \"x\"\n").unwrap();
        let e = inspect(&toml).unwrap_err().to_string();
        assert!(
            e.contains("text starting with \"[package]\"")
                && e.contains("SEG-Y (.sgy")
                && e.contains("gmsh"),
            "{e}"
        );
        let png = dir.join("a.bin");
        std::fs::write(&png, b"\x89PNG\r\n\x1a\n....").unwrap();
        let e = inspect(&png).unwrap_err().to_string();
        assert!(e.contains("a PNG image"), "{e}");
        let e = inspect(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }
}
