//! The volume's trade, measured (`arbvis study --technique cellproj-volume`): for each
//! mesh (the seed's grid and larger ones, and any scene given, e.g. the non-convex
//! bracket) and each projection, faithful with both sorts and several table sizes and
//! precise: the frame with the camera still, the frame while it turns 1° a frame (every
//! frame a new view: the faithful sort and index upload included), where that time goes
//! (sort, index buffer; the rest is the GL's raster and blend), and RGB RMSE and largest
//! error against the f64 reference over the image and over the mesh's interior.

use crate::error::RenderResult;
use std::time::Instant;

use crate::study::median;
use crate::techniques::{Frame, Renderer};
use arbvis_core::camera::{Camera, Projection};
use arbvis_core::progress::{Bar, Unit};
use arbvis_core::vocab::{Fidelity, TargetFormat};
use arbvis_gl::{Headless, ProgramKind, Surface, Target};

use super::super::prepare::Prepared;
use super::super::reference::silhouette_pixels;
use super::super::transfer::{Sort, VolumeSpec};
use super::super::volume_reference::{interior_mask, reference, score};
use super::super::{CellprojRenderer, CellprojScene};

/// One mesh to measure.
pub struct Case {
    /// Its name in the table.
    pub name: String,
    /// The scene (mesh, transfer function; mode is set to volume).
    pub scene: CellprojScene,
    /// The mesh, prepared.
    pub prepared: Prepared,
    /// The camera (its projection is swept).
    pub camera: Camera,
}

/// What to sweep.
#[derive(Debug, Clone)]
pub struct Options {
    /// Image size.
    pub size: [u32; 2],
    /// Timed frames per setting (median).
    pub frames: usize,
    /// Faithful table sizes (n; the length axis gets n/2).
    pub tables: Vec<u32>,
    /// Score against the reference up to this many tetrahedra.
    pub score_up_to: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            size: [320, 240],
            frames: 3,
            tables: vec![32, 64, 128, 256],
            score_up_to: 1_100_000,
        }
    }
}

/// One measured setting.
#[derive(Debug, Clone)]
pub struct Row {
    /// Mesh name.
    pub mesh: String,
    /// Tetrahedra.
    pub tets: usize,
    /// Orthographic or perspective.
    pub projection: &'static str,
    /// Setting name.
    pub setting: String,
    /// Median ms per frame, camera still.
    pub still_ms: f64,
    /// Median ms per frame, camera turning 1° a frame.
    pub moving_ms: f64,
    /// Of the moving frame: the sort (median).
    pub sort_ms: f64,
    /// Of the moving frame: building and uploading the index buffer (median).
    pub upload_ms: f64,
    /// Errors against the f64 reference (None: more tetrahedra than
    /// [`Options::score_up_to`], not scored).
    pub score: Option<Score>,
}

/// A setting's errors against the f64 reference.
#[derive(Debug, Clone, Copy)]
pub struct Score {
    /// RMSE over the image.
    pub rmse: f64,
    /// Largest error over the image.
    pub max: f64,
    /// RMSE over the interior pixels.
    pub rmse_interior: f64,
    /// Largest error over the interior pixels.
    pub max_interior: f64,
}

/// The settings of one mesh and projection: faithful MPVONC at each table size, centroid
/// at 128, the precise walk, precise projected, and precise `table` at 128.
fn settings(base: &VolumeSpec, options: &Options) -> Vec<(String, Fidelity, VolumeSpec)> {
    let mut settings: Vec<(String, Fidelity, VolumeSpec)> = Vec::new();
    for &n in &options.tables {
        for sort in [Sort::Mpvonc, Sort::Centroid] {
            if sort == Sort::Centroid && n != 128 {
                continue;
            }
            let mut v = base.clone();
            v.sort = sort;
            v.table_size = [n, (n / 2).max(2)];
            let name = format!("faithful {sort:?} table {n}x{n}x{}", (n / 2).max(2));
            settings.push((name.to_lowercase(), Fidelity::Faithful, v));
        }
    }
    settings.push(("precise walk".into(), Fidelity::Precise, base.clone()));
    let mut projected = base.clone();
    projected.precise = super::super::transfer::Precise::Projected;
    settings.push((
        "precise projected (mpvonc)".into(),
        Fidelity::Precise,
        projected,
    ));
    let mut table = base.clone();
    table.precise = super::super::transfer::Precise::Table;
    table.table_size = [128, 64];
    settings.push((
        "precise table 128x128x64 (mpvonc)".into(),
        Fidelity::Precise,
        table,
    ));
    settings
}

