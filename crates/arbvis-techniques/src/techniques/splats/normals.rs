//! Normals estimated in the project (the seed had CloudCompare compute them): the `k`
//! nearest neighbours of each point through a k-d tree, and the direction of least
//! variance of that neighbourhood (principal component analysis).
//!
//! # Decisions
//!
//! - **Per layer**, as the seed did (it exported each layer by its id and had normals
//!   computed for each apart), so that a layer's top and bottom surfaces are not bent
//!   toward the layer beside them: one tree per layer id, neighbours only from the same
//!   layer. Integer layer ids are grouped by value, real ones by their bits (all NaNs
//!   together); without a layer attribute all points form one group.
//! - **Neighbours**: `k` includes the point itself (a neighbourhood of `k` points, as
//!   CloudCompare's and PCL's k-NN count it). The tree is kiddo's `ImmutableKdTree` over
//!   the f32 positions (what the cloud stores; kiddo is the maintained k-d tree crate
//!   with k-NN queries on f32). Points with a non-finite coordinate are left out of the
//!   trees and get the fallback normal. Coincident points enter a tree once, with
//!   their count (a tree of many copies of one point is searched in full at that spot).
//! - **PCA** in f64: the covariance of the neighbourhood about its centroid, its
//!   eigen-decomposition by cyclic Jacobi rotations (written here: glam has no
//!   eigen-solver; Jacobi is accurate for the small eigenvalue that matters and never
//!   fails on repeated eigenvalues), the eigenvector of the smallest eigenvalue.
//! - **Degenerate neighbourhoods** (eigenvalues `λ0 ≤ λ1 ≤ λ2`), counted in the report:
//!   fewer than 3 points, or all coincident (`λ2 = 0`) → +Z (up in a geological section);
//!   collinear (`λ1 ≤ 1e-10 λ2`, a spread across the line under 1e-5 of its length) →
//!   the direction perpendicular to the line closest to +Z (+X when the line is
//!   vertical).
//! - **Sign**: PCA gives an axis, not a side. Estimates are made deterministic (z > 0,
//!   else y > 0, else x > 0); the side is chosen at draw time, toward the camera:
//!   [`orient_toward`] flips a normal whose dot product with the direction to the eye
//!   is negative, as the seed fixed its inverted normals.
//! - **Parallel** over the points of a layer (rayon), with a progress bar on a terminal
//!   for [`arbvis_data::points::progress::MIN_POINTS`] points or more.

use std::collections::BTreeMap;
use std::num::NonZeroUsize;

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use arbvis_data::points::progress::Progress;
use arbvis_data::points::{PointCloud, Values, LAYER};

/// The default neighbourhood size.
pub const DEFAULT_K: usize = 16;

/// Collinearity threshold on `λ1 / λ2`.
const COLLINEAR: f64 = 1e-10;

/// How an estimate was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalKind {
    /// The least-variance direction of a neighbourhood that spans a plane or a volume.
    Fitted,
    /// Collinear neighbourhood: the perpendicular closest to +Z.
    Collinear,
    /// All neighbours at one place: +Z.
    Coincident,
    /// Fewer than 3 points (or a non-finite position): +Z.
    TooFew,
}

/// A normal and how it was found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Unit normal (sign made deterministic, see the module doc).
    pub normal: DVec3,
    /// How.
    pub kind: NormalKind,
}

/// Layer ids, one per point, or none.
#[derive(Debug, Clone, Copy)]
pub enum LayerIds<'a> {
    /// All points in one group.
    None,
    /// Integer ids.
    Int(&'a [i32]),
    /// Real ids (grouped by bits).
    Float(&'a [f32]),
}

impl LayerIds<'_> {
    /// The group key of point `i` (points past the end of the ids share one group).
    fn key(&self, i: usize) -> u64 {
        match self {
            LayerIds::None => 0,
            LayerIds::Int(v) => v.get(i).map_or(1 << 40, |&x| x as u32 as u64),
            LayerIds::Float(v) => v.get(i).map_or(1 << 40, |x| {
                let x = if x.is_nan() { f32::NAN } else { x + 0.0 };
                x.to_bits() as u64
            }),
        }
    }
}

