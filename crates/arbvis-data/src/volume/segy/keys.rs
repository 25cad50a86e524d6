//! Which trace-header bytes hold the inline and crossline numbers. SEG-Y rev 1 puts them at
//! bytes 189 and 193, but files in the wild keep them elsewhere (the field record number at
//! 9 with the CDP at 21, the energy source point at 17 with the field record's trace number
//! at 13).
//! A scene, `inspect` and `convert` may name them (`iline`/`xline`, 1-based, 4-byte
//! integers, as segyio's `iline`/`xline` and mdio-python's header overrides take them);
//! otherwise the first of [`LAYOUTS`] whose numbers look like a grid in the file's first
//! traces is taken, and rev 1's bytes where none does.

use arbvis_core::vocab::FieldError;
use std::collections::HashSet;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::volume::VolumeError;

/// Trace-header bytes (1-based) as a user names them; `None` is detected.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyBytes {
    /// The inline number's first byte (segyio's `iline`; rev 1: 189).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iline: Option<u16>,
    /// The crossline number's first byte (segyio's `xline`; rev 1: 193).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub xline: Option<u16>,
}

impl KeyBytes {
    /// Both named, or neither.
    pub fn is_default(&self) -> bool {
        *self == KeyBytes::default()
    }

    /// Each named byte holds a 4-byte integer inside the 240-byte trace header.
    pub fn validate(&self) -> Result<(), FieldError> {
        for (name, b) in [("iline", self.iline), ("xline", self.xline)] {
            if let Some(b) = b {
                if !(1..=237).contains(&b) {
                    return Err(FieldError::new("", format!(
                        "{name} = {b}: a 4-byte number's first byte in the 240-byte trace header, 1..=237"
                    )));
                }
            }
        }
        if self.iline.is_some() && self.iline == self.xline {
            return Err(FieldError::new(
                "",
                format!(
                    "iline and xline are both byte {}: they must differ",
                    self.iline.unwrap_or(0)
                ),
            ));
        }
        Ok(())
    }
}

/// The layouts tried, in order: (inline byte, crossline byte, what the bytes are).
pub const LAYOUTS: [(u16, u16, &str); 3] = [
    (189, 193, "SEG-Y rev 1's inline and crossline numbers"),
    (9, 21, "the field record number and the CDP ensemble number"),
    (
        17,
        13,
        "the energy source point number and the trace number in the field record",
    ),
];

/// How the bytes in use were chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeysFrom {
    /// Named by the scene or the command line.
    Named,
    /// The first of [`LAYOUTS`] that looks like a grid in the first traces.
    Detected(&'static str),
    /// None looked like a grid: rev 1's bytes, for the gridding to judge.
    Standard,
}

/// The trace-header bytes in use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Keys {
    /// The inline number's first byte (1-based).
    pub iline: u16,
    /// The crossline number's first byte (1-based).
    pub xline: u16,
    /// Named, detected or the standard's.
    pub from: KeysFrom,
}

impl Default for Keys {
    fn default() -> Keys {
        Keys {
            iline: 189,
            xline: 193,
            from: KeysFrom::Standard,
        }
    }
}

impl Keys {
    /// The inline and crossline numbers of one trace header.
    pub fn read(&self, header: &[u8], big: bool) -> (i32, i32) {
        (
            super::header_i32(header, self.iline as usize - 1, big),
            super::header_i32(header, self.xline as usize - 1, big),
        )
    }

    /// `bytes 189 and 193` with how they were chosen, for `inspect` and errors.
    pub fn describe(&self) -> String {
        let how = match self.from {
            KeysFrom::Named => "as named".to_string(),
            KeysFrom::Detected(what) => format!("detected: {what}"),
            KeysFrom::Standard => {
                "SEG-Y rev 1's; no layout tried looked like a grid in the first traces, name them with iline and xline".to_string()
            }
        };
        format!("trace bytes {} and {} ({how})", self.iline, self.xline)
    }
}

/// Traces read to detect the layout: the file's first ones.
const DETECT_TRACES: usize = 2048;

