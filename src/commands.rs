//! The commands other than `study`, each a function of its parsed arguments that does
//! the work through the library: `info`, `render`, `inspect`, `bench`, `convert`, `view`.
//! (An argument struct's help is its command's doc line in `main.rs`.)

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

use arbvis::gl::{Backend, Headless};

use crate::cli::{self, parse_dims, png_path, SceneArgs, SegyKeyArgs};

#[derive(Args)]
pub struct InfoArgs {
    /// Offscreen backend to ask.
    #[arg(long, value_parser = cli::backend(), default_value = "egl")]
    pub backend: Backend,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `arbvis info`: the driver's report, text or JSON.
pub fn info(a: InfoArgs) -> Result<()> {
    let headless = Headless::new(a.backend)?;
    let caps = headless.gpu().caps();
    let filter = headless.gpu().linear_filter_error()?;
    let interpolation = headless.gpu().interpolation_error()?;
    if a.json {
        println!(
            "{}",
            arbvis::info::to_json(a.backend, caps, filter, interpolation)
        );
    } else {
        print!(
            "{}",
            arbvis::info::format_info(a.backend, caps, filter, interpolation)
        );
    }
    Ok(())
}

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output PNG (written atomically; the name must end in .png).
    #[arg(short, long, value_parser = png_path)]
    pub output: Option<PathBuf>,
    /// Offscreen backend.
    #[arg(long, value_parser = cli::backend(), default_value = "egl")]
    pub backend: Backend,
    /// Print every GL resource created, with its bytes, and the timings.
    #[arg(long)]
    pub stats: bool,
    /// Print what was written (and with --stats the resources and timings) as one
    /// JSON object on stdout instead of text.
    #[arg(long)]
    pub json: bool,
    /// Draw each colour table with its value range, and the isovalues or classes as
    /// keys, into the picture (a scene's `legend = true`); off by default, so that
    /// a picture holds the renderer's pixels alone.
    #[arg(long)]
    pub legend: bool,
    /// Draw the box's axes with ticks in the data's numbers (inline, crossline and
    /// time for a survey; x, y, z for a cloud) into the picture (`axes = true`).
    #[arg(long)]
    pub axes: bool,
}

/// `arbvis render`: one frame offscreen, written as a PNG, and its report.
pub fn render(a: RenderArgs) -> Result<()> {
    let done = render_scene(a);
    arbvis::fetch::print_stats();
    done
}

fn render_scene(a: RenderArgs) -> Result<()> {
    let Some(output) = a.output else {
        bail!("render needs an output file: -o OUT.png");
    };
    check_output_folder(&output)?;
    let (mut scene, origin) = a.scene.load()?;
    scene.legend |= a.legend;
    scene.axes |= a.axes;
    let rendered = arbvis::render::render(&scene, a.backend).map_err(|e| {
        anyhow::anyhow!(scene.explain_missing(format!("rendering {origin}: {e:#}")))
    })?;
    arbvis::png_io::write_png(
        &output,
        &scene.picture(&rendered.image),
        &rendered.png_text(&scene, &origin),
    )?;
    if a.json {
        let report = arbvis::render::report_json(&rendered, &scene, &output, a.stats);
        println!("{report}");
    } else {
        print!(
            "{}",
            arbvis::render::report_text(&rendered, &scene, &output, a.stats)
        );
    }
    Ok(())
}

/// An output's folder must exist (arbvis creates none): said as the output's fault before
/// any work is done.
pub fn check_output_folder(output: &Path) -> Result<()> {
    let folder = output.parent().filter(|p| !p.as_os_str().is_empty());
    match folder {
        Some(folder) if !folder.is_dir() => bail!(
            "the output {}: its folder {} does not exist (arbvis creates no folders; make it first)",
            output.display(),
            folder.display()
        ),
        _ => Ok(()),
    }
}

