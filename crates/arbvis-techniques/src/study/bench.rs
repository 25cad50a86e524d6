//! `arbvis bench SCENE`: time any scene offscreen, and for 3D opacity score it against the
//! f64 reference and sweep the settings that trade time for accuracy.
//!
//! Each frame is timed as a user's frame costs: clear + draw + `glFinish`; the first frame
//! after a setting is (re)applied is timed apart (llvmpipe compiles shader variants on
//! first use, and slicing rebuilds its mesh). Settings are measured in turn, `rounds`
//! times over, so that a machine whose speed drifts affects them alike. Renderers are
//! built once per fidelity and path and given each setting through `Renderer::update`,
//! as the viewer does.
//!
//! Scores are over RGB only (the target's alpha is coverage, which the reference and the
//! peers define differently): the largest channel difference and the RMSE over the three
//! colour channels of every pixel. The reference (see `opacity3d::reference`) is cached
//! in the export folder, keyed by the scene text, size and oversampling.

pub use super::measured::Measured;
use super::median;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use crate::scene::Scene;
use crate::session::{Mode, Session};
use crate::techniques::cellproj::CellprojScene;
use crate::techniques::opacity3d::prepare::{prepare, Prepared};
use crate::techniques::opacity3d::reference::reference_clipped;
use crate::techniques::opacity3d::renderer::{path, preintegrated, resolve_kind, Path3d};
use crate::techniques::opacity3d::Opacity3dScene;
use crate::techniques::opacity3d::{Opacity3dRenderer, Raycast};
use crate::techniques::{Frame, Renderer};
use arbvis_core::image::Image;
use arbvis_core::progress::{Bar, Unit};
use arbvis_core::vocab::Fidelity;
use arbvis_core::vocab::TargetFormat;
use arbvis_gl::{Gpu, Headless, ProgramKind};

/// What to measure (`arbvis bench`'s options; the command line's `BenchArgs` gives their help).
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Timed frames per setting and round (after the first, timed apart).
    pub frames: usize,
    /// Passes over all settings (interleaved).
    pub rounds: usize,
    /// Score against the f64 reference (3D opacity; RMSE and largest error over RGB).
    pub score: bool,
    /// Reference steps per voxel.
    pub oversample: f64,
    /// Faithful slicing at these slice counts, e.g. 128,256.
    pub faithful: Vec<usize>,
    /// Precise slicing at these slice counts.
    pub precise: Vec<usize>,
    /// The precise ray caster at these steps per voxel, e.g. 0.5,1,2 (the scene's
    /// [technique.opacity3d.raycast] options, else the defaults).
    pub raycast: Vec<f64>,
    /// The pre-integrated ray caster (one attribute) at these steps per voxel.
    pub raycast_preint: Vec<f64>,
    /// Write the levels, tables, camera (and with --score the reference) for a peer
    /// into this folder; the reference is reused from it when the scene matches.
    pub export: Option<PathBuf>,
    /// Also time probe programs on the scene's slices: rasterization and blending, one
    /// 2D fetch (fill rate), the 3D fetch, dependent table fetches, RGBA8 / RGBA32F.
    pub breakdown: bool,
    /// Cell-projection volume settings, e.g. centroid:64,mpvonc:128,precise,projected,
    /// table:128,grid:64 (faithful with a table of N x N x N/2 texels, the precise walk,
    /// precise as a projection in MPVONC order with the exact integral per fragment or
    /// with a float table of N x N x N/2, or the mesh resampled to a grid of N points
    /// along its longest side and ray cast, grid:N:F at F steps per spacing).
    pub cellproj: Vec<String>,
    /// Turn the camera this many degrees about the vertical axis before every frame,
    /// so each frame pays for a moving view (the splats' sort and tile lists).
    pub turn: f64,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            frames: 5,
            rounds: 1,
            score: false,
            oversample: 16.0,
            faithful: Vec::new(),
            precise: Vec::new(),
            raycast: Vec::new(),
            raycast_preint: Vec::new(),
            export: None,
            breakdown: false,
            cellproj: Vec::new(),
            turn: 0.0,
        }
    }
}

