//! The lower crates' choices as command-line values. clap lives only in this crate, so the
//! enums of `arbvis-core` and `arbvis-gl` are offered here by name, with the help clap
//! prints under each flag; the names are the enums' own (`name()`, as scenes write them).

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

use std::path::PathBuf;

use arbvis::gl::{Backend, ProgramChoice, TargetFormat};
use arbvis::study::bench::{BenchOptions, View};
use arbvis::vocab::Fidelity;

/// A parser of one of `choices` (value, help), its name matched without regard to case.
fn choice<T: Copy + Send + Sync + 'static>(
    choices: Vec<(T, &'static str, &'static str)>,
) -> impl TypedValueParser<Value = T> {
    let values: Vec<PossibleValue> = choices
        .iter()
        .map(|&(_, name, help)| PossibleValue::new(name).help(help))
        .collect();
    PossibleValuesParser::new(values).map(move |given: String| {
        choices
            .iter()
            .find(|(_, name, _)| name.eq_ignore_ascii_case(&given))
            .map(|&(value, _, _)| value)
            .expect("clap checked the name against the same list")
    })
}

/// `--backend`.
pub fn backend() -> impl TypedValueParser<Value = Backend> {
    choice(vec![
        (
            Backend::Egl,
            Backend::Egl.name(),
            "EGL through glutin's device platform (default)",
        ),
        (
            Backend::Osmesa,
            Backend::Osmesa.name(),
            "OSMesa, loaded from libOSMesa at run time",
        ),
    ])
}

/// `--programs`.
pub fn programs() -> impl TypedValueParser<Value = ProgramChoice> {
    choice(vec![
        (
            ProgramChoice::Arb,
            "arb",
            "ARB assembly; an error where the driver lacks it",
        ),
        (ProgramChoice::Glsl, "glsl", "GLSL"),
        (
            ProgramChoice::Auto,
            "auto",
            "ARB when both ARB program extensions are present, GLSL otherwise",
        ),
    ])
}

/// `--fidelity`.
pub fn fidelity() -> impl TypedValueParser<Value = Fidelity> {
    choice(vec![
        (
            Fidelity::Faithful,
            Fidelity::Faithful.name(),
            "As the original system did it",
        ),
        (
            Fidelity::Precise,
            Fidelity::Precise.name(),
            "As it should be done",
        ),
    ])
}

/// `--target`.
pub fn target() -> impl TypedValueParser<Value = TargetFormat> {
    choice(vec![
        (
            TargetFormat::Rgba8,
            TargetFormat::Rgba8.name(),
            "8 bits per channel, normalized",
        ),
        (
            TargetFormat::Rgba16f,
            TargetFormat::Rgba16f.name(),
            "16-bit float per channel",
        ),
        (
            TargetFormat::Rgba32f,
            TargetFormat::Rgba32f.name(),
            "32-bit float per channel",
        ),
    ])
}

/// `--view` of `bench`.
pub fn view() -> impl TypedValueParser<Value = View> {
    choice(vec![
        (View::File, View::File.name(), "The scene file's own camera"),
        (
            View::Axis,
            View::Axis.name(),
            "Orthographic, looking down the k axis (identity rotation)",
        ),
        (
            View::Rotated,
            View::Rotated.name(),
            "Orthographic at the `v3o2-sum` demo's rotation, zoom 0.8",
        ),
        (
            View::Perspective,
            View::Perspective.name(),
            "The same rotation in perspective (30 degrees vertical field of view), zoom 0.8",
        ),
    ])
}

/// `arbvis bench`'s options (the doc lines are its help): what to measure.
#[derive(Debug, Clone, clap::Args)]
pub struct BenchArgs {
    /// Timed frames per setting and round (after the first, timed apart).
    #[arg(long, default_value_t = 5)]
    pub frames: usize,
    /// Passes over all settings (interleaved).
    #[arg(long, default_value_t = 1)]
    pub rounds: usize,
    /// Score against the f64 reference (3D opacity; RMSE and largest error over RGB).
    #[arg(long)]
    pub score: bool,
    /// Reference steps per voxel.
    #[arg(long, default_value_t = 16.0)]
    pub oversample: f64,
    /// Faithful slicing at these slice counts, e.g. 128,256.
    #[arg(long, value_delimiter = ',')]
    pub faithful: Vec<usize>,
    /// Precise slicing at these slice counts.
    #[arg(long, value_delimiter = ',')]
    pub precise: Vec<usize>,
    /// The precise ray caster at these steps per voxel, e.g. 0.5,1,2 (the scene's
    /// [technique.opacity3d.raycast] options, else the defaults).
    #[arg(long, value_delimiter = ',')]
    pub raycast: Vec<f64>,
    /// The pre-integrated ray caster (one attribute) at these steps per voxel.
    #[arg(long, value_delimiter = ',')]
    pub raycast_preint: Vec<f64>,
    /// Write the levels, tables, camera (and with --score the reference) for a peer
    /// into this folder; the reference is reused from it when the scene matches.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Also time probe programs on the scene's slices: rasterization and blending, one
    /// 2D fetch (fill rate), the 3D fetch, dependent table fetches, RGBA8 / RGBA32F.
    #[arg(long)]
    pub breakdown: bool,
    /// Cell-projection volume settings, e.g. centroid:64,mpvonc:128,precise,projected,
    /// table:128,grid:64 (faithful with a table of N x N x N/2 texels, the precise walk,
    /// precise as a projection in MPVONC order with the exact integral per fragment or
    /// with a float table of N x N x N/2, or the mesh resampled to a grid of N points
    /// along its longest side and ray cast, grid:N:F at F steps per spacing).
    #[arg(long, value_delimiter = ',')]
    pub cellproj: Vec<String>,
    /// Turn the camera this many degrees about the vertical axis before every frame,
    /// so each frame pays for a moving view (the splats' sort and tile lists).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub turn: f64,
}

impl From<BenchArgs> for BenchOptions {
    fn from(a: BenchArgs) -> BenchOptions {
        BenchOptions {
            frames: a.frames,
            rounds: a.rounds,
            score: a.score,
            oversample: a.oversample,
            faithful: a.faithful,
            precise: a.precise,
            raycast: a.raycast,
            raycast_preint: a.raycast_preint,
            export: a.export,
            breakdown: a.breakdown,
            cellproj: a.cellproj,
            turn: a.turn,
        }
    }
}
