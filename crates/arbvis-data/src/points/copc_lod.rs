//! Which COPC nodes a view draws: Potree's policy. Nodes are ranked by the radius their
//! bounding sphere projects to on screen, in pixels; from the root down the largest is
//! taken while the point budget lasts, its children queued; nodes outside the view
//! frustum and nodes whose sphere projects under `min_node_pixels` (Potree's 150) are
//! not queued. The root is always taken: when it alone is over the budget, a stride of
//! its points is drawn (the loader thins it), so no picture has more points than the
//! budget. No GL: the view is the camera's matrix in the cloud's frame.
//!
//! The frame is fixed by the file, not by the cut: positions are rescaled around the
//! header's bounds (`PointCloud`'s rule: origin at their centre, scale half the largest
//! extent), so every budget and every cut places the cloud at the same place.

use std::collections::{BinaryHeap, HashMap};

use glam::{DMat4, DVec3, DVec4};

use super::copc::{Copc, Node};

/// A view of the cloud's frame ([-1, 1]³ around the header's bounds): the camera's
/// [`arbvis_core::camera::View`].
pub use arbvis_core::camera::View;

/// What a COPC cloud's load says: its cut in a line, and the spacing of the deepest level
/// drawn in the cloud's frame (what a splat must cover for the picture to have no gaps).
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The cut, as [`Cut::describe`] says it.
    pub describe: String,
    /// The deepest level's spacing, in frame units ([-1, 1] over the largest extent).
    pub spacing: f64,
    /// Each point's spacing over the deepest level's ([`spacings`]): 1, 2, 4, ...
    pub size_scales: Vec<f32>,
    /// The cut's nodes in the cloud's order: each key and its points in the cloud (the
    /// cloud holds them one node after the other).
    pub nodes: Vec<([i32; 4], usize)>,
}

/// The nodes a view draws and what was left.
#[derive(Debug, Clone, PartialEq)]
pub struct Cut {
    /// Nodes taken, largest on screen first.
    pub nodes: Vec<Node>,
    /// Points of those nodes.
    pub points: u64,
    /// The root's stride when it alone is over the budget (1: every point).
    pub root_stride: u64,
    /// Deepest level taken.
    pub deepest: i32,
    /// Nodes not queued: outside the view, and under `min_node_pixels`.
    pub culled: usize,
    pub too_small: usize,
    /// Nodes queued but left for the budget.
    pub over_budget: usize,
}

impl Cut {
    /// A cut of whole levels (`Copc::cut`), with the root's stride for `budget`.
    pub fn whole(nodes: Vec<Node>, points: u64, budget: u64) -> Cut {
        Cut {
            deepest: nodes.iter().map(|n| n.key[0]).max().unwrap_or(0),
            root_stride: if points > budget && budget > 0 {
                points.div_ceil(budget)
            } else {
                1
            },
            nodes,
            points,
            culled: 0,
            too_small: 0,
            over_budget: 0,
        }
    }

    /// A line for `--stats` and the viewer.
    pub fn describe(&self, copc: &Copc) -> String {
        let (read, unread) = copc.pages();
        let known = copc.nodes_read().len();
        let bytes: u64 = self.nodes.iter().map(|n| n.bytes).sum();
        let levels = self
            .nodes
            .iter()
            .map(|n| n.key[0])
            .collect::<std::collections::BTreeSet<_>>();
        format!(
            "COPC: {} of {}, levels {:?}, {} points{} ({} compressed), {} nodes outside the view, {} under the pixel size, {} left for the budget",
            self.nodes.len(),
            if unread == 0 {
                format!("{known} nodes")
            } else {
                format!(
                    "the {known} nodes of the {read} hierarchy page{} read ({unread} not read)",
                    if read == 1 { "" } else { "s" }
                )
            },
            levels,
            self.points / self.root_stride.max(1),
            if self.root_stride > 1 {
                format!(" (every {}th of the root's)", self.root_stride)
            } else {
                String::new()
            },
            arbvis_core::budget::format_bytes(bytes),
            self.culled,
            self.too_small,
            self.over_budget
        )
    }
}

