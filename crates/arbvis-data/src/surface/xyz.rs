//! x y z grids (`.xyz`, `.xyt`): a horizon or a fault as interpretation tools export one
//! in columns, a node per line: OpendTect's ASCII horizon export (X/Y, optionally with
//! inline and crossline, a header of column names or none), DUG Insight's `.xyz`/`.xyt`
//! (`#` comment lines), Petrel's points.
//!
//! # Decisions
//! - Numbers are separated by whitespace, commas or semicolons; lines starting with `#` or
//!   `!` are comments. Every data line has as many numbers as the first.
//! - Columns: a first line of names (OpendTect's header) says which is which: `x` (or
//!   `easting`, `cdp_x`, `utm x`...), `y` (`northing`, `cdp_y`), `z` (`time`, `twt`,
//!   `depth`, `tvdss`, `z (ms)`...), `inline` (`inl`, `il`, `iline`), `crossline` (`crl`,
//!   `xl`, `xline`); the others are the nodes' properties by their names (an attribute
//!   along the horizon). Without names, x, y, z are the first three and the others
//!   properties `column 4`, `column 5`...; a property's undefined values (nan, 1e29 or
//!   more in magnitude) are NaN. A file of inline, crossline and z without x and y is refused: it has no place
//!   without its survey's geometry.
//! - Undefined nodes are left out: a z of magnitude 1e29 or more (OpendTect's 1e30), or
//!   `nan`; so are nodes a file leaves out.
//! - Triangles: with inline and crossline columns, the survey's grid: each cell's two
//!   triangles where their three corners are defined (as ZMap+'s); without, the Delaunay
//!   triangulation of the nodes' x, y (the `delaunator` crate), less the triangles with an
//!   edge over twice the median edge, which would bridge undefined nodes and the bays of
//!   the outline. z as the file gives it (`z_down` turns a time or depth grid).
//! - Bounded: at most [`MAX_NODES`] nodes; every error names the line and column.

use std::path::Path;

use super::{Position, SurfaceError, TriangleMesh, VertexProperty};

/// Most nodes a file may hold (2^24: a 4096 x 4096 horizon).
pub const MAX_NODES: usize = 1 << 24;

/// A z at least this large in magnitude marks an undefined node (OpendTect writes 1e30).
pub const UNDEFINED: f64 = 1e29;

/// The largest map coordinate taken (a trillion metres: far past any map projection's,
/// and small enough for the triangulation's arithmetic).
pub const MAX_COORDINATE: f64 = 1e12;

/// What the reader found (`inspect`).
#[derive(Debug, Clone, PartialEq)]
pub struct XyzGrid {
    /// Nodes read with a z.
    pub nodes: usize,
    /// Nodes marked undefined.
    pub undefined: usize,
    /// Inlines and crosslines of the grid, where the file gives them.
    pub lattice: Option<[usize; 2]>,
    /// Nodes at the x, y of an earlier node (left out of a Delaunay triangulation).
    pub repeated: usize,
}

/// The columns of x, y, z, of inline and crossline where present, and of the properties
/// (column, name).
#[derive(Debug, Clone, PartialEq)]
struct Columns {
    x: usize,
    y: usize,
    z: usize,
    lines: Option<[usize; 2]>,
    others: Vec<(usize, String)>,
}

/// The column a header name stands for, if one of ours.
fn column_of(name: &str) -> Option<&'static str> {
    let name = name
        .trim_matches(|c: char| c == '"' || c == '\'')
        .to_ascii_lowercase();
    let word = name.split([' ', '(', '[']).next().unwrap_or("");
    match word {
        "x" | "easting" | "cdp_x" | "cdpx" | "utmx" | "utm_x" | "east" => Some("x"),
        "y" | "northing" | "cdp_y" | "cdpy" | "utmy" | "utm_y" | "north" => Some("y"),
        "z" | "time" | "twt" | "depth" | "tvdss" | "tvd" | "elevation" => Some("z"),
        "inline" | "inl" | "il" | "iline" => Some("inline"),
        "crossline" | "crl" | "xl" | "xline" => Some("crossline"),
        _ => None,
    }
}

