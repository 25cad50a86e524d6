//! The fast generalized winding number (Barill, Dickson, Schmidt, Levin and Jacobson 2018,
//! "Fast winding numbers for soups and clouds"): a bounding-volume tree over the
//! triangles, each node holding the Taylor expansion of its triangles' winding number
//! about its area-weighted centre `p̃`, so that a query sums a node's expansion when it is
//! far (`|q - p̃| > β r`, `r` the node's radius) and descends into it otherwise; leaves
//! near the query are summed exactly (van Oosterom-Strackee solid angles).
//!
//! # The expansion
//! The winding number is `w(q) = ∫ K(x - q) · n(x) dA / 4π` with `K(r) = r / |r|³`. With
//! `x - q = r + δ`, `r = p̃ - q`, second-order Taylor in `δ` gives
//! `4π w ≈ K(r)·N + ∂ⱼKᵢ(r) Mᵢⱼ + ½ ∂ⱼ∂ₖKᵢ(r) Hᵢⱼₖ` with the node's moments
//! `N = ∫ n dA` (the area-weighted normal), `Mᵢⱼ = ∫ nᵢ δⱼ dA` and `Hᵢⱼₖ = ∫ nᵢ δⱼ δₖ dA`,
//! exact for flat triangles: `∫_T δ δᵀ dA = A (c - p̃)(c - p̃)ᵀ + A/12 Σᵥ (v - c)(v - c)ᵀ`.
//! The derivatives are `∂ⱼKᵢ = δᵢⱼ/d³ - 3 rᵢ rⱼ/d⁵` and
//! `∂ⱼ∂ₖKᵢ = -3 (δᵢⱼ rₖ + δᵢₖ rⱼ + δⱼₖ rᵢ)/d⁵ + 15 rᵢ rⱼ rₖ/d⁷`.
//!
//! # Accuracy
//! A far node's truncation error falls as `(r/d)³` times its contribution (`d⁻⁵`; the
//! tests check that order on one triangle). With [`BETA`] = 2, measured against the exact
//! sum on 600 random queries (half anywhere around the mesh, half within a fiftieth of
//! its size from the surface) on closed and open meshes of 600 to 20,000 triangles: the
//! largest difference is 6.2e-3, the median 1e-3 (β = 3 would give 9e-4 for 2.2 times
//! the work, β = 4 2.5e-4 for 3.7 times). The tests hold it to [`ERROR_BOUND`] = 1e-2: an
//! inside test `|w| >= 0.5` can differ from the exact one only where the exact `|w|` is
//! within 1e-2 of 0.5.
//!
//! # Cost
//! Building is `O(n log n)`; a query sums `O(log n)` far nodes plus the leaves within
//! `β r` of it: 70 to 110 nodes and triangles on average in the tests (2,300 to 20,000
//! triangles), against one atan2 per triangle for the exact sum.

use glam::DVec3;

/// A node is summed by its expansion when the query is farther than `BETA` times its
/// radius from its centre (the paper's default).
pub const BETA: f64 = 2.0;

/// The bound on the difference from the exact winding number that the tests check (open
/// and closed meshes, random queries near and far; the largest measured is 6.2e-3, the
/// median 1e-3); see the module doc.
pub const ERROR_BOUND: f64 = 1e-2;

/// Triangles per leaf, at most.
const LEAF: usize = 8;

/// A node: its expansion, its extent and its children or triangles.
#[derive(Debug, Clone)]
struct Node {
    /// Area-weighted centre of its triangles (mean of centroids when they have no area).
    centre: DVec3,
    /// Largest distance from the centre to a corner of its triangles.
    radius: f64,
    /// `∫ n dA`.
    n: DVec3,
    /// `Mᵢⱼ = ∫ nᵢ δⱼ dA`.
    m: [[f64; 3]; 3],
    /// `Hᵢⱼₖ` for `j <= k`, in the order (0,0) (0,1) (0,2) (1,1) (1,2) (2,2).
    h: [[f64; 6]; 3],
    /// Triangles `order[first..first + count]` (leaves), else children `left`, `left + 1`.
    first: u32,
    count: u32,
    left: u32,
}

/// Index of `(j, k)` in a symmetric 3x3 stored as 6.
const SYM: [[usize; 3]; 3] = [[0, 1, 2], [1, 3, 4], [2, 4, 5]];

/// The tree over a triangle soup.
#[derive(Debug, Clone, Default)]
pub struct WindingTree {
    nodes: Vec<Node>,
    /// The triangles, in leaf order.
    triangles: Vec<[DVec3; 3]>,
}

