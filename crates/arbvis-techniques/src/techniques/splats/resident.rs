//! The GPU node cache of a COPC cloud: which octree nodes' vertices the splats' vertex
//! buffer holds, and where.
//!
//! The buffer is an arena of `capacity` vertices. A cut (the nodes a view draws) is
//! placed node by node: a node already resident with the same vertices keeps its place
//! (nothing uploaded), a new or changed one is written into free space, and when none is
//! left the least recently drawn nodes outside the cut are evicted. A cut that still does
//! not fit (fragmentation, or larger than the arena) is laid out afresh from the start in
//! an arena of twice the cut (or as large as it was, when that is more). No GL here: the renderer uploads what [`Placement`] lists.
//! A node's vertices are known by a 64-bit hash of their bits, so a node whose vertices
//! changed between cuts (colours normalised over the cut, normals estimated from its
//! neighbours) is uploaded again rather than drawn stale, without a CPU copy of the
//! buffer.

use std::collections::HashMap;

/// An octree node: level, then x, y, z.
pub type NodeKey = [i32; 4];

/// Where a cut's nodes went, and what to upload.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Each cut node's first vertex in the arena, in the cut's order.
    pub starts: Vec<usize>,
    /// Cut nodes (indices into the cut) whose vertices must be written at their start.
    pub uploads: Vec<usize>,
    /// Nodes evicted to make room.
    pub evicted: usize,
    /// The arena was laid out afresh: the cut's vertices one node after the other from
    /// the start, in a buffer of [`Resident::capacity`] vertices (reallocated).
    pub rebuilt: bool,
}

#[derive(Debug, Clone)]
struct Slot {
    start: usize,
    len: usize,
    /// The hash of its vertices' bits.
    hash: u64,
    /// The placement that last drew it.
    used: u64,
}

/// The arena's bookkeeping.
#[derive(Debug, Clone)]
pub struct Resident {
    capacity: usize,
    floats_per_vertex: usize,
    slots: HashMap<NodeKey, Slot>,
    /// Free ranges `(start, len)`, sorted by start, never adjacent.
    free: Vec<(usize, usize)>,
    clock: u64,
}

impl Resident {
    /// An empty arena of `capacity` vertices of `floats_per_vertex` floats.
    pub fn new(capacity: usize, floats_per_vertex: usize) -> Resident {
        Resident {
            capacity,
            floats_per_vertex,
            slots: HashMap::new(),
            free: if capacity > 0 {
                vec![(0, capacity)]
            } else {
                vec![]
            },
            clock: 0,
        }
    }

    /// Vertices the arena holds room for.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Nodes resident.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True when no node is resident.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Place `cut` (each node's key and vertices, `floats_per_vertex` floats a vertex);
    /// the caller uploads [`Placement::uploads`] at their starts, or, when
    /// [`Placement::rebuilt`], the cut's vertices in order into a new buffer.
    pub fn place(&mut self, cut: &[(NodeKey, &[f32])]) -> Placement {
        self.clock += 1;
        let f = self.floats_per_vertex;
        let total: usize = cut.iter().map(|(_, v)| v.len() / f).sum();
        if total > self.capacity {
            return self.rebuild(cut, 2 * total, 0);
        }
        let hashes: Vec<u64> = cut.iter().map(|(_, v)| hash(v)).collect();
        let mut starts = vec![usize::MAX; cut.len()];
        let mut uploads = Vec::new();
        // Nodes resident with the same vertices stay; the others are freed and placed.
        for (k, (key, vertices)) in cut.iter().enumerate() {
            let len = vertices.len() / f;
            if let Some(slot) = self.slots.get_mut(key) {
                if slot.len == len && slot.hash == hashes[k] {
                    slot.used = self.clock;
                    starts[k] = slot.start;
                    continue;
                }
                let slot = self.slots.remove(key).expect("resident");
                self.release(slot.start, slot.len);
            }
        }
        let mut evicted = 0;
        for (k, (key, vertices)) in cut.iter().enumerate() {
            if starts[k] != usize::MAX {
                continue;
            }
            let len = vertices.len() / f;
            let start = loop {
                if let Some(start) = self.allocate(len) {
                    break Some(start);
                }
                if !self.evict_oldest() {
                    break None;
                }
                evicted += 1;
            };
            let Some(start) = start else {
                return self.rebuild(cut, self.capacity.max(2 * total), evicted);
            };
            self.slots.insert(
                *key,
                Slot {
                    start,
                    len,
                    hash: hashes[k],
                    used: self.clock,
                },
            );
            starts[k] = start;
            uploads.push(k);
        }
        Placement {
            starts,
            uploads,
            evicted,
            rebuilt: false,
        }
    }

