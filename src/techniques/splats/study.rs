//! The trade of splats, measured (`arbvis study --technique splats`): for each cloud
//! size, the time of every way to put the points in back-to-front order
//! ([`super::sort::time_methods`]: the seed's comparator sort of structs, keys, the
//! parallel radix sort, a cache hit), and the frame time of the `splats-section` demo with
//! each sort method while the camera turns 1° per frame (so every frame sorts and uploads,
//! as a user's drag does), with the sort's share of it. For clouds up to 2 M points also
//! the f64 references' time and weighted blended OIT's error against exact order, and the
//! normals' estimation time.

use std::time::Instant;

use super::scene::SortChoice;
use super::sort::time_methods;
use crate::camera::{Camera, Projection};
use crate::gl::{Headless, Surface, Target};
use crate::points::section::{generate, SectionSpec};
use crate::points::{PointCloud, PointSource};
use crate::scene::{Scene, TechniqueScene};
use crate::techniques::{self, Frame};

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
    /// Sort choice.
    pub sort: String,
    /// Median milliseconds per frame (sort + upload + clear + draw + finish).
    pub ms: f64,
    /// Median milliseconds of the sort and upload within it.
    pub sort_ms: f64,
}

/// The sort timings (CPU); `progress` hears one line per row.
pub fn sorts(options: &Options, mut progress: impl FnMut(&str)) -> anyhow::Result<Vec<SortRow>> {
    let camera = Camera {
        projection: Projection::Perspective,
        rotation: glam::DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.0).to_array(),
        ..Camera::default()
    };
    let mut rows = Vec::new();
    for &points in &options.points {
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
    }
    Ok(rows)
}

/// Beside the sorts: the f64 references at `size` (exact compositing, and weighted
/// blended OIT with its RMSE against exact order, McGuire & Bavoil's eq. 7 weight) and
/// per-layer normals (k = 16), each timed once.
fn accuracy(cloud: &PointCloud, camera: &Camera, size: [u32; 2]) -> Vec<(String, f64)> {
    use super::reference::{self, Footprint, SplatParams, SplatScene};
    let facies = cloud.ints(crate::points::FACIES).unwrap_or(&[]);
    let rgba: Vec<[f64; 4]> = (0..cloud.len())
        .map(|i| {
            let f = facies.get(i).copied().unwrap_or(0);
            let c = crate::points::section::facies_colour(f).map(|c| c as f64 / 255.0);
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
/// per sort choice, the camera turning 1° about the vertical axis each frame.
pub fn frames(
    headless: &Headless,
    options: &Options,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<FrameRow>> {
    let gpu = headless.gpu();
    let mut scene = Scene::demo("splats-section")?;
    scene.size = options.size;
    let TechniqueScene::Splats(params) = &mut scene.technique else {
        anyhow::bail!("the splats-section demo is not a splat scene");
    };
    params.cloud = PointSource::Section(SectionSpec {
        points: options.frame_points,
        seed: 1,
    });
    let base = params.clone();
    let kind = scene.programs.resolve(gpu);
    let mut renderer = techniques::build(gpu, &scene, kind)?;
    let [w, h] = scene.size;
    let target = Target::create(gpu, w, h, scene.target_format(), renderer.needs_depth())?;
    let mut rows = Vec::new();
    for sort in [
        SortChoice::Seed,
        SortChoice::Keys,
        SortChoice::Radix,
        SortChoice::None,
        SortChoice::Oit,
    ] {
        let mut p = base.clone();
        p.sort = sort;
        renderer.update(gpu, &TechniqueScene::Splats(p))?;
        let (mut times, mut sort_times) = (Vec::new(), Vec::new());
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
                // File order and OIT do not sort (the status keeps the last sort's time).
                let sorted = !matches!(sort, SortChoice::None | SortChoice::Oit);
                sort_times.push(if sorted {
                    sort_ms(renderer.status().as_deref())
                } else {
                    0.0
                });
            }
        }
        let row = FrameRow {
            sort: format!("{sort:?}").to_lowercase(),
            ms: median(&mut times),
            sort_ms: median(&mut sort_times),
        };
        progress(&format!(
            "{:<6} {:>9.1} ms/frame, of which sort and upload {:>7.1} ms",
            row.sort, row.ms, row.sort_ms
        ));
        rows.push(row);
    }
    Ok(rows)
}

/// The sort time the renderer's status line reports (`... last sort (Radix): 3.2 ms`),
/// 0 where it reports none (OIT).
fn sort_ms(status: Option<&str>) -> f64 {
    status
        .and_then(|s| s.rsplit_once("): "))
        .and_then(|(_, t)| t.trim_end_matches(" ms").parse().ok())
        .unwrap_or(0.0)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Both sweeps as CSV text: sorts, then frames.
pub fn to_csv(sorts: &[SortRow], frames: &[FrameRow]) -> (String, String) {
    let mut s = String::from("points,method,ms\n");
    for r in sorts {
        s += &format!("{},\"{}\",{:.3}\n", r.points, r.method, r.ms);
    }
    let mut f = String::from("sort,ms_per_frame,sort_and_upload_ms\n");
    for r in frames {
        f += &format!("{},{:.3},{:.3}\n", r.sort, r.ms, r.sort_ms);
    }
    (s, f)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_status_line_gives_the_sort_time() {
        let s = "570000 of 570000 points drawn; last sort (Radix): 3.2 ms";
        assert_eq!(super::sort_ms(Some(s)), 3.2);
        assert_eq!(super::sort_ms(Some("weighted blended OIT (no sort)")), 0.0);
        assert_eq!(super::sort_ms(None), 0.0);
    }
}