#[derive(Args)]
pub struct InspectArgs {
    /// A volume, mesh, point cloud or surface file, or a survey store (a folder).
    pub file: PathBuf,
    /// Also read and inspect it this many more times and print the median time (what
    /// loading the file costs).
    #[arg(long, value_name = "RUNS")]
    pub time: Option<usize>,
    #[command(flatten)]
    pub segy_keys: SegyKeyArgs,
}

/// `arbvis inspect`: what the loaders see in a file, and with `--time` what reading it
/// costs.
pub fn inspect(a: InspectArgs) -> Result<()> {
    let keys = a.segy_keys.keys();
    print!("{}", arbvis::inspect::inspect_with(&a.file, keys)?);
    arbvis::fetch::print_stats();
    if let Some(runs) = a.time.filter(|&r| r > 0) {
        let mut ms: Vec<f64> = (0..runs.min(1000))
            .map(|_| {
                let t = std::time::Instant::now();
                arbvis::inspect::inspect_with(&a.file, keys)
                    .map(|_| t.elapsed().as_secs_f64() * 1e3)
            })
            .collect::<Result<_, _>>()?;
        ms.sort_by(f64::total_cmp);
        println!(
            "read and inspected in {:.2} ms (median of {})",
            ms[ms.len() / 2],
            ms.len()
        );
    }
    Ok(())
}

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub options: cli::BenchOptionArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// How to look at the scene: its own camera, or an axis-aligned, rotated or
    /// perspective view.
    #[arg(long, value_parser = cli::view(), default_value = "file")]
    pub view: arbvis::study::bench::View,
    /// Offscreen backend.
    #[arg(long, value_parser = cli::backend(), default_value = "egl")]
    pub backend: Backend,
}

/// `arbvis bench`: a scene timed (and scored) offscreen.
pub fn bench(a: BenchArgs) -> Result<()> {
    let options = arbvis::study::bench::BenchOptions::from(a.options);
    options.check()?;
    let (scene, origin) = a.scene.load()?;
    let scene = a.view.apply(&scene);
    let origin = format!("{origin} ({} view)", a.view.name());
    let headless = Headless::new(a.backend)?;
    let report =
        arbvis::study::bench::run(&headless, &scene, &origin, &options, arbvis::progress::line)
            .map_err(|e| {
                anyhow::anyhow!(scene.explain_missing(format!("benchmarking {origin}: {e:#}")))
            })?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", arbvis::study::bench::to_text(&report));
    }
    Ok(())
}

#[derive(Args)]
pub struct ConvertArgs {
    /// The survey: SEG-Y, NIfTI-1 (.nii, .nii.gz), raw with --raw-dims, or an MDIO
    /// dataset (a folder); or a point cloud (LAS, LAZ, PLY, the paper's .dat text) for COPC.
    pub input: PathBuf,
    /// The store's folder (created; an interrupted conversion there is resumed).
    /// Without it, an MDIO dataset given as the input gains the levels in place.
    /// A name ending in `.copc.laz` writes the cloud as COPC (started over if
    /// interrupted).
    pub store: Option<PathBuf>,
    /// Brick (chunk) side in voxels.
    #[arg(long, default_value_t = 64)]
    pub brick: usize,
    /// Derived attributes (per-trace Hilbert transform), comma-separated, or "none":
    /// envelope, phase, cosine-phase, frequency. The default, envelope, makes a store
    /// about 1.8 times the survey (amplitude alone: 0.92); each of phase and frequency
    /// adds about 0.45.
    #[arg(long, value_delimiter = ',', default_values_t = ["envelope".to_string()])]
    pub attributes: Vec<String>,
    /// Chunk compression: lz4 (blosc LZ4 over shuffled bytes, as MDIO's blosc), zstd,
    /// zstd:LEVEL (1-22) or none. On float surveys lz4 makes the smallest store and the
    /// fastest conversion.
    #[arg(long, default_value = "lz4")]
    pub compression: arbvis::store::compression::Compression,
    /// A raw input's dimensions I,J,K (i fastest), e.g. 512,400,300.
    #[arg(long, value_name = "I,J,K", value_parser = parse_dims)]
    pub raw_dims: Option<[usize; 3]>,
    /// A raw input's sample type (u8, i8, u16, i16, u32, i32, f32, f64).
    #[arg(long, default_value = "f32")]
    pub raw_type: String,
    /// A raw input's byte order.
    #[arg(long, default_value = "little")]
    pub raw_endian: String,
    /// Bytes to skip at the start of a raw input.
    #[arg(long, default_value_t = 0)]
    pub raw_offset: u64,
    /// COPC: a node whose subtree holds more points is sampled at its level's spacing
    /// (one point per cell of 128³) and the rest pushed down to its children.
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub node_points: u64,
    /// COPC: most points built in memory at once (default: a quarter of the memory
    /// budget, at most 8 Mi points); larger clouds go through spill files beside the
    /// output.
    #[arg(long, value_parser = clap::value_parser!(u64).range(10_000..))]
    pub memory_points: Option<u64>,
    #[command(flatten)]
    pub segy_keys: SegyKeyArgs,
}