/// One triangle's moments about `p`: `N`, `M`, `H`.
fn moments(t: &[DVec3; 3], p: DVec3) -> (DVec3, [[f64; 3]; 3], [[f64; 6]; 3]) {
    let n = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]);
    let c = (t[0] + t[1] + t[2]) / 3.0;
    let d = (c - p).to_array();
    let e = t.map(|v| (v - c).to_array());
    let n = n.to_array();
    let mut m = [[0.0; 3]; 3];
    let mut h = [[0.0; 6]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = n[i] * d[j];
            for k in j..3 {
                let second = d[j] * d[k]
                    + (e[0][j] * e[0][k] + e[1][j] * e[1][k] + e[2][j] * e[2][k]) / 12.0;
                h[i][SYM[j][k]] = n[i] * second;
            }
        }
    }
    (DVec3::from_array(n), m, h)
}

/// Exact winding number of one triangle at `q`, times 4π (van Oosterom-Strackee).
pub(crate) fn solid_angle(t: &[DVec3; 3], q: DVec3) -> f64 {
    let [a, b, c] = t.map(|v| v - q);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let det = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * det.atan2(den)
}

impl WindingTree {
    /// Build the tree over `triangles`.
    pub fn new(triangles: &[[DVec3; 3]]) -> WindingTree {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<DVec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len() / LEAF + 1);
        nodes.push(Self::node(triangles, &order, 0, triangles.len()));
        // Split breadth-first: a node's children are made together, so they sit at
        // `left` and `left + 1`.
        let mut next = 0;
        while next < nodes.len() {
            let (first, count) = (nodes[next].first as usize, nodes[next].count as usize);
            if count > LEAF {
                let slice = &mut order[first..first + count];
                let (lo, hi) = slice
                    .iter()
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &t| {
                        (lo.min(centroids[t as usize]), hi.max(centroids[t as usize]))
                    });
                let axis = (hi - lo).max_position();
                let half = count / 2;
                slice.select_nth_unstable_by(half, |&a, &b| {
                    centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
                });
                let left = nodes.len() as u32;
                nodes.push(Self::node(triangles, &order, first, half));
                nodes.push(Self::node(triangles, &order, first + half, count - half));
                nodes[next].left = left;
            }
            next += 1;
        }
        WindingTree {
            nodes,
            triangles: order.iter().map(|&t| triangles[t as usize]).collect(),
        }
    }

    /// A node over `order[first..first + count]`, its moments summed from its triangles.
    fn node(triangles: &[[DVec3; 3]], order: &[u32], first: usize, count: usize) -> Node {
        let own = &order[first..first + count];
        let (mut weighted, mut area, mut mean) = (DVec3::ZERO, 0.0, DVec3::ZERO);
        for &t in own {
            let t = &triangles[t as usize];
            let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
            let c = (t[0] + t[1] + t[2]) / 3.0;
            weighted += a * c;
            area += a;
            mean += c;
        }
        let centre = if area > 0.0 && (weighted / area).is_finite() {
            weighted / area
        } else {
            mean / count.max(1) as f64
        };
        let mut node = Node {
            centre,
            radius: 0.0,
            n: DVec3::ZERO,
            m: [[0.0; 3]; 3],
            h: [[0.0; 6]; 3],
            first: first as u32,
            count: count as u32,
            left: 0,
        };
        for &t in own {
            let t = &triangles[t as usize];
            for v in t {
                node.radius = node.radius.max((*v - centre).length());
            }
            let (n, m, h) = moments(t, centre);
            node.n += n;
            for (sum, row) in node.m.iter_mut().flatten().zip(m.iter().flatten()) {
                *sum += row;
            }
            for (sum, row) in node.h.iter_mut().flatten().zip(h.iter().flatten()) {
                *sum += row;
            }
        }
        node
    }

    /// The winding number at `q` (see the module doc for its accuracy).
    pub fn winding_number(&self, q: DVec3) -> f64 {
        self.evaluate(q).0
    }

    /// The winding number at `q`, the far nodes summed by their expansion and the
    /// triangles summed exactly.
    fn evaluate(&self, q: DVec3) -> (f64, usize, usize) {
        let (mut sum, mut far_nodes, mut exact) = (0.0, 0, 0);
        let mut stack = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push(0u32);
        }
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            let r = node.centre - q;
            let d = r.length();
            if d > BETA * node.radius {
                sum += far(node, r, d);
                far_nodes += 1;
            } else if node.left == 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                sum += self.triangles[a..b]
                    .iter()
                    .map(|t| solid_angle(t, q))
                    .sum::<f64>();
                exact += b - a;
            } else {
                stack.push(node.left);
                stack.push(node.left + 1);
            }
        }
        (sum / (4.0 * std::f64::consts::PI), far_nodes, exact)
    }
}

