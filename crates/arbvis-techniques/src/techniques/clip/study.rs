//! The trade of volume clipping, measured (`arbvis study --technique clip`): for each
//! volume size, shape and block size B, what the INDEX-DATA texture costs in bytes against
//! the single-resolution texture (the seed's compression ratio), how long each takes to
//! build, and, on the GPU, the frame time of the clipped 3D-opacity scene with no clip, the
//! single texture and INDEX-DATA at each B, each clipped frame's RMSE against the f64
//! reference clipped by the analytic shape, and the largest difference between the
//! INDEX-DATA and the single-texture images. [`plot`] draws RMSE against time. The
//! unclipped frame has no error (it draws another picture) and the single texture no
//! difference from itself: those fields are empty in the CSV and said in words in the
//! lines (they once printed as NaN).
//!
//! Shapes: the sphere of radius 0.35 N at the volume's centre; a torus generated as
//! a closed triangle mesh (1,152 triangles, tilted, so its surface cuts blocks at every
//! angle); and `cow.obj` (5,804 triangles) from the project's `data/surfaces/`. The
//! texture sweep adds an *open* mesh, the upper half of a finer torus's tube (4,608
//! triangles, open along the whole ring), whose unbalanced rows the fast winding number
//! decides: its "built in" time is the open-mesh clip's cost at each grid size.
//! Bytes: single-resolution and DATA one byte per texel (R8, the era's LUMINANCE8), INDEX
//! 16 (RGBA32F: the slot coordinates need more than 8 bits, see [`super::multires`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;

use super::mesh_field::MeshShape;
use super::multires::{MultiRes, TexelFormat};
use super::shape::Shape;
use super::texture::{ClipGrid, ClipTexture};
use super::{ClipError, ClipSpec, ShapeSpec};
use crate::scene::Scene;
use crate::techniques::opacity3d::prepare::prepare;
use crate::techniques::opacity3d::reference::reference_clipped;
use crate::techniques::opacity3d::Opacity3dScene;
use crate::techniques::Frame;
use crate::techniques::Params;
use arbvis_core::progress::{Bar, Unit};
use arbvis_data::volume::Limits;
use arbvis_data::volume::VolumeSource;
use arbvis_gl::{Headless, Surface, Target};

/// What to sweep.
#[derive(Debug, Clone)]
pub struct Options {
    /// Clip grid sides for the texture sweep (the issue's: 256 and 512).
    pub sizes: Vec<usize>,
    /// Block sides B.
    pub blocks: Vec<usize>,
    /// Side of the synthetic volume drawn for the frame times (the clip grid follows it).
    pub frame_volume: usize,
    /// Image side for the frame times.
    pub image: u32,
    /// Timed frames per setting (median), after one warm-up frame.
    pub frames: usize,
    /// Steps per voxel of the f64 reference the frames are scored against.
    pub oversample: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            sizes: vec![256, 512],
            blocks: vec![4, 8, 16, 32],
            frame_volume: 256,
            image: 512,
            frames: 3,
            oversample: 4.0,
        }
    }
}

/// One texture measurement: a shape at a size, single resolution (`block` None) or
/// INDEX-DATA with block side `block`.
#[derive(Debug, Clone)]
pub struct TextureRow {
    /// Clip grid side.
    pub n: usize,
    /// Shape name.
    pub shape: String,
    /// Block side, or None for the single-resolution texture.
    pub block: Option<usize>,
    /// Boundary blocks (DATA slots).
    pub boundary_blocks: usize,
    /// Blocks in all.
    pub blocks: usize,
    /// INDEX bytes (RGBA32F), 0 for single resolution.
    pub index_bytes: usize,
    /// DATA (or single-resolution) bytes, one per texel.
    pub data_bytes: usize,
    /// `(INDEX + DATA) / single`.
    pub ratio: f64,
    /// Build seconds (the single texture's distance field, or the INDEX-DATA split).
    pub build_seconds: f64,
}

/// One frame measurement.
#[derive(Debug, Clone)]
pub struct FrameRow {
    /// Setting: `no clip`, `single`, `INDEX-DATA B=8`, ...
    pub setting: String,
    /// Median milliseconds per frame (clear + draw + finish).
    pub ms: f64,
    /// RMSE of RGB against the f64 reference of the clipped volume (None for `no clip`,
    /// which draws another picture: the whole volume).
    pub rmse: Option<f64>,
    /// Largest channel difference against the single-texture image, in 1/255 levels
    /// (None for `no clip` and for the single texture itself, the comparison's baseline).
    pub levels_from_single: Option<f64>,
}

