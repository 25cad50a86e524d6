//! The PLY header: `ply`, `format`, `comment`, `obj_info`, `element` and `property`
//! lines up to `end_header`, with line and column in every error.

use std::path::Path;

use super::{Encoding, ScalarType};
use crate::points::PointsError;

/// A property as declared in the header.
pub(super) struct Declared {
    pub(super) name: String,
    /// `Some(count type)` for lists.
    pub(super) count: Option<ScalarType>,
    pub(super) ty: ScalarType,
    /// Line and column of the `property` line's name.
    pub(super) at: (usize, usize),
}

pub(super) struct DeclaredElement {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) properties: Vec<Declared>,
    /// Line and column of the `element` line's count.
    pub(super) at: (usize, usize),
}

pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) version: String,
    pub(super) comments: Vec<String>,
    pub(super) obj_info: Vec<String>,
    pub(super) elements: Vec<DeclaredElement>,
    /// Byte where the data starts.
    pub(super) data: usize,
    /// Line where the data starts (for ASCII).
    pub(super) data_line: usize,
}

/// Parse the header of `bytes`.
pub(super) fn parse(name: &Path, bytes: &[u8]) -> Result<Header, PointsError> {
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
        let l = Line::next(name, bytes, &mut pos, number)?;
        if number == 1 {
            l.first()?;
            continue;
        }
        match l.word(0) {
            "format" => {
                l.format(&mut header)?;
                format_seen = true;
            }
            "comment" => header.comments.push(rest(l.line, "comment")),
            "obj_info" => header.obj_info.push(rest(l.line, "obj_info")),
            "element" => l.element(&mut header.elements)?,
            "property" => l.property(&mut header.elements)?,
            "end_header" => {
                if !format_seen {
                    return Err(l.err(1, "end_header before any format line".into()));
                }
                header.data = pos;
                header.data_line = number + 1;
                return Ok(header);
            }
            "" => return Err(l.err(1, "an empty line in the header".into())),
            other => {
                return Err(l.err(
                    1,
                    format!(
                        "expected format, comment, obj_info, element, property or end_header, found \"{}\"",
                        arbvis_core::input::shorten(other, 40)
                    ),
                ))
            }
        }
    }
}

/// A header line and its words.
struct Line<'a> {
    name: &'a Path,
    /// Its 1-based number.
    number: usize,
    line: &'a str,
    words: Vec<(usize, &'a str)>,
}