/// A line's fields, with the 1-based column each starts at: separated by whitespace,
/// commas or semicolons; a field in double quotes (a header's `"Z (ms)"`) is one.
pub(crate) fn fields(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    // The field's byte offset and its column (characters from 1), counted as we go:
    // linear in the line however many fields it has.
    let mut start: Option<(usize, usize)> = None;
    let mut quoted = false;
    for (column, (i, c)) in line.char_indices().enumerate() {
        let separator = !quoted && (c.is_whitespace() || c == ',' || c == ';');
        match (separator, start) {
            (true, Some((s, col))) => {
                out.push((col, &line[s..i]));
                start = None;
            }
            (false, None) => {
                start = Some((i, column + 1));
                quoted = c == '"';
            }
            (false, Some(_)) if quoted && c == '"' => quoted = false,
            _ => {}
        }
    }
    if let Some((s, col)) = start {
        out.push((col, &line[s..]));
    }
    out
}

/// Parse x y z text (`name` names it in errors).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    parse_with_grid(name, bytes).map(|(mesh, _)| mesh)
}

/// One node as read: position, and inline and crossline numbers where given.
struct Node {
    at: [f64; 3],
    lines: Option<[f64; 2]>,
    line: usize,
    values: Vec<f64>,
}

/// [`parse`], and what the reader found.
pub fn parse_with_grid(name: &Path, bytes: &[u8]) -> Result<(TriangleMesh, XyzGrid), SurfaceError> {
    let text = super::utf8(name, bytes)?;
    let error = |line: usize, column: usize, message: String| {
        SurfaceError::format(name, Position::Line { line, column }, message)
    };
    let mut columns: Option<Columns> = None;
    let mut width = 0;
    let mut nodes: Vec<Node> = Vec::new();
    let mut undefined = 0;
    for (index, line) in text.lines().enumerate() {
        let n = index + 1;
        let trimmed = line.trim_start();
        if trimmed.is_empty() || trimmed.starts_with('#') || trimmed.starts_with('!') {
            continue;
        }
        let words = fields(line);
        if columns.is_none() {
            let named = header(&words).map_err(|(column, m)| error(n, column, m))?;
            width = words.len();
            match named {
                Some(c) => {
                    columns = Some(c);
                    continue;
                }
                None if width >= 3 => {
                    columns = Some(Columns {
                        x: 0,
                        y: 1,
                        z: 2,
                        lines: None,
                        others: (3..width)
                            .map(|i| (i, format!("column {}", i + 1)))
                            .collect(),
                    })
                }
                None => {
                    return Err(error(
                        n,
                        1,
                        format!("{width} numbers: expected x, y and z (and any more columns)"),
                    ))
                }
            }
        }
        let c = columns.as_ref().expect("set above");
        if words.len() != width {
            return Err(error(
                n,
                words
                    .get(width.min(words.len().saturating_sub(1)))
                    .map_or(1, |w| w.0),
                format!("{} values, where the first line has {width}", words.len()),
            ));
        }
        let number = |i: usize| -> Result<f64, SurfaceError> {
            let (column, word) = words[i];
            match word.to_ascii_lowercase().as_str() {
                "nan" => Ok(f64::NAN),
                w => w.parse::<f64>().map_err(|_| {
                    error(
                        n,
                        column,
                        format!(
                            "expected a number, found {:?}",
                            arbvis_core::input::shorten(word, 24)
                        ),
                    )
                }),
            }
        };
        let (x, y, z) = (number(c.x)?, number(c.y)?, number(c.z)?);
        if !(x.is_finite() && y.is_finite()) {
            return Err(error(n, words[c.x].0, "x and y must be finite".into()));
        }
        if x.abs().max(y.abs()) > MAX_COORDINATE {
            let column = if x.abs() > MAX_COORDINATE {
                words[c.x].0
            } else {
                words[c.y].0
            };
            return Err(error(
                n,
                column,
                format!("x {x:e}, y {y:e}: map coordinates within {MAX_COORDINATE:e}"),
            ));
        }
        if !z.is_finite() || z.abs() >= UNDEFINED {
            undefined += 1;
            continue;
        }
        let lines = match c.lines {
            Some([i, j]) => Some([number(i)?, number(j)?]),
            None => None,
        };
        if nodes.len() == MAX_NODES {
            return Err(error(n, 1, format!("more than {MAX_NODES} nodes")));
        }
        let mut values = Vec::with_capacity(c.others.len());
        for &(i, _) in &c.others {
            let v = number(i)?;
            values.push(if v.abs() < UNDEFINED { v } else { f64::NAN });
        }
        nodes.push(Node {
            at: [x, y, z],
            lines,
            line: n,
            values,
        });
    }
    if nodes.len() < 3 {
        return Err(error(
            text.lines().count().max(1),
            1,
            format!(
                "{} defined nodes ({undefined} undefined): a surface needs three or more",
                nodes.len()
            ),
        ));
    }
    triangulated(name, nodes, columns, undefined)
}

