//! A general PLY reader (Turk's polygon file format): every element of the file with
//! its scalar and list properties by name, stored by column. The point loader
//! ([`super::plycloud`]) takes the `vertex` element; a triangle-surface loader takes the
//! `face` element the same way:
//!
//! ```no_run
//! # use std::path::Path;
//! # fn f() -> Result<(), arbvis::points::PointsError> {
//! use arbvis::points::ply;
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

use super::progress::Progress;
use super::{read_file, PointsError};

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

/// A property as declared in the header.
struct Declared {
    name: String,
    /// `Some(count type)` for lists.
    count: Option<ScalarType>,
    ty: ScalarType,
}

struct DeclaredElement {
    name: String,
    count: usize,
    properties: Vec<Declared>,
}

struct Header {
    encoding: Encoding,
    version: String,
    comments: Vec<String>,
    obj_info: Vec<String>,
    elements: Vec<DeclaredElement>,
    /// Byte where the data starts.
    data: usize,
    /// Line where the data starts (for ASCII).
    data_line: usize,
}

/// Parse PLY bytes named `name`.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Ply, PointsError> {
    let header = parse_header(name, bytes)?;
    let mut elements = Vec::with_capacity(header.elements.len());
    match header.encoding {
        Encoding::Ascii => {
            let mut tokens = Tokens {
                bytes,
                pos: header.data,
                line: header.data_line,
                line_start: header.data,
            };
            for e in &header.elements {
                elements.push(ascii_element(name, e, &mut tokens)?);
            }
            tokens.skip_space();
            if tokens.pos < bytes.len() {
                let (line, column) = tokens.here();
                return Err(PointsError::text(
                    name,
                    line,
                    column,
                    "more values than the header declares after the last element",
                ));
            }
        }
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let big = header.encoding == Encoding::BinaryBigEndian;
            let mut pos = header.data;
            for e in &header.elements {
                elements.push(binary_element(name, e, bytes, &mut pos, big)?);
            }
            if pos < bytes.len() {
                return Err(PointsError::format(
                    name,
                    pos as u64,
                    format!(
                        "{} bytes after the last element: the header declares less data than the file holds",
                        bytes.len() - pos
                    ),
                ));
            }
        }
    }
    Ok(Ply {
        encoding: header.encoding,
        version: header.version,
        comments: header.comments,
        obj_info: header.obj_info,
        elements,
    })
}

