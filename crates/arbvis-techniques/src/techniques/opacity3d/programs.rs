//! The programs of 3D opacity: the verbatim faithful pair, and the precise programs
//! generated from one template per language (`programs/opacity3d/slice_precise.arbfp`,
//! its GLSL twin `slice_precise.frag`, and the GLSL-only `raycast.frag`).
//!
//! A template line that ends in a comment holding a bracketed list of tags (`# [sum
//! secondary]` in ARB, `// [sum secondary]` in GLSL) is kept only when the scene has every
//! tag (and none written `!tag`), and the comment is dropped; `@1 @2 @3` become the channel letter of the primary,
//! secondary and tertiary attribute in the precise volume, which holds the present
//! attributes only, in that order (one attribute: `r`). So a one-attribute scene's
//! program fetches one table, and the ARB and GLSL texts of a scene come from the same
//! lines. Tags: `sum` / `product`, `secondary`, `tertiary`, `orthographic` /
//! `perspective`, `skip` (the ray caster's empty-space skipping), `preint` (its
//! pre-integrated classification), `jitter` (its per-pixel step offset), `baked` (its
//! one-attribute table of step colour and opacity), `paged` (a store's bricks through
//! its page table, [`super::bricked`]), `neighbours` (one attribute's 2x2x2 levels in
//! one texel).
//!
//! Which paths exist in which language: faithful slicing (verbatim ARB, GLSL port),
//! precise slicing (ARB and GLSL), the precise ray caster (GLSL only: ARB fragment
//! programs have no loops or branches).

use std::borrow::Cow;

use super::{Combine, Interpolation, Opacity3dScene};
use crate::programs::{self, with_transform, ProgramPair};
use arbvis_core::camera::Projection;
use arbvis_gl::{Filter, ProgramKind, ProgramText};

/// What a precise program is specialized to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Variant {
    /// Sum or product.
    pub combine: Combine,
    /// Secondary and tertiary present (the primary always is).
    pub present: [bool; 3],
    /// Orthographic or perspective (where rays come from).
    pub projection: Projection,
    /// Ray caster only: empty-space skipping.
    pub skip: bool,
    /// Ray caster only: pre-integrated classification (one attribute).
    pub preint: bool,
    /// Ray caster only: per-pixel offset of the steps (point sampling).
    pub jitter: bool,
    /// Ray caster only, with jitter: one attribute's steps from the baked table.
    pub baked: bool,
    /// Ray caster only: a store's bricks through the page table (point sampling, no
    /// jitter; the atlas holds v3o2's packing, G primary, B secondary, R tertiary).
    pub paged: bool,
    /// Ray caster only, one attribute: the volume unit holds each voxel's 2x2x2 levels
    /// ([`super::prepare::Prepared::neighbour_words`]), one fetch a sample.
    pub neighbours: bool,
    /// What the program computes itself instead of the hardware.
    pub filter: InShader,
}

/// What a precise program computes itself instead of the hardware: linear reads of its
/// filtered textures (`texelFetch` and f32 `mix`, `programs/common/sampling.glsl`) where
/// the texture units keep coarse weights ([`arbvis_gl::Gpu::filters_exactly`]), and its
/// slices' sample points from each pixel's centre where the rasterizer interpolates from
/// snapped vertices ([`arbvis_gl::Gpu::interpolates_exactly`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct InShader {
    /// The attribute volume (or a store's brick atlas).
    pub volume: bool,
    /// The colour tables.
    pub tables: bool,
    /// The ray caster's step table (pre-integrated or baked; always linear).
    pub steps: bool,
    /// A clip's values (always linear; the GLSL clip test only).
    pub clip: bool,
    /// Slicing: each sample is the pixel's centre unprojected at its slice's depth, not
    /// the interpolated texture coordinate. (The ray caster always unprojects: one ray a
    /// pixel costs nothing beside its steps.)
    pub points: bool,
}