impl BenchOptions {
    /// Refuse values no run can use, naming the option.
    pub fn check(&self) -> Result<()> {
        if self.frames == 0 || self.rounds == 0 {
            bail!("--frames and --rounds must be at least 1");
        }
        if !(self.turn.is_finite() && self.turn.abs() <= 360.0) {
            bail!("--turn {}: degrees, at most 360 either way", self.turn);
        }
        let o = self.oversample;
        if !(o.is_finite() && o > 0.0 && o <= 1024.0) {
            bail!("--oversample {o}: must be above 0 and at most 1024");
        }
        Ok(())
    }
}

/// A view of a scene for benches and studies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    /// The scene file's own camera.
    #[default]
    File,
    /// Orthographic, looking down the k axis (identity rotation).
    Axis,
    /// Orthographic at the `v3o2-sum` demo's rotation, zoom 0.8.
    Rotated,
    /// The same rotation in perspective (30 degrees vertical field of view), zoom 0.8.
    Perspective,
}

impl View {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            View::File => "file",
            View::Axis => "axis",
            View::Rotated => "rotated",
            View::Perspective => "perspective",
        }
    }

    /// `scene` seen this way.
    pub fn apply(self, scene: &Scene) -> Scene {
        use arbvis_core::camera::{Camera, Projection};
        let rotated = [0.326506, -0.092296, -0.701057, 0.627211];
        let mut s = scene.clone();
        match self {
            View::File => {}
            View::Axis => s.camera = Camera::default(),
            View::Rotated => {
                s.camera = Camera {
                    rotation: rotated,
                    zoom: 0.8,
                    ..Camera::default()
                }
            }
            View::Perspective => {
                s.camera = Camera {
                    projection: Projection::Perspective,
                    rotation: rotated,
                    zoom: 0.8,
                    ..Camera::default()
                }
            }
        }
        s
    }
}

/// One setting: a name and the scene that realizes it.
#[derive(Debug, Clone)]
pub struct Setting {
    /// E.g. `precise slicing 256` or `raycast 1 step/voxel`.
    pub name: String,
    /// The scene with the setting applied.
    pub scene: Scene,
}

/// The settings to measure: the scene as given when no sweep is named, else one per
/// value of each sweep (faithful, precise, ray caster, in that order).
pub fn settings(scene: &Scene, options: &BenchOptions) -> Result<Vec<Setting>> {
    let sweeping = !(options.faithful.is_empty()
        && options.precise.is_empty()
        && options.raycast.is_empty()
        && options.raycast_preint.is_empty());
    if let Some(c) = scene.technique.get::<CellprojScene>() {
        if !options.cellproj.is_empty() {
            return cellproj_settings(scene, c, &options.cellproj);
        }
    }
    let Some(base) = scene.technique.get::<Opacity3dScene>() else {
        if sweeping {
            bail!("--faithful, --precise and --raycast[-preint] sweep 3D-opacity scenes only");
        }
        return Ok(vec![Setting {
            name: format!("{} {}", scene.technique.name(), scene.fidelity.name()),
            scene: scene.clone(),
        }]);
    };
    if !sweeping {
        let name = match (path(base, scene.fidelity), &base.raycast) {
            (Path3d::Raycast, Some(r)) => raycast_name(r, scene),
            _ => format!("{} slicing {}", scene.fidelity.name(), base.slices),
        };
        return Ok(vec![Setting {
            name,
            scene: scene.clone(),
        }]);
    }
    let mut out = Vec::new();
    let mut with = |name: String,
                    fidelity: Fidelity,
                    f: &dyn Fn(&mut crate::techniques::opacity3d::Opacity3dScene)|
     -> Result<()> {
        let mut s = scene.clone();
        s.fidelity = fidelity;
        s.target = None;
        if let Some(p) = s.technique.get_mut::<Opacity3dScene>() {
            f(p);
            p.validate()
                .map_err(|e| anyhow::anyhow!("{name}: {}: {}", e.key, e.message))?;
        }
        out.push(Setting { name, scene: s });
        Ok(())
    };
    for &n in &options.faithful {
        with(format!("faithful slicing {n}"), Fidelity::Faithful, &|p| {
            p.slices = n;
            p.raycast = None;
        })?;
    }
    for &n in &options.precise {
        with(format!("precise slicing {n}"), Fidelity::Precise, &|p| {
            p.slices = n;
            p.raycast = None;
        })?;
    }
    let own = base.raycast.unwrap_or_default();
    for (list, preintegrate) in [
        (&options.raycast, own.preintegrate),
        (&options.raycast_preint, true),
    ] {
        for &steps in list {
            let r = Raycast {
                steps_per_voxel: steps,
                preintegrate,
                ..own
            };
            let mut probe = scene.clone();
            probe.fidelity = Fidelity::Precise;
            if let Some(p) = probe.technique.get_mut::<Opacity3dScene>() {
                p.raycast = Some(r);
            }
            with(raycast_name(&r, &probe), Fidelity::Precise, &|p| {
                p.raycast = Some(r);
            })?;
        }
    }
    Ok(out)
}

