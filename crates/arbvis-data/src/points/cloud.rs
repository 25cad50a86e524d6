//! The point cloud: positions rescaled into [-1, 1]³ around an f64 origin, named
//! attributes with their statistics, colours and normals (see the module doc of
//! [`crate::points`] for the decisions).

use rayon::prelude::*;

/// A point cloud: f32 positions around an f64 origin, named attributes, optional colours
/// and normals. Every per-point vector has [`PointCloud::len`] entries.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    /// Centre of the bounding box, in the file's coordinates.
    pub origin: [f64; 3],
    /// Half of the largest extent of the bounding box (1 when it is zero).
    pub scale: f64,
    /// `(p - origin) / scale`, within [-1, 1]³.
    pub positions: Vec<[f32; 3]>,
    /// Smallest and largest coordinates, in the file's coordinates (zeros when empty).
    pub bounds: [[f64; 3]; 2],
    /// The box the cloud is framed by (`origin` and `scale` come from it): a COPC file's
    /// header bounds, the same for every cut; else `bounds`.
    pub frame: [[f64; 3]; 2],
    /// Named attributes, in the order of the file.
    pub attributes: Vec<Attribute>,
    /// Colours, 16 bits per channel.
    pub rgb: Option<Vec<[u16; 3]>>,
    /// Unit-less normals as the file gives them (not normalised).
    pub normals: Option<Vec<[f32; 3]>>,
}

/// One named attribute with its statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct Attribute {
    /// Name (`layer`, `intensity`, `col12`, a PLY property name, ...).
    pub name: String,
    /// One value per point.
    pub values: Values,
    /// Min, max, median and non-finite count, computed on load.
    pub stats: Stats,
}

/// Attribute values.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// Integer ids and counts.
    Int(Vec<i32>),
    /// Real values; may hold NaN.
    Float(Vec<f32>),
}

