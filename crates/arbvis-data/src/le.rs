//! Little-endian field reads from byte slices, one set for every binary header read
//! here (LAS/LAZ, COPC, the viewer's units). The `*_at` readers panic on a slice too
//! short: call them on bytes whose length was checked; the `*_get` ones return `None`.

use std::ops::Range;

/// The u16 at byte `at`.
pub fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

/// The u32 at byte `at`.
pub fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// The u64 at byte `at`.
pub fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

/// The f64 at byte `at`.
pub fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}

/// The u16 at byte `at`, if the slice holds it.
pub fn u16_get(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(
        b.get(at..at.checked_add(2)?)?.try_into().ok()?,
    ))
}

/// The u32 at byte `at`, if the slice holds it.
pub fn u32_get(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

/// The text in `range`, up to its first NUL, trimmed (invalid UTF-8 replaced).
pub fn text_at(b: &[u8], range: Range<usize>) -> String {
    let s = &b[range];
    let end = s.iter().position(|&c| c == 0).unwrap_or(s.len());
    String::from_utf8_lossy(&s[..end]).trim().to_string()
}