/// One setting per `--cellproj` name (see [`BenchOptions::cellproj`]).
fn cellproj_settings(
    scene: &Scene,
    base: &crate::techniques::cellproj::CellprojScene,
    names: &[String],
) -> Result<Vec<Setting>> {
    use crate::techniques::cellproj::transfer::Sort;
    let mut out = Vec::new();
    for name in names {
        let mut s = scene.clone();
        s.target = None;
        let mut c = base.clone();
        let mut volume = c.volume_spec();
        let (kind, size) = name.split_once(':').unwrap_or((name.as_str(), ""));
        match kind {
            "precise" | "walk" => {
                // The walk, whatever method the scene itself names.
                s.fidelity = Fidelity::Precise;
                volume.precise = crate::techniques::cellproj::transfer::Precise::Walk;
            }
            "projected" => {
                s.fidelity = Fidelity::Precise;
                volume.precise = crate::techniques::cellproj::transfer::Precise::Projected;
            }
            "table" => {
                s.fidelity = Fidelity::Precise;
                volume.precise = crate::techniques::cellproj::transfer::Precise::Table;
                let n: u32 = size
                    .parse()
                    .with_context(|| format!("--cellproj {name}: the table size after ':'"))?;
                volume.table_size = [n, (n / 2).max(2)];
            }
            "grid" => {
                s.fidelity = Fidelity::Precise;
                volume.precise = crate::techniques::cellproj::transfer::Precise::Grid;
                let (points, steps) = size.split_once(':').unwrap_or((size, "1"));
                volume.grid = points
                    .parse()
                    .with_context(|| format!("--cellproj {name}: the grid's points after ':'"))?;
                volume.grid_steps = steps.parse().with_context(|| {
                    format!("--cellproj {name}: steps per spacing after the second ':'")
                })?;
            }
            "centroid" | "mpvonc" => {
                s.fidelity = Fidelity::Faithful;
                volume.sort = if kind == "centroid" {
                    Sort::Centroid
                } else {
                    Sort::Mpvonc
                };
                let n: u32 = size
                    .parse()
                    .with_context(|| format!("--cellproj {name}: the table size after ':'"))?;
                volume.table_size = [n, (n / 2).max(2)];
            }
            _ => bail!(
                "--cellproj {name}: centroid:N, mpvonc:N, precise (the walk), projected, table:N or grid:N[:steps per spacing]"
            ),
        }
        c.volume = Some(volume);
        c.validate()
            .map_err(|e| anyhow::anyhow!("--cellproj {name}: {}: {}", e.key, e.message))?;
        s.technique = c.into();
        out.push(Setting {
            name: name.clone(),
            scene: s,
        });
    }
    Ok(out)
}

fn raycast_name(r: &Raycast, scene: &Scene) -> String {
    let pre = scene.technique.get::<Opacity3dScene>().is_some_and(|p| {
        let count = p.attributes().iter().flatten().count();
        preintegrated(p, scene.fidelity, count)
    });
    let exact = !r.jitter && !pre;
    format!(
        "raycast{}{} {} step/voxel",
        if pre { " pre-int" } else { "" },
        if exact { " exact-steps" } else { "" },
        r.steps_per_voxel
    )
}

/// A bench run.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Where the scene came from.
    pub scene: String,
    /// `GL_RENDERER`.
    pub renderer: String,
    /// `GL_VERSION`.
    pub version: String,
    /// Image size.
    pub size: [u32; 2],
    /// Timed frames per setting and round.
    pub frames: usize,
    /// Rounds.
    pub rounds: usize,
    /// Reference steps per voxel, when scored.
    pub oversample: Option<f64>,
    /// Seconds the reference took (0 when read from the cache).
    pub reference_s: Option<f64>,
    /// The settings, in the order measured.
    pub settings: Vec<Measured>,
}

