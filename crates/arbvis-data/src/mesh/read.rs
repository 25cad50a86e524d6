//! The reading layer the three loaders share: a byte cursor that hands out whitespace-
//! separated tokens without allocating, fixed-width binary values in either byte order,
//! and errors that carry the file and the position.
//!
//! Decisions:
//! - Positions in text are given as line, column and byte offset; the column counts bytes
//!   from the start of the line (files are ASCII in practice). In binary data only the
//!   byte offset is given. Line and column are computed only when an error is made.
//! - Every count read from a file is checked against the bytes that remain before
//!   anything is allocated for it: an ASCII value needs at least 2 bytes (a digit and a
//!   separator, except the last), a binary value its width.
//! - Numbers are parsed with Rust's own `str::parse`, so `nan`, `inf` and `infinity`
//!   (any case, with a sign) are read as such; callers decide whether they are allowed.

use std::path::Path;

use super::{MeshError, Position};

/// Numeric types of binary and text arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Num {
    /// Signed 8-bit.
    I8,
    /// Unsigned 8-bit.
    U8,
    /// Signed 16-bit.
    I16,
    /// Unsigned 16-bit.
    U16,
    /// Signed 32-bit.
    I32,
    /// Unsigned 32-bit.
    U32,
    /// Signed 64-bit.
    I64,
    /// Unsigned 64-bit.
    U64,
    /// IEEE single.
    F32,
    /// IEEE double.
    F64,
}

impl Num {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Num::I8 | Num::U8 => 1,
            Num::I16 | Num::U16 => 2,
            Num::I32 | Num::U32 | Num::F32 => 4,
            Num::I64 | Num::U64 | Num::F64 => 8,
        }
    }

    /// True for the two float types.
    pub fn is_float(self) -> bool {
        matches!(self, Num::F32 | Num::F64)
    }

    /// Decode consecutive values of this type as f64 into `out`.
    pub fn decode_f64(self, bytes: &[u8], big: bool, out: &mut Vec<f64>) {
        macro_rules! run {
            ($t:ty) => {{
                const N: usize = std::mem::size_of::<$t>();
                out.extend(bytes.chunks_exact(N).map(|c| {
                    let mut a = [0u8; N];
                    a.copy_from_slice(c);
                    (if big {
                        <$t>::from_be_bytes(a)
                    } else {
                        <$t>::from_le_bytes(a)
                    }) as f64
                }))
            }};
        }
        match self {
            Num::I8 => run!(i8),
            Num::U8 => run!(u8),
            Num::I16 => run!(i16),
            Num::U16 => run!(u16),
            Num::I32 => run!(i32),
            Num::U32 => run!(u32),
            Num::I64 => run!(i64),
            Num::U64 => run!(u64),
            Num::F32 => run!(f32),
            Num::F64 => run!(f64),
        }
    }

    /// Decode consecutive integers into `out`; unsigned 64-bit values above `i64::MAX`
    /// become `i64::MAX` (callers refuse them as out of range). Float types decode
    /// nothing: callers refuse them first.
    pub fn decode_int(self, bytes: &[u8], big: bool, out: &mut Vec<i64>) {
        macro_rules! run {
            ($t:ty) => {{
                const N: usize = std::mem::size_of::<$t>();
                out.extend(bytes.chunks_exact(N).map(|c| {
                    let mut a = [0u8; N];
                    a.copy_from_slice(c);
                    let v = if big {
                        <$t>::from_be_bytes(a)
                    } else {
                        <$t>::from_le_bytes(a)
                    };
                    i64::try_from(v).unwrap_or(i64::MAX)
                }))
            }};
        }
        match self {
            Num::I8 => run!(i8),
            Num::U8 => run!(u8),
            Num::I16 => run!(i16),
            Num::U16 => run!(u16),
            Num::I32 => run!(i32),
            Num::U32 => run!(u32),
            Num::I64 => run!(i64),
            Num::U64 => run!(u64),
            Num::F32 | Num::F64 => {}
        }
    }

    /// Its name as VTK XML writes it (`Float32`, `UInt8`, ...).
    pub fn xml_name(self) -> &'static str {
        match self {
            Num::I8 => "Int8",
            Num::U8 => "UInt8",
            Num::I16 => "Int16",
            Num::U16 => "UInt16",
            Num::I32 => "Int32",
            Num::U32 => "UInt32",
            Num::I64 => "Int64",
            Num::U64 => "UInt64",
            Num::F32 => "Float32",
            Num::F64 => "Float64",
        }
    }
}

/// Values read as f64, with the index and byte offset of the first one that is not
/// finite (callers that need finite values report it).
pub type Floats = (Vec<f64>, Option<(usize, usize)>);

