//! STL surfaces, binary and ASCII, read by hand.
//!
//! Why not the `stl_io` crate (0.11, read before deciding): it tells ASCII from binary
//! only by a leading `"solid "`, which many binary exporters also write in their 80-byte
//! header, so such files fail; its errors carry no byte offset or line; and it accepts
//! NaN vertices in binary files. The format is small enough to read here with positions.
//!
//! # Decisions
//! - Binary: an 80-byte header, a little-endian u32 triangle count, then 50 bytes per
//!   triangle (normal, three vertices as f32, a u16 attribute). A file whose size is
//!   exactly `84 + 50 * count` is binary whatever its header says. A file holding fewer
//!   bytes than its count declares is an error naming the byte where the data stop;
//!   bytes after the last declared triangle are ignored. Normals and attributes are
//!   ignored (orientation comes from the vertex order).
//! - ASCII: `solid name` then `facet normal nx ny nz / outer loop / vertex x y z ... /
//!   endloop / endfacet` blocks and `endsolid`; several solids in one file are read one
//!   after another. A loop of more than three vertices is split as a fan. Keywords are
//!   matched case-insensitively; errors name line and column.
//! - Vertices are welded (bit-equal positions, -0 = +0), since STL stores each triangle's
//!   corners separately; non-finite coordinates are errors.

use std::path::Path;

use super::obj::weld;
use super::{Position, SurfaceError, TriangleMesh};

/// Parse an STL file's bytes (`name` names it in errors).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    let declared = bytes
        .get(80..84)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64);
    let exact_binary = declared.is_some_and(|n| 84 + 50 * n == bytes.len() as u64);
    let head = &bytes[..bytes.len().min(1024)];
    let starts_solid = {
        let trimmed = head.trim_ascii_start();
        trimmed.len() >= 5 && trimmed[..5].eq_ignore_ascii_case(b"solid")
    };
    let looks_text = !head.contains(&0);
    if !exact_binary && starts_solid && looks_text {
        return ascii(name, bytes);
    }
    binary(name, bytes)
}

fn binary(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    if bytes.len() < 84 {
        return Err(SurfaceError::format(
            name,
            Position::Byte(bytes.len() as u64),
            format!(
                "not ASCII STL (no leading `solid`) and too short for binary STL: {} bytes, a binary STL needs an 84-byte header",
                bytes.len()
            ),
        ));
    }
    let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    if count == 0 {
        return Err(SurfaceError::format(
            name,
            Position::Byte(80),
            "the binary STL header declares 0 triangles",
        ));
    }
    let need = 84 + 50 * count;
    if need > bytes.len() as u64 {
        let whole = (bytes.len() as u64 - 84) / 50;
        return Err(SurfaceError::format(
            name,
            Position::Byte(84 + 50 * whole),
            format!(
                "the header declares {count} triangles ({need} bytes) but the file holds {} bytes: it ends after triangle {whole}",
                bytes.len()
            ),
        ));
    }
    let count = count as usize; // at most len / 50
    arbvis_core::budget::check(
        format!("reading {count} triangles"),
        arbvis_core::budget::times(3 * count as u64, CORNER_BYTES),
    )
    .map_err(|e| SurfaceError::format(name, Position::Byte(80), e.to_string()))?;
    let mut corners: Vec<[f64; 3]> = Vec::new();
    corners
        .try_reserve_exact(3 * count)
        .map_err(|_| SurfaceError::format(name, Position::Byte(80), "out of memory"))?;
    for t in 0..count {
        let base = 84 + 50 * t;
        for c in 0..3 {
            let mut p = [0.0; 3];
            for (a, coordinate) in p.iter_mut().enumerate() {
                let at = base + 12 + 12 * c + 4 * a;
                let v =
                    f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
                if !v.is_finite() {
                    return Err(SurfaceError::format(
                        name,
                        Position::Byte(at as u64),
                        format!("triangle {t}, corner {c}: coordinate {v} must be finite"),
                    ));
                }
                *coordinate = v as f64;
            }
            corners.push(p);
        }
    }
    let (vertices, remap) = weld(corners);
    TriangleMesh::from_indexed(name, vertices, remap.chunks_exact(3))
}

