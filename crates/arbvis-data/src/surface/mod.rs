//! Closed triangle surfaces, read from Wavefront OBJ ([`obj`], through the `tobj` crate)
//! and STL binary or ASCII ([`stl`], by hand), or built from an indexed polygon list
//! ([`TriangleMesh::from_indexed`], which a PLY face list feeds). Used as clip objects.
//!
//! # Decisions
//! - Polygons of more than three corners are split as a fan from their first corner (as
//!   `tobj` does); that is right for convex polygons (the cow's quads), not for concave ones.
//!   Polygons of fewer than three corners are errors.
//! - Every mesh is validated once, in [`TriangleMesh::from_indexed`]: at least one triangle,
//!   finite vertices (NaN / infinities name the vertex), indices in range (naming the
//!   polygon and corner). Formats wrap these errors with their own positions where they
//!   know them (the OBJ line).
//! - Defects that leave a surface usable are *not* errors: open edges (used by one
//!   triangle), non-manifold edges (used by three or more), triangles whose orientation
//!   disagrees with a neighbour's, degenerate triangles and self-intersections. The clip
//!   code decides inside and outside by the winding number, which stays defined with
//!   them (small holes shift it only near the hole). [`topology::inspect`] counts them
//!   (`arbvis inspect`-style text by [`describe`]).
//! - STL has no shared vertices: equal positions (bit for bit, after -0 = +0) are welded so
//!   that the edge counts mean something. OBJ and indexed input keep their indices.
//! - PLY: the point clouds' PLY reader (`crate::points::ply`, ASCII and binary, bounded)
//!   yields the vertices and face lists, which [`TriangleMesh::from_indexed`] checks.

pub mod obj;
pub mod stl;
pub mod topology;
pub mod tsurf;
pub mod xyz;
pub mod zmap;

use std::path::{Path, PathBuf};

pub use topology::{inspect, MeshReport};

/// Largest surface file read (a 256 MiB binary STL holds 5 million triangles).
pub const MAX_SURFACE_BYTES: u64 = 256 << 20;

/// A triangle surface: vertices and triangles indexing them (counter-clockwise seen from
/// outside for an outward orientation).
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions, all finite.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, every index `< vertices.len()`; at least one.
    pub triangles: Vec<[u32; 3]>,
    /// Values per vertex the file names (a TSurf's `PROPERTIES`, an x y z grid's other
    /// columns); none for formats without them.
    pub properties: Vec<VertexProperty>,
}

/// One named value per vertex, NaN where a vertex has none (a no-data value, a vertex
/// of an object that does not carry the property).
#[derive(Debug, Clone, PartialEq)]
pub struct VertexProperty {
    /// The name the file gives it.
    pub name: String,
    /// One per vertex.
    pub values: Vec<f64>,
}

impl VertexProperty {
    /// The smallest and largest defined value, None where every value is NaN.
    pub fn range(&self) -> Option<[f64; 2]> {
        let defined = self.values.iter().copied().filter(|v| v.is_finite());
        defined.fold(None, |r, v| match r {
            None => Some([v, v]),
            Some([lo, hi]) => Some([lo.min(v), hi.max(v)]),
        })
    }
}

/// Where in a file a problem is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Position {
    /// Text: 1-based line and column.
    Line {
        /// Line (1-based).
        line: usize,
        /// Column in characters (1-based).
        column: usize,
    },
    /// Binary: byte offset.
    Byte(u64),
    /// An item of the mesh (no file position known): "vertex 3", "polygon 7, corner 2".
    Item(&'static str, usize),
}

impl std::fmt::Display for Position {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Position::Line { line, column } => write!(f, "line {line}, column {column}"),
            Position::Byte(b) => write!(f, "at byte {b}"),
            Position::Item(what, i) => write!(f, "{what} {i}"),
        }
    }
}

