//! The hierarchy EVLR's pages. A page holds its top node and the `PAGE_LEVELS - 1` levels
//! under it whole, and an entry for each node `PAGE_LEVELS` levels down: the node itself
//! when it has no children, else a pointer (-1 points, COPC's child page) to a page that
//! it heads, and so on down. A reader then reads the pages a view reaches, not the whole
//! hierarchy: a page holds at most 1 + 8 + 64 + 512 = 585 entries (19 KB), where a
//! 10-billion-point file's whole hierarchy is about 11 MB.

use std::collections::{BTreeMap, VecDeque};

use super::octree::Key;

/// Levels below a page's top at which a node with children heads a page of its own.
pub(super) const PAGE_LEVELS: i32 = 3;

/// One hierarchy entry: key, chunk offset, compressed bytes, points.
pub(super) type Entry = (Key, u64, u64, u64);

/// An entry of a page: a node, or a child page (its top and index).
enum Item {
    Node(Entry),
    Page(Key, usize),
}

/// The hierarchy's bytes laid out from file offset `at`, the root page first, and the
/// root page's size. Every entry is in exactly one page.
pub(super) fn hierarchy(entries: &[Entry], at: u64) -> (Vec<u8>, u64) {
    let by_key: BTreeMap<Key, Entry> = entries.iter().map(|e| (e.0, *e)).collect();
    let mut children: BTreeMap<Key, Vec<Key>> = BTreeMap::new();
    for key in by_key.keys().filter(|k| k[0] > 0) {
        let parent = [key[0] - 1, key[1] >> 1, key[2] >> 1, key[3] >> 1];
        children.entry(parent).or_default().push(*key);
    }
    let mut pages: Vec<Vec<Item>> = vec![Vec::new()];
    let mut placed = 0;
    // Each page from its top, breadth first so a page's children follow it.
    let mut tops: VecDeque<(usize, Key)> = VecDeque::from([(0, [0, 0, 0, 0])]);
    while let Some((page, top)) = tops.pop_front() {
        let mut stack = vec![(top, 0)];
        while let Some((key, depth)) = stack.pop() {
            let Some(entry) = by_key.get(&key) else {
                continue;
            };
            let below = children.get(&key);
            if depth == PAGE_LEVELS && below.is_some() {
                let child = pages.len();
                pages.push(Vec::new());
                pages[page].push(Item::Page(key, child));
                tops.push_back((child, key));
                continue;
            }
            pages[page].push(Item::Node(*entry));
            placed += 1;
            if depth < PAGE_LEVELS {
                for &c in below.into_iter().flatten() {
                    stack.push((c, depth + 1));
                }
            }
        }
    }
    // A key without its parent (never made by the octree) goes in the root page.
    if placed < by_key.len() {
        let mut in_pages = std::collections::HashSet::new();
        for item in pages.iter().flatten() {
            if let Item::Node(e) = item {
                in_pages.insert(e.0);
            }
        }
        for e in by_key.values().filter(|e| !in_pages.contains(&e.0)) {
            pages[0].push(Item::Node(*e));
        }
    }
    let key_of = |i: &Item| match i {
        Item::Node(e) => e.0,
        Item::Page(k, _) => *k,
    };
    for page in &mut pages {
        page.sort_by_key(key_of);
    }
    let mut offsets = Vec::with_capacity(pages.len());
    let mut next = at;
    for page in &pages {
        offsets.push(next);
        next += 32 * page.len() as u64;
    }
    let mut out = Vec::with_capacity((next - at) as usize);
    for page in &pages {
        for item in page {
            let (key, offset, bytes, points) = match item {
                Item::Node((key, offset, bytes, points)) => {
                    (*key, *offset, *bytes as i32, *points as i32)
                }
                Item::Page(key, p) => (*key, offsets[*p], 32 * pages[*p].len() as i32, -1),
            };
            for v in key {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&offset.to_le_bytes());
            out.extend_from_slice(&bytes.to_le_bytes());
            out.extend_from_slice(&points.to_le_bytes());
        }
    }
    (out, 32 * pages[0].len() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A full octree `depth` levels deep under the root (every child present).
    fn full(depth: i32) -> Vec<Entry> {
        let mut out = Vec::new();
        for level in 0..=depth {
            let side = 1 << level;
            for x in 0..side {
                for y in 0..side {
                    for z in 0..side {
                        out.push(([level, x, y, z], 1000 + out.len() as u64, 10, 3));
                    }
                }
            }
        }
        out
    }

    /// The entries in the bytes, in order: key, offset, bytes, points.
    fn entries_of(bytes: &[u8]) -> Vec<(Key, u64, i32, i32)> {
        bytes
            .chunks_exact(32)
            .map(|e| {
                let i = |o: usize| i32::from_le_bytes(e[o..o + 4].try_into().unwrap());
                (
                    [i(0), i(4), i(8), i(12)],
                    u64::from_le_bytes(e[16..24].try_into().unwrap()),
                    i(24),
                    i(28),
                )
            })
            .collect()
    }

    #[test]
    fn shallow_trees_are_one_page_and_deep_ones_page_below_each_third_level() {
        for depth in 0..=3 {
            let e = full(depth);
            let (bytes, root) = hierarchy(&e, 5000);
            assert_eq!(root, 32 * e.len() as u64, "depth {depth}: one page");
            assert_eq!(bytes.len(), 32 * e.len());
        }
        // Five levels: the root page holds levels 0-2 and a pointer per level-3 node (512
        // of them), each page a level-3 node and its 8 children.
        let e = full(4);
        let at = 7000;
        let (bytes, root) = hierarchy(&e, at);
        let all = entries_of(&bytes);
        let pointers: Vec<_> = all.iter().filter(|x| x.3 == -1).collect();
        assert_eq!(pointers.len(), 512);
        assert_eq!(root, 32 * (1 + 8 + 64 + 512));
        // Every node once, with its own numbers; every pointer names a page starting
        // with its key, of 9 entries.
        let nodes: BTreeMap<Key, (u64, i32, i32)> = all
            .iter()
            .filter(|x| x.3 != -1)
            .map(|x| (x.0, (x.1, x.2, x.3)))
            .collect();
        assert_eq!(nodes.len(), e.len());
        for (key, offset, bytes, points) in &e {
            assert_eq!(nodes[key], (*offset, *bytes as i32, *points as i32));
        }
        for p in pointers {
            assert_eq!(p.2, 9 * 32);
            let first = ((p.1 - at) / 32) as usize;
            assert_eq!(all[first].0, p.0, "a page starts with its top");
            for x in &all[first..first + 9] {
                assert_ne!(x.3, -1);
            }
        }
    }

    #[test]
    fn a_lone_deep_node_without_children_stays_in_its_parents_page() {
        // A chain to level 3 with nothing under it, and one chain to level 6.
        let mut e: Vec<Entry> = (0..=3).map(|l| ([l, 0, 0, 0], 100, 1, 1)).collect();
        e.extend((1..=6).map(|l| ([l, 1 << (l - 1), 0, 0], 200, 1, 1)));
        let (bytes, root) = hierarchy(&e, 0);
        let all = entries_of(&bytes);
        // Root page: 0, two level-1..2 chains, (3,0,0,0) as a node, a pointer for
        // (3,4,0,0); its page: (3,4,0,0) down to (6,32,0,0), a node (it has no children).
        assert_eq!(root, 32 * (1 + 2 + 2 + 1 + 1));
        assert_eq!(all.iter().filter(|x| x.3 == -1).count(), 1);
        assert_eq!(all.len(), e.len() + 1);
    }
}
