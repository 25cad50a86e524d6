//! `arbvis bench` and `arbvis study`: the speed-for-accuracy trade of v3o2's 3D opacity,
//! measured. A synthetic seismic block (amplitude, envelope, cosine of phase: three
//! attributes of `volume³`) is drawn at `size²` for each setting that trades speed for
//! accuracy — slice count, target precision, opacity correction, ARB vs GLSL, faithful vs
//! precise — timed over several frames (median), and scored against the f64 reference
//! integral (RGB: max abs, RMSE, PSNR). `study` writes CSV and a plot (error against time).

pub mod bench;
pub mod breakdown;
pub mod export;
pub mod measured;
pub mod peers;

use std::path::Path;
use std::time::Instant;

use crate::gl::{GlResult, Headless, ProgramKind, Surface, Target};
use crate::image::Image;
use crate::scene::{Scene, TechniqueScene};
use crate::techniques::opacity3d::prepare::{prepare, Prepared};
use crate::techniques::opacity3d::reference::reference;
use crate::techniques::opacity3d::{Opacity3dRenderer, Opacity3dScene};
use crate::techniques::{Frame, Renderer};
use crate::vocab::Fidelity;
use crate::vocab::TargetFormat;
use crate::volume::synthetic::SyntheticSpec;
use crate::volume::VolumeSource;

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
        include_str!("../../scenes/bench/v3o2-sum-study.toml"),
        "scenes/bench/v3o2-sum-study.toml",
    )
    .expect("the built-in study scene parses");
    scene.size = [options.size, options.size];
    if let TechniqueScene::Opacity3d(o) = &mut scene.technique {
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
    match &scene.technique {
        TechniqueScene::Opacity3d(o) => o,
        _ => unreachable!("study scenes are opacity3d"),
    }
}

/// Time one setting: build from `prepared`, one warm-up frame, `frames` timed frames.
fn measure(
    headless: &Headless,
    scene: &Scene,
    prepared: &Prepared,
    kind: ProgramKind,
    frames: usize,
) -> GlResult<(f64, Image)> {
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
    crate::gl_check!(gpu)?;
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
        &crate::volume::Limits::for_max_side(headless.gpu().caps().max_3d_texture_size),
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
    let mut rows = Vec::new();
    for (fidelity, kind, target, correction, slices) in settings {
        let mut scene = base_scene.clone();
        scene.fidelity = fidelity;
        scene.target = Some(target);
        if let TechniqueScene::Opacity3d(o) = &mut scene.technique {
            o.slices = slices;
            o.opacity_correction = Some(correction);
        }
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

/// Plot RMSE against time per frame, one line per setting through its slice counts,
/// with the VTK GPU ray caster's time on this machine kind as a vertical line.
pub fn plot(rows: &[Row], path: &Path, title: &str, vtk_ms: f64) -> anyhow::Result<()> {
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
    let vtk = format!("VTK 9.7 GPU ray caster, 3 components ({vtk_ms:.0} ms)");
    plot_lines(&lines, path, title, Some((vtk_ms, vtk.as_str())))
}

/// Plot named lines of (ms, RMSE) points on log axes (a line and dots per series), and
/// where given a vertical line at a time with its label.
pub fn plot_lines(
    lines: &[(String, Vec<(f64, f64)>)],
    path: &Path,
    title: &str,
    vertical: Option<(f64, &str)>,
) -> anyhow::Result<()> {
    use plotters::prelude::*;
    register_plot_font()?;
    let (w, h) = (1100u32, 700u32);
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let finite = |v: f64| v.is_finite() && v > 0.0;
        let points: Vec<(f64, f64)> = lines
            .iter()
            .flat_map(|(_, p)| p.iter().copied())
            .filter(|&(x, y)| finite(x) && finite(y))
            .collect();
        if points.is_empty() {
            anyhow::bail!("nothing to plot");
        }
        let xs = points
            .iter()
            .map(|p| p.0)
            .chain(vertical.map(|v| v.0).filter(|&x| finite(x)));
        let (x0, x1) = xs.fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        let (y0, y1) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
        let (x0, x1, y0, y1) = (x0 * 0.8, x1 * 1.25, y0 * 0.8, y1 * 1.25);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("time per frame (ms, log)")
            .y_desc("RMSE of RGB against the f64 reference (log)")
            .label_style(("sans-serif", 14))
            .draw()?;
        for (n, (name, pts)) in lines.iter().enumerate() {
            let colour = Palette99::pick(n).to_rgba();
            let mut pts: Vec<(f64, f64)> = pts
                .iter()
                .copied()
                .filter(|&(x, y)| finite(x) && finite(y))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
        }
        if let Some((x, label)) = vertical.filter(|v| finite(v.0)) {
            chart
                .draw_series(LineSeries::new(
                    vec![(x, y0), (x, y1)],
                    BLACK.stroke_width(1),
                ))?
                .label(label)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
        root.present()?;
    }
    save_plot(&buffer, w, h, path)
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

/// The plots' font (egui's, already a dependency), registered with plotters.
fn register_plot_font() -> anyhow::Result<()> {
    plotters::style::register_font(
        "sans-serif",
        plotters::style::FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    )
    .map_err(|_| anyhow::anyhow!("the plot font did not load"))
}

/// Write a plotters RGB buffer as an opaque PNG.
fn save_plot(buffer: &[u8], w: u32, h: u32, path: &Path) -> anyhow::Result<()> {
    let data: Vec<f32> = buffer
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255].map(|v| v as f32 / 255.0))
        .collect();
    let image = Image {
        width: w,
        height: h,
        format: TargetFormat::Rgba8,
        data,
    };
    crate::png_io::write_png(path, &image, &[("Software", "arbvis study".into())])?;
    Ok(())
}

/// The README's one-paragraph summary: the fastest setting within a given error.
pub fn summary(rows: &[Row], vtk_ms: f64) -> String {
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
        if let Some(r) = best(&|r: &Row| r.rmse < bound) {
            s += &format!(
                "fastest with {label}: {} at {} slices, {:.1} ms/frame ({:.1}x VTK's {:.0} ms), RMSE {:.5}\n",
                r.series(),
                r.slices,
                r.ms,
                vtk_ms / r.ms,
                vtk_ms,
                r.rmse
            );
        }
    }
    s
}

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