/// Errors reading or building surfaces: each names the file (or the mesh's display name)
/// and the position of the problem.
#[derive(Debug, thiserror::Error)]
pub enum SurfaceError {
    /// The file could not be opened or read. (The field is not called `source`: the
    /// message already holds it, and a chain printed with `{:#}` would repeat it.)
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        error: std::io::Error,
    },
    /// The content is not what the format requires, or the mesh is unusable.
    #[error("{path}: {position}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// Where.
        position: Position,
        /// What was expected and what was found.
        message: String,
    },
    /// A PLY file the PLY reader refused (its error names the file and byte).
    #[error(transparent)]
    Ply(#[from] crate::points::PointsError),
    /// The format is not one this module reads.
    #[error("{path}: {message}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl SurfaceError {
    /// A malformed-file error at `position` in `path`.
    pub fn format(path: &Path, position: Position, message: impl Into<String>) -> Self {
        SurfaceError::Format {
            path: path.to_path_buf(),
            position,
            message: message.into(),
        }
    }
}

impl TriangleMesh {
    /// Build and validate a mesh from vertices and polygons (3 or more corners each, split
    /// as fans). `name` names the source in errors. This is the entry point for PLY faces.
    pub fn from_indexed<I, P>(
        name: &Path,
        vertices: Vec<[f64; 3]>,
        polygons: I,
    ) -> Result<TriangleMesh, SurfaceError>
    where
        I: IntoIterator<Item = P>,
        P: AsRef<[u32]>,
    {
        if let Some((v, p)) = vertices
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        {
            return Err(SurfaceError::format(
                name,
                Position::Item("vertex", v),
                format!("coordinates must be finite, found {p:?}"),
            ));
        }
        let n = vertices.len();
        let mut triangles = Vec::new();
        for (pi, poly) in polygons.into_iter().enumerate() {
            let poly = poly.as_ref();
            if poly.len() < 3 {
                return Err(SurfaceError::format(
                    name,
                    Position::Item("polygon", pi),
                    format!("a polygon needs 3 or more corners, found {}", poly.len()),
                ));
            }
            if let Some((c, &i)) = poly.iter().enumerate().find(|(_, &i)| i as usize >= n) {
                return Err(SurfaceError::format(
                    name,
                    Position::Item("polygon", pi),
                    format!("corner {c} is vertex {i}, but there are {n} vertices"),
                ));
            }
            triangles.try_reserve(poly.len() - 2).map_err(|_| {
                SurfaceError::format(name, Position::Item("polygon", pi), "out of memory")
            })?;
            for w in 1..poly.len() - 1 {
                triangles.push([poly[0], poly[w], poly[w + 1]]);
            }
        }
        if triangles.is_empty() {
            return Err(SurfaceError::format(
                name,
                Position::Item("polygon", 0),
                "the surface has no triangles",
            ));
        }
        Ok(TriangleMesh {
            vertices,
            triangles,
            properties: Vec::new(),
        })
    }

    /// The mesh with `properties` (each one value per vertex), or an error naming the
    /// first that is not.
    pub fn with_properties(
        mut self,
        name: &Path,
        properties: Vec<VertexProperty>,
    ) -> Result<TriangleMesh, SurfaceError> {
        if let Some(p) = properties
            .iter()
            .find(|p| p.values.len() != self.vertices.len())
        {
            return Err(SurfaceError::format(
                name,
                Position::Item("vertex", p.values.len().min(self.vertices.len())),
                format!(
                    "property {:?} has {} values for {} vertices",
                    p.name,
                    p.values.len(),
                    self.vertices.len()
                ),
            ));
        }
        self.properties = properties;
        Ok(self)
    }

    /// The property called `name`.
    pub fn property(&self, name: &str) -> Option<&VertexProperty> {
        self.properties.iter().find(|p| p.name == name)
    }

    /// The three corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Smallest and largest corner of the vertices used by triangles.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for t in &self.triangles {
            for &i in t {
                let p = self.vertices[i as usize];
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
        }
        (lo, hi)
    }

    /// The mesh with every vertex mapped by `f`.
    pub fn map_vertices(&self, f: impl Fn([f64; 3]) -> [f64; 3]) -> TriangleMesh {
        TriangleMesh {
            vertices: self.vertices.iter().map(|&p| f(p)).collect(),
            triangles: self.triangles.clone(),
            properties: self.properties.clone(),
        }
    }
}

