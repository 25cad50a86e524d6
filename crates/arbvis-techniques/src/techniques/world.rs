//! Where a technique's prepared data lie in the world frame, the one frame a scene's
//! layers share: the data's own coordinates, z up, held in f64 (UTM coordinates keep their
//! millimetres). A technique draws in its own object frame (its data centred, the longest
//! side spanning [-1, 1]); [`World`] says how that frame sits in the world, from which a
//! layered scene places each layer in its frame (`arbvis_core::camera::Placement`).
//!
//! A survey's object frame is its grid's: x the sample axis, y the crossline, z the
//! inline. In the world its samples go downwards (time in ms as metres, 1 m per ms: the
//! 2000 m/s two-way already used for its proportions; depth in metres), inlines along x
//! and crosslines along y, its first inline, crossline and sample at the origin (a
//! layer's `offset` moves it where no coordinates say otherwise).

use glam::{DQuat, DVec3};

/// How a technique's object frame sits in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct World {
    /// Half-extents of the data's box in the object frame (centred on its origin).
    pub half: DVec3,
    /// World units per object unit (uniform; negative for a mirrored survey grid).
    pub units: f64,
    /// The object axes turned into the world's.
    pub rotation: DQuat,
    /// The object frame's origin in world coordinates.
    pub centre: DVec3,
}

impl World {
    /// Data whose object frame is its file coordinates `lo`..`hi` centred and scaled so
    /// that the longest side spans [-1, 1] (meshes, clouds, surfaces).
    pub fn of_box(lo: [f64; 3], hi: [f64; 3]) -> World {
        let (lo, hi) = (DVec3::from_array(lo), DVec3::from_array(hi));
        let size = hi - lo;
        let longest = size.max_element();
        let units = if longest > 0.0 && longest.is_finite() {
            longest / 2.0
        } else {
            1.0
        };
        World {
            half: (size / (2.0 * units)).max(DVec3::splat(1e-9)),
            units,
            rotation: DQuat::IDENTITY,
            centre: (lo + hi) / 2.0,
        }
    }

    /// A survey of `dims` voxels and `size` (sample, crossline, inline extents in its
    /// own units) drawn in an object frame of half-extents `half`: each voxel a trace's
    /// sample at its centre, samples downwards from z = 0, the traces where `map` puts
    /// them (their CDP coordinates), else inlines along x and crosslines along y from the
    /// origin (see the module doc). A grid whose inline and crossline directions turn
    /// the other way round is mirrored (a negative `units`).
    pub fn of_survey(
        dims: [usize; 3],
        size: DVec3,
        half: DVec3,
        map: Option<&arbvis_data::volume::segy::geometry::MapFrame>,
    ) -> World {
        let longest = size.max_element();
        let units = if longest > 0.0 && longest.is_finite() {
            longest / 2.0
        } else {
            1.0
        };
        let (origin, crossline, inline) = match map {
            Some(m) => (m.origin, m.crossline, m.inline),
            None => ([0.0; 2], [0.0, 1.0], [1.0, 0.0]),
        };
        let inline = DVec3::new(inline[0], inline[1], 0.0).normalize();
        // The crossline direction made square to the inline one, on the side it lies.
        let square = DVec3::new(-inline.y, inline.x, 0.0);
        let side = square
            .dot(DVec3::new(crossline[0], crossline[1], 0.0))
            .signum();
        let crossline = square * if side == 0.0 { 1.0 } else { side };
        // Object x (samples) downwards, y (crosslines) and z (inlines) on the map.
        let axes = glam::DMat3::from_cols(DVec3::NEG_Z, crossline, inline);
        let (rotation, units) = match axes.determinant() > 0.0 {
            true => (DQuat::from_mat3(&axes), units),
            false => (DQuat::from_mat3(&(-axes)), -units),
        };
        // The box's centre: the middle voxel's centre.
        let n = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let step = size / n.max(DVec3::ONE);
        let middle = (n - 1.0).max(DVec3::ZERO) / 2.0 * step;
        let centre =
            DVec3::new(origin[0], origin[1], 0.0) + crossline * middle.y + inline * middle.z
                - DVec3::Z * middle.x;
        World {
            half,
            units,
            rotation,
            centre,
        }
    }

