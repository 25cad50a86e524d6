//! One open viewer window: the renderer, egui, the kept volume picture, the scene being
//! edited, and what each frame does (UI pass, camera input, actions, volume update,
//! blit, UI paint).

use std::time::{Duration, Instant};

use anyhow::anyhow;
use egui_glow::EguiGlow;
use glam::{DQuat, DVec2, DVec3};
use winit::dpi::LogicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use super::data::{self, ViewData};
use super::layout;
use super::lut3d;
use super::observed::Observed;
use super::options::ViewerOptions;
use super::panel::{self, PanelOutput, PanelState, UiAction};
use super::screenshot;
use super::script::MeasureMode;
use arbvis_core::camera::{Arcball, Camera, Projection};
use arbvis_core::png_io;
use arbvis_gl::window::GlWindow;
use arbvis_gl::{self, ProgramKind, Surface};
use arbvis_techniques::scene::Scene;
use arbvis_techniques::session::{FrameBudget, Mode, Pending, Session};
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;

/// A whole UI frame while the user drags: VTK's 15 frames per second.
const FRAME_BUDGET: Duration = Duration::from_millis(66);
/// The least the picture is given of a frame, however slow the UI.
const MIN_PICTURE_BUDGET: Duration = Duration::from_millis(10);

/// How long after the last edit the view counts as still.
pub const SETTLE: Duration = Duration::from_millis(250);

/// Margin kept around the volume's bounding sphere when framing.
const FRAME_MARGIN: f64 = 0.9;

/// The largest zoom at which a box of half-extents `half` stays in view at every rotation
/// (its bounding sphere fits the view's shorter side, with a 10 % margin for labels).
pub fn fit_zoom(camera: &Camera, half: DVec3) -> f64 {
    let r = half.length().max(1e-9) / FRAME_MARGIN;
    match camera.projection {
        Projection::Orthographic => 1.0 / r,
        // The eye sits at sqrt(3) / (tan(fov/2) zoom); the sphere fits when r / distance
        // <= sin(fov/2), the half-angle of the shorter side.
        Projection::Perspective => {
            let theta = camera.fov_y_deg.clamp(1.0, 170.0).to_radians() / 2.0;
            3f64.sqrt() * theta.cos() / r
        }
    }
}

// Fields drop in order: GL objects and egui's before the window's context.
pub(super) struct Running {
    /// The renderer and its kept picture (the session every front end shares).
    session: Session,
    data: ViewData,
    pub egui: EguiGlow,
    scene: Scene,
    panel: PanelState,
    arcball: Arcball,
    last_frame: Instant,
    last_edit: Option<Instant>,
    dragging: bool,
    /// Milliseconds of a frame the UI takes (all but the picture), smoothed.
    ui_ms: f64,
    /// The number the next screenshot's name is looked for from.
    screenshots: u32,
    view_px: [i32; 4],
    /// The whole view (the 3D picture and the legends' margin), GL pixels.
    shown_px: [i32; 4],
    view_rect: egui::Rect,
    /// The whole view in points.
    shown_rect: egui::Rect,
    /// The monitor's size in pixels, when winit knows it.
    screen: Option<[u32; 2]>,
    /// A script's `window-shot`: read the whole window after the next paint.
    window_shot: bool,
    action_error: Option<String>,
    pub window: GlWindow,
}

