//! The trade of splats, measured (`arbvis study --technique splats`): for each cloud
//! size, the time of every way to put the points in back-to-front order
//! ([`super::sort::time_methods`]: the seed's comparator sort of structs, keys, the
//! parallel radix sort, a cache hit), and the frame time of the `splats-section` demo with
//! each sort method while the camera turns 1° per frame (so every frame sorts and uploads,
//! as a user's drag does), with the sort's share of it; then the same demo in precise
//! mode drawn as points and as tiles (`draw = "tiles"`, each tile size), where the
//! order's share is the tile lists' time, and each drawing's RMSE against the f64
//! reference of the same splats in exact order ([`plot`]: RMSE against time). For clouds
//! up to 2 M points also the f64 references' time and weighted blended OIT's error against
//! exact order, and the normals' estimation time. `lod.rs`: the point budget's trade on a
//! COPC scene (`--technique splats-lod`).

pub mod lod;

use crate::study::median;
use crate::techniques::Params;
use std::time::Instant;

use super::prepare::prepare;
use super::scene::{DrawChoice, SortChoice};
use super::sort::time_methods;
use crate::scene::Scene;
use crate::techniques::splats::SplatsScene;
use crate::techniques::{self, Frame};
use arbvis_core::camera::{Camera, Projection};
use arbvis_core::progress::{Bar, Unit};
use arbvis_core::vocab::Fidelity;
use arbvis_data::points::section::{generate, SectionSpec};
use arbvis_data::points::{PointCloud, PointSource};
use arbvis_gl::{Headless, Surface, Target};

/// What to sweep.
#[derive(Debug, Clone)]
pub struct Options {
    /// Cloud sizes for the sort timings (the seed's 570,000; 10 M for scaling).
    pub points: Vec<usize>,
    /// Cloud size for the frame times.
    pub frame_points: usize,
    /// Image size for the frame times (the seed's 1600x900).
    pub size: [u32; 2],
    /// Timed runs per sort method and frames per sort choice (medians).
    pub runs: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            points: vec![570_000, 10_000_000],
            frame_points: 570_000,
            size: [1600, 900],
            runs: 5,
        }
    }
}

/// One sort timing.
#[derive(Debug, Clone)]
pub struct SortRow {
    /// Points sorted.
    pub points: usize,
    /// Method.
    pub method: String,
    /// Median milliseconds.
    pub ms: f64,
}

/// One frame timing.
#[derive(Debug, Clone)]
pub struct FrameRow {
    /// What was drawn: the sort choice, with the fidelity and draw where not the demo's.
    pub sort: String,
    /// Median milliseconds per frame (order + upload + clear + draw + finish).
    pub ms: f64,
    /// Median milliseconds of the order (the sort, or the tile lists) and upload within
    /// it.
    pub sort_ms: f64,
    /// RMSE of RGB of the last frame against the f64 reference of the same splats in
    /// exact back-to-front order (with the fidelity's footprint and colours).
    pub rmse: f64,
}

/// The sort timings (CPU); `progress` hears one line per row.
pub fn sorts(options: &Options, mut progress: impl FnMut(&str)) -> anyhow::Result<Vec<SortRow>> {
    let camera = Camera {
        projection: Projection::Perspective,
        rotation: glam::DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.0).to_array(),
        ..Camera::default()
    };
    let mut rows = Vec::new();
    // Work: points sorted (the references, below 2 M points, grow with them too).
    let bar = Bar::new(
        options.points.iter().map(|&n| n as u64).sum(),
        "splats study, sorts (1 of 2)",
        Unit::Work,
    );
    for &points in &options.points {
        bar.set_message(&format!("splats study, sorts of {points} points (1 of 2)"));
        let cloud = generate(&SectionSpec { points, seed: 1 })?;
        let mut push = |method: String, ms: f64| {
            progress(&format!("{points:>9} points  {ms:>9.2} ms  {method}"));
            rows.push(SortRow { points, method, ms });
        };
        for (method, time) in time_methods(&cloud, &camera, options.runs) {
            push(method.to_string(), time.as_secs_f64() * 1e3);
        }
        if points <= 2_000_000 {
            for (method, ms) in accuracy(&cloud, &camera, options.size) {
                push(method, ms);
            }
        }
        bar.inc(points as u64);
    }
    Ok(rows)
}