/// Largest difference and RMSE over RGB between `image` and `rgb` (3 floats a pixel,
/// top row first).
pub fn rgb_error(image: &Image, rgb: &[f32]) -> (f64, f64) {
    let (mut max, mut sum) = (0f64, 0f64);
    for (p, q) in image.data.chunks_exact(4).zip(rgb.chunks_exact(3)) {
        for c in 0..3 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            max = max.max(d);
            sum += d * d;
        }
    }
    let n = (rgb.len() / 3 * 3).max(1);
    (max, (sum / n as f64).sqrt())
}

/// Which renderer a setting draws with (one per fidelity, path, programs and target).
fn slot_key(scene: &Scene, kind: ProgramKind) -> (Fidelity, bool, ProgramKind, TargetFormat) {
    let raycast = scene
        .technique
        .get::<Opacity3dScene>()
        .is_some_and(|p| path(p, scene.fidelity) == Path3d::Raycast);
    (scene.fidelity, raycast, kind, scene.target_format())
}

struct Slot {
    key: (Fidelity, bool, ProgramKind, TargetFormat),
    /// The renderer and its picture, drawn as every front end draws.
    session: Session,
}

/// Run the bench; `progress` hears a line per setting and round.
pub fn run(
    headless: &Headless,
    scene: &Scene,
    origin: &str,
    options: &BenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<Report> {
    let gpu = headless.gpu();
    refuse_stores(scene)?;
    let settings = settings(scene, options)?;
    let prepared = prepare_volume(gpu, scene, &mut progress)?;
    let volume = cellproj_volume(scene, options, &mut progress)?;
    let (reference_rgb, reference_s) = match (&prepared, &volume, options.score) {
        (Some(prepared), _, true) => {
            let (rgb, seconds) = reference_rgb(scene, prepared, options, &mut progress)?;
            (Some(rgb), Some(seconds))
        }
        (None, Some((_, rgb, seconds)), true) => (Some(rgb.clone()), Some(*seconds)),
        (None, None, true) => {
            bail!(
                "--score needs a 3D-opacity or cell-projection volume scene (their f64 references)"
            )
        }
        _ => (None, None),
    };
    if let (Some(dir), Some(prepared)) = (&options.export, &prepared) {
        super::export::write(dir, scene, prepared, options.oversample)?;
    }
    let [w, h] = scene.size;
    let frame = Frame {
        camera: scene.camera,
        width: w,
        height: h,
    };
    let mut slots: Vec<Slot> = Vec::new();
    let mut results: Vec<Option<Measured>> = vec![None; settings.len()];
    let rounds = options.rounds.max(1);
    let bar = Bar::new((settings.len() * rounds) as u64, "bench", Unit::Work);
    for round in 0..rounds {
        for (i, setting) in settings.iter().enumerate() {
            bar.set_message(&format!(
                "bench round {} of {rounds}: {}",
                round + 1,
                setting.name
            ));
            let slot = slot_for(gpu, &mut slots, &setting.scene, prepared.as_ref(), [w, h])?;
            let (first, times, picture) = time_frames(gpu, slot, &setting.scene, frame, options)?;
            let kind = slot.session.renderer().program_kind();
            let entry = results[i]
                .get_or_insert_with(|| new_measured(setting, &setting.scene, kind, first));
            if round == 0 {
                if let Some(rgb) = &reference_rgb {
                    let (max, rmse) = rgb_error(&picture, rgb);
                    entry.rmse = Some(rmse);
                    entry.max_abs = Some(max);
                }
            }
            entry.frames_ms.extend_from_slice(&times);
            progress(&format!(
                "round {} {:<28} first {:>8.1} ms, median {:>8.1} ms{}",
                round + 1,
                setting.name,
                first,
                median(&times),
                entry
                    .rmse
                    .map(|r| format!(", RMSE {r:.5}"))
                    .unwrap_or_default()
            ));
            bar.inc(1);
        }
    }
    drop(bar);
    let mut results: Vec<Measured> = results.into_iter().flatten().collect();
    if let (true, Some(prepared)) = (options.breakdown, &prepared) {
        results.extend(super::breakdown::run(
            headless,
            scene,
            prepared,
            options.frames,
            options.rounds,
            &mut progress,
        )?);
    }
    let caps = gpu.caps();
    Ok(Report {
        scene: origin.to_string(),
        renderer: caps.renderer.clone(),
        version: caps.version.clone(),
        size: scene.size,
        frames: options.frames.max(1),
        rounds: options.rounds.max(1),
        oversample: options.score.then_some(options.oversample),
        reference_s,
        settings: results.into_iter().map(summarized).collect(),
    })
}

/// A store's frames depend on what is resident: bench sweeps and scores whole volumes.
fn refuse_stores(scene: &Scene) -> Result<()> {
    if let Some(p) = scene.technique.get::<Opacity3dScene>() {
        if crate::techniques::opacity3d::bricked::store_of(p)
            .map_err(anyhow::Error::msg)?
            .is_some()
        {
            bail!(
                "bench sweeps and scores scenes whose volume is loaded whole; this scene streams a store, \
                 whose frames depend on what is resident: time it with `arbvis render SCENE --stats` (build \
                 and draw times of the full picture) or `bash benches/store/run.sh` (first picture, turning \
                 frames, memory)"
            );
        }
    }
    Ok(())
}

/// A 3D-opacity scene's volume, prepared once for every setting (timed, said).
fn prepare_volume(
    gpu: &Gpu,
    scene: &Scene,
    progress: &mut impl FnMut(&str),
) -> Result<Option<Prepared>> {
    let Some(p) = scene.technique.get::<Opacity3dScene>() else {
        return Ok(None);
    };
    let t0 = Instant::now();
    let prepared = prepare(
        p,
        &scene.base,
        &arbvis_data::volume::Limits::for_max_side(gpu.caps().max_3d_texture_size),
    )
    .map_err(anyhow::Error::msg)?;
    progress(&format!(
        "prepared the data in {:.1} s",
        t0.elapsed().as_secs_f64()
    ));
    Ok(Some(prepared))
}

/// The renderer and target setting `s` draws with: one already made for its
/// [`slot_key`], given the setting's parameters, or a new one of `w` x `h` pixels (3D
/// opacity's from the shared `prepared` volume).
fn slot_for<'a>(
    gpu: &Gpu,
    slots: &'a mut Vec<Slot>,
    s: &Scene,
    prepared: Option<&Prepared>,
    [w, h]: [u32; 2],
) -> Result<&'a mut Slot> {
    let kind = s.programs.resolve(gpu);
    let key = slot_key(s, kind);
    if let Some(n) = slots.iter().position(|x| x.key == key) {
        slots[n].session.params_changed(gpu, s)?;
        return Ok(&mut slots[n]);
    }
    let renderer: Box<dyn Renderer> = match (s.technique.get::<Opacity3dScene>(), prepared) {
        (Some(p), Some(prepared)) => Box::new(Opacity3dRenderer::from_prepared(
            gpu,
            resolve_kind(gpu, p, s.fidelity, s.programs, kind)?,
            s.fidelity,
            p,
            &s.base,
            prepared.clone(),
            s.camera.projection,
        )?),
        _ => crate::render::build(gpu, s, kind)?,
    };
    let sized = Scene {
        size: [w, h],
        ..s.clone()
    };
    slots.push(Slot {
        key,
        session: Session::new(renderer, &sized, true),
    });
    Ok(slots.last_mut().expect("just pushed"))
}