/// Normals of a whole cloud and what happened.
#[derive(Debug, Clone, PartialEq)]
pub struct NormalReport {
    /// One unit normal per point.
    pub normals: Vec<[f32; 3]>,
    /// Groups the points were split into (layers, or 1).
    pub groups: usize,
    /// Estimates from collinear neighbourhoods.
    pub collinear: usize,
    /// Estimates from coincident neighbourhoods.
    pub coincident: usize,
    /// Points with fewer than 3 neighbours or a non-finite position.
    pub too_few: usize,
}

/// Normals of `cloud` with neighbourhoods of `k` points, per layer when `per_layer`
/// and the cloud has a [`LAYER`] attribute.
pub fn estimate_cloud(cloud: &PointCloud, k: usize, per_layer: bool) -> NormalReport {
    let layers = match cloud.attribute(LAYER).map(|a| &a.values) {
        Some(Values::Int(v)) if per_layer => LayerIds::Int(v),
        Some(Values::Float(v)) if per_layer => LayerIds::Float(v),
        _ => LayerIds::None,
    };
    estimate(&cloud.positions, layers, k)
}

/// Normals of `positions` with neighbourhoods of `k` points (the point included) taken
/// within each layer group.
pub fn estimate(positions: &[[f32; 3]], layers: LayerIds<'_>, k: usize) -> NormalReport {
    let n = positions.len();
    let mut report = NormalReport {
        normals: vec![[0.0, 0.0, 1.0]; n],
        groups: 0,
        collinear: 0,
        coincident: 0,
        too_few: 0,
    };
    let mut groups: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
    for (i, p) in positions.iter().enumerate() {
        if p.iter().all(|c| c.is_finite()) {
            groups.entry(layers.key(i)).or_default().push(i);
        } else {
            report.too_few += 1;
        }
    }
    report.groups = groups.len();
    let progress = Progress::new(n as u64, "estimating normals");
    for members in groups.values() {
        let local: Vec<[f32; 3]> = members.iter().map(|&i| positions[i]).collect();
        let estimates = estimate_group(&local, k, &progress);
        for (&i, e) in members.iter().zip(&estimates) {
            report.normals[i] = e.normal.as_vec3().to_array();
            match e.kind {
                NormalKind::Fitted => {}
                NormalKind::Collinear => report.collinear += 1,
                NormalKind::Coincident => report.coincident += 1,
                NormalKind::TooFew => report.too_few += 1,
            }
        }
    }
    report
}

/// Estimates for one group of finite points.
fn estimate_group(points: &[[f32; 3]], k: usize, progress: &Progress) -> Vec<Estimate> {
    let fallback = vec![
        Estimate {
            normal: DVec3::Z,
            kind: NormalKind::TooFew,
        };
        points.len()
    ];
    let k = k.min(points.len());
    if k == 0 || u32::try_from(points.len()).is_err() {
        progress.inc(points.len() as u64);
        return fallback;
    }
    let (unique, count, slot) = distinct(points);
    let (Some(qty), Ok(tree)) = (
        NonZeroUsize::new(k.min(unique.len())),
        ImmutableKdTree::<f32, 3>::new_from_slice(&unique),
    ) else {
        progress.inc(points.len() as u64);
        return fallback;
    };
    let estimates: Vec<Estimate> = (0..unique.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|u| {
            let found = tree
                .query(&unique[u])
                .nearest_n::<SquaredEuclidean<f32>>(qty)
                .execute();
            // The k nearest points: each distinct position as often as it occurs.
            let mut neighbours = Vec::with_capacity(k);
            for r in &found {
                let i = r.item as usize;
                let (Some(p), Some(&c)) = (unique.get(i), count.get(i)) else {
                    continue;
                };
                let take = (c as usize).min(k - neighbours.len());
                neighbours.extend(std::iter::repeat_n(
                    DVec3::from_array(p.map(f64::from)),
                    take,
                ));
                if neighbours.len() == k {
                    break;
                }
            }
            progress.inc(count.get(u).map_or(0, |&c| c as u64));
            pca_normal(neighbours)
        })
        .collect();
    slot.iter().map(|&u| estimates[u as usize]).collect()
}