fn parse_header(name: &Path, bytes: &[u8]) -> Result<Header, PointsError> {
    let mut header = Header {
        encoding: Encoding::Ascii,
        version: String::new(),
        comments: Vec::new(),
        obj_info: Vec::new(),
        elements: Vec::new(),
        data: 0,
        data_line: 0,
    };
    let mut format_seen = false;
    let mut pos = 0;
    let mut number = 0;
    loop {
        number += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(PointsError::text(
                name,
                number,
                1,
                if number == 1 {
                    "not a PLY file: no \"ply\" line".to_string()
                } else {
                    "the file ends inside the header: no \"end_header\" line".to_string()
                },
            ));
        };
        let raw = &bytes[pos..pos + len];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        pos += len + 1;
        let err = |column: usize, message: String| PointsError::text(name, number, column, message);
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(err(1, "the header holds bytes that are not text".into()));
        };
        let words: Vec<(usize, &str)> = words(line);
        let word = |i: usize| words.get(i).map_or("", |w| w.1);
        let col = |i: usize| words.get(i).map_or(line.chars().count() + 1, |w| w.0);
        if number == 1 {
            if line.trim_end() != "ply" {
                return Err(err(
                    1,
                    format!(
                        "not a PLY file: expected \"ply\" on the first line, found \"{}\"",
                        crate::input::shorten(line, 40)
                    ),
                ));
            }
            continue;
        }
        match word(0) {
            "format" => {
                header.encoding = match word(1) {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    other => {
                        return Err(err(
                            col(1),
                            format!(
                                "expected ascii, binary_little_endian or binary_big_endian, found \"{}\"",
                                crate::input::shorten(other, 40)
                            ),
                        ))
                    }
                };
                if word(2) != "1.0" {
                    return Err(err(
                        col(2),
                        format!(
                            "expected format version 1.0, found \"{}\"",
                            crate::input::shorten(word(2), 40)
                        ),
                    ));
                }
                header.version = word(2).to_string();
                format_seen = true;
            }
            "comment" => header.comments.push(rest(line, "comment")),
            "obj_info" => header.obj_info.push(rest(line, "obj_info")),
            "element" => {
                let count = word(2).parse::<usize>().map_err(|_| {
                    err(
                        col(2),
                        format!(
                            "expected the element's row count, found \"{}\"",
                            crate::input::shorten(word(2), 40)
                        ),
                    )
                })?;
                if word(1).is_empty() || words.len() != 3 {
                    return Err(err(1, "expected \"element NAME COUNT\"".into()));
                }
                if header.elements.iter().any(|e| e.name == word(1)) {
                    return Err(err(col(1), format!("element {} is declared twice", word(1))));
                }
                header.elements.push(DeclaredElement {
                    name: word(1).to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            "property" => {
                let Some(element) = header.elements.last_mut() else {
                    return Err(err(1, "a property before any element".into()));
                };
                let ty = |i: usize| {
                    ScalarType::from_name(word(i)).ok_or_else(|| {
                        err(
                            col(i),
                            format!(
                                "expected a PLY type (char, uchar, short, ushort, int, uint, float, double or int8 .. float64), found \"{}\"",
                                crate::input::shorten(word(i), 40)
                            ),
                        )
                    })
                };
                let (declared, n) = if word(1) == "list" {
                    let count = ty(2)?;
                    if !count.is_integer() {
                        return Err(err(
                            col(2),
                            format!("a list's length must have an integer type, found {}", word(2)),
                        ));
                    }
                    (
                        Declared {
                            name: word(4).to_string(),
                            count: Some(count),
                            ty: ty(3)?,
                        },
                        5,
                    )
                } else {
                    (
                        Declared {
                            name: word(2).to_string(),
                            count: None,
                            ty: ty(1)?,
                        },
                        3,
                    )
                };
                if words.len() != n {
                    return Err(err(
                        1,
                        "expected \"property TYPE NAME\" or \"property list COUNT_TYPE ITEM_TYPE NAME\"".into(),
                    ));
                }
                if element.properties.iter().any(|p| p.name == declared.name) {
                    return Err(err(
                        col(n - 1),
                        format!(
                            "property {} of element {} is declared twice",
                            declared.name, element.name
                        ),
                    ));
                }
                element.properties.push(declared);
            }
            "end_header" => {
                if !format_seen {
                    return Err(err(1, "end_header before any format line".into()));
                }
                header.data = pos;
                header.data_line = number + 1;
                return Ok(header);
            }
            "" => return Err(err(1, "an empty line in the header".into())),
            other => {
                return Err(err(
                    1,
                    format!(
                        "expected format, comment, obj_info, element, property or end_header, found \"{}\"",
                        crate::input::shorten(other, 40)
                    ),
                ))
            }
        }
    }
}

/// Words of a header line with their 1-based columns.
fn words(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (column, (i, c)) in line.char_indices().enumerate() {
        match (c.is_whitespace(), start) {
            (false, None) => start = Some((column + 1, i)),
            (true, Some((col, s))) => {
                out.push((col, &line[s..i]));
                start = None;
            }
            _ => {}
        }
    }
    if let Some((col, s)) = start {
        out.push((col, &line[s..]));
    }
    out
}

fn rest(line: &str, keyword: &str) -> String {
    line.trim_start()
        .strip_prefix(keyword)
        .unwrap_or("")
        .trim_start()
        .to_string()
}

/// Empty columns for `e`, reserved for its rows (the caller checked the count).
fn columns(name: &Path, e: &DeclaredElement) -> Result<Vec<Property>, PointsError> {
    let fail = |_| {
        PointsError::Invalid(format!(
            "{}: cannot allocate memory for {} rows of element {}",
            name.display(),
            e.count,
            e.name
        ))
    };
    e.properties
        .iter()
        .map(|d| {
            let data = match d.count {
                None => {
                    let mut values = Vec::new();
                    values.try_reserve_exact(e.count).map_err(fail)?;
                    PropertyData::Scalar { ty: d.ty, values }
                }
                Some(count) => {
                    let mut offsets = Vec::new();
                    offsets.try_reserve_exact(e.count + 1).map_err(fail)?;
                    offsets.push(0);
                    PropertyData::List {
                        count,
                        item: d.ty,
                        lists: Lists {
                            offsets,
                            values: Vec::new(),
                        },
                    }
                }
            };
            Ok(Property {
                name: d.name.clone(),
                data,
                first_non_finite: None,
            })
        })
        .collect()
}

fn binary_element(
    name: &Path,
    e: &DeclaredElement,
    bytes: &[u8],
    pos: &mut usize,
    big: bool,
) -> Result<Element, PointsError> {
    let start = *pos;
    let min_row: usize = e
        .properties
        .iter()
        .map(|p| p.count.unwrap_or(p.ty).size())
        .sum();
    let left = bytes.len() - start;
    let need = e.count.checked_mul(min_row);
    if need.is_none_or(|n| n > left) {
        return Err(PointsError::format(
            name,
            start as u64,
            format!(
                "element {} declares {} rows of at least {min_row} bytes, but only {left} bytes remain",
                e.name, e.count
            ),
        ));
    }
    let mut properties = columns(name, e)?;
    let count = if min_row == 0 { 0 } else { e.count };
    let progress = Progress::new(count as u64, &format!("reading {}", name.display()));
    for row in 0..count {
        if row % 65_536 == 65_535 {
            progress.inc(65_536);
        }
        for (d, p) in e.properties.iter().zip(properties.iter_mut()) {
            let at = *pos;
            let value = |ty: ScalarType, at: usize| -> Result<f64, PointsError> {
                bytes
                    .get(at..at + ty.size())
                    .map(|b| ty.decode(b, big))
                    .ok_or_else(|| {
                        PointsError::format(
                            name,
                            at as u64,
                            format!(
                                "element {} row {row} property {}: the file ends ({} bytes needed, {} left)",
                                e.name,
                                d.name,
                                ty.size(),
                                bytes.len() - at.min(bytes.len())
                            ),
                        )
                    })
            };
            match &mut p.data {
                PropertyData::Scalar { ty, values } => {
                    let v = value(*ty, at)?;
                    *pos += ty.size();
                    if !v.is_finite() && p.first_non_finite.is_none() {
                        p.first_non_finite = Some((row, Position::Byte(at as u64)));
                    }
                    values.push(v);
                }
                PropertyData::List { count, item, lists } => {
                    let n = value(*count, at)?;
                    *pos += count.size();
                    let left = bytes.len() - *pos;
                    if n < 0.0 || n * item.size() as f64 > left as f64 {
                        return Err(PointsError::format(
                            name,
                            at as u64,
                            format!(
                                "element {} row {row} property {}: a list of {n} items of {} bytes, but only {left} bytes remain",
                                e.name,
                                d.name,
                                item.size()
                            ),
                        ));
                    }
                    for _ in 0..n as usize {
                        let v = value(*item, *pos)?;
                        *pos += item.size();
                        lists.values.push(v);
                    }
                    lists.offsets.push(lists.values.len());
                }
            }
        }
    }
    Ok(Element {
        name: e.name.clone(),
        count: e.count,
        properties,
        start: Position::Byte(start as u64),
    })
}

/// Whitespace-separated tokens with their line and column.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Tokens<'a> {
    fn skip_space(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
            if b == b'\n' {
                self.line += 1;
                self.line_start = self.pos;
            }
        }
    }

    fn here(&self) -> (usize, usize) {
        (self.line, self.pos - self.line_start + 1)
    }

    /// The next token and its line and column, or `None` at the end.
    fn next(&mut self) -> Option<(&'a [u8], usize, usize)> {
        self.skip_space();
        if self.pos >= self.bytes.len() {
            return None;
        }
        let (line, column) = self.here();
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        Some((&self.bytes[start..self.pos], line, column))
    }
}