/// The first frame's time and `options.frames` more (ms) of setting `s` from `frame`,
/// each drawn whole by the slot's session (clear, draw, finish), the camera turned by
/// `options.turn` before each; and the last frame's picture.
fn time_frames(
    gpu: &Gpu,
    slot: &mut Slot,
    s: &Scene,
    frame: Frame,
    options: &BenchOptions,
) -> Result<(f64, Vec<f64>, Image)> {
    let turn = glam::DQuat::from_rotation_y(options.turn.to_radians());
    let mut scene = Scene {
        size: [frame.width, frame.height],
        camera: frame.camera,
        ..s.clone()
    };
    let mut one = |scene: &mut Scene| -> Result<f64> {
        if options.turn != 0.0 {
            scene.camera.rotation = (scene.camera.quat() * turn).to_array();
        }
        slot.session.redraw();
        let t0 = Instant::now();
        slot.session.frame(gpu, scene, Mode::Now)?;
        Ok(t0.elapsed().as_secs_f64() * 1e3)
    };
    let first = one(&mut scene)?;
    let mut times = Vec::with_capacity(options.frames);
    for _ in 0..options.frames.max(1) {
        times.push(one(&mut scene)?);
    }
    arbvis_gl::gl_check!(gpu)?;
    let picture = slot.session.read(
        gpu,
        &Scene {
            legend: false,
            axes: false,
            ..scene
        },
    )?;
    Ok((first, times, picture))
}

