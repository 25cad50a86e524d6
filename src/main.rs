//! The `arbvis` command line.
#![forbid(unsafe_code)]

use std::path::Path;
use std::process::ExitCode;

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};

mod cli;
mod commands;
mod studies;

use commands::{BenchArgs, ConvertArgs, InfoArgs, InspectArgs, RenderArgs};
use studies::StudyArgs;

#[derive(Parser)]
#[command(
    name = "arbvis",
    version,
    about = "Programmable-shader-era GPU visualization, faithful and precise"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// The memory budget: the most one file, scene or computation may make arbvis
    /// allocate, checked before each large allocation (bytes with K/M/G/T, or a share of
    /// physical memory such as 75%). Default: ARBVIS_MEMORY_BUDGET, else the scene's
    /// memory_budget, else half of the memory the process may use (physical
    /// memory, a cgroup or `ulimit -v`/`-d` limit).
    #[arg(long, global = true, value_name = "SIZE", value_parser = arbvis::budget::parse)]
    memory_budget: Option<u64>,
    /// Check the command without running it: parse its flags, load its scene (every key
    /// checked, errors with line and column) and confirm that the files it reads exist;
    /// nothing is rendered, converted or written.
    #[arg(long, global = true)]
    dry_run: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Print the GL driver, its profile, ARB program support and native limits.
    Info(InfoArgs),
    /// Render a scene offscreen to a PNG.
    Render(RenderArgs),
    /// Print what the loaders see in a file: volumes (SEG-Y, NIfTI: dimensions, ranges,
    /// sample type, byte order, statistics), meshes (VTK legacy, .vtu, gmsh: points, cells
    /// by type, bounds, arrays, flat tetrahedra), point clouds (.dat, LAS/LAZ, PLY: count,
    /// bounds, attributes), surfaces (OBJ, STL) and survey stores (format, dimensions with
    /// their coordinates, attributes, levels, completeness, size on disk).
    Inspect(InspectArgs),
    /// Time a scene offscreen: clear + draw + finish per frame, the first frame apart,
    /// settings interleaved over rounds. For 3D opacity: sweep faithful / precise slice
    /// counts and ray-caster steps, score against the f64 reference (RGB), and export what
    /// a peer needs (benches/peers/vtk_volume.py).
    Bench(BenchArgs),
    /// Measure what a technique trades between speed and accuracy, and plot it.
    ///
    /// Each study prints a line per setting on stderr, with a progress bar and the time
    /// left while stderr is a terminal (never in pipes, or when CI is set), and writes CSV
    /// and plots of error against time (log-log, one line per series) into --out. Times
    /// are for the default sizes, release build, llvmpipe on 2 cores: the opacity3d one
    /// measured, the others estimated from the README's per-frame figures; the bar gives
    /// this machine's estimate as the study runs. Use small sizes for a quick look (e.g.
    /// --volume 32 --size 64 --slices 16,64 --frames 1).
    ///
    /// --technique opacity3d (the default): v3o2's 3D opacity on a synthetic --volume³
    /// cube of 3 attributes at --size²: each --slices count x ARB / GLSL x faithful and
    /// precise (RGBA8 / RGBA16F / RGBA32F targets, opacity correction on and off), the
    /// median of --frames frames, scored as RGB RMSE against the f64 reference
    /// (--oversample steps per voxel). Writes opacity3d.csv and opacity3d.png (RMSE
    /// against ms). About 9 minutes.
    ///
    /// --technique cellproj: isosurfaces by cell projection on generated spherical-field
    /// grids (--grids points per side: 17 is the seed's 24,576 tetrahedra, 56 about a
    /// million) at 320x240: the seed's settings, per-vertex / per-fragment exit, active
    /// tetrahedra only, faithful / precise, mesh / view order; frame time, isovalue-edit
    /// latency, and the fraction of interior pixels with the reference's colour (meshes up
    /// to --score-up-to points per side; larger ones print "unscored"). Writes cellproj.csv
    /// and cellproj.png (wrong-colour fraction against ms). About 3 minutes.
    ///
    /// --technique cellproj-volume: cell projection's volume rendering on the --grids
    /// meshes and any --scenes, orthographic and perspective: faithful (MPVONC at table
    /// sizes 32-256, centroid order at 128) and precise (the walk, projected, the float
    /// table at 128); frame time with the camera still and turning, the sort's and
    /// upload's share, RGB RMSE against the f64 reference (meshes up to --score-up-to;
    /// larger ones print "unscored").
    /// Writes cellproj-volume.csv and cellproj-volume-MESH.png per scored mesh (RMSE
    /// against ms). About 5 minutes (4 min 26 s with the bracket on an idle 2-core
    /// machine).
    ///
    /// --technique clip: volume clipping. Textures: each --clip-sizes grid x shape
    /// (sphere, torus mesh, open half-torus, cow.obj from data/) x --blocks B:
    /// bytes of INDEX-DATA against the single texture and build time (clip-textures.csv).
    /// Frames: the clipped --volume³ cube at --size², no clip / single texture /
    /// INDEX-DATA at each B, with RMSE against the clipped f64 reference and the largest
    /// difference from the single texture (clip-frames.csv, clip.png: RMSE against ms,
    /// the unclipped frame's time as a vertical line). About 3 minutes.
    ///
    /// --technique splats: the generated geological section. Sorts: every back-to-front
    /// method at each --points size, the f64 references' and normals' times up to 2 M
    /// points (splats-sorts.csv). Frames: --frame-points points at 1600x900, the camera
    /// turning 1° a frame, each sort choice, OIT, precise points and tiles of 1-4 px, with
    /// RMSE against the f64 reference in exact order (splats-frames.csv, splats.png: RMSE
    /// against ms). About 2 minutes.
    ///
    /// --technique splats-lod: a COPC scene (--scenes SCENE): for each of --budgets, the
    /// nodes the budget allows for the scene's view, drawn and scored by RGB RMSE against
    /// the picture of every point, and timed with the camera turning 1° a frame
    /// (splats-lod.csv, splats-lod.png: RMSE against ms). About 35 s on a 20 M-point cloud.
    ///
    /// --from RUN.json...: instead of sweeping, the trade against VTK from runs of the
    /// peer script made on this machine (pip install vtk numpy; cargo build --release
    /// --no-default-features; then e.g. `python3 benches/peers/vtk_volume.py
    /// scenes/bench/cube256-amplitude.toml --precise 128,256,512 --raycast 0.5,1,2
    /// --faithful 128,256 --json run.json`): a plot per run (RUN.png), study.csv and the
    /// README-ready study.md. Peer figures are printed only from such runs.
    Study(StudyArgs),
    /// Convert a survey (SEG-Y, NIfTI-1, raw, an MDIO dataset) into a bricked
    /// multi-resolution zarr v3 store, or a point cloud (LAS, LAZ, PLY, or the splatting paper's
    /// .dat text: one point per line, x y z and properties) into a
    /// COPC file (when STORE ends in `.copc.laz`: an octree of LAZ chunks, built out of
    /// core, that `{ copc = ... }` scenes draw). A store is laid out as an MDIO v1
    /// dataset, that `{ store = "STORE" }` scenes stream (docs/stores.md). Streams the input (one column of
    /// traces per worker), computes the derived attributes, builds the levels; run it
    /// again after an interruption to resume. Given an MDIO dataset and no STORE, adds the
    /// levels, ranges and derived attributes to the dataset itself, beside its own arrays.
    Convert(ConvertArgs),
    /// Open the desktop viewer (winit + glutin + egui).
    #[cfg(feature = "viewer")]
    View(commands::ViewArgs),
    /// The desktop viewer is not in this build (headless, --no-default-features).
    #[cfg(not(feature = "viewer"))]
    View {
        /// Whatever was asked of the viewer.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        rest: Vec<String>,
    },
}

