//! Wavefront OBJ surfaces through the `tobj` crate (the maintained OBJ reader of the Rust
//! ecosystem: negative indices, `v x y z w`, polygons of any size, groups), with its
//! `use_f64` feature so coordinates keep double precision.
//!
//! # Decisions
//! - Only geometry is read: `v` and `f`; materials are not loaded (`mtllib` is ignored),
//!   points (`p`) and polylines (`l`) are skipped, texture and normal indices are ignored.
//! - `tobj` gives every group (`g`, `o`) its own copy of the vertices it uses, so the
//!   groups are concatenated and equal positions welded back (the cow has 173 groups:
//!   without welding every group border would count as open edges).
//! - `tobj` errors carry no position. The line is recovered: parse errors are on the line
//!   `tobj` stopped at (the reader's position); index errors, which `tobj` notices only at
//!   the end of a group, and non-finite vertices are located by a second scan of the text
//!   that names the line and column of the first offending item.

use std::io::Cursor;
use std::path::Path;

use super::{Position, SurfaceError, TriangleMesh};

/// Parse OBJ text (`name` names it in errors).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    let text = super::utf8(name, bytes)?;
    // Checked before tobj sees the text: tobj 4.0.5 multiplies indices unchecked
    // (`vn * 3 + 2`), which overflows on a hostile index.
    let mut counts = Counts::default();
    if let Some((position, message)) = locate(text, &mut counts) {
        return Err(SurfaceError::format(name, position, message));
    }
    arbvis_core::budget::check(
        format!(
            "reading {} vertices and {} faces of {} corners",
            counts.vertices, counts.faces, counts.corners
        ),
        counts.bytes(text.len()),
    )
    .map_err(|e| {
        SurfaceError::format(
            name,
            Position::Line {
                line: counts.last_face_line.max(1),
                column: 1,
            },
            e.to_string(),
        )
    })?;
    let text = geometry_only(text);
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut cursor = Cursor::new(text.as_bytes());
    let loaded = tobj::load_obj_buf(&mut cursor, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    });
    let models = match loaded {
        Ok((models, _materials)) => models,
        Err(e) => {
            if let Some((position, message)) = locate(&text, &mut Counts::default()) {
                return Err(SurfaceError::format(name, position, message));
            }
            let at = (cursor.position() as usize).min(text.len());
            let consumed = &text[..at];
            let mut line = consumed.matches('\n').count();
            if !consumed.ends_with('\n') || line == 0 {
                line += 1;
            }
            let source_line = text.lines().nth(line - 1).unwrap_or("");
            return Err(SurfaceError::format(
                name,
                Position::Line { line, column: 1 },
                format!(
                    "{e} in {:?}",
                    arbvis_core::input::shorten(source_line.trim(), 60)
                ),
            ));
        }
    };
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut polygons: Vec<Vec<u32>> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let base = vertices.len();
        vertices.extend(m.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let offset = |i: &u32| (base + *i as usize) as u32;
        if m.face_arities.is_empty() {
            polygons.extend(
                m.indices
                    .chunks_exact(3)
                    .map(|t| t.iter().map(offset).collect()),
            );
        } else {
            let mut start = 0usize;
            for &arity in &m.face_arities {
                let end = start + arity as usize;
                let Some(corners) = m.indices.get(start..end) else {
                    break;
                };
                polygons.push(corners.iter().map(offset).collect());
                start = end;
            }
        }
    }
    if vertices.iter().flatten().any(|c| !c.is_finite()) {
        if let Some((position, message)) = locate(&text, &mut Counts::default()) {
            return Err(SurfaceError::format(name, position, message));
        }
    }
    if polygons.is_empty() {
        return Err(SurfaceError::format(
            name,
            Position::Line {
                line: text.lines().count().max(1),
                column: 1,
            },
            "no faces (`f` lines) in the file: a clip surface needs triangles",
        ));
    }
    let (vertices, remap) = weld(vertices);
    let polygons = polygons.into_iter().map(|p| {
        p.into_iter()
            .map(|i| remap[i as usize])
            .collect::<Vec<u32>>()
    });
    TriangleMesh::from_indexed(name, vertices, polygons)
}

