//! `[technique.splats]`: which cloud, how its points are coloured, hidden, sized, shaded,
//! ordered, and whether a property is shown as a volume.

use serde::{Deserialize, Serialize};

use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::points::PointSource;
use arbvis_gl::ProgramChoice;

/// What colours a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourMode {
    /// The facies dictionary (`-999`, undefined, in grey).
    #[default]
    Facies,
    /// One colour per layer id.
    Layer,
    /// The property gradient scale (the seed's `gradient_scale` in the fragment program).
    Property,
    /// The file's RGB (LAS, PLY).
    Rgb,
    /// LAS intensity, as grey.
    Intensity,
    /// LAS classification, one colour per class.
    Classification,
    /// Height (z, the file's units) through the property gradient, over the z range of the
    /// cloud's frame (a COPC file's header bounds: every cut alike; else its points').
    Elevation,
}

/// How a splat's alpha falls off from its centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// `smoothstep` (faithful: of `n_dist` as the seed wrote it; precise: of `1 - n_dist`).
    Smoothstep,
    /// A Gaussian (faithful: the seed's `gauss(n_dist, 1.0, width)`; precise:
    /// `exp(-n_dist^2 / (2 width))`).
    #[default]
    Gaussian,
}

/// How points are put in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SortChoice {
    /// The seed's way: sort the point structs with a comparator computing both distances,
    /// then re-upload the whole buffer.
    Seed,
    /// One key per point, (key, index) pairs sorted; an index buffer uploaded.
    Keys,
    /// Parallel radix sort of (key, index); an index buffer uploaded.
    #[default]
    Radix,
    /// File order (wrong where splats overlap: for comparison).
    None,
    /// Weighted blended order-independent transparency (McGuire & Bavoil 2013): no
    /// order, an approximation of it.
    Oit,
}

/// How the splats reach the pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DrawChoice {
    /// One `GL_POINT` sprite per splat, blended in order (the seed's way).
    #[default]
    Points,
    /// Precise only: per-tile lists built on the CPU in order, composited per pixel by a
    /// GLSL gather program (`splats::tiles`); the same picture, without the per-point
    /// cost of `GL_POINTS` on software drivers.
    Tiles,
}

/// Surface or volume rendering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Splats composing the section's surfaces (lit with normals when asked).
    #[default]
    Surface,
    /// A property as density through a transfer function: points outside
    /// `threshold ± range` get alpha 0, inside `smoothstep(0, 1, normalized value)`.
    Volume,
}

/// The transfer function of volume mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeSpec {
    /// Centre of the shown values, in the property's own units.
    pub threshold: f64,
    /// Half-width of the shown values.
    pub range: f64,
}

impl Default for VolumeSpec {
    /// Porosity's densest band as the seed reports it (0.0-0.012).
    fn default() -> Self {
        VolumeSpec {
            threshold: 0.006,
            range: 0.006,
        }
    }
}

/// `[technique.splats]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplatsScene {
    /// The point cloud.
    pub cloud: PointSource,
    /// Surface or volume.
    #[serde(default)]
    pub mode: Mode,
    /// What colours the points.
    #[serde(default)]
    pub colour: ColourMode,
    /// The property of `colour = "property"` and of volume mode.
    #[serde(default = "porosity")]
    pub property: String,
    /// Faults (fault id >= 0) drawn white.
    #[serde(default)]
    pub faults_white: bool,
    /// Layer ids not drawn.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hide_layers: Vec<i32>,
    /// Eye-dome lighting's strength (precise, GLSL; 0: off; CloudCompare's and Potree's
    /// shading for clouds without normals, about 1).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub edl: f64,
    /// LAS classes (ASPRS codes: 2 ground, 5 high vegetation, 7 noise, ...) not drawn.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hide_classes: Vec<i32>,
    /// Points of undefined facies (-999) not drawn.
    #[serde(default)]
    pub hide_undefined: bool,
    /// The seed's `pointSize`.
    #[serde(default = "default_point_size")]
    pub point_size: f64,
    /// The seed's `factor` (`gl_PointSize = pointSize / distance * factor`).
    #[serde(default = "one")]
    pub factor: f64,
    /// Alpha fall-off.
    #[serde(default)]
    pub kernel: Kernel,
    /// Width of the Gaussian (the seed's `gauss_factor`, a variance).
    #[serde(default = "default_gauss_width")]
    pub gauss_width: f64,
    /// Phong lighting with normals estimated per layer (k nearest neighbours, PCA).
    #[serde(default)]
    pub lighting: bool,
    /// Neighbours per normal.
    #[serde(default = "default_k")]
    pub normals_k: usize,
    /// Ordering.
    #[serde(default)]
    pub sort: SortChoice,
    /// Points or tiles.
    #[serde(default)]
    pub draw: DrawChoice,
    /// Tile side in pixels (`draw = "tiles"`).
    #[serde(default = "default_tile")]
    pub tile: u32,
    /// Every `stride`-th point of the drawing order is drawn as a point (1: all; tiles
    /// draw all). The frame budget draws fewer while the user drags a large cloud.
    #[serde(default = "one_point", skip_serializing_if = "is_one_point")]
    pub stride: usize,
    /// Volume mode's transfer function.
    #[serde(default)]
    pub volume: VolumeSpec,
}