/// Line and column (1-based, column in bytes) of byte `at` in `bytes`.
pub fn line_column(bytes: &[u8], at: usize) -> (usize, usize) {
    let at = at.min(bytes.len());
    let head = &bytes[..at];
    let line = head.iter().filter(|&&b| b == b'\n').count() + 1;
    let start = head.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    (line, at - start + 1)
}

/// Byte offset of whitespace-separated token `n` (0-based) counted from byte `start`
/// (used only to place errors in ASCII lists, so the scan costs nothing when all is well).
pub fn nth_token(bytes: &[u8], start: usize, n: usize) -> usize {
    let mut i = start.min(bytes.len());
    let mut k = 0;
    loop {
        while i < bytes.len() && is_space(bytes[i]) {
            i += 1;
        }
        if k == n || i >= bytes.len() {
            return i;
        }
        while i < bytes.len() && !is_space(bytes[i]) {
            i += 1;
        }
        k += 1;
    }
}

/// An error at byte `at` of a text region.
pub fn text_error(name: &Path, bytes: &[u8], at: usize, message: impl Into<String>) -> MeshError {
    let (line, column) = line_column(bytes, at);
    MeshError::Format {
        path: name.to_path_buf(),
        at: Position::Text {
            line,
            column,
            byte: at as u64,
        },
        message: message.into(),
    }
}

/// An error at byte `at` of binary data.
pub fn binary_error(name: &Path, at: usize, message: impl Into<String>) -> MeshError {
    MeshError::Format {
        path: name.to_path_buf(),
        at: Position::Byte(at as u64),
        message: message.into(),
    }
}

/// How a token is quoted in an error: shortened, lossy UTF-8.
pub fn quote(token: &[u8]) -> String {
    format!(
        "\"{}\"",
        arbvis_core::input::shorten(&String::from_utf8_lossy(token), 40)
    )
}

/// An empty vector with room for `n` items, checked against the memory budget and
/// reserved fallibly: the error (the estimate, the budget and how to raise it, or the
/// system's refusal) is a message the caller places at a position, never an abort.
pub fn vec_for<T>(n: usize, what: &str) -> Result<Vec<T>, arbvis_core::budget::OverBudget> {
    arbvis_core::budget::vec_for(n, &format!("{n} {what}"))
}