impl FrameRow {
    /// The row's errors as the progress line says them: numbers, or why there are none.
    pub fn words(&self) -> String {
        let rmse = self
            .rmse
            .map_or("no RMSE (unclipped: another picture)".into(), |r| {
                format!("RMSE {r:.5}")
            });
        let levels = match (self.levels_from_single, self.setting.as_str()) {
            (Some(l), _) => format!("{l:.1} levels from the single texture"),
            (None, "single") => "(the single texture: the baseline of INDEX-DATA)".into(),
            (None, _) => "(not compared with the single texture)".into(),
        };
        format!("{rmse}  {levels}")
    }
}

/// The shapes of the sweep; `base` resolves `cow.obj`.
pub fn shapes() -> Vec<(String, ShapeSpec, PathBuf)> {
    let mut out = vec![
        (
            "sphere r = 0.35 N".to_string(),
            ShapeSpec::Sphere {
                center: [0.0; 3],
                radius: 0.7,
            },
            PathBuf::from("."),
        ),
        (
            "torus mesh".to_string(),
            ShapeSpec::TorusMesh {
                center: [0.05, -0.03, 0.02],
                major_radius: 0.55,
                minor_radius: 0.22,
                rotation: [35.0, 20.0, 0.0],
                segments: [48, 12],
            },
            PathBuf::from("."),
        ),
    ];
    let cow = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/surfaces/cow.obj");
    if cow.is_file() {
        out.push((
            "cow.obj".to_string(),
            ShapeSpec::Mesh {
                path: cow,
                // The cow spans x in [-4.4, 6.0]: scaled by 0.17 and centred it fills
                // most of the box [-1, 1]³.
                position: [-0.132, 0.075, 0.0],
                scale: 0.17,
                rotation: [0.0; 3],
            },
            PathBuf::from("."),
        ));
    }
    out
}

/// The open mesh of the texture sweep: the triangles of a tilted torus's tube above its
/// plane (4,608 of 9,216), open along the whole ring.
pub fn open_half_torus() -> Result<Shape, ClipError> {
    let torus = super::scene::torus(0.55, 0.22, [96, 48])?;
    let mut half = torus.clone();
    half.triangles.retain(|t| {
        t.iter()
            .map(|&i| torus.vertices[i as usize][2])
            .sum::<f64>()
            > 0.0
    });
    Ok(Shape::Mesh(Box::new(MeshShape::new(
        &half,
        DVec3::new(0.05, -0.03, 0.02),
        DVec3::ONE,
        glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.6, 0.35, 0.0),
    ))))
}

