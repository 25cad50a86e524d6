//! A general PLY reader (Turk's polygon file format): every element of the file with
//! its scalar and list properties by name, stored by column. The point loader
//! ([`super::plycloud`]) takes the `vertex` element; a triangle-surface loader takes the
//! `face` element the same way:
//!
//! ```no_run
//! # use std::path::Path;
//! # fn f() -> Result<(), arbvis_data::points::PointsError> {
//! use arbvis_data::points::ply;
//! let ply = ply::read(Path::new("bunny.ply"))?;
//! let vertex = ply.element("vertex").expect("a vertex element");
//! let (x, y, z) = (vertex.scalar("x"), vertex.scalar("y"), vertex.scalar("z"));
//! if let Some(faces) = ply.element("face").and_then(|f| f.face_indices()) {
//!     for polygon in faces.iter() {
//!         // `polygon` is `&[f64]`: vertex indices, exact integers of the file's
//!         // list type; check each against `vertex.count` before using it.
//!     }
//! }
//! # Ok(()) }
//! ```
//!
//! Decisions:
//! - **Formats**: `ascii`, `binary_little_endian`, `binary_big_endian`, version 1.0
//!   (others are refused). `comment` and `obj_info` lines are kept; header lines may end
//!   in `\r\n`.
//! - **Types**: `char uchar short ushort int uint float double` and their aliases
//!   `int8 uint8 int16 uint16 int32 uint32 float32 float64`. Every value is stored as
//!   f64, which holds every PLY type exactly: one column type serves all (8 bytes a
//!   value; floats are rounded to f32 first, so an ASCII `float` reads as the binary one
//!   would). List counts must be of an integer type and not negative.
//! - **ASCII data** is a stream of whitespace-separated values (rows need not be one per
//!   line). Integers may be written `3` or `3.0`; a value out of its type's range, or
//!   not a number, is an error with line and column.
//! - **Bounds**: before an element's columns are allocated its declared row count is
//!   checked against the bytes left (each row needs at least its scalars' and list
//!   counts' bytes in binary, two characters a value in ASCII), and each list's length
//!   against the bytes left, so a hostile count fails at once. Data after the last
//!   element is an error (it usually means a wrong header).
//! - **Non-finite floats** are kept; each property records where its first one was
//!   ([`Property::first_non_finite`]) so a loader that refuses them can say where.
//! - **Why by hand**: `ply-rs` is unmaintained; its maintained fork `ply-rs-bw` (4.x)
//!   reads every format and type and caps preallocation, but its generic element is one
//!   hash map per row (hundreds of bytes per vertex, against 8 per value here) and its
//!   errors give a line but no byte offset in binary data.

use std::fmt;
use std::path::Path;

use super::{read_file, PointsError};

mod data;
mod header;

/// Data encoding of a PLY file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0`.
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`.
    BinaryBigEndian,
}

impl Encoding {
    /// The header's name of the encoding.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

/// PLY scalar types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScalarType {
    /// `char` / `int8`.
    Char,
    /// `uchar` / `uint8`.
    UChar,
    /// `short` / `int16`.
    Short,
    /// `ushort` / `uint16`.
    UShort,
    /// `int` / `int32`.
    Int,
    /// `uint` / `uint32`.
    UInt,
    /// `float` / `float32`.
    Float,
    /// `double` / `float64`.
    Double,
}

impl ScalarType {
    /// The type called `name` in a header.
    pub fn from_name(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::Char,
            "uchar" | "uint8" => ScalarType::UChar,
            "short" | "int16" => ScalarType::Short,
            "ushort" | "uint16" => ScalarType::UShort,
            "int" | "int32" => ScalarType::Int,
            "uint" | "uint32" => ScalarType::UInt,
            "float" | "float32" => ScalarType::Float,
            "double" | "float64" => ScalarType::Double,
            _ => return None,
        })
    }

    /// Bytes in binary files.
    pub fn size(self) -> usize {
        match self {
            ScalarType::Char | ScalarType::UChar => 1,
            ScalarType::Short | ScalarType::UShort => 2,
            ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
            ScalarType::Double => 8,
        }
    }

    /// True for the integer types.
    pub fn is_integer(self) -> bool {
        !matches!(self, ScalarType::Float | ScalarType::Double)
    }

    /// Smallest and largest value of an integer type.
    fn range(self) -> (f64, f64) {
        match self {
            ScalarType::Char => (i8::MIN as f64, i8::MAX as f64),
            ScalarType::UChar => (0.0, u8::MAX as f64),
            ScalarType::Short => (i16::MIN as f64, i16::MAX as f64),
            ScalarType::UShort => (0.0, u16::MAX as f64),
            ScalarType::Int => (i32::MIN as f64, i32::MAX as f64),
            ScalarType::UInt => (0.0, u32::MAX as f64),
            ScalarType::Float | ScalarType::Double => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }

    /// Decode one value from exactly [`ScalarType::size`] bytes.
    fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            ScalarType::Char => b[0] as i8 as f64,
            ScalarType::UChar => b[0] as f64,
            ScalarType::Short => num!(i16, 2) as f64,
            ScalarType::UShort => num!(u16, 2) as f64,
            ScalarType::Int => num!(i32, 4) as f64,
            ScalarType::UInt => num!(u32, 4) as f64,
            ScalarType::Float => num!(f32, 4) as f64,
            ScalarType::Double => num!(f64, 8),
        }
    }
}

/// Where a value is in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Position {
    /// Byte offset in a binary file.
    Byte(u64),
    /// Line and column (1-based) in an ASCII file.
    Line {
        /// Line.
        line: usize,
        /// Column.
        column: usize,
    },
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Byte(b) => write!(f, "byte {b}"),
            Position::Line { line, column } => write!(f, "line {line}, column {column}"),
        }
    }
}

/// Variable-length lists of one property, stored end to end.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Lists {
    /// `offsets[i]..offsets[i + 1]` is row `i`'s range in `values`.
    offsets: Vec<usize>,
    values: Vec<f64>,
}

impl Lists {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True with no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i`'s values.
    pub fn get(&self, i: usize) -> Option<&[f64]> {
        let (&a, &b) = (self.offsets.get(i)?, self.offsets.get(i + 1)?);
        self.values.get(a..b)
    }

    /// Every row in order.
    pub fn iter(&self) -> impl Iterator<Item = &[f64]> + '_ {
        self.offsets.windows(2).map(|w| &self.values[w[0]..w[1]])
    }

    /// All values of all rows, end to end.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

