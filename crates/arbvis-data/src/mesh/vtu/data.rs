//! Decoding one `DataArray` of a `.vtu` file: ASCII numbers, inline base64, appended raw
//! or base64 data, uncompressed or in zlib blocks (see the parent module's doc for the
//! layouts and the bounds on declared sizes).

use std::borrow::Cow;
use std::io::Read;

use base64::Engine;

use super::desc::{ArrayDesc, File, Format};
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

    /// The array's numeric type, or an error naming the type it declares.
    pub(super) fn ty(&self, d: &ArrayDesc) -> Result<Num, MeshError> {
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

    /// `n` values as f64; `need` says where `n` comes from (for errors).
    pub(super) fn floats(
        &self,
        d: &ArrayDesc,
        n: Option<usize>,
        need: &str,
    ) -> Result<Vec<f64>, MeshError> {
        let n = self.count(d, n, need)?;
        let t = self.ty(d)?;
        self.values(
            d,
            n,
            t,
            need,
            |c, n| c.ascii_f64(n, "the values").map(|r| r.0),
            |data, out| t.decode_f64(data, self.big, out),
        )
    }

    /// `n` integers; `need` says where `n` comes from (for errors).
    pub(super) fn ints(
        &self,
        d: &ArrayDesc,
        n: Option<usize>,
        need: &str,
    ) -> Result<Vec<i64>, MeshError> {
        let n = self.count(d, n, need)?;
        let t = self.ty(d)?;
        if t.is_float() {
            return Err(self.err(d, format!("{} must be an integer type", t.xml_name())));
        }
        self.values(
            d,
            n,
            t,
            need,
            |c, n| c.ascii_int(n, "the values"),
            |data, out| t.decode_int(data, self.big, out),
        )
    }

    /// The value count, or an error where it overflowed.
    fn count(&self, d: &ArrayDesc, n: Option<usize>, need: &str) -> Result<usize, MeshError> {
        n.ok_or_else(|| self.err(d, format!("the value count ({need}) overflows")))
    }

    /// `n` values of type `t`: read from text by `ascii`, or decoded from the binary
    /// bytes by `decode`.
    fn values<T>(
        &self,
        d: &ArrayDesc,
        n: usize,
        t: Num,
        need: &str,
        ascii: impl Fn(&mut Cursor, usize) -> Result<Vec<T>, MeshError>,
        decode: impl FnOnce(&[u8], &mut Vec<T>),
    ) -> Result<Vec<T>, MeshError> {
        if d.format == Format::Ascii {
            return self.ascii(d, n, need, ascii);
        }
        let data = self.binary(d, n, t, need)?;
        let mut out = vec_for(n, "values").map_err(|m| self.err(d, m.into()))?;
        decode(&data, &mut out);
        Ok(out)
    }

    /// Check, without decoding or inflating anything, that `d` holds `n` values: an
    /// ASCII array's numbers are counted, a binary one's header (the byte count, or the
    /// block count, block size and last block size of a zlib table) must declare the
    /// bytes `n` values need. `need` says where `n` comes from.
    pub(super) fn precheck(
        &self,
        d: &ArrayDesc,
        n: Option<usize>,
        need: &str,
    ) -> Result<(), MeshError> {
        let n = self.count(d, n, need)?;
        let t = self.ty(d)?;
        if d.format == Format::Ascii {
            let held = count_words(d);
            if held != n {
                return Err(self.err(d, format!("holds {held} values, but {need} needs {n}")));
            }
            return Ok(());
        }
        let want = (n as u64).saturating_mul(t.size() as u64);
        let need = format!("{need} x {} bytes", t.size());
        let h = self.header.size();
        let ints = if self.zlib { 3 } else { 1 };
        let Some(head) = self.head_bytes(d, ints * h) else {
            // Too short or not decodable: decoding says where and why.
            return Ok(());
        };
        let v = self.table(&head);
        if !self.zlib {
            if v[0] != want {
                return Err(self.err(
                    d,
                    format!(
                        "the header says {} bytes, but {want} are needed ({need})",
                        v[0]
                    ),
                ));
            }
            return Ok(());
        }
        let (blocks, block) = (v[0], v[1]);
        let last = if v[2] == 0 { block } else { v[2] };
        let total = if blocks == 0 {
            Some(0)
        } else {
            (blocks - 1)
                .checked_mul(block)
                .and_then(|t| t.checked_add(last))
        };
        if total != Some(want) {
            return Err(self.err(d, format!(
                "the compression header declares {blocks} blocks of {block} bytes (last {last}): {} bytes, but {want} are needed ({need})",
                total.map_or("too many".into(), |t| t.to_string())
            )));
        }
        Ok(())
    }

    /// The first `len` bytes of a binary or appended array's data (its header), decoded
    /// from base64 where it is; `None` when the file does not hold them.
    fn head_bytes(&self, d: &ArrayDesc, len: usize) -> Option<Vec<u8>> {
        let dec = |s: &[u8]| {
            base64::engine::general_purpose::STANDARD
                .decode(s)
                .ok()
                .filter(|b| b.len() >= len)
                .map(|b| b[..len].to_vec())
        };
        match d.format {
            Format::Ascii => None,
            Format::Binary => {
                let text: Vec<u8> = d
                    .text
                    .iter()
                    .flat_map(|t| t.1.iter().copied())
                    .filter(|b| !b.is_ascii_whitespace())
                    .take(chars(len))
                    .collect();
                dec(&text)
            }
            Format::Appended => {
                let (start, b64) = self.appended?;
                let at = usize::try_from(d.offset?).ok()?.checked_add(start)?;
                if b64 {
                    dec(self.bytes.get(at..at.checked_add(chars(len))?)?)
                } else {
                    self.bytes.get(at..at.checked_add(len)?).map(<[u8]>::to_vec)
                }
            }
        }
    }

    /// `n` ASCII values from the element's text; more or fewer is an error.
    fn ascii<T>(
        &self,
        d: &ArrayDesc,
        n: usize,
        need: &str,
        read: impl Fn(&mut Cursor, usize) -> Result<Vec<T>, MeshError>,
    ) -> Result<Vec<T>, MeshError> {
        // Count first: a count that disagrees with the piece is told as such, not as a
        // value missing at the end of the element.
        let held = count_words(d);
        if held != n {
            return Err(self.err(d, format!("holds {held} values, but {need} needs {n}")));
        }
        let Some(&(start, _)) = d.text.iter().find(|t| !t.1.trim_ascii().is_empty()) else {
            return Ok(Vec::new());
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

    /// The data bytes of a binary or appended array that must hold `n` values of `t`
    /// (`need` says where `n` comes from).
    fn binary(
        &self,
        d: &ArrayDesc,
        n: usize,
        t: Num,
        need: &str,
    ) -> Result<Cow<'_, [u8]>, MeshError> {
        let want = n
            .checked_mul(t.size())
            .ok_or_else(|| self.err(d, format!("the byte count ({need}) overflows")))?;
        let need = format!("{need} x {} bytes", t.size());
        match d.format {
            Format::Binary => {
                let text: Vec<u8> = d
                    .text
                    .iter()
                    .flat_map(|t| t.1.iter().copied())
                    .filter(|b| !b.is_ascii_whitespace())
                    .collect();
                Ok(Cow::Owned(self.base64(d, &text, want, &need)?.0))
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
                let (data, used) = if b64 {
                    let (data, used) = self.base64(d, rest, want, &need)?;
                    (Cow::Owned(data), used)
                } else {
                    self.raw(d, rest, at, want, &need)?
                };
                self.appended_end
                    .set(self.appended_end.get().max(at + used));
                Ok(data)
            }
        }
    }

    fn uint(&self, b: &[u8]) -> u64 {
        let mut v = Vec::with_capacity(1);
        self.header.decode_int(b, self.big, &mut v);
        v.first().map_or(0, |&x| x as u64)
    }

    /// Raw appended data at `at` (`rest` the file from there): the bytes and how many
    /// of the file's bytes they used.
    fn raw<'b>(
        &self,
        d: &ArrayDesc,
        rest: &'b [u8],
        at: usize,
        want: usize,
        need: &str,
    ) -> Result<(Cow<'b, [u8]>, usize), MeshError> {
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
                    format!("the header says {v0} bytes, but {want} are needed ({need})"),
                ));
            }
            let data = rest.get(h..h + want).ok_or_else(|| trunc("data"))?;
            return Ok((Cow::Borrowed(data), h + want));
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
        let used = hb + body.len();
        Ok((Cow::Owned(self.inflate(d, &table, body, want, need)?), used))
    }

    fn table(&self, b: &[u8]) -> Vec<u64> {
        let mut v = Vec::new();
        self.header.decode_int(b, self.big, &mut v);
        v.into_iter().map(|x| x as u64).collect()
    }

    /// Base64 `text` (whitespace removed for inline arrays): the decoded (and inflated)
    /// bytes and how many characters of `text` they used.
    fn base64(
        &self,
        d: &ArrayDesc,
        text: &[u8],
        want: usize,
        need: &str,
    ) -> Result<(Vec<u8>, usize), MeshError> {
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
        let head = head.get(..hb).ok_or_else(|| {
            self.err(
                d,
                format!(
                    "the base64 header decodes to {} bytes, but {} {}-byte integers ({}) are needed: the header is cut short",
                    head.len(),
                    hb / h,
                    h,
                    if self.zlib {
                        format!("the block count {v0}, the block size, the last block's size and {v0} compressed sizes")
                    } else {
                        "the byte count".to_string()
                    }
                ),
            )
        })?;
        let table = self.table(head);
        let body_len = if self.zlib {
            compressed_len(&table)
                .ok_or_else(|| self.err(d, "the compressed sizes overflow".into()))?
        } else {
            if v0 != want as u64 {
                return Err(self.err(
                    d,
                    format!("the header says {v0} bytes, but {want} are needed ({need})"),
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
        let (body, used) = if separate {
            let s = text
                .get(hc..hc + chars(body_len))
                .ok_or_else(|| self.err(d, "the base64 text ends inside its data".into()))?;
            (dec(s, "data")?, hc + chars(body_len))
        } else {
            let all = dec(part(chars(hb + body_len), "data")?, "data")?;
            (
                all.get(hb..hb + body_len).unwrap_or(&[]).to_vec(),
                chars(hb + body_len),
            )
        };
        let body = body.get(..body_len).ok_or_else(|| {
            self.err(d, "the base64 data are shorter than the header says".into())
        })?;
        if self.zlib {
            Ok((self.inflate(d, &table, body, want, need)?, used))
        } else {
            Ok((body.to_vec(), used))
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
        need: &str,
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
                "the compression header declares {n} blocks of {block} bytes (last {last}): {} bytes, but {want} are needed ({need})",
                total.map_or("too many".into(), |t| t.to_string())
            )));
        }
        // Every block's claim is checked before any is inflated.
        let size = |i: usize| if i as u64 + 1 == n { last } else { block };
        for (i, &c) in table[3..].iter().enumerate() {
            let u = size(i);
            if u > c.saturating_mul(MAX_INFLATE_RATIO).saturating_add(64) {
                return Err(self.err(d, format!(
                    "block {i} declares {u} bytes from {c} compressed bytes, more than deflate can produce"
                )));
            }
        }
        let mut out = vec_for(want, "bytes").map_err(|m| self.err(d, m.into()))?;
        let mut pos = 0usize;
        for (i, &c) in table[3..].iter().enumerate() {
            let u = size(i);
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

/// Whitespace-separated words in an ASCII array's text.
fn count_words(d: &ArrayDesc) -> usize {
    d.text
        .iter()
        .map(|t| {
            t.1.split(|b| b.is_ascii_whitespace())
                .filter(|w| !w.is_empty())
                .count()
        })
        .sum()
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
