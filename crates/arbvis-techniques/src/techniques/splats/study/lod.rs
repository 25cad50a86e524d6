//! `arbvis study --technique splats-lod --scenes SCENE`: the point budget's trade on a
//! COPC scene. For each budget, the picture of the nodes chosen for the scene's view
//! (every node the budget allows: no pixel size, so the budget alone decides) against
//! the picture of every point, RMSE over RGB, beside the frame time with the camera
//! turning 1° a frame (`arbvis bench --turn 1`'s timing: the resident points drawn from a
//! moving view). Clouds whose every point fits in memory only (the full picture is the
//! reference).

use anyhow::{bail, Context, Result};

use crate::scene::Scene;
use crate::study::bench::{self, BenchOptions};
use crate::techniques::splats::SplatsScene;
use arbvis_data::points::copc::Copc;
use arbvis_data::points::copc_lod::{select, View};
use arbvis_data::points::PointSource;
use arbvis_gl::Headless;

/// One budget measured.
#[derive(Debug, Clone, PartialEq)]
pub struct LodRow {
    /// The point budget.
    pub budget: u64,
    /// Points and nodes drawn, and the deepest level.
    pub points: u64,
    pub nodes: usize,
    pub deepest: i32,
    /// Median frame time, camera turning, ms.
    pub ms: f64,
    /// RMSE of RGB against the picture of every point.
    pub rmse: f64,
}

/// The scene with `budget` and no pixel size.
fn with_budget(scene: &Scene, budget: u64) -> Result<Scene> {
    let mut s = scene.clone();
    let Some(p) = s.technique.get_mut::<SplatsScene>() else {
        bail!("the splats-lod study needs a splats scene");
    };
    let PointSource::Copc(spec) = &mut p.cloud else {
        bail!("the splats-lod study needs a scene whose cloud is a COPC file");
    };
    spec.points = budget;
    spec.min_node_pixels = 0.0;
    Ok(s)
}

/// Measure `budgets` (each under the cloud's point count) on `scene`.
pub fn lod(
    headless: &Headless,
    scene: &Scene,
    budgets: &[u64],
    frames: usize,
    mut progress: impl FnMut(&str),
) -> Result<Vec<LodRow>> {
    let Some(p) = scene.technique.get::<SplatsScene>() else {
        bail!("the splats-lod study needs a splats scene");
    };
    let PointSource::Copc(spec) = &p.cloud else {
        bail!("the splats-lod study needs a scene whose cloud is a COPC file");
    };
    let path = arbvis_data::fetch::resolve(&scene.base, &spec.path);
    let copc = Copc::open(&path).with_context(|| format!("opening {}", path.display()))?;
    progress(&format!(
        "splats-lod: the reference, all {} points of {}",
        copc.points,
        path.display()
    ));
    let full = crate::render::render_on(headless, &with_budget(scene, copc.points)?)?.image;
    let view = View::of(&scene.camera, scene.size);
    let mut rows = Vec::new();
    for &budget in budgets {
        let s = with_budget(scene, budget)?;
        let cut = select(&copc, &view, budget, 0.0)?;
        let image = crate::render::render_on(headless, &s)?.image;
        let rgb: Vec<f32> = full
            .data
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let (_, rmse) = bench::rgb_error(&image, &rgb);
        let options = BenchOptions {
            frames: frames.max(1),
            rounds: 1,
            turn: 1.0,
            ..Default::default()
        };
        let report = bench::run(headless, &s, "splats-lod", &options, |_| {})?;
        let ms = report.settings.first().map_or(f64::NAN, |m| m.median_ms);
        let row = LodRow {
            budget,
            points: cut.points / cut.root_stride.max(1),
            nodes: cut.nodes.len(),
            deepest: cut.deepest,
            ms,
            rmse,
        };
        progress(&format!(
            "budget {budget}: {} points in {} nodes to level {}, {ms:.1} ms a frame turning, RMSE {rmse:.5}",
            row.points, row.nodes, row.deepest
        ));
        rows.push(row);
    }
    Ok(rows)
}

/// The rows as CSV.
pub fn to_csv(rows: &[LodRow]) -> String {
    let mut s = String::from("budget,points,nodes,deepest_level,ms_turning,rmse\n");
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{:.3},{:.6}\n",
            r.budget, r.points, r.nodes, r.deepest, r.ms, r.rmse
        ));
    }
    s
}

/// RMSE against frame time, one point per budget.
pub fn plot(rows: &[LodRow], path: &std::path::Path, title: &str) -> Result<()> {
    let line = vec![(
        "budgets (points drawn)".to_string(),
        rows.iter().map(|r| (r.ms, r.rmse.max(1e-6))).collect(),
    )];
    let chart = crate::study::Chart {
        title,
        x: "time per frame, camera turning 1° a frame (ms)",
        y: "RMSE of RGB against every point drawn",
    };
    crate::study::plot_lines(&line, path, &chart, &[])
}