fn ascii_element(
    name: &Path,
    e: &DeclaredElement,
    tokens: &mut Tokens,
) -> Result<Element, PointsError> {
    tokens.skip_space();
    let (line, column) = tokens.here();
    let values_per_row = e.properties.len();
    let left = tokens.bytes.len() - tokens.pos;
    // Each value takes a character and a separator (the very last needs none).
    let need = e.count.checked_mul(2 * values_per_row);
    if need.is_none_or(|n| n > left + 1) {
        return Err(PointsError::text(
            name,
            line,
            column,
            format!(
                "element {} declares {} rows of {values_per_row} values, more than the {left} bytes left can hold",
                e.name, e.count
            ),
        ));
    }
    let mut properties = columns(name, e)?;
    let count = if values_per_row == 0 { 0 } else { e.count };
    let progress = Progress::new(count as u64, &format!("reading {}", name.display()));
    for row in 0..count {
        if row % 65_536 == 65_535 {
            progress.inc(65_536);
        }
        for (d, p) in e.properties.iter().zip(properties.iter_mut()) {
            let at = Where {
                name,
                element: &e.name,
                row,
                property: &d.name,
            };
            match &mut p.data {
                PropertyData::Scalar { ty, values } => {
                    let (v, line, column) = at.next(tokens, *ty, "a value")?;
                    if !v.is_finite() && p.first_non_finite.is_none() {
                        p.first_non_finite = Some((row, Position::Line { line, column }));
                    }
                    values.push(v);
                }
                PropertyData::List { count, item, lists } => {
                    let (n, line, column) = at.next(tokens, *count, "a list length")?;
                    let left = tokens.bytes.len() - tokens.pos;
                    if n < 0.0 || n > left as f64 {
                        return Err(PointsError::text(
                            name,
                            line,
                            column,
                            format!(
                                "element {} row {row} property {}: a list of {n} items, but only {left} bytes remain",
                                e.name, d.name
                            ),
                        ));
                    }
                    for _ in 0..n as usize {
                        lists.values.push(at.next(tokens, *item, "a list item")?.0);
                    }
                    lists.offsets.push(lists.values.len());
                }
            }
        }
    }
    Ok(Element {
        name: e.name.clone(),
        count: e.count,
        properties,
        start: Position::Line { line, column },
    })
}

