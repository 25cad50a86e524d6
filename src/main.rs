//! The `arbvis` command line.
#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};

mod cli;

use arbvis::gl::{Backend, Headless, ProgramChoice, TargetFormat};
use arbvis::scene::{parse_size, Fidelity, Scene};

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
    Info {
        /// Offscreen backend to ask.
        #[arg(long, value_parser = cli::backend(), default_value = "egl")]
        backend: Backend,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Render a scene offscreen to a PNG.
    Render {
        #[command(flatten)]
        scene: SceneArgs,
        /// Output PNG (written atomically; the name must end in .png).
        #[arg(short, long, value_parser = png_path)]
        output: Option<PathBuf>,
        /// Offscreen backend.
        #[arg(long, value_parser = cli::backend(), default_value = "egl")]
        backend: Backend,
        /// Print every GL resource created, with its bytes, and the timings.
        #[arg(long)]
        stats: bool,
        /// Print what was written (and with --stats the resources and timings) as one
        /// JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
        /// Draw each colour table with its value range, and the isovalues or classes as
        /// keys, into the picture (a scene's `legend = true`); off by default, so that
        /// a picture holds the renderer's pixels alone.
        #[arg(long)]
        legend: bool,
        /// Draw the box's axes with ticks in the data's numbers (inline, crossline and
        /// time for a survey; x, y, z for a cloud) into the picture (`axes = true`).
        #[arg(long)]
        axes: bool,
    },
    /// Print what the loaders see in a file: volumes (SEG-Y, NIfTI: dimensions, ranges,
    /// sample type, byte order, statistics), meshes (VTK legacy, .vtu, gmsh: points, cells
    /// by type, bounds, arrays, flat tetrahedra), point clouds (.dat, LAS/LAZ, PLY: count,
    /// bounds, attributes), surfaces (OBJ, STL) and survey stores (format, dimensions with
    /// their coordinates, attributes, levels, completeness, size on disk).
    Inspect {
        /// A volume, mesh, point cloud or surface file, or a survey store (a folder).
        file: PathBuf,
        /// Also read and inspect it this many more times and print the median time (what
        /// loading the file costs).
        #[arg(long, value_name = "RUNS")]
        time: Option<usize>,
        #[command(flatten)]
        segy_keys: SegyKeyArgs,
    },
    /// Time a scene offscreen: clear + draw + finish per frame, the first frame apart,
    /// settings interleaved over rounds. For 3D opacity: sweep faithful / precise slice
    /// counts and ray-caster steps, score against the f64 reference (RGB), and export what
    /// a peer needs (benches/peers/vtk_volume.py).
    Bench {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        options: cli::BenchArgs,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// How to look at the scene: its own camera, or an axis-aligned, rotated or
        /// perspective view.
        #[arg(long, value_parser = cli::view(), default_value = "file")]
        view: arbvis::study::bench::View,
        /// Offscreen backend.
        #[arg(long, value_parser = cli::backend(), default_value = "egl")]
        backend: Backend,
    },
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
    Study {
        #[command(flatten)]
        sweep: SweepArgs,
        /// Peer-script runs (JSON, from `benches/peers/vtk_volume.py ... --json RUN.json`)
        /// to plot and tabulate instead of sweeping.
        #[arg(long, num_args = 1..)]
        from: Vec<PathBuf>,
        /// The technique whose trade to sweep.
        #[arg(long, value_enum, ignore_case = true, default_value_t = StudyTechnique::Opacity3d)]
        technique: StudyTechnique,
        /// Cell projection: grid points per side of the generated meshes (17: the seed's
        /// 24,576 tetrahedra; 56: about a million).
        #[arg(long, value_delimiter = ',', default_values_t = [17, 25, 33, 45, 56])]
        grids: Vec<usize>,
        /// Cell projection: score meshes up to this many grid points per side against the
        /// f64 reference (larger meshes are timed only and print "unscored"; the volume
        /// study scores any mesh of at most as many tetrahedra as such a grid has).
        /// Default: 64 for the isosurfaces, 1,100,000 tetrahedra for the volume (the 56-point grid).
        #[arg(long, value_name = "POINTS")]
        score_up_to: Option<usize>,
        /// Cell projection's volume: cell-projection scenes whose meshes and transfer
        /// functions to add to the grids.
        #[arg(long, value_delimiter = ',')]
        scenes: Vec<PathBuf>,
        /// Splats-lod: point budgets.
        #[arg(long, value_delimiter = ',', default_values_t = [250_000u64, 500_000, 1_000_000, 2_000_000, 4_000_000, 8_000_000])]
        budgets: Vec<u64>,
        /// Clipping: clip grid sides of the texture sweep.
        #[arg(long, value_delimiter = ',', default_values_t = [256, 512])]
        clip_sizes: Vec<usize>,
        /// Clipping: block sides B.
        #[arg(long, value_delimiter = ',', default_values_t = [4, 8, 16, 32])]
        blocks: Vec<usize>,
        /// Splats: cloud sizes of the sort timings.
        #[arg(long, value_delimiter = ',', default_values_t = [570_000, 10_000_000])]
        points: Vec<usize>,
        /// Splats: cloud size and image of the frame times.
        #[arg(long, default_value_t = 570_000)]
        frame_points: usize,
        /// Steps per voxel of the f64 references (opacity3d and clip).
        #[arg(long, default_value_t = 4.0)]
        oversample: f64,
        /// Output folder.
        #[arg(long, default_value = "study")]
        out: PathBuf,
    },
    /// Convert a survey (SEG-Y, NIfTI-1, raw, an MDIO dataset) into a bricked
    /// multi-resolution zarr v3 store, or a point cloud (LAS, LAZ, PLY, or the splatting paper's
    /// .dat text: one point per line, x y z and properties) into a
    /// COPC file (when STORE ends in `.copc.laz`: an octree of LAZ chunks, built out of
    /// core, that `{ copc = ... }` scenes draw). A store is laid out as an MDIO v1
    /// dataset, that `{ store = "STORE" }` scenes stream (src/store/). Streams the input (one column of
    /// traces per worker), computes the derived attributes, builds the levels; run it
    /// again after an interruption to resume. Given an MDIO dataset and no STORE, adds the
    /// levels, ranges and derived attributes to the dataset itself, beside its own arrays.
    Convert {
        /// The survey: SEG-Y, NIfTI-1 (.nii, .nii.gz), raw with --raw-dims, or an MDIO
        /// dataset (a folder); or a point cloud (LAS, LAZ, PLY, the paper's .dat text) for COPC.
        input: PathBuf,
        /// The store's folder (created; an interrupted conversion there is resumed).
        /// Without it, an MDIO dataset given as the input gains the levels in place.
        /// A name ending in `.copc.laz` writes the cloud as COPC (started over if
        /// interrupted).
        store: Option<PathBuf>,
        /// Brick (chunk) side in voxels.
        #[arg(long, default_value_t = 64)]
        brick: usize,
        /// Derived attributes (per-trace Hilbert transform), comma-separated, or "none":
        /// envelope, phase, cosine-phase, frequency. The default, envelope, makes a store
        /// about 1.8 times the survey (amplitude alone: 0.92); each of phase and frequency
        /// adds about 0.45.
        #[arg(long, value_delimiter = ',', default_values_t = ["envelope".to_string()])]
        attributes: Vec<String>,
        /// Chunk compression: lz4 (blosc LZ4 over shuffled bytes, as MDIO's blosc), zstd,
        /// zstd:LEVEL (1-22) or none. On float surveys lz4 makes the smallest store and the
        /// fastest conversion.
        #[arg(long, default_value = "lz4")]
        compression: arbvis::store::compression::Compression,
        /// A raw input's dimensions I,J,K (i fastest), e.g. 512,400,300.
        #[arg(long, value_name = "I,J,K", value_parser = parse_dims)]
        raw_dims: Option<[usize; 3]>,
        /// A raw input's sample type (u8, i8, u16, i16, u32, i32, f32, f64).
        #[arg(long, default_value = "f32")]
        raw_type: String,
        /// A raw input's byte order.
        #[arg(long, default_value = "little")]
        raw_endian: String,
        /// Bytes to skip at the start of a raw input.
        #[arg(long, default_value_t = 0)]
        raw_offset: u64,
        /// COPC: a node whose subtree holds more points is sampled at its level's spacing
        /// (one point per cell of 128³) and the rest pushed down to its children.
        #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u64).range(1..))]
        node_points: u64,
        /// COPC: most points built in memory at once (default: a quarter of the memory
        /// budget, at most 8 Mi points); larger clouds go through spill files beside the
        /// output.
        #[arg(long, value_parser = clap::value_parser!(u64).range(10_000..))]
        memory_points: Option<u64>,
        #[command(flatten)]
        segy_keys: SegyKeyArgs,
    },
    /// Open the desktop viewer (winit + glutin + egui).
    #[cfg(feature = "viewer")]
    View {
        #[command(flatten)]
        scene: SceneArgs,
        /// Folder for screenshots (default: current folder).
        #[arg(long, default_value = ".")]
        screenshot_dir: PathBuf,
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
        script: Option<PathBuf>,
    },
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
    fn scene_args(&self) -> Option<&SceneArgs> {
        match self {
            Command::Render { scene, .. } | Command::Bench { scene, .. } => Some(scene),
            #[cfg(feature = "viewer")]
            Command::View { scene, .. } => Some(scene),
            _ => None,
        }
    }
}