impl InShader {
    /// What `params` computes in the shader on a driver whose texture units filter
    /// exactly (`units_exact`) or not and whose rasterizer interpolates from the true
    /// vertices (`interpolation_exact`) or not: as `interpolation` says, or, under `auto`,
    /// what the driver does coarsely.
    pub fn for_scene(
        params: &Opacity3dScene,
        units_exact: bool,
        interpolation_exact: bool,
    ) -> InShader {
        let (filters, points) = match params.interpolation {
            Interpolation::Auto => (!units_exact, !interpolation_exact),
            Interpolation::Hardware => (false, false),
            Interpolation::Shader => (true, true),
        };
        InShader {
            volume: filters && params.volume_filter == Filter::Linear,
            tables: filters && params.table_filter == Filter::Linear,
            steps: filters,
            clip: filters,
            points,
        }
    }
}

impl Variant {
    /// The tags this variant keeps.
    pub fn tags(&self) -> Vec<&'static str> {
        let mut tags = vec![match self.combine {
            Combine::Sum => "sum",
            Combine::Product => "product",
        }];
        if self.present[1] {
            tags.push("secondary");
        }
        if self.present[2] {
            tags.push("tertiary");
        }
        tags.push(match self.projection {
            Projection::Orthographic => "orthographic",
            Projection::Perspective => "perspective",
        });
        if self.skip {
            tags.push("skip");
        }
        if self.preint {
            tags.push("preint");
        }
        if self.jitter {
            tags.push("jitter");
        }
        if self.baked {
            tags.push("baked");
        }
        if self.paged {
            tags.push("paged");
        }
        if self.neighbours {
            tags.push("neighbours");
        }
        for (on, tag) in [
            (self.filter.volume, "exact_volume"),
            (self.filter.tables, "exact_tables"),
            (self.filter.steps, "exact_steps"),
            (self.filter.points, "pixel_points"),
        ] {
            if on {
                tags.push(tag);
            }
        }
        tags
    }

    /// Channel letter of each attribute in the precise volume (present ones, in order).
    pub fn channels(&self) -> [char; 3] {
        if self.paged {
            return ['g', 'b', 'r'];
        }
        let mut out = ['r'; 3];
        let mut next = 0;
        for (a, c) in out.iter_mut().enumerate() {
            if self.present[a] || a == 0 {
                *c = ['r', 'g', 'b'][next];
                next += 1;
            }
        }
        out
    }

    /// A short name for program labels, e.g. `sum+secondary+orthographic`.
    pub fn label(&self) -> String {
        self.tags().join("+")
    }
}

/// Keep the lines whose tags `tags` all holds, drop the tag comments, and put in the
/// channel letters; a line `// @sampling` becomes the linear reads
/// ([`programs::OPACITY3D_SAMPLING_GLSL`]), specialized alike.
pub fn specialize(template: &ProgramText, tags: &[&str], channels: [char; 3]) -> ProgramText {
    let mut out = String::with_capacity(template.text.len());
    let sampling = programs::OPACITY3D_SAMPLING_GLSL;
    let lines = template.text.split_inclusive('\n').flat_map(|line| {
        let include = line.trim() == "// @sampling";
        let text: &str = if include { &sampling.text } else { line };
        text.split_inclusive('\n')
    });
    for line in lines {
        let (body, newline) = match line.strip_suffix('\n') {
            Some(b) => (b, "\n"),
            None => (line, ""),
        };
        let (kept, body) = match line_tags(body) {
            Some((code, wanted)) => (
                wanted.iter().all(|t| match t.strip_prefix('!') {
                    Some(absent) => !tags.contains(&absent),
                    None => tags.contains(t),
                }),
                code,
            ),
            None => (true, body),
        };
        if kept {
            let mut text = body.to_string();
            for (a, c) in channels.iter().enumerate() {
                text = text.replace(&format!("@{}", a + 1), &c.to_string());
            }
            out += &text;
            out += newline;
        }
    }
    ProgramText {
        name: Cow::Owned(format!("{} [{}]", template.name, tags.join(" "))),
        text: Cow::Owned(out),
    }
}