/// The distinct positions of `points` (-0 and +0 alike), how often each occurs, and
/// which one each point is. The tree holds each position once: a k-d tree of many
/// coincident points is searched in full by every query at that spot (many copies of
/// one point made the search crawl in a test build; measured: docs/benchmarks.md,
/// "Figures behind the splats' settings"), and points at one position share one
/// normal anyway.
fn distinct(points: &[[f32; 3]]) -> (Vec<[f32; 3]>, Vec<u32>, Vec<u32>) {
    let bits = |p: &[f32; 3]| p.map(|c| (c + 0.0).to_bits());
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    order.par_sort_unstable_by_key(|&i| bits(&points[i as usize]));
    let mut unique: Vec<[f32; 3]> = Vec::new();
    let mut count: Vec<u32> = Vec::new();
    let mut slot = vec![0u32; points.len()];
    let mut last = None;
    for &i in &order {
        let p = points[i as usize].map(|c| c + 0.0);
        if last != Some(bits(&p)) {
            last = Some(bits(&p));
            unique.push(p);
            count.push(0);
        }
        if let Some(c) = count.last_mut() {
            *c += 1;
        }
        slot[i as usize] = (unique.len() - 1) as u32;
    }
    (unique, count, slot)
}

/// The normal of a neighbourhood (see the module doc for the degenerate cases).
pub fn pca_normal(points: impl IntoIterator<Item = DVec3>) -> Estimate {
    let points: Vec<DVec3> = points.into_iter().filter(|p| p.is_finite()).collect();
    let up = |kind| Estimate {
        normal: DVec3::Z,
        kind,
    };
    if points.len() < 3 {
        return up(NormalKind::TooFew);
    }
    let centroid = points.iter().sum::<DVec3>() / points.len() as f64;
    let mut c = [[0.0f64; 3]; 3];
    for p in &points {
        let d = (*p - centroid).to_array();
        for r in 0..3 {
            for s in 0..3 {
                c[r][s] += d[r] * d[s];
            }
        }
    }
    let (values, vectors) = symmetric_eigen(c);
    if values[2].is_nan() || values[2] <= 0.0 {
        return up(NormalKind::Coincident);
    }
    if values[1] <= COLLINEAR * values[2] {
        let axis = vectors[2];
        let mut n = DVec3::Z - axis * axis.z;
        if n.length() < 1e-6 {
            n = DVec3::X - axis * axis.x;
        }
        return Estimate {
            normal: canonical_sign(n.normalize_or(DVec3::Z)),
            kind: NormalKind::Collinear,
        };
    }
    Estimate {
        normal: canonical_sign(vectors[0].normalize_or(DVec3::Z)),
        kind: NormalKind::Fitted,
    }
}

/// z > 0, else y > 0, else x > 0.
fn canonical_sign(n: DVec3) -> DVec3 {
    let s = if n.z != 0.0 {
        n.z
    } else if n.y != 0.0 {
        n.y
    } else {
        n.x
    };
    if s < 0.0 {
        -n
    } else {
        n
    }
}

/// Eigenvalues (ascending) and unit eigenvectors of the symmetric matrix `a`, by cyclic
/// Jacobi rotations until the off-diagonal part vanishes against the diagonal.
pub fn symmetric_eigen(a: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut a = a;
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..64 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-32 * diag || !off.is_finite() || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = if theta.abs() > 1e150 {
                0.5 / theta
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in a.iter_mut() {
                let (kp, kq) = (row[p], row[q]);
                row[p] = c * kp - s * kq;
                row[q] = s * kp + c * kq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            a[p] = std::array::from_fn(|k| c * row_p[k] - s * row_q[k]);
            a[q] = std::array::from_fn(|k| s * row_p[k] + c * row_q[k]);
            for row in v.iter_mut() {
                let (kp, kq) = (row[p], row[q]);
                row[p] = c * kp - s * kq;
                row[q] = s * kp + c * kq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let values = idx.map(|i| a[i][i]);
    let vectors = idx.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]));
    (values, vectors)
}

/// `normal` flipped when it faces away from the eye (`normal · (eye - point) < 0`), as
/// the seed did at draw time. For an orthographic view pass a point far along the
/// direction toward the viewer as `eye`.
pub fn orient_toward(normal: DVec3, point: DVec3, eye: DVec3) -> DVec3 {
    if normal.dot(eye - point) < 0.0 {
        -normal
    } else {
        normal
    }
}

#[cfg(test)]
mod tests;
