//! Which bricks a view needs, and in which order to draw them (CPU, no GL).
//!
//! # Screen-space error
//! The levels form an octree over the survey (or over a window of it): brick `c` of level
//! `L` covers level-0 voxels `c B 2^L .. (c + 1) B 2^L`, and its eight children are the
//! level `L - 1` bricks `2c .. 2c + 1`. A brick is refined while its voxels project to more
//! than `pixels` pixels at its point nearest the eye (`pixels` = 1 at full quality: the
//! coarsest level whose voxels cover about one pixel; the viewer's interactive frames are
//! smaller, so the same rule picks coarser levels while the camera moves). Bricks outside
//! the view frustum, or that the tables make transparent (the caller's `visible`), are
//! dropped. The refinement is greedy, largest projected voxel first, and stops where the
//! cut would exceed `max_bricks` (the GPU budget): a view that cannot fit at full
//! resolution gets the finest cut that fits.
//!
//! # What is drawn
//! The wanted cut's bricks are drawn where resident; a brick not yet resident is replaced
//! by its nearest resident ancestor (which then stands for all of its wanted descendants,
//! so nothing is drawn twice), or left out when none is (before the top level arrives).
//!
//! # Order
//! Back to front: the top level's bricks sorted by their distance in cells from the eye's
//! cell (L1; along any ray from the eye it strictly grows, so that order is a visibility
//! order of a grid; orthographic views take the eye at infinity), and the same rule within
//! each brick's 2x2x2 children, depth first.

use std::collections::{BinaryHeap, HashSet};

use glam::{DMat4, DVec3, DVec4};

/// A brick of the pyramid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BrickId {
    /// Level (0: full resolution).
    pub level: u8,
    /// Brick indices along i, j, k.
    pub c: [u32; 3],
}

/// The pyramid's geometry, drawn over a window of the survey.
#[derive(Debug, Clone, PartialEq)]
pub struct Pyramid {
    /// Level-0 voxels along i, j, k.
    pub dims: [usize; 3],
    /// Brick side.
    pub brick: usize,
    /// Number of levels.
    pub levels: usize,
    /// The drawn window, level-0 voxels `lo .. hi`.
    pub window: [[usize; 3]; 2],
    /// Voxel size along i, j, k (the box's aspect).
    pub spacing: [f64; 3],
}

/// A view: the object-to-clip matrix, the viewport, and the eye (perspective) or the
/// direction toward the viewer (orthographic), in object space.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Object space to clip space.
    pub mvp: DMat4,
    /// Viewport in pixels.
    pub size: [u32; 2],
    /// The eye, for perspective.
    pub eye: Option<DVec3>,
    /// Toward the viewer (orthographic order).
    pub toward: DVec3,
}

impl Pyramid {
    /// Half-extents of the window's box in object space (longest side spans [-1, 1]).
    pub fn half(&self) -> DVec3 {
        let size: [f64; 3] = std::array::from_fn(|a| {
            let s = self.spacing[a];
            (self.window[1][a] - self.window[0][a]) as f64
                * if s.is_finite() && s > 0.0 { s } else { 1.0 }
        });
        let longest = size.iter().copied().fold(0.0, f64::max).max(1e-300);
        DVec3::from_array(size.map(|s| s / longest))
    }

    /// Object-space point of level-0 voxel coordinate `v` (continuous: voxel `i` spans
    /// `i .. i + 1`).
    pub fn object(&self, v: DVec3) -> DVec3 {
        let lo = DVec3::from_array(self.window[0].map(|x| x as f64));
        let n = DVec3::from_array(std::array::from_fn(|a| {
            (self.window[1][a] - self.window[0][a]) as f64
        }));
        let h = self.half();
        (v - lo) / n * 2.0 * h - h
    }

    /// Bricks per axis at `level`.
    pub fn counts(&self, level: usize) -> [usize; 3] {
        super::brick_counts(super::level_dims(self.dims, level), self.brick)
    }

    /// The level-0 voxels brick `id` covers, clipped to the window (may be empty).
    pub fn region(&self, id: BrickId) -> [[f64; 3]; 2] {
        let side = (self.brick << id.level) as f64;
        let lo: [f64; 3] =
            std::array::from_fn(|a| (id.c[a] as f64 * side).max(self.window[0][a] as f64));
        let hi: [f64; 3] = std::array::from_fn(|a| {
            ((id.c[a] as f64 + 1.0) * side)
                .min(self.dims[a] as f64)
                .min(self.window[1][a] as f64)
        });
        [lo, hi]
    }