/// `(code, tags)` when `line` ends in a comment `# [a b]` or `// [a b]`.
fn line_tags(line: &str) -> Option<(&str, Vec<&str>)> {
    let trimmed = line.trim_end();
    let inner = trimmed.strip_suffix(']')?;
    let open = inner.rfind('[')?;
    let before = inner[..open].trim_end();
    let code = before
        .strip_suffix("//")
        .or_else(|| before.strip_suffix('#'))?
        .trim_end();
    Some((code, inner[open + 1..].split_whitespace().collect()))
}

/// The precise slicing pair of `kind` for `variant`.
pub fn slicing_pair(kind: ProgramKind, variant: Variant) -> ProgramPair {
    let tags = variant.tags();
    let channels = variant.channels();
    let arb = specialize(&programs::OPACITY3D_SLICE_PRECISE_ARBFP, &tags, channels);
    let glsl = specialize(&programs::OPACITY3D_SLICE_PRECISE_FRAG, &tags, channels);
    with_transform(kind, &arb, &glsl)
}

/// The ray caster pair (GLSL) for `variant`.
pub fn raycast_pair(variant: Variant) -> ProgramPair {
    let frag = specialize(
        &programs::OPACITY3D_RAYCAST_FRAG,
        &variant.tags(),
        variant.channels(),
    );
    with_transform(ProgramKind::Glsl, &frag, &frag)
}

/// Every precise variant, both languages where they exist (the compile-everything test).
pub fn all_precise_pairs() -> Vec<ProgramPair> {
    let mut pairs = Vec::new();
    for combine in [Combine::Sum, Combine::Product] {
        for present in [
            [true, false, false],
            [true, true, false],
            [true, true, true],
            [true, false, true],
        ] {
            for projection in [Projection::Orthographic, Projection::Perspective] {
                for (skip, preint, jitter, baked) in [
                    (false, false, false, false),
                    (true, false, false, false),
                    (false, true, false, false),
                    (false, false, true, false),
                    (false, false, true, true),
                ] {
                    let v = Variant {
                        combine,
                        present,
                        projection,
                        skip,
                        preint,
                        jitter,
                        baked,
                        paged: false,
                        neighbours: false,
                        filter: InShader::default(),
                    };
                    // The GLSL programs also with every linear read in the shader.
                    let exact = Variant {
                        filter: InShader {
                            volume: true,
                            tables: true,
                            steps: true,
                            clip: true,
                            points: true,
                        },
                        ..v
                    };
                    // Slicing with the volume alone in the shader (nearest tables).
                    let volume_only = Variant {
                        filter: InShader {
                            volume: true,
                            ..InShader::default()
                        },
                        ..v
                    };
                    if !(skip || preint || jitter) {
                        for kind in [ProgramKind::Arb, ProgramKind::Glsl] {
                            for variant in [v, exact, volume_only] {
                                pairs.push(slicing_pair(kind, variant));
                            }
                        }
                    }
                    // Pre-integration and the baked table are for one attribute.
                    if !(preint || baked) || present == [true, false, false] {
                        pairs.push(raycast_pair(v));
                        pairs.push(raycast_pair(exact));
                    }
                    if present == [true, false, false] {
                        for variant in [v, exact] {
                            pairs.push(raycast_pair(Variant {
                                neighbours: true,
                                ..variant
                            }));
                        }
                    }
                    if !(skip || preint || jitter) {
                        pairs.push(raycast_pair(Variant { paged: true, ..v }));
                        pairs.push(raycast_pair(Variant {
                            paged: true,
                            ..exact
                        }));
                    }
                }
            }
        }
    }
    for tags in [
        &[][..],
        &["fetch2d"],
        &["fetch3d"],
        &["fetch3d", "table1"],
        &["fetch3d", "table3"],
    ] {
        let probe = specialize(&programs::OPACITY3D_PROBE_FRAG, tags, ['g', 'b', 'r']);
        pairs.push(with_transform(ProgramKind::Glsl, &probe, &probe));
    }
    pairs
}

