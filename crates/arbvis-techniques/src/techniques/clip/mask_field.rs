//! Voxel masks as clip objects: a volume thresholded (`value >= threshold`; NaN is
//! outside), stretched over the clipped volume's box (texture coordinates shared: a mask
//! is a segmentation of the same block, whatever its own spacing says).
//!
//! # The shape
//! The reference ([`MaskShape::inside`]) is the union of the mask's inside voxels as
//! cubes: a point is inside when its nearest mask voxel is (the voxel containing it;
//! outside the box, the nearest border voxel).
//!
//! # The distance
//! On the clip grid the mask is sampled at the voxel centres (nearest mask voxel; the
//! same voxels when the clip grid is the mask's grid). An exact Euclidean *feature*
//! transform (Felzenszwalb and Huttenlocher's separable lower envelope of parabolas, with
//! the spacing of each axis, keeping the argmin so the nearest voxel itself is known)
//! finds, for every voxel, the nearest voxel centre of the other class. The clip distance
//! is the distance from the voxel centre to that voxel's *cube* (per axis
//! `max(|Δ| - h/2, 0)`), positive inside, so that the boundary between an inside and an
//! outside voxel lies half-way between their centres, as the cube union's faces do. The
//! nearest cube is that of the nearest centre for face and edge neighbours; farther away
//! the two can differ slightly, which the texture's clamp at one diagonal hides. A grid
//! with only one class gets `±2 diag` everywhere.

use glam::DVec3;
use rayon::prelude::*;

use super::grid::ClipGrid;
use arbvis_data::volume::Volume;

const NONE: u32 = u32::MAX;

/// A thresholded volume over the clipped volume's box.
#[derive(Debug, Clone)]
pub struct MaskShape {
    /// Mask voxels along i, j, k.
    pub dims: [usize; 3],
    /// Inside flag per mask voxel, i fastest.
    pub inside: Vec<bool>,
    /// Half-extents of the box the mask spans.
    pub half: DVec3,
}

impl MaskShape {
    /// Threshold `volume` (`>= threshold` is inside, NaN outside) over `[-half, half]`.
    pub fn new(volume: &Volume, threshold: f64, half: [f64; 3]) -> MaskShape {
        MaskShape {
            dims: volume.dims,
            inside: volume
                .values
                .iter()
                .map(|&v| v as f64 >= threshold)
                .collect(),
            half: DVec3::from_array(half),
        }
    }

    /// Voxels inside.
    pub fn count_inside(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }

    /// Nearest mask voxel of object-space `p` (clamped to the grid).
    fn voxel_of(&self, p: DVec3) -> usize {
        let t = (p + self.half) / (2.0 * self.half);
        let c = |a: usize| {
            ((t[a] * self.dims[a] as f64).floor().max(0.0) as usize).min(self.dims[a] - 1)
        };
        c(0) + self.dims[0] * (c(1) + self.dims[1] * c(2))
    }

    /// The f64 reference: the voxel containing `p` is inside.
    pub fn inside(&self, p: DVec3) -> bool {
        self.inside[self.voxel_of(p)]
    }

    /// Clip distance at every voxel centre of `grid` (see the module doc), i fastest.
    pub fn field(&self, grid: &ClipGrid) -> Vec<f32> {
        let [ni, nj, _] = grid.dims;
        let mut occupied = vec![false; grid.len()];
        occupied
            .par_chunks_mut(ni * nj)
            .enumerate()
            .for_each(|(k, slice)| {
                for j in 0..nj {
                    for i in 0..ni {
                        slice[i + ni * j] = self.inside(grid.centre(i, j, k));
                    }
                }
            });
        let h = grid.voxel();
        let diag = grid.diagonal();
        let to_outside = feature_transform(
            grid.dims,
            h,
            &occupied.iter().map(|b| !b).collect::<Vec<_>>(),
        );
        let to_inside = feature_transform(grid.dims, h, &occupied);
        let coords = |v: usize| {
            DVec3::new(
                (v % ni) as f64,
                ((v / ni) % nj) as f64,
                (v / (ni * nj)) as f64,
            )
        };
        (0..grid.len())
            .into_par_iter()
            .map(|v| {
                let inside = occupied[v];
                let site = if inside { to_outside[v] } else { to_inside[v] };
                let d = if site == NONE {
                    2.0 * diag
                } else {
                    let gap =
                        ((coords(v) - coords(site as usize)).abs() * h - 0.5 * h).max(DVec3::ZERO);
                    gap.length().min(2.0 * diag)
                };
                (if inside { d } else { -d }) as f32
            })
            .collect()
    }
}

