//! `arbvis view`: the desktop viewer. A winit window with a glutin GL context, an egui
//! side panel over the GL view, an arcball camera, a screenshot button and an FPS
//! readout. It reuses the offscreen renderers and scene model and adds only interaction.

pub mod isovalues;
pub mod lut3d;
pub mod panel;
pub mod script;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, Context as _};
use egui_glow::EguiGlow;
use glam::DVec2;
use winit::application::ApplicationHandler;
use winit::dpi::LogicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

use crate::camera::Arcball;
use crate::gl::window::GlWindow;
use crate::gl::{self, ProgramKind, Surface};
use crate::png_io;
use crate::scene::{Scene, TechniqueScene};
use crate::techniques::{self, Frame, Renderer};
use panel::{PanelState, UiAction, PANEL_WIDTH};
use script::{Action, Script};

/// What `arbvis view` was asked to show.
pub struct ViewerOptions {
    /// The scene.
    pub scene: Scene,
    /// Where it came from (recorded in screenshots).
    pub origin: String,
    /// Folder for screenshots and saved scenes.
    pub screenshot_dir: PathBuf,
    /// UI actions to run, then exit.
    pub script: Option<Script>,
}

/// Open the viewer; returns when the window closes (an error if a script failed).
pub fn run(options: ViewerOptions) -> anyhow::Result<()> {
    let event_loop = EventLoop::new().context("cannot open a window (is DISPLAY set?)")?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        options,
        running: None,
        result: Ok(()),
        script: ScriptRunner::default(),
    };
    app.script.actions = app
        .options
        .script
        .as_ref()
        .map(|s| s.actions.clone())
        .unwrap_or_default();
    app.script.active = app.options.script.is_some();
    event_loop.run_app(&mut app)?;
    app.result
}

struct App {
    options: ViewerOptions,
    running: Option<Running>,
    result: anyhow::Result<()>,
    script: ScriptRunner,
}