/// A setting's median, fastest and slowest frame from its times.
fn summarized(mut m: Measured) -> Measured {
    m.median_ms = median(&m.frames_ms);
    m.min_ms = m.frames_ms.iter().copied().fold(f64::INFINITY, f64::min);
    m.max_ms = m.frames_ms.iter().copied().fold(0.0, f64::max);
    m
}

fn new_measured(setting: &Setting, s: &Scene, kind: ProgramKind, first: f64) -> Measured {
    let (path, slices, steps) = match s.technique.get::<Opacity3dScene>() {
        Some(p) => match path(p, s.fidelity) {
            Path3d::Raycast => ("raycast", None, p.raycast.map(|r| r.steps_per_voxel)),
            Path3d::Slicing => ("slicing", Some(p.slices), None),
        },
        None => ("", None, None),
    };
    Measured {
        technique: s.technique.name().to_string(),
        fidelity: s.fidelity.name().to_string(),
        path: path.to_string(),
        slices,
        steps_per_voxel: steps,
        programs: kind.name().to_string(),
        target: s.target_format().name().to_string(),
        ..Measured::untimed(setting.name.clone(), first)
    }
}

/// For a cell-projection volume scene scored or exported: the prepared mesh, the
/// reference's RGB and the seconds it took (the export written when asked).
fn cellproj_volume(
    scene: &Scene,
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<
    Option<(
        crate::techniques::cellproj::prepare::Prepared,
        Vec<f32>,
        f64,
    )>,
> {
    let Some(c) = scene.technique.get::<CellprojScene>() else {
        return Ok(None);
    };
    if !c.mode.volume() || !(options.score || options.export.is_some()) {
        return Ok(None);
    }
    let prepared = crate::techniques::cellproj::prepare::prepare(c, &scene.base)
        .map_err(anyhow::Error::msg)?;
    let spec = c.volume_spec();
    let tf = spec
        .build(&scene.base, prepared.scale)
        .map_err(anyhow::Error::msg)?;
    let isos = if c.mode == crate::techniques::cellproj::Mode::Both {
        c.normalized(prepared.scalar_range).isovalues
    } else {
        Vec::new()
    };
    let t0 = Instant::now();
    let image = crate::techniques::cellproj::volume_reference::reference(
        &prepared,
        &tf,
        &isos,
        &scene.camera,
        scene.size,
        scene.background.map(|v| v as f64),
    );
    let seconds = t0.elapsed().as_secs_f64();
    progress(&format!("volume reference in {seconds:.1} s"));
    let rgb: Vec<f32> = image
        .data
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    if let Some(dir) = &options.export {
        super::export::write_cellproj(dir, scene, &prepared, &tf, &rgb)?;
    }
    Ok(Some((prepared, rgb, seconds)))
}

/// What identifies a cached reference.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct ReferenceKey {
    scene: String,
    size: [u32; 2],
    oversample: f64,
}

fn reference_key(scene: &Scene, oversample: f64) -> ReferenceKey {
    // The key ignores what does not change the integral: fidelity, programs, target,
    // slices and the path.
    let mut s = scene.clone();
    s.fidelity = Fidelity::Precise;
    s.target = None;
    s.programs = Default::default();
    if let Some(p) = s.technique.get_mut::<Opacity3dScene>() {
        p.slices = 1;
        p.raycast = None;
        p.opacity_correction = None;
    }
    ReferenceKey {
        scene: s.with_absolute_paths().to_toml(),
        size: scene.size,
        oversample,
    }
}