/// Run the sweep; `progress` hears one line per setting.
pub fn run(
    headless: &Headless,
    cases: &[Case],
    options: &Options,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<Row>> {
    let gpu = headless.gpu();
    let kind = if gpu.caps().has_arb() {
        ProgramKind::Arb
    } else {
        ProgramKind::Glsl
    };
    let [w, h] = options.size;
    let mut rows = Vec::new();
    // Work per setting: its tetrahedra (sorting and drawing grow with them).
    let per_case = cases.first().map_or(0, |c| {
        2 * settings(&c.scene.volume_spec(), options).len() as u64
    });
    let bar = Bar::new(
        cases
            .iter()
            .map(|c| per_case * c.prepared.tets.len() as u64)
            .sum(),
        "cell-projection volume study",
        Unit::Work,
    );
    for case in cases {
        let base = case.scene.volume_spec();
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let camera = Camera {
                projection,
                ..case.camera
            };
            let scored = case.prepared.tets.len() <= options.score_up_to;
            let (want, mask) = if scored {
                let tf = base
                    .build(std::path::Path::new("."), case.prepared.scale)
                    .map_err(anyhow::Error::msg)?;
                let want = reference(
                    &case.prepared,
                    &tf,
                    &[],
                    &camera,
                    options.size,
                    [0.0, 0.0, 0.0, 1.0],
                );
                let silhouette = silhouette_pixels(&case.prepared, &camera, options.size, 1.5);
                let mask = interior_mask(&case.prepared, &camera, options.size, &silhouette);
                (Some(want), mask)
            } else {
                (None, Vec::new())
            };
            for (name, fidelity, volume) in settings(&base, options) {
                bar.set_message(&format!("cell-projection volume, {}: {name}", case.name));
                let mut scene = case.scene.clone();
                scene.mode = super::super::Mode::Volume;
                scene.volume = Some(volume);
                let format = match fidelity {
                    Fidelity::Faithful => TargetFormat::Rgba8,
                    Fidelity::Precise => TargetFormat::Rgba32f,
                };
                let target = Target::with_depth(gpu, w, h, format)?;
                let mut r = CellprojRenderer::from_prepared(
                    gpu,
                    kind,
                    fidelity,
                    &scene,
                    case.prepared.clone(),
                )?;
                let mut frame = Frame {
                    camera,
                    width: w,
                    height: h,
                };
                let one = |r: &mut CellprojRenderer, frame: &Frame| -> RenderResult<f64> {
                    let t0 = Instant::now();
                    target.clear(gpu, [0.0, 0.0, 0.0, 1.0])?;
                    r.draw(gpu, Surface::Target(&target), frame)?;
                    gpu.finish();
                    Ok(t0.elapsed().as_secs_f64() * 1e3)
                };
                one(&mut r, &frame)?;
                let image = target.read(gpu)?;
                let still: Vec<f64> = (0..options.frames.max(1))
                    .map(|_| one(&mut r, &frame))
                    .collect::<RenderResult<_>>()?;
                let turn = glam::DQuat::from_rotation_y(1f64.to_radians());
                let (mut moving, mut sort, mut upload) = (Vec::new(), Vec::new(), Vec::new());
                for _ in 0..options.frames.max(1) {
                    frame.camera.rotation = (frame.camera.quat() * turn).to_array();
                    moving.push(one(&mut r, &frame)?);
                    let t = r.volume().map(|v| v.times()).unwrap_or_default();
                    sort.push(t.sort_ms);
                    upload.push(t.upload_ms);
                }
                let score = want.as_ref().map(|want| {
                    let ((rmse, max), (rmse_interior, max_interior)) = score(&image, want, &mask);
                    Score {
                        rmse,
                        max,
                        rmse_interior,
                        max_interior,
                    }
                });
                let row = Row {
                    mesh: case.name.clone(),
                    tets: case.prepared.tets.len(),
                    projection: match projection {
                        Projection::Orthographic => "ortho",
                        Projection::Perspective => "persp",
                    },
                    setting: name,
                    still_ms: median(&still),
                    moving_ms: median(&moving),
                    sort_ms: median(&sort),
                    upload_ms: median(&upload),
                    score,
                };
                let scored = match row.score {
                    Some(s) => format!(
                        "RMSE {:.5} (interior {:.5}) max {:.4}",
                        s.rmse, s.rmse_interior, s.max
                    ),
                    None => format!(
                        "unscored (more than {} tetrahedra: no reference)",
                        options.score_up_to
                    ),
                };
                progress(&format!(
                    "{:<10} {:>8} {} {:<36} still {:>8.1} ms  moving {:>8.1} ms (sort {:>6.1}, indices {:>5.1})  {scored}",
                    row.mesh, row.tets, row.projection, row.setting, row.still_ms, row.moving_ms,
                    row.sort_ms, row.upload_ms
                ));
                rows.push(row);
                bar.inc(case.prepared.tets.len() as u64);
            }
        }
    }
    Ok(rows)
}