/// The texture sweep (CPU only); `progress` hears one line per row.
pub fn textures(
    options: &Options,
    max_3d_texture_size: usize,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<TextureRow>> {
    let mut rows = Vec::new();
    // Work: texels of each shape's grid, once for the single texture and once per B.
    let shapes_count = shapes().len() as u64 + 1;
    let per_size = shapes_count * (1 + options.blocks.len() as u64);
    let bar = Bar::new(
        options
            .sizes
            .iter()
            .map(|&n| per_size * (n as u64).pow(3))
            .sum(),
        "clip study, textures (1 of 2)",
        Unit::Work,
    );
    for &n in &options.sizes {
        bar.set_message(&format!("clip study, textures at {n}³ (1 of 2)"));
        let mut built = Vec::new();
        for (name, shape, base) in shapes() {
            let spec = ClipSpec {
                shape,
                invert: false,
                block: 8,
                multires: false,
                resolution: None,
            };
            built.push((name, spec.shape(&base, [1.0; 3])?));
        }
        built.push(("open half-torus mesh".to_string(), open_half_torus()?));
        for (name, built) in built {
            let grid = ClipGrid::new([n; 3], [1.0; 3])?;
            let single = ClipTexture::build(&built, &grid);
            let texels = n * n * n;
            let mut push = |row: TextureRow| {
                progress(&format!(
                    "{:>4}³ {:<18} {:<12} {:>6} of {:>8} blocks boundary  INDEX {:>10} B  DATA {:>11} B  ratio {:.3}  built in {:.3} s",
                    row.n,
                    row.shape,
                    row.block.map_or("single".into(), |b| format!("B = {b}")),
                    row.boundary_blocks,
                    row.blocks,
                    row.index_bytes,
                    row.data_bytes,
                    row.ratio,
                    row.build_seconds
                ));
                rows.push(row);
                bar.inc((n as u64).pow(3));
            };
            push(TextureRow {
                n,
                shape: name.clone(),
                block: None,
                boundary_blocks: 0,
                blocks: 0,
                index_bytes: 0,
                data_bytes: texels,
                ratio: 1.0,
                build_seconds: single.build_seconds,
            });
            for &b in &options.blocks {
                let t0 = Instant::now();
                let m = MultiRes::build(&single, b, max_3d_texture_size)?;
                let build_seconds = t0.elapsed().as_secs_f64();
                let (index_bytes, data_bytes) = m.bytes(TexelFormat::Rgba32F, TexelFormat::R8);
                push(TextureRow {
                    n,
                    shape: name.clone(),
                    block: Some(b),
                    boundary_blocks: m.slots,
                    blocks: m.classes.len(),
                    index_bytes,
                    data_bytes,
                    ratio: m.compression_ratio(
                        TexelFormat::Rgba32F,
                        TexelFormat::R8,
                        TexelFormat::R8,
                    ),
                    build_seconds,
                });
            }
        }
    }
    Ok(rows)
}

/// The scene the frame times draw: the three attributes of `scenes/bench/clip-sphere-study.toml`
/// (the `clip-sphere` demo as the README's numbers were measured) on a synthetic cube of
/// `options.frame_volume`³, `options.image`² pixels, clipped (keeping the inside) by the
/// issue's sphere.
pub fn frame_scene(options: &Options) -> anyhow::Result<Scene> {
    let mut scene = Scene::parse(
        include_str!("../../../../../scenes/bench/clip-sphere-study.toml"),
        "scenes/bench/clip-sphere-study.toml",
    )?;
    scene.size = [options.image; 2];
    let Some(p) = scene.technique.get_mut::<Opacity3dScene>() else {
        anyhow::bail!("the clip study scene is not a 3D-opacity scene");
    };
    let n = options.frame_volume;
    for a in [
        Some(&mut p.primary),
        p.secondary.as_mut(),
        p.tertiary.as_mut(),
    ]
    .into_iter()
    .flatten()
    {
        if let VolumeSource::Synthetic(s) = &mut a.volume {
            s.size = [n; 3];
        }
    }
    p.clip = Some(ClipSpec {
        shape: shapes().remove(0).1,
        invert: false,
        block: 8,
        multires: true,
        resolution: None,
    });
    Ok(scene)
}

/// The frame sweep (GPU): no clip, the single texture, INDEX-DATA at each B.
pub fn frames(
    headless: &Headless,
    options: &Options,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<Vec<FrameRow>> {
    let gpu = headless.gpu();
    let scene = frame_scene(options)?;
    let kind = scene.programs.resolve(gpu);
    let mut renderer = crate::render::build(gpu, &scene, kind)?;
    let [w, h] = scene.size;
    let target = Target::create(gpu, w, h, scene.target_format(), renderer.needs_depth())?;
    let frame = Frame {
        camera: scene.camera,
        width: w,
        height: h,
    };
    let Some(base) = scene.technique.get::<Opacity3dScene>() else {
        unreachable!("frame_scene makes a 3D-opacity scene");
    };
    let mut settings: Vec<(String, Option<ClipSpec>)> = vec![("no clip".into(), None)];
    let clip = base.clip.clone().expect("frame_scene sets a clip");
    settings.push((
        "single".into(),
        Some(ClipSpec {
            multires: false,
            ..clip.clone()
        }),
    ));
    for &b in &options.blocks {
        settings.push((
            format!("INDEX-DATA B = {b}"),
            Some(ClipSpec {
                block: b,
                multires: true,
                ..clip.clone()
            }),
        ));
    }
    let reference = reference_rgb(headless, &scene, options.oversample, &mut progress)?;
    let bar = Bar::new(
        settings.len() as u64,
        "clip study, frames (2 of 2)",
        Unit::Work,
    );
    let mut rows = Vec::new();
    let mut single_image = None;
    for (name, clip) in settings {
        bar.set_message(&format!("clip study, frames (2 of 2): {name}"));
        let clipped = clip.is_some();
        let mut p = base.clone();
        p.clip = clip;
        renderer.update(gpu, Params::of(&p))?;
        let mut times = Vec::new();
        for i in 0..=options.frames.max(1) {
            let t0 = Instant::now();
            target.clear(gpu, scene.clear_colour())?;
            renderer.draw(gpu, Surface::Target(&target), &frame)?;
            gpu.finish();
            if i > 0 {
                times.push(t0.elapsed().as_secs_f64() * 1e3);
            }
        }
        times.sort_by(f64::total_cmp);
        let image = target.read(gpu)?;
        let levels = match (&single_image, name.starts_with("INDEX")) {
            (Some(single), true) => Some(
                image
                    .compare(single, 0.0)
                    .map_or(f64::INFINITY, |d| d.max_abs * 255.0),
            ),
            _ => None,
        };
        let rmse = clipped.then(|| crate::study::bench::rgb_error(&image, &reference).1);
        if name == "single" {
            single_image = Some(image);
        }
        let row = FrameRow {
            setting: name,
            ms: times[times.len() / 2],
            rmse,
            levels_from_single: levels,
        };
        progress(&format!(
            "{:<18} {:>9.1} ms/frame  {}",
            row.setting,
            row.ms,
            row.words()
        ));
        rows.push(row);
        bar.inc(1);
    }
    Ok(rows)
}

/// The f64 reference of the frame scene, clipped by the analytic shape (RGB, 3 floats a
/// pixel, top row first).
fn reference_rgb(
    headless: &Headless,
    scene: &Scene,
    oversample: f64,
    progress: &mut impl FnMut(&str),
) -> anyhow::Result<Vec<f32>> {
    let Some(params) = scene.technique.get::<Opacity3dScene>() else {
        anyhow::bail!("the clip study scene is not a 3D-opacity scene");
    };
    let t0 = Instant::now();
    let limits = Limits::for_max_side(headless.gpu().caps().max_3d_texture_size);
    let prepared = prepare(params, &scene.base, &limits).map_err(anyhow::Error::msg)?;
    let spec = params.clip.as_ref().expect("frame_scene sets a clip");
    let shape = spec.shape(&scene.base, prepared.half.to_array())?;
    let image = reference_clipped(
        &prepared,
        params,
        &scene.camera,
        scene.size,
        scene.background.map(f64::from),
        oversample,
        |x| shape.inside(x),
    );
    progress(&format!(
        "clipped f64 reference ({oversample} steps per voxel) in {:.1} s",
        t0.elapsed().as_secs_f64()
    ));
    Ok(image
        .data
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect())
}

/// Plot the frames' RMSE against their time: the single texture and INDEX-DATA through
/// its block sides, with the unclipped frame's time as a vertical line.
pub fn plot(frames: &[FrameRow], path: &Path, title: &str) -> anyhow::Result<()> {
    let of = |pick: &dyn Fn(&FrameRow) -> bool| -> Vec<(f64, f64)> {
        frames
            .iter()
            .filter(|r| pick(r))
            .filter_map(|r| Some((r.ms, r.rmse?)))
            .collect()
    };
    let lines = vec![
        ("single texture".to_string(), of(&|r| r.setting == "single")),
        (
            "INDEX-DATA, block sides B".to_string(),
            of(&|r| r.setting.starts_with("INDEX")),
        ),
    ];
    let verticals: Vec<(f64, String)> = frames
        .iter()
        .filter(|r| r.rmse.is_none())
        .map(|r| (r.ms, format!("{} ({:.1} ms)", r.setting, r.ms)))
        .collect();
    let chart = crate::study::Chart {
        title,
        x: "time per frame (ms)",
        y: "RMSE of RGB against the clipped f64 reference",
    };
    crate::study::plot_lines(&lines, path, &chart, &verticals)
}

/// Both sweeps as CSV text: textures, then frames.
pub fn to_csv(textures: &[TextureRow], frames: &[FrameRow]) -> (String, String) {
    let mut t = String::from(
        "n,shape,block,boundary_blocks,blocks,index_bytes,data_bytes,ratio,build_seconds\n",
    );
    for r in textures {
        t += &format!(
            "{},\"{}\",{},{},{},{},{},{:.4},{:.4}\n",
            r.n,
            r.shape,
            r.block.map_or("single".into(), |b| b.to_string()),
            r.boundary_blocks,
            r.blocks,
            r.index_bytes,
            r.data_bytes,
            r.ratio,
            r.build_seconds
        );
    }
    // Unmeasured errors are empty fields (see [`FrameRow`] for why).
    let cell = |v: Option<f64>, digits: usize| v.map_or(String::new(), |v| format!("{v:.digits$}"));
    let mut f = String::from("setting,ms_per_frame,rmse,levels_from_single\n");
    for r in frames {
        f += &format!(
            "\"{}\",{:.3},{},{}\n",
            r.setting,
            r.ms,
            cell(r.rmse, 6),
            cell(r.levels_from_single, 2)
        );
    }
    (t, f)
}