/// Test helper of the line-oriented readers: `text` parsed as `name` is refused at `line`,
/// `column`, saying `says`.
#[cfg(test)]
pub(crate) fn assert_refused_at(name: &str, text: &str, line: usize, column: usize, says: &str) {
    let e = parse(Path::new(name), text.as_bytes())
        .unwrap_err()
        .to_string();
    let at = format!("line {line}, column {column}");
    assert!(e.contains(&at) && e.contains(says), "{text:?}: {e}");
}

/// Surfaces handed over in memory (`arbvis.Surface`), by name.
pub static SURFACES: crate::memory::Shelf<TriangleMesh> = crate::memory::Shelf::new("surface");

/// Parse a surface from bytes; the format is chosen from `name`'s extension (`.obj`,
/// `.stl`), `name` naming the source in errors.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    let ext = name
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "obj" => obj::parse(name, bytes),
        "stl" => stl::parse(name, bytes),
        "ply" => parse_ply(name, bytes),
        "ts" => tsurf::parse(name, bytes),
        "zmap" => zmap::parse(name, bytes),
        "xyz" | "xyt" => xyz::parse(name, bytes),
        _ => Err(SurfaceError::Unsupported {
            path: name.to_path_buf(),
            message: format!(
                "unknown surface extension {:?}: expected .obj, .stl, .ply, .ts (GOCAD TSurf), .zmap (ZMap+ grid) or .xyz, .xyt (x y z grid)",
                arbvis_core::input::shorten(&ext, 20)
            ),
        }),
    }
}

/// A PLY surface: its `vertex` element's x, y, z and its `face` element's index lists
/// (`vertex_indices` or `vertex_index`), read by [`crate::points::ply`] and checked by
/// [`TriangleMesh::from_indexed`] (indices in range, polygons split as fans).
fn parse_ply(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    let ply = crate::points::ply::parse(name, bytes)?;
    let missing = |what: &str| SurfaceError::Unsupported {
        path: name.to_path_buf(),
        message: format!("a PLY surface needs {what}"),
    };
    let vertex = ply
        .element("vertex")
        .ok_or_else(|| missing("a vertex element"))?;
    let declared = |p: crate::points::ply::Position| match p {
        crate::points::ply::Position::Line { line, column } => Position::Line { line, column },
        crate::points::ply::Position::Byte(b) => Position::Byte(b),
    };
    let axis = |a: &str| match vertex.property(a) {
        None => Err(SurfaceError::format(
            name,
            declared(vertex.declared),
            format!("the vertex element has no property {a}: a PLY surface needs x, y and z"),
        )),
        Some(p) => vertex.scalar(a).ok_or_else(|| {
            SurfaceError::format(
                name,
                declared(p.declared),
                format!("vertex property {a} is declared as a list: a coordinate must be a scalar"),
            )
        }),
    };
    let (x, y, z) = (axis("x")?, axis("y")?, axis("z")?);
    let faces = ply
        .element("face")
        .and_then(|f| f.face_indices())
        .ok_or_else(|| missing("a face element with a vertex_indices list"))?;
    // The vertices and the fans' triangles, made while the PLY's columns are held (those
    // were checked as they were read).
    let corners = faces.values().len() as u64;
    let estimate = arbvis_core::budget::times(x.len() as u64, 24)
        .saturating_add(arbvis_core::budget::times(corners, 12));
    arbvis_core::budget::check(
        format!("the surface of {} vertices and {corners} corners", x.len()),
        estimate,
    )
    .map_err(|e| {
        let face = ply.element("face").map_or(vertex.declared, |f| f.declared);
        SurfaceError::format(name, declared(face), e.to_string())
    })?;
    let vertices: Vec<[f64; 3]> = (0..x.len()).map(|i| [x[i], y[i], z[i]]).collect();
    // Indices arrive as f64 (the PLY reader's one numeric type): non-integers and
    // negatives become u32::MAX, which from_indexed reports as out of range.
    let polygons = faces.iter().map(|f| {
        f.iter()
            .map(|&i| {
                if i >= 0.0 && i.fract() == 0.0 && i < u32::MAX as f64 {
                    i as u32
                } else {
                    u32::MAX
                }
            })
            .collect::<Vec<u32>>()
    });
    TriangleMesh::from_indexed(name, vertices, polygons)
}