/// The surface of the defined `nodes` (three or more): on their inline/crossline lattice
/// where `columns` give one, else by Delaunay; `columns`' other values as properties.
fn triangulated(
    name: &Path,
    nodes: Vec<Node>,
    columns: Option<Columns>,
    undefined: usize,
) -> Result<(TriangleMesh, XyzGrid), SurfaceError> {
    let error = |line: usize, column: usize, message: String| {
        SurfaceError::format(name, Position::Line { line, column }, message)
    };
    let (triangles, lattice) = match columns.as_ref().and_then(|c| c.lines) {
        Some(_) => {
            let (triangles, shape) =
                lattice_triangles(&nodes).map_err(|(line, m)| error(line, 1, m))?;
            (triangles, Some(shape))
        }
        None => (delaunay_triangles(&nodes), None),
    };
    if triangles.is_empty() {
        return Err(error(
            nodes[0].line,
            1,
            format!(
                "{} nodes make no triangle: they lie on one line, or no two are neighbours",
                nodes.len()
            ),
        ));
    }
    let repeated = match lattice {
        Some(_) => 0,
        None => repeated_positions(&nodes),
    };
    let grid = XyzGrid {
        nodes: nodes.len(),
        undefined,
        lattice,
        repeated,
    };
    let vertices = nodes.iter().map(|n| n.at).collect();
    let properties = columns
        .map_or_else(Vec::new, |c| c.others)
        .into_iter()
        .enumerate()
        .map(|(k, (_, name))| VertexProperty {
            name,
            values: nodes.iter().map(|n| n.values[k]).collect(),
        })
        .collect();
    let mesh = TriangleMesh::from_indexed(name, vertices, triangles.iter().map(|t| t.to_vec()))?
        .with_properties(name, properties)?;
    Ok((mesh, grid))
}

/// The columns a first line of names gives, None when the line is numbers; an error
/// (column, message) for names without x, y and z.
fn header(words: &[(usize, &str)]) -> Result<Option<Columns>, (usize, String)> {
    let numbers = words
        .iter()
        .all(|(_, w)| w.eq_ignore_ascii_case("nan") || w.parse::<f64>().is_ok());
    if numbers {
        return Ok(None);
    }
    let find = |what: &str| words.iter().position(|(_, w)| column_of(w) == Some(what));
    let lines = match (find("inline"), find("crossline")) {
        (Some(i), Some(j)) => Some([i, j]),
        _ => None,
    };
    match (find("x"), find("y"), find("z")) {
        (Some(x), Some(y), Some(z)) => {
            let ours = [Some(x), Some(y), Some(z), lines.map(|l| l[0]), lines.map(|l| l[1])];
            let others = words
                .iter()
                .enumerate()
                .filter(|(i, _)| !ours.contains(&Some(*i)))
                .map(|(i, (_, w))| (i, w.trim_matches(|c: char| c == '"' || c == '\'').to_string()))
                .collect();
            Ok(Some(Columns {
                x,
                y,
                z,
                lines,
                others,
            }))
        }
        (None, None, Some(_)) if lines.is_some() => Err((
            1,
            "inline, crossline and z without x and y: a grid placed by the survey's numbers only; export it with X/Y".into(),
        )),
        _ => Err((
            1,
            format!(
                "a first line of names ({}) without x, y and z columns: expected names such as X, Y, Z, Inline, Crossline, or numbers",
                arbvis_core::input::shorten(
                    &words.iter().map(|(_, w)| *w).collect::<Vec<_>>().join(" "),
                    200
                )
            ),
        )),
    }
}

