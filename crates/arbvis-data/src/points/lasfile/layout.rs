//! One reader of a LAS 1.0-1.4 file's layout: the header's fields ([`RawHeader`], read
//! once, unchecked) and the walk over its VLRs and EVLRs ([`Walk`], each record checked
//! to lie before the point data or inside the file). The LAS/LAZ checks, COPC's `open`
//! and the viewer's units read headers through it; each caller judges the fields and
//! words its own errors. Offsets follow the LAS 1.4 R15 specification.

use std::ops::Range;

use crate::le::{f64_at, text_at, u16_at, u16_get, u32_at, u32_get, u64_at};

/// Bytes of a LAS 1.0-1.2 header, the least any version has.
pub const HEADER_MIN: usize = 227;
/// Bytes of a LAS 1.4 header.
pub const HEADER_14: usize = 375;
/// Bytes of a VLR's header.
pub const VLR_HEADER: u64 = 54;
/// Bytes of an EVLR's header.
pub const EVLR_HEADER: u64 = 60;

/// The fields of a LAS header as stored, unchecked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawHeader {
    /// Version, major and minor (bytes 24, 25).
    pub version: (u8, u8),
    /// Header size (byte 94).
    pub header_size: u16,
    /// Offset to the point data (byte 96).
    pub point_offset: u32,
    /// Number of VLRs (byte 100).
    pub vlr_count: u32,
    /// Point data format byte, with the compression bits (byte 104).
    pub format_byte: u8,
    /// Point record length (byte 105).
    pub record_length: u16,
    /// The legacy 32-bit point count (byte 107).
    pub legacy_count: u32,
    /// Scale factors of x, y, z (byte 131).
    pub scale: [f64; 3],
    /// Offsets of x, y, z (byte 155).
    pub offset: [f64; 3],
    /// Bounds (min, max) of x, y, z (bytes 179-226, stored max x, min x, max y, ...).
    pub bounds: [[f64; 3]; 2],
    /// Start of the first EVLR (byte 235; LAS 1.4 fields are 0 in a shorter slice).
    pub evlr_start: u64,
    /// Number of EVLRs (byte 243).
    pub evlr_count: u32,
    /// LAS 1.4's 64-bit point count (byte 247).
    pub count_64: u64,
}

impl RawHeader {
    /// The header in `b` (a file's first bytes); `None` when it holds less than
    /// [`HEADER_MIN`] bytes. The LAS 1.4 fields are read when `b` holds [`HEADER_14`].
    pub fn parse(b: &[u8]) -> Option<RawHeader> {
        if b.len() < HEADER_MIN {
            return None;
        }
        let read3 = |at: usize| -> [f64; 3] { std::array::from_fn(|a| f64_at(b, at + 8 * a)) };
        let v14 = b.len() >= HEADER_14;
        Some(RawHeader {
            version: (b[24], b[25]),
            header_size: u16_at(b, 94),
            point_offset: u32_at(b, 96),
            vlr_count: u32_at(b, 100),
            format_byte: b[104],
            record_length: u16_at(b, 105),
            legacy_count: u32_at(b, 107),
            scale: read3(131),
            offset: read3(155),
            bounds: [
                [f64_at(b, 187), f64_at(b, 203), f64_at(b, 219)],
                [f64_at(b, 179), f64_at(b, 195), f64_at(b, 211)],
            ],
            evlr_start: if v14 { u64_at(b, 235) } else { 0 },
            evlr_count: if v14 { u32_at(b, 243) } else { 0 },
            count_64: if v14 { u64_at(b, 247) } else { 0 },
        })
    }

    /// The point format, without the compression bits.
    pub fn point_format(&self) -> u8 {
        self.format_byte & 0x3f
    }

    /// Whether the points are compressed (LAZ).
    pub fn compressed(&self) -> bool {
        self.format_byte & 0x80 != 0
    }
}

/// A VLR or EVLR: where it is and what it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Vlr {
    /// User id, up to its first NUL, trimmed.
    pub user_id: String,
    /// User id, the 16 bytes as stored.
    pub user_raw: [u8; 16],
    /// Record id.
    pub record_id: u16,
    /// Byte offset of the record's header.
    pub at: usize,
    /// Its data (as declared: past the end when the walk refused it).
    pub data: Range<usize>,
}

/// Why a walk stopped.
#[derive(Debug)]
pub enum WalkError {
    /// Record `index`'s header, at `at`, would pass the end.
    Header {
        /// Which record.
        index: u32,
        /// Where its header starts.
        at: u64,
    },
    /// Record `index`'s data would pass the end.
    Data {
        /// Which record.
        index: u32,
        /// The record, its data as declared.
        vlr: Vlr,
        /// Bytes of data it declares.
        size: u64,
    },
    /// Reading a record's header failed.
    Io(std::io::Error),
}

/// A walk over VLRs (54-byte headers, u16 sizes) or EVLRs (60-byte headers, u64 sizes),
/// one after another from a start, each inside `..end`.
pub struct Walk {
    extended: bool,
    at: u64,
    index: u32,
    count: u32,
    end: u64,
}

/// Reads `buf.len()` bytes at an offset of the file (or of bytes held).
pub type ReadAt<'a> = dyn FnMut(u64, &mut [u8]) -> std::io::Result<()> + 'a;

impl Walk {
    /// The `count` VLRs from `header_size`, each before `end` (the point data).
    pub fn vlrs(header_size: u64, count: u32, end: u64) -> Walk {
        Walk {
            extended: false,
            at: header_size,
            index: 0,
            count,
            end,
        }
    }

    /// The `count` EVLRs from `start`, each before `end` (the end of the file).
    pub fn evlrs(start: u64, count: u32, end: u64) -> Walk {
        Walk {
            extended: true,
            at: start,
            index: 0,
            count,
            end,
        }
    }

