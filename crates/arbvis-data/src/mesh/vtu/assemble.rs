//! From the arrays the XML scan found to a [`Mesh`]: the structure is checked before
//! anything is decoded or inflated (a piece with cells, the arrays it needs with usable
//! types, the memory the declared counts imply within the budget), then the small cell
//! arrays are decoded and checked (offsets, types: a piece of points and faces only is
//! refused here), and only then the connectivity, the points and the data arrays.

use super::desc::{ArrayDesc, File, Format, Section};
use crate::mesh::cells::{vtk_kind, Kind as CellKind, RawCells, Shape};
use crate::mesh::read::{line_column, text_error, vec_for};
use crate::mesh::{DataArray, Mesh, MeshError, MeshInfo, ReadArray};
use arbvis_core::budget;

/// Bytes one value of `d` needs once decoded: its stored width (the bytes inflated or
/// copied) and the f64 or i64 it becomes.
fn decoded_bytes(d: &ArrayDesc) -> u64 {
    d.ty.map_or(8, |t| t.size() as u64) + 8
}

/// The mesh of the piece at `piece_at` (`np` points, `nc` cells) from its `arrays`.
pub(super) fn build(
    f: &File,
    arrays: &[ArrayDesc],
    piece_at: usize,
    np: u64,
    nc: u64,
    version: String,
) -> Result<Mesh, MeshError> {
    let p = Piece::new(f, arrays, piece_at, np, nc)?;
    p.precheck()?;
    let (offsets, kinds) = p.cell_kinds()?;
    p.check_memory()?;
    let cells = p.cells(offsets, kinds)?;
    let points = p.points()?;
    let (point_arrays, cell_arrays) = p.data_arrays()?;
    check_closed(f)?;
    Mesh::assemble(
        f.name,
        f.bytes,
        points,
        &cells,
        point_arrays,
        cell_arrays,
        info(f, arrays, version),
    )
}

/// A piece: its declared counts and the arrays it needs.
struct Piece<'f, 'a> {
    f: &'f File<'a>,
    arrays: &'f [ArrayDesc<'a>],
    /// Where `<Piece>` starts.
    at: usize,
    np: u64,
    nc: u64,
    np_usize: usize,
    nc_usize: usize,
    pts: &'f ArrayDesc<'a>,
    off_d: &'f ArrayDesc<'a>,
    conn_d: &'f ArrayDesc<'a>,
    types_d: &'f ArrayDesc<'a>,
    /// What the point and cell counts are, for errors.
    points_need: String,
    cells_need: String,
}

impl<'f, 'a> Piece<'f, 'a> {
    /// An error at byte `at`.
    fn err(&self, at: usize, m: String) -> MeshError {
        text_error(self.f.name, self.f.bytes, at, m)
    }