/// For every voxel, the index of the nearest voxel (Euclidean, spacing `h`) whose
/// `site` flag is set, or [`NONE`] when there is none: Felzenszwalb-Huttenlocher along
/// i, then j, then k, keeping the argmin.
fn feature_transform(dims: [usize; 3], h: DVec3, site: &[bool]) -> Vec<u32> {
    let [ni, nj, nk] = dims;
    let mut dist: Vec<f64> = site
        .iter()
        .map(|&s| if s { 0.0 } else { f64::INFINITY })
        .collect();
    let mut nearest: Vec<u32> = (0..site.len())
        .map(|v| if site[v] { v as u32 } else { NONE })
        .collect();
    // Along i: contiguous lines.
    dist.par_chunks_mut(ni)
        .zip(nearest.par_chunks_mut(ni))
        .for_each(|(d, n)| {
            let (d0, n0) = (d.to_vec(), n.to_vec());
            envelope(&d0, &n0, h.x, d, n);
        });
    // Along j: within each k-slice.
    dist.par_chunks_mut(ni * nj)
        .zip(nearest.par_chunks_mut(ni * nj))
        .for_each(|(d, n)| {
            let (mut ld, mut ln) = (vec![0.0; nj], vec![0; nj]);
            let (mut od, mut on) = (vec![0.0; nj], vec![0; nj]);
            for i in 0..ni {
                for j in 0..nj {
                    ld[j] = d[i + ni * j];
                    ln[j] = n[i + ni * j];
                }
                envelope(&ld, &ln, h.y, &mut od, &mut on);
                for j in 0..nj {
                    d[i + ni * j] = od[j];
                    n[i + ni * j] = on[j];
                }
            }
        });
    // Along k: lines across slices, computed per j in parallel and written back.
    if nk > 1 {
        let results: Vec<Vec<u32>> = (0..nj)
            .into_par_iter()
            .map(|j| {
                let mut rn = vec![0; ni * nk];
                let (mut ld, mut ln, mut scratch) = (vec![0.0; nk], vec![0; nk], vec![0.0; nk]);
                for i in 0..ni {
                    for k in 0..nk {
                        ld[k] = dist[i + ni * (j + nj * k)];
                        ln[k] = nearest[i + ni * (j + nj * k)];
                    }
                    envelope(&ld, &ln, h.z, &mut scratch, &mut rn[i * nk..(i + 1) * nk]);
                }
                rn
            })
            .collect();
        for (j, rn) in results.into_iter().enumerate() {
            for i in 0..ni {
                for k in 0..nk {
                    nearest[i + ni * (j + nj * k)] = rn[i * nk + k];
                }
            }
        }
    }
    nearest
}

/// One line: `out_d[q] = min_p (h (q - p))^2 + d[p]`, `out_n[q]` the `n[p]` of the minimum.
fn envelope(d: &[f64], n: &[u32], h: f64, out_d: &mut [f64], out_n: &mut [u32]) {
    let len = d.len();
    let finite: Vec<usize> = (0..len).filter(|&p| d[p].is_finite()).collect();
    if finite.is_empty() {
        out_d.fill(f64::INFINITY);
        out_n.fill(NONE);
        return;
    }
    let h2 = h * h;
    let key = |p: usize| d[p] + h2 * (p * p) as f64;
    let meet = |p: usize, q: usize| (key(q) - key(p)) / (2.0 * h2 * (q as f64 - p as f64));
    let mut v = vec![finite[0]; finite.len()];
    let mut z = vec![f64::NEG_INFINITY; finite.len() + 1];
    z[1] = f64::INFINITY;
    let mut k = 0;
    for &q in &finite[1..] {
        let mut s = meet(v[k], q);
        while s <= z[k] {
            k -= 1;
            s = meet(v[k], q);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    let mut k = 0;
    for q in 0..len {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dq = q as f64 - p as f64;
        out_d[q] = h2 * dq * dq + d[p];
        out_n[q] = n[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_transform_matches_brute_force() {
        let dims = [7, 5, 4];
        let h = DVec3::new(0.3, 0.5, 0.7);
        let n = 7 * 5 * 4;
        let site: Vec<bool> = (0..n).map(|v| (v * 37 + 11) % 23 == 0).collect();
        let f = feature_transform(dims, h, &site);
        let c = |v: usize| DVec3::new((v % 7) as f64, ((v / 7) % 5) as f64, (v / 35) as f64) * h;
        for (v, &nearest) in f.iter().enumerate() {
            let best = (0..n)
                .filter(|&s| site[s])
                .map(|s| (c(v) - c(s)).length())
                .fold(f64::INFINITY, f64::min);
            let got = (c(v) - c(nearest as usize)).length();
            assert!((got - best).abs() < 1e-12, "voxel {v}: {got} vs {best}");
        }
        assert!(feature_transform(dims, h, &vec![false; n])
            .iter()
            .all(|&s| s == NONE));
    }
}
