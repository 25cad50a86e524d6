//! `arbvis study`: each technique's sweep of its speed/accuracy trade, written as CSV and
//! plots into `--out`, or the trade against VTK from a peer's runs (`--from`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

use arbvis::gl::{Backend, Headless};
use arbvis::scene::Scene;
use arbvis::techniques::{cellproj, clip, splats};

use crate::cli;
use arbvis::techniques::cellproj::CellprojScene;

// `arbvis study`'s arguments (the help is the `Study` command's).
#[derive(Args)]
pub struct StudyArgs {
    #[command(flatten)]
    pub sweep: SweepArgs,
    /// Peer-script runs (JSON, from `benches/peers/vtk_volume.py ... --json RUN.json`)
    /// to plot and tabulate instead of sweeping.
    #[arg(long, num_args = 1..)]
    pub from: Vec<PathBuf>,
    // The study to run (help: the registered studies).
    #[arg(long, value_parser = study_name, default_value = "opacity3d", help = study_help())]
    pub technique: String,
    /// Cell projection: grid points per side of the generated meshes (17: the seed's
    /// 24,576 tetrahedra; 56: about a million).
    #[arg(long, value_delimiter = ',', default_values_t = [17, 25, 33, 45, 56])]
    pub grids: Vec<usize>,
    /// Cell projection: score meshes up to this many grid points per side against the
    /// f64 reference (larger meshes are timed only and print "unscored"; the volume
    /// study scores any mesh of at most as many tetrahedra as such a grid has).
    /// Default: 64 for the isosurfaces, 1,100,000 tetrahedra for the volume (the 56-point grid).
    #[arg(long, value_name = "POINTS")]
    pub score_up_to: Option<usize>,
    /// Cell projection's volume: cell-projection scenes whose meshes and transfer
    /// functions to add to the grids.
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<PathBuf>,
    /// Splats-lod: point budgets.
    #[arg(long, value_delimiter = ',', default_values_t = [250_000u64, 500_000, 1_000_000, 2_000_000, 4_000_000, 8_000_000])]
    pub budgets: Vec<u64>,
    /// Clipping: clip grid sides of the texture sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [256, 512])]
    pub clip_sizes: Vec<usize>,
    /// Clipping: block sides B.
    #[arg(long, value_delimiter = ',', default_values_t = [4, 8, 16, 32])]
    pub blocks: Vec<usize>,
    /// Splats: cloud sizes of the sort timings.
    #[arg(long, value_delimiter = ',', default_values_t = [570_000, 10_000_000])]
    pub points: Vec<usize>,
    /// Splats: cloud size and image of the frame times.
    #[arg(long, default_value_t = 570_000)]
    pub frame_points: usize,
    /// Steps per voxel of the f64 references (opacity3d and clip).
    #[arg(long, default_value_t = 4.0)]
    pub oversample: f64,
    /// Output folder.
    #[arg(long, default_value = "study")]
    pub out: PathBuf,
}

/// A study's runner: what `arbvis study --technique NAME` runs.
type Runner = fn(StudyArgs) -> Result<()>;

/// The runner of each study the catalog registers ([`arbvis::catalog::studies`]; a test
/// checks the two name the same studies): the command line holds the studies' arguments.
const RUNNERS: &[(&str, Runner)] = &[
    ("opacity3d", |a| opacity3d_study(&a)),
    ("clip", clip_study),
    ("cellproj", cellproj_study),
    ("cellproj-volume", |a| cellproj_volume_study(&a)),
    ("splats", splats_study),
    ("splats-lod", |a| splats_lod_study(&a)),
];

/// A registered study's name, in any case (`--technique`).
fn study_name(s: &str) -> Result<String, String> {
    let name = s.to_ascii_lowercase();
    if arbvis::catalog::studies().any(|(n, _)| n == name) {
        Ok(name)
    } else {
        let names: Vec<&str> = arbvis::catalog::studies().map(|(n, _)| n).collect();
        Err(format!(
            "no study named {s:?}; studies: {}",
            names.join(", ")
        ))
    }
}

/// `--technique`'s help: every registered study and what it sweeps.
fn study_help() -> String {
    let lines: Vec<String> = arbvis::catalog::studies()
        .map(|(name, about)| format!("- {name}: {about}"))
        .collect();
    format!(
        "The study to run (the techniques register them):\n{}",
        lines.join("\n")
    )
}