/// A queued node (its index) and its projected radius.
type Ranked = arbvis_core::vocab::Ranked<usize>;

/// Each point's spacing (file units) in a cloud loaded from `cut` (its nodes' points in
/// order, `positions` in file coordinates): the spacing of the deepest level drawn in its
/// part of the octree, the child octant it lies in (its own level's where that child is
/// not drawn). A level's points stand in for its missing children: a splat sized from
/// this covers what they would have.
pub fn spacings(copc: &Copc, cut: &Cut, positions: impl Iterator<Item = [f64; 3]>) -> Vec<f32> {
    let info = copc.info;
    // The deepest level drawn under each drawn node.
    let mut deepest: HashMap<[i32; 4], i32> = HashMap::new();
    for n in &cut.nodes {
        let mut k = n.key;
        loop {
            let e = deepest.entry(k).or_insert(n.key[0]);
            *e = (*e).max(n.key[0]);
            if k[0] == 0 {
                break;
            }
            k = [k[0] - 1, k[1] >> 1, k[2] >> 1, k[3] >> 1];
        }
    }
    let lo = [info.center_x, info.center_y, info.center_z].map(|c| c - info.halfsize);
    let mut out = Vec::new();
    let mut positions = positions;
    for n in &cut.nodes {
        let level = n.key[0].clamp(0, 30);
        let side = 2.0 * info.halfsize / f64::from(1u32 << level);
        let count = if cut.root_stride > 1 {
            n.points.div_ceil(cut.root_stride)
        } else {
            n.points
        };
        for p in positions.by_ref().take(count as usize) {
            let child: [i32; 4] = [
                level + 1,
                2 * n.key[1] + i32::from(p[0] >= lo[0] + side * (n.key[1] as f64 + 0.5)),
                2 * n.key[2] + i32::from(p[1] >= lo[1] + side * (n.key[2] as f64 + 0.5)),
                2 * n.key[3] + i32::from(p[2] >= lo[2] + side * (n.key[3] as f64 + 0.5)),
            ];
            let d = deepest.get(&child).copied().unwrap_or(level).clamp(0, 30);
            out.push((info.spacing / f64::from(1u32 << d)) as f32);
        }
    }
    out
}

/// The frame's origin and scale for `copc` (its header's bounds).
pub fn frame(copc: &Copc) -> ([f64; 3], f64) {
    super::cloud::origin_and_scale(&copc.bounds)
}

/// The nodes `view` draws within `budget` points. The hierarchy's child pages are read
/// as the view reaches them: a page is read when its key would be taken, and the choice
/// is made again with its nodes (as many rounds as pages nest).
pub fn select(
    copc: &Copc,
    view: &View,
    budget: u64,
    min_node_pixels: f64,
) -> Result<Cut, super::PointsError> {
    loop {
        let nodes = copc.nodes_read();
        let pages = copc.unread_pages();
        let (cut, wanted) = select_known(copc, &nodes, &pages, view, budget, min_node_pixels);
        if wanted.is_empty() {
            return Ok(cut);
        }
        copc.read_pages(&wanted)?;
    }
}

/// A tree entry: a node, or a child page not read (its key's points unknown).
enum Known<'a> {
    Node(&'a Node),
    Page([i32; 4]),
}

impl Known<'_> {
    fn key(&self) -> [i32; 4] {
        match self {
            Known::Node(n) => n.key,
            Known::Page(k) => *k,
        }
    }
}

