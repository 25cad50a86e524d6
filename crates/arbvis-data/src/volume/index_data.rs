//! INDEX-DATA atlases (seed 002 §2.1, after Kraus and Ertl's adaptive texture maps): equal
//! cubic slots of `side³` texels packed into one near-cubic 3D DATA texture, and the INDEX
//! entry that sends a normalized coordinate `p` into a slot with one multiply-add,
//! `data_tc = p * S + O`.
//!
//! Two users share it: the clip's multi-resolution texture
//! (`techniques::clip::multires`: one slot per boundary block, one scale `S` for
//! every block) and the store's brick atlas (`techniques::opacity3d::brick_cache`: one slot per resident
//! brick, bricks of several levels, so each INDEX entry carries its level's factor on `S`).
//! No GL here: the numbers only.

use glam::DVec3;

/// Slots of `side³` texels arranged `slots[0] x slots[1] x slots[2]` in one texture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotGrid {
    /// Slots per axis (zeros when there are none).
    pub slots: [usize; 3],
    /// Texels per slot side.
    pub side: usize,
}

/// Slots that no texture of the GL's largest size holds ([`SlotGrid::arrange`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{count} slots of {side}³ texels do not fit a texture of at most {max_size}³ texels (at most {cap} slots per side, {} in all)",
    cap.saturating_pow(3)
)]
pub struct SlotsDoNotFit {
    /// Slots asked for.
    pub count: usize,
    /// Texels per side of a slot.
    pub side: usize,
    /// Texels per side of the largest texture.
    pub max_size: usize,
    /// Slots per side that fit.
    pub cap: usize,
}

impl SlotGrid {
    /// The near-cubic arrangement of `count` slots of side `side` within `max_size`
    /// texels per axis: the largest count of slots per axis as small as possible
    /// (`ceil(cbrt(count))`), then the fewest slots in all. An error says why it does not fit.
    pub fn arrange(count: usize, side: usize, max_size: usize) -> Result<SlotGrid, SlotsDoNotFit> {
        if count == 0 {
            return Ok(SlotGrid {
                slots: [0; 3],
                side,
            });
        }
        let cap = max_size / side.max(1);
        let mut m = (count as f64).cbrt().ceil() as usize;
        while m.saturating_pow(3) < count {
            m += 1;
        }
        while m > 1 && (m - 1).pow(3) >= count {
            m -= 1;
        }
        if m > cap {
            return Err(SlotsDoNotFit {
                count,
                side,
                max_size,
                cap,
            });
        }
        let mut best = [m, m, m];
        for sx in 1..=m {
            for sy in 1..=m {
                let sz = count.div_ceil(sx * sy);
                if sz > m {
                    continue;
                }
                let key = |s: [usize; 3]| (s[0] * s[1] * s[2], s[0].max(s[1]).max(s[2]));
                if key([sx, sy, sz]) < key(best) {
                    best = [sx, sy, sz];
                }
            }
        }
        Ok(SlotGrid { slots: best, side })
    }

    /// Slots in all.
    pub fn capacity(&self) -> usize {
        self.slots.iter().product()
    }

    /// The DATA texture's size in texels.
    pub fn texels(&self) -> [usize; 3] {
        self.slots.map(|s| s * self.side)
    }

    /// Slot `s`'s position in the grid (slots numbered i fastest).
    pub fn slot_index(&self, s: usize) -> [usize; 3] {
        let g = self.slots;
        [
            s % g[0].max(1),
            (s / g[0].max(1)) % g[1].max(1),
            s / (g[0] * g[1]).max(1),
        ]
    }

    /// Slot `s`'s first texel.
    pub fn slot_corner(&self, s: usize) -> [usize; 3] {
        self.slot_index(s).map(|i| i * self.side)
    }

    /// Normalized DATA coordinate of slot `s`'s centre.
    pub fn slot_centre(&self, s: usize) -> DVec3 {
        let idx = self.slot_index(s);
        let d = self.texels();
        DVec3::from_array(
            [0, 1, 2].map(|a| (idx[a] as f64 + 0.5) * self.side as f64 / d[a].max(1) as f64),
        )
    }
}

/// The INDEX entry's offset `O = slot_centre - block_centre * S`: with it, a point `p` of
/// the block reads DATA at `p * S + O` (one MAD), `p` and `block_centre` in the INDEX's
/// normalized coordinates, `S` the scale from those to DATA coordinates.
pub fn offset(slot_centre: DVec3, block_centre: DVec3, scale: DVec3) -> DVec3 {
    slot_centre - block_centre * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrangement_is_near_cubic_and_bounded() {
        let arrange = |count, side| SlotGrid::arrange(count, side, 2048).map(|g| g.slots);
        assert_eq!(arrange(0, 10).unwrap(), [0, 0, 0]);
        assert_eq!(arrange(1, 10).unwrap(), [1, 1, 1]);
        let g = arrange(2600, 10).unwrap();
        assert!(
            g.iter().all(|&s| s <= 14) && g.iter().product::<usize>() >= 2600,
            "{g:?}"
        );
        assert!(g.iter().product::<usize>() < 2600 + 14 * 14, "{g:?}");
        // 204 slots of 10 texels per side fit 2048; 204³ + 1 slots do not.
        assert_eq!(arrange(204usize.pow(3), 10).unwrap(), [204; 3]);
        let e = arrange(204usize.pow(3) + 1, 10).unwrap_err().to_string();
        assert!(e.contains("do not fit") && e.contains("2048"), "{e}");
        assert!(arrange(1, 3000).is_err());
    }

    #[test]
    fn the_mad_lands_on_the_slot_texel_for_texel() {
        // A block of 10 voxels in a 37-voxel axis, its slot of 12 texels (one-texel
        // ring) in a grid of 3 x 2 x 2: voxel centres land on the slot's inner texel
        // centres.
        let g = SlotGrid::arrange(10, 12, 64).unwrap();
        let n = DVec3::splat(37.0);
        let d = DVec3::from_array(g.texels().map(|t| t as f64));
        let scale = n / d;
        for s in [0usize, 4, 9] {
            let block = DVec3::new(1.0, 2.0, 3.0);
            let centre = (block * 10.0 + DVec3::splat(5.0)) / n;
            let o = offset(g.slot_centre(s), centre, scale);
            for v in [0.5, 3.5, 9.5] {
                let p = (block * 10.0 + DVec3::splat(v)) / n;
                let texel = (p * scale + o) * d;
                let corner = DVec3::from_array(g.slot_corner(s).map(|c| c as f64));
                let expected = corner + DVec3::splat(1.0 + v);
                assert!(
                    (texel - expected).abs().max_element() < 1e-9,
                    "{texel} {expected}"
                );
            }
        }
    }
}
