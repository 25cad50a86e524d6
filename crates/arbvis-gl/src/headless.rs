//! Offscreen contexts without a window: EGL (glutin's device platform, surfaceless,
//! compatibility profile) and OSMesa (libOSMesa loaded at run time).
//!
//! Facts this rests on (DESIGN.md §8): an EGL config must ask for PBUFFER surfaces or Mesa
//! finds none; a context created without a profile is Core 3.3, which has no ARB programs,
//! so a compatibility profile is requested explicitly, 4.5 first.

use std::ffi::{c_char, c_void};

use glutin::api::egl::{context::PossiblyCurrentContext, device::Device, display::Display};
use glutin::config::{Api, ConfigSurfaceTypes, ConfigTemplateBuilder};
use glutin::context::{ContextApi, ContextAttributesBuilder, GlProfile, Version};
use glutin::display::GlDisplay;

use super::error::{GlError, GlResult};
use super::gpu::Gpu;

/// Which offscreen backend to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// EGL through glutin's device platform (default).
    #[default]
    Egl,
    /// OSMesa, loaded from libOSMesa at run time.
    Osmesa,
}

impl Backend {
    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Egl => "egl",
            Backend::Osmesa => "osmesa",
        }
    }
}

/// An offscreen context made current on the creating thread, with its [`Gpu`].
///
/// Drop every GL object made from [`Headless::gpu`] before the `Headless` itself.
pub struct Headless {
    gpu: Gpu,
    backend: Backend,
    // Dropped after `gpu` (fields drop in declaration order).
    _context: HeadlessContext,
}

enum HeadlessContext {
    Egl {
        _context: PossiblyCurrentContext,
        _display: Display,
    },
    Osmesa {
        _context: OsmesaContext,
    },
}

/// What to install when no EGL context can be made.
const EGL_HINT: &str = "arbvis renders offscreen through EGL: install Mesa's EGL and software \
renderer (Debian/Ubuntu: apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri, or run \
scripts/install-deps.sh) or a GPU driver, or try --backend osmesa";

impl Headless {
    /// Create a context on `backend` and make it current on this thread.
    pub fn new(backend: Backend) -> GlResult<Headless> {
        match backend {
            Backend::Egl => Self::egl(),
            Backend::Osmesa => Self::osmesa(),
        }
    }

    /// The context's GL handle.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Which backend this is.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    fn egl() -> GlResult<Headless> {
        let err = |reason: String| GlError::Context {
            backend: "egl",
            reason: format!("{reason}; {EGL_HINT}"),
        };
        let mut devices: Vec<Device> = Device::query_devices()
            .map_err(|e| err(format!("no EGL devices: {e}")))?
            .collect();
        if devices.is_empty() {
            return Err(err("EGL reports no devices".into()));
        }
        // A real GPU first; Mesa's software device otherwise. ARBVIS_EGL_SOFTWARE=1 forces it.
        let force_software = std::env::var_os("ARBVIS_EGL_SOFTWARE").is_some_and(|v| v == "1");
        devices.sort_by_key(|d| {
            let software = d.extensions().contains("EGL_MESA_device_software");
            software != force_software
        });
        let mut reasons = Vec::new();
        for device in &devices {
            match Self::egl_on(device) {
                Ok(h) => return Ok(h),
                Err(e) => reasons.push(format!("{}: {e}", device.name().unwrap_or("device"))),
            }
        }
        Err(err(reasons.join("; ")))
    }

    fn egl_on(device: &Device) -> Result<Headless, DeviceRefusal> {
        // SAFETY: the device comes from query_devices and outlives this call.
        let display = unsafe { Display::with_device(device, None) }?;
        let template = ConfigTemplateBuilder::new()
            .with_surface_type(ConfigSurfaceTypes::PBUFFER)
            .with_api(Api::OPENGL)
            .build();
        // SAFETY: the template is valid for this display.
        let config = unsafe { display.find_configs(template) }?
            .next()
            .ok_or(DeviceRefusal::NoConfig)?;
        let mut last = None;
        for attrs in compatibility_attributes(None) {
            // SAFETY: config belongs to display; no window handle.
            match unsafe { display.create_context(&config, &attrs) } {
                Ok(ctx) => {
                    let ctx = ctx.make_current_surfaceless()?;
                    let gpu = Gpu::from_loader(|s| display.get_proc_address(s))?;
                    return Ok(Headless {
                        gpu,
                        backend: Backend::Egl,
                        _context: HeadlessContext::Egl {
                            _context: ctx,
                            _display: display,
                        },
                    });
                }
                Err(e) => last = Some(e),
            }
        }
        Err(DeviceRefusal::NoContext(last))
    }

    fn osmesa() -> GlResult<Headless> {
        let ctx = OsmesaContext::new()?;
        let get_proc = ctx.get_proc_address;
        let gpu = Gpu::from_loader(|name| {
            // SAFETY: OSMesaGetProcAddress takes a NUL-terminated name.
            unsafe { get_proc(name.as_ptr()) }
        })?;
        Ok(Headless {
            gpu,
            backend: Backend::Osmesa,
            _context: HeadlessContext::Osmesa { _context: ctx },
        })
    }
}

