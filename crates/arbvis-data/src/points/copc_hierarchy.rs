//! A COPC file's hierarchy, read a page at a time. The info VLR names the root page; an
//! entry whose point count is -1 names a child page holding that key's entry and its
//! subtree. [`Copc::open`](super::copc::Copc::open) reads the root page only; the level
//! of detail reads a child page when the view reaches its key
//! ([`super::copc_lod::select`]), and `inspect`, whole-level cuts and the writer's checks
//! read them all. A 10-billion-point file's hierarchy (about 11 MB) is never read whole
//! to draw a view.
//!
//! Every page lies inside a hierarchy EVLR (`copc`, record 1000: PDAL, Untwine and laspy
//! write one holding every page; copclib writes each page as an EVLR of its own, child
//! pages before their parents), a whole number of 32-byte entries, and is read once (a
//! second reference, a cycle among pages, is refused when it is met). Every key lies
//! inside the octree and is listed once; a child page holds only its key's subtree (what
//! a lazy reader assumes: laspy's, Potree's and copclib's do too). A key whose parent has
//! no entry is read as copclib reads it (its `GetAllNodes` and `FindNode` return it):
//! its points are drawn, under its nearest listed ancestor (laspy's `CopcReader` walks
//! from the root through the keys listed and leaves such a subtree out; docs/splats.md).
//! Every chunk lies inside the point data
//! with at most 1,000,000 points plus one per compressed byte (as for LAZ files). Once
//! every page is read the counts must sum to the header's. A page that fails adds nothing
//! and its error answers every later read (a held file never turns into a partial one).
//! An error is (its byte, what was expected).

use std::collections::{BTreeMap, HashMap, HashSet};

/// Deepest octree level read (keys are i32: 2^30 nodes a side is far past any survey).
const MAX_LEVEL: i32 = 30;

/// One octree node: its key, where its chunk lies and how many points it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Node {
    /// Level (0: the root), then x, y, z in `0..2^level`.
    pub key: [i32; 4],
    /// Byte offset of its LAZ chunk.
    pub offset: u64,
    /// Compressed bytes.
    pub bytes: u64,
    /// Points.
    pub points: u64,
}

/// A page not read yet: where it lies and the byte of the entry that names it.
#[derive(Debug, Clone, Copy)]
struct PageRef {
    offset: u64,
    size: u64,
    named_at: u64,
}

/// The pages read so far and those named but not read.
#[derive(Debug)]
pub(super) struct Hierarchy {
    /// The hierarchy EVLRs' data: file offsets `start..end` of each.
    evlrs: Vec<(u64, u64)>,
    /// The point data: file offsets `start..end` (every chunk lies inside).
    point_data: (u64, u64),
    /// The header's point count (the nodes' sum once every page is read).
    points: u64,
    /// Nodes holding points, in the pages read.
    nodes: Vec<Node>,
    /// Every key listed in the pages read and the byte of its entry.
    keys: HashMap<[i32; 4], u64>,
    /// Child pages named and not read, by key.
    unread: BTreeMap<[i32; 4], PageRef>,
    /// Offsets of every page read or named.
    pages: HashSet<u64>,
    /// Pages read.
    read: usize,
    /// The first page that failed its checks: every later read answers with it.
    failed: Option<(u64, String)>,
}

/// What reading one page added, taken back when the page fails its checks.
#[derive(Default)]
struct Added {
    nodes: usize,
    keys: Vec<[i32; 4]>,
    pages: Vec<([i32; 4], u64)>,
}

/// Reads `buf.len()` bytes at a file offset.
pub(super) type ReadAt<'a> = &'a mut dyn FnMut(u64, &mut [u8]) -> std::io::Result<()>;

