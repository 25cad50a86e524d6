//! VTK XML unstructured grids (`.vtu`, `<VTKFile type="UnstructuredGrid">`), one piece.
//!
//! The XML is read with `quick-xml` up to the `<AppendedData>` element, whose raw bytes
//! follow the `_` marker and are never given to the XML parser. Each `DataArray` of
//! `Points`, `Cells` (`connectivity`, `offsets`, `types`), `PointData` and `CellData` is
//! decoded from:
//! - `format="ascii"`: whitespace-separated numbers in the element;
//! - `format="binary"`: base64 in the element, whitespace ignored;
//! - `format="appended"`: at `offset` in the appended data, `encoding="raw"` or `"base64"`.
//!
//! Binary data start with a header of `header_type` integers (`UInt32`, the default, or
//! `UInt64`) in the file's `byte_order`: uncompressed, the byte count; with
//! `compressor="vtkZLibDataCompressor"`, the block count `n`, the uncompressed block size,
//! the size of the last block (0: a full block) and the `n` compressed sizes, followed by
//! the zlib blocks. In base64, VTK encodes the header and the data separately (the header
//! ends in `=` padding); other writers encode them together; both are read. Every
//! declared size is checked before anything is allocated: a block may not declare more
//! than 1032 bytes per compressed byte (the most deflate can produce), and inflation stops
//! one byte past the declared size, which is then an error.
//!
//! Decisions: `offsets` are end offsets (one per cell, VTK XML's convention); arrays in
//! `FieldData` and other elements are not decoded; more than one `<Piece>`, other dataset
//! types and other compressors (LZ4, LZMA) are refused by name. Positions inside base64
//! or compressed data cannot be mapped back to the file: such errors give the position
//! of the `DataArray` tag and the index of the value.

mod data;

use std::borrow::Cow;
use std::path::Path;

use quick_xml::events::{BytesStart, Event};

use super::cells::{vtk_kind, RawCells};
use super::read::{quote, text_error, vec_for, Num};
use super::{DataArray, Mesh, MeshError, MeshInfo};

#[derive(Debug, Clone, Copy, PartialEq)]
enum Section {
    Points,
    Cells,
    PointData,
    CellData,
    Other,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Binary,
    Appended,
}

#[derive(Debug)]
struct ArrayDesc<'a> {
    section: Section,
    name: String,
    ty: Option<Num>,
    type_name: String,
    comps: usize,
    format: Format,
    offset: Option<u64>,
    at: usize,
    text: Vec<(usize, &'a [u8])>,
}

struct File<'a> {
    name: &'a Path,
    bytes: &'a [u8],
    big: bool,
    header: Num,
    zlib: bool,
    /// Start of the appended data (after `_`) and whether it is base64.
    appended: Option<(usize, bool)>,
}

fn num_type(t: &[u8]) -> Option<Num> {
    Some(match t {
        b"Int8" | b"Char" => Num::I8,
        b"UInt8" | b"UChar" => Num::U8,
        b"Int16" | b"Short" => Num::I16,
        b"UInt16" | b"UShort" => Num::U16,
        b"Int32" | b"Int" => Num::I32,
        b"UInt32" | b"UInt" => Num::U32,
        b"Int64" | b"Long" | b"IdType" => Num::I64,
        b"UInt64" | b"ULong" => Num::U64,
        b"Float32" | b"Float" => Num::F32,
        b"Float64" | b"Double" => Num::F64,
        _ => return None,
    })
}

/// Attribute `key` of `e`, raw.
fn attr(e: &BytesStart, key: &[u8]) -> Option<Vec<u8>> {
    e.attributes()
        .with_checks(false)
        .flatten()
        .find(|a| a.key.local_name().as_ref().as_bytes() == key)
        .map(|a| match a.value {
            Cow::Borrowed(s) => s.as_bytes().to_vec(),
            Cow::Owned(s) => s.into_bytes(),
        })
}

