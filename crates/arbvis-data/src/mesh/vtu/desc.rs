//! What the XML scan of a `.vtu` file finds: the file's encoding settings, and each
//! `DataArray` with where it sits (decoded later, by [`super::data`]).

use std::cell::Cell;
use std::path::Path;

use crate::mesh::read::Num;

/// Which element a `DataArray` is in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Section {
    Points,
    Cells,
    PointData,
    CellData,
    Other,
}

/// How a `DataArray` stores its values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Format {
    Ascii,
    Binary,
    Appended,
}

/// One `DataArray` as declared.
#[derive(Debug)]
pub(super) struct ArrayDesc<'a> {
    pub section: Section,
    pub name: String,
    pub ty: Option<Num>,
    pub type_name: String,
    pub comps: usize,
    pub format: Format,
    pub offset: Option<u64>,
    /// The byte where its tag starts.
    pub at: usize,
    /// Its text (ASCII numbers or base64), with positions.
    pub text: Vec<(usize, &'a [u8])>,
}

/// The file and the `<VTKFile>` settings every binary array follows.
pub(super) struct File<'a> {
    pub name: &'a Path,
    pub bytes: &'a [u8],
    pub big: bool,
    pub header: Num,
    pub zlib: bool,
    /// Start of the appended data (after `_`) and whether it is base64.
    pub appended: Option<(usize, bool)>,
    /// The end of the appended data the arrays decoded so far use (to check that the
    /// file goes on to `</AppendedData>` and `</VTKFile>` after it).
    pub appended_end: Cell<usize>,
}

/// The numeric type of a VTK XML type name.
pub(super) fn num_type(t: &[u8]) -> Option<Num> {
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
