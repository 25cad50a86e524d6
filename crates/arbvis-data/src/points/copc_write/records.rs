//! The records a COPC file holds: LAS 1.4 point formats 6 (no colour), 7 (RGB) or 8
//! (RGB and near infrared), each followed by the input's extra bytes. Records of the
//! legacy formats 0-5 are rewritten field by field (LAS 1.4 R15, tables 7-17): return
//! numbers widen to 4 bits, the classification to a byte, the scan angle rank (whole
//! degrees) becomes the scaled angle (0.006°), a missing GPS time is 0; formats 9 and 10
//! lose their wave packets (COPC has no waveform formats).

/// Bytes of a record of each LAS point format, without extra bytes.
pub(crate) const BASE: [usize; 11] = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67];

/// The output format for an input format: 8 where there is near infrared, 7 where there
/// is colour, else 6.
pub(crate) fn output_format(input: u8) -> u8 {
    match input {
        8 | 10 => 8,
        2 | 3 | 5 | 7 => 7,
        _ => 6,
    }
}

/// Byte offset of the RGB triple in a record of `format`, if it has one.
fn rgb_at(format: u8) -> Option<usize> {
    match format {
        2 => Some(20),
        3 | 5 => Some(28),
        7 | 8 | 10 => Some(30),
        _ => None,
    }
}

/// Byte offset of the GPS time in a record of `format`, if it has one.
fn gps_at(format: u8) -> Option<usize> {
    match format {
        1 | 3 | 4 | 5 => Some(20),
        6..=10 => Some(22),
        _ => None,
    }
}

/// Rewrite one record of input format `from` (`input.len()` bytes, extra bytes after its
/// base) as a record of format `to` (6, 7 or 8) with the same extra bytes, appended to
/// `out`.
pub(crate) fn convert(from: u8, to: u8, input: &[u8], out: &mut Vec<u8>) {
    let base_in = BASE[from as usize];
    let start = out.len();
    if from >= 6 {
        // Same layout up to the GPS time; RGB and NIR where both have them.
        out.extend_from_slice(&input[..30]);
    } else {
        out.extend_from_slice(&input[..14]);
        let (a, b) = (input[14], input[15]);
        let returns = (a & 7) | ((a >> 3) & 7) << 4;
        let class_flags = (b >> 5) & 7; // synthetic, key-point, withheld
        let flags = class_flags | ((a >> 6) & 1) << 6 | ((a >> 7) & 1) << 7;
        let angle = ((input[16] as i8 as f64) / 0.006).round() as i16;
        out.extend_from_slice(&[returns, flags, b & 31, input[17]]);
        out.extend_from_slice(&angle.to_le_bytes());
        out.extend_from_slice(&input[18..20]);
        match gps_at(from) {
            Some(at) => out.extend_from_slice(&input[at..at + 8]),
            None => out.extend_from_slice(&[0; 8]),
        }
    }
    if to >= 7 {
        match rgb_at(from) {
            Some(at) => out.extend_from_slice(&input[at..at + 6]),
            None => out.extend_from_slice(&[0; 6]),
        }
    }
    if to == 8 {
        // Only formats 8 and 10 have NIR (map to 8), right after RGB.
        out.extend_from_slice(&input[36..38]);
    }
    debug_assert_eq!(out.len() - start, BASE[to as usize]);
    out.extend_from_slice(&input[base_in..]);
}

/// The integer coordinates of a record.
pub(crate) fn xyz(record: &[u8]) -> [i32; 3] {
    std::array::from_fn(|a| i32::from_le_bytes(record[4 * a..4 * a + 4].try_into().expect("4")))
}

/// The GPS time of a record of format 6-8.
pub(crate) fn gps_time(record: &[u8]) -> f64 {
    f64::from_le_bytes(record[22..30].try_into().expect("8"))
}

/// The return number (1-15) of a record of format 6-8.
pub(crate) fn return_number(record: &[u8]) -> u8 {
    record[14] & 15
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A format 3 record (GPS and RGB) with two extra bytes becomes format 7, field by
    /// field.
    #[test]
    fn legacy_record_becomes_format_7() {
        let mut r = vec![0u8; 36];
        r[0..4].copy_from_slice(&(-5i32).to_le_bytes());
        r[4..8].copy_from_slice(&7i32.to_le_bytes());
        r[8..12].copy_from_slice(&123456i32.to_le_bytes());
        r[12..14].copy_from_slice(&900u16.to_le_bytes());
        r[14] = 2 | 3 << 3 | 1 << 6 | 1 << 7; // return 2 of 3, scan direction, edge
        r[15] = 9 | 1 << 5 | 1 << 7; // class 9, synthetic, withheld
        r[16] = (-15i8) as u8; // -15 degrees
        r[17] = 77;
        r[18..20].copy_from_slice(&4321u16.to_le_bytes());
        r[20..28].copy_from_slice(&1.5e8f64.to_le_bytes());
        r[28..34].copy_from_slice(&[1, 2, 3, 4, 5, 6]);
        r[34..36].copy_from_slice(&[0xAB, 0xCD]);
        let mut out = Vec::new();
        convert(3, output_format(3), &r, &mut out);
        assert_eq!(out.len(), 38);
        assert_eq!(xyz(&out), [-5, 7, 123456]);
        assert_eq!(u16::from_le_bytes([out[12], out[13]]), 900);
        assert_eq!(return_number(&out), 2);
        assert_eq!(out[14] >> 4, 3);
        assert_eq!(out[15], 1 | 4 | 1 << 6 | 1 << 7);
        assert_eq!(out[16], 9);
        assert_eq!(out[17], 77);
        assert_eq!(i16::from_le_bytes([out[18], out[19]]), -2500);
        assert_eq!(u16::from_le_bytes([out[20], out[21]]), 4321);
        assert_eq!(gps_time(&out), 1.5e8);
        assert_eq!(&out[30..36], &[1, 2, 3, 4, 5, 6]);
        assert_eq!(&out[36..38], &[0xAB, 0xCD]);
    }

    /// A format 0 record gets GPS time 0; format 10 keeps NIR and drops its wave packet.
    #[test]
    fn missing_fields_are_zero_and_wave_packets_go() {
        let r0: Vec<u8> = (0..20).collect();
        let mut out = Vec::new();
        convert(0, 6, &r0, &mut out);
        assert_eq!(out.len(), 30);
        assert_eq!(gps_time(&out), 0.0);
        let r10: Vec<u8> = (0..67).collect();
        out.clear();
        convert(10, output_format(10), &r10, &mut out);
        assert_eq!(out, (0..38).collect::<Vec<u8>>());
    }
}
