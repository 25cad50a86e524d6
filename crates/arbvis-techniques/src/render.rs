//! Offscreen rendering of a scene: context, renderer, target, one frame, read back.

use crate::error::RenderResult;
use std::time::{Duration, Instant};

use crate::gl::{Backend, Caps, Headless, ProgramKind, Resource, Surface, Target};
use crate::image::Image;
use crate::scene::Scene;
use crate::techniques::{Frame, Renderer};

/// One rendered scene and what made it.
pub struct Rendered {
    /// The frame as the target holds it, top row first (alpha is coverage); see
    /// [`Scene::picture`] for what a picture file shows.
    pub image: Image,
    /// The program kind that drew it.
    pub program_kind: ProgramKind,
    /// The backend that drew it.
    pub backend: Backend,
    /// The driver.
    pub caps: Caps,
    /// Every GL resource created, with its bytes.
    pub resources: Vec<Resource>,
    /// Time to build the renderer (programs, uploads).
    pub build_time: Duration,
    /// Time to draw and finish the frame.
    pub draw_time: Duration,
    /// The renderer's own line about the frame (a store's resident bricks, levels, bytes).
    pub status: Option<String>,
}

impl Rendered {
    /// PNG text chunks: scene, program kind, fidelity, renderer.
    pub fn png_text(&self, scene: &Scene, origin: &str) -> Vec<(&'static str, String)> {
        vec![
            ("Software", format!("arbvis {}", env!("CARGO_PKG_VERSION"))),
            ("arbvis:scene-origin", origin.to_string()),
            ("arbvis:scene", scene.to_toml()),
            ("arbvis:technique", scene.technique.name().to_string()),
            ("arbvis:programs", self.program_kind.name().to_string()),
            ("arbvis:fidelity", scene.fidelity.name().to_string()),
            ("arbvis:target", scene.target_format().name().to_string()),
            ("arbvis:backend", self.backend.name().to_string()),
            (
                "arbvis:renderer",
                format!(
                    "{} | {} | {}",
                    self.caps.vendor, self.caps.renderer, self.caps.version
                ),
            ),
        ]
    }
}

/// Build the renderer `scene` names, with programs of `kind`; nothing else is created.
pub fn build(
    gpu: &crate::gl::Gpu,
    scene: &Scene,
    kind: ProgramKind,
) -> RenderResult<Box<dyn Renderer>> {
    crate::catalog::build(gpu, &scene.technique, &scene.settings(), kind)
}

/// Render `scene` offscreen on `backend`.
pub fn render(scene: &Scene, backend: Backend) -> RenderResult<Rendered> {
    let headless = Headless::new(backend)?;
    render_on(&headless, scene)
}

/// Render `scene` with an existing context.
pub fn render_on(headless: &Headless, scene: &Scene) -> RenderResult<Rendered> {
    let gpu = headless.gpu();
    let kind = scene.programs.resolve(gpu);
    let [width, height] = scene.size;
    crate::budget::check_estimates(
        &format!("this {} scene", scene.technique.name()),
        &scene.memory_estimate(true),
    )?;
    let t0 = Instant::now();
    let mut renderer = build(gpu, scene, kind)?;
    let target = Target::create(
        gpu,
        width,
        height,
        scene.target_format(),
        renderer.needs_depth(),
    )?;
    gpu.finish();
    let build_time = t0.elapsed();
    let t1 = Instant::now();
    draw_frame(gpu, &mut *renderer, &target, scene)?;
    let draw_time = t1.elapsed();
    let image = read_frame(gpu, &*renderer, &target, scene)?;
    Ok(Rendered {
        image,
        program_kind: renderer.program_kind(),
        backend: headless.backend(),
        caps: gpu.caps().clone(),
        resources: gpu.resources(),
        build_time,
        draw_time,
        status: renderer.status(),
    })
}

/// A scene kept ready to draw frame after frame (the Python `Renderer`): its context,
/// renderer and target. A changed camera, size, background or technique parameter costs
/// a frame (the renderer takes new parameters through [`Renderer::update`]); another
/// technique, fidelity, program choice, target format or data folder a new renderer.
pub struct Session {
    headless: Headless,
    scene: Scene,
    renderer: Box<dyn Renderer>,
    target: Target,
}

impl Session {
    /// A context on `backend` and `scene`'s renderer.
    pub fn new(scene: &Scene, backend: Backend) -> RenderResult<Session> {
        let headless = Headless::new(backend)?;
        let (renderer, target) = Session::build(&headless, scene)?;
        Ok(Session {
            headless,
            scene: scene.clone(),
            renderer,
            target,
        })
    }

    fn build(headless: &Headless, scene: &Scene) -> RenderResult<(Box<dyn Renderer>, Target)> {
        let gpu = headless.gpu();
        crate::budget::check_estimates(
            &format!("this {} scene", scene.technique.name()),
            &scene.memory_estimate(true),
        )?;
        let renderer = build(gpu, scene, scene.programs.resolve(gpu))?;
        let [width, height] = scene.size;
        let format = scene.target_format();
        let target = Target::create(gpu, width, height, format, renderer.needs_depth())?;
        Ok((renderer, target))
    }