/// The series of a setting name: faithful MPVONC through its table sizes is one line.
fn family(setting: &str) -> &str {
    match setting.find(" table ") {
        Some(i) if setting.starts_with("faithful mpvonc") => &setting[..i],
        _ => setting,
    }
}

/// Plot RMSE over the image against the still frame's time, one plot per scored mesh
/// (`OUT/cellproj-volume-MESH.png`): a line per setting family and projection, faithful
/// MPVONC through its table sizes. Returns the files written.
pub fn plot(rows: &[Row], out: &std::path::Path) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let mut meshes: Vec<&str> = rows
        .iter()
        .filter(|r| r.score.is_some())
        .map(|r| r.mesh.as_str())
        .collect();
    meshes.dedup();
    let mut written = Vec::new();
    for mesh in meshes {
        let of_mesh: Vec<&Row> = rows.iter().filter(|r| r.mesh == mesh).collect();
        let mut names: Vec<String> = of_mesh
            .iter()
            .map(|r| format!("{} ({})", family(&r.setting), r.projection))
            .collect();
        names.sort();
        names.dedup();
        let lines: Vec<(String, Vec<(f64, f64)>)> = names
            .into_iter()
            .map(|name| {
                let points = of_mesh
                    .iter()
                    .filter(|r| format!("{} ({})", family(&r.setting), r.projection) == name)
                    .filter_map(|r| Some((r.still_ms, r.score?.rmse)))
                    .collect();
                (name, points)
            })
            .collect();
        let tets = of_mesh.first().map_or(0, |r| r.tets);
        let title = format!("cell-projection volume: {mesh} ({tets} tetrahedra)");
        let chart = crate::study::Chart {
            title: &title,
            x: "time per frame, camera still (ms)",
            y: "RMSE of RGB against the f64 reference",
        };
        let path = out.join(format!("cellproj-volume-{mesh}.png"));
        crate::study::plot_lines(&lines, &path, &chart, &[])?;
        written.push(path);
    }
    Ok(written)
}

/// The rows as CSV (an unscored setting's errors are empty fields).
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "mesh,tets,projection,setting,still_ms,moving_ms,sort_ms,upload_ms,rmse,max,rmse_interior,max_interior\n",
    );
    for r in rows {
        s += &format!(
            "{},{},{},\"{}\",{:.3},{:.3},{:.3},{:.3},{}\n",
            r.mesh,
            r.tets,
            r.projection,
            r.setting,
            r.still_ms,
            r.moving_ms,
            r.sort_ms,
            r.upload_ms,
            r.score.map_or(",,,".to_string(), |s| format!(
                "{:.6},{:.6},{:.6},{:.6}",
                s.rmse, s.max, s.rmse_interior, s.max_interior
            ))
        );
    }
    s
}
