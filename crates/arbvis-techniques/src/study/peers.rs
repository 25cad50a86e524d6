//! `arbvis study --from RUN.json ...`: the trade against the peer, from the runs of
//! `benches/peers/vtk_volume.py --json` (one per scene and view: arbvis's settings and
//! VTK's, timed in one interleaved run and scored against one reference).
//!
//! For each run: error against time for every series on the same log axes (faithful
//! slicing, precise slicing, the ray caster, VTK float32 and uint8; `RUN.png`), and in a
//! README-ready Markdown file (`study.md`) the machine and driver, each VTK setting with
//! the fastest arbvis setting at equal or lower RMSE and the ratio of their median frame
//! times, whether each precise series' error falls with the work spent, its order of
//! convergence between neighbouring settings (`-log(e2/e1) / log(w2/w1)`, work = slices or
//! steps per voxel) and the work it needs for RMSE 1/255 and 1e-3 (log-log interpolation
//! between the settings that bracket it). `study.csv` holds every point.

use super::median;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Deserialize;

/// One arbvis setting of a run.
#[derive(Debug, Clone, Deserialize)]
struct ArbvisPoint {
    rmse: Option<f64>,
    frames_ms: Vec<f64>,
}

/// One VTK setting of a run.
#[derive(Debug, Clone, Deserialize)]
struct VtkPoint {
    #[serde(rename = "type")]
    scalar_type: String,
    sample_distance: f64,
    frames_ms: Vec<f64>,
    rmse: f64,
}

#[derive(Debug, Clone, Deserialize)]
struct ArbvisHeader {
    scene: String,
    renderer: String,
    version: String,
    size: [u32; 2],
}

/// A peer-script run.
#[derive(Debug, Clone, Deserialize)]
struct Run {
    arbvis: ArbvisHeader,
    arbvis_frames: BTreeMap<String, ArbvisPoint>,
    vtk: Vec<VtkPoint>,
    vtk_version: String,
}

/// A point of a series: work (slices or steps per voxel; VTK: voxels per sample), median
/// ms, RMSE, and the setting's name.
#[derive(Debug, Clone)]
struct Point {
    work: f64,
    ms: f64,
    rmse: f64,
    name: String,
}

/// The series of a run, by name, each sorted by work.
fn series(run: &Run) -> BTreeMap<String, Vec<Point>> {
    let mut out: BTreeMap<String, Vec<Point>> = BTreeMap::new();
    for (name, p) in &run.arbvis_frames {
        let Some(rmse) = p.rmse else { continue };
        // "faithful slicing 128", "raycast 0.75 step/voxel", "raycast pre-int 2 step/voxel"
        let words: Vec<&str> = name.split_whitespace().collect();
        let (label, work) = match words.iter().position(|w| w.parse::<f64>().is_ok()) {
            Some(i) => (
                words[..i].join(" "),
                words[i].parse::<f64>().unwrap_or(f64::NAN),
            ),
            None => (name.clone(), f64::NAN),
        };
        out.entry(format!("arbvis {label}"))
            .or_default()
            .push(Point {
                work,
                ms: median(&p.frames_ms),
                rmse,
                name: name.clone(),
            });
    }
    for v in &run.vtk {
        out.entry(format!("VTK {}", v.scalar_type))
            .or_default()
            .push(Point {
                work: 1.0 / v.sample_distance,
                ms: median(&v.frames_ms),
                rmse: v.rmse,
                name: format!("VTK {} sd {}", v.scalar_type, v.sample_distance),
            });
    }
    for points in out.values_mut() {
        points.sort_by(|a, b| a.work.total_cmp(&b.work));
    }
    out
}

fn read_run(path: &Path) -> Result<Run> {
    let text = arbvis_core::input::read_text(path, 64 << 20)
        .with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{}:{}:{}: {e}", path.display(), e.line(), e.column()))
}