/// Bytes a corner costs while it is read and welded: its position (24), the welding's
/// hash map (up to about 80 with the map's spare room), the welded position (24) and
/// index (4), and its share of the triangles (4).
const CORNER_BYTES: u64 = 24 + 80 + 24 + 4 + 4;

/// Weld the corners of polygons of `sizes` corners each, in order, into an indexed mesh.
fn indexed(
    name: &Path,
    corners: Vec<[f64; 3]>,
    sizes: &[u32],
) -> Result<TriangleMesh, SurfaceError> {
    let (vertices, remap) = weld(corners);
    let mut next = 0usize;
    let faces = sizes.iter().map(|&n| {
        let f = &remap[next..next + n as usize];
        next += n as usize;
        f
    });
    TriangleMesh::from_indexed(name, vertices, faces)
}

/// Whitespace-separated words with their 1-based line and column. Columns are counted
/// on from the last word's, so a long line costs its length once, not once per word.
struct Words<'a> {
    text: &'a str,
    at: usize,
    line: usize,
    line_start: usize,
    /// A byte offset on the current line and its 0-based character column.
    counted: (usize, usize),
}

struct Word<'a> {
    text: &'a str,
    line: usize,
    column: usize,
}

impl<'a> Words<'a> {
    fn next(&mut self) -> Option<Word<'a>> {
        let bytes = self.text.as_bytes();
        while self.at < bytes.len() && bytes[self.at].is_ascii_whitespace() {
            if bytes[self.at] == b'\n' {
                self.line += 1;
                self.line_start = self.at + 1;
            }
            self.at += 1;
        }
        if self.at >= bytes.len() {
            return None;
        }
        let start = self.at;
        while self.at < bytes.len() && !bytes[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
        Some(Word {
            text: &self.text[start..self.at],
            line: self.line,
            column: self.column(start),
        })
    }

    /// The 1-based character column of byte `at` on the current line (`at` never moves
    /// back within a line).
    fn column(&mut self, at: usize) -> usize {
        if self.counted.0 < self.line_start {
            self.counted = (self.line_start, 0);
        }
        let (from, chars) = self.counted;
        let chars = chars + self.text[from..at].chars().count();
        self.counted = (at, chars);
        chars + 1
    }

    /// Skip the rest of the current line (a solid's name).
    fn skip_line(&mut self) {
        let bytes = self.text.as_bytes();
        while self.at < bytes.len() && bytes[self.at] != b'\n' {
            self.at += 1;
        }
    }

    fn position(&mut self) -> Position {
        Position::Line {
            line: self.line,
            column: self.column(self.at),
        }
    }
}

/// An ASCII STL: `solid NAME`, facets (`facet normal X Y Z`, `outer loop`, 3 or more
/// `vertex X Y Z`, `endloop`, `endfacet`), `endsolid`; one solid or more.
fn ascii(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    let text = super::utf8(name, bytes)?;
    // Each corner takes at least `vertex 0 0 0` (14 bytes): the budget holds for the
    // corners the text can hold.
    arbvis_core::budget::check(
        "reading the ASCII STL's vertices",
        arbvis_core::budget::times(text.len() as u64 / 14 + 1, CORNER_BYTES + 4),
    )
    .map_err(|e| {
        SurfaceError::format(name, Position::Line { line: 1, column: 1 }, e.to_string())
    })?;
    let mut r = Ascii {
        name,
        words: Words {
            text,
            at: 0,
            line: 1,
            line_start: 0,
            counted: (0, 0),
        },
        corners: Vec::new(),
        sizes: Vec::new(),
    };
    while r.solid()? {}
    if r.sizes.is_empty() {
        return Err(SurfaceError::format(
            name,
            r.words.position(),
            "no facets in the ASCII STL",
        ));
    }
    indexed(name, r.corners, &r.sizes)
}

