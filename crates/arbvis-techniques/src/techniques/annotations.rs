//! What a picture's legends and axes say, as each renderer knows it
//! ([`super::Renderer::annotations`]): each colour table with its value range, the
//! isovalues or classes as keys, and the box's three axes in the data's own numbers. The
//! viewer draws its own; `crate::annotate` draws these into offscreen pictures.

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
    /// The box drawn (half-extents in object units, as the renderer places it) and its
    /// three axes (x, y, z of the object box), where the data has them.
    pub axes: Option<([f64; 3], [Axis; 3])>,
}

/// A table's 256 colours without their alpha.
pub fn colours(entries: &[[u8; 4]]) -> Vec<[u8; 3]> {
    entries.iter().map(|e| [e[0], e[1], e[2]]).collect()
}

/// An RGBA colour of 0..1 components as 8-bit RGB.
pub fn rgb8(c: [f64; 4]) -> [u8; 3] {
    [c[0], c[1], c[2]].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}
