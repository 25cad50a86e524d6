//! `arbvis bench` and `arbvis study`: the speed-for-accuracy trade of v3o2's 3D opacity,
//! measured. A synthetic seismic block (amplitude, envelope, cosine of phase: three
//! attributes of `volume³`) is drawn at `size²` for each setting that trades speed for
//! accuracy — slice count, target precision, opacity correction, ARB vs GLSL, faithful vs
//! precise — timed over several frames (median), and scored against the f64 reference
//! integral (RGB: max abs, RMSE, PSNR). `study` writes CSV and a plot (error against time,
//! [`plot::plot_lines`], which every technique's study draws with). Peer figures come only
//! from peer runs made on this machine ([`peers`], `study --from`).

pub mod bench;
pub mod breakdown;
pub mod export;
pub mod measured;
pub mod peers;
pub mod plot;

pub use plot::{plot_lines, Chart};

use crate::error::RenderResult;
use std::path::Path;
use std::time::Instant;

use crate::scene::Scene;
use crate::techniques::opacity3d::prepare::{prepare, Prepared};
use crate::techniques::opacity3d::reference::reference;
use crate::techniques::opacity3d::{Opacity3dRenderer, Opacity3dScene};
use crate::techniques::{Frame, Renderer};
use arbvis_core::image::Image;
use arbvis_core::progress::{Bar, Unit};
use arbvis_core::vocab::Fidelity;
use arbvis_core::vocab::TargetFormat;
use arbvis_data::volume::synthetic::SyntheticSpec;
use arbvis_data::volume::VolumeSource;
use arbvis_gl::{Headless, ProgramKind, Surface, Target};

/// What to sweep.
#[derive(Debug, Clone)]
pub struct StudyOptions {
    /// Voxels per side of the synthetic volume.
    pub volume: usize,
    /// Image side in pixels.
    pub size: u32,
    /// Slice counts.
    pub slices: Vec<usize>,
    /// Timed frames per setting (the median is reported), after one warm-up frame.
    pub frames: usize,
    /// Reference steps per reference spacing.
    pub oversample: f64,
    /// Score against the reference (study) or only time (bench).
    pub score: bool,
    /// Sweep every target and correction (study) or a few settings (bench).
    pub full: bool,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions {
            volume: 256,
            size: 512,
            slices: vec![64, 128, 256, 512, 1024],
            frames: 3,
            oversample: 4.0,
            score: true,
            full: true,
        }
    }
}

/// One measured setting.
#[derive(Debug, Clone)]
pub struct Row {
    /// Faithful or precise.
    pub fidelity: Fidelity,
    /// ARB or GLSL.
    pub kind: ProgramKind,
    /// Colour target.
    pub target: TargetFormat,
    /// Opacity correction on.
    pub correction: bool,
    /// Slice count.
    pub slices: usize,
    /// Median time per frame, milliseconds.
    pub ms: f64,
    /// Largest RGB difference from the reference (NaN when not scored).
    pub max_abs: f64,
    /// RMS RGB difference from the reference.
    pub rmse: f64,
    /// PSNR in dB.
    pub psnr: f64,
}

impl Row {
    /// A short name of the setting (without the slice count).
    pub fn series(&self) -> String {
        match self.fidelity {
            Fidelity::Faithful => format!("faithful {}", self.kind.name()),
            Fidelity::Precise => format!(
                "precise {} {}{}",
                self.kind.name(),
                self.target.name(),
                if self.correction {
                    ""
                } else {
                    " no-correction"
                }
            ),
        }
    }
}

/// The study's scene (`scenes/bench/v3o2-sum-study.toml`, the `v3o2-sum` demo as the
/// README's numbers were measured) on a `volume³` cube.
pub fn study_scene(options: &StudyOptions) -> Scene {
    let mut scene = Scene::parse(
        include_str!("../../../../scenes/bench/v3o2-sum-study.toml"),
        "scenes/bench/v3o2-sum-study.toml",
    )
    .expect("the built-in study scene parses");
    scene.size = [options.size, options.size];
    if let Some(o) = scene.technique.get_mut::<Opacity3dScene>() {
        for attr in o.attributes_mut().into_iter().flatten() {
            attr.volume = VolumeSource::Synthetic(SyntheticSpec {
                size: [options.volume; 3],
                ..SyntheticSpec::default()
            });
        }
    }
    scene
}