/// Beside the sorts: the f64 references at `size` (exact compositing, and weighted
/// blended OIT with its RMSE against exact order, McGuire & Bavoil's eq. 7 weight) and
/// per-layer normals (k = 16), each timed once.
fn accuracy(cloud: &PointCloud, camera: &Camera, size: [u32; 2]) -> Vec<(String, f64)> {
    use super::reference::{self, Footprint, SplatParams, SplatScene};
    let facies = cloud.ints(arbvis_data::points::FACIES).unwrap_or(&[]);
    let rgba: Vec<[f64; 4]> = (0..cloud.len())
        .map(|i| {
            let f = facies.get(i).copied().unwrap_or(0);
            let c = arbvis_data::points::section::facies_colour(f).map(|c| c as f64 / 255.0);
            [c[0], c[1], c[2], 0.6]
        })
        .collect();
    let scene = SplatScene {
        positions: &cloud.positions,
        rgba: &rgba,
        params: SplatParams {
            point_size: 20.0,
            footprint: Footprint::Smoothstep,
            ..SplatParams::default()
        },
        background: [0.0, 0.0, 0.0, 1.0],
    };
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let exact = reference::composite(&scene, camera, size);
    let exact_ms = ms(t);
    let t = Instant::now();
    let oit = reference::weighted_blended(&scene, reference::OitWeight::Eq7, camera, size);
    let oit_ms = ms(t);
    let rmse = reference::rmse_rgb(&exact, &oit).unwrap_or(f64::NAN);
    let t = Instant::now();
    super::normals::estimate_cloud(cloud, super::normals::DEFAULT_K, true);
    let normals_ms = ms(t);
    let [w, h] = size;
    vec![
        (
            format!("f64 exact compositing at {w}x{h} (reference)"),
            exact_ms,
        ),
        (
            format!("f64 weighted blended OIT at {w}x{h}: RMSE {rmse:.4} against exact order"),
            oit_ms,
        ),
        ("normals, k = 16 per layer (kiddo + PCA)".into(), normals_ms),
    ]
}

