//! `arbvis view`: the desktop viewer. A winit window with a glutin GL context; egui panels
//! around the 3D view (controls, the lut 3D editor, sections); an arcball camera;
//! screenshots and saved scenes. It reuses the offscreen renderers and the scene model
//! and adds only interaction.
//!
//! # When it draws
//! The event loop waits ([`ControlFlow::Wait`]): a frame is drawn only for input, a
//! repaint egui asks for (animations, with their delay), a volume picture still being drawn
//! in parts, the refinement once the user is still, or a script step. An idle viewer draws
//! nothing. The picture is kept by the session every front end shares
//! ([`arbvis_techniques::session`]) and redrawn only when the camera, parameters, size or
//! background change; the UI is redrawn over it.
//!
//! # Framing and size
//! The 3D view is what is left of the window beside the panels; the scene's `size` follows
//! it, so a screenshot and the saved scene agree. At start, on `Reset camera` (Home) and on
//! `Fit volume` the zoom is chosen so that the volume's bounding sphere (with a 10 % margin, room for the axis labels)
//! fits the view's shorter side: the camera fits its `[-1, 1]` square to the shorter side,
//! so the whole volume then stays in view at every rotation and window aspect. At start the
//! scene's zoom is only lowered, never raised.

#![deny(unsafe_code)]

pub mod check;
pub mod clip;
pub mod curve;
pub mod data;
pub mod face;
pub mod isovalues;
pub mod layout;
pub mod legend;
pub mod lut3d;
pub mod observed;
mod options;
pub mod overlay;
pub mod panel;
pub mod remembered;
pub mod runner;
mod running;
pub mod screenshot;
pub mod script;
pub mod section_range;
pub mod splats;
pub mod store_sections;
pub mod surface_colour;
pub mod transfer;
pub mod widgets;

use std::time::{Duration, Instant};

use anyhow::Context as _;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::WindowId;

use runner::{ScriptRunner, ScriptStep};
use running::Running;

pub use options::ViewerOptions;
pub use running::fit_zoom;

/// Wakes the event loop.
#[derive(Debug, Clone, Copy)]
enum Wake {
    /// egui asked for a repaint after this delay.
    Repaint(Duration),
}

/// Open the viewer; returns when the window closes (an error if a script failed).
pub fn run(options: ViewerOptions) -> anyhow::Result<()> {
    let event_loop = EventLoop::<Wake>::with_user_event()
        .build()
        .context("cannot open a window (is DISPLAY set?)")?;
    event_loop.set_control_flow(ControlFlow::Wait);
    let script = options.script.as_ref().map(ScriptRunner::new);
    let mut app = App {
        proxy: event_loop.create_proxy(),
        options,
        running: None,
        result: Ok(()),
        script,
        redraw_at: None,
        idle_until: None,
        frames: 0,
    };
    event_loop.run_app(&mut app)?;
    app.result
}

struct App {
    proxy: EventLoopProxy<Wake>,
    options: ViewerOptions,
    running: Option<Running>,
    result: anyhow::Result<()>,
    script: Option<ScriptRunner>,
    /// The next frame is due at this instant (egui's delayed repaints, refinement).
    redraw_at: Option<Instant>,
    /// A script's `idle`: no frames for the script before this.
    idle_until: Option<Instant>,
    /// Frames drawn.
    frames: u64,
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
            self.remember(&r);
            r.egui.destroy();
        }
        event_loop.exit();
    }

    /// Remember the window's size for the next run (not a scripted one's).
    fn remember(&self, r: &Running) {
        if self.script.is_some() {
            return;
        }
        let Some(folder) = remembered::folder() else {
            return;
        };
        let window = r.window.window();
        let size = window.inner_size().to_logical::<f32>(window.scale_factor());
        if let Err(e) = remembered::save(&folder, egui::vec2(size.width, size.height)) {
            eprintln!(
                "arbvis: note: the window's size was not remembered in {}: {e}",
                folder.display()
            );
        }
    }

    /// Ask for a frame at `at` (now when in the past).
    fn schedule(&mut self, at: Instant) {
        self.redraw_at = Some(self.redraw_at.map_or(at, |t| t.min(at)));
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        let mut measure = None;
        if let Some(script) = self.script.as_mut() {
            let step = script.step(&mut r.observed(self.frames));
            match step {
                Ok(ScriptStep::Events(events)) => {
                    self.idle_until = None;
                    r.egui.egui_winit.egui_input_mut().events.extend(events);
                }
                Ok(ScriptStep::Idle(until)) => self.idle_until = Some(until),
                Ok(ScriptStep::Measure(mode)) => measure = Some(mode),
                Ok(ScriptStep::Resize(w, h)) => {
                    let _ = r
                        .window
                        .window()
                        .request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                }
                Ok(ScriptStep::WindowShot) => r.request_window_shot(),
                Ok(ScriptStep::Quit) => return self.shutdown(event_loop),
                Err(e) => return self.fail(event_loop, e),
            }
        }
        self.frames += 1;
        match r.frame(&self.options, measure) {
            Ok(Some(next)) => self.schedule(next),
            Ok(None) => {}
            Err(e) => self.fail(event_loop, e),
        }
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none() {
            let proxy = self.proxy.clone();
            match Running::start(event_loop, &mut self.options, proxy_repaint(proxy)) {
                Ok(r) => {
                    r.window.window().request_redraw();
                    self.running = Some(r);
                }
                Err(e) => self.fail(event_loop, e),
            }
        }
    }

    fn user_event(&mut self, _event_loop: &ActiveEventLoop, event: Wake) {
        let Wake::Repaint(delay) = event;
        // egui asks with `Duration::MAX` for "no repaint needed".
        if let Some(at) = Instant::now().checked_add(delay) {
            if delay < Duration::from_secs(3600) {
                self.schedule(at);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else {
            return;
        };
        let response = r.egui.on_window_event(r.window.window(), &event);
        // (egui says "repaint" for RedrawRequested itself: that would never stop.)
        if response.repaint && !matches!(event, WindowEvent::RedrawRequested) {
            r.window.window().request_redraw();
        }
        match event {
            WindowEvent::CloseRequested => self.shutdown(event_loop),
            WindowEvent::Resized(size) => {
                r.window.resize(size.width, size.height);
                r.window.window().request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = &self.running else { return };
        let now = Instant::now();
        // A script drives frames itself, except while it idles.
        if self.script.is_some() {
            match self.idle_until {
                Some(t) if t > now => {}
                _ => {
                    self.idle_until = None;
                    r.window.window().request_redraw();
                }
            }
        }
        match self.redraw_at {
            Some(t) if t <= now => {
                self.redraw_at = None;
                r.window.window().request_redraw();
            }
            _ => {}
        }
        let wake = [self.redraw_at, self.idle_until]
            .into_iter()
            .flatten()
            .min();
        event_loop.set_control_flow(match wake {
            Some(t) => ControlFlow::WaitUntil(t),
            None => ControlFlow::Wait,
        });
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(mut r) = self.running.take() {
            self.remember(&r);
            r.egui.destroy();
        }
    }
}

/// egui's repaint requests, sent to the event loop (they may come from any thread).
fn proxy_repaint(proxy: EventLoopProxy<Wake>) -> impl Fn(egui::RequestRepaintInfo) + Send + Sync {
    let proxy = std::sync::Mutex::new(proxy);
    move |info| {
        if let Ok(p) = proxy.lock() {
            let _ = p.send_event(Wake::Repaint(info.delay));
        }
    }
}
