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

mod assemble;
mod data;
mod desc;

use std::borrow::Cow;
use std::cell::Cell;
use std::path::Path;

use quick_xml::events::{BytesStart, Event};

use self::desc::{num_type, ArrayDesc, File, Format, Section};
use super::read::{quote, text_error, Num};
use super::{Mesh, MeshError};

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
        appended_end: Cell::new(0),
    };
    let mut version = String::new();
    // Open elements and where each starts.
    let mut stack: Vec<(Vec<u8>, usize)> = Vec::new();
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
                        let section = match stack.last().map(|s| s.0.as_slice()) {
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
                    stack.push((local, before));
                }
            }
            Event::Text(_) => {
                if let Some(d) = current.as_mut() {
                    if stack.last().is_some_and(|s| s.0 == b"DataArray") {
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
            Event::Eof => {
                if let Some((open, at)) = stack.last() {
                    return Err(terr(
                        bytes.len(),
                        format!(
                            "the file ends inside <{}> (opened at line {}): it is truncated, or an element is never closed",
                            String::from_utf8_lossy(open),
                            super::read::line_column(bytes, *at).0
                        ),
                    ));
                }
                break;
            }
            _ => {}
        }
    }
    if !saw_root {
        return Err(terr(0, "no <VTKFile> element".into()));
    }
    let (piece_at, np, nc) = piece.ok_or_else(|| terr(bytes.len(), "no <Piece> element".into()))?;
    assemble::build(&f, &arrays, piece_at, np, nc, version)
}