impl Values {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Values::Int(v) => v.len(),
            Values::Float(v) => v.len(),
        }
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` as f64.
    pub fn get(&self, i: usize) -> Option<f64> {
        match self {
            Values::Int(v) => v.get(i).map(|&x| x as f64),
            Values::Float(v) => v.get(i).map(|&x| x as f64),
        }
    }

    /// "int" or "float".
    pub fn kind(&self) -> &'static str {
        match self {
            Values::Int(_) => "int",
            Values::Float(_) => "float",
        }
    }
}

/// Statistics of an attribute over its finite values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    /// Smallest finite value (NaN when none).
    pub min: f64,
    /// Largest finite value (NaN when none).
    pub max: f64,
    /// Element `n / 2` of the sorted finite values (NaN when none).
    pub median: f64,
    /// Values that are NaN or infinite.
    pub non_finite: usize,
}

impl Stats {
    /// Statistics of integer values.
    pub fn of_ints(values: &[i32]) -> Stats {
        let (Some(&min), Some(&max)) = (values.iter().min(), values.iter().max()) else {
            return Stats::empty(0);
        };
        let mut copy = values.to_vec();
        let mid = copy.len() / 2;
        let (_, &mut median, _) = copy.select_nth_unstable(mid);
        Stats {
            min: min as f64,
            max: max as f64,
            median: median as f64,
            non_finite: 0,
        }
    }

    /// Statistics of real values, leaving out NaN and infinities.
    pub fn of_floats(values: &[f32]) -> Stats {
        let mut finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let non_finite = values.len() - finite.len();
        if finite.is_empty() {
            return Stats::empty(non_finite);
        }
        let (min, max) = finite
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let mid = finite.len() / 2;
        let (_, &mut median, _) = finite.select_nth_unstable_by(mid, f32::total_cmp);
        Stats {
            min: min as f64,
            max: max as f64,
            median: median as f64,
            non_finite,
        }
    }

    fn empty(non_finite: usize) -> Stats {
        Stats {
            min: f64::NAN,
            max: f64::NAN,
            median: f64::NAN,
            non_finite,
        }
    }

    /// True when max equals min or there is no finite value: a colour scale over
    /// `max - min` would divide by zero.
    pub fn zero_range(&self) -> bool {
        self.max.partial_cmp(&self.min) != Some(std::cmp::Ordering::Greater)
    }
}

/// What a loader gathered, before positions are rescaled and statistics computed.
#[derive(Debug, Default)]
pub struct CloudParts {
    /// Coordinates as the file gives them (must all be finite).
    pub positions: Vec<[f64; 3]>,
    /// Named attributes, one value per point each.
    pub attributes: Vec<(String, Values)>,
    /// Colours, 16 bits per channel.
    pub rgb: Option<Vec<[u16; 3]>>,
    /// Normals.
    pub normals: Option<Vec<[f32; 3]>>,
}

/// Why [`CloudParts`] cannot make a cloud.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PartsError {
    /// A column whose length is not the number of points.
    #[error("{what} has {len} values for {points} points")]
    Length {
        /// The column ("attribute NAME", "the colour", "the normal").
        what: String,
        /// Its length.
        len: usize,
        /// The number of points.
        points: usize,
    },
    /// A position with a NaN or infinite coordinate.
    #[error("point {point} has a non-finite coordinate {position:?}")]
    NonFinite {
        /// The point's index.
        point: usize,
        /// Its position.
        position: [f64; 3],
    },
}

impl PointCloud {
    /// Rescale `parts` (origin at the bounding-box centre, scale half the largest
    /// extent) and compute every attribute's statistics. Errors name the first
    /// non-finite position or a column of the wrong length.
    pub fn from_parts(parts: CloudParts) -> Result<PointCloud, PartsError> {
        PointCloud::from_parts_framed(parts, None)
    }

    /// [`PointCloud::from_parts`], framed by `frame` (smallest and largest corner) rather
    /// than the points' own bounds where given: every cut of a COPC file framed by the
    /// file's bounds gives a point the same f32 position.
    pub fn from_parts_framed(
        parts: CloudParts,
        frame: Option<&[[f64; 3]; 2]>,
    ) -> Result<PointCloud, PartsError> {
        let n = parts.positions.len();
        let check = |what: String, len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(PartsError::Length {
                    what,
                    len,
                    points: n,
                })
            }
        };
        for (name, values) in &parts.attributes {
            check(format!("attribute {name}"), values.len())?;
        }
        if let Some(rgb) = &parts.rgb {
            check("the colour".into(), rgb.len())?;
        }
        if let Some(normals) = &parts.normals {
            check("the normal".into(), normals.len())?;
        }
        if let Some(i) = parts
            .positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(PartsError::NonFinite {
                point: i,
                position: parts.positions[i],
            });
        }
        let bounds = bounds(&parts.positions);
        let frame = *frame.unwrap_or(&bounds);
        let (origin, scale) = origin_and_scale(&frame);
        let positions = parts
            .positions
            .par_iter()
            .map(|p| std::array::from_fn(|a| local(p[a], origin[a], scale)))
            .collect();
        let attributes = parts
            .attributes
            .into_par_iter()
            .map(|(name, values)| {
                let stats = match &values {
                    Values::Int(v) => Stats::of_ints(v),
                    Values::Float(v) => Stats::of_floats(v),
                };
                Attribute {
                    name,
                    values,
                    stats,
                }
            })
            .collect();
        Ok(PointCloud {
            origin,
            scale,
            positions,
            bounds,
            frame,
            attributes,
            rgb: parts.rgb,
            normals: parts.normals,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True for a cloud without points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Point `i` in the file's coordinates: `origin + scale * local`.
    pub fn original(&self, i: usize) -> Option<[f64; 3]> {
        let p = self.positions.get(i)?;
        Some(std::array::from_fn(|a| {
            self.origin[a] + self.scale * p[a] as f64
        }))
    }

    /// The attribute called `name`.
    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }

    /// The integer attribute called `name` (e.g. [`LAYER`](super::LAYER), [`FACIES`](super::FACIES), [`FAULT`](super::FAULT)).
    pub fn ints(&self, name: &str) -> Option<&[i32]> {
        match &self.attribute(name)?.values {
            Values::Int(v) => Some(v),
            Values::Float(_) => None,
        }
    }

    /// The real attribute called `name` (e.g. [`POROSITY`](super::POROSITY)).
    pub fn floats(&self, name: &str) -> Option<&[f32]> {
        match &self.attribute(name)?.values {
            Values::Float(v) => Some(v),
            Values::Int(_) => None,
        }
    }

    /// Point count, bounds, origin and scale, colours, normals and every attribute's
    /// statistics, one item per line.
    pub fn describe(&self) -> String {
        // Coordinates with the decimals the f32 positions resolve (scale * 2^-24).
        let decimals = decimals_for(self.scale * 2f64.powi(-24));
        let c = |v: f64| fixed(v, decimals);
        let [lo, hi] = self.bounds;
        let mut s = format!(
            "points: {}\nbounds: x {} .. {}, y {} .. {}, z {} .. {}\norigin: {} {} {}, scale {} (positions stored as f32 in [-1, 1]^3)\n",
            self.len(),
            c(lo[0]),
            c(hi[0]),
            c(lo[1]),
            c(hi[1]),
            c(lo[2]),
            c(hi[2]),
            c(self.origin[0]),
            c(self.origin[1]),
            c(self.origin[2]),
            c(self.scale)
        );
        if let Some(rgb) = &self.rgb {
            let max = rgb.iter().flatten().copied().max().unwrap_or(0);
            s += &format!("colour: RGB, 16 bits per channel (largest value {max})\n");
        }
        if self.normals.is_some() {
            s += "normals: yes\n";
        }
        for a in &self.attributes {
            let st = a.stats;
            // Float attributes are f32: show the f32 values, not their f64 expansions.
            let v = |x: f64| match a.values {
                Values::Int(_) => format!("{x}"),
                Values::Float(_) => format!("{}", x as f32),
            };
            s += &format!(
                "attribute {} ({}): min {} max {} median {}",
                a.name,
                a.values.kind(),
                v(st.min),
                v(st.max),
                v(st.median)
            );
            if st.non_finite > 0 {
                s += &format!(", {} NaN or infinite", st.non_finite);
            }
            if st.zero_range() {
                s += ", zero range";
            }
            s += "\n";
        }
        s
    }
}

/// The centre of `bounds` and half of its largest extent (1 when that is 0), computed
/// from halves so that finite coordinates anywhere in f64's range (±1.7e308) give a
/// finite origin and scale: `0.5 * (lo + hi)` and `hi - lo` would overflow there.
pub(crate) fn origin_and_scale(bounds: &[[f64; 3]; 2]) -> ([f64; 3], f64) {
    let [lo, hi] = bounds;
    let origin = std::array::from_fn(|a| 0.5 * lo[a] + 0.5 * hi[a]);
    let half = (0..3)
        .map(|a| 0.5 * hi[a] - 0.5 * lo[a])
        .fold(0.0, f64::max);
    let scale = if half > 0.0 && half.is_finite() {
        half
    } else {
        1.0
    };
    (origin, scale)
}

/// `(v - origin) / scale` as f32, in halves where `v - origin` overflows (coordinates
/// near ±f64::MAX on both sides of the origin; the scale is then large, so halving it
/// loses nothing).
fn local(v: f64, origin: f64, scale: f64) -> f32 {
    let d = v - origin;
    if d.is_finite() {
        (d / scale) as f32
    } else {
        ((0.5 * v - 0.5 * origin) / (0.5 * scale)) as f32
    }
}

/// Bytes that [`PointCloud::from_parts`] holds at its peak for a cloud of `points`
/// points with `attributes` attributes: the parts (f64 positions, one i32 or f32 per
/// attribute, u16 colours, f32 normals), the f32 positions made from them, and the copy
/// of each attribute that its median is selected in (all made in parallel). Loaders add
/// what they hold besides (their input, decoding buffers) and check the sum against
/// [`arbvis_core::budget`] before reading the points.
pub fn footprint(points: u64, attributes: usize, rgb: bool, normals: bool) -> u64 {
    let per_point =
        24 + 12 + 8 * attributes as u64 + if rgb { 6 } else { 0 } + if normals { 12 } else { 0 };
    arbvis_core::budget::times(points, per_point)
}

/// Decimals that show a step of `step` (0 to 12).
pub(crate) fn decimals_for(step: f64) -> usize {
    if step > 0.0 && step.is_finite() {
        (-step.log10()).ceil().clamp(0.0, 12.0) as usize
    } else {
        6
    }
}

/// `v` with at most `decimals` decimals, trailing zeros dropped.
pub(crate) fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Smallest and largest coordinates of finite points (zeros for none).
fn bounds(points: &[[f64; 3]]) -> [[f64; 3]; 2] {
    if points.is_empty() {
        return [[0.0; 3]; 2];
    }
    points
        .par_iter()
        .fold(
            || [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]],
            |[lo, hi], p| {
                [
                    std::array::from_fn(|a| lo[a].min(p[a])),
                    std::array::from_fn(|a| hi[a].max(p[a])),
                ]
            },
        )
        .reduce(
            || [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]],
            |[l1, h1], [l2, h2]| {
                [
                    std::array::from_fn(|a| l1[a].min(l2[a])),
                    std::array::from_fn(|a| h1[a].max(h2[a])),
                ]
            },
        )
}
