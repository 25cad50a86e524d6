//! The speed/accuracy trade of cell projection, measured: frames per second at the seed's
//! size (24,576 tetrahedra, 320x240) and up to about a million tetrahedra; the latency
//! from an isovalue change to the new frame; per-vertex vs per-fragment exit; faithful vs
//! precise; each setting scored against the f64 reference (fraction of interior pixels
//! with the right isovalue colour; one reference per mesh and projection), on meshes up to
//! [`Options::score_up_to`] points per side; larger meshes are timed only and say
//! "unscored" (they once printed "agree NaN"). [`plot`] draws the wrong-colour fraction
//! against time.

pub mod volume;

use crate::error::RenderResult;
use crate::study::median;
use crate::techniques::Params;
use std::time::Instant;

use crate::techniques::{Frame, Renderer};
use arbvis_core::camera::{Camera, Projection};
use arbvis_core::vocab::Fidelity;
use arbvis_core::vocab::TargetFormat;
use arbvis_data::mesh::grid::{generate, Field, GridSpec};
use arbvis_data::mesh::scalars::ScalarSpec;
use arbvis_gl::{Headless, ProgramKind, Surface, Target};

use super::prepare::{from_mesh, Prepared};
use super::reference::{agreement, reference, silhouette_pixels, Hit};
use super::{CellprojRenderer, CellprojScene, Exit, Isovalue, IsovalueUnits};
use arbvis_core::progress::{Bar, Unit};

/// What to sweep.
#[derive(Debug, Clone)]
pub struct Options {
    /// Grid points per side (the seed: 17; 17 → 24,576 tetrahedra, 56 → 1.0 M).
    pub grids: Vec<usize>,
    /// Image size.
    pub size: [u32; 2],
    /// Timed frames per setting (median), after one warm-up frame.
    pub frames: usize,
    /// Score against the reference on meshes up to this many points per side (one
    /// reference per mesh and projection, slow at a million tetrahedra; measured:
    /// docs/benchmarks.md, "Figures behind cell projection's settings").
    pub score_up_to: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            grids: vec![17, 25, 33, 45, 56],
            size: [320, 240],
            frames: 5,
            score_up_to: 64,
        }
    }
}

/// One measured setting.
#[derive(Debug, Clone)]
pub struct Row {
    /// Tetrahedra drawn.
    pub tets: usize,
    /// Setting name.
    pub setting: String,
    /// Median milliseconds per frame (clear + draw + finish).
    pub ms: f64,
    /// Milliseconds from an isovalue edit to the finished new frame (median).
    pub edit_ms: f64,
    /// Fraction of interior pixels agreeing with the reference (None: the mesh is larger
    /// than [`Options::score_up_to`], not scored).
    pub agreement: Option<f64>,
}

/// The seed's isovalues.
pub fn seed_isovalues() -> Vec<Isovalue> {
    [
        (0.3, [1.0, 0.0, 0.0, 1.0]),
        (0.5, [0.0, 1.0, 0.0, 1.0]),
        (0.9, [0.0, 0.0, 1.0, 1.0]),
    ]
    .map(|(value, color)| Isovalue { value, color })
    .to_vec()
}

fn scene_for(points: usize, exit: Exit, active_only: bool) -> CellprojScene {
    CellprojScene {
        mesh: arbvis_data::mesh::MeshSource::Grid(GridSpec {
            points: [points; 3],
            field: Field::Spherical,
        }),
        scalars: ScalarSpec::default(),
        mode: Default::default(),
        volume: None,
        isovalues: seed_isovalues(),
        isovalue_units: IsovalueUnits::Normalized,
        exit,
        table_size: 256,
        shading: false,
        active_only,
        order: Default::default(),
        depth: Default::default(),
        interpolation: Default::default(),
    }
}

/// The study's camera: the demo's rotation.
pub fn study_camera(projection: Projection) -> Camera {
    Camera {
        projection,
        rotation: [0.2391, 0.3696, 0.0990, 0.8924],
        zoom: 0.9,
        ..Camera::default()
    }
}

