//! What the LAS reader's parts share: the header facts ([`LasInfo`]), the raw VLRs found
//! by the checks, the record sizes of the point formats and little-endian readers.

use crate::points::{decimals_for, fixed};

/// Header facts of a LAS/LAZ file.
#[derive(Debug, Clone, PartialEq)]
pub struct LasInfo {
    /// Version, major and minor.
    pub version: (u8, u8),
    /// Point data record format (0-10), without the compression bit.
    pub point_format: u8,
    /// True for LAZ.
    pub compressed: bool,
    /// Bytes per point record (uncompressed).
    pub record_length: u16,
    /// Points declared by the header.
    pub points: u64,
    /// Scale factors of x, y, z.
    pub scale: [f64; 3],
    /// Offsets of x, y, z.
    pub offset: [f64; 3],
    /// Bounds written in the header (min, max).
    pub header_bounds: [[f64; 3]; 2],
    /// Names of the extra-bytes attributes read.
    pub extra_bytes: Vec<String>,
}

impl LasInfo {
    /// The format lines of `arbvis inspect`.
    pub fn describe(&self) -> String {
        let [lo, hi] = self.header_bounds;
        // Bounds with the decimals of the header's scale factors (0.01 → 2).
        let d: [usize; 3] = std::array::from_fn(|a| decimals_for(self.scale[a]));
        let b = |v: f64, a: usize| fixed(v, d[a]);
        format!(
            "format: LAS {}.{}, point format {}, {}, {}-byte records\nheader: {} points, scale {} {} {}, offset {} {} {}, bounds x {} .. {}, y {} .. {}, z {} .. {}\nextra bytes: {}\n",
            self.version.0,
            self.version.1,
            self.point_format,
            if self.compressed { "compressed (LAZ)" } else { "uncompressed" },
            self.record_length,
            self.points,
            self.scale[0],
            self.scale[1],
            self.scale[2],
            self.offset[0],
            self.offset[1],
            self.offset[2],
            b(lo[0], 0),
            b(hi[0], 0),
            b(lo[1], 1),
            b(hi[1], 1),
            b(lo[2], 2),
            b(hi[2], 2),
            if self.extra_bytes.is_empty() {
                "none".to_string()
            } else {
                self.extra_bytes.join(", ")
            }
        )
    }
}

/// Bytes of a point record of each format, without extra bytes.
pub(super) const RECORD_LENGTH: [u16; 11] = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67];

/// A variable length record: where its data is in the file.
pub(super) struct RawVlr {
    pub(super) user_id: String,
    pub(super) record_id: u16,
    /// Byte offset of the record's header.
    pub(super) at: usize,
    /// Its data.
    pub(super) data: std::ops::Range<usize>,
}

pub(super) fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}
pub(super) fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
pub(super) fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}
pub(super) fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}
pub(super) fn text_at(b: &[u8], range: std::ops::Range<usize>) -> String {
    let s = &b[range];
    let end = s.iter().position(|&c| c == 0).unwrap_or(s.len());
    String::from_utf8_lossy(&s[..end]).trim().to_string()
}