fn porosity() -> String {
    arbvis_data::points::POROSITY.into()
}
fn default_point_size() -> f64 {
    10.0
}
fn one() -> f64 {
    1.0
}
fn one_point() -> usize {
    1
}
fn is_one_point(stride: &usize) -> bool {
    *stride == 1
}
fn default_gauss_width() -> f64 {
    0.2
}
fn default_k() -> usize {
    16
}
fn default_tile() -> u32 {
    DEFAULT_TILE
}

/// Default tile side in pixels: for 1.3-pixel splats at 1600x900 on llvmpipe, the camera
/// turning, tiles of 2 pixels were as fast as tiles of 1 with fewer list entries, and
/// larger tiles slower (measured: docs/benchmarks.md, "Figures behind the splats'
/// settings").
pub const DEFAULT_TILE: u32 = 2;

/// Largest stride: a point of every million.
pub const MAX_STRIDE: usize = 1_000_000;

/// Largest point size asked for (GL clamps to its own range, 255 on llvmpipe).
pub const MAX_POINT_SIZE: f64 = 4096.0;

/// Memory per point of a generated section while it is prepared and drawn: the cloud's
/// attributes, colours, normals, sort keys and the GPU's copies: the growth of peak
/// resident memory per point, lit or not, rounded up (measured: docs/benchmarks.md,
/// "Memory estimates and work limits").
pub const BYTES_PER_POINT: u64 = 450;

/// Memory per tile of `draw = "tiles"`: its list's start on the CPU and in the texture the
/// gather reads, with room to spare; the entries themselves are bounded apart
/// (`tiles::DEFAULT_MAX_ENTRIES`, 16 bytes each).
pub const BYTES_PER_TILE: u64 = 16;

impl SplatsScene {
    /// Defaults for a measured cloud (a reader of kind `Cloud`: LAS, LAZ, COPC, PLY, and
    /// any point format registered later) where the scene's text leaves the key out (`written` tells which dotted keys it writes): the
    /// seed's faithful shaders draw each splat of such a cloud as a ring, so
    /// - no `fidelity`: precise (the Gaussian falls off from the splat's centre);
    /// - no `edl`, `lighting` or `programs`: eye-dome lighting at 1 (GLSL), Potree's and
    ///   CloudCompare's shading for clouds without normals;
    /// - no `colour`: `elevation` (every cloud has it; `rgb`, `intensity` and
    ///   `classification` where the file holds them).
    ///
    /// The seed's `.dat` sections and the generated one keep the seed's defaults.
    pub fn unwritten_defaults(&mut self, written: &dyn Fn(&str) -> bool, fidelity: &mut Fidelity) {
        // Measured clouds' defaults, whatever the format (the seed's own keep its look).
        if self.cloud.data_kind() != arbvis_data::sniff::DataKind::Cloud {
            return;
        }
        let key = |k: &str| written(&format!("technique.splats.{k}"));
        if !written("fidelity") {
            *fidelity = Fidelity::Precise;
        }
        let arb_asked = written("programs");
        if !key("edl") && !key("lighting") && !arb_asked && *fidelity == Fidelity::Precise {
            self.edl = 1.0;
        }
        if !key("colour") {
            self.colour = ColourMode::Elevation;
        }
    }
}