/// Time one setting: frames, then isovalue edits (each rewrites the table and draws).
#[allow(clippy::too_many_arguments)]
fn measure(
    headless: &Headless,
    params: &CellprojScene,
    prepared: &Prepared,
    fidelity: Fidelity,
    kind: ProgramKind,
    camera: Camera,
    options: &Options,
) -> RenderResult<(f64, f64, arbvis_core::image::Image, Vec<f32>)> {
    let gpu = headless.gpu();
    let [w, h] = options.size;
    let target = Target::with_depth(gpu, w, h, TargetFormat::Rgba8)?;
    let mut r = CellprojRenderer::from_prepared(gpu, kind, fidelity, params, prepared.clone())?;
    let frame = Frame {
        camera,
        width: w,
        height: h,
    };
    let draw = |r: &mut CellprojRenderer| -> RenderResult<f64> {
        let t0 = Instant::now();
        target.clear(gpu, [0.0, 0.0, 0.0, 1.0])?;
        r.draw(gpu, Surface::Target(&target), &frame)?;
        gpu.finish();
        Ok(t0.elapsed().as_secs_f64() * 1e3)
    };
    draw(&mut r)?;
    let mut times = Vec::new();
    for _ in 0..options.frames.max(1) {
        times.push(draw(&mut r)?);
    }
    let mut edits = Vec::new();
    for i in 0..options.frames.max(1) {
        let mut edited = params.clone();
        edited.isovalues[0].value = 0.3 + 0.01 * (i % 5) as f64;
        let t0 = Instant::now();
        r.update(gpu, Params::of(&edited))?;
        draw(&mut r)?;
        edits.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    r.update(gpu, Params::of(&params.clone()))?;
    draw(&mut r)?;
    let image = target.read(gpu)?;
    let depth = target.read_depth(gpu)?.unwrap_or_default();
    Ok((median(&times), median(&edits), image, depth))
}

/// Run the sweep; `progress` hears one line per setting.
pub fn run(
    headless: &Headless,
    options: &Options,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<Row>> {
    let mut rows = Vec::new();
    let has_arb = headless.gpu().caps().has_arb();
    // Work per setting: its tetrahedra (frames and the reference grow with them).
    let tets_of = |points: usize| 6 * points.saturating_sub(1).pow(3) as u64;
    let bar = Bar::new(
        options.grids.iter().map(|&g| SETTINGS * tets_of(g)).sum(),
        "cell-projection study",
        Unit::Work,
    );
    for &points in &options.grids {
        // The reference of each projection, computed once per mesh (every setting of a
        // projection draws the same isosurfaces from the same camera).
        let mut references: Vec<(Projection, Vec<Option<Hit>>, Vec<bool>)> = Vec::new();
        let mesh = generate(&GridSpec {
            points: [points; 3],
            field: Field::Spherical,
        })?;
        let s = ScalarSpec::default().evaluate(&mesh)?;
        let prepared = from_mesh(&mesh, &s.values, s.name, s.range).map_err(anyhow::Error::msg)?;
        let tets = prepared.tets.len();
        let kind = if has_arb {
            ProgramKind::Arb
        } else {
            ProgramKind::Glsl
        };
        for (name, fidelity, kind, exit, projection, active_only, view_order) in sweep(kind) {
            bar.set_message(&format!("cell projection, {tets} tets: {name}"));
            let mut params = scene_for(points, exit, active_only);
            if view_order {
                params.order = super::Order::View;
                params.depth = super::Depth::Entry;
            }
            let camera = study_camera(projection);
            let (ms, edit_ms, image, depth) = measure(
                headless, &params, &prepared, fidelity, kind, camera, options,
            )?;
            let agreement_fraction = if points <= options.score_up_to {
                if !references.iter().any(|r| r.0 == projection) {
                    let hits = reference(&prepared, &params.isovalues, &camera, options.size);
                    let silhouette = silhouette_pixels(&prepared, &camera, options.size, 1.5);
                    references.push((projection, hits, silhouette));
                }
                let (_, hits, silhouette) = references
                    .iter()
                    .find(|r| r.0 == projection)
                    .expect("computed above");
                let sorted = params.sorted_isovalues();
                Some(
                    agreement(
                        &image,
                        Some(&depth),
                        hits,
                        &sorted,
                        [0.0, 0.0, 0.0, 1.0],
                        silhouette,
                    )
                    .interior_fraction(),
                )
            } else {
                None
            };
            let row = Row {
                tets,
                setting: format!("{name} {}", kind.name()),
                ms,
                edit_ms,
                agreement: agreement_fraction,
            };
            progress(&format!(
                "{:>9} tets  {:<36} {:>8.2} ms ({:>6.1} fps, {:>8.0} tets/s)  edit->frame {:>7.2} ms  {}",
                row.tets,
                row.setting,
                row.ms,
                1e3 / row.ms,
                row.tets as f64 / row.ms * 1e3,
                row.edit_ms,
                agreement_words(row.agreement, options.score_up_to)
            ));
            rows.push(row);
            bar.inc(tets_of(points));
        }
    }
    Ok(rows)
}

/// One setting of the sweep: its name, fidelity, program kind, exit, projection, whether
/// only active tetrahedra are drawn, and whether in view order.
type Setting = (
    &'static str,
    Fidelity,
    ProgramKind,
    Exit,
    Projection,
    bool,
    bool,
);

/// The settings each mesh is drawn with; `kind` is the faithful programs' (ARB where the
/// driver has it), precise is GLSL.
fn sweep(kind: ProgramKind) -> [Setting; SETTINGS as usize] {
    use Projection::{Orthographic as Ortho, Perspective as Persp};
    let (faithful, precise, glsl) = (Fidelity::Faithful, Fidelity::Precise, ProgramKind::Glsl);
    [
        (
            "seed: faithful per-vertex, all tets (ortho)",
            faithful,
            kind,
            Exit::Vertex,
            Ortho,
            false,
            false,
        ),
        (
            "seed: faithful per-fragment, all tets (persp)",
            faithful,
            kind,
            Exit::Fragment,
            Persp,
            false,
            false,
        ),
        (
            "faithful per-vertex (ortho)",
            faithful,
            kind,
            Exit::Vertex,
            Ortho,
            true,
            false,
        ),
        (
            "faithful per-fragment (ortho)",
            faithful,
            kind,
            Exit::Fragment,
            Ortho,
            true,
            false,
        ),
        (
            "faithful per-fragment (persp)",
            faithful,
            kind,
            Exit::Fragment,
            Persp,
            true,
            false,
        ),
        (
            "precise (ortho)",
            precise,
            glsl,
            Exit::Auto,
            Ortho,
            true,
            false,
        ),
        (
            "precise (persp)",
            precise,
            glsl,
            Exit::Auto,
            Persp,
            true,
            false,
        ),
        // Front to back per view, back faces dropped, entry depth (the camera
        // is still: the per-view rebuild happens once, before the timed frames).
        (
            "faithful per-vertex, view order (ortho)",
            faithful,
            kind,
            Exit::Vertex,
            Ortho,
            true,
            true,
        ),
        (
            "precise, view order (ortho)",
            precise,
            glsl,
            Exit::Auto,
            Ortho,
            true,
            true,
        ),
    ]
}

/// Settings per mesh.
const SETTINGS: u64 = 9;

/// The agreement as the progress line says it: a fraction, or why there is none.
pub fn agreement_words(agreement: Option<f64>, score_up_to: usize) -> String {
    match agreement {
        Some(a) => format!("agree {a:.4}"),
        None => format!("unscored (above --score-up-to {score_up_to} points per side)"),
    }
}

/// Plot each setting's disagreement with the reference (1 - interior agreement) against
/// its frame time, through the mesh sizes (unscored meshes are left out).
pub fn plot(rows: &[Row], path: &std::path::Path, title: &str) -> anyhow::Result<()> {
    let mut names: Vec<&str> = rows.iter().map(|r| r.setting.as_str()).collect();
    names.dedup();
    names.sort();
    names.dedup();
    let lines: Vec<(String, Vec<(f64, f64)>)> = names
        .into_iter()
        .map(|name| {
            let points = rows
                .iter()
                .filter(|r| r.setting == name)
                .filter_map(|r| Some((r.ms, 1.0 - r.agreement?)))
                .collect();
            (name.to_string(), points)
        })
        .collect();
    let chart = crate::study::Chart {
        title,
        x: "time per frame (ms)",
        y: "interior pixels with the wrong isovalue colour (fraction)",
    };
    crate::study::plot_lines(&lines, path, &chart, &[])
}

/// The rows as CSV (the setting quoted: names hold commas; an unscored agreement is an
/// empty field).
pub fn to_csv(rows: &[Row]) -> String {
    let mut s = String::from("tets,setting,ms_per_frame,fps,edit_to_frame_ms,interior_agreement\n");
    for r in rows {
        s += &format!(
            "{},\"{}\",{:.3},{:.1},{:.3},{:.5}\n",
            r.tets,
            r.setting.replace('"', "'"),
            r.ms,
            1e3 / r.ms,
            r.edit_ms,
            r.agreement.map_or(String::new(), |a| format!("{a:.5}"))
        );
    }
    s
}