/// An ASCII STL being read: the facets' corners and their counts so far.
struct Ascii<'a> {
    name: &'a Path,
    words: Words<'a>,
    corners: Vec<[f64; 3]>,
    sizes: Vec<u32>,
}

impl<'a> Ascii<'a> {
    /// An error at word `w`.
    fn err(&self, w: &Word, message: String) -> SurfaceError {
        SurfaceError::format(
            self.name,
            Position::Line {
                line: w.line,
                column: w.column,
            },
            message,
        )
    }

    /// An error where the words stopped (the end of the file).
    fn at_end(&mut self, message: impl Into<String>) -> SurfaceError {
        SurfaceError::format(self.name, self.words.position(), message)
    }

    /// The next word, which must be the keyword `kw` (any case).
    fn expect(&mut self, kw: &str) -> Result<Word<'a>, SurfaceError> {
        match self.words.next() {
            Some(w) if w.text.eq_ignore_ascii_case(kw) => Ok(w),
            Some(w) => Err(self.err(
                &w,
                format!(
                    "expected `{}`, found {:?}",
                    kw,
                    arbvis_core::input::shorten(w.text, 40)
                ),
            )),
            None => Err(self.at_end(format!("the file ends where `{kw}` was expected"))),
        }
    }

    /// The next word, a finite number (`what` names it in errors).
    fn number(&mut self, what: &str) -> Result<f64, SurfaceError> {
        let Some(w) = self.words.next() else {
            return Err(self.at_end(format!("the file ends where {what} was expected")));
        };
        match w.text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(v) => Err(self.err(&w, format!("{what} {v} must be finite"))),
            Err(_) => Err(self.err(
                &w,
                format!(
                    "expected {what} (a number), found {:?}",
                    arbvis_core::input::shorten(w.text, 40)
                ),
            )),
        }
    }

    /// A solid, its facets up to `endsolid`; false at the end of the file.
    fn solid(&mut self) -> Result<bool, SurfaceError> {
        match self.words.next() {
            None => return Ok(false),
            Some(w) if w.text.eq_ignore_ascii_case("solid") => self.words.skip_line(),
            Some(w) => {
                return Err(self.err(
                    &w,
                    format!(
                        "expected `solid`, found {:?}",
                        arbvis_core::input::shorten(w.text, 40)
                    ),
                ))
            }
        }
        loop {
            let Some(w) = self.words.next() else {
                return Err(
                    self.at_end("the file ends inside a solid: expected `facet` or `endsolid`")
                );
            };
            if w.text.eq_ignore_ascii_case("endsolid") {
                self.words.skip_line();
                return Ok(true);
            }
            if !w.text.eq_ignore_ascii_case("facet") {
                return Err(self.err(
                    &w,
                    format!(
                        "expected `facet` or `endsolid`, found {:?}",
                        arbvis_core::input::shorten(w.text, 40)
                    ),
                ));
            }
            self.facet()?;
        }
    }

    /// A facet after its `facet` keyword: the normal (read, unused), the loop of 3 or
    /// more vertices, `endfacet`.
    fn facet(&mut self) -> Result<(), SurfaceError> {
        self.expect("normal")?;
        for _ in 0..3 {
            self.number("a normal component")?;
        }
        self.expect("outer")?;
        let loop_word = self.expect("loop")?;
        let first = self.corners.len();
        loop {
            let Some(w) = self.words.next() else {
                return Err(
                    self.at_end("the file ends inside a loop: expected `vertex` or `endloop`")
                );
            };
            if w.text.eq_ignore_ascii_case("endloop") {
                break;
            }
            if !w.text.eq_ignore_ascii_case("vertex") {
                return Err(self.err(
                    &w,
                    format!(
                        "expected `vertex` or `endloop`, found {:?}",
                        arbvis_core::input::shorten(w.text, 40)
                    ),
                ));
            }
            let mut p = [0.0; 3];
            for c in &mut p {
                *c = self.number("a vertex coordinate")?;
            }
            self.corners.push(p);
        }
        let size = self.corners.len() - first;
        if size < 3 {
            return Err(self.err(
                &loop_word,
                format!("a loop needs 3 or more vertices, found {size}"),
            ));
        }
        self.expect("endfacet")?;
        self.sizes.push(size as u32);
        Ok(())
    }
}

