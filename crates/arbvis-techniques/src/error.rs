//! What can go wrong making or drawing a technique's picture: the GL's errors and every
//! data layer's, kept as their own types (`#[from]`) so that a caller can still ask which
//! file and position failed, and each prints the message its layer wrote.

use arbvis_core::budget::{OverBudget, SizeError};
use arbvis_core::colortable::TableError;
use arbvis_core::vocab::FieldError;
use arbvis_data::mesh::MeshError;
use arbvis_data::points::PointsError;
use arbvis_data::store::StoreError;
use arbvis_data::surface::SurfaceError;
use arbvis_data::volume::VolumeError;
use arbvis_gl::GlError;

/// An error preparing data for a renderer, making one or drawing with it.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The GL refused (a context, a program, a texture, memory).
    #[error(transparent)]
    Gl(#[from] GlError),
    /// A volume could not be read or used.
    #[error(transparent)]
    Volume(#[from] VolumeError),
    /// A mesh could not be read or used.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A point cloud could not be read or used.
    #[error(transparent)]
    Points(#[from] PointsError),
    /// A survey store could not be read.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A surface could not be read.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// A brick of a survey store failed to load on the loader thread (shared: the
    /// cache keeps it to answer every frame that asks for the brick).
    #[error(transparent)]
    Brick(#[from] std::sync::Arc<StoreError>),
    /// A colour table could not be made.
    #[error(transparent)]
    Table(#[from] TableError),
    /// A memory size that is not one.
    #[error(transparent)]
    Size(#[from] SizeError),
    /// Over the memory budget.
    #[error(transparent)]
    Budget(#[from] OverBudget),
    /// Parameters that parse but cannot be drawn (the key is relative to the technique's
    /// table).
    #[error(transparent)]
    Parameters(#[from] FieldError),
    /// One layer of a layered scene failed: the error names it.
    #[error("layer {index} ({name}): {source}")]
    Layer {
        /// 0-based, as `layer.INDEX` keys count.
        index: usize,
        /// Its name, or "unnamed".
        name: String,
        /// What failed.
        source: Box<RenderError>,
    },
    /// A layer whose data cannot be placed in a scene's world frame.
    #[error("{0}")]
    Unplaced(String),
    /// A worker thread could not be started.
    #[error("cannot start a thread: {0}")]
    Thread(std::io::Error),
    /// A worker thread stopped answering.
    #[error("{0}")]
    Stalled(&'static str),
    /// A table of more texels than the driver's largest 2D texture holds in rows.
    #[error(
        "{label}: {texels} texels need {rows} rows of {row}, more than this driver's {max} \
         (GL_MAX_TEXTURE_SIZE)"
    )]
    TooManyRows {
        /// The texture.
        label: String,
        /// Texels asked for.
        texels: usize,
        /// Rows they need.
        rows: usize,
        /// Texels per row.
        row: usize,
        /// GL_MAX_TEXTURE_SIZE.
        max: usize,
    },
    /// A technique's own error (3D opacity's attribute data and tables, its clip, its ray
    /// caster's bricks): the type is the technique's (`source` downcasts to it), the
    /// message its own.
    #[error("{source}")]
    Technique {
        /// The technique's name, as scenes write it.
        technique: &'static str,
        /// Its error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The legends and axes could not be drawn.
    #[error("drawing the legends and axes: {0}")]
    Annotate(#[from] AnnotateError),
}

/// Drawing the legends and axes onto a picture failed ([`crate::annotate`]).
#[derive(Debug, thiserror::Error)]
pub enum AnnotateError {
    /// The font did not register.
    #[error("the annotation font did not load")]
    Font,
    /// plotters could not draw.
    #[error(transparent)]
    Draw(#[from] AnnotationDrawing),
}

/// plotters' error drawing on a bitmap.
pub type AnnotationDrawing = plotters::drawing::DrawingAreaErrorKind<
    <plotters::backend::BitMapBackend<'static> as plotters::backend::DrawingBackend>::ErrorType,
>;

/// Rows of `row` texels a 2D texture needs to hold `texels` (at least one), within the
/// driver's largest 2D texture, or [`RenderError::TooManyRows`] naming `label`.
pub fn texture_rows(
    gpu: &arbvis_gl::Gpu,
    label: &str,
    texels: usize,
    row: usize,
) -> RenderResult<usize> {
    let rows = texels.div_ceil(row).max(1);
    let max = gpu.caps().max_texture_size.max(1) as usize;
    if rows > max {
        return Err(RenderError::TooManyRows {
            label: label.to_string(),
            texels,
            rows,
            row,
            max,
        });
    }
    Ok(rows)
}

/// A result whose error is a [`RenderError`].
pub type RenderResult<T> = Result<T, RenderError>;
