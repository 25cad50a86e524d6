//! ZMap+ grids (`.zmap`, `.dat`, `.grd` as Petrel, OpendTect and Kingdom export a horizon or
//! a fault's throw): a header between `@` lines, then the nodes column by column.
//!
//! # Decisions
//! - The header: `@NAME, GRID, NODES_PER_LINE`; `FIELD_WIDTH, NULL_VALUE, NULL_TEXT,
//!   DECIMALS, START_COLUMN`; `ROWS, COLUMNS, XMIN, XMAX, YMIN, YMAX`; a line of three
//!   numbers (a transform, ignored); `@`. Lines starting with `!` are comments.
//! - The nodes follow column by column, west to east, each column north to south (the
//!   first value at `YMIN`..`YMAX`'s top, `YMAX`), separated by whitespace (the fixed
//!   field width is not needed to split them; a value running into the next is an error).
//! - A node equal to the null value (within 1e-6 of it, relative) or to the null text is
//!   undefined; a cell's two triangles are made where their three corners are defined.
//! - z as the file gives it (a grid of time or depth positive downwards is turned by the
//!   layer's `z_down`). Every error names the line and column.

use std::path::Path;

use super::{Position, SurfaceError, TriangleMesh};
use arbvis_core::input::words as tokens;

/// What the header says (`inspect`).
#[derive(Debug, Clone, PartialEq)]
pub struct ZmapGrid {
    /// Rows (north to south) and columns (west to east).
    pub shape: [usize; 2],
    /// `[xmin, xmax, ymin, ymax]`.
    pub extent: [f64; 4],
    /// Nodes equal to the null value.
    pub undefined: usize,
}

/// Most nodes a grid may declare (2^28: 2 GB of f64 vertices and more triangles).
const MAX_NODES: u64 = 1 << 28;

/// Parse ZMap+ text (`name` names it in errors).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    parse_with_grid(name, bytes).map(|(mesh, _)| mesh)
}

/// [`parse`], and the grid's header.
pub fn parse_with_grid(
    name: &Path,
    bytes: &[u8],
) -> Result<(TriangleMesh, ZmapGrid), SurfaceError> {
    let text = super::utf8(name, bytes)?;
    let error = |line: usize, column: usize, message: String| {
        SurfaceError::format(name, Position::Line { line, column }, message)
    };
    // The header's fields, with the line each came from, up to the closing `@`.
    let mut fields: Vec<(usize, usize, &str)> = Vec::new();
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let mut opened = false;
    let mut body_start = None;
    for (n, line) in lines.by_ref() {
        let trimmed = line.trim_start();
        if trimmed.is_empty() || trimmed.starts_with('!') {
            continue;
        }
        if let Some(rest) = trimmed.strip_prefix('@') {
            if opened {
                body_start = Some(n + 1);
                break;
            }
            opened = true;
            fields.extend(split_fields(n, line, rest));
            continue;
        }
        if !opened {
            return Err(error(
                n,
                1,
                "not a ZMap+ grid: expected a header line starting with `@`".into(),
            ));
        }
        fields.extend(split_fields(n, line, line));
    }
    let Some(_) = body_start else {
        let n = text.lines().count().max(1);
        return Err(error(
            n,
            1,
            "the ZMap+ header does not end (a line `@` is expected after it)".into(),
        ));
    };
    // 3 + 5 + 6 + 3 fields.
    if fields.len() < 14 {
        let (n, c, _) = fields.last().copied().unwrap_or((1, 1, ""));
        return Err(error(n, c, format!("the ZMap+ header has {} fields: expected NAME, GRID, NODES; WIDTH, NULL, NULL TEXT, DECIMALS, COLUMN; ROWS, COLUMNS, XMIN, XMAX, YMIN, YMAX", fields.len())));
    }
    if !fields[1].2.eq_ignore_ascii_case("GRID") {
        let (n, c, f) = fields[1];
        return Err(error(n, c, format!("{f:?}: only GRID files are read")));
    }
    let number = |i: usize| -> Result<f64, SurfaceError> {
        let (n, c, f) = fields[i];
        f.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| error(n, c, format!("{f:?}: a finite number is expected here")))
    };
    let null = if fields[4].2.is_empty() {
        None
    } else {
        Some(number(4)?)
    };
    let null_text = fields[5].2;
    let count = |i: usize| -> Result<usize, SurfaceError> {
        let v = number(i)?;
        let (n, c, f) = fields[i];
        (v >= 2.0 && v.fract() == 0.0 && v <= MAX_NODES as f64)
            .then_some(v as usize)
            .ok_or_else(|| {
                error(
                    n,
                    c,
                    format!("{f:?}: a count of 2 or more nodes is expected"),
                )
            })
    };
    let (rows, columns) = (count(8)?, count(9)?);
    let extent = [number(10)?, number(11)?, number(12)?, number(13)?];
    if rows as u64 * columns as u64 > MAX_NODES {
        let (n, c, _) = fields[8];
        return Err(error(
            n,
            c,
            format!("{rows} x {columns} nodes: more than {MAX_NODES}"),
        ));
    }
    // The nodes, column by column.
    let total = rows * columns;
    let mut z = Vec::with_capacity(total.min(text.len() / 2 + 1));
    let mut undefined = 0;
    'lines: for (n, line) in lines {
        for (column, token) in tokens(line) {
            if token.starts_with('!') {
                continue 'lines;
            }
            let value = if token == null_text && !null_text.is_empty() {
                None
            } else {
                let v = token
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        error(
                            n,
                            column,
                            format!("{token:?}: a node's value is a finite number"),
                        )
                    })?;
                let is_null = null.is_some_and(|u| (v - u).abs() <= 1e-6 * u.abs().max(1.0));
                (!is_null).then_some(v)
            };
            if z.len() == total {
                return Err(error(
                    n,
                    column,
                    format!("more than the {rows} x {columns} nodes the header declares"),
                ));
            }
            undefined += usize::from(value.is_none());
            z.push(value);
        }
    }
    if z.len() < total {
        let n = text.lines().count().max(1);
        return Err(error(
            n,
            1,
            format!(
                "{} nodes where the header declares {rows} x {columns} = {total}",
                z.len()
            ),
        ));
    }
    let mesh = triangles(name, &z, [rows, columns], extent)?;
    Ok((
        mesh,
        ZmapGrid {
            shape: [rows, columns],
            extent,
            undefined,
        },
    ))
}