/// Merge bit-equal positions (-0 and +0 equal); returns the vertices and, for each input
/// vertex, its new index. Non-finite positions are kept apart (and rejected later).
pub(crate) fn weld(vertices: Vec<[f64; 3]>) -> (Vec<[f64; 3]>, Vec<u32>) {
    let mut map = std::collections::HashMap::with_capacity(vertices.len());
    let mut out = Vec::with_capacity(vertices.len());
    let mut remap = Vec::with_capacity(vertices.len());
    for p in vertices {
        let key = p.map(|c| (c + 0.0).to_bits());
        let index = *map.entry(key).or_insert_with(|| {
            out.push(p);
            out.len() as u32 - 1
        });
        remap.push(index);
    }
    (out, remap)
}

/// What an OBJ file holds, counted before `tobj` reads it.
#[derive(Debug, Default)]
struct Counts {
    vertices: u64,
    faces: u64,
    corners: u64,
    last_face_line: usize,
}

impl Counts {
    fn add(&mut self, keyword: &str, words: &std::str::SplitWhitespace, line: usize) {
        match keyword {
            "v" => self.vertices += 1,
            "f" => {
                self.faces += 1;
                self.corners += words.clone().count() as u64;
                self.last_face_line = line;
            }
            _ => {}
        }
    }

    /// Bytes held at the peak of reading `len` bytes of text with these counts: the
    /// geometry-only copy of the text; `tobj`'s positions (24 bytes a vertex), its faces
    /// (about 100 bytes each, 24 a corner) and per-group copies (24 + 4 bytes a corner);
    /// our polygons (40 bytes each, 4 a corner) and corner positions (24 a corner); the
    /// welding (about 110 bytes a corner) and the triangles (12 each, fewer than the
    /// corners).
    fn bytes(&self, len: usize) -> u64 {
        let times = arbvis_core::budget::times;
        (2 * len as u64)
            .saturating_add(times(self.vertices, 24))
            .saturating_add(times(self.faces, 140))
            .saturating_add(times(self.corners, 24 + 28 + 4 + 24 + 110 + 12))
    }
}

