//! From the arrays the XML scan found to a [`Mesh`]: the structure is checked before
//! anything is decoded or inflated (a piece with cells, the arrays it needs with usable
//! types, the memory the declared counts imply within the budget), then the small cell
//! arrays are decoded and checked (offsets, types: a piece of points and faces only is
//! refused here), and only then the connectivity, the points and the data arrays.

use super::desc::{ArrayDesc, File, Format, Section};
use crate::budget;
use crate::mesh::cells::{vtk_kind, RawCells, Shape};
use crate::mesh::read::{line_column, text_error, vec_for};
use crate::mesh::{DataArray, Mesh, MeshError, MeshInfo, ReadArray};

/// Bytes one value of `d` needs once decoded: its stored width (the bytes inflated or
/// copied) and the f64 or i64 it becomes.
fn decoded_bytes(d: &ArrayDesc) -> u64 {
    d.ty.map_or(8, |t| t.size() as u64) + 8
}

pub(super) fn build(
    f: &File,
    arrays: &[ArrayDesc],
    piece_at: usize,
    np: u64,
    nc: u64,
    version: String,
) -> Result<Mesh, MeshError> {
    let terr = |at: usize, m: String| text_error(f.name, f.bytes, at, m);
    let line = line_column(f.bytes, piece_at).0;
    let find = |section: Section, name: Option<&str>, what: &str| {
        arrays
            .iter()
            .find(|d| d.section == section && name.is_none_or(|n| d.name == n))
            .ok_or_else(|| terr(piece_at, format!("the piece has no {what} DataArray")))
    };
    if nc == 0 {
        return Err(terr(
            piece_at,
            "the piece has no cells (NumberOfCells=\"0\"), so no volume cells".into(),
        ));
    }
    let pts = find(Section::Points, None, "Points")?;
    if pts.comps != 3 {
        return Err(terr(
            pts.at,
            format!("Points have {} components, expected 3", pts.comps),
        ));
    }
    let off_d = find(Section::Cells, Some("offsets"), "Cells offsets")?;
    let conn_d = find(Section::Cells, Some("connectivity"), "Cells connectivity")?;
    let types_d = find(Section::Cells, Some("types"), "Cells types")?;
    for d in [pts, off_d, conn_d, types_d] {
        f.ty(d)?;
    }
    let np_usize = usize::try_from(np)
        .map_err(|_| terr(piece_at, format!("NumberOfPoints={np} is too large")))?;
    let nc_usize = usize::try_from(nc)
        .map_err(|_| terr(piece_at, format!("NumberOfCells={nc} is too large")))?;
    let points_need = format!("NumberOfPoints=\"{np}\" (line {line})");
    let cells_need = format!("NumberOfCells=\"{nc}\" (line {line})");

    // Every array must hold what the piece declares: ASCII numbers are counted, binary
    // headers read, before anything is decoded or inflated.
    f.precheck(pts, np_usize.checked_mul(3), &format!("3 x {points_need}"))?;
    f.precheck(off_d, Some(nc_usize), &cells_need)?;
    f.precheck(types_d, Some(nc_usize), &cells_need)?;
    for d in arrays {
        let (n, need) = match d.section {
            Section::PointData => (np_usize, &points_need),
            Section::CellData => (nc_usize, &cells_need),
            _ => continue,
        };
        f.precheck(
            d,
            n.checked_mul(d.comps),
            &format!("{} components x {need}", d.comps),
        )?;
    }

    // The cells' own small arrays first: offsets and types say whether there is any
    // volume to read before the connectivity and the points are inflated.
    budget::check(
        format!("decoding the offsets and types of {nc} cells"),
        budget::times(nc, decoded_bytes(off_d) + decoded_bytes(types_d) + 64),
    )
    .map_err(|e| terr(piece_at, e.to_string()))?;
    let offsets = f.ints(off_d, Some(nc_usize), &cells_need)?;
    let mut prev = 0;
    for (i, &o) in offsets.iter().enumerate() {
        if o < prev {
            return Err(terr(off_d.at, format!("offset {i} is {o}, less than the one before ({prev}): offsets must not decrease")));
        }
        prev = o;
    }
    let types = f.ints(types_d, Some(nc_usize), &cells_need)?;
    let mut kinds = vec_for(nc_usize, "cell types").map_err(|m| terr(piece_at, m))?;
    for (i, &t) in types.iter().enumerate() {
        kinds.push(vtk_kind(t).map_err(|m| terr(types_d.at, format!("cell {i}: {m}")))?);
    }
    if kinds.iter().all(|k| k.shape == Shape::Skip) {
        return Err(terr(
            types_d.at,
            format!(
                "no volume cells (tetrahedra, hexahedra, voxels, wedges, pyramids): the {nc} cells are points, lines and faces (the first is {})",
                kinds[0].name
            ),
        ));
    }
    // What the declared counts make: every array decoded (the stored bytes and the f64
    // or i64 they become), the points as [f64; 3], a cell's kind and offsets, and up to
    // 6 tetrahedra per cell; before the connectivity, points and data are inflated.
    let per_point: u64 = 3 * decoded_bytes(pts)
        + 24
        + arrays
            .iter()
            .filter(|d| d.section == Section::PointData)
            .map(|d| d.comps as u64 * decoded_bytes(d))
            .sum::<u64>();
    let per_cell: u64 = decoded_bytes(off_d)
        + decoded_bytes(types_d)
        + 64
        + 6 * 20
        + arrays
            .iter()
            .filter(|d| d.section == Section::CellData)
            .map(|d| d.comps as u64 * (decoded_bytes(d) + 6 * 8))
            .sum::<u64>();
    let estimate = budget::times(np, per_point).saturating_add(budget::times(nc, per_cell));
    budget::check(
        format!("decoding the piece's {np} points and {nc} cells"),
        estimate,
    )
    .map_err(|e| terr(piece_at, e.to_string()))?;

    let conn_len = offsets.last().copied().unwrap_or(0);
    let conn_n = usize::try_from(conn_len)
        .map_err(|_| terr(off_d.at, format!("the last offset {conn_len} is too large")))?;
    let conn_need = format!("the last offset, {conn_len}");
    f.precheck(conn_d, Some(conn_n), &conn_need)?;
    budget::check(
        format!("the connectivity of {nc} cells ({conn_n} point indices)"),
        budget::times(conn_n as u64, decoded_bytes(conn_d) + 4),
    )
    .map_err(|e| terr(off_d.at, e.to_string()))?;
    let conn = f.ints(conn_d, Some(conn_n), &conn_need)?;

    let mut cells = RawCells {
        text: true,
        token_base: (conn_d.format == Format::Ascii)
            .then(|| conn_d.text.first().map_or(conn_d.at, |t| t.0)),
        kinds,
        ..RawCells::default()
    };
    let mk = |m: String| terr(piece_at, m);
    cells.offsets = vec_for(nc_usize + 1, "cell offsets").map_err(mk)?;
    cells.at = vec_for(nc_usize, "cell positions").map_err(mk)?;
    cells.nodes = vec_for(conn.len(), "cell nodes").map_err(mk)?;
    cells.offsets.push(0);
    for &o in &offsets {
        let start = *cells.offsets.last().unwrap_or(&0);
        cells.at.push(if cells.token_base.is_some() {
            start
        } else {
            conn_d.at
        });
        cells.offsets.push(o as usize);
    }
    drop(offsets);
    for (j, &p) in conn.iter().enumerate() {
        let p = u32::try_from(p)
            .ok()
            .filter(|&p| p < u32::MAX)
            .ok_or_else(|| {
                terr(
                    conn_d.at,
                    format!("connectivity value {j} is {p}, not a point index (0 to 2^32 - 2)"),
                )
            })?;
        cells.nodes.push(p);
    }
    drop(conn);

    let coords = f.floats(pts, np_usize.checked_mul(3), &format!("3 x {points_need}"))?;
    if let Some(i) = coords.iter().position(|v| !v.is_finite()) {
        return Err(terr(
            pts.at,
            format!(
                "point {} has a coordinate that is not finite ({})",
                i / 3,
                coords[i]
            ),
        ));
    }
    let points: Vec<[f64; 3]> = coords.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    drop(coords);

    let mut point_arrays = Vec::new();
    let mut cell_arrays = Vec::new();
    for d in arrays {
        let (list, n, need) = match d.section {
            Section::PointData => (&mut point_arrays, np_usize, &points_need),
            Section::CellData => (&mut cell_arrays, nc_usize, &cells_need),
            _ => continue,
        };
        let values = f.floats(
            d,
            n.checked_mul(d.comps),
            &format!("{} components x {need}", d.comps),
        )?;
        list.push(ReadArray {
            array: DataArray {
                name: d.name.clone(),
                components: d.comps,
                values,
            },
            at: d.at,
        });
    }
    check_closed(f)?;
    let encodings: Vec<&str> = arrays
        .iter()
        .filter(|d| d.section != Section::Other)
        .map(|d| match (d.format, f.appended) {
            (Format::Ascii, _) => "ascii",
            (Format::Binary, _) => "binary (base64)",
            (Format::Appended, Some((_, true))) => "appended base64",
            _ => "appended raw",
        })
        .fold(Vec::new(), |mut v, e| {
            if !v.contains(&e) {
                v.push(e);
            }
            v
        });
    let info = MeshInfo {
        format: "VTK XML UnstructuredGrid".into(),
        version,
        encoding: format!(
            "{}{}, {} headers, {}",
            encodings.join(" + "),
            if f.zlib { ", zlib" } else { "" },
            f.header.xml_name(),
            if f.big { "big-endian" } else { "little-endian" }
        ),
        ..MeshInfo::default()
    };
    Mesh::assemble(
        f.name,
        f.bytes,
        points,
        &cells,
        point_arrays,
        cell_arrays,
        info,
    )
}

/// A file with appended data must go on, after the last byte an array uses, to
/// `</AppendedData>` and `</VTKFile>`: without them it is truncated (the XML before the
/// appended data was checked by the parser).
fn check_closed(f: &File) -> Result<(), MeshError> {
    let Some((start, _)) = f.appended else {
        return Ok(());
    };
    let used = f.appended_end.get().max(start);
    let tail = f.bytes.trim_ascii_end();
    let closing = tail
        .strip_suffix(b"</VTKFile>")
        .map(|t| t.trim_ascii_end())
        .and_then(|t| t.strip_suffix(b"</AppendedData>"))
        .map(|t| t.len());
    match closing {
        Some(at) if at >= used => Ok(()),
        Some(at) => Err(text_error(
            f.name,
            f.bytes,
            at,
            format!(
                "the appended data the arrays declare run to byte {used}, past </AppendedData> at byte {at}: the file is truncated or its offsets are wrong"
            ),
        )),
        None => Err(text_error(
            f.name,
            f.bytes,
            f.bytes.len(),
            format!(
                "the file ends at byte {} without </AppendedData> and </VTKFile> after the appended data (which the arrays use up to byte {used}): it is truncated",
                f.bytes.len()
            ),
        )),
    }
}