    /// A piece with cells, its points of 3 components, the three cell arrays, each
    /// of a usable type.
    fn new(
        f: &'f File<'a>,
        arrays: &'f [ArrayDesc<'a>],
        at: usize,
        np: u64,
        nc: u64,
    ) -> Result<Self, MeshError> {
        let terr = |at: usize, m: String| text_error(f.name, f.bytes, at, m);
        let line = line_column(f.bytes, at).0;
        let find = |section: Section, name: Option<&str>, what: &str| {
            arrays
                .iter()
                .find(|d| d.section == section && name.is_none_or(|n| d.name == n))
                .ok_or_else(|| terr(at, format!("the piece has no {what} DataArray")))
        };
        if nc == 0 {
            return Err(terr(
                at,
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
            .map_err(|_| terr(at, format!("NumberOfPoints={np} is too large")))?;
        let nc_usize = usize::try_from(nc)
            .map_err(|_| terr(at, format!("NumberOfCells={nc} is too large")))?;
        Ok(Piece {
            f,
            arrays,
            at,
            np,
            nc,
            np_usize,
            nc_usize,
            pts,
            off_d,
            conn_d,
            types_d,
            points_need: format!("NumberOfPoints=\"{np}\" (line {line})"),
            cells_need: format!("NumberOfCells=\"{nc}\" (line {line})"),
        })
    }

    /// The values a data array `d` must hold, and what says so; `None` for arrays
    /// outside `PointData` and `CellData`.
    fn data_need(&self, d: &ArrayDesc) -> Option<(Option<usize>, String)> {
        let (n, need) = match d.section {
            Section::PointData => (self.np_usize, &self.points_need),
            Section::CellData => (self.nc_usize, &self.cells_need),
            _ => return None,
        };
        Some((
            n.checked_mul(d.comps),
            format!("{} components x {need}", d.comps),
        ))
    }

    /// Every array must hold what the piece declares: ASCII numbers are counted, binary
    /// headers read, before anything is decoded or inflated.
    fn precheck(&self) -> Result<(), MeshError> {
        let f = self.f;
        f.precheck(
            self.pts,
            self.np_usize.checked_mul(3),
            &format!("3 x {}", self.points_need),
        )?;
        f.precheck(self.off_d, Some(self.nc_usize), &self.cells_need)?;
        f.precheck(self.types_d, Some(self.nc_usize), &self.cells_need)?;
        for d in self.arrays {
            if let Some((n, need)) = self.data_need(d) {
                f.precheck(d, n, &need)?;
            }
        }
        Ok(())
    }

    /// The cells' own small arrays first: offsets (never decreasing) and types (some
    /// volume cells) say whether there is any volume to read before the connectivity
    /// and the points are inflated.
    fn cell_kinds(&self) -> Result<(Vec<i64>, Vec<CellKind>), MeshError> {
        let (f, nc, nc_usize) = (self.f, self.nc, self.nc_usize);
        let (off_d, types_d) = (self.off_d, self.types_d);
        budget::check(
            format!("decoding the offsets and types of {nc} cells"),
            budget::times(nc, decoded_bytes(off_d) + decoded_bytes(types_d) + 64),
        )
        .map_err(|e| self.err(self.at, e.to_string()))?;
        let offsets = f.ints(off_d, Some(nc_usize), &self.cells_need)?;
        let mut prev = 0;
        for (i, &o) in offsets.iter().enumerate() {
            if o < prev {
                return Err(self.err(off_d.at, format!("offset {i} is {o}, less than the one before ({prev}): offsets must not decrease")));
            }
            prev = o;
        }
        let types = f.ints(types_d, Some(nc_usize), &self.cells_need)?;
        let mut kinds = vec_for(nc_usize, "cell types").map_err(|m| self.err(self.at, m.into()))?;
        for (i, &t) in types.iter().enumerate() {
            kinds.push(vtk_kind(t).map_err(|m| self.err(types_d.at, format!("cell {i}: {m}")))?);
        }
        if kinds.iter().all(|k| k.shape == Shape::Skip) {
            return Err(self.err(
                types_d.at,
                format!(
                    "no volume cells (tetrahedra, hexahedra, voxels, wedges, pyramids): the {nc} cells are points, lines and faces (the first is {})",
                    kinds[0].name
                ),
            ));
        }
        Ok((offsets, kinds))
    }

    /// What the declared counts make, within the budget: every array decoded (the
    /// stored bytes and the f64 or i64 they become), the points as [f64; 3], a cell's
    /// kind and offsets, and up to 6 tetrahedra per cell; before the connectivity,
    /// points and data are inflated.
    fn check_memory(&self) -> Result<(), MeshError> {
        let in_section = |s: Section| self.arrays.iter().filter(move |d| d.section == s);
        let per_point: u64 = 3 * decoded_bytes(self.pts)
            + 24
            + in_section(Section::PointData)
                .map(|d| d.comps as u64 * decoded_bytes(d))
                .sum::<u64>();
        let per_cell: u64 = decoded_bytes(self.off_d)
            + decoded_bytes(self.types_d)
            + 64
            + 6 * 20
            + in_section(Section::CellData)
                .map(|d| d.comps as u64 * (decoded_bytes(d) + 6 * 8))
                .sum::<u64>();
        let (np, nc) = (self.np, self.nc);
        let estimate = budget::times(np, per_point).saturating_add(budget::times(nc, per_cell));
        budget::check(
            format!("decoding the piece's {np} points and {nc} cells"),
            estimate,
        )
        .map_err(|e| self.err(self.at, e.to_string()))
    }

    /// The cells: the connectivity (as long as the last offset, each a point index)
    /// decoded and laid out by the offsets.
    fn cells(&self, offsets: Vec<i64>, kinds: Vec<CellKind>) -> Result<RawCells, MeshError> {
        let (f, off_d, conn_d, nc) = (self.f, self.off_d, self.conn_d, self.nc);
        let conn_len = offsets.last().copied().unwrap_or(0);
        let conn_n = usize::try_from(conn_len)
            .map_err(|_| self.err(off_d.at, format!("the last offset {conn_len} is too large")))?;
        let conn_need = format!("the last offset, {conn_len}");
        f.precheck(conn_d, Some(conn_n), &conn_need)?;
        budget::check(
            format!("the connectivity of {nc} cells ({conn_n} point indices)"),
            budget::times(conn_n as u64, decoded_bytes(conn_d) + 4),
        )
        .map_err(|e| self.err(off_d.at, e.to_string()))?;
        let conn = f.ints(conn_d, Some(conn_n), &conn_need)?;
        let mut cells = RawCells {
            text: true,
            token_base: (conn_d.format == Format::Ascii)
                .then(|| conn_d.text.first().map_or(conn_d.at, |t| t.0)),
            kinds,
            ..RawCells::default()
        };
        let mk = |m: arbvis_core::budget::OverBudget| self.err(self.at, m.into());
        cells.offsets = vec_for(self.nc_usize + 1, "cell offsets").map_err(mk)?;
        cells.at = vec_for(self.nc_usize, "cell positions").map_err(mk)?;
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
                    self.err(
                        conn_d.at,
                        format!("connectivity value {j} is {p}, not a point index (0 to 2^32 - 2)"),
                    )
                })?;
            cells.nodes.push(p);
        }
        Ok(cells)
    }

    /// The points, each coordinate finite.
    fn points(&self) -> Result<Vec<[f64; 3]>, MeshError> {
        let pts = self.pts;
        let coords = self.f.floats(
            pts,
            self.np_usize.checked_mul(3),
            &format!("3 x {}", self.points_need),
        )?;
        if let Some(i) = coords.iter().position(|v| !v.is_finite()) {
            return Err(self.err(
                pts.at,
                format!(
                    "point {} has a coordinate that is not finite ({})",
                    i / 3,
                    coords[i]
                ),
            ));
        }
        Ok(coords.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
    }

    /// The `PointData` and `CellData` arrays, decoded.
    fn data_arrays(&self) -> Result<(Vec<ReadArray>, Vec<ReadArray>), MeshError> {
        let mut point_arrays = Vec::new();
        let mut cell_arrays = Vec::new();
        for d in self.arrays {
            let Some((n, need)) = self.data_need(d) else {
                continue;
            };
            let values = self.f.floats(d, n, &need)?;
            let list = if d.section == Section::PointData {
                &mut point_arrays
            } else {
                &mut cell_arrays
            };
            list.push(ReadArray {
                array: DataArray {
                    name: d.name.clone(),
                    components: d.comps,
                    values,
                },
                at: d.at,
            });
        }
        Ok((point_arrays, cell_arrays))
    }
}

/// The format lines: each encoding the arrays use, compression, header type, byte order.
fn info(f: &File, arrays: &[ArrayDesc], version: String) -> MeshInfo {
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
    MeshInfo {
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
    }
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