/// The verbatim faithful pair (or its GLSL port) for a combination.
pub fn faithful_pair(kind: ProgramKind, combine: Combine) -> programs::ProgramPair {
    use programs::*;
    let (arb, glsl) = match combine {
        Combine::Sum => (OPACITY3D_SUM_ARBFP, OPACITY3D_SUM_FRAG),
        Combine::Product => (OPACITY3D_PRODUCT_ARBFP, OPACITY3D_PRODUCT_FRAG),
    };
    with_transform(kind, &arb, &glsl)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn variant(combine: Combine, present: [bool; 3]) -> Variant {
        Variant {
            combine,
            present,
            projection: Projection::Orthographic,
            skip: false,
            preint: false,
            jitter: false,
            baked: false,
            paged: false,
            neighbours: false,
            filter: InShader::default(),
        }
    }

    #[test]
    fn one_attribute_fetches_one_table() {
        let v = variant(Combine::Sum, [true, false, false]);
        for kind in [ProgramKind::Arb, ProgramKind::Glsl] {
            let pair = slicing_pair(kind, v);
            let text = &pair.fragment.text;
            let fetches = text.matches("texture2").count() + text.matches("texture[2]").count();
            assert!(fetches >= 1, "{text}");
            assert!(
                !text.contains("texture[3]") && !text.contains("texture3"),
                "{text}"
            );
            assert!(
                !text.contains("texture[4]") && !text.contains("texture4"),
                "{text}"
            );
            assert!(!text.contains('@') && !text.contains("# ["), "{text}");
            assert!(text.contains("coord.r"), "{text}");
        }
        // The ARB program of one attribute: one 3D fetch and one table fetch.
        let arb = slicing_pair(ProgramKind::Arb, v).fragment.text;
        assert_eq!(arb.matches("TEX ").count(), 2, "{arb}");
    }

    #[test]
    fn channels_follow_the_present_attributes() {
        assert_eq!(
            variant(Combine::Sum, [true, false, true]).channels()[..1],
            ['r']
        );
        assert_eq!(
            variant(Combine::Sum, [true, false, true]).channels()[2],
            'g'
        );
        assert_eq!(
            variant(Combine::Sum, [true, true, true]).channels(),
            ['r', 'g', 'b']
        );
        let arb = slicing_pair(
            ProgramKind::Arb,
            variant(Combine::Product, [true, false, true]),
        )
        .fragment
        .text;
        assert!(arb.contains("coord.g, texture[4]"), "{arb}");
        assert!(!arb.contains("texture[3]"), "{arb}");
        assert!(arb.contains("MOV_SAT") && !arb.contains("MUL_SAT"), "{arb}");
    }

    #[test]
    fn tags_are_parsed_only_at_line_ends() {
        assert_eq!(
            line_tags("MUL a, b, c;  # [sum secondary]"),
            Some(("MUL a, b, c;", vec!["sum", "secondary"]))
        );
        assert_eq!(
            line_tags("    x = y;  // [perspective]"),
            Some(("    x = y;", vec!["perspective"]))
        );
        assert_eq!(line_tags("vec4 v = a[2];"), None);
        assert_eq!(line_tags("PARAM m[4] = { program.local[0..3] };"), None);
        let t = ProgramText::embedded("t", "a\nb # [x]\nc // [x y]\nd // [!y]\ne");
        assert_eq!(specialize(&t, &["x"], ['r'; 3]).text, "a\nb\nd\ne");
        assert_eq!(specialize(&t, &["x", "y"], ['r'; 3]).text, "a\nb\nc\ne");
        assert_eq!(specialize(&t, &[], ['r'; 3]).text, "a\nd\ne");
    }
}