/// The grid's defined nodes and the triangles whose corners are all defined.
fn triangles(
    name: &Path,
    z: &[Option<f64>],
    [rows, columns]: [usize; 2],
    [x0, x1, y0, y1]: [f64; 4],
) -> Result<TriangleMesh, SurfaceError> {
    let mut index = vec![u32::MAX; z.len()];
    let mut vertices = Vec::new();
    for c in 0..columns {
        for r in 0..rows {
            let at = c * rows + r;
            if let Some(v) = z[at] {
                index[at] = vertices.len() as u32;
                let x = x0 + (x1 - x0) * c as f64 / (columns - 1) as f64;
                let y = y1 - (y1 - y0) * r as f64 / (rows - 1) as f64;
                vertices.push([x, y, v]);
            }
        }
    }
    let node = |r: usize, c: usize| index[c * rows + r];
    let mut polygons = Vec::new();
    for c in 0..columns - 1 {
        for r in 0..rows - 1 {
            let (a, b, d, e) = (
                node(r, c),
                node(r + 1, c),
                node(r + 1, c + 1),
                node(r, c + 1),
            );
            for t in [[a, d, b], [a, e, d]] {
                if t.iter().all(|&v| v != u32::MAX) {
                    polygons.push(t);
                }
            }
        }
    }
    TriangleMesh::from_indexed(name, vertices, polygons)
}

/// The comma-separated fields of a header line (`rest`: after its `@`), with their line
/// and column; an empty field is kept (the null text may be empty).
fn split_fields<'t>(n: usize, line: &'t str, rest: &'t str) -> Vec<(usize, usize, &'t str)> {
    let offset = line.len() - rest.len();
    let mut out = Vec::new();
    let mut start = 0;
    for part in rest.split(',') {
        let lead = part.len() - part.trim_start().len();
        let column = line[..offset + start + lead].chars().count() + 1;
        out.push((n, column, part.trim()));
        start += part.len() + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3 rows x 4 columns, one undefined node (row 1 of column 2: the seventh value,
    /// inside the grid), nodes column by column north to south.
    const GRID: &str = "! exported\n@top, GRID, 4\n15, -99999.0, , 4, 1\n3, 4, 100.0, 130.0, 200.0, 220.0\n0.0, 0.0, 0.0\n@\n  -1.0  -2.0  -3.0  -4.0\n  -5.0  -6.0  -7.0 -99999.0\n  -9.0 -10.0 -11.0 -12.0\n";

    #[test]
    fn nodes_run_column_by_column_from_the_north_west() {
        let (mesh, grid) = parse_with_grid(Path::new("g.zmap"), GRID.as_bytes()).unwrap();
        assert_eq!(
            grid,
            ZmapGrid {
                shape: [3, 4],
                extent: [100.0, 130.0, 200.0, 220.0],
                undefined: 1
            }
        );
        assert_eq!(mesh.vertices.len(), 11);
        // Column 0 north to south: (100, 220), (100, 210), (100, 200).
        assert_eq!(mesh.vertices[0], [100.0, 220.0, -1.0]);
        assert_eq!(mesh.vertices[2], [100.0, 200.0, -3.0]);
        // Column 1 starts with the fourth value.
        assert_eq!(mesh.vertices[3], [110.0, 220.0, -4.0]);
        // Six cells, twelve triangles, less the six that touch the inner undefined node.
        assert_eq!(mesh.triangles.len(), 12 - 6);
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let cases = [
            (GRID.replace("GRID", "POINT"), 2, 7, "only GRID"),
            (GRID.replace("3, 4,", "3, x,"), 4, 4, "finite number"),
            (GRID.replace("3, 4,", "1, 4,"), 4, 1, "2 or more"),
            (GRID.replace(" -6.0", " abc"), 8, 9, "finite number"),
            (
                GRID.replace("-12.0\n", "-12.0 5.0\n"),
                9,
                26,
                "more than the 3 x 4",
            ),
            (
                GRID.replace("  -9.0 -10.0 -11.0 -12.0\n", ""),
                8,
                1,
                "8 nodes where the header declares 3 x 4 = 12",
            ),
            (GRID.replace("\n@\n", "\n"), 8, 1, "does not end"),
            ("1 2 3\n".to_string(), 1, 1, "not a ZMap+ grid"),
            (GRID.replace("3, 4,", "100000, 100000,"), 4, 1, "more than"),
        ];
        for (text, line, column, says) in cases {
            crate::surface::assert_refused_at("bad.zmap", &text, line, column, says);
        }
    }
}