    /// Lay `cut` out from the arena's start, with `capacity` vertices of room (`evicted`
    /// nodes already evicted for it).
    fn rebuild(&mut self, cut: &[(NodeKey, &[f32])], capacity: usize, evicted: usize) -> Placement {
        let f = self.floats_per_vertex;
        let evicted = evicted
            + self
                .slots
                .keys()
                .filter(|k| !cut.iter().any(|(c, _)| c == *k))
                .count();
        let clock = self.clock;
        *self = Resident::new(capacity, f);
        self.clock = clock;
        let mut starts = Vec::with_capacity(cut.len());
        let mut at = 0;
        for (key, vertices) in cut {
            let len = vertices.len() / f;
            self.slots.insert(
                *key,
                Slot {
                    start: at,
                    len,
                    hash: hash(vertices),
                    used: clock,
                },
            );
            starts.push(at);
            at += len;
        }
        self.free = if at < capacity {
            vec![(at, capacity - at)]
        } else {
            vec![]
        };
        Placement {
            starts,
            uploads: (0..cut.len()).collect(),
            evicted,
            rebuilt: true,
        }
    }

    /// First fit of `len` vertices.
    fn allocate(&mut self, len: usize) -> Option<usize> {
        if len == 0 {
            return Some(0);
        }
        let k = self.free.iter().position(|&(_, l)| l >= len)?;
        let (start, l) = self.free[k];
        if l == len {
            self.free.remove(k);
        } else {
            self.free[k] = (start + len, l - len);
        }
        Some(start)
    }

    /// Return a range to the free list, merged with its neighbours.
    fn release(&mut self, start: usize, len: usize) {
        if len == 0 {
            return;
        }
        let k = self.free.partition_point(|&(s, _)| s < start);
        self.free.insert(k, (start, len));
        if k + 1 < self.free.len() && self.free[k].0 + self.free[k].1 == self.free[k + 1].0 {
            self.free[k].1 += self.free[k + 1].1;
            self.free.remove(k + 1);
        }
        if k > 0 && self.free[k - 1].0 + self.free[k - 1].1 == self.free[k].0 {
            self.free[k - 1].1 += self.free[k].1;
            self.free.remove(k);
        }
    }

    /// Evict the least recently drawn node not in the current placement; false when
    /// every resident node is in it.
    fn evict_oldest(&mut self) -> bool {
        let oldest = self
            .slots
            .iter()
            .filter(|(_, s)| s.used < self.clock)
            .min_by_key(|(key, s)| (s.used, **key))
            .map(|(key, _)| *key);
        let Some(key) = oldest else {
            return false;
        };
        let slot = self.slots.remove(&key).expect("resident");
        self.release(slot.start, slot.len);
        true
    }
}