/// The text with what this reader ignores blanked (line numbers kept): texture and
/// normal lines, and the texture/normal parts of face corners (`f 1/2/3` becomes `f 1`).
fn geometry_only(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("f") => {
                out.push('f');
                for w in words {
                    out.push(' ');
                    out.push_str(w.split('/').next().unwrap_or(""));
                }
            }
            Some("vt" | "vn" | "vp" | "l" | "p" | "mtllib" | "usemtl") => {}
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

/// The first non-finite vertex, face of fewer than 3 corners or out-of-range face index
/// in OBJ text, with its line and column (`None` when this scan finds nothing wrong).
fn locate(text: &str, counts: &mut Counts) -> Option<(Position, String)> {
    let mut vertex_count: i64 = 0;
    for (l, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        counts.add(keyword, &words, l + 1);
        let column_of = |word: &str| {
            let offset = word.as_ptr() as usize - line.as_ptr() as usize;
            line[..offset].chars().count() + 1
        };
        match keyword {
            "v" => {
                vertex_count += 1;
                for word in words.take(3) {
                    if word.parse::<f64>().is_ok_and(|c| !c.is_finite()) {
                        return Some((
                            Position::Line {
                                line: l + 1,
                                column: column_of(word),
                            },
                            format!(
                                "vertex {vertex_count} has the coordinate {:?}: must be finite",
                                arbvis_core::input::shorten(word, 30)
                            ),
                        ));
                    }
                }
            }
            "f" => {
                let corners = words.clone().count();
                if corners < 3 {
                    return Some((
                        Position::Line {
                            line: l + 1,
                            column: column_of(keyword),
                        },
                        format!(
                            "a face with {corners} corner{}: a face needs 3 or more (2 corners are a line, written `l`)",
                            if corners == 1 { "" } else { "s" }
                        ),
                    ));
                }
                for word in words {
                    let first = word.split('/').next().unwrap_or("");
                    let Ok(i) = first.parse::<i64>() else {
                        return Some((
                            Position::Line {
                                line: l + 1,
                                column: column_of(word),
                            },
                            format!(
                                "face corner {:?}: expected a vertex index",
                                arbvis_core::input::shorten(word, 30)
                            ),
                        ));
                    };
                    let resolved = if i < 0 { vertex_count + i + 1 } else { i };
                    if resolved < 1 || resolved > vertex_count {
                        return Some((
                            Position::Line {
                                line: l + 1,
                                column: column_of(word),
                            },
                            format!(
                                "face corner {:?} refers to vertex {resolved}, but only {vertex_count} vertices are defined before it (1-based)",
                                arbvis_core::input::shorten(word, 30)
                            ),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::topology::inspect;

    fn name() -> &'static Path {
        Path::new("t.obj")
    }

    use arbvis_core::input::data_file;

    #[test]
    fn quads_pentagons_and_negative_indices() {
        let text = "# a unit cube's top as a quad, one pentagon, relative indices\n\
                    v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n\
                    g one\nf 1 2 3 4\ng two\nf -5/1 -4 -3//2 -1 -2\n";
        let m = parse(name(), text.as_bytes()).unwrap();
        assert_eq!(m.vertices.len(), 5, "groups share welded vertices");
        assert_eq!(m.triangles.len(), 2 + 3);
        assert_eq!(m.triangles[0], [0, 1, 2]);
        assert_eq!(m.triangles[1], [0, 2, 3]);
        let last = m.triangles[4].map(|i| m.vertices[i as usize]);
        assert_eq!(last, [[0.0, 0.0, 0.0], [0.5, 1.5, 0.0], [0.0, 1.0, 0.0]]);
    }

    #[test]
    fn bad_obj_errors_name_line_and_column() {
        let cases: [(&str, &str); 6] = [
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "line 4, column 7"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 -9\ng b\nf 1 2 3\n",
                "line 5, column 7",
            ),
            ("v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n", "line 2, column 3"),
            ("v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n", "line 2, column 5"),
            ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "line 2"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n", "line 4"),
        ];
        for (text, want) in cases {
            let e = parse(name(), text.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(want) && e.starts_with("t.obj"), "{text:?}: {e}");
        }
        let e = parse(name(), b"v 0 0 0\n# nothing else\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no faces"), "{e}");
        let e = parse(name(), b"").unwrap_err().to_string();
        assert!(e.contains("no faces"), "{e}");
        let e = parse(name(), b"v 0 0 0\n\xff\n").unwrap_err().to_string();
        assert!(e.contains("line 2, column 1"), "{e}");
    }

    // --- issue 17: clouds and surfaces ---

    #[test]
    fn faces_of_fewer_than_three_corners_are_errors_at_their_line() {
        let e = parse(name(), b"v 0 0 0\nv 1 0 0\n  f 1 2\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.obj: line 3, column 3: a face with 2 corners: a face needs 3"),
            "{e}"
        );
        // Among good faces: not dropped silently.
        let mixed = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 1\nf 1 3 2\n";
        let e = parse(name(), mixed.as_bytes()).unwrap_err().to_string();
        assert!(
            e.starts_with("t.obj: line 5, column 1: a face with 2 corners"),
            "{e}"
        );
        let e = parse(name(), b"v 0 0 0\nf 1\n").unwrap_err().to_string();
        assert!(e.contains("line 2, column 1: a face with 1 corner:"), "{e}");
        let e = parse(name(), b"v 0 0 0\nf\n").unwrap_err().to_string();
        assert!(e.contains("line 2, column 1: a face with 0 corners"), "{e}");
    }

    #[test]
    fn text_that_is_not_utf8_is_named_once() {
        let e = parse(name(), b"v 0 0 0\n# caf\xe9\nf 1 1 1\n").unwrap_err();
        let chain = format!("{:#}", anyhow::Error::from(e));
        assert_eq!(
            chain,
            "t.obj: line 2, column 6: byte 13 (0xe9) is not UTF-8: the file must be text"
        );
    }

    #[test]
    fn coordinates_near_the_f64_limit() {
        // A closed tetrahedron spanning ±1.6e308: its volume is beyond f64, said so.
        let text = "v -1.6e308 -1.6e308 -1.6e308\nv 1.6e308 -1.6e308 -1.6e308\nv -1.6e308 1.6e308 -1.6e308\nv -1.6e308 -1.6e308 1.6e308\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
        let m = parse(name(), text.as_bytes()).unwrap();
        let r = inspect(&m);
        assert!(r.is_closed(), "{r}");
        // (3.2e308)^3 / 6 = 5.46e924.
        assert!(r.signed_volume == f64::INFINITY, "{r}");
        assert!((r.volume_log10 - ((3.2f64.log10() + 308.0) * 3.0 - 6f64.log10())).abs() < 1e-9);
        assert!(
            r.to_string()
                .contains("signed volume: 5.461333e924 (beyond f64's range)"),
            "{r}"
        );
        assert_eq!((r.degenerate_triangles, r.self_intersections), (0, 0));
        // Tiny coordinates keep their volume too (no underflow in the products).
        let tiny = text.replace("1.6e308", "1e-200");
        let r = inspect(&parse(name(), tiny.as_bytes()).unwrap());
        // (2e-200)^3 / 6 = 1.33e-600 underflows f64: 0, with its power of ten said.
        assert_eq!(r.signed_volume, 0.0);
        assert!(
            (r.volume_log10 - (8f64 / 6.0).log10() + 600.0).abs() < 1e-9,
            "{r}"
        );
        assert!(r.to_string().contains("signed volume: 1.33333"), "{r}");
        assert!(r.to_string().contains("e-600 (beyond f64's range)"), "{r}");
    }

    #[test]
    fn garbage_never_panics() {
        let seeds: [&[u8]; 6] = [
            b"f 0 0 0\n",
            b"v 0 0 0\nvt 0 0\nf 1/0 1/0 1/0\n",
            b"v 0 0 0 0\nf 1 1 1\n",
            b"f -9223372036854775808 1 2\n",
            b"v 1e308 1e308 1e308 1e-308\nf 1 1 1\n",
            b"o\ng\nusemtl\nmtllib\ns off\nf\n",
        ];
        for s in seeds {
            for cut in 0..=s.len() {
                let _ = parse(name(), &s[..cut]);
            }
        }
    }

    #[test]
    fn the_cow() {
        let path = data_file("surfaces/cow.obj");
        let m = crate::surface::read(&path).unwrap();
        // 734 triangles, 2519 quads, 8 pentagons, 2 hexagons.
        assert_eq!(m.triangles.len(), 734 + 2 * 2519 + 3 * 8 + 4 * 2);
        assert_eq!(m.vertices.len(), 2903);
        let r = inspect(&m);
        assert_eq!(r.open_edges, 0, "{r}");
        assert_eq!(r.non_manifold_edges, 0, "{r}");
        assert_eq!(r.misoriented_edges, 0, "{r}");
        assert!((r.signed_volume - 53.4868).abs() < 1e-3, "{r}");
        // What the approximate search finds (not checked against another tool); the
        // winding number stays an integer regardless (see techniques::clip's tests).
        assert_eq!(r.self_intersections, 75, "{r}");
        assert_eq!(r.degenerate_triangles, 0);
    }
}