// Fields drop in order: the renderer's GL objects and egui's before the window's context.
struct Running {
    renderer: Box<dyn Renderer>,
    egui: EguiGlow,
    window: GlWindow,
    scene: Scene,
    panel: PanelState,
    arcball: Arcball,
    last_frame: Instant,
    screenshots: u32,
    view_px: [i32; 4],
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        self.shutdown(event_loop);
    }

    fn shutdown(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(mut r) = self.running.take() {
            r.egui.destroy();
        }
        event_loop.exit();
    }

    fn start(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<Running> {
        let scene = self.options.scene.clone();
        let [w, h] = scene.size;
        let attributes = Window::default_attributes()
            .with_title(format!("arbvis — {}", self.options.origin))
            .with_inner_size(LogicalSize::new(
                w as f64 + PANEL_WIDTH as f64,
                h.max(480) as f64,
            ));
        let prefer_egl = std::env::var_os("ARBVIS_PREFER_EGL").is_some_and(|v| v == "1");
        let window = GlWindow::new(event_loop, attributes, prefer_egl)?;
        let gpu = window.gpu();
        let kind = scene.programs.resolve(gpu);
        let renderer = techniques::build(gpu, &scene, kind)?;
        let egui = EguiGlow::new(event_loop, gpu.glow().clone(), None, None, false);
        let panel = PanelState {
            kind: Some(kind),
            ..PanelState::default()
        };
        Ok(Running {
            renderer,
            egui,
            window,
            scene,
            panel,
            arcball: Arcball::default(),
            last_frame: Instant::now(),
            screenshots: 0,
            view_px: [0, 0, 1, 1],
        })
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none() {
            match self.start(event_loop) {
                Ok(r) => self.running = Some(r),
                Err(e) => self.fail(event_loop, e),
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        let response = r.egui.on_window_event(r.window.window(), &event);
        if response.repaint {
            r.window.window().request_redraw();
        }
        match event {
            WindowEvent::CloseRequested => self.shutdown(event_loop),
            WindowEvent::Resized(size) => r.window.resize(size.width, size.height),
            WindowEvent::RedrawRequested => {
                let step = self.script.step(&r.panel.widgets, r.view_rect());
                match step {
                    Ok(ScriptStep::Events(events)) => {
                        r.egui.egui_winit.egui_input_mut().events.extend(events);
                        if let Err(e) = r.frame(&self.options) {
                            self.fail(event_loop, e);
                        }
                    }
                    Ok(ScriptStep::Quit) => self.shutdown(event_loop),
                    Err(e) => self.fail(event_loop, e),
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(r) = &self.running {
            r.window.window().request_redraw();
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(mut r) = self.running.take() {
            r.egui.destroy();
        }
    }
}

impl Running {
    fn view_rect(&self) -> egui::Rect {
        let ppp = self.egui.egui_ctx.pixels_per_point();
        let size = self.window.window().inner_size();
        egui::Rect::from_min_max(
            egui::pos2(PANEL_WIDTH, 0.0),
            egui::pos2(size.width as f32 / ppp, size.height as f32 / ppp),
        )
    }

    fn frame(&mut self, options: &ViewerOptions) -> anyhow::Result<()> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f64().max(1e-6);
        self.last_frame = now;
        let a = 0.1;
        self.panel.frame_ms = self.panel.frame_ms * (1.0 - a) + dt * 1e3 * a;
        self.panel.fps = 1e3 / self.panel.frame_ms.max(1e-6);

        let caps = self.window.gpu().caps().clone();
        let mut out = None;
        let (scene, panel) = (&mut self.scene, &mut self.panel);
        self.egui.run(self.window.window(), |ui| {
            out = Some(panel::show(ui, scene, panel, &caps));
        });
        let out = out.ok_or_else(|| anyhow!("egui produced no UI"))?;

        // Camera from pointer input on the view.
        let view_size = DVec2::new(out.view.width() as f64, out.view.height() as f64);
        let local = |p: egui::Pos2| {
            DVec2::new((p.x - out.view.min.x) as f64, (p.y - out.view.min.y) as f64)
        };
        if let Some(p) = out.input.drag_start {
            self.arcball.begin(&self.scene.camera, local(p), view_size);
        }
        if let Some(p) = out.input.drag_to {
            self.arcball
                .drag(&mut self.scene.camera, local(p), view_size);
        }
        if out.input.drag_end {
            self.arcball.end();
        }
        if out.input.scroll != 0.0 {
            let z = self.scene.camera.zoom * (out.input.scroll as f64 / 200.0).exp();
            self.scene.camera.zoom = z.clamp(0.1, 10.0);
        }

        let mut screenshot = false;
        for action in &out.actions {
            match action {
                UiAction::SetPrograms(kind) => self.set_programs(*kind),
                UiAction::ParamsChanged => {
                    if let Err(e) = self
                        .renderer
                        .update(self.window.gpu(), &self.scene.technique)
                    {
                        self.panel.status = format!("error: {e}");
                    }
                }
                UiAction::Screenshot => screenshot = true,
                UiAction::SaveScene => self.save_scene(options),
                UiAction::SetFidelity => {
                    let kind = self.renderer.program_kind();
                    self.set_programs(kind);
                }
                UiAction::SaveTables => self.save_tables(options),
            }
        }

        // The GL view, in window pixels (GL's origin is the bottom left).
        let ppp = self.egui.egui_ctx.pixels_per_point();
        let win = self.window.window().inner_size();
        let x = (out.view.min.x * ppp).round() as i32;
        let w = ((out.view.width() * ppp).round() as i32).max(1);
        let h = ((out.view.height() * ppp).round() as i32).max(1);
        let y = win.height as i32 - (out.view.max.y * ppp).round() as i32;
        self.view_px = [x, y, w, h];
        let gpu = self.window.gpu();
        gl::clear(
            gpu,
            Surface::Window([0, 0, win.width as i32, win.height as i32]),
            [0.1, 0.1, 0.1, 1.0],
        )?;
        gl::clear(gpu, Surface::Window(self.view_px), self.scene.background)?;
        let frame = Frame {
            camera: self.scene.camera,
            width: w as u32,
            height: h as u32,
        };
        self.renderer
            .draw(gpu, Surface::Window(self.view_px), &frame)?;
        if screenshot {
            self.screenshot(options);
        }
        self.egui.paint(self.window.window());
        self.window.swap_buffers()?;
        Ok(())
    }

    fn set_programs(&mut self, kind: ProgramKind) {
        match techniques::build(self.window.gpu(), &self.scene, kind) {
            Ok(r) => {
                self.renderer = r;
                self.panel.kind = Some(kind);
                self.scene.programs = match kind {
                    ProgramKind::Arb => crate::gl::ProgramChoice::Arb,
                    ProgramKind::Glsl => crate::gl::ProgramChoice::Glsl,
                };
                self.panel.status = format!("programs: {}", kind.name());
            }
            Err(e) => self.panel.status = format!("cannot switch to {}: {e}", kind.name()),
        }
    }

    /// The view as a picture: what the window shows (opaque), or, for a transparent
    /// scene, the same frame drawn again offscreen on transparent black (straight colour,
    /// coverage alpha), exactly as `arbvis render --transparent` writes it.
    fn picture(&mut self) -> anyhow::Result<crate::image::Image> {
        let gpu = self.window.gpu();
        if !self.scene.transparent {
            return Ok(gl::read_window(gpu, self.view_px)?.opaque());
        }
        let [_, _, w, h] = self.view_px;
        let (w, h) = (w.max(1) as u32, h.max(1) as u32);
        let target = gl::Target::new(gpu, w, h, self.scene.target_format())?;
        target.clear(gpu, self.scene.clear_colour())?;
        let frame = Frame {
            camera: self.scene.camera,
            width: w,
            height: h,
        };
        self.renderer.draw(gpu, Surface::Target(&target), &frame)?;
        Ok(self.scene.picture(&target.read(gpu)?))
    }

    fn screenshot(&mut self, options: &ViewerOptions) {
        let result = self.picture().and_then(|image| {
            self.screenshots += 1;
            let path = options
                .screenshot_dir
                .join(format!("arbvis-screenshot-{:03}.png", self.screenshots));
            let caps = self.window.gpu().caps();
            let text = [
                ("Software", format!("arbvis {}", env!("CARGO_PKG_VERSION"))),
                ("arbvis:scene-origin", options.origin.clone()),
                ("arbvis:scene", self.scene.to_toml()),
                (
                    "arbvis:programs",
                    self.renderer.program_kind().name().to_string(),
                ),
                (
                    "arbvis:renderer",
                    format!("{} | {} | {}", caps.vendor, caps.renderer, caps.version),
                ),
            ];
            png_io::write_png(&path, &image, &text)?;
            Ok(path)
        });
        self.panel.status = match result {
            Ok(p) => format!("saved {}", p.display()),
            Err(e) => format!("screenshot failed: {e}"),
        };
    }

    fn save_tables(&mut self, options: &ViewerOptions) {
        self.panel.status = match save_tables(&mut self.scene, &options.screenshot_dir) {
            Ok(paths) => format!("saved {}", paths.join(", ")),
            Err(e) => format!("cannot save tables: {e}"),
        };
    }

    fn save_scene(&mut self, options: &ViewerOptions) {
        let path = options.screenshot_dir.join("arbvis-scene.toml");
        let scene = self.scene.with_absolute_paths();
        self.panel.status = match png_io::write_atomic(&path, scene.to_toml().as_bytes()) {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => format!("cannot save {}: {e}", path.display()),
        };
    }
}

/// Write each opacity3d table (with its alpha curve applied) as
/// `arbvis-table-ROLE.table` in `dir`, and point the scene at the files.
fn save_tables(scene: &mut Scene, dir: &std::path::Path) -> Result<Vec<String>, String> {
    let base = scene.base.clone();
    let TechniqueScene::Opacity3d(o) = &mut scene.technique else {
        return Err("this scene has no colour tables".into());
    };
    let mut written = Vec::new();
    for (role, attr) in lut3d::ROLES.iter().zip(o.attributes_mut()) {
        let Some(attr) = attr else { continue };
        let table = attr.table.build(&base)?;
        let path = dir.join(format!("arbvis-table-{role}.table"));
        table.save(&path)?;
        attr.table.file = Some(std::fs::canonicalize(&path).unwrap_or(path.clone()));
        attr.table.alpha.clear();
        written.push(path.display().to_string());
    }
    Ok(written)
}

/// What the script does this frame.
enum ScriptStep {
    /// Inject these events and draw.
    Events(Vec<egui::Event>),
    /// Close the viewer.
    Quit,
}

/// Runs a [`Script`] frame by frame.
#[derive(Default)]
struct ScriptRunner {
    active: bool,
    actions: Vec<Action>,
    index: usize,
    phase: u32,
    frames_in_action: u32,
}

impl ScriptRunner {
    fn step(
        &mut self,
        widgets: &std::collections::HashMap<String, egui::Rect>,
        view: egui::Rect,
    ) -> anyhow::Result<ScriptStep> {
        use egui::{Event, Modifiers, PointerButton};
        if !self.active {
            return Ok(ScriptStep::Events(Vec::new()));
        }
        let press = |pos, pressed| Event::PointerButton {
            pos,
            button: PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        };
        let Some(action) = self.actions.get(self.index).cloned() else {
            return Ok(ScriptStep::Quit);
        };
        self.frames_in_action += 1;
        let mut events = Vec::new();
        let mut done = false;
        match action {
            Action::Wait(n) => done = self.frames_in_action > n,
            Action::Quit => return Ok(ScriptStep::Quit),
            Action::Click(label) => match (self.phase, widgets.get(&label)) {
                (0, Some(rect)) => {
                    events.push(Event::PointerMoved(rect.center()));
                    events.push(press(rect.center(), true));
                    self.phase = 1;
                }
                (_, Some(rect)) => {
                    events.push(press(rect.center(), false));
                    done = true;
                }
                (_, None) if self.frames_in_action > 10 => {
                    let mut known: Vec<_> = widgets.keys().cloned().collect();
                    known.sort();
                    return Err(anyhow!(
                        "script: no widget labelled {label:?}; widgets: {known:?}"
                    ));
                }
                (_, None) => {}
            },
            Action::Drag(dx, dy) => {
                let c = view.center();
                let d = egui::vec2(dx, dy);
                match self.phase {
                    0 => {
                        events.push(Event::PointerMoved(c));
                        events.push(press(c, true));
                    }
                    1 => events.push(Event::PointerMoved(c + d * 0.5)),
                    2 => events.push(Event::PointerMoved(c + d)),
                    _ => {
                        events.push(press(c + d, false));
                        done = true;
                    }
                }
                self.phase += 1;
            }
        }
        if done {
            self.index += 1;
            self.phase = 0;
            self.frames_in_action = 0;
        }
        Ok(ScriptStep::Events(events))
    }
}
