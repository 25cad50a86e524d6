//! Empty space for the precise ray caster (CPU, no GL): the volume cut into
//! bricks of `size³` voxels, each with the range of levels a sample inside it can
//! interpolate (its voxels and one voxel around them: a trilinear sample at a point of the
//! brick reads the voxels either side of it), and against the current tables and
//! coefficients a flag: 1 where some sample in the brick can have alpha above 0.
//!
//! A sample's alpha is 0 exactly when, in a sum, every attribute's `Ca · alpha` is 0, and
//! in a product when any one is; an interpolated level between two entries reads between
//! their alphas (linear) or one of them (nearest), so the largest table alpha over the
//! entries of the brick's range bounds them all. Skipping the samples of an empty brick
//! therefore leaves the result unchanged. The ray caster clips every ray to the box of
//! the occupied bricks ([`Bricks::occupied_box`], its margins) and, with a scene's
//! `brick`, skips the empty bricks inside it too.

use rayon::prelude::*;

use super::prepare::Prepared;
use super::{coefficients, Combine, Opacity3dScene};

/// Level ranges per brick.
#[derive(Debug, Clone, PartialEq)]
pub struct Bricks {
    /// Voxels per brick side.
    pub size: usize,
    /// Bricks along i, j, k.
    pub counts: [usize; 3],
    /// Per brick (i fastest), per attribute: lowest and highest level a sample can read.
    pub ranges: Vec<[(u8, u8); 3]>,
}

impl Bricks {
    /// The bricks of `prepared` (size 0 is taken as 1).
    pub fn new(prepared: &Prepared, size: usize) -> Bricks {
        let size = size.max(1);
        let d = prepared.dims;
        let counts = d.map(|n| n.div_ceil(size));
        // Per axis, the voxel span each brick reads: [b size - 1, (b + 1) size], clamped.
        let span = |b: usize, n: usize| {
            let lo = (b * size).saturating_sub(1);
            let hi = ((b + 1) * size).min(n - 1);
            lo..=hi
        };
        // Slabs of bricks in parallel (a large volume is a pass over every voxel).
        let ranges = (0..counts[2])
            .into_par_iter()
            .flat_map_iter(|bk| {
                let mut slab = Vec::with_capacity(counts[0] * counts[1]);
                for bj in 0..counts[1] {
                    for bi in 0..counts[0] {
                        let mut r = [(u8::MAX, u8::MIN); 3];
                        for k in span(bk, d[2]) {
                            for j in span(bj, d[1]) {
                                let row = d[0] * (j + d[1] * k);
                                for i in span(bi, d[0]) {
                                    for (a, range) in r.iter_mut().enumerate() {
                                        let v = prepared.byte(row + i, a);
                                        range.0 = range.0.min(v);
                                        range.1 = range.1.max(v);
                                    }
                                }
                            }
                        }
                        slab.push(r);
                    }
                }
                slab
            })
            .collect();
        Bricks {
            size,
            counts,
            ranges,
        }
    }

    /// One byte per brick (i fastest): 255 where a sample can have alpha above 0, else 0.
    pub fn occupancy(&self, prepared: &Prepared, params: &Opacity3dScene) -> Vec<u8> {
        let coeff = coefficients(params);
        // Largest alpha entry of each table over [lo, hi], through a prefix of maxima per
        // start would cost more than it saves: ranges are short, tables 256 entries.
        let most = |a: usize, (lo, hi): (u8, u8)| -> f64 {
            match &prepared.tables[a] {
                Some(t) => {
                    let top = t.entries[lo as usize..=hi as usize]
                        .iter()
                        .map(|e| e[3])
                        .max()
                        .unwrap_or(0);
                    coeff[a][3] * top as f64
                }
                None => match params.combine {
                    Combine::Sum => 0.0,
                    Combine::Product => 1.0,
                },
            }
        };
        self.ranges
            .iter()
            .map(|r| {
                let alphas = [0, 1, 2].map(|a| most(a, r[a]));
                let visible = match params.combine {
                    Combine::Sum => alphas.iter().any(|&x| x > 0.0),
                    Combine::Product => alphas.iter().all(|&x| x > 0.0),
                };
                if visible {
                    255
                } else {
                    0
                }
            })
            .collect()
    }

    /// The box, in texture coordinates, of the bricks `occupancy` marks: a brick covers
    /// the sample points `[b, b + 1) size / n` along each axis (a sample there reads
    /// only the voxels its range was taken over), so every sample outside the box lies
    /// in an empty brick and has alpha 0. `None` when no brick is occupied.
    pub fn occupied_box(&self, prepared: &Prepared, occupancy: &[u8]) -> Option<[[f64; 3]; 2]> {
        let [ni, nj, _] = self.counts;
        let mut lo = [usize::MAX; 3];
        let mut hi = [0usize; 3];
        for (b, _) in occupancy.iter().enumerate().filter(|(_, &o)| o != 0) {
            let at = [b % ni, (b / ni) % nj, b / (ni * nj)];
            for a in 0..3 {
                lo[a] = lo[a].min(at[a]);
                hi[a] = hi[a].max(at[a]);
            }
        }
        if lo[0] == usize::MAX {
            return None;
        }
        let d = prepared.dims;
        Some([
            std::array::from_fn(|a| (lo[a] * self.size) as f64 / d[a] as f64),
            std::array::from_fn(|a| (((hi[a] + 1) * self.size) as f64 / d[a] as f64).min(1.0)),
        ])
    }

