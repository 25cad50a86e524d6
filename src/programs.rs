//! The program texts of `programs/`, embedded, and the pairs each technique draws with.

use crate::gl::{ProgramKind, ProgramText};

macro_rules! program {
    ($path:literal) => {
        ProgramText::embedded($path, include_str!(concat!("../programs/", $path)))
    };
}

/// `common/transform.arbvp`: MVP in vertex locals 0..3, texcoord 0 passed through.
pub const TRANSFORM_ARBVP: ProgramText = program!("common/transform.arbvp");
/// GLSL twin of [`TRANSFORM_ARBVP`].
pub const TRANSFORM_VERT: ProgramText = program!("common/transform.vert");
/// `--demo quad` fragment program (ARB).
pub const QUAD_ARBFP: ProgramText = program!("quad/quad.arbfp");
/// GLSL twin of [`QUAD_ARBFP`].
pub const QUAD_FRAG: ProgramText = program!("quad/quad.frag");
/// v3o2's sum program, verbatim (the C strings joined with no separator).
pub const OPACITY3D_SUM_ARBFP: ProgramText = program!("opacity3d/sum.arbfp");
/// v3o2's product program, verbatim.
pub const OPACITY3D_PRODUCT_ARBFP: ProgramText = program!("opacity3d/product.arbfp");
/// GLSL port of the sum program.
pub const OPACITY3D_SUM_FRAG: ProgramText = program!("opacity3d/sum.frag");
/// GLSL port of the product program.
pub const OPACITY3D_PRODUCT_FRAG: ProgramText = program!("opacity3d/product.frag");

/// Precise sum (new): texel-centre lookup, clamp, opacity correction.
pub const OPACITY3D_SUM_PRECISE_ARBFP: ProgramText = program!("opacity3d/sum_precise.arbfp");
/// GLSL twin of [`OPACITY3D_SUM_PRECISE_ARBFP`].
pub const OPACITY3D_SUM_PRECISE_FRAG: ProgramText = program!("opacity3d/sum_precise.frag");
/// Precise product (new).
pub const OPACITY3D_PRODUCT_PRECISE_ARBFP: ProgramText =
    program!("opacity3d/product_precise.arbfp");
/// GLSL twin of [`OPACITY3D_PRODUCT_PRECISE_ARBFP`].
pub const OPACITY3D_PRODUCT_PRECISE_FRAG: ProgramText = program!("opacity3d/product_precise.frag");

/// A vertex + fragment pair of one kind.
#[derive(Debug, Clone)]
pub struct ProgramPair {
    /// Which language.
    pub kind: ProgramKind,
    /// Vertex stage.
    pub vertex: ProgramText,
    /// Fragment stage.
    pub fragment: ProgramText,
}

/// The pair that draws fragment program `arb` or its GLSL twin `glsl`, with the common
/// transform as vertex stage.
pub fn with_transform(kind: ProgramKind, arb: &ProgramText, glsl: &ProgramText) -> ProgramPair {
    match kind {
        ProgramKind::Arb => ProgramPair {
            kind,
            vertex: TRANSFORM_ARBVP,
            fragment: arb.clone(),
        },
        ProgramKind::Glsl => ProgramPair {
            kind,
            vertex: TRANSFORM_VERT,
            fragment: glsl.clone(),
        },
    }
}

/// Every pair the techniques can draw with, both kinds (the compile-everything test).
pub fn all_pairs() -> Vec<ProgramPair> {
    let fragments = [
        (QUAD_ARBFP, QUAD_FRAG),
        (OPACITY3D_SUM_ARBFP, OPACITY3D_SUM_FRAG),
        (OPACITY3D_PRODUCT_ARBFP, OPACITY3D_PRODUCT_FRAG),
        (OPACITY3D_SUM_PRECISE_ARBFP, OPACITY3D_SUM_PRECISE_FRAG),
        (
            OPACITY3D_PRODUCT_PRECISE_ARBFP,
            OPACITY3D_PRODUCT_PRECISE_FRAG,
        ),
    ];
    let mut pairs = Vec::new();
    for (arb, glsl) in &fragments {
        for kind in [ProgramKind::Arb, ProgramKind::Glsl] {
            pairs.push(with_transform(kind, arb, glsl));
        }
    }
    pairs
}

/// Every embedded text, by name (to check that `programs/` holds nothing unembedded).
pub fn all_texts() -> Vec<ProgramText> {
    vec![
        TRANSFORM_ARBVP,
        TRANSFORM_VERT,
        QUAD_ARBFP,
        QUAD_FRAG,
        OPACITY3D_SUM_ARBFP,
        OPACITY3D_PRODUCT_ARBFP,
        OPACITY3D_SUM_FRAG,
        OPACITY3D_PRODUCT_FRAG,
        OPACITY3D_SUM_PRECISE_ARBFP,
        OPACITY3D_SUM_PRECISE_FRAG,
        OPACITY3D_PRODUCT_PRECISE_ARBFP,
        OPACITY3D_PRODUCT_PRECISE_FRAG,
    ]
}