/// Parse a `.vtu` file held in memory; `name` is used in errors.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    let terr = |at: usize, m: String| text_error(name, bytes, at, m);
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut f = File {
        name,
        bytes,
        big: false,
        header: Num::U32,
        zlib: false,
        appended: None,
    };
    let mut version = String::new();
    let mut stack: Vec<Vec<u8>> = Vec::new();
    let mut arrays: Vec<ArrayDesc> = Vec::new();
    let mut current: Option<ArrayDesc> = None;
    let mut piece: Option<(usize, u64, u64)> = None;
    let mut saw_root = false;
    loop {
        let before = reader.buffer_position() as usize;
        let ev = reader.read_event().map_err(|e| {
            terr(
                reader.error_position() as usize,
                format!("not well-formed XML: {e}"),
            )
        })?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let empty = matches!(ev, Event::Empty(_));
                let local = e.local_name().as_ref().as_bytes().to_vec();
                match local.as_slice() {
                    b"VTKFile" => {
                        saw_root = true;
                        let kind = attr(e, b"type").unwrap_or_default();
                        if kind.as_slice() != b"UnstructuredGrid" {
                            return Err(terr(before, format!(
                                "VTKFile type {} is not a volume mesh: arbvis reads type=\"UnstructuredGrid\" (.vtu)",
                                quote(&kind)
                            )));
                        }
                        version = String::from_utf8_lossy(&attr(e, b"version").unwrap_or_default())
                            .into_owned();
                        f.big = match attr(e, b"byte_order").as_deref() {
                            None | Some(b"LittleEndian") => false,
                            Some(b"BigEndian") => true,
                            Some(o) => {
                                return Err(terr(
                                    before,
                                    format!(
                                        "byte_order {} is neither LittleEndian nor BigEndian",
                                        quote(o)
                                    ),
                                ))
                            }
                        };
                        f.header = match attr(e, b"header_type").as_deref() {
                            None | Some(b"UInt32") => Num::U32,
                            Some(b"UInt64") => Num::U64,
                            Some(o) => {
                                return Err(terr(
                                    before,
                                    format!(
                                        "header_type {} is neither UInt32 nor UInt64",
                                        quote(o)
                                    ),
                                ))
                            }
                        };
                        f.zlib = match attr(e, b"compressor").as_deref() {
                            None | Some(b"") => false,
                            Some(b"vtkZLibDataCompressor") => true,
                            Some(o) => return Err(terr(before, format!(
                                "compressor {} is not supported (arbvis reads uncompressed data and vtkZLibDataCompressor)",
                                quote(o)
                            ))),
                        };
                    }
                    b"Piece" => {
                        if piece.is_some() {
                            return Err(terr(
                                before,
                                "more than one <Piece>: arbvis reads single-piece .vtu files"
                                    .into(),
                            ));
                        }
                        let count = |key: &[u8]| -> Result<u64, MeshError> {
                            let v = attr(e, key).ok_or_else(|| {
                                terr(
                                    before,
                                    format!(
                                        "<Piece> has no {} attribute",
                                        String::from_utf8_lossy(key)
                                    ),
                                )
                            })?;
                            std::str::from_utf8(&v)
                                .ok()
                                .and_then(|s| s.trim().parse::<u64>().ok())
                                .ok_or_else(|| {
                                    terr(
                                        before,
                                        format!(
                                            "{}={} is not a whole number",
                                            String::from_utf8_lossy(key),
                                            quote(&v)
                                        ),
                                    )
                                })
                        };
                        piece = Some((before, count(b"NumberOfPoints")?, count(b"NumberOfCells")?));
                    }
                    b"AppendedData" => {
                        let enc = attr(e, b"encoding").unwrap_or_default();
                        let b64 = match enc.as_slice() {
                            b"raw" => false,
                            b"base64" => true,
                            o => {
                                return Err(terr(
                                    before,
                                    format!(
                                        "AppendedData encoding {} is neither raw nor base64",
                                        quote(o)
                                    ),
                                ))
                            }
                        };
                        let mut p = reader.buffer_position() as usize;
                        while p < bytes.len() && bytes[p].is_ascii_whitespace() {
                            p += 1;
                        }
                        if bytes.get(p) != Some(&b'_') {
                            return Err(terr(
                                p,
                                "expected '_' at the start of the appended data".into(),
                            ));
                        }
                        f.appended = Some((p + 1, b64));
                        break;
                    }
                    b"DataArray" => {
                        let section = match stack.last().map(|s| s.as_slice()) {
                            Some(b"Points") => Section::Points,
                            Some(b"Cells") => Section::Cells,
                            Some(b"PointData") => Section::PointData,
                            Some(b"CellData") => Section::CellData,
                            _ => Section::Other,
                        };
                        let type_name = attr(e, b"type").unwrap_or_default();
                        let comps = match attr(e, b"NumberOfComponents") {
                            None => 1,
                            Some(v) => std::str::from_utf8(&v).ok().and_then(|s| s.trim().parse::<usize>().ok()).filter(|&k| (1..=1024).contains(&k)).ok_or_else(|| {
                                terr(before, format!("NumberOfComponents={} is not a whole number from 1 to 1024", quote(&v)))
                            })?,
                        };
                        let format = match attr(e, b"format").as_deref() {
                            Some(b"ascii") => Format::Ascii,
                            Some(b"binary") => Format::Binary,
                            Some(b"appended") => Format::Appended,
                            o => {
                                if section == Section::Other {
                                    Format::Ascii
                                } else {
                                    return Err(terr(
                                        before,
                                        format!(
                                            "DataArray format {} is not ascii, binary or appended",
                                            quote(o.unwrap_or(b"(missing)"))
                                        ),
                                    ));
                                }
                            }
                        };
                        let offset = match attr(e, b"offset") {
                            None => None,
                            Some(v) => Some(
                                std::str::from_utf8(&v)
                                    .ok()
                                    .and_then(|s| s.trim().parse::<u64>().ok())
                                    .ok_or_else(|| {
                                        terr(
                                            before,
                                            format!("offset={} is not a whole number", quote(&v)),
                                        )
                                    })?,
                            ),
                        };
                        let d = ArrayDesc {
                            section,
                            name: String::from_utf8_lossy(&attr(e, b"Name").unwrap_or_default())
                                .into_owned(),
                            ty: num_type(&type_name),
                            type_name: String::from_utf8_lossy(&type_name).into_owned(),
                            comps,
                            format,
                            offset,
                            at: before,
                            text: Vec::new(),
                        };
                        if empty {
                            arrays.push(d);
                        } else {
                            current = Some(d);
                        }
                    }
                    _ => {}
                }
                if !empty {
                    stack.push(local);
                }
            }
            Event::Text(_) => {
                if let Some(d) = current.as_mut() {
                    if stack.last().is_some_and(|s| s == b"DataArray") {
                        let end = reader.buffer_position() as usize;
                        d.text.push((before, &bytes[before..end]));
                    }
                }
            }
            Event::End(ref e) => {
                stack.pop();
                if e.local_name().as_ref() == "DataArray" {
                    if let Some(d) = current.take() {
                        arrays.push(d);
                    }
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !saw_root {
        return Err(terr(0, "no <VTKFile> element".into()));
    }
    let (piece_at, np, nc) = piece.ok_or_else(|| terr(bytes.len(), "no <Piece> element".into()))?;
    build(&f, &arrays, piece_at, np, nc, version)
}

fn build(
    f: &File,
    arrays: &[ArrayDesc],
    piece_at: usize,
    np: u64,
    nc: u64,
    version: String,
) -> Result<Mesh, MeshError> {
    let terr = |at: usize, m: String| text_error(f.name, f.bytes, at, m);
    let find = |section: Section, name: Option<&str>, what: &str| {
        arrays
            .iter()
            .find(|d| d.section == section && name.is_none_or(|n| d.name == n))
            .ok_or_else(|| terr(piece_at, format!("the piece has no {what} DataArray")))
    };
    let pts = find(Section::Points, None, "Points")?;
    if pts.comps != 3 {
        return Err(terr(
            pts.at,
            format!("Points have {} components, expected 3", pts.comps),
        ));
    }
    let np_usize = usize::try_from(np)
        .map_err(|_| terr(piece_at, format!("NumberOfPoints={np} is too large")))?;
    let nc_usize = usize::try_from(nc)
        .map_err(|_| terr(piece_at, format!("NumberOfCells={nc} is too large")))?;
    let coords = f.floats(pts, np_usize.checked_mul(3))?;
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

    let off_d = find(Section::Cells, Some("offsets"), "Cells offsets")?;
    let offsets = f.ints(off_d, Some(nc_usize))?;
    let conn_len = offsets.last().copied().unwrap_or(0);
    let mut prev = 0;
    for (i, &o) in offsets.iter().enumerate() {
        if o < prev {
            return Err(terr(off_d.at, format!("offset {i} is {o}, less than the one before ({prev}): offsets must not decrease")));
        }
        prev = o;
    }
    let conn_d = find(Section::Cells, Some("connectivity"), "Cells connectivity")?;
    let conn_n = usize::try_from(conn_len)
        .map_err(|_| terr(off_d.at, format!("the last offset {conn_len} is too large")))?;
    let conn = f.ints(conn_d, Some(conn_n))?;
    let types_d = find(Section::Cells, Some("types"), "Cells types")?;
    let types = f.ints(types_d, Some(nc_usize))?;

    let mut cells = RawCells {
        text: true,
        token_base: (conn_d.format == Format::Ascii)
            .then(|| conn_d.text.first().map_or(conn_d.at, |t| t.0)),
        ..RawCells::default()
    };
    let mk = |m: String| terr(piece_at, m);
    cells.kinds = vec_for(nc_usize, "cell types").map_err(mk)?;
    cells.offsets = vec_for(nc_usize + 1, "cell offsets").map_err(mk)?;
    cells.at = vec_for(nc_usize, "cell positions").map_err(mk)?;
    cells.nodes = vec_for(conn.len(), "cell nodes").map_err(mk)?;
    cells.offsets.push(0);
    for (i, (&t, &o)) in types.iter().zip(&offsets).enumerate() {
        cells
            .kinds
            .push(vtk_kind(t).map_err(|m| terr(types_d.at, format!("cell {i}: {m}")))?);
        let start = *cells.offsets.last().unwrap_or(&0);
        cells.at.push(if cells.token_base.is_some() {
            start
        } else {
            conn_d.at
        });
        cells.offsets.push(o as usize);
    }
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
    let mut point_arrays = Vec::new();
    let mut cell_arrays = Vec::new();
    for d in arrays {
        let (list, n) = match d.section {
            Section::PointData => (&mut point_arrays, np_usize),
            Section::CellData => (&mut cell_arrays, nc_usize),
            _ => continue,
        };
        let values = f.floats(d, n.checked_mul(d.comps))?;
        list.push(DataArray {
            name: d.name.clone(),
            components: d.comps,
            values,
        });
    }
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
