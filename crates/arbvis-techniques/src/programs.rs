//! The program texts of `programs/`, embedded, and the pairs each technique draws with.

use arbvis_gl::{ProgramKind, ProgramText};

macro_rules! program {
    ($path:literal) => {
        ProgramText::embedded($path, include_str!(concat!("../../../programs/", $path)))
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

/// Precise slicing (new), a template: specialized per scene by
/// `techniques::opacity3d::programs` (tags and channel placeholders).
pub const OPACITY3D_SLICE_PRECISE_ARBFP: ProgramText = program!("opacity3d/slice_precise.arbfp");
/// GLSL twin of [`OPACITY3D_SLICE_PRECISE_ARBFP`] (the same tags).
pub const OPACITY3D_SLICE_PRECISE_FRAG: ProgramText = program!("opacity3d/slice_precise.frag");
/// Precise single-pass ray caster (new, GLSL only), a template like the slicing one.
pub const OPACITY3D_RAYCAST_FRAG: ProgramText = program!("opacity3d/raycast.frag");
/// The precise 3D-opacity programs' linear reads (GLSL, tagged), joined where a template
/// says `// @sampling`: in the texture unit or, where its weights are coarse, the shader.
pub const OPACITY3D_SAMPLING_GLSL: ProgramText = program!("common/sampling.glsl");
/// The probes of `arbvis bench --breakdown` (new, GLSL), a template.
pub const OPACITY3D_PROBE_FRAG: ProgramText = program!("opacity3d/probe.frag");

/// A surface lit per vertex (faithful): ARB vertex stage.
pub const SURFACE_GOURAUD_ARBVP: ProgramText = program!("surface/gouraud.arbvp");
/// ARB fragment stage of [`SURFACE_GOURAUD_ARBVP`] (the interpolated colour).
pub const SURFACE_GOURAUD_ARBFP: ProgramText = program!("surface/gouraud.arbfp");
/// GLSL twin of [`SURFACE_GOURAUD_ARBVP`].
pub const SURFACE_GOURAUD_VERT: ProgramText = program!("surface/gouraud.vert");
/// GLSL twin of [`SURFACE_GOURAUD_ARBFP`].
pub const SURFACE_GOURAUD_FRAG: ProgramText = program!("surface/gouraud.frag");
/// A surface lit per pixel (precise): ARB vertex stage (normal and colour passed on).
pub const SURFACE_PHONG_ARBVP: ProgramText = program!("surface/phong.arbvp");
/// ARB fragment stage of [`SURFACE_PHONG_ARBVP`] (the headlight per pixel).
pub const SURFACE_PHONG_ARBFP: ProgramText = program!("surface/phong.arbfp");
/// GLSL twin of [`SURFACE_PHONG_ARBVP`].
pub const SURFACE_PHONG_VERT: ProgramText = program!("surface/phong.vert");
/// GLSL twin of [`SURFACE_PHONG_ARBFP`].
pub const SURFACE_PHONG_FRAG: ProgramText = program!("surface/phong.frag");
/// A section as the era drew it (faithful): 8-bit levels, the table's nearest entry.
pub const SECTION_FAITHFUL_ARBFP: ProgramText = program!("section/faithful.arbfp");
/// GLSL twin of [`SECTION_FAITHFUL_ARBFP`].
pub const SECTION_FAITHFUL_FRAG: ProgramText = program!("section/faithful.frag");
/// A section in precise mode: float values interpolated in the program, the table between entries.
pub const SECTION_PRECISE_ARBFP: ProgramText = program!("section/precise.arbfp");
/// GLSL twin of [`SECTION_PRECISE_ARBFP`].
pub const SECTION_PRECISE_FRAG: ProgramText = program!("section/precise.frag");

/// The seed's Cg vertex program (reference text, not compiled).
pub const CELLPROJ_SEED_VERTEX_CG: ProgramText = program!("cellproj/seed_vertex.cg");
/// The seed's Cg fragment program (reference text, not compiled).
pub const CELLPROJ_SEED_FRAGMENT_CG: ProgramText = program!("cellproj/seed_fragment.cg");
/// Cell projection, exit per fragment (the seed's Cg, ported): ARB vertex stage.
pub const CELLPROJ_PERSPECTIVE_ARBVP: ProgramText = program!("cellproj/perspective.arbvp");
/// ARB fragment stage of [`CELLPROJ_PERSPECTIVE_ARBVP`].
pub const CELLPROJ_PERSPECTIVE_ARBFP: ProgramText = program!("cellproj/perspective.arbfp");
/// GLSL twin of [`CELLPROJ_PERSPECTIVE_ARBVP`].
pub const CELLPROJ_PERSPECTIVE_VERT: ProgramText = program!("cellproj/perspective.vert");
/// GLSL twin of [`CELLPROJ_PERSPECTIVE_ARBFP`].
pub const CELLPROJ_PERSPECTIVE_FRAG: ProgramText = program!("cellproj/perspective.frag");
/// Cell projection, exit per vertex (the seed's orthographic case): ARB vertex stage.
pub const CELLPROJ_ORTHOGRAPHIC_ARBVP: ProgramText = program!("cellproj/orthographic.arbvp");
/// ARB fragment stage of [`CELLPROJ_ORTHOGRAPHIC_ARBVP`].
pub const CELLPROJ_ORTHOGRAPHIC_ARBFP: ProgramText = program!("cellproj/orthographic.arbfp");
/// GLSL twin of [`CELLPROJ_ORTHOGRAPHIC_ARBVP`].
pub const CELLPROJ_ORTHOGRAPHIC_VERT: ProgramText = program!("cellproj/orthographic.vert");
/// GLSL twin of [`CELLPROJ_ORTHOGRAPHIC_ARBFP`].
pub const CELLPROJ_ORTHOGRAPHIC_FRAG: ProgramText = program!("cellproj/orthographic.frag");
/// Precise cell projection (new, GLSL only): vertex stage.
pub const CELLPROJ_PRECISE_VERT: ProgramText = program!("cellproj/precise.vert");
/// Precise cell projection: fragment stage (exact crossing, guarded exit, depth, shading).
pub const CELLPROJ_PRECISE_FRAG: ProgramText = program!("cellproj/precise.frag");
/// Volume, faithful: the seed's exit computation and the pre-integrated 3D table.
pub const CELLPROJ_VOLUME_ARBFP: ProgramText = program!("cellproj/volume.arbfp");
/// GLSL twin of [`CELLPROJ_VOLUME_ARBFP`].
pub const CELLPROJ_VOLUME_FRAG: ProgramText = program!("cellproj/volume.frag");
/// Volume, faithful, orthographic: the exit parameters from the vertices
/// ([`CELLPROJ_ORTHOGRAPHIC_ARBVP`]), then the pre-integrated 3D table.
pub const CELLPROJ_VOLUME_ORTHOGRAPHIC_ARBFP: ProgramText =
    program!("cellproj/volume_orthographic.arbfp");
/// GLSL twin of [`CELLPROJ_VOLUME_ORTHOGRAPHIC_ARBFP`].
pub const CELLPROJ_VOLUME_ORTHOGRAPHIC_FRAG: ProgramText =
    program!("cellproj/volume_orthographic.frag");
/// Volume, precise `table` with the exit per fragment: the cell's planes per corner,
/// passed on `flat` (vertex stage).
pub const CELLPROJ_VOLUME_CELL_VERT: ProgramText = program!("cellproj/volume_cell.vert");
/// Volume, precise `table` per fragment: the segment between the cell's planes, then the
/// pre-integrated table.
pub const CELLPROJ_VOLUME_CELL_FRAG: ProgramText = program!("cellproj/volume_cell.frag");
/// Volume, precise: the boundary faces for the entry layers (vertex stage).
pub const CELLPROJ_VOLUME_PEEL_VERT: ProgramText = program!("cellproj/volume_peel.vert");
/// Volume, precise: one entry layer (depth peeling of the boundary).
pub const CELLPROJ_VOLUME_PEEL_FRAG: ProgramText = program!("cellproj/volume_peel.frag");
/// Volume, precise: the neighbour walk (joined with [`CELLPROJ_VOLUME_INTEGRAL_GLSL`]).
pub const CELLPROJ_VOLUME_WALK_FRAG: ProgramText = program!("cellproj/volume_walk.frag");
/// Volume, precise `grid`: the mesh resampled to a grid and ray cast (joined with
/// [`CELLPROJ_VOLUME_INTEGRAL_GLSL`]).
pub const CELLPROJ_VOLUME_GRID_FRAG: ProgramText = program!("cellproj/volume_grid.frag");
/// Volume, precise as a projection: exact integral per fragment, CPU order.
pub const CELLPROJ_VOLUME_PROJECTED_FRAG: ProgramText = program!("cellproj/volume_projected.frag");
/// Volume, precise: the exact segment integral, a GLSL part joined before a main.
pub const CELLPROJ_VOLUME_INTEGRAL_GLSL: ProgramText = program!("cellproj/volume_integral.glsl");

/// Splats: the vertex stage (the seed's size rule, per-point Phong).
pub const SPLATS_VERT: ProgramText = program!("splats/splat.vert");
/// Splats: the seed's fragment functions as written.
pub const SPLATS_SEED_FRAG: ProgramText = program!("splats/seed.frag");
/// Splats: the corrected fragment stage (footprint from `gl_FragCoord`).
pub const SPLATS_PRECISE_FRAG: ProgramText = program!("splats/precise.frag");
/// Splats, precise: [`SPLATS_VERT`] plus each splat's window position and size.
pub const SPLATS_PRECISE_VERT: ProgramText = program!("splats/precise.vert");
/// ARB twin of [`SPLATS_VERT`] (`result.pointsize`, the `if`s as selects).
pub const SPLATS_ARBVP: ProgramText = program!("splats/splat.arbvp");
/// ARB twin of [`SPLATS_SEED_FRAG`] (the sprite coordinate as `fragment.texcoord[0]`).
pub const SPLATS_SEED_ARBFP: ProgramText = program!("splats/seed.arbfp");
/// ARB twin of [`SPLATS_PRECISE_FRAG`].
pub const SPLATS_PRECISE_ARBFP: ProgramText = program!("splats/precise.arbfp");
/// ARB twin of [`SPLATS_PRECISE_VERT`].
pub const SPLATS_PRECISE_ARBVP: ProgramText = program!("splats/precise.arbvp");
/// Weighted blended OIT's composite of the splats (ARB, over the common transform).
pub const SPLATS_OIT_COMPOSITE_ARBFP: ProgramText = program!("splats/oit_composite.arbfp");
/// GLSL twin of [`SPLATS_OIT_COMPOSITE_ARBFP`].
pub const SPLATS_OIT_COMPOSITE_FRAG: ProgramText = program!("splats/oit_composite.frag");
/// Splats composited per pixel from tile lists (GLSL only: ARB fragment programs have
/// no loops), over the common transform.
pub const SPLATS_TILES_FRAG: ProgramText = program!("splats/tiles.frag");
/// Eye-dome lighting: the depth pass (vertex and fragment) and the shading pass.
pub const SPLATS_EDL_DEPTH_VERT: ProgramText = program!("splats/edl_depth.vert");
/// See [`SPLATS_EDL_DEPTH_VERT`].
pub const SPLATS_EDL_DEPTH_FRAG: ProgramText = program!("splats/edl_depth.frag");
/// See [`SPLATS_EDL_DEPTH_VERT`].
pub const SPLATS_EDL_FRAG: ProgramText = program!("splats/edl.frag");

/// The pair `pair` chooses for each fidelity and program kind (faithful ARB, faithful
/// GLSL, precise ARB, precise GLSL): a technique's [`crate::techniques::Technique::program_pairs`]
/// where one pair draws each combination.
pub fn each_fidelity_and_kind(
    pair: fn(arbvis_core::vocab::Fidelity, arbvis_gl::ProgramKind) -> ProgramPair,
) -> Vec<ProgramPair> {
    use arbvis_core::vocab::Fidelity;
    use arbvis_gl::ProgramKind;
    [Fidelity::Faithful, Fidelity::Precise]
        .into_iter()
        .flat_map(|f| [ProgramKind::Arb, ProgramKind::Glsl].map(|k| pair(f, k)))
        .collect()
}

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

/// Both kinds of the pair that draws `arb` or its GLSL twin `glsl` (see [`with_transform`]).
pub fn both_kinds(arb: &ProgramText, glsl: &ProgramText) -> Vec<ProgramPair> {
    [ProgramKind::Arb, ProgramKind::Glsl]
        .map(|kind| with_transform(kind, arb, glsl))
        .into()
}

/// Clip prologue (seed 002), single resolution: inserted after a host's `!!ARBfp1.0`.
pub const CLIP_SINGLE_ARBFP: ProgramText = program!("clip/single.arbfp");
/// Clip prologue, INDEX-DATA with the seed's coordinate formula (faithful).
pub const CLIP_MULTIRES_SLOT_CENTRE_ARBFP: ProgramText =
    program!("clip/multires_slot_centre.arbfp");
/// Clip prologue, INDEX-DATA with one MAD (precise).
pub const CLIP_MULTIRES_OFFSET_ARBFP: ProgramText = program!("clip/multires_offset.arbfp");
/// GLSL `clip_value(p)` twin of [`CLIP_SINGLE_ARBFP`].
pub const CLIP_SINGLE_GLSL: ProgramText = program!("clip/single.glsl");
/// GLSL twin of [`CLIP_MULTIRES_SLOT_CENTRE_ARBFP`].
pub const CLIP_MULTIRES_SLOT_CENTRE_GLSL: ProgramText = program!("clip/multires_slot_centre.glsl");
/// GLSL twin of [`CLIP_MULTIRES_OFFSET_ARBFP`].
pub const CLIP_MULTIRES_OFFSET_GLSL: ProgramText = program!("clip/multires_offset.glsl");

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
        OPACITY3D_SLICE_PRECISE_ARBFP,
        OPACITY3D_SLICE_PRECISE_FRAG,
        OPACITY3D_RAYCAST_FRAG,
        OPACITY3D_SAMPLING_GLSL,
        OPACITY3D_PROBE_FRAG,
        SURFACE_GOURAUD_ARBVP,
        SURFACE_GOURAUD_ARBFP,
        SURFACE_GOURAUD_VERT,
        SURFACE_GOURAUD_FRAG,
        SURFACE_PHONG_ARBVP,
        SURFACE_PHONG_ARBFP,
        SURFACE_PHONG_VERT,
        SURFACE_PHONG_FRAG,
        SECTION_FAITHFUL_ARBFP,
        SECTION_FAITHFUL_FRAG,
        SECTION_PRECISE_ARBFP,
        SECTION_PRECISE_FRAG,
        CELLPROJ_SEED_VERTEX_CG,
        CELLPROJ_SEED_FRAGMENT_CG,
        CELLPROJ_PERSPECTIVE_ARBVP,
        CELLPROJ_PERSPECTIVE_ARBFP,
        CELLPROJ_PERSPECTIVE_VERT,
        CELLPROJ_PERSPECTIVE_FRAG,
        CELLPROJ_ORTHOGRAPHIC_ARBVP,
        CELLPROJ_ORTHOGRAPHIC_ARBFP,
        CELLPROJ_ORTHOGRAPHIC_VERT,
        CELLPROJ_ORTHOGRAPHIC_FRAG,
        CELLPROJ_PRECISE_VERT,
        CELLPROJ_PRECISE_FRAG,
        CELLPROJ_VOLUME_ARBFP,
        CELLPROJ_VOLUME_FRAG,
        CELLPROJ_VOLUME_ORTHOGRAPHIC_ARBFP,
        CELLPROJ_VOLUME_ORTHOGRAPHIC_FRAG,
        CELLPROJ_VOLUME_CELL_VERT,
        CELLPROJ_VOLUME_CELL_FRAG,
        CELLPROJ_VOLUME_PEEL_VERT,
        CELLPROJ_VOLUME_PEEL_FRAG,
        CELLPROJ_VOLUME_WALK_FRAG,
        CELLPROJ_VOLUME_GRID_FRAG,
        CELLPROJ_VOLUME_PROJECTED_FRAG,
        CELLPROJ_VOLUME_INTEGRAL_GLSL,
        SPLATS_VERT,
        SPLATS_SEED_FRAG,
        SPLATS_PRECISE_FRAG,
        SPLATS_PRECISE_VERT,
        SPLATS_ARBVP,
        SPLATS_SEED_ARBFP,
        SPLATS_PRECISE_ARBFP,
        SPLATS_PRECISE_ARBVP,
        SPLATS_OIT_COMPOSITE_ARBFP,
        SPLATS_OIT_COMPOSITE_FRAG,
        SPLATS_TILES_FRAG,
        SPLATS_EDL_DEPTH_VERT,
        SPLATS_EDL_DEPTH_FRAG,
        SPLATS_EDL_FRAG,
        CLIP_SINGLE_ARBFP,
        CLIP_MULTIRES_SLOT_CENTRE_ARBFP,
        CLIP_MULTIRES_OFFSET_ARBFP,
        CLIP_SINGLE_GLSL,
        CLIP_MULTIRES_SLOT_CENTRE_GLSL,
        CLIP_MULTIRES_OFFSET_GLSL,
    ]
}