/// The bytes to grid by: those `named`, else detected from the first traces'
/// headers (`header(t)` is trace `t`'s 240-byte header).
pub(crate) fn resolve(
    path: &Path,
    named: KeyBytes,
    traces: usize,
    big: bool,
    mut header: impl FnMut(usize) -> Result<[u8; 240], VolumeError>,
) -> Result<Keys, VolumeError> {
    named.validate().map_err(|e| VolumeError::Unsupported {
        path: path.into(),
        message: e.message,
    })?;
    if let (Some(iline), Some(xline)) = (named.iline, named.xline) {
        return Ok(Keys {
            iline,
            xline,
            from: KeysFrom::Named,
        });
    }
    let n = traces.min(DETECT_TRACES);
    let headers: Vec<[u8; 240]> = (0..n).map(&mut header).collect::<Result<_, _>>()?;
    // Only the layouts that agree with a byte the user named.
    let candidates = LAYOUTS.iter().filter(|(il, xl, _)| {
        named.iline.is_none_or(|b| b == *il) && named.xline.is_none_or(|b| b == *xl)
    });
    for &(iline, xline, what) in candidates {
        let keys = Keys {
            iline,
            xline,
            from: KeysFrom::Detected(what),
        };
        let traces = headers.iter().map(|h| {
            let (il, xl) = keys.read(h, big);
            (il, xl, super::header_i32(h, 36, big))
        });
        if looks_like_a_grid(traces) {
            return Ok(keys);
        }
    }
    Ok(Keys {
        iline: named.iline.unwrap_or(189),
        xline: named.xline.unwrap_or(193),
        from: if named.is_default() {
            KeysFrom::Standard
        } else {
            KeysFrom::Named
        },
    })
}

/// Whether these (inline, crossline, offset) numbers of consecutive traces look like part
/// of a grid: no trace twice at one position and offset (a pre-stack gather holds one trace
/// per offset), and (with several traces) one of the two numbers repeating, as it does
/// along a line of a sorted survey. Two running counters (trace sequence numbers) never
/// repeat either number: they are not a grid.
fn looks_like_a_grid(traces: impl Iterator<Item = (i32, i32, i32)>) -> bool {
    let mut seen = HashSet::new();
    let (mut inlines, mut crosslines, mut positions) =
        (HashSet::new(), HashSet::new(), HashSet::new());
    for (il, xl, offset) in traces {
        if !seen.insert((il, xl, offset)) {
            return false;
        }
        inlines.insert(il);
        crosslines.insert(xl);
        positions.insert((il, xl));
    }
    let n = positions.len();
    if n < 4 {
        // Too few positions to tell: any numbers will do.
        return n > 0;
    }
    inlines.len().min(crosslines.len()) <= n / 2
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header_with(at: &[(u16, i32)]) -> [u8; 240] {
        let mut h = [0u8; 240];
        for &(byte, v) in at {
            h[byte as usize - 1..][..4].copy_from_slice(&v.to_be_bytes());
        }
        h
    }

    /// A 5 x 7 grid, inline-sorted, numbered as a file would with the keys at `il` and
    /// `xl`, and trace sequence numbers at bytes 1 and 5 (never a grid).
    fn survey(il: u16, xl: u16) -> Vec<[u8; 240]> {
        let mut out = Vec::new();
        for i in 0..5 {
            for j in 0..7 {
                let t = i * 7 + j;
                out.push(header_with(&[
                    (1, t + 1),
                    (5, t + 1),
                    (il, 1000 + 2 * i),
                    (xl, 20 + j),
                ]));
            }
        }
        out
    }

    fn detect(headers: &[[u8; 240]], named: KeyBytes) -> Keys {
        resolve(Path::new("x.sgy"), named, headers.len(), true, |t| {
            Ok(headers[t])
        })
        .unwrap()
    }

    #[test]
    fn each_layout_is_found_where_its_numbers_are() {
        for (il, xl, what) in LAYOUTS {
            let k = detect(&survey(il, xl), KeyBytes::default());
            assert_eq!(
                (k.iline, k.xline, k.from),
                (il, xl, KeysFrom::Detected(what))
            );
        }
    }

    #[test]
    fn named_bytes_win_and_bad_ones_are_refused() {
        let h = survey(189, 193);
        let named = KeyBytes {
            iline: Some(9),
            xline: Some(21),
        };
        assert_eq!(detect(&h, named).from, KeysFrom::Named);
        for bad in [(0, 193), (238, 193), (189, 189)] {
            let named = KeyBytes {
                iline: Some(bad.0),
                xline: Some(bad.1),
            };
            let e = resolve(Path::new("x.sgy"), named, h.len(), true, |t| Ok(h[t]));
            assert!(e.is_err(), "{bad:?}");
        }
    }

    #[test]
    fn counters_and_constants_are_no_grid() {
        // Only sequence numbers (bytes 1 and 5 both count up): the standard's bytes, said so.
        let mut h = survey(189, 193);
        for x in &mut h {
            x[188..196].fill(0);
        }
        let k = detect(&h, KeyBytes::default());
        assert_eq!((k.iline, k.xline, k.from), (189, 193, KeysFrom::Standard));
        assert!(k.describe().contains("name them with iline and xline"));
        // A crossline-sorted survey (crosslines outer) is a grid too.
        let mut t = Vec::new();
        for j in 0..7 {
            for i in 0..5 {
                t.push(header_with(&[(9, 1000 + i), (21, 20 + j)]));
            }
        }
        assert_eq!(detect(&t, KeyBytes::default()).iline, 9);
    }
}
