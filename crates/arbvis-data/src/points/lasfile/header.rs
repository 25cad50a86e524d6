//! What the LAS reader's parts share: the header facts ([`LasInfo`]) and the record
//! sizes of the point formats.

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