/// A property's values.
#[derive(Debug, Clone, PartialEq)]
pub enum PropertyData {
    /// One value per row.
    Scalar {
        /// Type in the file.
        ty: ScalarType,
        /// One value per row.
        values: Vec<f64>,
    },
    /// One list per row.
    List {
        /// Type of the length.
        count: ScalarType,
        /// Type of the items.
        item: ScalarType,
        /// The lists.
        lists: Lists,
    },
}

/// One property of an element.
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    /// Name.
    pub name: String,
    /// Values.
    pub data: PropertyData,
    /// Row and position of the first NaN or infinite value, if any.
    pub first_non_finite: Option<(usize, Position)>,
    /// Where the header declares it (the line and column of its name).
    pub declared: Position,
}

/// One element (`vertex`, `face`, ...) with its rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Name.
    pub name: String,
    /// Rows.
    pub count: usize,
    /// Properties in header order.
    pub properties: Vec<Property>,
    /// Where its data starts.
    pub start: Position,
    /// Where the header declares it (the line and column of its row count).
    pub declared: Position,
}

impl Element {
    /// The property called `name`.
    pub fn property(&self, name: &str) -> Option<&Property> {
        self.properties.iter().find(|p| p.name == name)
    }

    /// The values of scalar property `name`.
    pub fn scalar(&self, name: &str) -> Option<&[f64]> {
        match &self.property(name)?.data {
            PropertyData::Scalar { values, .. } => Some(values),
            PropertyData::List { .. } => None,
        }
    }

    /// The lists of list property `name`.
    pub fn list(&self, name: &str) -> Option<&Lists> {
        match &self.property(name)?.data {
            PropertyData::List { lists, .. } => Some(lists),
            PropertyData::Scalar { .. } => None,
        }
    }

    /// A face element's polygons: its `vertex_indices` list, or `vertex_index` as some
    /// writers name it.
    pub fn face_indices(&self) -> Option<&Lists> {
        self.list("vertex_indices")
            .or_else(|| self.list("vertex_index"))
    }
}

/// A whole PLY file.
#[derive(Debug, Clone, PartialEq)]
pub struct Ply {
    /// Data encoding.
    pub encoding: Encoding,
    /// The format line's version (`1.0`).
    pub version: String,
    /// `comment` lines, without the keyword.
    pub comments: Vec<String>,
    /// `obj_info` lines, without the keyword.
    pub obj_info: Vec<String>,
    /// Elements in file order.
    pub elements: Vec<Element>,
}

impl Ply {
    /// The element called `name`.
    pub fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }
}

/// Read a PLY file.
pub fn read(path: &Path) -> Result<Ply, PointsError> {
    let bytes = read_file(path)?;
    parse(path, &bytes)
}

/// Parse PLY bytes named `name`.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Ply, PointsError> {
    let header = header::parse(name, bytes)?;
    let elements = match header.encoding {
        Encoding::Ascii => data::read_ascii(name, bytes, &header)?,
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            data::read_binary(name, bytes, &header)?
        }
    };
    Ok(Ply {
        encoding: header.encoding,
        version: header.version,
        comments: header.comments,
        obj_info: header.obj_info,
        elements,
    })
}

#[cfg(test)]
pub(crate) mod tests;