/// A 64-bit hash of the floats' bits (a multiply-xorshift over each pair of floats):
/// bit for bit, so a NaN (a point without the property) matches itself.
fn hash(values: &[f32]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15_u64 ^ values.len() as u64;
    let mut pairs = values.chunks_exact(2);
    for p in &mut pairs {
        let w = u64::from(p[0].to_bits()) | (u64::from(p[1].to_bits()) << 32);
        h = (h ^ w).wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 32;
    }
    for v in pairs.remainder() {
        h = (h ^ u64::from(v.to_bits())).wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^= h >> 29;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertices of one float each, valued from the key and a version, `len` of them.
    fn node(key: NodeKey, len: usize, version: f32) -> (NodeKey, Vec<f32>) {
        let v = (0..len)
            .map(|i| key[1] as f32 * 1000.0 + key[0] as f32 * 100.0 + i as f32 + version)
            .collect();
        (key, v)
    }

    fn cut(nodes: &[(NodeKey, Vec<f32>)]) -> Vec<(NodeKey, &[f32])> {
        nodes.iter().map(|(k, v)| (*k, v.as_slice())).collect()
    }

    /// The GPU buffer as the renderer keeps it: rebuilt with the cut in order, else the
    /// uploads written at their starts.
    struct Buffer(Vec<f32>);

    impl Buffer {
        fn new() -> Buffer {
            Buffer(Vec::new())
        }

        /// Apply `p` as the renderer does, then check that every cut node's vertices lie
        /// at its start and that no two resident nodes overlap.
        fn apply(&mut self, r: &Resident, nodes: &[(NodeKey, Vec<f32>)], p: &Placement) {
            let f = r.floats_per_vertex;
            if p.rebuilt {
                self.0 = vec![0.0; r.capacity() * f];
                let all: Vec<f32> = nodes.iter().flat_map(|(_, v)| v.iter().copied()).collect();
                self.0[..all.len()].copy_from_slice(&all);
            } else {
                for &k in &p.uploads {
                    let (s, v) = (p.starts[k] * f, &nodes[k].1);
                    self.0[s..s + v.len()].copy_from_slice(v);
                }
            }
            for ((_, v), &s) in nodes.iter().zip(&p.starts) {
                let held: Vec<u32> = self.0[s * f..s * f + v.len()]
                    .iter()
                    .map(|x| x.to_bits())
                    .collect();
                let want: Vec<u32> = v.iter().map(|x| x.to_bits()).collect();
                assert_eq!(held, want, "{p:?}");
            }
            let mut ranges: Vec<(usize, usize)> =
                r.slots.values().map(|s| (s.start, s.len)).collect();
            ranges.extend(r.free.iter().copied());
            ranges.sort_unstable();
            let mut at = 0;
            for (s, l) in ranges.into_iter().filter(|r| r.1 > 0) {
                assert!(s >= at, "overlap at {s}");
                at = s + l;
            }
            assert!(at <= r.capacity());
        }
    }

    #[test]
    fn resident_nodes_are_not_uploaded_again() {
        let (mut r, mut gpu) = (Resident::new(100, 1), Buffer::new());
        // A NaN (a point without the property) does not make a node look changed.
        let mut root = node([0, 0, 0, 0], 10, 0.0);
        root.1[3] = f32::NAN;
        let a = vec![root, node([1, 1, 0, 0], 7, 0.0)];
        let p = r.place(&cut(&a));
        assert_eq!(p.uploads, vec![0, 1]);
        gpu.0 = vec![0.0; 100];
        gpu.apply(&r, &a, &p);
        // The finer cut keeps both and adds two: only those are uploaded.
        let b = vec![
            a[0].clone(),
            node([2, 3, 1, 0], 13, 0.0),
            a[1].clone(),
            node([2, 2, 0, 1], 5, 0.0),
        ];
        let q = r.place(&cut(&b));
        assert_eq!(q.uploads, vec![1, 3]);
        assert_eq!((q.starts[0], q.starts[2]), (p.starts[0], p.starts[1]));
        assert!(!q.rebuilt);
        gpu.apply(&r, &b, &q);
    }

    #[test]
    fn a_node_whose_vertices_changed_is_uploaded_again() {
        let (mut r, mut gpu) = (Resident::new(50, 1), Buffer(vec![0.0; 50]));
        let a = vec![node([0, 0, 0, 0], 10, 0.0), node([1, 1, 0, 0], 7, 0.0)];
        let p = r.place(&cut(&a));
        gpu.apply(&r, &a, &p);
        let b = vec![node([0, 0, 0, 0], 10, 0.5), a[1].clone()];
        let p = r.place(&cut(&b));
        assert_eq!(p.uploads, vec![0]);
        gpu.apply(&r, &b, &p);
        // The same key with another count (a thinned root) too.
        let c = vec![node([0, 0, 0, 0], 4, 0.5), a[1].clone()];
        let p = r.place(&cut(&c));
        assert_eq!(p.uploads, vec![0]);
        gpu.apply(&r, &c, &p);
    }

    #[test]
    fn the_least_recently_drawn_nodes_are_evicted_first() {
        let mut r = Resident::new(30, 1);
        let n = |x: i32| node([3, x, 0, 0], 10, 0.0);
        r.place(&cut(&[n(1)]));
        r.place(&cut(&[n(2)]));
        r.place(&cut(&[n(3)]));
        // Full: 1 was drawn longest ago, so placing 4 evicts it and keeps 2 and 3.
        let p = r.place(&cut(&[n(4)]));
        assert_eq!((p.evicted, p.rebuilt), (1, false));
        let keep = r.place(&cut(&[n(2), n(3), n(4)]));
        assert!(keep.uploads.is_empty(), "{keep:?}");
        // Nodes of the cut itself are never evicted for it: 5 takes 4's place, the only
        // node outside the cut.
        let all = [n(2), n(3), n(5)];
        let p = r.place(&cut(&all));
        assert_eq!(
            (p.evicted, p.rebuilt, p.starts[2]),
            (1, false, keep.starts[2])
        );
    }

    #[test]
    fn a_cut_larger_than_the_arena_grows_it_and_fragmentation_lays_it_out_again() {
        let (mut r, mut gpu) = (Resident::new(20, 2), Buffer::new());
        let big: Vec<_> = (0..3).map(|x| node([2, x, 0, 0], 10, 0.0)).collect();
        let big: Vec<_> = big
            .into_iter()
            .map(|(k, v)| {
                (
                    k,
                    v.iter().flat_map(|&a| [a, a + 0.25]).collect::<Vec<f32>>(),
                )
            })
            .collect();
        let p = r.place(&cut(&big));
        assert!(p.rebuilt);
        assert_eq!(r.capacity(), 60, "twice the cut's 30 vertices of 2 floats");
        gpu.apply(&r, &big, &p);
        // Holes of 10 vertices between resident nodes; a node of 12 fits in none until
        // the others are evicted, and merged free space takes it.
        let (mut r, mut gpu) = (Resident::new(40, 1), Buffer(vec![0.0; 40]));
        let n = |x: i32, len| node([3, x, 0, 0], len, 0.0);
        let first = [n(0, 10), n(1, 10), n(2, 10), n(3, 10)];
        let p = r.place(&cut(&first));
        gpu.apply(&r, &first, &p);
        let second = [n(0, 10), n(2, 10), n(5, 12)];
        let p = r.place(&cut(&second));
        // 1 and 3 evicted leave 10 + 10 apart: no 12 fits, so the cut is laid out afresh
        // in an arena of twice the cut.
        assert!(p.rebuilt, "{p:?}");
        assert_eq!((p.uploads.len(), p.evicted, r.capacity()), (3, 2, 64));
        gpu.apply(&r, &second, &p);
    }

    #[test]
    fn random_cuts_always_hold_their_vertices() {
        // A deterministic walk of cuts over 64 nodes of uneven sizes, in an arena of 100
        // vertices at first (cuts of up to 232 make it grow).
        let (mut r, mut gpu) = (Resident::new(100, 3), Buffer(vec![0.0; 300]));
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as usize
        };
        let (mut kept, mut rebuilt) = (0, 0);
        for round in 0..200 {
            let count = 1 + next() % 8;
            let mut nodes: Vec<(NodeKey, Vec<f32>)> = Vec::new();
            for _ in 0..count {
                let x = (next() % 64) as i32;
                if nodes.iter().any(|(k, _)| k[1] == x) {
                    continue;
                }
                let len = 1 + (x as usize * 7) % 29;
                let version = if next() % 10 == 0 { round as f32 } else { 0.0 };
                let (key, v) = node([4, x, 0, 0], len, version);
                let v: Vec<f32> = v.iter().flat_map(|&a| [a, -a, a * 0.5]).collect();
                nodes.push((key, v));
            }
            let p = r.place(&cut(&nodes));
            kept += nodes.len() - p.uploads.len();
            rebuilt += usize::from(p.rebuilt);
            gpu.apply(&r, &nodes, &p);
        }
        assert!(kept > 0 && rebuilt > 0, "kept {kept}, rebuilt {rebuilt}");
    }

    #[test]
    fn the_hash_sees_every_bit() {
        let v: Vec<f32> = (0..9).map(|i| i as f32 * 0.37).collect();
        for k in 0..v.len() {
            let mut w = v.clone();
            w[k] = f32::from_bits(w[k].to_bits() ^ 1);
            assert_ne!(hash(&v), hash(&w), "float {k}");
        }
        assert_ne!(hash(&v[..8]), hash(&v));
        assert_eq!(hash(&[f32::NAN]), hash(&[f32::NAN]));
    }
}
