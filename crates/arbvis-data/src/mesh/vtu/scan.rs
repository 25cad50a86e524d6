//! The XML scan of a `.vtu` file, up to its appended data: the `<VTKFile>` settings,
//! the `<Piece>` counts and every `DataArray` with its text (decoded later).

use std::borrow::Cow;
use std::cell::Cell;
use std::path::Path;

use quick_xml::events::{BytesStart, Event};

use super::desc::{num_type, ArrayDesc, File, Format, Section};
use crate::mesh::read::{quote, text_error, Num};
use crate::mesh::MeshError;

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

/// What the scan found.
pub(super) struct Scan<'a> {
    /// The file and its `<VTKFile>` settings.
    pub(super) file: File<'a>,
    /// The `version` attribute.
    pub(super) version: String,
    /// Every `DataArray`, in order.
    pub(super) arrays: Vec<ArrayDesc<'a>>,
    /// Open elements and where each starts.
    stack: Vec<(Vec<u8>, usize)>,
    /// The `DataArray` open now.
    current: Option<ArrayDesc<'a>>,
    /// Where `<Piece>` starts, its points and cells.
    piece: Option<(usize, u64, u64)>,
    saw_root: bool,
}

/// Whether the scan goes on after an element.
enum Flow {
    Go,
    Stop,
}

impl<'a> Scan<'a> {
    /// An error at byte `at`, with its line and column.
    fn err(&self, at: usize, m: String) -> MeshError {
        text_error(self.file.name, self.file.bytes, at, m)
    }

