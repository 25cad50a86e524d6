//! What the commands share: the lower crates' choices as command-line values (clap lives
//! only in this crate, so the enums of `arbvis-core` and `arbvis-gl` are offered here by
//! name, with the help clap prints under each flag; the names are the enums' own, `name()`,
//! as scenes write them), the scene a command takes and its overrides ([`SceneArgs`]),
//! the SEG-Y keys, and the parsers of sizes, demos and output names.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::Args;

use arbvis::gl::{Backend, ProgramChoice, TargetFormat};
use arbvis::scene::{parse_size, Scene};
use arbvis::study::bench::{BenchOptions, View};
use arbvis::techniques::opacity3d::Opacity3dScene;
use arbvis::techniques::splats::SplatsScene;
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
#[derive(Debug, Clone, Args)]
pub struct BenchOptionArgs {
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

impl From<BenchOptionArgs> for BenchOptions {
    fn from(a: BenchOptionArgs) -> BenchOptions {
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

/// Where the scene comes from and what overrides it.
#[derive(Args)]
pub struct SceneArgs {
    /// Scene file (TOML).
    scene: Option<PathBuf>,
    // A built-in demo instead of a file (the help names the catalog's demos).
    #[arg(long, conflicts_with = "scene", num_args = 0..=1, default_missing_value = "",
          value_name = "NAME", value_parser = demo_name, help = demo_help())]
    pub demo: Option<String>,
    /// Image size, e.g. 512x512.
    #[arg(long, value_parser = parse_size)]
    size: Option<[u32; 2]>,
    /// Program kind: arb, glsl, or auto (ARB where the driver has it).
    #[arg(long, value_parser = programs(), ignore_case = true)]
    programs: Option<ProgramChoice>,
    /// Faithful (original programs, 8-bit) or precise (corrected, float).
    #[arg(long, value_parser = fidelity(), ignore_case = true)]
    fidelity: Option<Fidelity>,
    /// Colour target precision (default from fidelity).
    #[arg(long, value_parser = target(), ignore_case = true)]
    target: Option<TargetFormat>,
    /// Transparent background: straight colour with alpha = coverage (default: opaque,
    /// what the screen shows).
    #[arg(long)]
    transparent: bool,
    /// Texture memory for a survey store's bricks (e.g. 256M, 2G): the GPU brick cache's
    /// budget (a scene's `[technique.opacity3d.store] gpu_memory`).
    #[arg(long, value_name = "SIZE", value_parser = gpu_memory)]
    gpu_memory: Option<String>,
    /// The most points drawn of a COPC cloud (a scene's `copc = { points = N }`; Potree's
    /// default is 1000000): the nodes largest on screen first.
    #[arg(long, value_name = "POINTS")]
    point_budget: Option<u64>,
}

/// Where a SEG-Y file keeps its inline and crossline numbers.
#[derive(Args)]
pub struct SegyKeyArgs {
    /// SEG-Y: the trace-header byte (1-based) where the inline number starts (a 4-byte
    /// integer; segyio's `iline`). Default: detected (189, as SEG-Y rev 1, or 9 or 17).
    #[arg(long, value_name = "BYTE")]
    iline: Option<u16>,
    /// SEG-Y: the trace-header byte where the crossline number starts (segyio's
    /// `xline`). Default: detected (193, as SEG-Y rev 1, or 21 or 13).
    #[arg(long, value_name = "BYTE")]
    xline: Option<u16>,
}

impl SegyKeyArgs {
    pub fn keys(&self) -> arbvis::volume::segy::KeyBytes {
        arbvis::volume::segy::KeyBytes {
            iline: self.iline,
            xline: self.xline,
        }
    }
}

/// `--gpu-memory`: a size the memory budget's parser reads, kept as written.
fn gpu_memory(s: &str) -> Result<String, arbvis::budget::SizeError> {
    arbvis::budget::parse(s).map(|_| s.to_string())
}

impl SceneArgs {
    /// The scene and a name for where it came from.
    pub fn load(&self) -> Result<(Scene, String)> {
        let (mut scene, origin) = match (&self.scene, &self.demo) {
            (Some(path), _) => (Scene::load_checked(path)?, path.display().to_string()),
            (None, Some(name)) => (Scene::demo(name)?, format!("demo:{name}")),
            (None, None) => bail!("name a scene file or --demo NAME"),
        };
        if let Some(s) = self.size {
            scene.size = s;
        }
        if let Some(p) = self.programs {
            scene.programs = p;
        }
        if let Some(f) = self.fidelity {
            scene.fidelity = f;
        }
        if let Some(t) = self.target {
            scene.target = Some(t);
        }
        if self.transparent {
            scene.transparent = true;
        }
        if let Some(g) = &self.gpu_memory {
            if let Some(p) = scene.technique.get_mut::<Opacity3dScene>() {
                p.store.get_or_insert_with(Default::default).gpu_memory = g.clone();
            }
        }
        if let Some(points) = self.point_budget {
            let Some(p) = scene.technique.get_mut::<SplatsScene>() else {
                bail!("--point-budget: the scene draws no point cloud");
            };
            let arbvis::points::PointSource::Copc(spec) = &mut p.cloud else {
                bail!("--point-budget: the scene's cloud is not a COPC file");
            };
            spec.points = points;
        }
        if let Some(bytes) = scene
            .memory_budget_bytes()
            .map_err(|e| anyhow::anyhow!("{origin}: {e}"))?
        {
            arbvis::budget::set_from_scene(bytes);
        }
        Ok((scene, origin))
    }
}

/// `I,J,K`: three positive sizes.
pub fn parse_dims(s: &str) -> Result<[usize; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let sizes: Vec<usize> = parts
        .iter()
        .map(|p| p.parse::<usize>().ok().filter(|&n| n > 0))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("{s:?}: expected three positive sizes I,J,K, e.g. 512,400,300"))?;
    sizes
        .try_into()
        .map_err(|_| format!("{s:?}: expected three sizes I,J,K, e.g. 512,400,300"))
}

/// A demo's name, or "" (`--demo` alone: list them).
fn demo_name(s: &str) -> Result<String, String> {
    if s.is_empty() || arbvis::scene::demos().any(|d| d.0 == s) {
        Ok(s.to_string())
    } else {
        Err(format!("no demo named {s:?}; demos: {}", demo_list(", ")))
    }
}

/// `--demo`'s help: what it does and every demo the catalog registers.
fn demo_help() -> String {
    format!(
        "A built-in demo instead of a file; `--demo` alone lists them. Demos: {}.",
        demo_list(", ")
    )
}

/// The demos' names joined by `separator`.
pub fn demo_list(separator: &str) -> String {
    arbvis::scene::demos()
        .map(|d| d.0)
        .collect::<Vec<_>>()
        .join(separator)
}

/// An output path ending in `.png` (arbvis writes PNG only: a `.jpg` name would hold a
/// PNG and mislead every program that trusts the extension).
pub fn png_path(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    let png = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        Ok(p)
    } else {
        Err(format!(
            "{s:?}: arbvis writes PNG images only; name the output *.png"
        ))
    }
}
