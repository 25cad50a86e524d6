//! Offscreen rendering of a scene: context, renderer, target, one frame, read back.

use crate::error::RenderResult;
use std::time::{Duration, Instant};

use crate::scene::Scene;
use crate::session::{Mode, Session};
use crate::techniques::Renderer;
use arbvis_core::image::Image;
use arbvis_gl::{Backend, Caps, Headless, ProgramKind, Resource};

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
    gpu: &arbvis_gl::Gpu,
    scene: &Scene,
    kind: ProgramKind,
) -> RenderResult<Box<dyn Renderer>> {
    let layers: Vec<_> = scene.layers().collect();
    crate::layered::build_any(gpu, &layers, &scene.settings(), kind)
}

/// Render `scene` offscreen on `backend`.
pub fn render(scene: &Scene, backend: Backend) -> RenderResult<Rendered> {
    let headless = Headless::new(backend)?;
    render_on(&headless, scene)
}

/// Render `scene` with an existing context, through a [`Session`] as every front end
/// draws: the renderer built, then one complete frame (every datum the view needs).
pub fn render_on(headless: &Headless, scene: &Scene) -> RenderResult<Rendered> {
    let gpu = headless.gpu();
    let kind = scene.programs.resolve(gpu);
    let t0 = Instant::now();
    let mut session = Session::build(gpu, scene, kind, true)?;
    gpu.finish();
    let build_time = t0.elapsed();
    let t1 = Instant::now();
    session.frame(gpu, scene, Mode::Complete)?;
    let draw_time = t1.elapsed();
    let image = session.read(gpu, scene)?;
    let renderer = session.renderer();
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
