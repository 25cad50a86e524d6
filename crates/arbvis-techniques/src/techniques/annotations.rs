//! What a picture's legends and axes say, as each renderer knows it
//! ([`super::Renderer::annotations`]): each colour table with its value range, the
//! isovalues or classes as keys, and the box's three axes in the data's own numbers. The
//! viewer draws its own; `crate::annotate` draws these into offscreen pictures.

use arbvis_core::camera::Placement;
use arbvis_data::volume::axes::Axis;

/// One legend.
#[derive(Debug, Clone, PartialEq)]
pub enum Legend {
    /// A colour table as a bar from `low` to `high` (the values at its first and last
    /// entry), titled with what it colours and its units.
    Bar {
        /// What it colours (`primary: amplitude`, `Pressure`).
        title: String,
        /// 256 colours, low end first.
        colours: Vec<[u8; 3]>,
        /// The value at the first entry.
        low: f64,
        /// The value at the last entry.
        high: f64,
    },
    /// Named colours (isovalues, classes, facies).
    Keys {
        /// What they are.
        title: String,
        /// Each colour and its name.
        keys: Vec<([u8; 3], String)>,
    },
}

/// A picture's legends and axes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Annotations {
    /// Legends, in the order they are drawn.
    pub legends: Vec<Legend>,
    /// The box drawn and its three axes, where the data has them.
    pub axes: Option<BoxAxes>,
}

/// A box with its three axes in the data's own numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxAxes {
    /// Half-extents in object units, as the renderer places its data.
    pub half: [f64; 3],
    /// The axes along x, y and z of the object box.
    pub axes: [Axis; 3],
    /// Where the object frame sits in the scene's (a layer's placement; identity alone).
    pub placement: Placement,
}

impl BoxAxes {
    /// The box of `half` extents with `axes`, unplaced.
    pub fn new(half: [f64; 3], axes: [Axis; 3]) -> BoxAxes {
        BoxAxes {
            half,
            axes,
            placement: Placement::default(),
        }
    }
}

/// A table's 256 colours without their alpha.
pub fn colours(entries: &[[u8; 4]]) -> Vec<[u8; 3]> {
    entries.iter().map(|e| [e[0], e[1], e[2]]).collect()
}

/// An RGBA colour of 0..1 components as 8-bit RGB.
pub fn rgb8(c: [f64; 4]) -> [u8; 3] {
    [c[0], c[1], c[2]].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}