/// Read a surface file (regular files of at most [`MAX_SURFACE_BYTES`]).
pub fn read(path: &Path) -> Result<TriangleMesh, SurfaceError> {
    let bytes = arbvis_core::input::read_regular(path, MAX_SURFACE_BYTES).map_err(|error| {
        SurfaceError::Io {
            path: path.to_path_buf(),
            error,
        }
    })?;
    parse(path, &bytes)
}

/// `bytes` as UTF-8 text, or an error naming the line, column and byte of the first byte
/// that is not (OBJ and ASCII STL are text).
pub(crate) fn utf8<'a>(name: &Path, bytes: &'a [u8]) -> Result<&'a str, SurfaceError> {
    // A byte-order mark (spreadsheets write one) is not part of the first line.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let valid = &bytes[..at];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        let start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        // The valid prefix is UTF-8: count its characters.
        let column = std::str::from_utf8(&valid[start..]).map_or(1, |s| s.chars().count() + 1);
        SurfaceError::format(
            name,
            Position::Line { line, column },
            format!(
                "byte {at} (0x{:02x}) is not UTF-8: the file must be text",
                bytes[at]
            ),
        )
    })
}

/// `arbvis inspect` text for a surface: counts, bounds and the defects of
/// [`topology::inspect`], one item per line.
pub fn describe(mesh: &TriangleMesh) -> String {
    inspect(mesh).to_string()
}

/// `arbvis inspect` text for a surface file: what a grid's reader found (its shape and
/// undefined nodes, for ZMap+ and x y z grids), then [`describe`].
pub fn describe_file(path: &Path) -> Result<String, SurfaceError> {
    let bytes = arbvis_core::input::read_regular(path, MAX_SURFACE_BYTES).map_err(|error| {
        SurfaceError::Io {
            path: path.to_path_buf(),
            error,
        }
    })?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let (mesh, grid) = match ext.as_str() {
        "zmap" => {
            let (mesh, g) = zmap::parse_with_grid(path, &bytes)?;
            let [x0, x1, y0, y1] = g.extent;
            let grid = format!(
                "grid: {} rows x {} columns over x {x0}..{x1}, y {y0}..{y1} (ZMap+)\nundefined nodes: {} (left out)\n",
                g.shape[0], g.shape[1], g.undefined
            );
            (mesh, grid)
        }
        "xyz" | "xyt" => {
            let (mesh, g) = xyz::parse_with_grid(path, &bytes)?;
            let how = match g.lattice {
                Some([i, c]) => format!("on its grid of {i} inlines x {c} crosslines (its inline and crossline columns)"),
                None => "by Delaunay over x, y (no inline and crossline columns)".into(),
            };
            let repeated = match g.repeated {
                0 => String::new(),
                r => format!("; {r} at the x, y of an earlier node (left out)"),
            };
            let grid = format!(
                "nodes: {} defined, {} undefined (left out){repeated}; triangulated {how}\n",
                g.nodes, g.undefined
            );
            (mesh, grid)
        }
        "ts" => {
            let (mesh, facts) = tsurf::parse_with_facts(path, &bytes)?;
            let mut said = format!(
                "objects: {}; z positive {}\n",
                facts.objects,
                if facts.depth_positive {
                    "downwards (depth, turned up)"
                } else {
                    "upwards (elevation)"
                }
            );
            if !facts.coordinate_system.is_empty() {
                said += &format!(
                    "coordinate system (as the file names it; not applied): {}\n",
                    facts.coordinate_system.join("; ")
                );
            }
            for (name, size) in &facts.vectors {
                said += &format!("property {name:?}: a vector of {size} values (not drawn)\n");
            }
            (mesh, said)
        }
        _ => (parse(path, &bytes)?, String::new()),
    };
    let mut text = format!("{grid}{}", describe(&mesh));
    if !text.ends_with('\n') {
        text.push('\n');
    }
    Ok(text + &describe_properties(&mesh))
}