    /// The world box `[lo, hi]` of the data (the object box turned, scaled and moved).
    pub fn bounds(&self) -> [DVec3; 2] {
        let m = glam::DMat3::from_quat(self.rotation);
        let reach = DVec3::new(
            m.row(0).abs().dot(self.half),
            m.row(1).abs().dot(self.half),
            m.row(2).abs().dot(self.half),
        ) * self.units.abs();
        [self.centre - reach, self.centre + reach]
    }

    /// A point of the world in the object frame.
    pub fn to_object(&self, world: DVec3) -> DVec3 {
        self.rotation.inverse() * ((world - self.centre) / self.units)
    }

    /// A point of the object frame in the world.
    pub fn to_world(&self, object: DVec3) -> DVec3 {
        self.centre + self.rotation * (object * self.units)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_survey_hangs_from_the_origin_with_its_samples_downwards() {
        // An odd survey: 6 samples 0.1 apart, 9 crosslines 0.1 apart, 12 inlines 0.15.
        let dims = [6, 9, 12];
        let size = DVec3::new(0.6, 0.9, 1.8);
        let half = size / size.max_element();
        let w = World::of_survey(dims, size, half, None);
        let step = size / DVec3::new(6.0, 9.0, 12.0);
        // The first voxel's centre (object: half a step in from the corner).
        let first = w.to_world(-half + step / 2.0 / w.units);
        assert!(first.abs_diff_eq(DVec3::ZERO, 1e-12), "{first}");
        // The last sample of the last inline (x) and crossline (y).
        let last = w.to_world(half - step / 2.0 / w.units);
        assert!(
            last.abs_diff_eq(DVec3::new(1.65, 0.8, -0.5), 1e-12),
            "{last}"
        );
    }

    /// A survey on a turned grid, either way round: its corner traces land on their CDP
    /// coordinates, its samples go down.
    #[test]
    fn a_survey_lands_on_its_cdp_coordinates_either_way_round() {
        use arbvis_data::volume::segy::geometry::MapFrame;
        let dims = [11, 7, 5];
        let size = DVec3::new(44.0, 7.0 * 12.5, 5.0 * 25.0);
        let half = size / size.max_element();
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        for turn in [1.0, -1.0] {
            let map = MapFrame {
                origin: [612_345.0, 6_123_456.0],
                crossline: [-s * turn, c * turn],
                inline: [c, s],
            };
            let w = World::of_survey(dims, size, half, Some(&map));
            let step = size / DVec3::new(11.0, 7.0, 5.0);
            assert_eq!(
                w.units < 0.0,
                turn < 0.0,
                "mirrored when turned the other way"
            );
            let at = |i: f64, j: f64, k: f64| {
                w.to_world(-half + (DVec3::new(i, j, k) + 0.5) * step / w.units.abs())
            };
            let want = |j: f64, k: f64, z: f64| {
                DVec3::new(
                    map.origin[0] + j * 12.5 * map.crossline[0] + k * 25.0 * map.inline[0],
                    map.origin[1] + j * 12.5 * map.crossline[1] + k * 25.0 * map.inline[1],
                    z,
                )
            };
            // f64 at 6e6: 1e-8 m.
            for (i, j, k) in [(0.0, 0.0, 0.0), (10.0, 6.0, 4.0), (3.0, 6.0, 0.0)] {
                let got = at(i, j, k);
                let expected = want(j, k, -i * 4.0);
                assert!(got.abs_diff_eq(expected, 1e-7), "{turn}: {got} {expected}");
            }
        }
    }

    #[test]
    fn a_box_keeps_its_file_coordinates() {
        let w = World::of_box([635_000.25, 848_000.5, -3.0], [636_200.25, 848_300.5, 97.0]);
        assert_eq!(w.units, 600.0);
        let corner = w.to_world(DVec3::new(1.0, -0.25, -1.0 / 12.0));
        // f64 at 1e6: a few 1e-10.
        assert!(corner.abs_diff_eq(DVec3::new(636_200.25, 848_000.5, -3.0), 1e-8));
        let [lo, hi] = w.bounds();
        assert!(lo.abs_diff_eq(DVec3::new(635_000.25, 848_000.5, -3.0), 1e-8));
        assert!(hi.abs_diff_eq(DVec3::new(636_200.25, 848_300.5, 97.0), 1e-8));
    }
}