/// A node's expansion at `r = centre - q`, `d = |r|`, times 4π.
fn far(node: &Node, r: DVec3, d: f64) -> f64 {
    let rr = r.to_array();
    let (d2, d3) = (d * d, d * d * d);
    let (d5, d7) = (d3 * d2, d3 * d2 * d2);
    let first = node.n.dot(r) / d3;
    let (mut trace, mut rmr) = (0.0, 0.0);
    for i in 0..3 {
        trace += node.m[i][i];
        for j in 0..3 {
            rmr += rr[i] * node.m[i][j] * rr[j];
        }
    }
    let second = trace / d3 - 3.0 * rmr / d5;
    // A = Σᵢₖ rₖ Hᵢᵢₖ, B = Σᵢⱼ rᵢ Hᵢⱼⱼ, C = Σᵢⱼₖ rᵢ rⱼ rₖ Hᵢⱼₖ.
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for i in 0..3 {
        let h = &node.h[i];
        for k in 0..3 {
            a += rr[k] * h[SYM[i][k]];
            b += rr[i] * h[SYM[k][k]];
            for j in 0..3 {
                c += rr[i] * rr[j] * rr[k] * h[SYM[j][k]];
            }
        }
    }
    let third = 0.5 * (-3.0 * (2.0 * a + b) / d5 + 15.0 * c / d7);
    first + second + third
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// xorshift, uniform in [0, 1).
    pub(super) struct Rng(pub(super) u64);

    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next()
        }
    }

    /// A sphere of radius `r` around `c` (outward), `nu` x `nv` quads split in two, cut at
    /// the polar angle `cut` (π: closed; less: open, a bowl), its vertices jittered so no
    /// two triangles are alike.
    pub(super) fn sphere(
        c: DVec3,
        r: f64,
        nu: usize,
        nv: usize,
        cut: f64,
        rng: &mut Rng,
    ) -> Vec<[DVec3; 3]> {
        let at = |u: usize, v: usize| {
            let (phi, theta) = (
                std::f64::consts::TAU * u as f64 / nu as f64,
                std::f64::consts::PI * v as f64 / nv as f64,
            );
            c + r * DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            )
        };
        let mut grid = vec![vec![DVec3::ZERO; nv + 1]; nu + 1];
        for (u, column) in grid.iter_mut().enumerate() {
            for (v, p) in column.iter_mut().enumerate() {
                let jitter = if v == 0 || v == nv {
                    0.0
                } else {
                    0.1 * r / nv as f64
                };
                *p = at(u % nu, v)
                    + jitter
                        * DVec3::new(
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                        );
            }
        }
        grid[nu] = grid[0].clone();
        let mut out = Vec::new();
        for u in 0..nu {
            for v in 0..nv {
                if std::f64::consts::PI * (v + 1) as f64 / nv as f64 > cut + 1e-12 {
                    continue;
                }
                let (a, b, c2, d) = (
                    grid[u][v],
                    grid[u + 1][v],
                    grid[u + 1][v + 1],
                    grid[u][v + 1],
                );
                out.push([a, d, c2]);
                out.push([a, c2, b]);
            }
        }
        out
    }

    pub(super) fn exact(triangles: &[[DVec3; 3]], q: DVec3) -> f64 {
        triangles.iter().map(|t| solid_angle(t, q)).sum::<f64>() / (4.0 * std::f64::consts::PI)
    }

    /// Query `k`: even ones anywhere in the box around the mesh, odd ones near its
    /// surface (within 0.02, a fiftieth of its size).
    pub(super) fn query(triangles: &[[DVec3; 3]], rng: &mut Rng, k: usize) -> DVec3 {
        if k.is_multiple_of(2) {
            DVec3::new(
                rng.range(-1.6, 1.6),
                rng.range(-1.4, 1.5),
                rng.range(-1.5, 1.7),
            )
        } else {
            let t = triangles[(rng.next() * triangles.len() as f64) as usize];
            let (a, b) = (rng.next(), rng.next());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]) + rng.range(-0.02, 0.02) * n
        }
    }

    /// The largest difference from the exact sum over `queries` random queries.
    fn worst(triangles: &[[DVec3; 3]], rng: &mut Rng, queries: usize) -> f64 {
        let tree = WindingTree::new(triangles);
        (0..queries)
            .map(|k| {
                let q = query(triangles, rng, k);
                (tree.winding_number(q) - exact(triangles, q)).abs()
            })
            .fold(0f64, f64::max)
    }

    #[test]
    fn matches_the_exact_sum_on_closed_and_open_meshes() {
        let mut rng = Rng(0x5eed_1234_abcd);
        let c = DVec3::new(0.07, -0.05, 0.11);
        let cases: Vec<(&str, Vec<[DVec3; 3]>)> = vec![
            (
                "closed sphere",
                sphere(c, 1.0, 48, 24, std::f64::consts::PI, &mut rng),
            ),
            ("open bowl", sphere(c, 0.9, 64, 32, 2.0, &mut rng)),
            ("fine open bowl", sphere(c, 1.1, 160, 64, 2.4, &mut rng)),
            (
                "random soup",
                (0..600)
                    .map(|_| {
                        let p = DVec3::new(
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                        );
                        let e = |rng: &mut Rng| {
                            DVec3::new(
                                rng.range(-0.2, 0.2),
                                rng.range(-0.2, 0.2),
                                rng.range(-0.2, 0.2),
                            )
                        };
                        [p, p + e(&mut rng), p + e(&mut rng)]
                    })
                    .collect(),
            ),
        ];
        for (what, triangles) in &cases {
            let w = worst(triangles, &mut rng, 600);
            eprintln!(
                "{what}: {} triangles, largest difference {w:.2e}",
                triangles.len()
            );
            assert!(w <= ERROR_BOUND, "{what}: {w}");
        }
        // Inside and far outside a closed mesh: 1 and 0, the far one to the expansion's
        // precision (one node at 60 radii: (1/60)^3 of a contribution that is itself 0).
        let closed = &cases[0].1;
        let tree = WindingTree::new(closed);
        assert!((tree.winding_number(c) - 1.0).abs() <= ERROR_BOUND);
        assert!(tree.winding_number(c + DVec3::new(50.0, -30.0, 7.0)).abs() < 1e-9);
    }

    #[test]
    fn one_far_triangle_converges_at_the_expansions_order() {
        // The remainder of a second-order expansion of K ~ d^-2 falls as d^-5: each
        // doubling of the distance divides the error by about 32 (30 to 34 allowed for
        // the next order's share).
        let t = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.2, 0.1),
            DVec3::new(0.3, 0.9, -0.2),
        ];
        let tree = WindingTree::new(&[t]);
        let node = &tree.nodes[0];
        let error = |d: f64| {
            let q = node.centre + d * DVec3::new(0.3, -0.5, 0.8).normalize();
            (far(node, node.centre - q, d) - solid_angle(&t, q)).abs()
        };
        for d in [4.0, 8.0, 16.0] {
            let ratio = error(d) / error(2.0 * d);
            assert!((30.0..34.0).contains(&ratio), "d {d}: ratio {ratio}");
        }
        // At twice the radius (BETA), a twentieth of the triangle's own contribution.
        let d = BETA * node.radius;
        let q = node.centre + d * DVec3::new(0.3, -0.5, 0.8).normalize();
        assert!(error(d) < 0.05 * solid_angle(&t, q).abs());
    }

    #[test]
    fn far_queries_cost_a_few_nodes() {
        // 20,480 triangles; a query away from the surface sums a few dozen expansions
        // and no triangle exactly; one near it, a few leaves: against 20,480 atan2.
        let mut rng = Rng(77);
        let triangles = sphere(DVec3::ZERO, 1.0, 160, 64, std::f64::consts::PI, &mut rng);
        let tree = WindingTree::new(&triangles);
        let (w, far_nodes, exact) = tree.evaluate(DVec3::new(0.1, 0.2, -0.15));
        assert!((w - 1.0).abs() < ERROR_BOUND, "{w}");
        assert!(
            far_nodes < 400 && exact < 200,
            "{far_nodes} nodes, {exact} triangles"
        );
        let (_, far_nodes, exact) = tree.evaluate(DVec3::new(1.001, 0.0, 0.0));
        assert!(
            far_nodes + exact < 2000,
            "{far_nodes} nodes, {exact} triangles"
        );
        assert!(triangles.len() > 20_000);
    }
}