impl<'a> Line<'a> {
    /// Line `number`, from byte `pos` (moved past it): text ending in `\n`.
    fn next(
        name: &'a Path,
        bytes: &'a [u8],
        pos: &mut usize,
        number: usize,
    ) -> Result<Line<'a>, PointsError> {
        let Some(len) = bytes[*pos..].iter().position(|&b| b == b'\n') else {
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
        let raw = &bytes[*pos..*pos + len];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        *pos += len + 1;
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(PointsError::text(
                name,
                number,
                1,
                "the header holds bytes that are not text",
            ));
        };
        Ok(Line {
            name,
            number,
            line,
            words: arbvis_core::input::words(line),
        })
    }

    /// An error at `column` of this line.
    fn err(&self, column: usize, message: String) -> PointsError {
        PointsError::text(self.name, self.number, column, message)
    }

    /// Word `i` (empty past the last).
    fn word(&self, i: usize) -> &'a str {
        self.words.get(i).map_or("", |w| w.1)
    }

    /// The column of word `i` (past the line's end past the last word).
    fn col(&self, i: usize) -> usize {
        self.words
            .get(i)
            .map_or(self.line.chars().count() + 1, |w| w.0)
    }

    /// The first line: `ply`.
    fn first(&self) -> Result<(), PointsError> {
        if self.line.trim_end() != "ply" {
            return Err(self.err(
                1,
                format!(
                    "not a PLY file: expected \"ply\" on the first line, found \"{}\"",
                    arbvis_core::input::shorten(self.line, 40)
                ),
            ));
        }
        Ok(())
    }

    /// `format ENCODING 1.0`.
    fn format(&self, header: &mut Header) -> Result<(), PointsError> {
        header.encoding = match self.word(1) {
            "ascii" => Encoding::Ascii,
            "binary_little_endian" => Encoding::BinaryLittleEndian,
            "binary_big_endian" => Encoding::BinaryBigEndian,
            other => {
                return Err(self.err(
                    self.col(1),
                    format!(
                        "expected ascii, binary_little_endian or binary_big_endian, found \"{}\"",
                        arbvis_core::input::shorten(other, 40)
                    ),
                ))
            }
        };
        if self.word(2) != "1.0" {
            return Err(self.err(
                self.col(2),
                format!(
                    "expected format version 1.0, found \"{}\"",
                    arbvis_core::input::shorten(self.word(2), 40)
                ),
            ));
        }
        header.version = self.word(2).to_string();
        Ok(())
    }

    /// `element NAME COUNT`, a name not declared before.
    fn element(&self, elements: &mut Vec<DeclaredElement>) -> Result<(), PointsError> {
        let (word, col) = (|i| self.word(i), |i| self.col(i));
        let count = word(2).parse::<usize>().map_err(|_| {
            self.err(
                col(2),
                format!(
                    "expected the element's row count, found \"{}\"",
                    arbvis_core::input::shorten(word(2), 40)
                ),
            )
        })?;
        if word(1).is_empty() || self.words.len() != 3 {
            return Err(self.err(1, "expected \"element NAME COUNT\"".into()));
        }
        if elements.iter().any(|e| e.name == word(1)) {
            return Err(self.err(col(1), format!("element {} is declared twice", word(1))));
        }
        elements.push(DeclaredElement {
            name: word(1).to_string(),
            count,
            properties: Vec::new(),
            at: (self.number, col(2)),
        });
        Ok(())
    }

    /// The PLY type named by word `i`.
    fn ty(&self, i: usize) -> Result<ScalarType, PointsError> {
        ScalarType::from_name(self.word(i)).ok_or_else(|| {
            self.err(
                self.col(i),
                format!(
                    "expected a PLY type (char, uchar, short, ushort, int, uint, float, double or int8 .. float64), found \"{}\"",
                    arbvis_core::input::shorten(self.word(i), 40)
                ),
            )
        })
    }

    /// `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME`, of the last
    /// element, a name not declared before in it.
    fn property(&self, elements: &mut [DeclaredElement]) -> Result<(), PointsError> {
        let Some(element) = elements.last_mut() else {
            return Err(self.err(1, "a property before any element".into()));
        };
        let (declared, n) = if self.word(1) == "list" {
            let count = self.ty(2)?;
            if !count.is_integer() {
                return Err(self.err(
                    self.col(2),
                    format!(
                        "a list's length must have an integer type, found {}",
                        self.word(2)
                    ),
                ));
            }
            (
                Declared {
                    name: self.word(4).to_string(),
                    count: Some(count),
                    ty: self.ty(3)?,
                    at: (self.number, self.col(4)),
                },
                5,
            )
        } else {
            (
                Declared {
                    name: self.word(2).to_string(),
                    count: None,
                    ty: self.ty(1)?,
                    at: (self.number, self.col(2)),
                },
                3,
            )
        };
        if self.words.len() != n {
            return Err(self.err(
                1,
                "expected \"property TYPE NAME\" or \"property list COUNT_TYPE ITEM_TYPE NAME\""
                    .into(),
            ));
        }
        if element.properties.iter().any(|p| p.name == declared.name) {
            return Err(self.err(
                self.col(n - 1),
                format!(
                    "property {} of element {} is declared twice",
                    declared.name, element.name
                ),
            ));
        }
        element.properties.push(declared);
        Ok(())
    }
}

fn rest(line: &str, keyword: &str) -> String {
    line.trim_start()
        .strip_prefix(keyword)
        .unwrap_or("")
        .trim_start()
        .to_string()
}