/// The sizes a bench or study sweeps.
#[derive(Args)]
pub struct SweepArgs {
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

/// Run the study `a` names.
pub fn study(a: StudyArgs) -> Result<()> {
    if !a.from.is_empty() {
        print!("{}", arbvis::study::peers::study(&a.from, &a.out)?);
        println!("wrote {}", a.out.join("study.md").display());
        return Ok(());
    }
    let runner = RUNNERS
        .iter()
        .find(|(name, _)| *name == a.technique)
        .map(|(_, run)| *run);
    match runner {
        Some(run) => run(a),
        None => bail!("study {:?} is registered but has no runner", a.technique),
    }
}

/// The files [`study`] reads, checked by `--dry-run`.
pub fn check_inputs(a: &StudyArgs) -> Result<()> {
    for path in &a.from {
        if !path.exists() {
            bail!("{}: no such file or folder", path.display());
        }
    }
    for path in &a.scenes {
        Scene::load(path)?;
    }
    Ok(())
}

fn opacity3d_study(a: &StudyArgs) -> Result<()> {
    let headless = Headless::new(a.sweep.backend)?;
    let caps = headless.gpu().caps().clone();
    let mut options = a.sweep.options(true, true)?;
    options.oversample = checked_oversample(a.oversample)?;
    let rows = arbvis::study::run(&headless, &options, arbvis::progress::line)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let csv = a.out.join("opacity3d.csv");
    arbvis::png_io::write_atomic(&csv, arbvis::study::to_csv(&rows).as_bytes())
        .with_context(|| format!("writing {}", csv.display()))?;
    let png = a.out.join("opacity3d.png");
    let title = format!(
        "v3o2 3D opacity, {0}^3 x 3 attributes at {1}x{1}: {2}",
        options.volume, options.size, caps.renderer
    );
    arbvis::study::plot(&rows, &png, &title)?;
    print!("{}", arbvis::study::summary(&rows));
    println!("wrote {} and {}", csv.display(), png.display());
    Ok(())
}

fn cellproj_study(a: StudyArgs) -> Result<()> {
    let headless = Headless::new(a.sweep.backend)?;
    let options = cellproj::study::Options {
        grids: a.grids,
        frames: a.sweep.frames.max(1),
        score_up_to: a
            .score_up_to
            .unwrap_or(cellproj::study::Options::default().score_up_to),
        ..Default::default()
    };
    if options.grids.iter().any(|&g| !(2..=128).contains(&g)) {
        bail!("--grids: each must be 2..=128 points per side");
    }
    let rows = cellproj::study::run(&headless, &options, arbvis::progress::line)?;
    write_study(&a.out, [("cellproj.csv", cellproj::study::to_csv(&rows))])?;
    if rows.iter().any(|r| r.agreement.is_some()) {
        let png = a.out.join("cellproj.png");
        let title = format!(
            "cell projection: the seed's isosurfaces at {}x{}",
            options.size[0], options.size[1]
        );
        cellproj::study::plot(&rows, &png, &title)?;
        println!("wrote {}", png.display());
    } else {
        println!(
            "no plot: no mesh was scored (each has more than {} points per side)",
            options.score_up_to
        );
    }
    Ok(())
}

fn cellproj_volume_study(a: &StudyArgs) -> Result<()> {
    use cellproj::study::volume;
    let headless = Headless::new(a.sweep.backend)?;
    let mut cases = Vec::new();
    for &n in &a.grids {
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
    for path in &a.scenes {
        let scene = Scene::load(path)?;
        let name = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().to_string());
        cases.push(volume_case(&name, &scene)?);
    }
    let defaults = volume::Options::default();
    let options = volume::Options {
        frames: a.sweep.frames.max(1),
        // A grid of n points per side has 6 (n - 1)³ tetrahedra.
        score_up_to: a
            .score_up_to
            .map_or(defaults.score_up_to, |n| 6 * n.saturating_sub(1).pow(3)),
        ..defaults
    };
    let rows = volume::run(&headless, &cases, &options, arbvis::progress::line)?;
    write_study(&a.out, [("cellproj-volume.csv", volume::to_csv(&rows))])?;
    let plots = volume::plot(&rows, &a.out)?;
    for png in &plots {
        println!("wrote {}", png.display());
    }
    if plots.is_empty() {
        println!(
            "no plot: no mesh was scored (each has more than {} tetrahedra)",
            options.score_up_to
        );
    }
    Ok(())
}

/// A volume study case from a cell-projection scene (its camera, mesh and transfer
/// function).
fn volume_case(name: &str, scene: &Scene) -> Result<cellproj::study::volume::Case> {
    let Some(c) = scene.technique.get::<CellprojScene>() else {
        bail!("{name}: not a cell-projection scene");
    };
    let prepared = cellproj::prepare::prepare(c, &scene.base).map_err(anyhow::Error::msg)?;
    let camera = if scene.camera == arbvis::camera::Camera::default() {
        cellproj::study::study_camera(arbvis::camera::Projection::Orthographic)
    } else {
        scene.camera
    };
    Ok(cellproj::study::volume::Case {
        name: name.to_string(),
        scene: c.clone(),
        prepared,
        camera,
    })
}

fn clip_study(a: StudyArgs) -> Result<()> {
    if a.clip_sizes.iter().any(|&n| !(1..=2048).contains(&n))
        || a.blocks.iter().any(|&b| !(1..=256).contains(&b))
    {
        bail!("--clip-sizes must be 1..=2048 and --blocks 1..=256");
    }
    // Checked before any work: a block larger than a grid fails only at that grid.
    let smallest = a.clip_sizes.iter().chain([&a.sweep.volume]).min().copied();
    if let (Some(b), Some(n)) = (a.blocks.iter().max(), smallest) {
        if *b > n {
            bail!(
                "--blocks {b} is larger than the smallest grid ({n}: --clip-sizes or \
                 --volume); blocks must fit in every grid"
            );
        }
    }
    let options = clip::study::Options {
        sizes: a.clip_sizes,
        blocks: a.blocks,
        frame_volume: a.sweep.volume,
        image: a.sweep.size,
        frames: a.sweep.frames.max(1),
        oversample: checked_oversample(a.oversample)?,
    };
    let headless = Headless::new(a.sweep.backend)?;
    let max = headless.gpu().caps().max_3d_texture_size.max(1) as usize;
    let study = clip::study::textures(&options, max, arbvis::progress::line)?;
    let frames = clip::study::frames(&headless, &options, arbvis::progress::line)?;
    let (textures, times) = clip::study::to_csv(&study, &frames);
    write_study(
        &a.out,
        [("clip-textures.csv", textures), ("clip-frames.csv", times)],
    )?;
    let png = a.out.join("clip.png");
    let title = format!(
        "clipping: {0}³ x 3 attributes at {1}x{1}, sphere r = 0.35 N",
        options.frame_volume, options.image
    );
    clip::study::plot(&frames, &png, &title)?;
    println!("wrote {}", png.display());
    Ok(())
}

fn splats_study(a: StudyArgs) -> Result<()> {
    let most = arbvis::points::MAX_POINTS as usize;
    if a.points
        .iter()
        .chain([&a.frame_points])
        .any(|&n| n == 0 || n > most)
    {
        bail!("--points and --frame-points must be 1..={most}");
    }
    let options = splats::study::Options {
        points: a.points,
        frame_points: a.frame_points,
        runs: a.sweep.frames.max(1),
        ..Default::default()
    };
    let sorts = splats::study::sorts(&options, arbvis::progress::line)?;
    let headless = Headless::new(a.sweep.backend)?;
    let frames = splats::study::frames(&headless, &options, arbvis::progress::line)?;
    let (s, f) = splats::study::to_csv(&sorts, &frames);
    write_study(&a.out, [("splats-sorts.csv", s), ("splats-frames.csv", f)])?;
    let png = a.out.join("splats.png");
    let title = format!(
        "splats: {} points at 1600x900, camera turning",
        options.frame_points
    );
    splats::study::plot(&frames, &png, &title)?;
    println!("wrote {}", png.display());
    Ok(())
}

fn splats_lod_study(a: &StudyArgs) -> Result<()> {
    let [path] = a.scenes.as_slice() else {
        bail!("--technique splats-lod: name one COPC scene with --scenes SCENE");
    };
    let scene = Scene::load(path)?;
    let headless = Headless::new(a.sweep.backend)?;
    let rows = splats::study::lod::lod(
        &headless,
        &scene,
        &a.budgets,
        a.sweep.frames,
        arbvis::progress::line,
    )?;
    write_study(
        &a.out,
        [("splats-lod.csv", splats::study::lod::to_csv(&rows))],
    )?;
    let png = a.out.join("splats-lod.png");
    let title = format!(
        "splats-lod: {} at {}x{}, budgets {}-{} points",
        path.display(),
        scene.size[0],
        scene.size[1],
        a.budgets.iter().min().unwrap_or(&0),
        a.budgets.iter().max().unwrap_or(&0)
    );
    splats::study::lod::plot(&rows, &png, &title)?;
    println!("wrote {}", png.display());
    Ok(())
}

/// `--oversample`, refused where no reference can use it.
fn checked_oversample(o: f64) -> Result<f64> {
    if o.is_finite() && o > 0.0 && o <= 1024.0 {
        Ok(o)
    } else {
        bail!("--oversample {o}: must be above 0 and at most 1024")
    }
}

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

#[cfg(test)]
mod tests {
    #[test]
    fn every_registered_study_has_a_runner_and_every_runner_a_registration() {
        let mut registered: Vec<&str> = arbvis::catalog::studies().map(|(n, _)| n).collect();
        let mut run: Vec<&str> = super::RUNNERS.iter().map(|(n, _)| *n).collect();
        registered.sort();
        run.sort();
        assert_eq!(registered, run);
    }
}