/// [`select`] over the nodes and unread pages known, and the unread pages it would take.
fn select_known(
    copc: &Copc,
    nodes: &[Node],
    pages: &[[i32; 4]],
    view: &View,
    budget: u64,
    min_node_pixels: f64,
) -> (Cut, Vec<[i32; 4]>) {
    let (origin, scale) = frame(copc);
    let info = copc.info;
    let planes = frustum(&view.view_projection);
    // By key, as the nodes alone are: a page stands where its key's node will, so equal
    // priorities are taken in the same order before and after it is read.
    let mut known: Vec<Known> = nodes
        .iter()
        .map(Known::Node)
        .chain(pages.iter().map(|&k| Known::Page(k)))
        .collect();
    known.sort_by_key(Known::key);
    // Each entry's children: the entries whose nearest present ancestor it is.
    let index: HashMap<[i32; 4], usize> = known
        .iter()
        .enumerate()
        .map(|(i, n)| (n.key(), i))
        .collect();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); known.len()];
    let mut roots = Vec::new();
    for (i, n) in known.iter().enumerate() {
        match nearest_ancestor(n.key(), &index) {
            Some(p) => children[p].push(i),
            None => roots.push(i),
        }
    }
    let half_height = 0.5 * view.size[1] as f64;
    let rank = |i: usize| -> Option<f64> {
        let key = known[i].key();
        let side = 2.0 * info.halfsize / f64::from(1u32 << key[0].clamp(0, 31));
        let lo = [info.center_x, info.center_y, info.center_z].map(|c| c - info.halfsize);
        let c = DVec3::new(
            (lo[0] + side * (key[1] as f64 + 0.5) - origin[0]) / scale,
            (lo[1] + side * (key[2] as f64 + 0.5) - origin[1]) / scale,
            (lo[2] + side * (key[3] as f64 + 0.5) - origin[2]) / scale,
        );
        let r = 0.5 * 3f64.sqrt() * side / scale;
        if planes.iter().any(|p| p.dot(c.extend(1.0)) < -r) {
            return None;
        }
        let w = view.view_projection.row(3).dot(c.extend(1.0));
        // A sphere around the eye (or behind it) is as large as it gets.
        Some(if w <= r {
            f64::INFINITY
        } else {
            r * view.projection_y * half_height / w
        })
    };
    let mut cut = Cut {
        nodes: Vec::new(),
        points: 0,
        root_stride: 1,
        deepest: 0,
        culled: 0,
        too_small: 0,
        over_budget: 0,
    };
    let mut wanted = Vec::new();
    let mut queue = BinaryHeap::new();
    for &i in &roots {
        // The roots are queued whatever their size (a picture always has them).
        queue.push(Ranked {
            priority: rank(i).unwrap_or(0.0),
            item: i,
        });
    }
    while let Some(Ranked { item: index, .. }) = queue.pop() {
        let n = match known[index] {
            Known::Node(n) => *n,
            // Its points are not known until its page is read.
            Known::Page(key) => {
                wanted.push(key);
                continue;
            }
        };
        if !cut.nodes.is_empty() && cut.points + n.points > budget {
            cut.over_budget += 1 + queue.len();
            break;
        }
        cut.points += n.points;
        cut.deepest = cut.deepest.max(n.key[0]);
        cut.nodes.push(n);
        for &c in &children[index] {
            match rank(c) {
                None => cut.culled += 1,
                Some(p) if p < min_node_pixels => cut.too_small += 1,
                Some(p) => queue.push(Ranked {
                    priority: p,
                    item: c,
                }),
            }
        }
    }
    if cut.points > budget && budget > 0 {
        cut.root_stride = cut.points.div_ceil(budget);
    }
    (cut, wanted)
}

/// The index of `key`'s nearest ancestor in `index` (none for the root, or when no
/// ancestor is listed).
pub fn nearest_ancestor(key: [i32; 4], index: &HashMap<[i32; 4], usize>) -> Option<usize> {
    let mut k = key;
    while k[0] > 0 {
        k = [k[0] - 1, k[1] >> 1, k[2] >> 1, k[3] >> 1];
        if let Some(&p) = index.get(&k) {
            return Some(p);
        }
    }
    None
}

/// The six planes of the view frustum (Gribb and Hartmann): a point is inside when every
/// plane's dot product with it is at least 0; each plane scaled to a unit normal.
fn frustum(m: &DMat4) -> [DVec4; 6] {
    let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
    [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2, r3 - r2].map(|p| {
        let n = p.truncate().length();
        if n > 0.0 {
            p / n
        } else {
            p
        }
    })
}