    fn nonempty(&self, id: BrickId) -> bool {
        let [lo, hi] = self.region(id);
        (0..3).all(|a| hi[a] > lo[a])
    }

    /// The object-space box of brick `id` (clipped to the window).
    pub fn object_box(&self, id: BrickId) -> [DVec3; 2] {
        let [lo, hi] = self.region(id);
        [
            self.object(DVec3::from_array(lo)),
            self.object(DVec3::from_array(hi)),
        ]
    }

    /// Children of `id` (none at level 0).
    pub fn children(&self, id: BrickId) -> Vec<BrickId> {
        if id.level == 0 {
            return Vec::new();
        }
        let level = id.level - 1;
        let n = self.counts(level as usize);
        let mut out = Vec::with_capacity(8);
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let c = [2 * id.c[0] + dx, 2 * id.c[1] + dy, 2 * id.c[2] + dz];
                    if (0..3).all(|a| (c[a] as usize) < n[a]) {
                        let child = BrickId { level, c };
                        if self.nonempty(child) {
                            out.push(child);
                        }
                    }
                }
            }
        }
        out
    }

    /// The parent of `id` (none at the top level).
    pub fn parent(&self, id: BrickId) -> Option<BrickId> {
        ((id.level as usize) + 1 < self.levels).then(|| BrickId {
            level: id.level + 1,
            c: id.c.map(|x| x / 2),
        })
    }

    /// The top level's bricks within the window.
    pub fn roots(&self) -> Vec<BrickId> {
        let top = self.levels - 1;
        let n = self.counts(top);
        let mut out = Vec::new();
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let id = BrickId {
                        level: top as u8,
                        c: [i as u32, j as u32, k as u32],
                    };
                    if self.nonempty(id) {
                        out.push(id);
                    }
                }
            }
        }
        out
    }

    /// Object-space size of one voxel of `level` (largest over the axes).
    pub fn voxel(&self, level: u8) -> f64 {
        let h = self.half();
        (0..3)
            .map(|a| 2.0 * h[a] / (self.window[1][a] - self.window[0][a]) as f64)
            .fold(0.0, f64::max)
            * (1u64 << level) as f64
    }
}

impl View {
    fn to_pixels(self, p: DVec3) -> Option<(f64, f64, f64)> {
        let c = self.mvp * DVec4::new(p.x, p.y, p.z, 1.0);
        (c.w > 1e-12).then(|| {
            (
                (c.x / c.w * 0.5 + 0.5) * self.size[0] as f64,
                (c.y / c.w * 0.5 + 0.5) * self.size[1] as f64,
                c.w,
            )
        })
    }

    /// Pixels covered by a length `s` across the view at `p`.
    pub fn projected(&self, p: DVec3, s: f64) -> f64 {
        let n = self.toward.normalize_or_zero();
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        match (
            self.to_pixels(p),
            self.to_pixels(p + u * s),
            self.to_pixels(p + v * s),
        ) {
            (Some(a), Some(b), Some(c)) => {
                let d1 = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
                let d2 = ((c.0 - a.0).powi(2) + (c.1 - a.1).powi(2)).sqrt();
                d1.max(d2)
            }
            // Behind the eye: as large as can be (refine).
            _ => f64::INFINITY,
        }
    }

    /// Whether the box may be seen (not wholly outside one clip plane).
    pub fn sees(&self, b: [DVec3; 2]) -> bool {
        let corners: Vec<DVec4> = (0..8)
            .map(|i| {
                let p = DVec3::new(
                    if i & 1 == 0 { b[0].x } else { b[1].x },
                    if i & 2 == 0 { b[0].y } else { b[1].y },
                    if i & 4 == 0 { b[0].z } else { b[1].z },
                );
                self.mvp * DVec4::new(p.x, p.y, p.z, 1.0)
            })
            .collect();
        for axis in 0..3 {
            if corners.iter().all(|c| c[axis] > c.w) || corners.iter().all(|c| c[axis] < -c.w) {
                return false;
            }
        }
        true
    }

    /// The point of box `b` nearest the eye (its centre in orthographic views).
    pub fn nearest(&self, b: [DVec3; 2]) -> DVec3 {
        match self.eye {
            Some(e) => e.clamp(b[0], b[1]),
            None => (b[0] + b[1]) * 0.5,
        }
    }
}

