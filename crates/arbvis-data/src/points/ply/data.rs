//! PLY data: binary (either byte order) and ASCII rows read into columns, each row
//! count checked against the bytes left before anything is allocated.

use std::path::Path;

use super::header::{DeclaredElement, Header};
use super::{Element, Encoding, Lists, Position, Property, PropertyData, ScalarType};
use crate::points::progress::Progress;
use crate::points::PointsError;

/// The elements of ASCII data starting after the header; nothing may follow them.
pub(super) fn read_ascii(
    name: &Path,
    bytes: &[u8],
    header: &Header,
) -> Result<Vec<Element>, PointsError> {
    let mut tokens = Tokens {
        bytes,
        pos: header.data,
        line: header.data_line,
        line_start: header.data,
    };
    let mut elements = Vec::with_capacity(header.elements.len());
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
    Ok(elements)
}

/// The elements of binary data starting after the header; nothing may follow them.
pub(super) fn read_binary(
    name: &Path,
    bytes: &[u8],
    header: &Header,
) -> Result<Vec<Element>, PointsError> {
    let big = header.encoding == Encoding::BinaryBigEndian;
    let mut pos = header.data;
    let mut elements = Vec::with_capacity(header.elements.len());
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
    Ok(elements)
}

/// Empty columns for `e`, reserved for its rows (the caller checked the count against
/// the bytes left, the estimate against the budget).
fn columns(name: &Path, e: &DeclaredElement) -> Result<Vec<Property>, PointsError> {
    let (line, column) = e.at;
    let fail = |error: arbvis_core::budget::OverBudget| {
        PointsError::text(
            name,
            line,
            column,
            format!("element {} declares {} rows: {error}", e.name, e.count),
        )
    };
    let what = format!("the columns of element {}", e.name);
    e.properties
        .iter()
        .map(|d| {
            let data = match d.count {
                None => PropertyData::Scalar {
                    ty: d.ty,
                    values: arbvis_core::budget::vec_for(e.count, &what).map_err(fail)?,
                },
                Some(count) => {
                    let mut offsets =
                        arbvis_core::budget::vec_for(e.count.saturating_add(1), &what)
                            .map_err(fail)?;
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
                declared: Position::Line {
                    line: d.at.0,
                    column: d.at.1,
                },
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
                    reserve_items(name, Position::Byte(at as u64), &mut lists.values, n, e)?;
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
        declared: declared(e),
    })
}

/// Room for `n` more list items (checked against the budget, fallible): the items of all
/// rows together may outgrow it even though each list fits the file.
fn reserve_items(
    name: &Path,
    at: Position,
    values: &mut Vec<f64>,
    n: f64,
    e: &DeclaredElement,
) -> Result<(), PointsError> {
    let what = format!("the list items of element {}", e.name);
    arbvis_core::budget::reserve(values, n as usize, &what).map_err(|error| {
        let message = format!("element {}: {error}", e.name);
        match at {
            Position::Byte(b) => PointsError::format(name, b, message),
            Position::Line { line, column } => PointsError::text(name, line, column, message),
        }
    })
}

/// Where the header declares `e`.
fn declared(e: &DeclaredElement) -> Position {
    Position::Line {
        line: e.at.0,
        column: e.at.1,
    }
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
                    // Each item takes a character and a separator.
                    if n < 0.0 || 2.0 * n > left as f64 + 1.0 {
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
                    reserve_items(
                        name,
                        Position::Line { line, column },
                        &mut lists.values,
                        n,
                        e,
                    )?;
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
        declared: declared(e),
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
    let shown = || arbvis_core::input::shorten(&String::from_utf8_lossy(token), 40);
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