/// `arbvis convert`: a survey into a store (or an MDIO dataset in place), or a cloud into
/// a COPC file.
pub fn convert(a: ConvertArgs) -> Result<()> {
    if let Some(out) = a.store.as_ref().filter(|s| is_copc_name(s)) {
        return convert_to_copc(&a, out);
    }
    let mut derived = Vec::new();
    for name in a.attributes.iter().filter(|n| n.as_str() != "none") {
        match arbvis::volume::attributes::by_name(name) {
            Some(arbvis::volume::attributes::Attribute::Amplitude) | None => bail!(
                "--attributes {name}: derived attributes are envelope, phase, cosine-phase, frequency (or none)"
            ),
            Some(attribute) => derived.push(attribute),
        }
    }
    let raw = raw_spec(&a)?;
    let options = arbvis::store::convert::ConvertOptions {
        brick: a.brick,
        derived,
        compression: a.compression,
        raw,
        segy_keys: a.segy_keys.keys(),
        ..Default::default()
    };
    let store = match &a.store {
        Some(s) => s.clone(),
        None if arbvis::fetch::is_folder(&arbvis::fetch::local_or_url(&a.input)) => a.input.clone(),
        None => bail!("{NO_STORE_NAMED}"),
    };
    let input = arbvis::fetch::local_or_url(&a.input);
    if arbvis::fetch::url_of(&store).is_some() {
        bail!("{}: convert writes a store to a local folder (copy it to object storage with the bucket's own tools: aws s3 sync, rclone)", store.display());
    }
    let report = arbvis::store::convert::convert(&input, &store, &options)
        .with_context(|| format!("converting {}", a.input.display()))?;
    print!("{}", arbvis::store::convert::describe(&report, &store));
    arbvis::fetch::print_stats();
    Ok(())
}

/// What `convert` says when an input that is not an MDIO dataset has no store named.
pub const NO_STORE_NAMED: &str =
    "name the store to write (arbvis convert SURVEY STORE); only an MDIO dataset converts in place";

/// Whether a conversion's output names a COPC file (`*.copc.laz`).
fn is_copc_name(path: &Path) -> bool {
    path.to_string_lossy().to_lowercase().ends_with(".copc.laz")
}

/// A raw input's layout from `--raw-dims`, `--raw-type`, `--raw-endian`, `--raw-offset`.
fn raw_spec(a: &ConvertArgs) -> Result<Option<arbvis::volume::raw::RawSpec>> {
    let Some(dims) = a.raw_dims else {
        return Ok(None);
    };
    let raw_type = &a.raw_type;
    let raw_endian = &a.raw_endian;
    Ok(Some(arbvis::volume::raw::RawSpec {
        path: a.input.clone(),
        dims,
        sample: serde_json::from_value(serde_json::json!(raw_type)).map_err(|_| {
            anyhow::anyhow!("--raw-type {raw_type}: one of u8, i8, u16, i16, u32, i32, f32, f64")
        })?,
        endian: serde_json::from_value(serde_json::json!(raw_endian))
            .map_err(|_| anyhow::anyhow!("--raw-endian {raw_endian}: little or big"))?,
        offset: a.raw_offset,
        spacing: [1.0; 3],
    }))
}