impl Hierarchy {
    /// The hierarchy EVLRs' data at `evlrs`, points at `point_data`, `points` in the
    /// header, and the root page (offset, size) named at byte `root_at`, read through
    /// `read`.
    pub(super) fn open(
        evlrs: Vec<(u64, u64)>,
        point_data: (u64, u64),
        points: u64,
        (root, root_at): ((u64, u64), u64),
        read: ReadAt<'_>,
    ) -> Result<Hierarchy, (u64, String)> {
        let mut h = Hierarchy {
            evlrs,
            point_data,
            points,
            nodes: Vec::new(),
            keys: HashMap::new(),
            unread: BTreeMap::new(),
            pages: HashSet::new(),
            read: 0,
            failed: None,
        };
        let root = h.name_page(root.0, root.1, root_at)?;
        h.read_page(root, None, read)?;
        Ok(h)
    }

    /// Nodes holding points in the pages read, by level then key.
    pub(super) fn nodes(&self) -> Vec<Node> {
        let mut nodes = self.nodes.clone();
        nodes.sort();
        nodes
    }

    /// Keys of the child pages named and not read.
    pub(super) fn unread(&self) -> Vec<[i32; 4]> {
        self.unread.keys().copied().collect()
    }

    /// Pages read and pages named but not read.
    pub(super) fn pages(&self) -> (usize, usize) {
        (self.read, self.unread.len())
    }