/// Binary STL bytes for `triangles` (tests and fixtures).
pub fn to_binary(header: &[u8; 80], triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut out = header.to_vec();
    out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        out.extend_from_slice(&[0u8; 12]);
        for c in t {
            for v in c {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::topology::inspect;

    fn name() -> &'static Path {
        Path::new("t.stl")
    }

    /// A tetrahedron, outward counter-clockwise, not symmetric.
    fn tetra() -> Vec<[[f32; 3]; 3]> {
        let p = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
            [0.0, 0.0, 1.5],
        ];
        [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
            .iter()
            .map(|t: &[usize; 3]| t.map(|i| p[i]))
            .collect()
    }

    fn header(text: &str) -> [u8; 80] {
        let mut h = [b' '; 80];
        h[..text.len()].copy_from_slice(text.as_bytes());
        h
    }

    #[test]
    fn binary_even_with_a_solid_header() {
        for h in ["binary", "solid exported by a CAD program"] {
            let bytes = to_binary(&header(h), &tetra());
            let m = parse(name(), &bytes).unwrap();
            assert_eq!((m.vertices.len(), m.triangles.len()), (4, 4), "{h}");
            let r = inspect(&m);
            assert_eq!((r.open_edges, r.misoriented_edges), (0, 0));
            assert!((r.signed_volume - 1.5).abs() < 1e-12, "{}", r.signed_volume);
        }
    }

    #[test]
    fn binary_hostile_input() {
        let good = to_binary(&header("x"), &tetra());
        for cut in 0..good.len() {
            let e = parse(name(), &good[..cut]).unwrap_err().to_string();
            if cut >= 84 {
                let whole = (cut - 84) / 50;
                assert!(
                    e.contains(&format!("at byte {}", 84 + 50 * whole))
                        && e.contains("declares 4 triangles"),
                    "{cut}: {e}"
                );
            }
        }
        let mut huge = good.clone();
        huge[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = parse(name(), &huge).unwrap_err().to_string();
        assert!(e.contains("4294967295 triangles"), "{e}");
        let mut zero = good.clone();
        zero[80..84].copy_from_slice(&0u32.to_le_bytes());
        assert!(parse(name(), &zero)
            .unwrap_err()
            .to_string()
            .contains("0 triangles"));
        let mut nan = good.clone();
        nan[84 + 50 + 28..84 + 50 + 32].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = parse(name(), &nan).unwrap_err().to_string();
        assert!(
            e.contains("at byte 162") && e.contains("triangle 1, corner 1"),
            "{e}"
        );
        let mut trailing = good.clone();
        trailing.extend_from_slice(b"extra");
        assert_eq!(parse(name(), &trailing).unwrap().triangles.len(), 4);
    }

    fn ascii_text() -> String {
        let mut s = String::from("solid tetra made by hand\n");
        for t in tetra() {
            s += "  facet normal 0 0 0\n    outer loop\n";
            for c in t {
                s += &format!("      vertex {} {} {}\n", c[0], c[1], c[2]);
            }
            s += "    endloop\n  endfacet\n";
        }
        s + "endsolid tetra\n"
    }

    #[test]
    fn ascii_reads_and_matches_binary() {
        let a = parse(name(), ascii_text().as_bytes()).unwrap();
        let b = parse(name(), &to_binary(&header("b"), &tetra())).unwrap();
        assert_eq!(a, b);
        // A quad loop is split in two; two solids in one file.
        let quad = "SOLID q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\nsolid r\nfacet normal 0 0 1 outer loop vertex 0 0 1 vertex 1 0 1 vertex 1 1 1 endloop endfacet endsolid r";
        let m = parse(name(), quad.as_bytes()).unwrap();
        assert_eq!((m.triangles.len(), m.vertices.len()), (3, 7));
    }

    #[test]
    fn ascii_errors_name_line_and_column() {
        let text = ascii_text();
        let cases = [
            (
                text.replacen("vertex 2 0 0", "vertex 2 nan 0", 1),
                "line 6, column 16",
            ),
            (
                text.replacen("vertex 2 0 0", "vertex 2 zero 0", 1),
                "line 6, column 16",
            ),
            (text.replacen("endloop", "endlop", 1), "line 7, column 5"),
            (text.replacen("outer loop", "outer", 1), "expected `loop`"),
            (
                text.replacen("      vertex 0 3 0\n", "", 1),
                "needs 3 or more vertices",
            ),
            ("solid x\n".to_string(), "ends inside a solid"),
            ("solid x\nendsolid x\n".to_string(), "no facets"),
        ];
        for (t, want) in cases {
            let e = parse(name(), t.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
        }
        for cut in 0..text.len() {
            let _ = parse(name(), &text.as_bytes()[..cut]);
        }
    }

    // --- issue 17: clouds and surfaces ---

    #[test]
    fn one_long_line_is_read_in_linear_time() {
        // 20,000 facets on one 1.7 MB line; the last keyword misspelt after a two-byte
        // character, so its column counts characters, not bytes.
        let facet = "facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet ";
        let body = facet.repeat(20_000);
        let text = format!("solid x\n{body}é endsolid x\n");
        let t = std::time::Instant::now();
        let e = parse(name(), text.as_bytes()).unwrap_err().to_string();
        let took = t.elapsed();
        let column = body.chars().count() + 1;
        assert!(
            e.contains(&format!(
                "line 2, column {column}: expected `facet` or `endsolid`, found \"é\""
            )),
            "{e}"
        );
        // Linear: milliseconds in release. Counting each word's column from the line start
        // (380,000 words, 0.85 MB each on average) took minutes.
        assert!(took.as_secs_f64() < 10.0, "{took:?}");
        let good = format!("solid x\n{body}endsolid x\n");
        let m = parse(name(), good.as_bytes()).unwrap();
        assert_eq!((m.vertices.len(), m.triangles.len()), (3, 20_000));
    }

    #[test]
    fn coordinates_near_the_f32_limit_in_binary() {
        // f32::MAX corners: finite, welded, inspected without overflow.
        let big = f32::MAX;
        let t = [[[-big, -big, -big], [big, -big, -big], [-big, big, -big]]];
        let m = parse(name(), &to_binary(&header("big"), &t)).unwrap();
        let r = inspect(&m);
        assert_eq!((r.degenerate_triangles, r.open_edges), (0, 3), "{r}");
        assert_eq!(r.min, [-(big as f64), -(big as f64), -(big as f64)]);
    }

    #[test]
    fn the_real_binary_stl() {
        let p = arbvis_core::input::data_file("surfaces/42400-IDGH.stl");
        let m = crate::surface::read(&p).unwrap();
        assert_eq!(m.triangles.len(), 11_036);
        let r = inspect(&m);
        assert_eq!(
            (r.open_edges, r.non_manifold_edges, r.misoriented_edges),
            (0, 0, 0),
            "{r}"
        );
        // Euler characteristic V - E + F = 5500 - 16554 + 11036 = -18: a closed surface of
        // genus 10 (the part has ten holes through it).
        assert_eq!((m.vertices.len(), r.edges), (5500, 16_554));
        assert_eq!(
            (r.degenerate_triangles, r.self_intersections),
            (3, 0),
            "{r}"
        );
        assert!((r.signed_volume - 139.0754).abs() < 1e-3, "{r}");
    }
}