/// `convert CLOUD OUT.copc.laz`.
fn convert_to_copc(a: &ConvertArgs, out: &Path) -> Result<()> {
    use arbvis::points::copc_write::{write_copc, CopcWriteOptions};
    let options = CopcWriteOptions {
        node_points: a.node_points as usize,
        memory_points: a.memory_points,
        ..Default::default()
    };
    let report = write_copc(&a.input, out, &options)
        .with_context(|| format!("converting {}", a.input.display()))?;
    let spilled = if report.spilled {
        format!(
            " (built through spill files, at most {} points in memory at once)",
            report.memory_points
        )
    } else {
        String::new()
    };
    println!(
        "{}: {} points, point format {} ({} bytes a record), {} nodes, levels 0-{}, {}{}",
        out.display(),
        report.points,
        report.format.0,
        report.format.1,
        report.nodes,
        report.depth,
        arbvis::budget::format_bytes(report.bytes),
        spilled
    );
    Ok(())
}

#[cfg(feature = "viewer")]
#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Folder for screenshots (default: current folder).
    #[arg(long, default_value = ".")]
    pub screenshot_dir: PathBuf,
    /// Run a script of UI actions, one per line, then exit (an error names the line of a
    /// step that did not take effect).
    ///
    /// Actions (`#` starts a comment; LABEL is a widget's text, e.g. `Save tables`,
    /// `Lock secondary`, `primary Cr`, `primary table`, `primary alpha`, `slices`,
    /// `Interactive quality`, `inline section`; FX FY are fractions of the widget from
    /// its top-left corner, 0..1; DX DY are points):
    ///   wait N                      let N frames pass
    ///   click LABEL                 click the widget
    ///   click-at LABEL FX FY        click at a point of it (adds an alpha-curve point)
    ///   right-click-at LABEL FX FY  secondary click there (removes a curve point)
    ///   double-click-at LABEL FX FY double click there (also removes a curve point)
    ///   drag-on LABEL FX FY DX DY   press there, move by DX DY, release (moves a point)
    ///   drag DX DY                  drag across the 3D view (turns the camera)
    ///   scroll DY                   scroll over the 3D view (zoom)
    ///   set LABEL VALUE             a slider's or number's value, true/false for a check
    ///                               box, an option's name for a choice
    ///   key NAME                    press a key: Home (reset camera), F12 (screenshot)
    ///   print LABEL                 print a labelled text line (e.g. `Clip stats`)
    ///   resize W H                  resize the window to W x H pixels
    ///   idle MS                     draw nothing for MS ms; print the frames drawn
    ///   measure N full|interactive|ui  draw N frames, print the frame rate
    ///   quit                        close the viewer (implied at the end)
    #[arg(long, verbatim_doc_comment)]
    pub script: Option<PathBuf>,
}

/// `arbvis view`: the desktop viewer on the scene, until its window closes or its
/// script ends.
#[cfg(feature = "viewer")]
pub fn view(a: ViewArgs) -> Result<()> {
    let (scene, origin) = a.scene.load()?;
    let script = match a.script {
        Some(p) => Some(arbvis::viewer::script::Script::load(&p)?),
        None => None,
    };
    let explain = scene.clone();
    arbvis::viewer::run(arbvis::viewer::ViewerOptions {
        scene,
        origin,
        screenshot_dir: a.screenshot_dir,
        script,
    })
    .map_err(|e| anyhow::anyhow!(explain.explain_missing(format!("{e:#}"))))
}

/// What a build without the viewer answers to `arbvis view`.
#[cfg(not(feature = "viewer"))]
pub const NO_VIEWER: &str =
    "this arbvis was built without the viewer (cargo's --no-default-features, \
the headless build); build the whole program with `cargo install --path .` (or run \
`cargo run --release -- view ...`)";