/// Work needed for `bound` (log-log interpolation between bracketing points).
fn work_for(points: &[Point], bound: f64) -> Option<f64> {
    if points.first().is_some_and(|p| p.rmse <= bound) {
        return Some(points[0].work);
    }
    points.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        (a.rmse > bound && b.rmse <= bound).then(|| {
            let t = (bound.ln() - a.rmse.ln()) / (b.rmse.ln() - a.rmse.ln());
            (a.work.ln() + t * (b.work.ln() - a.work.ln())).exp()
        })
    })
}

/// Work as a reader counts it: whole slices for slicing (rounded up: the least count
/// that reaches the bound), else steps per voxel.
fn work_words(series: &str, work: f64) -> String {
    if series.contains("slicing") {
        format!("{} slices", work.ceil() as u64)
    } else {
        format!("{} step/voxel", (work * 100.0).round() / 100.0)
    }
}

/// The Markdown for one run.
fn markdown(name: &str, run: &Run, series: &BTreeMap<String, Vec<Point>>) -> String {
    let mut s = format!(
        "### {name}\n\n{} at {}x{}; {} ({}); VTK {}. Medians of every timed frame, \
         arbvis and VTK alternating round by round; RMSE over RGB against one f64 \
         reference.\n\n",
        run.arbvis.scene,
        run.arbvis.size[0],
        run.arbvis.size[1],
        run.arbvis.renderer,
        run.arbvis.version,
        run.vtk_version
    );
    s += "| VTK setting | VTK ms | VTK RMSE | fastest arbvis at equal or lower RMSE | ms | RMSE | speed-up |\n|---|---|---|---|---|---|---|\n";
    let arb: Vec<&Point> = series
        .iter()
        .filter(|(k, _)| k.starts_with("arbvis"))
        .flat_map(|(_, v)| v)
        .collect();
    for v in series
        .iter()
        .filter(|(k, _)| k.starts_with("VTK"))
        .flat_map(|(_, v)| v.iter().rev())
    {
        let best = arb
            .iter()
            .filter(|a| a.rmse <= v.rmse)
            .min_by(|a, b| a.ms.total_cmp(&b.ms));
        s += &match best {
            Some(a) => format!(
                "| {} | {:.0} | {:.4} | {} | {:.0} | {:.4} | {:.2}x |\n",
                v.name,
                v.ms,
                v.rmse,
                a.name,
                a.ms,
                a.rmse,
                v.ms / a.ms
            ),
            None => format!(
                "| {} | {:.0} | {:.4} | none | | | |\n",
                v.name, v.ms, v.rmse
            ),
        };
    }
    s += "\n| arbvis series | settings (ms / RMSE) | error falls with work | order between settings | for 1/255 | for 1e-3 |\n|---|---|---|---|---|---|\n";
    for (label, points) in series.iter().filter(|(k, _)| k.starts_with("arbvis")) {
        let settings: Vec<String> = points
            .iter()
            .map(|p| format!("{}: {:.0} / {:.4}", work_words(label, p.work), p.ms, p.rmse))
            .collect();
        let falls = points.windows(2).all(|w| w[1].rmse <= w[0].rmse);
        let orders: Vec<String> = points
            .windows(2)
            .map(|w| {
                let p = -(w[1].rmse / w[0].rmse).ln() / (w[1].work / w[0].work).ln();
                format!("{p:.1}")
            })
            .collect();
        let need =
            |b: f64| work_for(points, b).map_or("beyond".to_string(), |w| work_words(label, w));
        s += &format!(
            "| {label} | {} | {} | {} | {} | {} |\n",
            settings.join(", "),
            if falls { "yes" } else { "no" },
            orders.join(", "),
            need(1.0 / 255.0),
            need(1e-3)
        );
    }
    s + "\n"
}