    /// Bricks per unit of texture coordinate along each axis (voxels / brick size).
    pub fn per_unit(&self, prepared: &Prepared) -> [f64; 3] {
        prepared.dims.map(|n| n as f64 / self.size as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_core::colortable::ColorTable;
    use glam::DVec3;

    fn prepared(dims: [usize; 3], levels: Vec<u8>) -> Prepared {
        let n = levels.len();
        let mut table = ColorTable::builtin("grey").unwrap();
        for (k, e) in table.entries.iter_mut().enumerate() {
            e[3] = if (100..=120).contains(&k) { 50 } else { 0 };
        }
        Prepared {
            dims,
            half: DVec3::ONE,
            size: DVec3::ONE,
            map: None,
            packed: super::super::prepare::pack([Some(&levels), None, None], n),
            tables: [Some(table), None, None],
            ranges: [Some((0.0, 255.0)), None, None],
            no_data: [arbvis_data::volume::quantize::NoData::Absent; 3],
        }
    }

    #[test]
    fn ranges_include_one_voxel_around_each_brick() {
        // 10 voxels along i, bricks of 4: [0..4], [3..8], [7..9] read.
        let levels: Vec<u8> = (0..10).map(|i| i * 10).collect();
        let b = Bricks::new(&prepared([10, 1, 1], levels), 4);
        assert_eq!(b.counts, [3, 1, 1]);
        let primary: Vec<(u8, u8)> = b.ranges.iter().map(|r| r[0]).collect();
        assert_eq!(primary, [(0, 40), (30, 80), (70, 90)]);
        // Absent attributes read level 0.
        assert!(b.ranges.iter().all(|r| r[1] == (0, 0) && r[2] == (0, 0)));
    }

    #[test]
    fn occupancy_against_the_table_alpha() {
        // Alpha is above 0 only for levels 100..=120.
        let mut levels = vec![0u8; 16];
        levels[5] = 110; // inside brick 1 (voxels 4..8); brick 0 reads up to voxel 4 only
        levels[15] = 121; // just past the visible entries
        let p = prepared([16, 1, 1], levels);
        let scene = crate::scene::Scene::demo("v3o2-sum").unwrap();
        let crate::scene::TechniqueScene::Opacity3d(mut params) = scene.technique else {
            unreachable!()
        };
        params.secondary = None;
        params.tertiary = None;
        let b = Bricks::new(&p, 4);
        // Brick 0 reads voxels 0..=4 (level 0 to 0), brick 1 reads 3..=8 (0..110),
        // brick 2 reads 7..=12 (0), brick 3 reads 11..=15 (0..121): 121 has alpha 0 but
        // the range 0..121 holds entries 100..=120.
        assert_eq!(b.occupancy(&p, &params), [0, 255, 0, 255]);
        params.primary.coefficients[3] = 0.0;
        assert_eq!(b.occupancy(&p, &params), [0, 0, 0, 0]);
        // A product with an absent attribute: the neutral factor keeps it visible.
        params.primary.coefficients[3] = 1.0;
        params.combine = Combine::Product;
        assert_eq!(b.occupancy(&p, &params), [0, 255, 0, 255]);
    }

    #[test]
    fn the_occupied_box_holds_every_occupied_brick_and_no_more() {
        // 10 x 7 x 5 voxels in bricks of 4: 3 x 2 x 2 bricks, the last ones partial.
        let p = prepared([10, 7, 5], vec![0; 350]);
        let b = Bricks::new(&p, 4);
        assert_eq!(b.counts, [3, 2, 2]);
        let mut occupancy = vec![0u8; 12];
        assert_eq!(b.occupied_box(&p, &occupancy), None);
        // Brick (1, 0, 1) alone: voxels 4..8 of 10, 0..4 of 7, 4..5 of 5 (clamped).
        occupancy[1 + 3 * 2] = 255;
        assert_eq!(
            b.occupied_box(&p, &occupancy),
            Some([[0.4, 0.0, 0.8], [0.8, 4.0 / 7.0, 1.0]])
        );
        // And brick (2, 1, 0): the box spans both.
        occupancy[2 + 3] = 255;
        assert_eq!(
            b.occupied_box(&p, &occupancy),
            Some([[0.4, 0.0, 0.0], [1.0, 1.0, 1.0]])
        );
    }
}