fn params(scene: &Scene) -> &Opacity3dScene {
    scene
        .technique
        .get::<Opacity3dScene>()
        .expect("study scenes are opacity3d")
}

/// Time one setting: build from `prepared`, one warm-up frame, `frames` timed frames.
fn measure(
    headless: &Headless,
    scene: &Scene,
    prepared: &Prepared,
    kind: ProgramKind,
    frames: usize,
) -> RenderResult<(f64, Image)> {
    let gpu = headless.gpu();
    let [w, h] = scene.size;
    let target = Target::new(gpu, w, h, scene.target_format())?;
    let mut renderer = Opacity3dRenderer::from_prepared(
        gpu,
        kind,
        scene.fidelity,
        params(scene),
        &scene.base,
        prepared.clone(),
        scene.camera.projection,
    )?;
    let frame = Frame {
        camera: scene.camera,
        width: w,
        height: h,
    };
    let mut times = Vec::new();
    for i in 0..=frames.max(1) {
        let t0 = Instant::now();
        target.clear(gpu, scene.background)?;
        renderer.draw(gpu, Surface::Target(&target), &frame)?;
        gpu.finish();
        if i > 0 {
            times.push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    arbvis_gl::gl_check!(gpu)?;
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], target.read(gpu)?))
}

fn without_alpha(image: &Image) -> Image {
    let mut out = image.clone();
    out.data.chunks_exact_mut(4).for_each(|p| p[3] = 0.0);
    out
}

/// Run the sweep; `progress` hears one line per setting.
pub fn run(
    headless: &Headless,
    options: &StudyOptions,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<Row>> {
    let base_scene = study_scene(options);
    let t0 = Instant::now();
    let prepared = prepare(
        params(&base_scene),
        &base_scene.base,
        &arbvis_data::volume::Limits::for_max_side(headless.gpu().caps().max_3d_texture_size),
    )
    .map_err(anyhow::Error::msg)?;
    progress(&format!(
        "prepared {0}^3 x 3 attributes in {1:.1} s",
        options.volume,
        t0.elapsed().as_secs_f64()
    ));
    let reference_image = if options.score {
        let t0 = Instant::now();
        let r = reference(
            &prepared,
            params(&base_scene),
            &base_scene.camera,
            base_scene.size,
            base_scene.background.map(|v| v as f64),
            options.oversample,
        );
        progress(&format!(
            "reference ({} steps per voxel) in {:.1} s",
            options.oversample,
            t0.elapsed().as_secs_f64()
        ));
        Some(without_alpha(&r))
    } else {
        None
    };
    let mut settings = Vec::new();
    let kinds: Vec<ProgramKind> = if headless.gpu().caps().has_arb() {
        vec![ProgramKind::Arb, ProgramKind::Glsl]
    } else {
        vec![ProgramKind::Glsl]
    };
    for &slices in &options.slices {
        for &kind in &kinds {
            settings.push((Fidelity::Faithful, kind, TargetFormat::Rgba8, false, slices));
            let targets: &[TargetFormat] = if options.full {
                &[
                    TargetFormat::Rgba8,
                    TargetFormat::Rgba16f,
                    TargetFormat::Rgba32f,
                ]
            } else {
                &[TargetFormat::Rgba32f]
            };
            for &target in targets {
                for correction in [true, false] {
                    if correction || options.full {
                        settings.push((Fidelity::Precise, kind, target, correction, slices));
                    }
                }
            }
        }
    }
    // Work per setting: slices times frames drawn (a frame's time grows with its slices).
    let work = |slices: usize| (slices * (options.frames.max(1) + 1)) as u64;
    let bar = Bar::new(
        settings.iter().map(|s| work(s.4)).sum(),
        "3D-opacity study",
        Unit::Work,
    );
    let mut rows = Vec::new();
    for (fidelity, kind, target, correction, slices) in settings {
        let mut scene = base_scene.clone();
        scene.fidelity = fidelity;
        scene.target = Some(target);
        if let Some(o) = scene.technique.get_mut::<Opacity3dScene>() {
            o.slices = slices;
            o.opacity_correction = Some(correction);
        }
        bar.set_message(&format!(
            "3D-opacity study: {} {} {} at {slices} slices",
            fidelity.name(),
            kind.name(),
            target.name()
        ));
        let (ms, image) = measure(headless, &scene, &prepared, kind, options.frames)?;
        let (max_abs, rmse, psnr) = match &reference_image {
            Some(r) => {
                let d = without_alpha(&image)
                    .compare(r, 0.0)
                    .ok_or_else(|| anyhow::anyhow!("image sizes differ"))?;
                (d.max_abs, d.rmse, d.psnr)
            }
            None => (f64::NAN, f64::NAN, f64::NAN),
        };
        let row = Row {
            fidelity,
            kind,
            target,
            correction,
            slices,
            ms,
            max_abs,
            rmse,
            psnr,
        };
        let score = if options.score {
            format!("  rmse {rmse:.5}  max {max_abs:.4}")
        } else {
            String::new()
        };
        progress(&format!(
            "{:<36} {:>5} slices {:>9.1} ms{score}",
            row.series(),
            slices,
            ms
        ));
        rows.push(row);
        bar.inc(work(slices));
    }
    Ok(rows)
}

/// The rows as CSV, one header line.
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "fidelity,programs,target,opacity_correction,slices,ms_per_frame,max_abs,rmse,psnr_db\n",
    );
    for r in rows {
        s += &format!(
            "{},{},{},{},{},{:.3},{:.6},{:.6},{:.2}\n",
            r.fidelity.name(),
            r.kind.name(),
            r.target.name(),
            r.correction,
            r.slices,
            r.ms,
            r.max_abs,
            r.rmse,
            r.psnr
        );
    }
    s
}

