//! 3D opacity clipped by a clip object (`[technique.opacity3d.clip]`, seed 002): the
//! clip's textures built on the CPU over the prepared volume's box, its GPU stage
//! ([`ClipStage`], units 7/8, locals 10..13), and each program of 3D opacity composed
//! with the clip test:
//! - faithful ARB: the verbatim v3o2 text with the clip prologue inserted after its
//!   `!!ARBfp1.0` header ([`compose_arb`]); the verbatim file stays byte for byte and the
//!   composed text ends with its body unchanged;
//! - precise slicing (ARB and GLSL) and the GLSL twins: the same prologue, or
//!   `clip_value` and a `discard` first in `main` ([`compose_glsl`]);
//! - the ray caster: `clip_value` per sample at the top of `classify`, where a clipped
//!   sample returns transparent black and so contributes nothing. With a clip the ray
//!   caster point-samples: pre-integration and the baked step table read whole steps
//!   without `classify`, so they are turned off ([`super::renderer::preintegrated`],
//!   [`super::renderer::step_table`]).
//!
//! On slices a clipped fragment is discarded: its slab (the length of ray it stands for)
//! is left out whole, so the clip boundary is placed to within half a slice spacing along
//! each ray; the ray caster places it to within half a step.
//!
//! # Cost
//! The clip-sphere demo (64³ x 3 attributes, inverted sphere, B = 8), timed by
//! `arbvis bench` against the same scene without a clip and with the single-resolution
//! texture (measured: docs/benchmarks.md, "Clipping"): every path pays for the clip. As
//! the seed found, INDEX-DATA is slower than the single texture (two dependent fetches);
//! on the ray caster, whose samples all pay the lookup, the two cost alike.

use crate::error::RenderResult;
use std::borrow::Cow;
use std::path::Path;
use std::time::Instant;

use super::prepare::Prepared;
use super::Path3d;
use crate::programs::ProgramPair;
use crate::techniques::clip::multires::IndexEncoding;
use crate::techniques::clip::stage::{
    arb_prologue, compose_arb, compose_glsl, compose_glsl_at, glsl_function, glsl_function_exact,
    ClipStage, Lookup,
};
use crate::techniques::clip::stats::ClipStats;
use crate::techniques::clip::{ClipSpec, ClipTextures};
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{Gpu, ProgramKind, ProgramText};

/// Where 3D opacity's programs read the sample's volume coordinate.
pub const ARB_COORD: &str = "fragment.texcoord[0]";
/// The GLSL twin of [`ARB_COORD`].
pub const GLSL_COORD: &str = "v_texcoord0.xyz";
/// The ray caster's per-sample function, which the clip test opens.
pub const CLASSIFY: &str = "vec4 classify(vec3 tc)";

/// A clip ready to draw with: its scene value, CPU textures (the f64 shape among them)
/// and GPU stage.
pub struct Clip {
    /// What the scene asked for.
    pub spec: ClipSpec,
    /// The shape and textures (CPU).
    pub textures: ClipTextures,
    /// The uploaded textures and constants.
    pub stage: ClipStage,
    /// What the build took and what the upload costs (the viewer's clip editor).
    pub stats: ClipStats,
}

/// Build `spec`'s textures over `prepared`'s box (files relative to `base`) and upload
/// them for `fidelity`; INDEX-DATA when `spec.multires`, else the single texture. The
/// build is timed (CPU textures and upload) into [`Clip::stats`].
pub fn build(
    gpu: &Gpu,
    spec: &ClipSpec,
    base: &Path,
    prepared: &Prepared,
    fidelity: Fidelity,
) -> RenderResult<Clip> {
    let start = Instant::now();
    let max = gpu.caps().max_3d_texture_size.max(1) as usize;
    let textures = spec.build(base, prepared.dims, prepared.half.to_array(), max)?;
    let stage = ClipStage::new(gpu, &textures, fidelity)?;
    let stats = ClipStats::of(&textures, fidelity, start.elapsed().as_secs_f64());
    Ok(Clip {
        spec: spec.clone(),
        textures,
        stage,
        stats,
    })
}

/// `pair`'s fragment program (drawn on `path`) with `stage`'s clip test composed in; with
/// `exact` (a precise GLSL program whose linear reads are the shader's) the clip values
/// are interpolated in the shader too.
pub fn compose(
    pair: ProgramPair,
    stage: &ClipStage,
    path: Path3d,
    exact: bool,
) -> RenderResult<ProgramPair> {
    let text = &pair.fragment.text;
    let function = match exact {
        true => glsl_function_exact(stage.lookup),
        false => stage.glsl_function(),
    };
    let composed = match (pair.kind, path) {
        (ProgramKind::Arb, _) => compose_arb(text, &stage.arb_prologue(ARB_COORD)),
        (ProgramKind::Glsl, Path3d::Slicing) => compose_glsl(text, &function, GLSL_COORD),
        (ProgramKind::Glsl, Path3d::Raycast) => compose_glsl_at(
            text,
            &function,
            CLASSIFY,
            "if (clip_value(tc) < 0.5) return vec4(0.0);",
        ),
    }
    .map_err(
        |source| crate::techniques::opacity3d::error::Opacity3dError::Compose {
            program: pair.fragment.name.to_string(),
            source,
        },
    )?;
    Ok(ProgramPair {
        fragment: ProgramText {
            name: Cow::Owned(format!("{} + clip {:?}", pair.fragment.name, stage.lookup)),
            text: Cow::Owned(composed),
        },
        ..pair
    })
}

/// The verbatim v3o2 pairs (sum, product; ARB and GLSL) composed with every clip lookup,
/// for the compile-everything test (`programs/clip/` holds fragments, not programs).
pub fn all_clip_pairs() -> Vec<ProgramPair> {
    use super::programs::faithful_pair;
    use super::Combine;
    let lookups = [
        Lookup::Single,
        Lookup::Multires(IndexEncoding::SlotCentre),
        Lookup::Multires(IndexEncoding::Offset),
    ];
    let mut out = Vec::new();
    for combine in [Combine::Sum, Combine::Product] {
        for kind in [ProgramKind::Arb, ProgramKind::Glsl] {
            let pair = faithful_pair(kind, combine);
            for lookup in lookups {
                let text = &pair.fragment.text;
                let composed = match kind {
                    ProgramKind::Arb => compose_arb(text, &arb_prologue(lookup, ARB_COORD)),
                    ProgramKind::Glsl => compose_glsl(text, &glsl_function(lookup), GLSL_COORD),
                }
                .expect("the verbatim programs take the clip");
                out.push(ProgramPair {
                    fragment: ProgramText {
                        name: Cow::Owned(format!("{} + clip {lookup:?}", pair.fragment.name)),
                        text: Cow::Owned(composed),
                    },
                    ..pair.clone()
                });
            }
        }
    }
    out
}