/// Read the runs, write `study.csv`, `study.md` and a plot per run into `out`.
pub fn study(runs: &[PathBuf], out: &Path) -> Result<String> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut csv = String::from("run,series,setting,work,ms_median,rmse\n");
    let mut md = String::new();
    for path in runs {
        let run = read_run(path)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| "run".into());
        let series = series(&run);
        for (label, points) in &series {
            for p in points {
                csv += &format!(
                    "{name},{label},{},{},{:.3},{:.6}\n",
                    p.name, p.work, p.ms, p.rmse
                );
            }
        }
        md += &markdown(&name, &run, &series);
        let lines: Vec<(String, Vec<(f64, f64)>)> = series
            .iter()
            .map(|(k, v)| (k.clone(), v.iter().map(|p| (p.ms, p.rmse)).collect()))
            .collect();
        let title = format!(
            "{name}: {} at {}x{}, {}",
            run.arbvis.scene, run.arbvis.size[0], run.arbvis.size[1], run.arbvis.renderer
        );
        let chart = super::Chart {
            title: &title,
            x: "time per frame, median (ms)",
            y: "RMSE of RGB against the f64 reference",
        };
        super::plot_lines(&lines, &out.join(format!("{name}.png")), &chart, &[])?;
    }
    arbvis_core::png_io::write_atomic(&out.join("study.csv"), csv.as_bytes())?;
    arbvis_core::png_io::write_atomic(&out.join("study.md"), md.as_bytes())?;
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    const RUN: &str = r#"{"arbvis": {"scene": "s", "renderer": "llvmpipe", "version": "4.5",
        "size": [8, 8], "settings": []},
      "arbvis_frames": {
        "precise slicing 128": {"rmse": 0.0039, "max_abs": 0.1, "frames_ms": [10, 12, 11]},
        "precise slicing 256": {"rmse": 0.001, "max_abs": 0.1, "frames_ms": [20, 22]},
        "raycast 0.5 step/voxel": {"rmse": 0.002, "max_abs": 0.1, "frames_ms": [5]}},
      "vtk": [{"type": "float32", "sample_distance": 2.0, "first_ms": 1, "frames_ms": [12],
               "rmse": 0.003, "max_abs": 0.1},
              {"type": "float32", "sample_distance": 1.0, "first_ms": 1, "frames_ms": [30],
               "rmse": 0.0015, "max_abs": 0.1}],
      "vtk_version": "9.7.2"}"#;

    #[test]
    fn ratios_orders_and_work_needed() {
        let run: Run = serde_json::from_str(RUN).unwrap();
        let s = series(&run);
        assert_eq!(s["arbvis precise slicing"].len(), 2);
        assert_eq!(s["arbvis precise slicing"][0].ms, 11.0);
        let md = markdown("t", &run, &s);
        // sd 2 (0.003): the ray caster (5 ms, 0.002) is fastest: 12 / 5.
        assert!(
            md.contains(
                "| VTK float32 sd 2 | 12 | 0.0030 | raycast 0.5 step/voxel | 5 | 0.0020 | 2.40x |"
            ),
            "{md}"
        );
        // sd 1 (0.0015): only precise 256 (21 ms): 30 / 21.
        assert!(
            md.contains("precise slicing 256 | 21 | 0.0010 | 1.43x"),
            "{md}"
        );
        // 128 -> 256 slices: error / 4 for work x 2: order 2; 1e-3 needs 256.
        // Slice counts are whole numbers.
        assert!(
            md.contains("| yes | 2.0 | 128 slices | 256 slices |"),
            "{md}"
        );
        assert!(
            md.contains("| 128 slices: 11 / 0.0039, 256 slices: 21 / 0.0010 |"),
            "{md}"
        );
        // Between bracketing settings the count is interpolated (log-log) and rounded up:
        // 0.002 lies t = ln(0.002/0.0039) / ln(0.001/0.0039) = 0.4907 of the way from 128
        // to 256 slices, at 128 x 2^0.4907 = 179.8: 180 slices.
        let w = work_for(&s["arbvis precise slicing"], 0.002).unwrap();
        assert!((w - 179.8).abs() < 0.1, "{w}");
        assert_eq!(work_words("arbvis precise slicing", w), "180 slices");
        assert_eq!(work_words("arbvis raycast", 0.755), "0.76 step/voxel");
    }
}