/// The frame timings (GPU) of the `splats-section` demo at `options.frame_points`, one
/// per sort choice, then precise points and tiles (tile sides 1 to 4), the camera turning
/// 1° about the vertical axis each frame.
pub fn frames(
    headless: &Headless,
    options: &Options,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<FrameRow>> {
    let gpu = headless.gpu();
    // The demo as the README's numbers were measured (it has since been reframed).
    let mut scene = Scene::parse(
        include_str!("../../../../../scenes/bench/splats-section-study.toml"),
        "scenes/bench/splats-section-study.toml",
    )?;
    scene.size = options.size;
    let Some(params) = scene.technique.get_mut::<SplatsScene>() else {
        anyhow::bail!("the splats study scene is not a splat scene");
    };
    params.cloud = PointSource::Section(SectionSpec {
        points: options.frame_points,
        seed: 1,
    });
    let base = params.clone();
    let mut settings: Vec<(String, Fidelity, super::SplatsScene)> = [
        SortChoice::Seed,
        SortChoice::Keys,
        SortChoice::Radix,
        SortChoice::None,
        SortChoice::Oit,
    ]
    .into_iter()
    .map(|sort| {
        let p = super::SplatsScene {
            sort,
            ..base.clone()
        };
        (format!("{sort:?}").to_lowercase(), scene.fidelity, p)
    })
    .collect();
    settings.push(("radix (precise)".into(), Fidelity::Precise, base.clone()));
    for tile in [1, 2, 3, 4] {
        let p = super::SplatsScene {
            draw: DrawChoice::Tiles,
            tile,
            ..base.clone()
        };
        settings.push((format!("tiles {tile}px (precise)"), Fidelity::Precise, p));
    }
    let [w, h] = scene.size;
    let mut rows = Vec::new();
    let mut built: Option<(Fidelity, Box<dyn techniques::Renderer>)> = None;
    // The references of the last frame's view, one per fidelity, made when first needed.
    let (_, prepared) = prepare(&base, &scene.base).map_err(anyhow::Error::msg)?;
    let mut references = Vec::new();
    let bar = Bar::new(
        settings.len() as u64,
        "splats study, frames (2 of 2)",
        Unit::Work,
    );
    for (name, fidelity, p) in settings {
        bar.set_message(&format!("splats study, frames (2 of 2): {name}"));
        let renderer = match &mut built {
            Some((f, r)) if *f == fidelity => {
                r.update(gpu, Params::of(&p))?;
                r
            }
            _ => {
                let mut s = scene.clone();
                s.fidelity = fidelity;
                s.technique = p.clone().into();
                let kind = s.programs.resolve(gpu);
                &mut built
                    .insert((fidelity, crate::render::build(gpu, &s, kind)?))
                    .1
            }
        };
        let format = scene.target.unwrap_or(fidelity.default_target());
        let target = Target::create(gpu, w, h, format, renderer.needs_depth())?;
        let (mut times, mut order_times) = (Vec::new(), Vec::new());
        let mut camera = scene.camera;
        for i in 0..=options.runs.max(1) {
            let turn = glam::DQuat::from_rotation_y(1f64.to_radians());
            camera.rotation = (camera.quat() * turn).to_array();
            let frame = Frame {
                camera,
                width: w,
                height: h,
            };
            let t0 = Instant::now();
            target.clear(gpu, scene.clear_colour())?;
            renderer.draw(gpu, Surface::Target(&target), &frame)?;
            gpu.finish();
            if i > 0 {
                times.push(t0.elapsed().as_secs_f64() * 1e3);
                order_times.push(order_ms(renderer.status().as_deref()));
            }
        }
        if !references.iter().any(|(f, _)| *f == fidelity) {
            let t0 = Instant::now();
            let background = scene.clear_colour().map(f64::from);
            let image = reference_of(&prepared, &p, fidelity, &camera, scene.size, background);
            progress(&format!(
                "f64 reference ({}, exact order) in {:.1} s",
                fidelity.name(),
                t0.elapsed().as_secs_f64()
            ));
            references.push((fidelity, image));
        }
        let reference = &references
            .iter()
            .find(|(f, _)| *f == fidelity)
            .expect("made above")
            .1;
        let rmse = super::reference::rmse_rgb(&target.read(gpu)?, reference).unwrap_or(f64::NAN);
        let row = FrameRow {
            sort: name,
            ms: median(&times),
            sort_ms: median(&order_times),
            rmse,
        };
        progress(&format!(
            "{:<26} {:>9.1} ms/frame, of which order and upload {:>7.1} ms, RMSE {:.5}",
            row.sort, row.ms, row.sort_ms, row.rmse
        ));
        rows.push(row);
        bar.inc(1);
    }
    Ok(rows)
}

/// The f64 reference of `prepared` drawn with `params` at `fidelity` from `camera`, in
/// exact back-to-front order, over the scene's clear colour.
fn reference_of(
    prepared: &super::prepare::Prepared,
    params: &super::SplatsScene,
    fidelity: Fidelity,
    camera: &Camera,
    size: [u32; 2],
    background: [f64; 4],
) -> arbvis_core::image::Image {
    use super::reference::{composite, eye_position, view_direction, SplatParams, SplatScene};
    let rgba = super::prepare::point_rgba(
        prepared,
        params,
        fidelity,
        eye_position(camera),
        view_direction(camera),
    );
    let splats = SplatScene {
        positions: &prepared.positions,
        rgba: &rgba,
        params: SplatParams {
            point_size: params.point_size,
            factor: params.factor,
            footprint: super::prepare::footprint(params, fidelity),
            size_range: [1.0, 255.0],
        },
        background,
    };
    composite(&splats, camera, size)
}

/// Plot each drawing's RMSE against its frame time: the faithful sorts and OIT, precise
/// points, and precise tiles through their tile sides.
pub fn plot(frames: &[FrameRow], path: &std::path::Path, title: &str) -> anyhow::Result<()> {
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in frames {
        let series = if r.sort.starts_with("tiles") {
            "tiles (precise), 1 to 4 px".to_string()
        } else {
            r.sort.clone()
        };
        match lines.iter_mut().find(|(n, _)| *n == series) {
            Some((_, points)) => points.push((r.ms, r.rmse)),
            None => lines.push((series, vec![(r.ms, r.rmse)])),
        }
    }
    let chart = crate::study::Chart {
        title,
        x: "time per frame, camera turning 1° a frame (ms)",
        y: "RMSE of RGB against the f64 reference in exact order",
    };
    crate::study::plot_lines(&lines, path, &chart, &[])
}

/// The order's time in the renderer's status line: `last lists 21.3 ms` (tiles), else
/// `last sort (Radix): 3.2 ms`; 0 where it reports neither (OIT, file order).
fn order_ms(status: Option<&str>) -> f64 {
    let Some(s) = status else { return 0.0 };
    let after = |marker: &str| {
        let rest = &s[s.find(marker)? + marker.len()..];
        let number = rest.split(" ms").next()?;
        number.trim().parse().ok()
    };
    if s.contains("OIT") || s.contains("(None)") {
        return 0.0;
    }
    after("last lists ").or_else(|| after("): ")).unwrap_or(0.0)
}

/// Both sweeps as CSV text: sorts, then frames.
pub fn to_csv(sorts: &[SortRow], frames: &[FrameRow]) -> (String, String) {
    let mut s = String::from("points,method,ms\n");
    for r in sorts {
        s += &format!("{},\"{}\",{:.3}\n", r.points, r.method, r.ms);
    }
    let mut f = String::from("drawn,ms_per_frame,order_and_upload_ms,rmse\n");
    for r in frames {
        f += &format!("{},{:.3},{:.3},{:.6}\n", r.sort, r.ms, r.sort_ms, r.rmse);
    }
    (s, f)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_status_line_gives_the_order_time() {
        let s = "570000 of 570000 points drawn; last sort (Radix): 3.2 ms";
        assert_eq!(super::order_ms(Some(s)), 3.2);
        let tiles = "570000 of 570000 points drawn as tiles of 2 px: 774448 list entries, \
                     placed, binned and ordered per tile: last lists 21.3 ms";
        assert_eq!(super::order_ms(Some(tiles)), 21.3);
        assert_eq!(super::order_ms(Some("weighted blended OIT (no sort)")), 0.0);
        let none = "570000 of 570000 points drawn; last sort (None): 0.0 ms";
        assert_eq!(super::order_ms(Some(none)), 0.0);
        assert_eq!(super::order_ms(None), 0.0);
    }
}
