//! The readers arbvis has, in one registry ([`READERS`]): each says the format it reads,
//! the files it claims (by name or an unmistakable opening), the kind of data it yields
//! (defaults follow the kind, not the format) and whether it reads from a URL. `arbvis
//! inspect` picks its reader with [`format`] and lists them all from here ([`reads`]); the
//! point readers pick theirs with [`point_format`]; scenes ask a source for its reader.

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
    /// A folder: a bricked multi-resolution store (zarr v3) or an MDIO dataset.
    Store,
    /// Lines and wells as CSV: polylines, a deviation survey, a log.
    Lines,
}

/// The kind of data a reader yields: what a scene's defaults follow.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataKind {
    /// A seismic survey: traces on an inline/crossline grid, samples in time or depth
    /// (three-quarter view from above, time running down).
    Survey,
    /// A volume on a regular grid with no survey geometry (medical, simulation).
    Volume,
    /// A tetrahedral mesh with values at its points.
    Mesh,
    /// A measured point cloud (lidar, photogrammetry): precise, lit, coloured by height.
    Cloud,
    /// The historical system's own point format: its scenes keep the seed's look.
    SeedCloud,
    /// A triangle surface.
    Surface,
    /// Polylines and wells (a `lines` layer).
    Lines,
}

/// One reader as the registry knows it.
#[derive(Debug, Clone, Copy)]
pub struct Reader {
    /// The format it reads.
    pub format: Format,
    /// What it reads, as `inspect` lists it, e.g. `SEG-Y (.sgy, .segy)`.
    pub reads: &'static str,
    /// The kind of data it yields.
    pub kind: DataKind,
    /// Whether it reads from an `s3://` or `http(s)://` URL.
    pub url: bool,
    /// Whether a file of this name (lower case) and opening is this reader's.
    claims: fn(&str, &[u8]) -> bool,
    /// A weaker test of the opening alone, tried after every reader's claim failed.
    guesses: fn(&[u8]) -> bool,
}

fn never(_: &[u8]) -> bool {
    false
}

/// Every reader, in the order their claims are tried (the first claim wins; then the
/// guesses in the same order): NIfTI (`.nii`, `.nii.gz`, or `n+1` at byte 344), SEG-Y by
/// extension, a mesh (`.vtk`, `.vtu`, `.msh`, or a VTK or gmsh opening), the point formats
/// (`.las`, `.laz`, `.ply`, `.dat` or `LASF`; which one by [`point_format`]), a surface
/// (`.obj`, `.stl`), stores (folders, found by `inspect` and scenes, never sniffed); SEG-Y
/// last by its binary header's sample format code.
pub const READERS: &[Reader] = &[
    Reader {
        format: Format::Nifti,
        reads: "NIfTI-1 (.nii, .nii.gz)",
        kind: DataKind::Volume,
        url: false,
        claims: |name, head| {
            name.ends_with(".nii")
                || name.ends_with(".nii.gz")
                || head.get(344..348) == Some(b"n+1\0")
        },
        guesses: never,
    },
    Reader {
        format: Format::Segy,
        reads: "SEG-Y (.sgy, .segy)",
        kind: DataKind::Survey,
        url: false,
        claims: |name, _| name.ends_with(".sgy") || name.ends_with(".segy"),
        guesses: looks_like_segy,
    },
    Reader {
        format: Format::Mesh,
        reads: "VTK legacy (.vtk), VTK XML (.vtu), gmsh (.msh)",
        kind: DataKind::Mesh,
        url: false,
        claims: |name, head| {
            [".vtk", ".vtu", ".msh"].iter().any(|e| name.ends_with(e)) || looks_like_mesh(head)
        },
        guesses: never,
    },
    Reader {
        format: Format::Copc,
        reads: "COPC (.copc.laz, described from its octree)",
        kind: DataKind::Cloud,
        url: true,
        claims: |name, head| {
            is_point_file(name, head) && point_format(Path::new(name), head) == Format::Copc
        },
        guesses: never,
    },
    Reader {
        format: Format::Las,
        reads: "LAS/LAZ (.las, .laz)",
        kind: DataKind::Cloud,
        url: false,
        claims: |name, head| {
            is_point_file(name, head) && point_format(Path::new(name), head) == Format::Las
        },
        guesses: never,
    },
    Reader {
        format: Format::Ply,
        reads: "PLY (.ply)",
        kind: DataKind::Cloud,
        url: false,
        claims: |name, head| {
            is_point_file(name, head) && point_format(Path::new(name), head) == Format::Ply
        },
        guesses: never,
    },
    Reader {
        format: Format::Dat,
        reads: "ReconMS text (.dat)",
        kind: DataKind::SeedCloud,
        url: false,
        claims: |name, head| {
            is_point_file(name, head) && point_format(Path::new(name), head) == Format::Dat
        },
        guesses: never,
    },
    Reader {
        format: Format::Surface,
        reads: "OBJ (.obj), STL (.stl), GOCAD TSurf (.ts), ZMap+ grids (.zmap), x y z grids (.xyz, .xyt)",
        kind: DataKind::Surface,
        url: false,
        claims: |name, head| {
            name.ends_with(".obj")
                || name.ends_with(".stl")
                || (name.ends_with(".ts") && head.trim_ascii_start().starts_with(b"GOCAD TSurf"))
                || name.ends_with(".zmap")
                || name.ends_with(".xyz")
                || name.ends_with(".xyt")
        },
        guesses: never,
    },
    Reader {
        format: Format::Lines,
        reads: "lines and wells as CSV (.csv: x, y, z polylines, MD/INC/AZI deviation surveys, MD and value logs)",
        kind: DataKind::Lines,
        url: false,
        claims: |name, _| name.ends_with(".csv"),
        guesses: never,
    },
    Reader {
        format: Format::Store,
        reads: "survey stores and MDIO datasets (a folder, from `arbvis convert` or mdio-python)",
        kind: DataKind::Survey,
        url: true,
        claims: |_, _| false,
        guesses: never,
    },
];