/// The value being read, for error messages.
struct Where<'a> {
    name: &'a Path,
    element: &'a str,
    row: usize,
    property: &'a str,
}

impl Where<'_> {
    /// The next token as a value of `ty` with its line and column.
    fn next(
        &self,
        tokens: &mut Tokens,
        ty: ScalarType,
        what: &str,
    ) -> Result<(f64, usize, usize), PointsError> {
        let Some((token, line, column)) = tokens.next() else {
            let (line, column) = tokens.here();
            return Err(PointsError::text(
                self.name,
                line,
                column,
                format!(
                    "element {} row {} property {}: the file ends where {what} was expected",
                    self.element, self.row, self.property
                ),
            ));
        };
        let v = ascii_value(token, ty).map_err(|m| {
            PointsError::text(
                self.name,
                line,
                column,
                format!(
                    "element {} row {} property {}: {m}",
                    self.element, self.row, self.property
                ),
            )
        })?;
        Ok((v, line, column))
    }
}

/// A token as a value of `ty`, or what is wrong with it.
fn ascii_value(token: &[u8], ty: ScalarType) -> Result<f64, String> {
    let text = std::str::from_utf8(token).unwrap_or("");
    let shown = || crate::input::shorten(&String::from_utf8_lossy(token), 40);
    let v = text
        .parse::<f64>()
        .map_err(|_| format!("expected a number, found \"{}\"", shown()))?;
    if ty.is_integer() {
        let (lo, hi) = ty.range();
        if v.fract() != 0.0 || !(lo..=hi).contains(&v) {
            return Err(format!(
                "expected an integer of {lo}..{hi} ({ty:?}), found \"{}\"",
                shown()
            ));
        }
        Ok(v)
    } else if ty == ScalarType::Float {
        Ok(v as f32 as f64)
    } else {
        Ok(v)
    }
}

#[cfg(test)]
pub(crate) mod tests;