/// Why one EGL device gave no context.
#[derive(Debug, thiserror::Error)]
enum DeviceRefusal {
    /// EGL refused a call.
    #[error("{0}")]
    Egl(#[from] glutin::error::Error),
    /// The device has no configuration for offscreen OpenGL.
    #[error("no PBUFFER-capable OpenGL config")]
    NoConfig,
    /// No compatibility-profile context of any version (the last refusal).
    #[error("no compatibility-profile context: {}", .0.as_ref().map_or(String::new(), |e| e.to_string()))]
    NoContext(Option<glutin::error::Error>),
    /// The context's GL lacks what arbvis needs.
    #[error("{0}")]
    Gl(#[from] GlError),
}

/// Context attributes to try, best first: compatibility profile 4.5, then 3.0, then any
/// version (a context without a profile is Core 3.3 on Mesa, which has no ARB programs).
pub(super) fn compatibility_attributes(
    window: Option<raw_window_handle::RawWindowHandle>,
) -> Vec<glutin::context::ContextAttributes> {
    [Some(Version::new(4, 5)), Some(Version::new(3, 0)), None]
        .into_iter()
        .map(|version| {
            ContextAttributesBuilder::new()
                .with_profile(GlProfile::Compatibility)
                .with_context_api(ContextApi::OpenGl(version))
                .build(window)
        })
        .collect()
}

/// File names tried for libOSMesa, newest soname first (`ARBVIS_OSMESA_LIBRARY` overrides).
pub const OSMESA_LIBRARIES: [&str; 3] = ["libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"];
const OSMESA_RGBA: u32 = 0x1908; // GL_RGBA
const GL_UNSIGNED_BYTE: u32 = 0x1401;

type CreateContextExt = unsafe extern "C" fn(u32, i32, i32, i32, *mut c_void) -> *mut c_void;
type MakeCurrent = unsafe extern "C" fn(*mut c_void, *mut c_void, u32, i32, i32) -> u8;
type GetProcAddress = unsafe extern "C" fn(*const c_char) -> *const c_void;
type DestroyContext = unsafe extern "C" fn(*mut c_void);

struct OsmesaContext {
    context: *mut c_void,
    destroy: DestroyContext,
    get_proc_address: GetProcAddress,
    // OSMesa needs a colour buffer to make a context current; all drawing goes to FBOs.
    _buffer: Box<[u8; 4]>,
    _library: libloading::Library,
}

impl OsmesaContext {
    fn new() -> GlResult<OsmesaContext> {
        // ARBVIS_OSMESA_LIBRARY names one file to load instead (a custom Mesa build).
        let custom = std::env::var("ARBVIS_OSMESA_LIBRARY").ok();
        let names: Vec<&str> = match &custom {
            Some(c) => vec![c.as_str()],
            None => OSMESA_LIBRARIES.to_vec(),
        };
        let mut last = String::new();
        let mut library = None;
        for &name in &names {
            // SAFETY: loading libOSMesa runs its initializers, which have no preconditions.
            match unsafe { libloading::Library::new(name) } {
                Ok(l) => {
                    library = Some(l);
                    break;
                }
                Err(e) => last = e.to_string(),
            }
        }
        let library = library.ok_or_else(|| GlError::MissingLibrary {
            library: "libOSMesa",
            tried: names.join(", "),
            reason: last,
            hint: "install Debian's libosmesa6 (apt-get install libosmesa6), or use --backend egl",
        })?;
        let err = |reason: String| GlError::Context {
            backend: "osmesa",
            reason,
        };
        // SAFETY: symbol types match osmesa.h.
        unsafe {
            let sym = |name: &[u8]| -> GlResult<*const c_void> {
                library
                    .get::<*const c_void>(name)
                    .map(|s| *s)
                    .map_err(|e| err(e.to_string()))
            };
            let create: CreateContextExt = std::mem::transmute(sym(b"OSMesaCreateContextExt\0")?);
            let make_current: MakeCurrent = std::mem::transmute(sym(b"OSMesaMakeCurrent\0")?);
            let get_proc_address: GetProcAddress =
                std::mem::transmute(sym(b"OSMesaGetProcAddress\0")?);
            let destroy: DestroyContext = std::mem::transmute(sym(b"OSMesaDestroyContext\0")?);
            // Mesa creates a compatibility-profile context here, at the highest version.
            let context = create(OSMESA_RGBA, 24, 8, 0, std::ptr::null_mut());
            if context.is_null() {
                return Err(err("OSMesaCreateContextExt returned null".into()));
            }
            let mut buffer = Box::new([0u8; 4]);
            if make_current(context, buffer.as_mut_ptr().cast(), GL_UNSIGNED_BYTE, 1, 1) == 0 {
                destroy(context);
                return Err(err("OSMesaMakeCurrent failed".into()));
            }
            Ok(OsmesaContext {
                context,
                destroy,
                get_proc_address,
                _buffer: buffer,
                _library: library,
            })
        }
    }
}

impl Drop for OsmesaContext {
    fn drop(&mut self) {
        // SAFETY: the context was created by this library and is destroyed once.
        unsafe { (self.destroy)(self.context) };
    }
}