/// The reader of `format`.
pub fn reader(format: Format) -> &'static Reader {
    READERS
        .iter()
        .find(|r| r.format == format)
        .expect("every format has its reader in READERS")
}

/// The format of the file at `path` whose first bytes are `head` (4096 of them let a
/// SEG-Y file without its extension be told), or `None` for one arbvis does not read:
/// the first reader of [`READERS`] that claims it, else the first whose guess takes it.
pub fn format(path: &Path, head: &[u8]) -> Option<Format> {
    let name = path.to_string_lossy().to_lowercase();
    READERS
        .iter()
        .find(|r| (r.claims)(&name, head))
        .or_else(|| READERS.iter().find(|r| (r.guesses)(head)))
        .map(|r| r.format)
}

/// Every reader by the kind of data it yields, as `inspect` says what it reads:
/// `surveys: SEG-Y (.sgy, .segy), ...; volumes: ...`.
pub fn reads() -> String {
    let kinds = [
        (DataKind::Survey, "surveys"),
        (DataKind::Volume, "volumes"),
        (DataKind::Mesh, "tetrahedral meshes"),
        (DataKind::Cloud, "point clouds"),
        (DataKind::SeedCloud, "the seed's point clouds"),
        (DataKind::Surface, "surfaces"),
        (DataKind::Lines, "lines"),
    ];
    let groups: Vec<String> = kinds
        .iter()
        .filter_map(|(kind, name)| {
            let readers: Vec<&str> = READERS
                .iter()
                .filter(|r| r.kind == *kind)
                .map(|r| r.reads)
                .collect();
            (!readers.is_empty()).then(|| format!("{name}: {}", readers.join(", ")))
        })
        .collect();
    groups.join("; ")
}

// Here rather than in `volume` (which the SEG-Y sniffer reads): the sources' readers.
impl crate::volume::VolumeSource {
    /// The reader of the source's file or folder ([`READERS`]); `None` for a raw file, the
    /// generated cube or a volume in memory, whose scene says what they are.
    pub fn reader(&self) -> Option<&'static Reader> {
        use crate::volume::VolumeSource as V;
        match self {
            V::Segy(_) => Some(reader(Format::Segy)),
            V::Nifti(_) => Some(reader(Format::Nifti)),
            V::Store(_) => Some(reader(Format::Store)),
            V::Raw(_) | V::Synthetic(_) | V::Memory(_) => None,
        }
    }

    /// The kind of data the source yields: its reader's; a survey handed over in memory
    /// (indexed inline, crossline, sample as segyio and mdio give it); else a volume.
    pub fn data_kind(&self) -> DataKind {
        match self {
            crate::volume::VolumeSource::Memory(_) => DataKind::Survey,
            _ => self.reader().map_or(DataKind::Volume, |r| r.kind),
        }
    }
}

/// A name or opening of the point readers: `.las`, `.laz`, `.ply`, `.dat` or `LASF`.
fn is_point_file(name: &str, head: &[u8]) -> bool {
    [".las", ".laz", ".ply", ".dat"]
        .iter()
        .any(|e| name.ends_with(e))
        || head.starts_with(b"LASF")
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_format_has_one_reader_and_files_find_theirs() {
        let formats = [
            Format::Nifti,
            Format::Segy,
            Format::Mesh,
            Format::Copc,
            Format::Las,
            Format::Ply,
            Format::Dat,
            Format::Surface,
            Format::Store,
            Format::Lines,
        ];
        for f in formats {
            assert_eq!(READERS.iter().filter(|r| r.format == f).count(), 1, "{f:?}");
        }
        // A SEG-Y binary header's sample format code (5: IEEE float) at byte 3224.
        let mut segy = vec![b' '; 3600];
        segy[3224..3226].copy_from_slice(&5u16.to_be_bytes());
        let cases: [(&str, &[u8], Option<Format>); 15] = [
            ("a.NII.GZ", b"", Some(Format::Nifti)),
            ("a.sgy", b"", Some(Format::Segy)),
            ("well.CSV", b"MD,INC,AZI", Some(Format::Lines)),
            ("a.vtu", b"", Some(Format::Mesh)),
            ("mesh", b"  # vtk DataFile Version 2.0", Some(Format::Mesh)),
            ("a.laz", b"LASF", Some(Format::Las)),
            // The opening wins within the point formats, the name elsewhere.
            ("a.ply", b"LASF", Some(Format::Las)),
            ("a.dat", b"ply\n", Some(Format::Ply)),
            ("a.dat", b"1 2 3\n", Some(Format::Dat)),
            ("a.STL", b"solid", Some(Format::Surface)),
            ("h.ts", b"\nGOCAD TSurf 1", Some(Format::Surface)),
            ("app.ts", b"const x = 1;", None),
            ("a.vtk", &segy, Some(Format::Mesh)),
            ("traces.bin", &segy, Some(Format::Segy)),
            ("notes.txt", b"hello", None),
        ];
        for (name, head, want) in cases {
            assert_eq!(format(Path::new(name), head), want, "{name}");
        }
        // inspect's list names every reader, under its kind.
        let list = reads();
        for r in READERS {
            assert!(list.contains(r.reads), "{list}");
        }
        assert!(list.starts_with("surveys: SEG-Y (.sgy, .segy)"), "{list}");
    }
}