/// What a view needs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Selection {
    /// The wanted cut, most urgent first (coarse before fine, large error first).
    pub wanted: Vec<BrickId>,
    /// What to draw now (wanted bricks where resident, else resident ancestors), back to
    /// front.
    pub draw: Vec<BrickId>,
    /// Wanted bricks not resident.
    pub missing: usize,
}

type Node = arbvis_core::vocab::Ranked<BrickId>;

/// The wanted cut for `view` at `pixels` per voxel, at most `max_bricks` bricks; `visible`
/// says whether a brick can show anything (ranges against the tables).
pub fn wanted(
    pyr: &Pyramid,
    view: &View,
    pixels: f64,
    max_bricks: usize,
    visible: &dyn Fn(BrickId) -> bool,
) -> Vec<BrickId> {
    let error = |id: BrickId| {
        let b = pyr.object_box(id);
        view.projected(view.nearest(b), pyr.voxel(id.level))
    };
    let keep = |id: BrickId| view.sees(pyr.object_box(id)) && visible(id);
    let mut heap = BinaryHeap::new();
    let mut leaves: Vec<BrickId> = Vec::new();
    for r in pyr.roots().into_iter().filter(|&r| keep(r)) {
        heap.push(Node {
            priority: error(r),
            item: r,
        });
    }
    let mut count = heap.len();
    while let Some(Node {
        priority: e,
        item: id,
    }) = heap.pop()
    {
        if id.level == 0 || e <= pixels {
            leaves.push(id);
            continue;
        }
        let kids: Vec<BrickId> = pyr.children(id).into_iter().filter(|&c| keep(c)).collect();
        if count - 1 + kids.len() > max_bricks {
            leaves.push(id);
            continue;
        }
        count = count - 1 + kids.len();
        for k in kids {
            heap.push(Node {
                priority: error(k),
                item: k,
            });
        }
    }
    // Most urgent first: coarse levels (they stand in for everything below), then by error.
    leaves.sort_by(|a, b| b.level.cmp(&a.level).then(error(*b).total_cmp(&error(*a))));
    leaves
}

/// The bricks to draw for `wanted` given what is resident, back to front.
pub fn drawable(
    pyr: &Pyramid,
    view: &View,
    wanted: &[BrickId],
    resident: &dyn Fn(BrickId) -> bool,
) -> (Vec<BrickId>, usize) {
    let mut stand_ins: HashSet<BrickId> = HashSet::new();
    let mut direct: Vec<BrickId> = Vec::new();
    let mut missing = 0;
    for &w in wanted {
        if resident(w) {
            direct.push(w);
            continue;
        }
        missing += 1;
        let mut a = pyr.parent(w);
        while let Some(p) = a {
            if resident(p) {
                stand_ins.insert(p);
                break;
            }
            a = pyr.parent(p);
        }
    }
    let covered = |id: BrickId, set: &HashSet<BrickId>| {
        let mut a = pyr.parent(id);
        while let Some(p) = a {
            if set.contains(&p) {
                return true;
            }
            a = pyr.parent(p);
        }
        false
    };
    let mut chosen: HashSet<BrickId> = stand_ins
        .iter()
        .copied()
        .filter(|&s| !covered(s, &stand_ins))
        .collect();
    for d in direct {
        if !covered(d, &chosen) {
            chosen.insert(d);
        }
    }
    (back_to_front(pyr, view, &chosen), missing)
}

/// `set` (a cut of the pyramid: no brick above another) in back-to-front order.
pub fn back_to_front(pyr: &Pyramid, view: &View, set: &HashSet<BrickId>) -> Vec<BrickId> {
    // Every ancestor of a member, so the walk knows where to descend.
    let mut inner: HashSet<BrickId> = HashSet::new();
    for &id in set {
        let mut a = pyr.parent(id);
        while let Some(p) = a {
            if !inner.insert(p) {
                break;
            }
            a = pyr.parent(p);
        }
    }
    let mut out = Vec::with_capacity(set.len());
    let roots = pyr.roots();
    let ordered = order(pyr, view, roots);
    for r in ordered {
        walk(pyr, view, r, set, &inner, &mut out);
    }
    out
}

fn walk(
    pyr: &Pyramid,
    view: &View,
    id: BrickId,
    set: &HashSet<BrickId>,
    inner: &HashSet<BrickId>,
    out: &mut Vec<BrickId>,
) {
    if set.contains(&id) {
        out.push(id);
    } else if inner.contains(&id) {
        for c in order(pyr, view, pyr.children(id)) {
            walk(pyr, view, c, set, inner, out);
        }
    }
}