    /// Read the child page of `key` (nothing when it is not an unread page).
    pub(super) fn read_key(
        &mut self,
        key: [i32; 4],
        read: ReadAt<'_>,
    ) -> Result<(), (u64, String)> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        match self.unread.remove(&key) {
            Some(page) => self.read_page(page, Some(key), read),
            None => Ok(()),
        }
    }

    /// Read every page not read yet.
    pub(super) fn read_all(&mut self, read: ReadAt<'_>) -> Result<(), (u64, String)> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        while let Some((key, page)) = self.unread.pop_first() {
            self.read_page(page, Some(key), read)?;
        }
        Ok(())
    }

    /// Check a page named at byte `named_at` and remember its offset.
    fn name_page(
        &mut self,
        offset: u64,
        size: u64,
        named_at: u64,
    ) -> Result<PageRef, (u64, String)> {
        let inside = self
            .evlrs
            .iter()
            .any(|&(base, end)| offset >= base && offset.saturating_add(size) <= end);
        if !inside || size == 0 || !size.is_multiple_of(32) {
            let evlrs: Vec<String> = self
                .evlrs
                .iter()
                .take(4)
                .map(|(base, end)| format!("{base}..{end}"))
                .collect();
            let more = self.evlrs.len().saturating_sub(4);
            return Err((
                named_at,
                format!(
                    "a hierarchy page of {size} bytes at {offset}: expected a whole number of 32-byte entries inside a hierarchy EVLR ({}{})",
                    evlrs.join(", "),
                    if more > 0 { format!(" and {more} more") } else { String::new() }
                ),
            ));
        }
        if !self.pages.insert(offset) {
            return Err((
                named_at,
                format!(
                    "the hierarchy page at {offset} is referenced twice (a cycle among the pages)"
                ),
            ));
        }
        Ok(PageRef {
            offset,
            size,
            named_at,
        })
    }

    /// Read one page (the root's, or the child page of `top`), check its entries and add
    /// them. A page that fails adds nothing, and its error stands for every later read.
    fn read_page(
        &mut self,
        page: PageRef,
        top: Option<[i32; 4]>,
        read: ReadAt<'_>,
    ) -> Result<(), (u64, String)> {
        let mut added = Added {
            nodes: self.nodes.len(),
            ..Added::default()
        };
        let result = self.add_page(page, top, read, &mut added);
        if let Err(e) = &result {
            self.nodes.truncate(added.nodes);
            for key in &added.keys {
                self.keys.remove(key);
            }
            for (key, offset) in &added.pages {
                self.unread.remove(key);
                self.pages.remove(offset);
            }
            // Still unread: a view that reaches it asks for it again and gets the error.
            if let Some(key) = top {
                self.unread.insert(key, page);
            }
            self.failed = Some(e.clone());
        }
        result
    }

    /// [`Hierarchy::read_page`]'s reading and checks, noting in `added` what it adds.
    fn add_page(
        &mut self,
        page: PageRef,
        top: Option<[i32; 4]>,
        read: ReadAt<'_>,
        added: &mut Added,
    ) -> Result<(), (u64, String)> {
        let mut data = vec![0u8; page.size as usize];
        read(page.offset, &mut data).map_err(|e| {
            (
                page.named_at,
                format!(
                    "the hierarchy page of {} bytes at {}: {e}",
                    page.size, page.offset
                ),
            )
        })?;
        for (k, e) in data.chunks_exact(32).enumerate() {
            let at = page.offset + 32 * k as u64;
            let i32_at = |o: usize| i32::from_le_bytes(e[o..o + 4].try_into().expect("4"));
            let key = [i32_at(0), i32_at(4), i32_at(8), i32_at(12)];
            let target = u64::from_le_bytes(e[16..24].try_into().expect("8"));
            let (bytes, points) = (i32_at(24), i32_at(28));
            let fail = |m: String| (at, format!("hierarchy entry {key:?}: {m}"));
            let side = if (0..=MAX_LEVEL).contains(&key[0]) {
                1i64 << key[0]
            } else {
                return Err(fail(format!("level {}: expected 0..={MAX_LEVEL}", key[0])));
            };
            if key[1..].iter().any(|&c| c < 0 || c as i64 >= side) {
                return Err(fail(format!(
                    "x, y, z must lie in 0..{side} at level {}",
                    key[0]
                )));
            }
            let first = self
                .keys
                .get(&key)
                .copied()
                .or_else(|| self.unread.get(&key).map(|p| p.named_at));
            if let Some(first) = first {
                return Err(fail(if first == at {
                    "its entry is read a second time: this page overlaps one read before"
                        .to_string()
                } else {
                    format!("the key is listed twice (first at byte {first})")
                }));
            }
            // A child page holds its key's subtree (a reader reads it when a view
            // reaches that key).
            if let Some(t) = top {
                let up = key[0] - t[0];
                if up < 0 || (1..4).any(|a| key[a] >> up != t[a]) {
                    return Err(fail(format!(
                        "a child page holds {t:?} and the keys under it"
                    )));
                }
            }
            if points == -1 {
                if bytes <= 0 {
                    return Err(fail(format!("a child page of {bytes} bytes")));
                }
                // The page's entry for this key comes again inside it.
                let child = self.name_page(target, bytes as u64, at)?;
                self.unread.insert(key, child);
                added.pages.push((key, target));
                continue;
            }
            if points < 0 || bytes < 0 {
                return Err(fail(format!(
                    "{points} points in {bytes} bytes: expected counts of 0 or more (-1: a child page)"
                )));
            }
            let (points, bytes) = (points as u64, bytes as u64);
            let (start, end) = self.point_data;
            if points > 0 {
                if target < start || target.saturating_add(bytes) > end || bytes == 0 {
                    return Err(fail(format!(
                        "its chunk ({bytes} bytes at {target}) must lie in the point data ({start}..{end})"
                    )));
                }
                if points > 1_000_000 + bytes {
                    return Err(fail(format!(
                        "{points} points in {bytes} compressed bytes: more than 1,000,000 plus one a byte"
                    )));
                }
                self.nodes.push(Node {
                    key,
                    offset: target,
                    bytes,
                    points,
                });
            }
            self.keys.insert(key, at);
            added.keys.push(key);
        }
        if self.unread.is_empty() {
            let total: u64 = self.nodes.iter().map(|n| n.points).sum();
            if total != self.points {
                return Err((
                    247,
                    format!(
                        "the header declares {} points, the hierarchy's nodes hold {total}",
                        self.points
                    ),
                ));
            }
        }
        self.read += 1;
        Ok(())
    }
}