    /// Where the next record would start (after the last, the end of the records).
    pub fn at(&self) -> u64 {
        self.at
    }

    /// The next record, its header read through `read`; `None` after the last.
    pub fn next(&mut self, read: &mut ReadAt<'_>) -> Option<Result<Vlr, WalkError>> {
        if self.index >= self.count {
            return None;
        }
        let (index, at) = (self.index, self.at);
        let head = if self.extended {
            EVLR_HEADER
        } else {
            VLR_HEADER
        };
        if at > self.end || self.end - at < head {
            self.index = self.count;
            return Some(Err(WalkError::Header { index, at }));
        }
        let mut h = [0u8; EVLR_HEADER as usize];
        let h = &mut h[..head as usize];
        if let Err(e) = read(at, h) {
            self.index = self.count;
            return Some(Err(WalkError::Io(e)));
        }
        let size = if self.extended {
            u64_at(h, 20)
        } else {
            u16_at(h, 20) as u64
        };
        let start = at + head;
        let vlr = Vlr {
            user_id: text_at(h, 2..18),
            user_raw: h[2..18].try_into().expect("16 bytes"),
            record_id: u16_at(h, 18),
            at: at as usize,
            data: start as usize..start.saturating_add(size) as usize,
        };
        if size > self.end - start {
            self.index = self.count;
            return Some(Err(WalkError::Data { index, vlr, size }));
        }
        self.index += 1;
        self.at = start + size;
        Some(Ok(vlr))
    }
}

/// Reads from bytes held in memory (a walk checks each record against them first).
pub fn from_bytes(b: &[u8]) -> impl FnMut(u64, &mut [u8]) -> std::io::Result<()> + '_ {
    move |at, buf| {
        let at = at as usize;
        let src = b
            .get(at..at + buf.len())
            .ok_or(std::io::ErrorKind::UnexpectedEof)?;
        buf.copy_from_slice(src);
        Ok(())
    }
}

/// The VLRs of the LAS header held in `b` (a file's first bytes) that lie whole inside
/// `b`, in order, up to the first that does not; none when `b` is no LAS header. Nothing
/// else is checked: for readers that take what they find (the viewer's units).
pub fn vlrs_in_head(b: &[u8]) -> Vec<Vlr> {
    if b.get(0..4) != Some(b"LASF") {
        return Vec::new();
    }
    let (Some(header), Some(count)) = (u16_get(b, 94), u32_get(b, 100)) else {
        return Vec::new();
    };
    let mut walk = Walk::vlrs(header as u64, count, b.len() as u64);
    let mut read = from_bytes(b);
    std::iter::from_fn(|| walk.next(&mut read)?.ok()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 227-byte LAS 1.2 header followed by VLRs of `sizes` bytes (user `u`, record k).
    fn head(sizes: &[u16]) -> Vec<u8> {
        let mut b = vec![0u8; HEADER_MIN];
        b[0..4].copy_from_slice(b"LASF");
        b[24..26].copy_from_slice(&[1, 2]);
        b[94..96].copy_from_slice(&(HEADER_MIN as u16).to_le_bytes());
        b[100..104].copy_from_slice(&(sizes.len() as u32).to_le_bytes());
        for (k, &n) in sizes.iter().enumerate() {
            let mut h = vec![0u8; VLR_HEADER as usize];
            h[2] = b'u';
            h[18..20].copy_from_slice(&(k as u16).to_le_bytes());
            h[20..22].copy_from_slice(&n.to_le_bytes());
            b.extend(h);
            b.extend(vec![7u8; n as usize]);
        }
        b
    }

    #[test]
    fn the_walk_checks_each_record_against_its_end() {
        let b = head(&[3, 5]);
        let h = RawHeader::parse(&b).unwrap();
        assert_eq!((h.version, h.header_size, h.vlr_count), ((1, 2), 227, 2));
        let mut read = from_bytes(&b);
        let mut walk = Walk::vlrs(227, 2, b.len() as u64);
        let a = walk.next(&mut read).unwrap().unwrap();
        assert_eq!(
            (a.user_id.as_str(), a.record_id, a.at, a.data),
            ("u", 0, 227, 281..284)
        );
        let c = walk.next(&mut read).unwrap().unwrap();
        assert_eq!((c.at, c.data), (284, 338..343));
        assert!(walk.next(&mut read).is_none());
        assert_eq!(walk.at(), b.len() as u64);
        // Data past the end, then a header past it: each refused once, the walk over.
        let mut walk = Walk::vlrs(227, 2, b.len() as u64 - 1);
        walk.next(&mut read).unwrap().unwrap();
        match walk.next(&mut read) {
            Some(Err(WalkError::Data {
                index: 1,
                vlr,
                size: 5,
            })) => assert_eq!(vlr.at, 284),
            other => panic!("{other:?}"),
        }
        assert!(walk.next(&mut read).is_none());
        let mut walk = Walk::evlrs(b.len() as u64 - 10, u32::MAX, b.len() as u64);
        assert!(matches!(
            walk.next(&mut read),
            Some(Err(WalkError::Header { index: 0, .. }))
        ));
    }

    #[test]
    fn vlrs_in_head_takes_those_that_fit() {
        let b = head(&[3, 5]);
        assert_eq!(vlrs_in_head(&b).len(), 2);
        assert_eq!(vlrs_in_head(&b[..b.len() - 1]).len(), 1);
        assert!(vlrs_in_head(b"LASF").is_empty());
        assert!(vlrs_in_head(&b[4..]).is_empty());
        let mut many = head(&[]);
        many[100..104].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(vlrs_in_head(&many).is_empty());
        assert!(RawHeader::parse(&b[..HEADER_MIN - 1]).is_none());
    }
}
