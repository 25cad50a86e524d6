//! One sniffer of the formats arbvis reads, from a file's first bytes and its name:
//! `arbvis inspect` picks its reader with [`format`], the point readers theirs with
//! [`point_format`].

use std::path::Path;

/// A format told from a file's first bytes and name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// NIfTI-1, plain or gzip.
    Nifti,
    /// SEG-Y rev 0-2.
    Segy,
    /// A tetrahedral mesh (VTK legacy or XML, gmsh).
    Mesh,
    /// COPC: LAS 1.4 whose first VLR is `copc` record 1.
    Copc,
    /// LAS or LAZ.
    Las,
    /// PLY.
    Ply,
    /// Whitespace-separated text, one point per line.
    Dat,
    /// A closed triangle surface (OBJ, STL).
    Surface,
}

/// The format of the file at `path` whose first bytes are `head` (4096 of them let a
/// SEG-Y file without its extension be told), or `None` for one arbvis does not read.
/// In order: NIfTI (`.nii`, `.nii.gz`, or `n+1` at byte 344), SEG-Y by extension, a mesh
/// (`.vtk`, `.vtu`, `.msh`, or a VTK or gmsh opening), points (`.las`, `.laz`, `.ply`,
/// `.dat` or `LASF`; which one by [`point_format`]), a surface (`.obj`, `.stl`), SEG-Y by
/// its binary header's sample format code.
pub fn format(path: &Path, head: &[u8]) -> Option<Format> {
    let name = path.to_string_lossy().to_lowercase();
    let ends = |e: &str| name.ends_with(e);
    if ends(".nii") || ends(".nii.gz") || head.get(344..348) == Some(b"n+1\0") {
        return Some(Format::Nifti);
    }
    if ends(".sgy") || ends(".segy") {
        return Some(Format::Segy);
    }
    if ends(".vtk") || ends(".vtu") || ends(".msh") || looks_like_mesh(head) {
        return Some(Format::Mesh);
    }
    if ends(".las") || ends(".laz") || ends(".ply") || ends(".dat") || head.starts_with(b"LASF") {
        return Some(point_format(path, head));
    }
    if ends(".obj") || ends(".stl") {
        return Some(Format::Surface);
    }
    if looks_like_segy(head) {
        return Some(Format::Segy);
    }
    None
}

/// The format of a point file: COPC, LAS/LAZ (`LASF`) or PLY (`ply`) from the content,
/// else LAS/LAZ or PLY from the extension (`.las`, `.laz`, `.ply`), else `.dat` text.
pub fn point_format(path: &Path, head: &[u8]) -> Format {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if is_copc(head) {
        Format::Copc
    } else if head.starts_with(b"LASF") || ext == "las" || ext == "laz" {
        Format::Las
    } else if head.starts_with(b"ply") || ext == "ply" {
        Format::Ply
    } else {
        Format::Dat
    }
}

/// A VTK legacy or XML opening, or gmsh's, in the first 256 bytes.
fn looks_like_mesh(head: &[u8]) -> bool {
    let text = String::from_utf8_lossy(&head[..head.len().min(256)]);
    let start = text.trim_start();
    start.starts_with("# vtk DataFile")
        || start.starts_with("$MeshFormat")
        || (start.starts_with("<?xml") || start.starts_with("<VTKFile")) && text.contains("VTKFile")
}

/// A SEG-Y binary header at byte 3200 with a known sample format code (either order).
fn looks_like_segy(head: &[u8]) -> bool {
    let Some(code) = head.get(3224..3226) else {
        return false;
    };
    [
        u16::from_be_bytes([code[0], code[1]]),
        u16::from_le_bytes([code[0], code[1]]),
    ]
    .iter()
    .any(|&c| crate::volume::segy::SampleFormat::from_code(c).is_some())
}

/// Whether `head` (a file's first bytes) is a COPC file's: LAS 1.4 whose first VLR is
/// `copc` record 1.
pub fn is_copc(head: &[u8]) -> bool {
    use crate::points::lasfile::layout::{HEADER_14 as HEADER, VLR_HEADER};
    head.len() >= HEADER + VLR_HEADER as usize
        && head.starts_with(b"LASF")
        && head[24..26] == [1, 4]
        && &head[HEADER + 2..HEADER + 6] == b"copc"
        && head[HEADER + 6..HEADER + 18].iter().all(|&b| b == 0)
        && u16::from_le_bytes([head[HEADER + 18], head[HEADER + 19]]) == 1
}
