//! A desktop window with a GL context: winit window + glutin (GLX by default, EGL when
//! preferred), compatibility profile so ARB programs work in the window too.

use std::num::NonZeroU32;

use glutin::config::{ConfigTemplateBuilder, GlConfig};
use glutin::context::{NotCurrentGlContext, PossiblyCurrentContext};
use glutin::display::{GetGlDisplay, GlDisplay};
use glutin::surface::{GlSurface, Surface, SwapInterval, WindowSurface};
use glutin_winit::{ApiPreference, DisplayBuilder, GlWindow as _};
use raw_window_handle::HasWindowHandle;
use winit::event_loop::ActiveEventLoop;
use winit::window::{Window, WindowAttributes};

use super::error::{GlError, GlResult};
use super::gpu::Gpu;

/// A window, its surface and current context, and the [`Gpu`] on it.
pub struct GlWindow {
    gpu: Gpu,
    surface: Surface<WindowSurface>,
    context: PossiblyCurrentContext,
    window: Window,
}

fn err(reason: impl std::fmt::Display) -> GlError {
    GlError::Context {
        backend: "window",
        reason: reason.to_string(),
    }
}

impl GlWindow {
    /// Open a window with `attributes`; `prefer_egl` picks EGL over GLX.
    pub fn new(
        event_loop: &ActiveEventLoop,
        attributes: WindowAttributes,
        prefer_egl: bool,
    ) -> GlResult<GlWindow> {
        let preference = if prefer_egl {
            ApiPreference::PreferEgl
        } else {
            ApiPreference::FallbackEgl
        };
        let (window, config) = DisplayBuilder::new()
            .with_preference(preference)
            .with_window_attributes(Some(attributes))
            .build(event_loop, ConfigTemplateBuilder::new(), |configs| {
                // Fewest samples: pixels must be what the programs computed.
                configs
                    .reduce(|a, b| {
                        if b.num_samples() < a.num_samples() {
                            b
                        } else {
                            a
                        }
                    })
                    .expect("glutin offers at least one config when find_configs succeeds")
            })
            .map_err(err)?;
        let window = window.ok_or_else(|| err("no window was created"))?;
        let raw = window.window_handle().ok().map(|h| h.as_raw());
        let display = config.display();
        let mut last = String::new();
        let mut not_current = None;
        for attrs in super::headless::compatibility_attributes(raw) {
            // SAFETY: the config and window handle belong to this display.
            match unsafe { display.create_context(&config, &attrs) } {
                Ok(c) => {
                    not_current = Some(c);
                    break;
                }
                Err(e) => last = e.to_string(),
            }
        }
        let not_current =
            not_current.ok_or_else(|| err(format!("no compatibility context: {last}")))?;
        let surface_attrs = window
            .build_surface_attributes(Default::default())
            .map_err(err)?;
        // SAFETY: the surface is created for this window, which outlives it (field order).
        let surface =
            unsafe { display.create_window_surface(&config, &surface_attrs) }.map_err(err)?;
        let context = not_current.make_current(&surface).map_err(err)?;
        // No vsync: the FPS readout shows what the renderer costs.
        let _ = surface.set_swap_interval(&context, SwapInterval::DontWait);
        let gpu = Gpu::from_loader(|s| display.get_proc_address(s))?;
        Ok(GlWindow {
            gpu,
            surface,
            context,
            window,
        })
    }

    /// The GL handle.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The winit window.
    pub fn window(&self) -> &Window {
        &self.window
    }

    /// Resize the surface to the window's new inner size.
    pub fn resize(&self, width: u32, height: u32) {
        if let (Some(w), Some(h)) = (NonZeroU32::new(width), NonZeroU32::new(height)) {
            self.surface.resize(&self.context, w, h);
        }
    }

    /// Present the back buffer.
    pub fn swap_buffers(&self) -> GlResult<()> {
        self.surface.swap_buffers(&self.context).map_err(err)
    }
}