impl Command {
    /// The scene arguments of the commands that take a scene.
    fn scene_args(&self) -> Option<&cli::SceneArgs> {
        match self {
            Command::Render(a) => Some(&a.scene),
            Command::Bench(a) => Some(&a.scene),
            #[cfg(feature = "viewer")]
            Command::View(a) => Some(&a.scene),
            _ => None,
        }
    }
}

fn main() -> ExitCode {
    arbvis::png_io::remove_temporaries_on_signals();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A URL's password or signature never reaches the terminal or a log.
            let message = arbvis::secrets::redact(&format!("{e:#}"));
            eprintln!("arbvis: error: {message}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    if let Some(bytes) = cli.memory_budget {
        arbvis::budget::set(bytes);
    } else if let Ok(text) = std::env::var("ARBVIS_MEMORY_BUDGET") {
        // The library ignores a value it cannot read; the command line says so.
        arbvis::budget::parse(&text)
            .map_err(|e| anyhow::anyhow!("ARBVIS_MEMORY_BUDGET={text}: {e}"))?;
    }
    if cli
        .command
        .scene_args()
        .is_some_and(|a| a.demo.as_deref() == Some(""))
    {
        // `--demo` without a name: the list is the answer.
        println!("{}", cli::demo_list("\n"));
        return Ok(());
    }
    if cli.dry_run {
        return dry_run(&cli.command);
    }
    match cli.command {
        Command::Info(a) => commands::info(a),
        Command::Render(a) => commands::render(a),
        Command::Inspect(a) => commands::inspect(a),
        Command::Bench(a) => commands::bench(a),
        Command::Study(a) => studies::study(a),
        Command::Convert(a) => commands::convert(a),
        #[cfg(feature = "viewer")]
        Command::View(a) => commands::view(a),
        #[cfg(not(feature = "viewer"))]
        Command::View { .. } => bail!("{}", commands::NO_VIEWER),
    }
}

/// `--dry-run`: the command's scene loaded and the files it reads found, nothing run.
fn dry_run(command: &Command) -> Result<()> {
    let exists = |path: &Path| -> Result<()> {
        // A URL is checked by its reader (a missing object is a 404 naming it).
        if arbvis::fetch::is_url(&path.to_string_lossy()) || path.exists() {
            Ok(())
        } else {
            bail!("{}: no such file or folder", path.display())
        }
    };
    if let Some(args) = command.scene_args() {
        args.load()?;
    }
    match command {
        Command::Render(RenderArgs {
            output: Some(output),
            ..
        }) => commands::check_output_folder(output)?,
        Command::Inspect(a) => exists(&a.file)?,
        Command::Convert(a) => {
            exists(&a.input)?;
            if a.store.is_none()
                && !arbvis::fetch::is_folder(&arbvis::fetch::local_or_url(&a.input))
            {
                bail!("{}", commands::NO_STORE_NAMED);
            }
        }
        Command::Study(a) => studies::check_inputs(a)?,
        _ => {}
    }
    println!("dry run: the command, its scene and its files check out; nothing was run");
    Ok(())
}