    /// Scan `bytes` (named `name`) up to the appended data or the end.
    pub(super) fn run(name: &'a Path, bytes: &'a [u8]) -> Result<Scan<'a>, MeshError> {
        let mut scan = Scan {
            file: File {
                name,
                bytes,
                big: false,
                header: Num::U32,
                zlib: false,
                appended: None,
                appended_end: Cell::new(0),
            },
            version: String::new(),
            arrays: Vec::new(),
            stack: Vec::new(),
            current: None,
            piece: None,
            saw_root: false,
        };
        let mut reader = quick_xml::Reader::from_reader(bytes);
        loop {
            let before = reader.buffer_position() as usize;
            let ev = reader.read_event().map_err(|e| {
                scan.err(
                    reader.error_position() as usize,
                    format!("not well-formed XML: {e}"),
                )
            })?;
            let after = reader.buffer_position() as usize;
            let flow = match ev {
                Event::Start(ref e) => scan.start(e, false, before, after)?,
                Event::Empty(ref e) => scan.start(e, true, before, after)?,
                Event::Text(_) => scan.text(before, after),
                Event::End(ref e) => scan.end(e),
                Event::Eof => return scan.eof(),
                _ => Flow::Go,
            };
            if let Flow::Stop = flow {
                return Ok(scan);
            }
        }
    }

    /// The `<Piece>` found, after a `<VTKFile>`.
    pub(super) fn piece(&self) -> Result<(usize, u64, u64), MeshError> {
        if !self.saw_root {
            return Err(self.err(0, "no <VTKFile> element".into()));
        }
        self.piece
            .ok_or_else(|| self.err(self.file.bytes.len(), "no <Piece> element".into()))
    }

    /// An element opens at `before` (its tag ends at `after`).
    fn start(
        &mut self,
        e: &BytesStart,
        empty: bool,
        before: usize,
        after: usize,
    ) -> Result<Flow, MeshError> {
        let local = e.local_name().as_ref().as_bytes().to_vec();
        match local.as_slice() {
            b"VTKFile" => self.root(e, before)?,
            b"Piece" => self.piece_counts(e, before)?,
            b"AppendedData" => {
                self.appended(e, before, after)?;
                return Ok(Flow::Stop);
            }
            b"DataArray" => {
                let d = self.data_array(e, before)?;
                if empty {
                    self.arrays.push(d);
                } else {
                    self.current = Some(d);
                }
            }
            _ => {}
        }
        if !empty {
            self.stack.push((local, before));
        }
        Ok(Flow::Go)
    }

    /// Text from `before` to `after`: part of the open `DataArray`'s, if any.
    fn text(&mut self, before: usize, after: usize) -> Flow {
        if let Some(d) = self.current.as_mut() {
            if self.stack.last().is_some_and(|s| s.0 == b"DataArray") {
                d.text.push((before, &self.file.bytes[before..after]));
            }
        }
        Flow::Go
    }

    /// An element closes.
    fn end(&mut self, e: &quick_xml::events::BytesEnd) -> Flow {
        self.stack.pop();
        if e.local_name().as_ref() == "DataArray" {
            if let Some(d) = self.current.take() {
                self.arrays.push(d);
            }
        }
        Flow::Go
    }

    /// The end of the file: every element must be closed.
    fn eof(self) -> Result<Scan<'a>, MeshError> {
        if let Some((open, at)) = self.stack.last() {
            let bytes = self.file.bytes;
            return Err(self.err(
                bytes.len(),
                format!(
                    "the file ends inside <{}> (opened at line {}): it is truncated, or an element is never closed",
                    String::from_utf8_lossy(open),
                    crate::mesh::read::line_column(bytes, *at).0
                ),
            ));
        }
        Ok(self)
    }

    /// `<VTKFile>`: an unstructured grid; its version, byte order, header type and
    /// compressor.
    fn root(&mut self, e: &BytesStart, before: usize) -> Result<(), MeshError> {
        self.saw_root = true;
        let kind = attr(e, b"type").unwrap_or_default();
        if kind.as_slice() != b"UnstructuredGrid" {
            return Err(self.err(before, format!(
                "VTKFile type {} is not a volume mesh: arbvis reads type=\"UnstructuredGrid\" (.vtu)",
                quote(&kind)
            )));
        }
        self.version =
            String::from_utf8_lossy(&attr(e, b"version").unwrap_or_default()).into_owned();
        self.file.big = match attr(e, b"byte_order").as_deref() {
            None | Some(b"LittleEndian") => false,
            Some(b"BigEndian") => true,
            Some(o) => {
                return Err(self.err(
                    before,
                    format!(
                        "byte_order {} is neither LittleEndian nor BigEndian",
                        quote(o)
                    ),
                ))
            }
        };
        self.file.header = match attr(e, b"header_type").as_deref() {
            None | Some(b"UInt32") => Num::U32,
            Some(b"UInt64") => Num::U64,
            Some(o) => {
                return Err(self.err(
                    before,
                    format!("header_type {} is neither UInt32 nor UInt64", quote(o)),
                ))
            }
        };
        self.file.zlib = match attr(e, b"compressor").as_deref() {
            None | Some(b"") => false,
            Some(b"vtkZLibDataCompressor") => true,
            Some(o) => return Err(self.err(before, format!(
                "compressor {} is not supported (arbvis reads uncompressed data and vtkZLibDataCompressor)",
                quote(o)
            ))),
        };
        Ok(())
    }

    /// `<Piece>`, the only one: its point and cell counts.
    fn piece_counts(&mut self, e: &BytesStart, before: usize) -> Result<(), MeshError> {
        if self.piece.is_some() {
            return Err(self.err(
                before,
                "more than one <Piece>: arbvis reads single-piece .vtu files".into(),
            ));
        }
        let count = |key: &[u8]| -> Result<u64, MeshError> {
            let v = attr(e, key).ok_or_else(|| {
                self.err(
                    before,
                    format!("<Piece> has no {} attribute", String::from_utf8_lossy(key)),
                )
            })?;
            whole(&v).ok_or_else(|| {
                self.err(
                    before,
                    format!(
                        "{}={} is not a whole number",
                        String::from_utf8_lossy(key),
                        quote(&v)
                    ),
                )
            })
        };
        self.piece = Some((before, count(b"NumberOfPoints")?, count(b"NumberOfCells")?));
        Ok(())
    }

    /// `<AppendedData>`: its encoding, and where its bytes start (after the `_` that
    /// follows the tag ending at `after`).
    fn appended(&mut self, e: &BytesStart, before: usize, after: usize) -> Result<(), MeshError> {
        let bytes = self.file.bytes;
        let enc = attr(e, b"encoding").unwrap_or_default();
        let b64 = match enc.as_slice() {
            b"raw" => false,
            b"base64" => true,
            o => {
                return Err(self.err(
                    before,
                    format!(
                        "AppendedData encoding {} is neither raw nor base64",
                        quote(o)
                    ),
                ))
            }
        };
        let mut p = after;
        while p < bytes.len() && bytes[p].is_ascii_whitespace() {
            p += 1;
        }
        if bytes.get(p) != Some(&b'_') {
            return Err(self.err(p, "expected '_' at the start of the appended data".into()));
        }
        self.file.appended = Some((p + 1, b64));
        Ok(())
    }

    /// A `DataArray` tag: its section, name, type, components, format and offset.
    fn data_array(&self, e: &BytesStart, before: usize) -> Result<ArrayDesc<'a>, MeshError> {
        let section = match self.stack.last().map(|s| s.0.as_slice()) {
            Some(b"Points") => Section::Points,
            Some(b"Cells") => Section::Cells,
            Some(b"PointData") => Section::PointData,
            Some(b"CellData") => Section::CellData,
            _ => Section::Other,
        };
        let type_name = attr(e, b"type").unwrap_or_default();
        let comps = match attr(e, b"NumberOfComponents") {
            None => 1,
            Some(v) => whole(&v)
                .and_then(|k| usize::try_from(k).ok())
                .filter(|&k| (1..=1024).contains(&k))
                .ok_or_else(|| {
                    self.err(
                        before,
                        format!(
                            "NumberOfComponents={} is not a whole number from 1 to 1024",
                            quote(&v)
                        ),
                    )
                })?,
        };
        let format = match attr(e, b"format").as_deref() {
            Some(b"ascii") => Format::Ascii,
            Some(b"binary") => Format::Binary,
            Some(b"appended") => Format::Appended,
            _ if section == Section::Other => Format::Ascii,
            o => {
                return Err(self.err(
                    before,
                    format!(
                        "DataArray format {} is not ascii, binary or appended",
                        quote(o.unwrap_or(b"(missing)"))
                    ),
                ))
            }
        };
        let offset = match attr(e, b"offset") {
            None => None,
            Some(v) => Some(whole(&v).ok_or_else(|| {
                self.err(
                    before,
                    format!("offset={} is not a whole number", quote(&v)),
                )
            })?),
        };
        Ok(ArrayDesc {
            section,
            name: String::from_utf8_lossy(&attr(e, b"Name").unwrap_or_default()).into_owned(),
            ty: num_type(&type_name),
            type_name: String::from_utf8_lossy(&type_name).into_owned(),
            comps,
            format,
            offset,
            at: before,
            text: Vec::new(),
        })
    }
}

/// An attribute's whole number (spaces around allowed).
fn whole(v: &[u8]) -> Option<u64> {
    std::str::from_utf8(v)
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok())
}