/// Bricks of one level (siblings or roots) far to near: by L1 distance in cells from the
/// eye's cell, largest first (orthographic: along the direction toward the viewer).
fn order(pyr: &Pyramid, view: &View, mut ids: Vec<BrickId>) -> Vec<BrickId> {
    let Some(first) = ids.first().copied() else {
        return ids;
    };
    let side = (pyr.brick << first.level) as f64;
    let key = |id: &BrickId| -> f64 {
        match view.eye {
            Some(e) => {
                // The eye in level-0 voxels, then in cells of this level.
                let h = pyr.half();
                let lo = DVec3::from_array(pyr.window[0].map(|x| x as f64));
                let n = DVec3::from_array(std::array::from_fn(|a| {
                    (pyr.window[1][a] - pyr.window[0][a]) as f64
                }));
                let v = (e + h) / (2.0 * h) * n + lo;
                (0..3)
                    .map(|a| (id.c[a] as f64 - (v[a] / side).floor()).abs())
                    .sum::<f64>()
            }
            None => -(0..3)
                .map(|a| {
                    id.c[a] as f64 * view.toward[a].signum() * (view.toward[a] != 0.0) as u8 as f64
                })
                .sum::<f64>(),
        }
    };
    ids.sort_by(|a, b| key(b).total_cmp(&key(a)));
    ids
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pyramid() -> Pyramid {
        Pyramid {
            dims: [100, 70, 40],
            brick: 16,
            levels: super::super::level_count([100, 70, 40], 16),
            window: [[0, 0, 0], [100, 70, 40]],
            spacing: [1.0; 3],
        }
    }

    fn ortho(size: u32, zoom: f64) -> View {
        View {
            mvp: DMat4::from_scale(DVec3::new(zoom, zoom, -zoom)),
            size: [size, size],
            eye: None,
            toward: DVec3::Z,
        }
    }

    #[test]
    fn the_cut_follows_the_pixel_size_and_the_budget() {
        let p = pyramid();
        assert_eq!(p.levels, 4);
        // 100 voxels across 2 object units; at 50 px across the box one level-1 voxel
        // is one pixel: level 1 everywhere.
        let all = |_: BrickId| true;
        let w = wanted(&p, &ortho(50, 1.0), 1.0 + 1e-9, 10_000, &all);
        assert!(w.iter().all(|b| b.level == 1), "{w:?}");
        assert_eq!(w.len(), p.counts(1).iter().product::<usize>());
        // At 100 px: level 0, all of its bricks.
        let w = wanted(&p, &ortho(100, 1.0), 1.0 + 1e-9, 10_000, &all);
        assert!(w.iter().all(|b| b.level == 0));
        assert_eq!(w.len(), 7 * 5 * 3);
        // A budget of 20 bricks: the cut stays within it, coarser.
        let w = wanted(&p, &ortho(100, 1.0), 1.0, 20, &all);
        assert!(w.len() <= 20 && w.iter().any(|b| b.level > 0), "{w:?}");
        // Invisible bricks are never wanted.
        let w = wanted(&p, &ortho(100, 1.0), 1.0, 10_000, &|b| b.c[0] != 0);
        assert!(w.iter().all(|b| b.c[0] != 0));
    }

    #[test]
    fn stand_ins_cover_without_overlap_and_order_is_back_to_front() {
        let p = pyramid();
        let view = ortho(100, 1.0);
        let w = wanted(&p, &view, 1.0, 10_000, &|_| true);
        // Only the top level and one level-0 brick resident.
        let resident = |b: BrickId| b.level == 3 || (b.level == 0 && b.c == [0, 0, 0]);
        let (draw, missing) = drawable(&p, &view, &w, &resident);
        assert_eq!(missing, w.len() - 1);
        // The root stands in for everything, so the resident level-0 brick is not drawn.
        assert_eq!(draw, p.roots());
        // Everything resident: every wanted brick; along each line of sight (+z toward
        // the viewer) the farther brick first. (Depth first over the octree, so z is not
        // monotone across lines of sight, which do not occlude each other.)
        let (draw, missing) = drawable(&p, &view, &w, &|_| true);
        assert_eq!(missing, 0);
        assert_eq!(draw.len(), w.len());
        for (n, a) in draw.iter().enumerate() {
            for b in &draw[n + 1..] {
                if a.c[..2] == b.c[..2] {
                    assert!(a.c[2] < b.c[2], "{a:?} drawn before {b:?}");
                }
            }
        }
    }
}