/// The reference's RGB (from the export folder's cache when its key matches), and the
/// seconds it took to compute (0 when cached).
fn reference_rgb(
    scene: &Scene,
    prepared: &Prepared,
    options: &BenchOptions,
    progress: &mut impl FnMut(&str),
) -> Result<(Vec<f32>, f64)> {
    let key = reference_key(scene, options.oversample);
    let [w, h] = scene.size;
    let bytes = w as u64 * h as u64 * 12;
    if let Some(dir) = &options.export {
        if let Some(rgb) = read_cached(dir, &key, bytes) {
            progress("reference read from the export folder's cache");
            return Ok((rgb, 0.0));
        }
    }
    let Some(params) = scene.technique.get::<Opacity3dScene>() else {
        bail!("--score needs a 3D-opacity scene");
    };
    let t0 = Instant::now();
    // A clipped scene is scored against the integral inside the analytic clip object.
    let clip = match &params.clip {
        Some(clip) => Some(
            clip.shape(&scene.base, prepared.half.to_array())
                .context("building the clip shape for the reference")?,
        ),
        None => None,
    };
    let image = reference_clipped(
        prepared,
        params,
        &scene.camera,
        scene.size,
        scene.background.map(|v| v as f64),
        options.oversample,
        |x| clip.as_ref().is_none_or(|c| c.inside(x)),
    );
    let seconds = t0.elapsed().as_secs_f64();
    progress(&format!(
        "reference ({} steps per voxel) in {seconds:.1} s",
        options.oversample
    ));
    let rgb: Vec<f32> = image
        .data
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    if let Some(dir) = &options.export {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let raw: Vec<u8> = rgb.iter().flat_map(|v| v.to_le_bytes()).collect();
        arbvis_core::png_io::write_atomic(&dir.join("reference.f32"), &raw)?;
        arbvis_core::png_io::write_atomic(
            &dir.join("reference.toml"),
            toml::to_string(&key)?.as_bytes(),
        )?;
    }
    Ok((rgb, seconds))
}

fn read_cached(dir: &Path, key: &ReferenceKey, bytes: u64) -> Option<Vec<f32>> {
    let text = arbvis_core::input::read_text(
        &dir.join("reference.toml"),
        arbvis_core::input::MAX_SCENE_BYTES,
    )
    .ok()?;
    let stored: ReferenceKey = toml::from_str(&text).ok()?;
    if &stored != key {
        return None;
    }
    let raw = arbvis_core::input::read_regular(&dir.join("reference.f32"), bytes).ok()?;
    (raw.len() as u64 == bytes).then(|| {
        raw.chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    })
}

/// The report as text: a header and a line per setting.
pub fn to_text(report: &Report) -> String {
    let mut s = format!(
        "{} at {}x{} on {} ({}), {} frames x {} rounds per setting\n",
        report.scene,
        report.size[0],
        report.size[1],
        report.renderer,
        report.version,
        report.frames,
        report.rounds
    );
    s += &format!(
        "{:<52} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}\n",
        "setting", "first ms", "median", "min", "max", "RMSE", "max err"
    );
    for m in &report.settings {
        let score = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.5}"));
        s += &format!(
            "{:<52} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9} {:>9}\n",
            m.name,
            m.first_ms,
            m.median_ms,
            m.min_ms,
            m.max_ms,
            score(m.rmse),
            score(m.max_abs)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_error_ignores_alpha_and_counts_three_channels() {
        let image = Image {
            width: 2,
            height: 1,
            format: TargetFormat::Rgba32f,
            data: vec![0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 0.25, 0.0],
        };
        let (max, rmse) = rgb_error(&image, &[0.5, 0.5, 0.5, 0.0, 0.0, 0.0]);
        assert_eq!(max, 0.25);
        assert!((rmse - (0.0625f64 / 6.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn sweeps_make_one_setting_per_value() {
        let scene = Scene::demo("v3o2-sum").unwrap();
        let options = BenchOptions {
            faithful: vec![64],
            precise: vec![128, 256],
            raycast: vec![0.5],
            raycast_preint: vec![2.0],
            ..Default::default()
        };
        let s = settings(&scene, &options).unwrap();
        let names: Vec<&str> = s.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "faithful slicing 64",
                "precise slicing 128",
                "precise slicing 256",
                "raycast 0.5 step/voxel",
                // v3o2-sum has three attributes and pre-integration takes one: the name
                // says what is drawn.
                "raycast 2 step/voxel"
            ]
        );
        assert_eq!(s[0].scene.fidelity, Fidelity::Faithful);
        assert_eq!(s[3].scene.fidelity, Fidelity::Precise);
        // A bad value is named.
        let bad = BenchOptions {
            precise: vec![0],
            ..Default::default()
        };
        let e = settings(&scene, &bad).unwrap_err().to_string();
        assert!(
            e.contains("precise slicing 0") && e.contains("slices"),
            "{e}"
        );
        // Other techniques take no sweep.
        let quad = Scene::demo("quad").unwrap();
        assert!(settings(&quad, &options).is_err());
        assert_eq!(settings(&quad, &BenchOptions::default()).unwrap().len(), 1);
        assert_eq!(median(&[3.0, 1.0, 2.0, 10.0]), 2.5);
    }
}
