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
    /// World units per object unit (uniform).
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

    /// A survey of `size` (sample, crossline, inline extents in its own units) drawn in
    /// an object frame of half-extents `half`: samples downwards from z = 0, inlines
    /// along x, crosslines along y from the origin (see the module doc).
    pub fn of_survey(size: DVec3, half: DVec3) -> World {
        let longest = size.max_element();
        let units = if longest > 0.0 && longest.is_finite() {
            longest / 2.0
        } else {
            1.0
        };
        // Object x (samples) to world -z, y (crosslines) to y, z (inlines) to x: a
        // rotation by 90 degrees about y (determinant 1: windings kept).
        let rotation = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
        World {
            half,
            units,
            rotation,
            centre: DVec3::new(size.z / 2.0, size.y / 2.0, -size.x / 2.0),
        }
    }

    /// The world box `[lo, hi]` of the data (the object box turned, scaled and moved).
    pub fn bounds(&self) -> [DVec3; 2] {
        let m = glam::DMat3::from_quat(self.rotation);
        let reach = DVec3::new(
            m.row(0).abs().dot(self.half),
            m.row(1).abs().dot(self.half),
            m.row(2).abs().dot(self.half),
        ) * self.units;
        [self.centre - reach, self.centre + reach]
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
        // An odd survey: 0.6 of sample extent, 0.9 crosslines, 1.8 inlines.
        let size = DVec3::new(0.6, 0.9, 1.8);
        let half = size / size.max_element();
        let w = World::of_survey(size, half);
        // The first sample of the first inline and crossline: object (-hx, -hy, -hz).
        let first = w.to_world(-half);
        assert!(first.abs_diff_eq(DVec3::ZERO, 1e-12), "{first}");
        // The last sample lies 0.6 below, at the last inline (x) and crossline (y).
        let last = w.to_world(half);
        assert!(
            last.abs_diff_eq(DVec3::new(1.8, 0.9, -0.6), 1e-12),
            "{last}"
        );
        let [lo, hi] = w.bounds();
        assert!(lo.abs_diff_eq(DVec3::new(0.0, 0.0, -0.6), 1e-12));
        assert!(hi.abs_diff_eq(DVec3::new(1.8, 0.9, 0.0), 1e-12));
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
