//! What can go wrong preparing a clip (its own file, so that every part of the clip
//! can name it without importing the module that assembles them).

/// Errors preparing a clip: the shape's files, or parameters that cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum ClipError {
    /// A clip mesh could not be read.
    #[error(transparent)]
    Surface(#[from] arbvis_data::surface::SurfaceError),
    /// A mask volume could not be read.
    #[error(transparent)]
    Volume(#[from] arbvis_data::volume::VolumeError),
    /// Parameters out of range, or a texture that cannot be built.
    #[error("{0}")]
    Invalid(String),
}

/// A program text the clip cannot be composed into.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ComposeError {
    /// An ARB text without its header.
    #[error("not an ARB fragment program (no !!ARBfp1.0 header)")]
    NoArbHeader,
    /// A GLSL text without the function the clip goes into.
    #[error("no `{0}` in the GLSL text")]
    NoFunction(String),
    /// That function's header without a body.
    #[error("`{0}` has no body")]
    NoBody(String),
}
