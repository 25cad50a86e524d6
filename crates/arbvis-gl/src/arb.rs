//! ARB assembly program entry points, loaded through the context's `get_proc_address`
//! (glow has none of them). Only the calls the seeds use, plus what error reporting and
//! `arbvis info` need.

use std::ffi::{c_void, CStr};

/// `GL_VERTEX_PROGRAM_ARB`.
pub const VERTEX_PROGRAM: u32 = 0x8620;
/// `GL_FRAGMENT_PROGRAM_ARB`.
pub const FRAGMENT_PROGRAM: u32 = 0x8804;
/// `GL_PROGRAM_FORMAT_ASCII_ARB`.
pub const PROGRAM_FORMAT_ASCII: u32 = 0x8875;
/// `GL_PROGRAM_ERROR_POSITION_ARB`.
pub const PROGRAM_ERROR_POSITION: u32 = 0x864B;
/// `GL_PROGRAM_ERROR_STRING_ARB`.
pub const PROGRAM_ERROR_STRING: u32 = 0x8874;
/// `GL_MAX_PROGRAM_NATIVE_INSTRUCTIONS_ARB`.
pub const MAX_NATIVE_INSTRUCTIONS: u32 = 0x88A3;
/// `GL_MAX_PROGRAM_NATIVE_TEMPORARIES_ARB`.
pub const MAX_NATIVE_TEMPORARIES: u32 = 0x88A7;
/// `GL_MAX_PROGRAM_NATIVE_TEX_INDIRECTIONS_ARB`.
pub const MAX_NATIVE_TEX_INDIRECTIONS: u32 = 0x8810;
/// `GL_MAX_PROGRAM_LOCAL_PARAMETERS_ARB`.
pub const MAX_LOCAL_PARAMETERS: u32 = 0x88B4;

type GenPrograms = unsafe extern "system" fn(i32, *mut u32);
type DeletePrograms = unsafe extern "system" fn(i32, *const u32);
type BindProgram = unsafe extern "system" fn(u32, u32);
type ProgramString = unsafe extern "system" fn(u32, u32, i32, *const c_void);
type ProgramLocal4d = unsafe extern "system" fn(u32, u32, f64, f64, f64, f64);
type GetProgramiv = unsafe extern "system" fn(u32, u32, *mut i32);
type GetString = unsafe extern "system" fn(u32) -> *const u8;
type TexEnvi = unsafe extern "system" fn(u32, u32, i32);

/// `GL_POINT_SPRITE` (compatibility profile).
pub const POINT_SPRITE: u32 = 0x8861;
/// `GL_COORD_REPLACE` (compatibility profile).
pub const COORD_REPLACE: u32 = 0x8862;

/// The ARB program function table.
#[derive(Clone, Copy)]
pub struct ArbFns {
    gen_programs: GenPrograms,
    delete_programs: DeletePrograms,
    bind_program: BindProgram,
    program_string: ProgramString,
    program_local_4d: ProgramLocal4d,
    get_programiv: GetProgramiv,
    get_string: GetString,
    tex_envi: TexEnvi,
}

impl std::fmt::Debug for ArbFns {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ArbFns")
    }
}

impl ArbFns {
    /// Load every entry point; `None` when any is missing.
    pub(crate) fn load(loader: &mut dyn FnMut(&CStr) -> *const c_void) -> Option<ArbFns> {
        macro_rules! load {
            ($name:literal, $ty:ty) => {{
                let p = loader($name);
                if p.is_null() {
                    return None;
                }
                // SAFETY: the pointer comes from the context's loader for this exact
                // entry point, whose C signature is the one of the target type.
                unsafe { std::mem::transmute::<*const c_void, $ty>(p) }
            }};
        }
        Some(ArbFns {
            gen_programs: load!(c"glGenProgramsARB", GenPrograms),
            delete_programs: load!(c"glDeleteProgramsARB", DeletePrograms),
            bind_program: load!(c"glBindProgramARB", BindProgram),
            program_string: load!(c"glProgramStringARB", ProgramString),
            program_local_4d: load!(c"glProgramLocalParameter4dARB", ProgramLocal4d),
            get_programiv: load!(c"glGetProgramivARB", GetProgramiv),
            get_string: load!(c"glGetString", GetString),
            tex_envi: load!(c"glTexEnvi", TexEnvi),
        })
    }

    /// `glGenProgramsARB(1, &id)`.
    pub(crate) fn gen_program(&self) -> u32 {
        let mut id = 0;
        // SAFETY: one id written into a valid u32.
        unsafe { (self.gen_programs)(1, &mut id) };
        id
    }

    /// `glDeleteProgramsARB(1, &id)`.
    pub(crate) fn delete_program(&self, id: u32) {
        // SAFETY: reads one u32.
        unsafe { (self.delete_programs)(1, &id) };
    }

    /// `glBindProgramARB(target, id)`.
    pub(crate) fn bind_program(&self, target: u32, id: u32) {
        // SAFETY: plain values.
        unsafe { (self.bind_program)(target, id) };
    }

    /// `glProgramStringARB`, the bytes handed over exactly as given.
    pub(crate) fn program_string(&self, target: u32, text: &[u8]) {
        // SAFETY: pointer and length describe the live slice.
        unsafe {
            (self.program_string)(
                target,
                PROGRAM_FORMAT_ASCII,
                text.len() as i32,
                text.as_ptr().cast(),
            )
        };
    }

    /// `glProgramLocalParameter4dARB` (as v3o2 set its coefficients).
    pub(crate) fn program_local_4d(&self, target: u32, index: u32, v: [f64; 4]) {
        // SAFETY: plain values.
        unsafe { (self.program_local_4d)(target, index, v[0], v[1], v[2], v[3]) };
    }

    /// `glGetProgramivARB`.
    pub(crate) fn get_programiv(&self, target: u32, pname: u32) -> i32 {
        let mut v = 0;
        // SAFETY: one int written into a valid i32.
        unsafe { (self.get_programiv)(target, pname, &mut v) };
        v
    }

    /// `glGetString` that tolerates a null result (glow's does not).
    pub(crate) fn get_string(&self, name: u32) -> String {
        // SAFETY: glGetString returns null or a NUL-terminated static string.
        unsafe {
            let p = (self.get_string)(name);
            if p.is_null() {
                String::new()
            } else {
                CStr::from_ptr(p.cast()).to_string_lossy().into_owned()
            }
        }
    }

    /// `glTexEnvi(GL_POINT_SPRITE, GL_COORD_REPLACE, on)` for the active texture unit:
    /// point sprites hand their coordinates to ARB fragment programs as that unit's
    /// `fragment.texcoord`.
    pub(crate) fn coord_replace(&self, on: bool) {
        // SAFETY: plain values.
        unsafe { (self.tex_envi)(POINT_SPRITE, COORD_REPLACE, on as i32) };
    }

    /// `glGetIntegerv(GL_PROGRAM_ERROR_POSITION_ARB)` through glow.
    pub(crate) fn error_position(gl: &glow::Context) -> i32 {
        use glow::HasContext;
        // SAFETY: a plain integer query.
        unsafe { gl.get_parameter_i32(PROGRAM_ERROR_POSITION) }
    }
}
