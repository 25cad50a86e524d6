//! The reading layer of gmsh files: integers and reals in ASCII or binary (either byte
//! order, 4- or 8-byte sizes), section end lines, and node/element tag tables.

use std::collections::HashMap;

use crate::mesh::read::{quote, Cursor};
use crate::mesh::MeshError;

/// A cursor over a gmsh file and how its numbers are stored.
pub(super) struct Reader<'a> {
    /// The cursor.
    pub c: Cursor<'a>,
    /// Binary file type.
    pub binary: bool,
    /// Big-endian binary.
    pub big: bool,
    /// Bytes of a `size_t` (binary 4.1).
    pub size_t: usize,
}

impl Reader<'_> {
    pub(super) fn err(&self, at: usize, m: impl Into<String>) -> MeshError {
        if self.binary {
            self.c.err_bin(at, m)
        } else {
            self.c.err(at, m)
        }
    }

    /// An integer: ASCII token, or binary of `width` bytes (signed when `width == 4`).
    pub(super) fn int(&mut self, width: usize, what: &str) -> Result<(usize, i64), MeshError> {
        if !self.binary {
            return self.c.parse_with::<i64>(|| what.to_string());
        }
        let at = self.c.pos;
        let b = self.c.take(width, what)?;
        let v = if width == 4 {
            let a = [b[0], b[1], b[2], b[3]];
            i64::from(if self.big {
                i32::from_be_bytes(a)
            } else {
                i32::from_le_bytes(a)
            })
        } else {
            let mut a = [0u8; 8];
            a.copy_from_slice(b);
            let u = if self.big {
                u64::from_be_bytes(a)
            } else {
                u64::from_le_bytes(a)
            };
            i64::try_from(u).unwrap_or(i64::MAX)
        };
        Ok((at, v))
    }

    /// A non-negative count whose items need at least `min` bytes each (ASCII: `min_text`).
    pub(super) fn count(
        &mut self,
        width: usize,
        what: &str,
        min: usize,
        min_text: usize,
    ) -> Result<usize, MeshError> {
        let (at, n) = self.int(width, what)?;
        if n < 0 {
            return Err(self.err(at, format!("{what} is negative: {n}")));
        }
        self.c
            .check_fits(at, what, n as u64, if self.binary { min } else { min_text })
    }

    pub(super) fn f64(&mut self, what: &str) -> Result<(usize, f64), MeshError> {
        if !self.binary {
            return self.c.parse_with::<f64>(|| what.to_string());
        }
        let at = self.c.pos;
        let b = self.c.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok((
            at,
            if self.big {
                f64::from_be_bytes(a)
            } else {
                f64::from_le_bytes(a)
            },
        ))
    }

    /// The section's end line `$End<name>`.
    pub(super) fn end(&mut self, name: &str) -> Result<(), MeshError> {
        let want = format!("$End{name}");
        let (at, t) = self.c.need(&want)?;
        if t != want.as_bytes() {
            return Err(self
                .c
                .err(at, format!("expected {want}, found {}", quote(t))));
        }
        Ok(())
    }
}

/// Tag to index: a table indexed by tag while the tags stay compact (gmsh writes 1..n),
/// a hash map once one does not (sparse tags stay correct, only slower).
pub(super) enum TagMap {
    Dense(Vec<u32>),
    Sparse(HashMap<i64, u32>),
}

const NO_INDEX: u32 = u32::MAX;

impl Default for TagMap {
    fn default() -> Self {
        TagMap::Dense(Vec::new())
    }
}

impl TagMap {
    /// Map `tag` to `index`; false if the tag is already there. Tags below `room` (a
    /// bound from counts already checked against the file) may use the table.
    pub(super) fn insert(&mut self, tag: i64, index: u32, room: usize) -> bool {
        if let TagMap::Dense(v) = self {
            if tag >= 0 && (tag as u64) < room.max(v.len()) as u64 {
                let t = tag as usize;
                if t >= v.len() {
                    v.resize(t + 1, NO_INDEX);
                }
                let fresh = v[t] == NO_INDEX;
                if fresh {
                    v[t] = index;
                }
                return fresh;
            }
            let map = v
                .iter()
                .enumerate()
                .filter(|(_, &i)| i != NO_INDEX)
                .map(|(t, &i)| (t as i64, i))
                .collect();
            *self = TagMap::Sparse(map);
        }
        match self {
            TagMap::Sparse(m) => m.insert(tag, index).is_none(),
            TagMap::Dense(_) => false,
        }
    }

    pub(super) fn get(&self, tag: i64) -> Option<u32> {
        match self {
            TagMap::Dense(v) => usize::try_from(tag)
                .ok()
                .and_then(|t| v.get(t))
                .copied()
                .filter(|&i| i != NO_INDEX),
            TagMap::Sparse(m) => m.get(&tag).copied(),
        }
    }
}
