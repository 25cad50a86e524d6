//! The shared vocabulary at the bottom of the house: words every layer uses and none
//! owns. A scene value that cannot be used ([`FieldError`]), the two fidelity modes
//! ([`Fidelity`]), the precision of a colour target ([`TargetFormat`]) and an item ranked
//! by a priority in a heap ([`Ranked`]). Nothing here imports anything of arbvis: its
//! crate, `arbvis-core`, depends on no other crate of the workspace (ARCHITECTURE.md).

/// Colour-target precision; faithful mode draws into RGBA8 as the original did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TargetFormat {
    /// 8 bits per channel, normalized.
    #[default]
    Rgba8,
    /// 16-bit float per channel.
    Rgba16f,
    /// 32-bit float per channel.
    Rgba32f,
}

impl TargetFormat {
    /// Bytes per pixel.
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            TargetFormat::Rgba8 => 4,
            TargetFormat::Rgba16f => 8,
            TargetFormat::Rgba32f => 16,
        }
    }

    /// Smallest step between two stored values near 1.0, the quantum tolerances derive from.
    pub fn quantum(self) -> f32 {
        match self {
            TargetFormat::Rgba8 => 1.0 / 255.0,
            TargetFormat::Rgba16f => 1.0 / 1024.0, // 10-bit mantissa
            TargetFormat::Rgba32f => f32::EPSILON,
        }
    }

    /// Name as written in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TargetFormat::Rgba8 => "rgba8",
            TargetFormat::Rgba16f => "rgba16f",
            TargetFormat::Rgba32f => "rgba32f",
        }
    }
}

/// Where a precise mode's interpolation happens. GL leaves its precision to the driver:
/// llvmpipe filters textures in f32 and interpolates attributes from the true vertices;
/// NVIDIA's texture units keep 8-bit weights (up to 1e-2 off after a steep table) and its
/// rasterizer interpolates from vertices snapped to 1/256 pixel (up to 1/512 pixel off).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Interpolation {
    /// In the shader where the driver's probe (`arbvis info`) finds the hardware coarse,
    /// else in the hardware.
    #[default]
    Auto,
    /// The texture units and the rasterizer, whatever their precision (fastest).
    Hardware,
    /// The shader: texels fetched and mixed in f32, samples from each pixel's centre.
    Shader,
}

/// Faithful (the original programs, 8-bit targets, original formulas) or precise
/// (corrected maths, float targets). DESIGN.md §3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Fidelity {
    /// As the original system did it.
    #[default]
    Faithful,
    /// As it should be done.
    Precise,
}

impl Fidelity {
    /// The target precision this fidelity uses unless the scene names one.
    pub fn default_target(self) -> TargetFormat {
        match self {
            Fidelity::Faithful => TargetFormat::Rgba8,
            Fidelity::Precise => TargetFormat::Rgba32f,
        }
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Fidelity::Faithful => "faithful",
            Fidelity::Precise => "precise",
        }
    }
}

/// A value that parses but cannot be used: the dotted key that holds it, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldError {
    /// Dotted key relative to where the check ran, e.g. `primary.table.builtin`.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl FieldError {
    /// An error at `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> FieldError {
        FieldError {
            key: key.into(),
            message: message.into(),
        }
    }

    /// The same error seen from the enclosing table `prefix`.
    pub fn within(self, prefix: &str) -> FieldError {
        FieldError {
            key: if self.key.is_empty() {
                prefix.to_string()
            } else {
                format!("{prefix}.{}", self.key)
            },
            message: self.message,
        }
    }
}

impl std::error::Error for FieldError {}

impl std::fmt::Display for FieldError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.key, self.message)
    }
}

/// An item ranked by an `f64` priority: a `BinaryHeap` pops the largest priority first
/// (`total_cmp`, so NaN has a place), ties the smaller item first. What the survey
/// store's bricks and a COPC file's nodes are chosen by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranked<T> {
    /// The priority (screen-space error, projected size).
    pub priority: f64,
    /// What it ranks.
    pub item: T,
}

impl<T: Ord> Eq for Ranked<T> {}

impl<T: Ord> PartialOrd for Ranked<T> {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl<T: Ord> Ord for Ranked<T> {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.priority
            .total_cmp(&other.priority)
            .then(other.item.cmp(&self.item))
    }
}

/// `v` with four significant digits, trailing zeros dropped (`0.3554`, `1.641`, `-17.81`);
/// what warnings, keys and legends print for a value of the data.
pub fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (3 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod ranked_tests {
    use super::Ranked;

    /// Largest priority first, ties by the smaller item, NaN (total order) above every
    /// number.
    #[test]
    fn a_heap_pops_the_largest_priority_and_ties_by_the_smaller_item() {
        let mut heap = std::collections::BinaryHeap::new();
        for (priority, item) in [(1.0, 7), (3.5, 2), (3.5, 1), (-2.0, 0), (f64::NAN, 9)] {
            heap.push(Ranked { priority, item });
        }
        let order: Vec<u32> = std::iter::from_fn(|| heap.pop().map(|r| r.item)).collect();
        assert_eq!(order, [9, 1, 2, 7, 0]);
    }
}