/// A line per vertex property: its name, how many vertices have it, and its range.
pub fn describe_properties(mesh: &TriangleMesh) -> String {
    let mut out = String::new();
    for p in &mesh.properties {
        let defined = p.values.iter().filter(|v| v.is_finite()).count();
        let range = match p.range() {
            Some([lo, hi]) => format!(", {lo} to {hi}"),
            None => String::new(),
        };
        out += &format!(
            "property {:?}: {defined} of {} vertices{range}\n",
            p.name,
            p.values.len()
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name() -> &'static Path {
        Path::new("faces.ply")
    }

    #[test]
    fn from_indexed_checks_with_positions() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.3, 0.2, 1.0],
        ];
        let faces: Vec<Vec<u32>> = vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3, 0]];
        let m = TriangleMesh::from_indexed(name(), v.clone(), &faces).unwrap();
        assert_eq!(
            m.triangles,
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [1, 3, 0]]
        );
        let e = |v: Vec<[f64; 3]>, f: &[Vec<u32>]| {
            TriangleMesh::from_indexed(name(), v, f)
                .unwrap_err()
                .to_string()
        };
        let mut nan = v.clone();
        nan[2][1] = f64::NAN;
        assert!(e(nan, &faces).contains("faces.ply: vertex 2: coordinates must be finite"));
        let mut inf = v.clone();
        inf[3][0] = f64::NEG_INFINITY;
        assert!(e(inf, &faces).contains("vertex 3"));
        let bad = vec![vec![0, 1, 2], vec![0, 4, 1]];
        assert!(e(v.clone(), &bad)
            .contains("polygon 1: corner 1 is vertex 4, but there are 4 vertices"));
        assert!(
            e(v.clone(), &[vec![0, 1]]).contains("polygon 0: a polygon needs 3 or more corners")
        );
        assert!(e(v.clone(), &[]).contains("no triangles"));
        assert!(e(vec![], &[vec![0, 0, 0]]).contains("but there are 0 vertices"));
    }

    #[test]
    fn parse_dispatches_by_extension() {
        let e = parse(Path::new("x.ply"), b"ply\n").unwrap_err().to_string();
        assert!(e.contains("x.ply"), "{e}");
        let e = parse(Path::new("x.off"), b"OFF\n").unwrap_err().to_string();
        assert!(
            e.contains("expected .obj, .stl, .ply, .ts (GOCAD TSurf), .zmap (ZMap+ grid) or .xyz"),
            "{e}"
        );
        let e = read(Path::new("/")).unwrap_err().to_string();
        assert!(e.contains("directory"), "{e}");
        let m = parse(Path::new("X.OBJ"), b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.bounds(), ([0.0; 3], [1.0, 1.0, 0.0]));
    }

    #[test]
    fn ply_surfaces_are_read_and_checked() {
        // A tetrahedron in ASCII PLY, one face a quad split as a fan (5 triangles).
        let ascii = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
                     property float z\nelement face 4\nproperty list uchar int vertex_indices\n\
                     end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n\
                     4 0 3 2 1\n3 0 1 4\n3 1 2 4\n3 2 3 4\n";
        let m = parse(Path::new("t.ply"), ascii.as_bytes()).unwrap();
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(m.triangles.len(), 5);
        assert_eq!(m.triangles[0], [0, 3, 2]);
        assert_eq!(m.triangles[1], [0, 2, 1]);
        // An index out of range names the polygon; a missing face element is said.
        let bad = ascii.replace("3 2 3 4", "3 2 3 9");
        let e = parse(Path::new("t.ply"), bad.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.ply") && e.contains('9'), "{e}");
        let cloud = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                     property float z\nend_header\n0 0 0\n";
        let e = parse(Path::new("c.ply"), cloud.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.ply") && e.contains("face element"), "{e}");
        // The PLY reader's own errors pass through with their byte.
        let e = parse(Path::new("x.ply"), b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nend_header\n\0")
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.ply") && e.contains("byte"), "{e}");
    }

    #[test]
    fn the_bunny_is_a_ply_surface() {
        let path = arbvis_core::input::data_file("points/bunny.ply");
        let m = read(&path).unwrap();
        assert_eq!((m.vertices.len(), m.triangles.len()), (35_947, 69_451));
    }
}
