//! Decoding one `DataArray` of a `.vtu` file: ASCII numbers, inline base64, appended raw
//! or base64 data, uncompressed or in zlib blocks (see the parent module's doc for the
//! layouts and the bounds on declared sizes).

use std::io::Read;

use base64::Engine;

use super::{ArrayDesc, File, Format};
use crate::mesh::read::{quote, text_error, vec_for, Cursor, Num};
use crate::mesh::MeshError;

/// Deflate cannot expand by more than about 1032:1.
const MAX_INFLATE_RATIO: u64 = 1032;

fn chars(bytes: usize) -> usize {
    bytes.div_ceil(3) * 4
}

impl File<'_> {
    fn err(&self, d: &ArrayDesc, m: String) -> MeshError {
        text_error(
            self.name,
            self.bytes,
            d.at,
            format!("DataArray \"{}\": {m}", d.name),
        )
    }

    fn ty(&self, d: &ArrayDesc) -> Result<Num, MeshError> {
        d.ty.ok_or_else(|| {
            self.err(
                d,
                format!(
                    "type {} is not a numeric type (Int8 ... UInt64, Float32, Float64)",
                    quote(d.type_name.as_bytes())
                ),
            )
        })
    }

    /// `n` values as f64.
    pub(super) fn floats(&self, d: &ArrayDesc, n: Option<usize>) -> Result<Vec<f64>, MeshError> {
        let n = n.ok_or_else(|| self.err(d, "the value count overflows".into()))?;
        let t = self.ty(d)?;
        if d.format == Format::Ascii {
            return self.ascii(d, n, |c, n| c.ascii_f64(n, "the values").map(|r| r.0));
        }
        let data = self.binary(d, n, t)?;
        let mut out = vec_for(n, "values").map_err(|m| self.err(d, m))?;
        t.decode_f64(&data, self.big, &mut out);
        Ok(out)
    }

    /// `n` integers.
    pub(super) fn ints(&self, d: &ArrayDesc, n: Option<usize>) -> Result<Vec<i64>, MeshError> {
        let n = n.ok_or_else(|| self.err(d, "the value count overflows".into()))?;
        let t = self.ty(d)?;
        if t.is_float() {
            return Err(self.err(d, format!("{} must be an integer type", t.xml_name())));
        }
        if d.format == Format::Ascii {
            return self.ascii(d, n, |c, n| c.ascii_int(n, "the values"));
        }
        let data = self.binary(d, n, t)?;
        let mut out = vec_for(n, "values").map_err(|m| self.err(d, m))?;
        t.decode_int(&data, self.big, &mut out);
        Ok(out)
    }

    /// `n` ASCII values from the element's text; more or fewer is an error.
    fn ascii<T>(
        &self,
        d: &ArrayDesc,
        n: usize,
        read: impl Fn(&mut Cursor, usize) -> Result<Vec<T>, MeshError>,
    ) -> Result<Vec<T>, MeshError> {
        let Some(&(start, _)) = d.text.iter().find(|t| !t.1.trim_ascii().is_empty()) else {
            if n == 0 {
                return Ok(Vec::new());
            }
            return Err(self.err(d, format!("expected {n} values, found none")));
        };
        let end = d.text.last().map_or(start, |t| t.0 + t.1.len());
        let mut c = Cursor::new(self.name, &self.bytes[..end]);
        c.pos = start;
        let v = read(&mut c, n)?;
        if let Some((at, t)) = c.token() {
            return Err(c.err(
                at,
                format!(
                    "DataArray \"{}\" should hold {n} values; found more: {}",
                    d.name,
                    quote(t)
                ),
            ));
        }
        Ok(v)
    }

    /// The data bytes of a binary or appended array that must hold `n` values of `t`.
    fn binary(&self, d: &ArrayDesc, n: usize, t: Num) -> Result<Vec<u8>, MeshError> {
        let want = n
            .checked_mul(t.size())
            .ok_or_else(|| self.err(d, "the byte count overflows".into()))?;
        match d.format {
            Format::Binary => {
                let text: Vec<u8> = d
                    .text
                    .iter()
                    .flat_map(|t| t.1.iter().copied())
                    .filter(|b| !b.is_ascii_whitespace())
                    .collect();
                self.base64(d, &text, want)
            }
            _ => {
                let (start, b64) = self.appended.ok_or_else(|| {
                    self.err(
                        d,
                        "format=\"appended\" but the file has no <AppendedData>".into(),
                    )
                })?;
                let off = d
                    .offset
                    .ok_or_else(|| self.err(d, "format=\"appended\" without an offset".into()))?;
                let at = usize::try_from(off)
                    .ok()
                    .and_then(|o| o.checked_add(start))
                    .filter(|&a| a <= self.bytes.len())
                    .ok_or_else(|| {
                        self.err(d, format!("offset {off} lies beyond the end of the file"))
                    })?;
                let rest = &self.bytes[at..];
                if b64 {
                    self.base64(d, rest, want)
                } else {
                    self.raw(d, rest, at, want)
                }
            }
        }
    }

    fn uint(&self, b: &[u8]) -> u64 {
        let mut v = Vec::with_capacity(1);
        self.header.decode_int(b, self.big, &mut v);
        v.first().map_or(0, |&x| x as u64)
    }

    fn raw(
        &self,
        d: &ArrayDesc,
        rest: &[u8],
        at: usize,
        want: usize,
    ) -> Result<Vec<u8>, MeshError> {
        let h = self.header.size();
        let trunc = |what: &str| {
            crate::mesh::read::binary_error(
                self.name,
                at,
                format!(
                    "DataArray \"{}\": the appended data end inside its {what}",
                    d.name
                ),
            )
        };
        let first = rest.get(..h).ok_or_else(|| trunc("header"))?;
        let v0 = self.uint(first);
        if !self.zlib {
            if v0 != want as u64 {
                return Err(self.err(
                    d,
                    format!("the header says {v0} bytes, but {want} are needed"),
                ));
            }
            return Ok(rest.get(h..h + want).ok_or_else(|| trunc("data"))?.to_vec());
        }
        let hb = header_bytes(v0, h)
            .filter(|&hb| hb <= rest.len())
            .ok_or_else(|| trunc("block table"))?;
        let table = self.table(&rest[..hb]);
        let body_len = compressed_len(&table)
            .ok_or_else(|| self.err(d, "the compressed sizes overflow".into()))?;
        let body = usize::try_from(body_len)
            .ok()
            .and_then(|l| rest.get(hb..hb.checked_add(l)?))
            .ok_or_else(|| trunc("compressed blocks"))?;
        self.inflate(d, &table, body, want)
    }

    fn table(&self, b: &[u8]) -> Vec<u64> {
        let mut v = Vec::new();
        self.header.decode_int(b, self.big, &mut v);
        v.into_iter().map(|x| x as u64).collect()
    }

    fn base64(&self, d: &ArrayDesc, text: &[u8], want: usize) -> Result<Vec<u8>, MeshError> {
        let h = self.header.size();
        let dec = |s: &[u8], what: &str| {
            base64::engine::general_purpose::STANDARD
                .decode(s)
                .map_err(|e| self.err(d, format!("bad base64 in its {what}: {e}")))
        };
        let part = |n: usize, what: &str| {
            text.get(..n).ok_or_else(|| {
                self.err(
                    d,
                    format!(
                        "the base64 text ends inside its {what} ({} characters, {n} needed)",
                        text.len()
                    ),
                )
            })
        };
        let first = dec(part(chars(h), "header")?, "header")?;
        let v0 = self.uint(first.get(..h).unwrap_or(&[]));
        let hb = if self.zlib {
            header_bytes(v0, h)
                .filter(|&hb| chars(hb) <= text.len())
                .ok_or_else(|| {
                    self.err(
                        d,
                        format!("the block count {v0} does not fit in the base64 text"),
                    )
                })?
        } else {
            h
        };
        let hc = chars(hb);
        let head = dec(part(hc, "header")?, "header")?;
        let table = self.table(head.get(..hb).unwrap_or(&[]));
        let body_len = if self.zlib {
            compressed_len(&table)
                .ok_or_else(|| self.err(d, "the compressed sizes overflow".into()))?
        } else {
            if v0 != want as u64 {
                return Err(self.err(
                    d,
                    format!("the header says {v0} bytes, but {want} are needed"),
                ));
            }
            v0
        };
        let body_len = usize::try_from(body_len)
            .ok()
            .filter(|&l| chars(l) <= text.len())
            .ok_or_else(|| {
                self.err(
                    d,
                    format!(
                        "the header announces {body_len} bytes, more than the base64 text holds"
                    ),
                )
            })?;
        let separate = hb % 3 == 0 || text[hc - 1] == b'=';
        let body = if separate {
            let s = text
                .get(hc..hc + chars(body_len))
                .ok_or_else(|| self.err(d, "the base64 text ends inside its data".into()))?;
            dec(s, "data")?
        } else {
            let all = dec(part(chars(hb + body_len), "data")?, "data")?;
            all.get(hb..hb + body_len).unwrap_or(&[]).to_vec()
        };
        let body = body.get(..body_len).ok_or_else(|| {
            self.err(d, "the base64 data are shorter than the header says".into())
        })?;
        if self.zlib {
            self.inflate(d, &table, body, want)
        } else {
            Ok(body.to_vec())
        }
    }

    /// Inflate zlib blocks described by `table` (`[n, block, last, sizes...]`) from `body`
    /// into exactly `want` bytes.
    fn inflate(
        &self,
        d: &ArrayDesc,
        table: &[u64],
        body: &[u8],
        want: usize,
    ) -> Result<Vec<u8>, MeshError> {
        let (n, block, last) = (table[0], table[1], table[2]);
        let last = if last == 0 { block } else { last };
        let total = if n == 0 {
            Some(0)
        } else {
            (n - 1).checked_mul(block).and_then(|t| t.checked_add(last))
        };
        if total != Some(want as u64) {
            return Err(self.err(d, format!(
                "the compression header declares {n} blocks of {block} bytes (last {last}): {} bytes, but {want} are needed",
                total.map_or("too many".into(), |t| t.to_string())
            )));
        }
        let mut out = vec_for(want, "bytes").map_err(|m| self.err(d, m))?;
        let mut pos = 0usize;
        for (i, &c) in table[3..].iter().enumerate() {
            let u = if i as u64 + 1 == n { last } else { block };
            if u > c.saturating_mul(MAX_INFLATE_RATIO).saturating_add(64) {
                return Err(self.err(d, format!(
                    "block {i} declares {u} bytes from {c} compressed bytes, more than deflate can produce"
                )));
            }
            let src = &body[pos..pos + c as usize];
            pos += c as usize;
            let before = out.len();
            let got = flate2::read::ZlibDecoder::new(src)
                .take(u + 1)
                .read_to_end(&mut out)
                .map_err(|e| self.err(d, format!("zlib block {i} does not inflate: {e}")))?;
            if got as u64 != u {
                out.truncate(before);
                return Err(self.err(
                    d,
                    format!(
                        "zlib block {i} inflates to {} bytes, but the header says {u}",
                        if got as u64 > u {
                            format!("more than {u}")
                        } else {
                            got.to_string()
                        }
                    ),
                ));
            }
        }
        Ok(out)
    }
}

/// Bytes of a compression header with `n` blocks of `h`-byte integers.
fn header_bytes(n: u64, h: usize) -> Option<usize> {
    usize::try_from(n).ok()?.checked_add(3)?.checked_mul(h)
}

/// Sum of the compressed block sizes of a table `[n, block, last, sizes...]`.
fn compressed_len(table: &[u64]) -> Option<u64> {
    table
        .get(3..)?
        .iter()
        .try_fold(0u64, |a, &c| a.checked_add(c))
}
