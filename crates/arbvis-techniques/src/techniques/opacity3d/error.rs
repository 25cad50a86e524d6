//! What only 3D opacity refuses: an attribute's data or colour table, the clip composed
//! into its programs, and the precise ray caster's bricks beyond the GPU budget. The
//! shared [`RenderError`] carries it as a technique's error ([`RenderError::Technique`]).

use crate::error::RenderError;
use crate::techniques::clip::error::{ClipError, ComposeError};
use arbvis_core::colortable::TableError;

/// 3D opacity's own errors.
#[derive(Debug, thiserror::Error)]
pub enum Opacity3dError {
    /// A clip could not be prepared.
    #[error("clip: {0}")]
    Clip(#[from] ClipError),
    /// The clip could not be composed into a program's text.
    #[error("clip composition of {program}: {source}")]
    Compose {
        /// The program.
        program: String,
        /// Why.
        source: ComposeError,
    },
    /// The precise ray caster needs more bricks resident at once than the GPU budget
    /// holds.
    #[error(
        "the precise ray caster draws in one pass and needs its {bricks} bricks resident at \
         once, more than the {capacity} the GPU budget holds: raise --gpu-memory (or \
         store.gpu_memory), or draw a coarser level"
    )]
    GpuBudget {
        /// Bricks the view needs.
        bricks: usize,
        /// Bricks the budget holds.
        capacity: usize,
    },
    /// One attribute's colour table (`primary`, ...).
    #[error("{attribute} table: {source}")]
    AttributeTable {
        /// The attribute.
        attribute: &'static str,
        /// What failed.
        source: TableError,
    },
    /// One attribute's data (`primary`, `secondary`, `tertiary`).
    #[error("{attribute}: {source}")]
    Attribute {
        /// The attribute.
        attribute: &'static str,
        /// What failed.
        source: Box<RenderError>,
    },
}

impl Opacity3dError {
    /// Whether the user's input (a data file, a table) is at fault, not the drawing.
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            Opacity3dError::AttributeTable { .. } | Opacity3dError::Attribute { .. }
        )
    }

    /// `error`, said of attribute `attribute`.
    pub fn of_attribute(error: RenderError, attribute: &'static str) -> RenderError {
        Opacity3dError::Attribute {
            attribute,
            source: Box::new(error),
        }
        .into()
    }
}

impl From<Opacity3dError> for RenderError {
    fn from(e: Opacity3dError) -> RenderError {
        RenderError::Technique {
            technique: <super::Opacity3dScene as crate::techniques::Technique>::NAME,
            source: Box::new(e),
        }
    }
}

impl From<ClipError> for RenderError {
    fn from(e: ClipError) -> RenderError {
        Opacity3dError::Clip(e).into()
    }
}