/// A cursor over a file's bytes.
pub struct Cursor<'a> {
    /// The file's display name.
    pub name: &'a Path,
    /// The whole file.
    pub bytes: &'a [u8],
    /// The next byte to read.
    pub pos: usize,
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\r' | b'\x0b' | b'\x0c')
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `bytes`.
    pub fn new(name: &'a Path, bytes: &'a [u8]) -> Cursor<'a> {
        Cursor {
            name,
            bytes,
            pos: 0,
        }
    }

    /// An error at byte `at`, as text.
    pub fn err(&self, at: usize, message: impl Into<String>) -> MeshError {
        text_error(self.name, self.bytes, at, message)
    }

    /// An error at byte `at` of binary data.
    pub fn err_bin(&self, at: usize, message: impl Into<String>) -> MeshError {
        binary_error(self.name, at, message)
    }

    /// Bytes left after the cursor.
    pub fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// Skip spaces, tabs and line ends.
    pub fn skip_space(&mut self) {
        while self.pos < self.bytes.len() && is_space(self.bytes[self.pos]) {
            self.pos += 1;
        }
    }

    /// True when only whitespace is left.
    pub fn at_end(&mut self) -> bool {
        self.skip_space();
        self.pos >= self.bytes.len()
    }

    /// The next token and its offset, or `None` at the end.
    pub fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_space();
        let start = self.pos;
        while self.pos < self.bytes.len() && !is_space(self.bytes[self.pos]) {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.bytes[start..self.pos]))
    }

    /// The next token, which must exist: `what` says what was expected.
    pub fn need(&mut self, what: &str) -> Result<(usize, &'a [u8]), MeshError> {
        match self.token() {
            Some(t) => Ok(t),
            None => Err(self.err(
                self.bytes.len(),
                format!("expected {what}, found the end of the file"),
            )),
        }
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Option<&'a [u8]> {
        let save = self.pos;
        let t = self.token().map(|t| t.1);
        self.pos = save;
        t
    }

    /// Consume the keyword `word` (ASCII case-insensitive) or fail.
    pub fn keyword(&mut self, word: &str) -> Result<usize, MeshError> {
        let (at, t) = self.need(word)?;
        if t.eq_ignore_ascii_case(word.as_bytes()) {
            Ok(at)
        } else {
            Err(self.err(at, format!("expected {word}, found {}", quote(t))))
        }
    }

    /// Parse the next token as `T`.
    pub fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Result<(usize, T), MeshError> {
        self.parse_with(|| what.to_string())
    }

    /// Parse the next token as `T`; `what` is called only to word an error, so a loop
    /// over millions of values allocates nothing per value.
    pub fn parse_with<T: std::str::FromStr>(
        &mut self,
        what: impl Fn() -> String,
    ) -> Result<(usize, T), MeshError> {
        match self.token() {
            Some((at, t)) => match std::str::from_utf8(t)
                .ok()
                .and_then(|s| s.parse::<T>().ok())
            {
                Some(v) => Ok((at, v)),
                None => Err(self.err(at, format!("expected {}, found {}", what(), quote(t)))),
            },
            None => Err(self.err(
                self.bytes.len(),
                format!("expected {}, found the end of the file", what()),
            )),
        }
    }

    /// Parse a count of items that each need at least `min_bytes` bytes of the rest of
    /// the file; a count the file cannot hold is refused before anything is allocated.
    pub fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, MeshError> {
        let (at, t) = self.need(what)?;
        let text = std::str::from_utf8(t).unwrap_or("");
        if text.starts_with('-') && text[1..].bytes().all(|b| b.is_ascii_digit()) && text.len() > 1
        {
            return Err(self.err(at, format!("{what} is negative: {}", quote(t))));
        }
        let n: u64 = text.parse().map_err(|_| {
            self.err(
                at,
                format!("expected {what} (a whole number), found {}", quote(t)),
            )
        })?;
        self.check_fits(at, what, n, min_bytes)
    }

    /// Check that `n` items of at least `min_bytes` each fit in the rest of the file.
    pub fn check_fits(
        &self,
        at: usize,
        what: &str,
        n: u64,
        min_bytes: usize,
    ) -> Result<usize, MeshError> {
        // The last ASCII value needs no separator: allow one byte of slack.
        let room = self.remaining() as u64 + 1;
        let need = n.checked_mul(min_bytes as u64);
        match (usize::try_from(n), need) {
            (Ok(n), Some(need)) if need <= room => Ok(n),
            _ => Err(self.err(
                at,
                format!(
                    "{what} is {n}, but the {} bytes left in the file can hold at most {} (at least {min_bytes} bytes each)",
                    self.remaining(),
                    room / min_bytes.max(1) as u64
                ),
            )),
        }
    }

    /// The rest of the current line (without the line end), consuming the line end.
    pub fn line(&mut self) -> (usize, &'a [u8]) {
        let start = self.pos.min(self.bytes.len());
        let end = self.bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(self.bytes.len(), |p| start + p);
        self.pos = (end + 1).min(self.bytes.len());
        let mut line = &self.bytes[start..end];
        if line.last() == Some(&b'\r') {
            line = &line[..line.len() - 1];
        }
        (start, line)
    }

    /// Skip the rest of the current line, which must hold only whitespace: binary data
    /// starts right after a header line's line end.
    pub fn end_line(&mut self) -> Result<(), MeshError> {
        let (at, rest) = self.line();
        match rest.iter().position(|&b| !is_space(b)) {
            None => Ok(()),
            Some(p) => Err(self.err(
                at + p,
                format!("expected the end of the line, found {}", quote(&rest[p..])),
            )),
        }
    }

    /// The next `n` bytes of binary data (`what` names them in the error).
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], MeshError> {
        if n > self.remaining() {
            return Err(self.err_bin(
                self.pos,
                format!(
                    "{what} needs {n} bytes but the file has only {} left",
                    self.remaining()
                ),
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// `n` ASCII numbers as f64; returns them and the index and offset of the first
    /// value that is not finite, if any.
    pub fn ascii_f64(&mut self, n: usize, what: &str) -> Result<Floats, MeshError> {
        self.check_fits(self.pos, what, n as u64, 2)?;
        let mut out = vec_for(n, what).map_err(|m| self.err(self.pos, m))?;
        let mut bad = None;
        for i in 0..n {
            let (at, v) = self.parse_with::<f64>(|| format_what(what, i, n))?;
            if !v.is_finite() && bad.is_none() {
                bad = Some((i, at));
            }
            out.push(v);
        }
        Ok((out, bad))
    }

    /// `n` ASCII integers.
    pub fn ascii_int(&mut self, n: usize, what: &str) -> Result<Vec<i64>, MeshError> {
        self.check_fits(self.pos, what, n as u64, 2)?;
        let mut out = vec_for(n, what).map_err(|m| self.err(self.pos, m))?;
        for i in 0..n {
            let (_, v) = self.parse_with::<i64>(|| format_what(what, i, n))?;
            out.push(v);
        }
        Ok(out)
    }
}

/// "a number (value 3 of 10 of {what})", for error messages only.
fn format_what(what: &str, i: usize, n: usize) -> String {
    format!("a number (value {} of {n} of {what})", i + 1)
}