impl Running {
    pub fn start(
        event_loop: &ActiveEventLoop,
        options: &mut ViewerOptions,
        repaint: impl Fn(egui::RequestRepaintInfo) + Send + Sync + 'static,
    ) -> anyhow::Result<Running> {
        let mut scene = options.scene.clone();
        let opacity3d = scene.technique.get::<Opacity3dScene>().is_some();
        // The window fits the monitor (winit knows its size once the loop runs).
        let monitor = event_loop
            .primary_monitor()
            .or_else(|| event_loop.available_monitors().next());
        let screen = monitor.as_ref().map(|m| [m.size().width, m.size().height]);
        let usable = monitor.as_ref().map(|m| {
            let f = m.scale_factor().max(0.1);
            let s = m.size();
            layout::usable(egui::vec2(
                (s.width as f64 / f) as f32,
                (s.height as f64 / f) as f32,
            ))
        });
        // The size the user left the window at (not in a scripted run), within the
        // screen; else the screen's usable part.
        let remembered = options
            .script
            .is_none()
            .then(super::remembered::folder)
            .flatten()
            .and_then(|f| super::remembered::load(&f))
            .map(|r| usable.map_or(r, |u| r.min(u)));
        let size =
            remembered.unwrap_or_else(|| layout::first_window(scene.size, opacity3d, usable));
        let wanted = layout::first_window(scene.size, opacity3d, None);
        let attributes = Window::default_attributes()
            .with_title(format!("arbvis — {}", options.origin))
            .with_inner_size(LogicalSize::new(size.x as f64, size.y as f64))
            .with_min_inner_size(LogicalSize::new(
                size.x.min(400.0) as f64,
                size.y.min(300.0) as f64,
            ));
        let prefer_egl = std::env::var_os("ARBVIS_PREFER_EGL").is_some_and(|v| v == "1");
        let window = GlWindow::new(event_loop, attributes, prefer_egl)?;
        let gpu = window.gpu();
        let kind = scene.programs.resolve(gpu);
        let mut data = ViewData::default();
        let renderer = data::build(gpu, &scene, kind, &mut data)?;
        let egui = EguiGlow::new(event_loop, gpu.glow().clone(), None, None, false);
        egui.egui_ctx.set_request_repaint_callback(repaint);
        layout::style(&egui.egui_ctx);
        let mut panel = PanelState {
            // What draws, which a mode may override (precise cell projection and splat
            // tiles run GLSL whatever is asked).
            kind: Some(renderer.program_kind()),
            ..PanelState::default()
        };
        if size.x < wanted.x || size.y < wanted.y {
            if let Some([sw, sh]) = screen {
                panel.status = format!(
                    "the window fits the {sw}x{sh} screen: the view is smaller than the scene's {}x{}",
                    scene.size[0], scene.size[1]
                );
            }
        }
        if let Some(g) = data.section_grid() {
            panel.sections.index = g.dims.map(|d| d / 2);
        }
        if let Some(b) = data.data_box() {
            let fit = fit_zoom(&scene.camera, b.half);
            if scene.camera.zoom > fit {
                panel.status = format!(
                    "zoom {:.2} -> {fit:.2}: the whole box in view",
                    scene.camera.zoom
                );
                scene.camera.zoom = fit;
            }
        }
        Ok(Running {
            session: Session::new(renderer, &scene, false),
            data,
            egui,
            scene,
            panel,
            arcball: Arcball::default(),
            last_frame: Instant::now(),
            last_edit: None,
            dragging: false,
            ui_ms: 0.0,
            screenshots: 1,
            view_px: [0, 0, 1, 1],
            shown_px: [0, 0, 1, 1],
            view_rect: egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1.0, 1.0)),
            shown_rect: egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1.0, 1.0)),
            screen,
            window_shot: false,
            action_error: None,
            window,
        })
    }

    /// What a script sees between frames.
    pub fn observed(&mut self, frames: u64) -> Observed<'_> {
        let size = self.window.window().inner_size();
        let position = self.window.window().outer_position().ok();
        let outer = self.window.window().outer_size();
        Observed {
            widgets: &mut self.panel.widgets,
            view: self.view_rect,
            shown: self.shown_rect,
            frames,
            camera: self.scene.camera,
            window: [size.width, size.height],
            outer: position.map(|p| [p.x, p.y, outer.width as i32, outer.height as i32]),
            screen: self.screen,
            pixels_per_point: self.egui.egui_ctx.pixels_per_point(),
            view_px: [self.view_px[2] as u32, self.view_px[3] as u32],
            overlay: &self.panel.overlay_items,
            action_error: self.action_error.take(),
            quality: self.panel.quality.name(),
            scale: self.session.picture().scale,
        }
    }

    fn fail_action(&mut self, message: String) {
        self.panel.status = message.clone();
        self.action_error = Some(message);
    }

    /// Draw one frame; returns when the next is due (none: wait for input).
    pub fn frame(
        &mut self,
        options: &ViewerOptions,
        measure: Option<MeasureMode>,
    ) -> anyhow::Result<Option<Instant>> {
        let now = Instant::now();
        self.count_frame(now, measure);
        let caps = self.window.gpu().caps().clone();
        let mut out = None;
        let (scene, data, panel) = (&mut self.scene, &mut self.data, &mut self.panel);
        self.egui.run(self.window.window(), |ui| {
            out = Some(panel::show(ui, scene, data, panel, &caps));
        });
        let out = out.ok_or_else(|| anyhow!("egui produced no UI"))?;
        self.view_rect = out.view;
        self.shown_rect = out.shown;

        self.turn_camera(&out);
        let screenshot = self.take_actions(&out.actions, options);

        // Read each frame (a copy): the clip's cost after any rebuild above.
        let facts = self.session.renderer().facts();
        let clip = facts
            .into_iter()
            .find(|(l, _)| *l == arbvis_techniques::techniques::clip::stats::LABEL);
        self.panel.clip.stats = clip.map(|(_, line)| line);
        let win = self.place_view(&out);

        if out.edited || out.input.scroll != 0.0 || out.input.drag_end {
            self.last_edit = Some(now);
        }
        let settling = self
            .last_edit
            .is_some_and(|t| now.duration_since(t) < SETTLE);
        // A screenshot shows the full-quality picture, drawn now if need be.
        let interacting =
            !screenshot && (self.dragging || settling || measure == Some(MeasureMode::Interactive));
        let mode = if screenshot || measure == Some(MeasureMode::Full) {
            Mode::Now
        } else if interacting {
            Mode::Interacting
        } else {
            Mode::Still
        };
        let gpu = self.window.gpu();
        // A store's bricks keep arriving: frames go on until none is due.
        let streaming = self.session.renderer().pending();
        self.session.quality = self.panel.quality;
        // The picture gets what the frame budget leaves after the UI's own work.
        let budget = FRAME_BUDGET.saturating_sub(Duration::from_secs_f64(self.ui_ms / 1e3));
        self.session.set_budget(FrameBudget {
            interactive: budget.max(MIN_PICTURE_BUDGET),
            ..self.session.budget()
        });
        let before_picture = Instant::now();
        let pending = self.session.frame(gpu, &self.scene, mode)?;
        let picture_time = before_picture.elapsed();
        let p = self.session.picture();
        self.panel.volume_info = format!(
            "picture: {:.0} ms full ({} part{}), {:.0} ms interactive at 1/{:.1} of each side{}",
            p.full_ms,
            p.parts,
            if p.parts == 1 { "" } else { "s" },
            p.interactive_ms,
            p.scale,
            self.session
                .renderer()
                .status()
                .map_or(String::new(), |s| format!("\n{s}"))
        );

        arbvis_gl::clear(
            gpu,
            Surface::Window([0, 0, win.width as i32, win.height as i32]),
            [0.1, 0.1, 0.1, 1.0],
        )?;
        arbvis_gl::clear(gpu, Surface::Window(self.shown_px), self.scene.background)?;
        if let Some(shown) = self.session.shown() {
            shown.blit_to_window(gpu, self.view_px)?;
        }
        // The view before egui paints over it, to tell its marks from the picture's.
        let bare = match screenshot && self.panel.overlay {
            true => Some(arbvis_gl::read_window(gpu, self.shown_px)?),
            false => None,
        };
        self.egui.paint(self.window.window());
        if screenshot {
            self.screenshot(options, bare);
        }
        if std::mem::take(&mut self.window_shot) {
            self.save_window(options);
        }
        self.window.swap_buffers()?;
        // The UI's share of this frame (all but the picture), smoothed over frames.
        let ui = now.elapsed().saturating_sub(picture_time).as_secs_f64() * 1e3;
        self.ui_ms = if self.ui_ms == 0.0 {
            ui
        } else {
            0.8 * self.ui_ms + 0.2 * ui
        };
        Ok(match pending {
            Pending::Done if streaming => Some(Instant::now()),
            Pending::Done => None,
            Pending::Building => Some(Instant::now()),
            Pending::Refine => Some(self.last_edit.unwrap_or(now) + SETTLE),
        })
    }

    /// The frame time and rate the panel shows; a measuring run turns the camera a little
    /// each frame, as a slow drag would.
    fn count_frame(&mut self, now: Instant, measure: Option<MeasureMode>) {
        let dt = now.duration_since(self.last_frame).as_secs_f64().max(1e-6);
        self.last_frame = now;
        let a = if self.panel.frame_ms == 0.0 { 1.0 } else { 0.2 };
        self.panel.frame_ms = self.panel.frame_ms * (1.0 - a) + dt * 1e3 * a;
        self.panel.fps = 1e3 / self.panel.frame_ms.max(1e-6);
        if matches!(measure, Some(MeasureMode::Full | MeasureMode::Interactive)) {
            let q = DQuat::from_rotation_y(2f64.to_radians()) * self.scene.camera.quat();
            self.scene.camera.rotation = q.to_array();
        }
    }

    /// The camera from pointer input on the view: the arcball's drag, the wheel's zoom.
    fn turn_camera(&mut self, out: &PanelOutput) {
        let view_size = DVec2::new(out.view.width() as f64, out.view.height() as f64);
        let local = |p: egui::Pos2| {
            DVec2::new((p.x - out.view.min.x) as f64, (p.y - out.view.min.y) as f64)
        };
        if let Some(p) = out.input.drag_start {
            self.arcball.begin(&self.scene.camera, local(p), view_size);
            self.dragging = true;
        }
        if let Some(p) = out.input.drag_to {
            self.arcball
                .drag(&mut self.scene.camera, local(p), view_size);
        }
        if out.input.drag_end {
            self.arcball.end();
            self.dragging = false;
        }
        if out.input.scroll != 0.0 {
            let z = self.scene.camera.zoom * (out.input.scroll as f64 / 200.0).exp();
            self.scene.camera.zoom = z.clamp(0.1, 10.0);
        }
    }

    /// Do what the panel asked this frame; true when it asked for a screenshot.
    fn take_actions(&mut self, actions: &[UiAction], options: &ViewerOptions) -> bool {
        let mut screenshot = false;
        for action in actions {
            match action {
                UiAction::SetPrograms(kind) => self.set_programs(*kind),
                UiAction::ParamsChanged => {
                    // A layered scene's renderer takes the first layer's parameters and
                    // is rebuilt for any other layer's (Session::apply tells which).
                    let gpu = self.window.gpu();
                    let result = match self.scene.is_layered() {
                        true => self.session.apply(gpu, &self.scene),
                        false => self.session.params_changed(gpu, &self.scene),
                    };
                    if let Err(e) = result {
                        self.fail_action(format!("error: {e}"));
                    }
                }
                UiAction::Screenshot => screenshot = true,
                UiAction::SaveScene => self.save_scene(options),
                UiAction::SetFidelity => {
                    // The scene's own choice, not what the last mode drew with.
                    let kind = self.scene.programs.resolve(self.window.gpu());
                    self.set_programs(kind);
                }
                UiAction::SaveTables => self.save_tables(options),
                UiAction::ResetCamera => {
                    // A survey's three-quarter view, as its scene started.
                    self.scene.camera = self.scene.technique.default_camera().unwrap_or_default();
                    self.fit();
                }
                UiAction::FitVolume => self.fit(),
            }
        }
        screenshot
    }

    /// The 3D view and the picture shown in window pixels (GL's origin is the bottom
    /// left); the scene's size follows the view. Returns the window's size.
    fn place_view(&mut self, out: &PanelOutput) -> winit::dpi::PhysicalSize<u32> {
        let ppp = self.egui.egui_ctx.pixels_per_point();
        let win = self.window.window().inner_size();
        let to_px = |r: egui::Rect| {
            let x = (r.min.x * ppp).round() as i32;
            let w = ((r.max.x * ppp).round() as i32 - x).max(1);
            let top = (r.min.y * ppp).round() as i32;
            let h = ((r.max.y * ppp).round() as i32 - top).max(1);
            [x, win.height as i32 - top - h, w, h]
        };
        self.view_px = to_px(out.view);
        self.shown_px = to_px(out.shown);
        self.scene.size = [self.view_px[2] as u32, self.view_px[3] as u32];
        win
    }

    /// Zoom so that the whole volume (mesh, cloud) stays in view.
    fn fit(&mut self) {
        if let Some(b) = self.data.data_box() {
            self.scene.camera.zoom = fit_zoom(&self.scene.camera, b.half);
        }
    }

    /// A script's `window-shot`: read the whole window after the next paint.
    pub fn request_window_shot(&mut self) {
        self.window_shot = true;
    }

    /// Write the whole window as `arbvis-window-NNN.png` (for looking at the layout).
    fn save_window(&mut self, options: &ViewerOptions) {
        let win = self.window.window().inner_size();
        let rect = [0, 0, win.width as i32, win.height as i32];
        let result = arbvis_gl::read_window(self.window.gpu(), rect)
            .map_err(anyhow::Error::from)
            .and_then(|image| {
                let bytes = png_io::encode_png("window", &image, &[])?;
                Ok(screenshot::write_next(
                    &options.screenshot_dir,
                    screenshot::WINDOW_PREFIX,
                    1,
                    &bytes,
                )?)
            });
        match result {
            Ok((p, _)) => self.panel.status = format!("saved {}", p.display()),
            Err(e) => self.fail_action(format!("window shot failed: {e}")),
        }
    }

    fn set_programs(&mut self, kind: ProgramKind) {
        match data::build(self.window.gpu(), &self.scene, kind, &mut self.data) {
            Ok(r) => {
                self.session.replace_renderer(r);
                let drawn = self.session.renderer().program_kind();
                self.panel.kind = Some(drawn);
                self.scene.programs = match kind {
                    ProgramKind::Arb => arbvis_gl::ProgramChoice::Arb,
                    ProgramKind::Glsl => arbvis_gl::ProgramChoice::Glsl,
                };
                self.panel.status = if drawn == kind {
                    format!("programs: {}", kind.name())
                } else {
                    format!(
                        "programs: {} asked; this mode draws with {} only (the choice applies in faithful mode)",
                        kind.name(),
                        drawn.name()
                    )
                };
            }
            Err(e) => self.fail_action(format!("cannot switch to {}: {e}", kind.name())),
        }
    }

    /// Write the view as the next free `arbvis-screenshot-NNN.png`: the picture, with
    /// what egui drew over it when `bare` (the view before egui painted) is given.
    fn screenshot(&mut self, options: &ViewerOptions, bare: Option<arbvis_core::image::Image>) {
        let gpu = self.window.gpu();
        let picture = self.session.file_picture(gpu, &self.scene);
        let result = picture.map_err(anyhow::Error::from).and_then(|picture| {
            let image = match bare {
                Some(bare) => {
                    let painted = arbvis_gl::read_window(self.window.gpu(), self.shown_px)?;
                    let [vx, vy, _, vh] = self.view_px;
                    let [sx, sy, _, sh] = self.shown_px;
                    let at = [
                        (vx - sx).max(0) as u32,
                        ((sy + sh) - (vy + vh)).max(0) as u32,
                    ];
                    let margin = if self.scene.transparent {
                        [0.0; 4]
                    } else {
                        let [r, g, b, _] = self.scene.background;
                        [r, g, b, 1.0]
                    };
                    screenshot::compose(&picture, at, &bare, &painted, margin)
                }
                None => picture,
            };
            let caps = self.window.gpu().caps();
            let text = [
                ("Software", format!("arbvis {}", env!("CARGO_PKG_VERSION"))),
                ("arbvis:scene-origin", options.origin.clone()),
                ("arbvis:scene", self.scene.to_toml()),
                (
                    "arbvis:programs",
                    self.session.renderer().program_kind().name().to_string(),
                ),
                (
                    "arbvis:renderer",
                    format!("{} | {} | {}", caps.vendor, caps.renderer, caps.version),
                ),
                (
                    "arbvis:overlay",
                    if self.panel.overlay {
                        "box, axes and legends"
                    } else {
                        "none"
                    }
                    .to_string(),
                ),
            ];
            let bytes = png_io::encode_png("screenshot", &image, &text)?;
            let (path, n) = screenshot::write_next(
                &options.screenshot_dir,
                screenshot::PREFIX,
                self.screenshots,
                &bytes,
            )?;
            self.screenshots = n + 1;
            Ok(path)
        });
        match result {
            Ok(p) => self.panel.status = format!("saved {}", p.display()),
            Err(e) => self.fail_action(format!("screenshot failed: {e}")),
        }
    }

    fn save_tables(&mut self, options: &ViewerOptions) {
        match save_tables(&mut self.scene, &options.screenshot_dir) {
            Ok(paths) if paths.is_empty() => {
                self.fail_action("cannot save tables: this scene has no colour tables".into())
            }
            Ok(paths) => self.panel.status = format!("saved {}", paths.join(", ")),
            Err(e) => self.fail_action(format!("cannot save tables: {e}")),
        }
    }

    fn save_scene(&mut self, options: &ViewerOptions) {
        let path = options.screenshot_dir.join("arbvis-scene.toml");
        let scene = self.scene.with_absolute_paths();
        match png_io::write_atomic(&path, scene.to_toml().as_bytes()) {
            Ok(()) => self.panel.status = format!("saved {}", path.display()),
            Err(e) => self.fail_action(format!("cannot save {}: {e}", path.display())),
        }
    }
}

/// Write each opacity3d table (with its alpha curve applied) as
/// `arbvis-table-ROLE.table` in `dir`, and point the scene at the files; none for a
/// scene without tables.
fn save_tables(
    scene: &mut Scene,
    dir: &std::path::Path,
) -> Result<Vec<String>, arbvis_core::colortable::TableError> {
    let base = scene.base.clone();
    let Some(o) = scene.technique.get_mut::<Opacity3dScene>() else {
        return Ok(Vec::new());
    };
    let mut written = Vec::new();
    for (role, attr) in lut3d::ROLES.iter().zip(o.attributes_mut()) {
        let Some(attr) = attr else { continue };
        let table = attr.table.build(&base)?;
        let path = dir.join(format!("arbvis-table-{role}.table"));
        table.save(&path)?;
        attr.table.file = Some(std::fs::canonicalize(&path).unwrap_or(path.clone()));
        attr.table.colors.clear();
        attr.table.alpha.clear();
        written.push(path.display().to_string());
    }
    Ok(written)
}