    /// Draw `scene` (what changed since the last frame applied first), as the target
    /// holds it: top row first, alpha is coverage.
    pub fn render(&mut self, scene: &Scene) -> RenderResult<Image> {
        let old = &self.scene;
        let same_renderer = old.technique.name() == scene.technique.name()
            && old.fidelity == scene.fidelity
            && old.programs == scene.programs
            && old.target_format() == scene.target_format()
            && old.base == scene.base;
        if !same_renderer {
            (self.renderer, self.target) = Session::build(&self.headless, scene)?;
        } else {
            let gpu = self.headless.gpu();
            if old.technique != scene.technique {
                self.renderer.update(gpu, scene.technique.params())?;
            }
            if old.size != scene.size {
                let [width, height] = scene.size;
                let depth = self.renderer.needs_depth();
                self.target = Target::create(gpu, width, height, scene.target_format(), depth)?;
            }
        }
        self.scene = scene.clone();
        let gpu = self.headless.gpu();
        draw_frame(gpu, &mut *self.renderer, &self.target, scene)?;
        read_frame(gpu, &*self.renderer, &self.target, scene)
    }

    /// The program kind the renderer draws with.
    pub fn program_kind(&self) -> ProgramKind {
        self.renderer.program_kind()
    }

    /// The backend drawing.
    pub fn backend(&self) -> Backend {
        self.headless.backend()
    }

    /// The driver.
    pub fn caps(&self) -> &Caps {
        self.headless.gpu().caps()
    }
}

/// One frame of `scene` by `renderer` on `target`: cleared, drawn and finished.
fn draw_frame(
    gpu: &crate::gl::Gpu,
    renderer: &mut dyn Renderer,
    target: &Target,
    scene: &Scene,
) -> RenderResult<()> {
    target.clear(gpu, scene.clear_colour())?;
    let frame = Frame {
        camera: scene.camera,
        width: scene.size[0],
        height: scene.size[1],
    };
    renderer.draw(gpu, Surface::Target(target), &frame)?;
    arbvis_gl::gl_check!(gpu)?;
    gpu.finish();
    Ok(())
}

/// The frame on `target` read back, with the legends and axes `scene` asks for drawn in.
fn read_frame(
    gpu: &crate::gl::Gpu,
    renderer: &dyn Renderer,
    target: &Target,
    scene: &Scene,
) -> RenderResult<Image> {
    let mut image = target.read(gpu)?;
    let show = crate::annotate::Show {
        legend: scene.legend,
        axes: scene.axes,
    };
    if show.legend || show.axes {
        crate::annotate::draw(&mut image, &scene.camera, &renderer.annotations(), show)?;
    }
    Ok(image)
}

/// What `arbvis render` prints after writing `output`: the line that says so, and with
/// `stats` the resources, the renderer's status and the timings.
pub fn report_text(
    rendered: &Rendered,
    scene: &Scene,
    output: &std::path::Path,
    stats: bool,
) -> String {
    let mut s = format!(
        "wrote {} ({}x{}, {} programs, {} target, {} on {})\n",
        output.display(),
        scene.size[0],
        scene.size[1],
        rendered.program_kind.name(),
        scene.target_format().name(),
        rendered.caps.renderer,
        rendered.backend.name()
    );
    if stats {
        s += &format_stats(&rendered.resources);
        if let Some(status) = &rendered.status {
            s += &format!("{status}\n");
        }
        s += &format!(
            "build {:.3} ms, draw {:.3} ms\n",
            rendered.build_time.as_secs_f64() * 1e3,
            rendered.draw_time.as_secs_f64() * 1e3
        );
    }
    s
}

/// [`report_text`] as one JSON object (`render --json`): `output`, `size`, `programs`,
/// `target`, `fidelity`, `technique`, `renderer`, `backend`, and with `stats` also
/// `resources` (kind, label, bytes each), `resource_bytes`, `status`, `build_ms` and
/// `draw_ms`.
pub fn report_json(
    rendered: &Rendered,
    scene: &Scene,
    output: &std::path::Path,
    stats: bool,
) -> String {
    let mut report = serde_json::json!({
        "output": output.display().to_string(),
        "size": scene.size,
        "programs": rendered.program_kind.name(),
        "target": scene.target_format().name(),
        "fidelity": scene.fidelity.name(),
        "technique": scene.technique.name(),
        "renderer": rendered.caps.renderer,
        "backend": rendered.backend.name(),
    });
    if stats {
        let resources: Vec<_> = rendered
            .resources
            .iter()
            .map(|r| serde_json::json!({"kind": r.kind, "label": r.label, "bytes": r.bytes}))
            .collect();
        let total: u64 = rendered.resources.iter().map(|r| r.bytes).sum();
        report["resources"] = resources.into();
        report["resource_bytes"] = total.into();
        report["status"] = rendered.status.clone().into();
        report["build_ms"] = (rendered.build_time.as_secs_f64() * 1e3).into();
        report["draw_ms"] = (rendered.draw_time.as_secs_f64() * 1e3).into();
    }
    serde_json::to_string_pretty(&report).unwrap_or_default()
}

/// `--stats`: every resource, one line each, and the total.
pub fn format_stats(resources: &[Resource]) -> String {
    let mut s = String::from("GL resources created:\n");
    let mut total = 0;
    for r in resources {
        s += &format!("  {:<12} {:>12} B  {}\n", r.kind, r.bytes, r.label);
        total += r.bytes;
    }
    s += &format!(
        "  {} resources, {} bytes in total\n",
        resources.len(),
        total
    );
    s
}
