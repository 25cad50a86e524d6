//! The reading layer of legacy files: header-line arguments, type names, and ASCII or
//! big-endian binary arrays with the positions their errors need.

use crate::mesh::read::{nth_token, quote, vec_for, Cursor, Floats, Num};
use crate::mesh::MeshError;

/// The numeric type of a legacy type name (`None` for `bit`, strings and unknown names).
pub(super) fn num_type(t: &[u8]) -> Option<Num> {
    let t = String::from_utf8_lossy(t).to_ascii_lowercase();
    Some(match t.as_str() {
        "unsigned_char" | "vtktypeuint8" => Num::U8,
        "char" | "signed_char" | "vtktypeint8" => Num::I8,
        "unsigned_short" | "vtktypeuint16" => Num::U16,
        "short" | "vtktypeint16" => Num::I16,
        "unsigned_int" | "vtktypeuint32" => Num::U32,
        "int" | "vtkidtype" | "vtktypeint32" => Num::I32,
        "unsigned_long" | "vtktypeuint64" | "unsigned_long_long" | "unsigned___int64" => Num::U64,
        "long" | "vtktypeint64" | "long_long" | "__int64" => Num::I64,
        "float" | "vtktypefloat32" => Num::F32,
        "double" | "vtktypefloat64" => Num::F64,
        _ => return None,
    })
}

/// A cursor over a legacy file, ASCII or binary.
pub(super) struct Reader<'a> {
    /// The cursor.
    pub c: Cursor<'a>,
    /// BINARY (big-endian) data.
    pub binary: bool,
}

impl<'a> Reader<'a> {
    /// The remaining tokens of the current line.
    pub(super) fn args(&mut self) -> Vec<(usize, &'a [u8])> {
        let (at, line) = self.c.line();
        let mut out = Vec::new();
        let mut i = 0;
        while i < line.len() {
            while i < line.len() && line[i].is_ascii_whitespace() {
                i += 1;
            }
            let s = i;
            while i < line.len() && !line[i].is_ascii_whitespace() {
                i += 1;
            }
            if i > s {
                out.push((at + s, &line[s..i]));
            }
        }
        out
    }

    /// Argument `i` of a header line, parsed.
    pub(super) fn arg<T: std::str::FromStr>(
        &self,
        args: &[(usize, &[u8])],
        i: usize,
        kw_at: usize,
        what: &str,
    ) -> Result<T, MeshError> {
        let (at, t) = args.get(i).copied().ok_or_else(|| {
            self.c.err(
                kw_at,
                format!("expected {what} on this line, found the line end"),
            )
        })?;
        std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| {
                self.c
                    .err(at, format!("expected {what}, found {}", quote(t)))
            })
    }

    /// A type-name argument.
    pub(super) fn type_arg(
        &self,
        args: &[(usize, &[u8])],
        i: usize,
        kw_at: usize,
    ) -> Result<Num, MeshError> {
        let (at, t) = args.get(i).copied().ok_or_else(|| {
            self.c.err(
                kw_at,
                "expected a data type on this line, found the line end",
            )
        })?;
        num_type(t).ok_or_else(|| {
            self.c.err(
                at,
                format!(
                    "data type {} is not supported (expected unsigned_char, char, short, int, long, float, double, vtktypeint32, vtktypeint64, ...)",
                    quote(t)
                ),
            )
        })
    }

    /// A count argument that must fit in the rest of the file.
    pub(super) fn count_arg(
        &self,
        args: &[(usize, &[u8])],
        i: usize,
        kw_at: usize,
        what: &str,
        min_bytes: usize,
    ) -> Result<usize, MeshError> {
        let n: i64 = self.arg(args, i, kw_at, what)?;
        let at = args[i].0;
        if n < 0 {
            return Err(self.c.err(at, format!("{what} is negative: {n}")));
        }
        self.c.check_fits(at, what, n as u64, min_bytes)
    }

    pub(super) fn min_bytes(&self, t: Num) -> usize {
        if self.binary {
            t.size()
        } else {
            2
        }
    }

    /// `n` values of type `t` as f64, with the index and offset of the first non-finite.
    pub(super) fn values(&mut self, n: usize, t: Num, what: &str) -> Result<Floats, MeshError> {
        if !self.binary {
            return self.c.ascii_f64(n, what);
        }
        let start = self.c.pos;
        let out = self.binary(n, t, what, |data, out| t.decode_f64(data, true, out))?;
        let bad = out
            .iter()
            .position(|v| !v.is_finite())
            .map(|i| (i, start + i * t.size()));
        Ok((out, bad))
    }

    /// `n` integers of type `t`, with the offset of each value given by `at(i)` later.
    pub(super) fn ints(
        &mut self,
        n: usize,
        t: Num,
        what: &str,
    ) -> Result<(Vec<i64>, usize), MeshError> {
        let start = self.c.pos;
        if t.is_float() {
            return Err(self
                .c
                .err(start, format!("{what} must be integers, not floats")));
        }
        if !self.binary {
            return Ok((self.c.ascii_int(n, what)?, start));
        }
        let out = self.binary(n, t, what, |data, out| t.decode_int(data, true, out))?;
        Ok((out, start))
    }

    /// `n` big-endian binary values of type `t`, decoded by `decode` (the length checked
    /// against the file before anything is allocated).
    pub(super) fn binary<T>(
        &mut self,
        n: usize,
        t: Num,
        what: &str,
        decode: impl FnOnce(&[u8], &mut Vec<T>),
    ) -> Result<Vec<T>, MeshError> {
        let start = self.c.pos;
        let len = n.checked_mul(t.size()).ok_or_else(|| {
            self.c
                .err_bin(start, format!("{what}: {n} values overflow"))
        })?;
        let data = self.c.take(len, what)?;
        let mut out = vec_for(n, what).map_err(|m| self.c.err_bin(start, m))?;
        decode(data, &mut out);
        Ok(out)
    }

    /// An error about integer `i` of an array read by [`Reader::ints`] from `start`.
    pub(super) fn int_err(&self, start: usize, i: usize, t: Num, m: String) -> MeshError {
        if self.binary {
            self.c.err_bin(start + i * t.size(), m)
        } else {
            self.c.err(nth_token(self.c.bytes, start, i), m)
        }
    }
}