/// Whether a conversion's output names a COPC file (`*.copc.laz`).
fn is_copc_name(path: &Path) -> bool {
    path.to_string_lossy().to_lowercase().ends_with(".copc.laz")
}

/// An output's folder must exist (arbvis creates none): said as the output's fault before
/// any work is done.
fn check_output_folder(output: &Path) -> Result<()> {
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

/// `--dry-run`: the command's scene loaded and the files it reads found, nothing run.
fn dry_run(command: &Command) -> Result<()> {
    let exists = |path: &Path| -> Result<()> {
        if path.exists() {
            Ok(())
        } else {
            bail!("{}: no such file or folder", path.display())
        }
    };
    if let Some(args) = command.scene_args() {
        args.load()?;
    }
    match command {
        Command::Render {
            output: Some(output),
            ..
        } => check_output_folder(output)?,
        Command::Inspect { file, .. } => exists(file)?,
        Command::Convert { input, store, .. } => {
            exists(input)?;
            if store.is_none() && !input.is_dir() {
                bail!("name the store to write (arbvis convert SURVEY STORE); only an MDIO dataset converts in place");
            }
        }
        Command::Study { from, scenes, .. } => {
            for path in from {
                exists(path)?;
            }
            for path in scenes {
                Scene::load(path)?;
            }
        }
        _ => {}
    }
    println!("dry run: the command, its scene and its files check out; nothing was run");
    Ok(())
}

/// What a build without the viewer answers to `arbvis view`.
#[cfg(not(feature = "viewer"))]
const NO_VIEWER: &str = "this arbvis was built without the viewer (cargo's --no-default-features, \
the headless build); build the whole program with `cargo install --path .` (or run \
`cargo run --release -- view ...`)";

/// Write a study's files into `out` (created if missing), atomically, saying so.
fn write_study<const N: usize>(out: &Path, files: [(&str, String); N]) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    for (name, text) in files {
        let path = out.join(name);
        arbvis::png_io::write_atomic(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// A volume study case from a cell-projection scene (its camera, mesh and transfer
/// function).
fn volume_case(
    name: &str,
    scene: &Scene,
) -> Result<arbvis::techniques::cellproj::study::volume::Case> {
    let arbvis::scene::TechniqueScene::Cellproj(c) = &scene.technique else {
        bail!("{name}: not a cell-projection scene");
    };
    let prepared = arbvis::techniques::cellproj::prepare::prepare(c, &scene.base)
        .map_err(anyhow::Error::msg)?;
    let camera = if scene.camera == arbvis::camera::Camera::default() {
        arbvis::techniques::cellproj::study::study_camera(arbvis::camera::Projection::Orthographic)
    } else {
        scene.camera
    };
    Ok(arbvis::techniques::cellproj::study::volume::Case {
        name: name.to_string(),
        scene: (**c).clone(),
        prepared,
        camera,
    })
}

/// Techniques with a trade study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum StudyTechnique {
    /// v3o2's 3D opacity: slice counts, targets, opacity correction, program kinds.
    Opacity3d,
    /// Cell projection: mesh sizes, exit per vertex / per fragment, faithful / precise,
    /// mesh / view order, isovalue-edit latency.
    Cellproj,
    /// Cell projection's volume: faithful (both sorts, table sizes) and precise, still
    /// and turning, ortho and perspective, against the f64 reference, on the `--grids`
    /// meshes and any `--scenes` (e.g. scenes/data/bracket-volume.toml).
    CellprojVolume,
    /// Volume clipping: clip grid sizes, shapes and block sizes (bytes, ratio, build
    /// time), and frame times with no clip, the single texture and INDEX-DATA.
    Clip,
    /// Splats: every sort method at each cloud size, and frame times per sort choice
    /// while the camera turns.
    Splats,
    /// Splats of a COPC cloud (`--scenes SCENE`): each of `--budgets`' pictures against
    /// every point's, and the frame time turning.
    SplatsLod,
}

/// The sizes a bench or study sweeps.
#[derive(Args)]
struct SweepArgs {
    /// Voxels per side of the synthetic volume.
    #[arg(long, default_value_t = 256)]
    volume: usize,
    /// Image side in pixels.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Slice counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [64, 128, 256, 512, 1024])]
    slices: Vec<usize>,
    /// Timed frames per setting (median reported).
    #[arg(long, default_value_t = 3)]
    frames: usize,
    /// Offscreen backend.
    #[arg(long, value_parser = cli::backend(), default_value = "egl")]
    backend: Backend,
}

impl SweepArgs {
    fn options(&self, score: bool, full: bool) -> Result<arbvis::study::StudyOptions> {
        if self.volume == 0 || self.size == 0 || self.slices.contains(&0) {
            bail!("volume, size and slice counts must be positive");
        }
        Ok(arbvis::study::StudyOptions {
            volume: self.volume,
            size: self.size,
            slices: self.slices.clone(),
            frames: self.frames.max(1),
            score,
            full,
            ..Default::default()
        })
    }
}

/// `--oversample`, refused where no reference can use it.
fn checked_oversample(o: f64) -> Result<f64> {
    if o.is_finite() && o > 0.0 && o <= 1024.0 {
        Ok(o)
    } else {
        bail!("--oversample {o}: must be above 0 and at most 1024")
    }
}

/// Where the scene comes from and what overrides it.
#[derive(Args)]
struct SceneArgs {
    /// Scene file (TOML).
    scene: Option<PathBuf>,
    /// A built-in demo instead of a file; `--demo` alone lists them. Demos: quad,
    /// v3o2-sum, v3o2-product, cellproj-planar, cellproj-spherical,
    /// cellproj-spherical-precise, splats-section, splats-section-precise, clip-sphere,
    /// clip-mesh.
    #[arg(long, conflicts_with = "scene", num_args = 0..=1, default_missing_value = "",
          value_name = "NAME", value_parser = demo_name)]
    demo: Option<String>,
    /// Image size, e.g. 512x512.
    #[arg(long, value_parser = parse_size)]
    size: Option<[u32; 2]>,
    /// Program kind: arb, glsl, or auto (ARB where the driver has it).
    #[arg(long, value_parser = cli::programs(), ignore_case = true)]
    programs: Option<ProgramChoice>,
    /// Faithful (original programs, 8-bit) or precise (corrected, float).
    #[arg(long, value_parser = cli::fidelity(), ignore_case = true)]
    fidelity: Option<Fidelity>,
    /// Colour target precision (default from fidelity).
    #[arg(long, value_parser = cli::target(), ignore_case = true)]
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
struct SegyKeyArgs {
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
    fn keys(&self) -> arbvis::volume::segy::KeyBytes {
        arbvis::volume::segy::KeyBytes {
            iline: self.iline,
            xline: self.xline,
        }
    }
}

fn gpu_memory(s: &str) -> Result<String, String> {
    arbvis::budget::parse(s).map(|_| s.to_string())
}

impl SceneArgs {
    /// The scene and a name for where it came from.
    fn load(&self) -> Result<(Scene, String)> {
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
            if let arbvis::scene::TechniqueScene::Opacity3d(p) = &mut scene.technique {
                p.store.get_or_insert_with(Default::default).gpu_memory = g.clone();
            }
        }
        if let Some(points) = self.point_budget {
            match &mut scene.technique {
                arbvis::scene::TechniqueScene::Splats(p) => match &mut p.cloud {
                    arbvis::points::PointSource::Copc(spec) => spec.points = points,
                    _ => bail!("--point-budget: the scene's cloud is not a COPC file"),
                },
                _ => bail!("--point-budget: the scene draws no point cloud"),
            }
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
fn parse_dims(s: &str) -> Result<[usize; 3], String> {
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
    if s.is_empty() || arbvis::scene::DEMOS.iter().any(|d| d.0 == s) {
        Ok(s.to_string())
    } else {
        Err(format!("no demo named {s:?}; demos: {}", demo_list(", ")))
    }
}

/// The demos' names joined by `separator`.
fn demo_list(separator: &str) -> String {
    arbvis::scene::DEMOS
        .iter()
        .map(|d| d.0)
        .collect::<Vec<_>>()
        .join(separator)
}

/// An output path ending in `.png` (arbvis writes PNG only: a `.jpg` name would hold a
/// PNG and mislead every program that trusts the extension).
fn png_path(s: &str) -> Result<PathBuf, String> {
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

fn main() -> ExitCode {
    arbvis::png_io::remove_temporaries_on_signals();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("arbvis: error: {e:#}");
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
        println!("{}", demo_list("\n"));
        return Ok(());
    }
    if cli.dry_run {
        return dry_run(&cli.command);
    }
    match cli.command {
        Command::Info { backend, json } => {
            let headless = Headless::new(backend)?;
            let caps = headless.gpu().caps();
            let filter = headless.gpu().linear_filter_error()?;
            let interpolation = headless.gpu().interpolation_error()?;
            if json {
                let text = arbvis::info::to_json(backend, caps, filter, interpolation);
                println!("{text}");
            } else {
                let text = arbvis::info::format_info(backend, caps, filter, interpolation);
                print!("{text}");
            }
        }
        Command::Render {
            scene,
            output,
            backend,
            stats,
            json,
            legend,
            axes,
        } => {
            let Some(output) = output else {
                bail!("render needs an output file: -o OUT.png");
            };
            check_output_folder(&output)?;
            let (mut scene, origin) = scene.load()?;
            scene.legend |= legend;
            scene.axes |= axes;
            let rendered = arbvis::render::render(&scene, backend).map_err(|e| {
                anyhow::anyhow!(scene.explain_missing(format!("rendering {origin}: {e:#}")))
            })?;
            arbvis::png_io::write_png(
                &output,
                &scene.picture(&rendered.image),
                &rendered.png_text(&scene, &origin),
            )?;
            if json {
                let report = arbvis::render::report_json(&rendered, &scene, &output, stats);
                println!("{report}");
            } else {
                print!(
                    "{}",
                    arbvis::render::report_text(&rendered, &scene, &output, stats)
                );
            }
        }
        Command::Convert {
            input,
            store,
            brick,
            attributes,
            compression,
            raw_dims,
            raw_type,
            raw_endian,
            raw_offset,
            node_points,
            memory_points,
            segy_keys,
        } => {
            if let Some(out) = store.as_ref().filter(|s| is_copc_name(s)) {
                let report = arbvis::points::copc_write::write_copc(
                    &input,
                    out,
                    &arbvis::points::copc_write::CopcWriteOptions {
                        node_points: node_points as usize,
                        memory_points,
                        ..Default::default()
                    },
                )
                .with_context(|| format!("converting {}", input.display()))?;
                println!(
                    "{}: {} points, point format {} ({} bytes a record), {} nodes, levels 0-{}, {}{}",
                    out.display(),
                    report.points,
                    report.format.0,
                    report.format.1,
                    report.nodes,
                    report.depth,
                    arbvis::budget::format_bytes(report.bytes),
                    if report.spilled {
                        format!(
                            " (built through spill files, at most {} points in memory at once)",
                            report.memory_points
                        )
                    } else {
                        String::new()
                    }
                );
                return Ok(());
            }
            let mut derived = Vec::new();
            for name in attributes.iter().filter(|a| a.as_str() != "none") {
                match arbvis::volume::attributes::by_name(name) {
                    Some(arbvis::volume::attributes::Attribute::Amplitude) | None => bail!(
                        "--attributes {name}: derived attributes are envelope, phase, cosine-phase, frequency (or none)"
                    ),
                    Some(a) => derived.push(a),
                }
            }
            let raw = match raw_dims {
                Some(dims) => Some(arbvis::volume::raw::RawSpec {
                    path: input.clone(),
                    dims,
                    sample: serde_json::from_value(serde_json::json!(raw_type)).map_err(|_| {
                        anyhow::anyhow!(
                            "--raw-type {raw_type}: one of u8, i8, u16, i16, u32, i32, f32, f64"
                        )
                    })?,
                    endian: serde_json::from_value(serde_json::json!(raw_endian))
                        .map_err(|_| anyhow::anyhow!("--raw-endian {raw_endian}: little or big"))?,
                    offset: raw_offset,
                    spacing: [1.0; 3],
                }),
                None => None,
            };
            let options = arbvis::store::convert::ConvertOptions {
                brick,
                derived,
                compression,
                raw,
                segy_keys: segy_keys.keys(),
                ..Default::default()
            };
            let store = match store {
                Some(s) => s,
                None if input.is_dir() => input.clone(),
                None => bail!(
                    "name the store to write (arbvis convert SURVEY STORE); only an MDIO dataset converts in place"
                ),
            };
            let report = arbvis::store::convert::convert(&input, &store, &options)
                .with_context(|| format!("converting {}", input.display()))?;
            print!("{}", arbvis::store::convert::describe(&report, &store));
        }
        Command::Bench {
            scene,
            options,
            json,
            view,
            backend,
        } => {
            let options = arbvis::study::bench::BenchOptions::from(options);
            options.check()?;
            let (scene, origin) = scene.load()?;
            let scene = view.apply(&scene);
            let origin = format!("{origin} ({} view)", view.name());
            let headless = Headless::new(backend)?;
            let report = arbvis::study::bench::run(
                &headless,
                &scene,
                &origin,
                &options,
                arbvis::progress::line,
            )
            .map_err(|e| {
                anyhow::anyhow!(scene.explain_missing(format!("benchmarking {origin}: {e:#}")))
            })?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", arbvis::study::bench::to_text(&report));
            }
        }
        Command::Study { from, out, .. } if !from.is_empty() => {
            print!("{}", arbvis::study::peers::study(&from, &out)?);
            println!("wrote {}", out.join("study.md").display());
        }
        Command::Study {
            sweep,
            technique: StudyTechnique::Splats,
            points,
            frame_points,
            out,
            ..
        } => {
            let most = arbvis::points::MAX_POINTS as usize;
            if points
                .iter()
                .chain([&frame_points])
                .any(|&n| n == 0 || n > most)
            {
                bail!("--points and --frame-points must be 1..={most}");
            }
            let options = arbvis::techniques::splats::study::Options {
                points,
                frame_points,
                runs: sweep.frames.max(1),
                ..Default::default()
            };
            let sorts = arbvis::techniques::splats::study::sorts(&options, arbvis::progress::line)?;
            let headless = Headless::new(sweep.backend)?;
            let frames = arbvis::techniques::splats::study::frames(
                &headless,
                &options,
                arbvis::progress::line,
            )?;
            let (s, f) = arbvis::techniques::splats::study::to_csv(&sorts, &frames);
            write_study(&out, [("splats-sorts.csv", s), ("splats-frames.csv", f)])?;
            let png = out.join("splats.png");
            let title = format!(
                "splats: {} points at 1600x900, camera turning",
                options.frame_points
            );
            arbvis::techniques::splats::study::plot(&frames, &png, &title)?;
            println!("wrote {}", png.display());
        }
        Command::Study {
            sweep,
            technique: StudyTechnique::SplatsLod,
            scenes,
            budgets,
            out,
            ..
        } => {
            let [path] = scenes.as_slice() else {
                bail!("--technique splats-lod: name one COPC scene with --scenes SCENE");
            };
            let scene = Scene::load(path)?;
            let headless = Headless::new(sweep.backend)?;
            let rows = arbvis::techniques::splats::study::lod::lod(
                &headless,
                &scene,
                &budgets,
                sweep.frames,
                arbvis::progress::line,
            )?;
            write_study(
                &out,
                [(
                    "splats-lod.csv",
                    arbvis::techniques::splats::study::lod::to_csv(&rows),
                )],
            )?;
            let png = out.join("splats-lod.png");
            let title = format!(
                "splats-lod: {} at {}x{}, budgets {}-{} points",
                path.display(),
                scene.size[0],
                scene.size[1],
                budgets.iter().min().unwrap_or(&0),
                budgets.iter().max().unwrap_or(&0)
            );
            arbvis::techniques::splats::study::lod::plot(&rows, &png, &title)?;
            println!("wrote {}", png.display());
        }
        Command::Study {
            sweep,
            technique: StudyTechnique::Clip,
            clip_sizes,
            blocks,
            oversample,
            out,
            ..
        } => {
            if clip_sizes.iter().any(|&n| !(1..=2048).contains(&n))
                || blocks.iter().any(|&b| !(1..=256).contains(&b))
            {
                bail!("--clip-sizes must be 1..=2048 and --blocks 1..=256");
            }
            // Checked before any work: a block larger than a grid fails only at that grid.
            let smallest = clip_sizes.iter().chain([&sweep.volume]).min().copied();
            if let (Some(b), Some(n)) = (blocks.iter().max(), smallest) {
                if *b > n {
                    bail!(
                        "--blocks {b} is larger than the smallest grid ({n}: --clip-sizes or \
                         --volume); blocks must fit in every grid"
                    );
                }
            }
            let options = arbvis::techniques::clip::study::Options {
                sizes: clip_sizes,
                blocks,
                frame_volume: sweep.volume,
                image: sweep.size,
                frames: sweep.frames.max(1),
                oversample: checked_oversample(oversample)?,
            };
            let headless = Headless::new(sweep.backend)?;
            let max = headless.gpu().caps().max_3d_texture_size.max(1) as usize;
            let study =
                arbvis::techniques::clip::study::textures(&options, max, arbvis::progress::line)?;
            let frames = arbvis::techniques::clip::study::frames(
                &headless,
                &options,
                arbvis::progress::line,
            )?;
            let (textures, times) = arbvis::techniques::clip::study::to_csv(&study, &frames);
            write_study(
                &out,
                [("clip-textures.csv", textures), ("clip-frames.csv", times)],
            )?;
            let png = out.join("clip.png");
            let title = format!(
                "clipping: {0}³ x 3 attributes at {1}x{1}, sphere r = 0.35 N",
                options.frame_volume, options.image
            );
            arbvis::techniques::clip::study::plot(&frames, &png, &title)?;
            println!("wrote {}", png.display());
        }
        Command::Study {
            sweep,
            technique: StudyTechnique::CellprojVolume,
            grids,
            scenes,
            score_up_to,
            out,
            ..
        } => {
            use arbvis::techniques::cellproj::study::volume;
            let headless = Headless::new(sweep.backend)?;
            let mut cases = Vec::new();
            for &n in &grids {
                if !(2..=128).contains(&n) {
                    bail!("--grids: each must be 2..=128 points per side");
                }
                let scene = Scene::parse(
                    &format!(
                        "[technique.cellproj]\nmesh = {{ grid = {{ points = [{n}, {n}, {n}], field = \"spherical\" }} }}\nmode = \"volume\"\n[technique.cellproj.volume]\npoints = [[0.0, 0.1, 0.2, 0.9, 0.0], [0.45, 0.2, 0.6, 0.8, 0.3], [0.5, 1.0, 0.9, 0.2, 1.0], [0.55, 0.9, 0.3, 0.1, 0.3], [1.0, 0.8, 0.1, 0.1, 0.6]]\nunit_distance = 0.25\n"
                    ),
                    "grid",
                )?;
                cases.push(volume_case(&format!("grid{n}"), &scene)?);
            }
            for path in &scenes {
                let scene = Scene::load(path)?;
                let name = path
                    .file_stem()
                    .map_or("scene".into(), |s| s.to_string_lossy().to_string());
                cases.push(volume_case(&name, &scene)?);
            }
            let defaults = volume::Options::default();
            let options = volume::Options {
                frames: sweep.frames.max(1),
                // A grid of n points per side has 6 (n - 1)³ tetrahedra.
                score_up_to: score_up_to
                    .map_or(defaults.score_up_to, |n| 6 * n.saturating_sub(1).pow(3)),
                ..defaults
            };
            let rows = volume::run(&headless, &cases, &options, arbvis::progress::line)?;
            write_study(&out, [("cellproj-volume.csv", volume::to_csv(&rows))])?;
            let plots = volume::plot(&rows, &out)?;
            for png in &plots {
                println!("wrote {}", png.display());
            }
            if plots.is_empty() {
                println!(
                    "no plot: no mesh was scored (each has more than {} tetrahedra)",
                    options.score_up_to
                );
            }
        }
        Command::Study {
            sweep,
            technique: StudyTechnique::Cellproj,
            grids,
            score_up_to,
            out,
            ..
        } => {
            let headless = Headless::new(sweep.backend)?;
            let options = arbvis::techniques::cellproj::study::Options {
                grids,
                frames: sweep.frames.max(1),
                score_up_to: score_up_to
                    .unwrap_or(arbvis::techniques::cellproj::study::Options::default().score_up_to),
                ..Default::default()
            };
            if options.grids.iter().any(|&g| !(2..=128).contains(&g)) {
                bail!("--grids: each must be 2..=128 points per side");
            }
            let rows = arbvis::techniques::cellproj::study::run(
                &headless,
                &options,
                arbvis::progress::line,
            )?;
            let text = arbvis::techniques::cellproj::study::to_csv(&rows);
            write_study(&out, [("cellproj.csv", text)])?;
            if rows.iter().any(|r| r.agreement.is_some()) {
                let png = out.join("cellproj.png");
                let title = format!(
                    "cell projection: the seed's isosurfaces at {}x{}",
                    options.size[0], options.size[1]
                );
                arbvis::techniques::cellproj::study::plot(&rows, &png, &title)?;
                println!("wrote {}", png.display());
            } else {
                println!(
                    "no plot: no mesh was scored (each has more than {} points per side)",
                    options.score_up_to
                );
            }
        }
        Command::Study {
            sweep,
            oversample,
            out,
            ..
        } => {
            let headless = Headless::new(sweep.backend)?;
            let caps = headless.gpu().caps().clone();
            let mut options = sweep.options(true, true)?;
            options.oversample = checked_oversample(oversample)?;
            let rows = arbvis::study::run(&headless, &options, arbvis::progress::line)?;
            std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
            let csv = out.join("opacity3d.csv");
            arbvis::png_io::write_atomic(&csv, arbvis::study::to_csv(&rows).as_bytes())
                .with_context(|| format!("writing {}", csv.display()))?;
            let png = out.join("opacity3d.png");
            let title = format!(
                "v3o2 3D opacity, {0}^3 x 3 attributes at {1}x{1}: {2}",
                options.volume, options.size, caps.renderer
            );
            arbvis::study::plot(&rows, &png, &title)?;
            print!("{}", arbvis::study::summary(&rows));
            println!("wrote {} and {}", csv.display(), png.display());
        }
        Command::Inspect {
            file,
            time,
            segy_keys,
        } => {
            let keys = segy_keys.keys();
            print!("{}", arbvis::inspect::inspect_with(&file, keys)?);
            if let Some(runs) = time.filter(|&r| r > 0) {
                let mut ms: Vec<f64> = (0..runs.min(1000))
                    .map(|_| {
                        let t = std::time::Instant::now();
                        arbvis::inspect::inspect_with(&file, keys)
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
        }
        #[cfg(not(feature = "viewer"))]
        Command::View { .. } => bail!("{NO_VIEWER}"),
        #[cfg(feature = "viewer")]
        Command::View {
            scene,
            screenshot_dir,
            script,
        } => {
            let (scene, origin) = scene.load()?;
            let script = match script {
                Some(p) => Some(arbvis::viewer::script::Script::load(&p)?),
                None => None,
            };
            let explain = scene.clone();
            arbvis::viewer::run(arbvis::viewer::ViewerOptions {
                scene,
                origin,
                screenshot_dir,
                script,
            })
            .map_err(|e| anyhow::anyhow!(explain.explain_missing(format!("{e:#}"))))?;
        }
    }
    Ok(())
}