/// Plot RMSE against time per frame, one line per setting through its slice counts.
pub fn plot(rows: &[Row], path: &Path, title: &str) -> anyhow::Result<()> {
    let mut series: Vec<String> = rows.iter().map(Row::series).collect();
    series.sort();
    series.dedup();
    let lines: Vec<(String, Vec<(f64, f64)>)> = series
        .into_iter()
        .map(|name| {
            let points = rows
                .iter()
                .filter(|r| r.series() == name)
                .map(|r| (r.ms, r.rmse))
                .collect();
            (name, points)
        })
        .collect();
    let chart = Chart {
        title,
        x: "time per frame (ms)",
        y: "RMSE of RGB against the f64 reference",
    };
    plot_lines(&lines, path, &chart, &[])
}

/// The median of `v` (the mean of the middle two for an even count; NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => (s[n / 2 - 1] + s[n / 2]) / 2.0,
    }
}

/// The README's one-paragraph summary: the fastest setting within a given error. Peer
/// figures are not guessed here: `arbvis study --from RUN.json` compares with a peer run
/// made on this machine.
pub fn summary(rows: &[Row]) -> String {
    let mut s = String::new();
    let best = |pred: &dyn Fn(&Row) -> bool| {
        rows.iter()
            .filter(|r| pred(r))
            .min_by(|a, b| a.ms.total_cmp(&b.ms))
            .cloned()
    };
    for (label, bound) in [
        ("RMSE < 1/255", 1.0 / 255.0),
        ("RMSE < 0.5/255", 0.5 / 255.0),
    ] {
        match best(&|r: &Row| r.rmse < bound) {
            Some(r) => {
                s += &format!(
                    "fastest with {label}: {} at {} slices, {:.1} ms/frame, RMSE {:.5}\n",
                    r.series(),
                    r.slices,
                    r.ms,
                    r.rmse
                )
            }
            None => s += &format!("no setting reached {label}\n"),
        }
    }
    s + PEER_HINT
}

/// Where peer figures come from (printed after the summary): a run of the VTK peer made
/// on this machine, never a number written in the code.
pub const PEER_HINT: &str = "\
to compare with VTK's GPU ray caster on this machine (pip install vtk numpy; \
cargo build --release --no-default-features):
  python3 benches/peers/vtk_volume.py scenes/bench/cube256-amplitude.toml \\
      --precise 128,256,512 --raycast 0.5,1,2 --faithful 128,256 --json run.json
  arbvis study --from run.json --out study
";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_has_a_header_and_a_line_per_row() {
        let row = Row {
            fidelity: Fidelity::Precise,
            kind: ProgramKind::Glsl,
            target: TargetFormat::Rgba16f,
            correction: true,
            slices: 64,
            ms: 12.5,
            max_abs: 0.1,
            rmse: 0.01,
            psnr: 40.0,
        };
        let csv = to_csv(&[row.clone(), row]);
        assert_eq!(csv.lines().count(), 3);
        assert!(csv
            .lines()
            .nth(1)
            .unwrap()
            .starts_with("precise,glsl,rgba16f,true,64,12.500,"));
    }
}