impl SplatsScene {
    /// The large allocations this scene makes that the scene alone determines (a
    /// generated section, the tile lists of an image of `size`); cloud files are held to
    /// the budget by their loaders once their headers are read.
    pub fn memory_estimate(&self, size: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        use arbvis_core::budget::Estimate;
        let mut out = Vec::new();
        if let PointSource::Section(spec) = &self.cloud {
            out.push(Estimate::of(
                format!("the generated section's {} points", spec.points),
                spec.points as u64,
                BYTES_PER_POINT,
            ));
        }
        if self.draw == DrawChoice::Tiles {
            let t = self.tile.max(1) as u64;
            let tiles = (size[0] as u64).div_ceil(t) * (size[1] as u64).div_ceil(t);
            out.push(Estimate::of(
                format!("the lists of {tiles} tiles of {t} pixels"),
                tiles,
                BYTES_PER_TILE,
            ));
        }
        out
    }

    /// `draw = "tiles"` is precise and GLSL only: faithful mode runs the seed's programs
    /// as `GL_POINTS`, and ARB fragment programs have no loops to walk a tile's list.
    pub fn draw_allowed(
        &self,
        fidelity: Fidelity,
        programs: ProgramChoice,
    ) -> Result<(), FieldError> {
        if self.edl > 0.0 && (fidelity == Fidelity::Faithful || programs == ProgramChoice::Arb) {
            return Err(FieldError::new(
                "edl",
                "eye-dome lighting is a precise shading in GLSL: use fidelity = \"precise\" \
                 and programs = \"glsl\" or \"auto\", or edl = 0",
            ));
        }
        if self.draw != DrawChoice::Tiles {
            return Ok(());
        }
        if fidelity == Fidelity::Faithful {
            return Err(FieldError::new(
                "draw",
                "\"tiles\" composites the precise footprints; faithful mode draws the seed's \
                 programs as points: use fidelity = \"precise\" or draw = \"points\"",
            ));
        }
        if programs == ProgramChoice::Arb {
            return Err(FieldError::new(
                "draw",
                "\"tiles\" needs a GLSL program (ARB fragment programs have no loops): use \
                 programs = \"glsl\" or \"auto\", or draw = \"points\"",
            ));
        }
        Ok(())
    }

    /// Check values that parse but cannot render; the error names the key.
    pub fn validate(&self) -> Result<(), FieldError> {
        let positive = |key: &str, v: f64, max: f64| {
            if v.is_finite() && v > 0.0 && v <= max {
                Ok(())
            } else {
                Err(FieldError::new(
                    key,
                    format!("{v}: must be positive and at most {max}"),
                ))
            }
        };
        positive("point_size", self.point_size, MAX_POINT_SIZE)?;
        positive("factor", self.factor, 1e6)?;
        if !(self.edl.is_finite() && (0.0..=100.0).contains(&self.edl)) {
            return Err(FieldError::new(
                "edl",
                format!("{}: must be 0 (off) to 100", self.edl),
            ));
        }
        if !(self.gauss_width.is_finite() && self.gauss_width >= 0.0) {
            return Err(FieldError::new(
                "gauss_width",
                format!("{}: must be finite and not negative", self.gauss_width),
            ));
        }
        if !(1..=MAX_STRIDE).contains(&self.stride) {
            return Err(FieldError::new(
                "stride",
                format!("{}: must be 1..={MAX_STRIDE}", self.stride),
            ));
        }
        if !(3..=256).contains(&self.normals_k) {
            return Err(FieldError::new(
                "normals_k",
                format!("{}: must be 3..=256", self.normals_k),
            ));
        }
        if !(1..=256).contains(&self.tile) {
            return Err(FieldError::new(
                "tile",
                format!("{}: must be 1..=256 pixels", self.tile),
            ));
        }
        if self.draw == DrawChoice::Tiles && self.sort == SortChoice::Oit {
            return Err(FieldError::new(
                "draw",
                "\"tiles\" composites in the sort's order; sort = \"oit\" has none",
            ));
        }
        let v = self.volume;
        if !(v.threshold.is_finite() && v.range.is_finite() && v.range >= 0.0) {
            return Err(FieldError::new(
                "volume",
                format!(
                    "threshold {} range {}: finite, range not negative",
                    v.threshold, v.range
                ),
            ));
        }
        Ok(())
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