/// A grid's triangles and its shape (inlines, crosslines).
type Lattice = (Vec<[u32; 3]>, [usize; 2]);

/// Triangles of the nodes' inline-crossline grid: each cell's two, where their corners are
/// defined; and the grid's shape. An error (line, message) for numbers off the grid's steps
/// or a node given twice.
fn lattice_triangles(nodes: &[Node]) -> Result<Lattice, (usize, String)> {
    let numbers = |a: usize| -> Vec<f64> {
        let mut v: Vec<f64> = nodes.iter().map(|n| n.lines.expect("lines")[a]).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let axes = [numbers(0), numbers(1)];
    let mut steps = [1.0; 2];
    let mut shape = [1usize; 2];
    for a in 0..2 {
        let v = &axes[a];
        let step = v
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        steps[a] = if step.is_finite() && step > 0.0 {
            step
        } else {
            1.0
        };
        let span = (v[v.len() - 1] - v[0]) / steps[a];
        if !(span.is_finite() && span < MAX_NODES as f64) {
            return Err((
                nodes[0].line,
                format!(
                    "{} numbers spanning {span} steps",
                    ["inline", "crossline"][a]
                ),
            ));
        }
        shape[a] = span.round() as usize + 1;
    }
    if shape[0].saturating_mul(shape[1]) > MAX_NODES {
        return Err((
            nodes[0].line,
            format!(
                "a grid of {} x {} nodes: at most {MAX_NODES}",
                shape[0], shape[1]
            ),
        ));
    }
    let mut slot = vec![u32::MAX; shape[0] * shape[1]];
    for (i, node) in nodes.iter().enumerate() {
        let l = node.lines.expect("lines");
        let at: [f64; 2] = std::array::from_fn(|a| (l[a] - axes[a][0]) / steps[a]);
        if at.iter().any(|t| (t - t.round()).abs() > 1e-6) {
            return Err((
                node.line,
                format!(
                    "inline {} crossline {} is off the grid's steps ({} and {})",
                    l[0], l[1], steps[0], steps[1]
                ),
            ));
        }
        let s = at[0].round() as usize * shape[1] + at[1].round() as usize;
        if slot[s] != u32::MAX {
            return Err((
                node.line,
                format!("inline {} crossline {} again", l[0], l[1]),
            ));
        }
        slot[s] = i as u32;
    }
    let mut triangles = Vec::new();
    for i in 0..shape[0].saturating_sub(1) {
        for j in 0..shape[1].saturating_sub(1) {
            let c = |di: usize, dj: usize| slot[(i + di) * shape[1] + j + dj];
            for t in [[c(0, 0), c(1, 0), c(1, 1)], [c(0, 0), c(1, 1), c(0, 1)]] {
                if t.iter().all(|&v| v != u32::MAX) {
                    triangles.push(t);
                }
            }
        }
    }
    Ok((triangles, shape))
}

/// How many nodes lie at the x, y of another (all but the first at each).
fn repeated_positions(nodes: &[Node]) -> usize {
    let mut at: Vec<[f64; 2]> = nodes.iter().map(|n| [n.at[0], n.at[1]]).collect();
    at.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    at.windows(2).filter(|w| w[0] == w[1]).count()
}

/// The Delaunay triangles of the nodes' x, y (relative to the first node, so that UTM
/// coordinates keep their precision), less those with an edge over twice the median edge.
fn delaunay_triangles(nodes: &[Node]) -> Vec<[u32; 3]> {
    let origin = nodes[0].at;
    let points: Vec<delaunator::Point> = nodes
        .iter()
        .map(|n| delaunator::Point {
            x: n.at[0] - origin[0],
            y: n.at[1] - origin[1],
        })
        .collect();
    let all = delaunator::triangulate(&points).triangles;
    let length = |a: usize, b: usize| (points[a].x - points[b].x).hypot(points[a].y - points[b].y);
    let longest: Vec<f64> = all
        .chunks_exact(3)
        .map(|t| {
            length(t[0], t[1])
                .max(length(t[1], t[2]))
                .max(length(t[2], t[0]))
        })
        .collect();
    let mut edges: Vec<f64> = all
        .chunks_exact(3)
        .flat_map(|t| [length(t[0], t[1]), length(t[1], t[2]), length(t[2], t[0])])
        .collect();
    if edges.is_empty() {
        return Vec::new();
    }
    let middle = edges.len() / 2;
    let median = *edges.select_nth_unstable_by(middle, f64::total_cmp).1;
    all.chunks_exact(3)
        .zip(longest)
        .filter(|(_, l)| *l < 2.0 * median)
        .map(|(t, _)| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::assert_refused_at;

    fn read(text: &str) -> (TriangleMesh, XyzGrid) {
        parse_with_grid(Path::new("h.xyz"), text.as_bytes()).unwrap()
    }

    /// A 4 x 3 grid in UTM with a rotated lattice, one node undefined (1e30).
    fn rotated_grid(with_lines: bool) -> String {
        let mut text = String::from("# exported\n");
        if with_lines {
            text += "\"X\" \"Y\" \"Inline\" \"Crossline\" \"Z (ms)\" \"Amplitude\"\n";
        }
        let (c, s) = (0.6f64, 0.8f64);
        for il in 0..4 {
            for xl in 0..3 {
                let (u, v) = (il as f64 * 25.0, xl as f64 * 25.0);
                let (x, y) = (620_000.5 + u * c - v * s, 6_074_000.25 + u * s + v * c);
                let z = if (il, xl) == (2, 1) {
                    1e30
                } else {
                    1200.0 + il as f64 * 3.0 - xl as f64
                };
                text += &match with_lines {
                    true => {
                        // An amplitude per node, undefined (1e30) at node (0, 2).
                        let a = if (il, xl) == (0, 2) {
                            1e30
                        } else {
                            il as f64 * 10.0 + xl as f64 - 7.5
                        };
                        format!("{x:.2}\t{y:.2}\t{}\t{}\t{z}\t{a}\n", 100 + il * 2, 300 + xl)
                    }
                    false => format!("{x:.2}, {y:.2}, {z}\n"),
                };
            }
        }
        text
    }

    #[test]
    fn a_grid_with_inline_and_crossline_columns_is_triangulated_on_its_lattice() {
        let (mesh, grid) = read(&rotated_grid(true));
        assert_eq!(
            grid,
            XyzGrid {
                nodes: 11,
                undefined: 1,
                lattice: Some([4, 3]),
                repeated: 0,
            }
        );
        // 3 x 2 cells of two triangles; the undefined node (2, 1) takes away the six
        // triangles that touch it.
        assert_eq!(mesh.triangles.len(), 12 - 6);
        assert_eq!(mesh.vertices[0], [620_000.5, 6_074_000.25, 1200.0]);
        // The other column is a property of the nodes, in their order (node (2, 1) left
        // out with its z), undefined at node (0, 2).
        let amplitude = mesh.property("Amplitude").expect("a property");
        let expected: Vec<f64> = (0..4)
            .flat_map(|il| (0..3).map(move |xl| (il, xl)))
            .filter(|&n| n != (2, 1))
            .map(|(il, xl)| match (il, xl) {
                (0, 2) => f64::NAN,
                _ => il as f64 * 10.0 + xl as f64 - 7.5,
            })
            .collect();
        assert_eq!(amplitude.values.len(), expected.len());
        for (a, e) in amplitude.values.iter().zip(&expected) {
            assert!(a == e || (a.is_nan() && e.is_nan()), "{a} against {e}");
        }
        assert_eq!(amplitude.range(), Some([-7.5, 24.5]));
        // A node at the x, y of another is counted (Delaunay leaves it out).
        let (_, grid) = read("0 0 1\n1 0 1\n0 1 2\n1 0 5\n0 0 3\n");
        assert_eq!(grid.repeated, 2);
        // Without names, a fourth column is "column 4".
        let (mesh, _) = read("0 0 1 9\n1 0 1 8\n0 1 2 7\n");
        assert_eq!(mesh.property("column 4").unwrap().values, [9.0, 8.0, 7.0]);
    }

    #[test]
    fn a_grid_of_x_y_z_alone_is_triangulated_by_delaunay_without_bridging_the_hole() {
        let (mesh, grid) = read(&rotated_grid(false));
        assert_eq!(
            grid,
            XyzGrid {
                nodes: 11,
                undefined: 1,
                lattice: None,
                repeated: 0,
            }
        );
        // The lattice's cells, each split one way or the other; none spans the missing
        // node's 50 m gap (twice the 25 m median edge is kept, 50 m diagonals are not).
        let longest = mesh
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .map(|(a, b)| {
                let (p, q) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
                (p[0] - q[0]).hypot(p[1] - q[1])
            })
            .fold(0.0, f64::max);
        assert!(longest < 36.0, "{longest}");
        // The two cells away from the hole whole (4 triangles), and in each of the four
        // around it the triangle of its three defined corners (4).
        assert_eq!(mesh.triangles.len(), 8);
    }

    #[test]
    fn malformed_grids_are_refused_at_their_line_and_column() {
        assert_refused_at(
            "h.xyz",
            "1 2 3\n4 5\n",
            2,
            3,
            "2 values, where the first line has 3",
        );
        assert_refused_at(
            "h.xyz",
            "1 2 3\n4 five 6\n",
            2,
            3,
            "expected a number, found \"five\"",
        );
        assert_refused_at("h.xyz", "1 2\n", 1, 1, "expected x, y and z");
        assert_refused_at(
            "h.xyz",
            "Inline Crossline Z\n1 2 3\n",
            1,
            1,
            "without x and y",
        );
        assert_refused_at(
            "h.xyz",
            "a b c\n1 2 3\n",
            1,
            1,
            "without x, y and z columns",
        );
        assert_refused_at("h.xyz", "1 2 3\n4 5 6\n", 2, 1, "2 defined nodes");
        assert_refused_at("h.xyz", "1 1 3\n2 2 3\n3 3 3\n", 1, 1, "no triangle");
        assert_refused_at(
            "h.xyz",
            "1 2 3\n4 1e308 6\n7 8 9\n",
            2,
            3,
            "map coordinates within 1e12",
        );
        assert_refused_at(
            "h.xyz",
            "1 2 1e30\n4 5 nan\n7 8 9\n",
            3,
            1,
            "1 defined nodes (2 undefined)",
        );
        let twice = "X Y IL XL Z\n0 0 1 1 5\n1 0 2 1 5\n0 1 1 2 5\n1 0 2 1 6\n";
        assert_refused_at("h.xyz", twice, 5, 1, "inline 2 crossline 1 again");
        // Inlines 0, 2 and 3.5: steps of 1.5, which 2 is not on.
        let off = "X Y IL XL Z\n0 0 0 1 5\n1 0 2 1 5\n0 1 0 2 5\n2 0 3.5 1 6\n";
        assert_refused_at("h.xyz", off, 3, 1, "off the grid's steps");
    }
}
