//! The clip as a GPU stage a volume technique composes with: its textures on units after
//! v3o2's (7 and 8), its constants in `program.local[10..13]`, and the clip test as text
//! joined to the technique's own program.
//!
//! # Composition
//! - ARB: the verbatim v3o2 text is kept byte for byte after its `!!ARBfp1.0` header;
//!   the clip prologue (its own `TEMP`s, the lookups, one `KIL`) is inserted between the
//!   header and the verbatim body ([`compose_arb`]). The program's provenance is the
//!   verbatim file plus this module's prologue.
//! - GLSL: a `clip_value(p)` function is inserted before `main`, and `main` begins with
//!   `if (clip_value(COORD) < 0.5) discard;` ([`compose_glsl`]); a ray caster instead
//!   calls `clip_value` per sample.
//!
//! # The test
//! Keep where the clip value is at least 0.5. Single resolution: one trilinear fetch.
//! INDEX-DATA: INDEX (nearest) at `p * index_scale`; alpha 0 discards, 1 keeps, 0.5 reads
//! DATA (linear) at the block's coordinate: faithful (the seed as written) rebuilds the
//! block centre with a FLR and adds `(p - centre) S` to the slot centre the INDEX holds;
//! precise stores `slot_centre - block_centre S` and needs one MAD (`p S + index.rgb`,
//! decided by the INDEX fetch alone). Faithful DATA and single textures are 8-bit (the
//! era's LUMINANCE8), precise ones 32-bit float.

use crate::error::RenderResult;
use crate::techniques::clip::error::ComposeError;
use arbvis_gl::GlResult;
use glam::DVec3;

use super::multires::{IndexEncoding, MultiRes};
use super::texture::ClipTexture;
use super::ClipTextures;
use crate::programs;
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{Extent, Filter, Gpu, Program, TexelData, TexelFormat, Texture};

/// The ARB clip prologue of `lookup` (`programs/clip/*.arbfp`, units 7/8 and locals
/// 10-13 written there), reading the host program's volume coordinate `coord`.
pub fn arb_prologue(lookup: Lookup, coord: &str) -> String {
    let text = match lookup {
        Lookup::Single => programs::CLIP_SINGLE_ARBFP,
        Lookup::Multires(IndexEncoding::SlotCentre) => programs::CLIP_MULTIRES_SLOT_CENTRE_ARBFP,
        Lookup::Multires(IndexEncoding::Offset) => programs::CLIP_MULTIRES_OFFSET_ARBFP,
    };
    text.text.replace("@COORD@", coord)
}

/// The GLSL `clip_value(p)` of `lookup` (`programs/clip/*.glsl`).
pub fn glsl_function(lookup: Lookup) -> String {
    let text = match lookup {
        Lookup::Single => programs::CLIP_SINGLE_GLSL,
        Lookup::Multires(IndexEncoding::SlotCentre) => programs::CLIP_MULTIRES_SLOT_CENTRE_GLSL,
        Lookup::Multires(IndexEncoding::Offset) => programs::CLIP_MULTIRES_OFFSET_GLSL,
    };
    text.text.to_string()
}

/// [`glsl_function`] with the read of the clip values (the linearly filtered texture: the
/// single one, or the DATA) interpolated in the shader by `lerp3`, which the host program
/// defines (`programs/common/sampling.glsl`, carried by the precise 3D-opacity programs):
/// for drivers whose texture units keep coarse weights. The INDEX read stays (NEAREST).
pub fn glsl_function_exact(lookup: Lookup) -> String {
    let unit = match lookup {
        Lookup::Single => INDEX_UNIT,
        Lookup::Multires(_) => DATA_UNIT,
    };
    glsl_function(lookup).replace(
        &format!("texture(texture{unit}, "),
        &format!("lerp3(texture{unit}, "),
    )
}

/// Unit of the single-resolution texture, or of the INDEX.
pub const INDEX_UNIT: u32 = 7;
/// Unit of the DATA texture.
pub const DATA_UNIT: u32 = 8;
/// First `program.local` the clip uses (10: INDEX scale, 11: DATA scale S, 12: n / B,
/// 13: B / n).
pub const FIRST_LOCAL: usize = 10;

/// Which lookup the programs do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lookup {
    /// One single-resolution texture.
    Single,
    /// INDEX-DATA, with the INDEX in this encoding.
    Multires(IndexEncoding),
}

/// The clip's GL textures and constants.
pub struct ClipStage {
    /// The lookup the programs must do.
    pub lookup: Lookup,
    textures: Vec<(u32, Texture)>,
    constants: Vec<(usize, [f64; 4])>,
}

fn dims_u32(d: [usize; 3]) -> Extent {
    Extent::D3(d[0] as u32, d[1] as u32, d[2] as u32)
}

/// An 8-bit copy of values in [0, 1] (faithful textures).
fn bytes(values: &[f32]) -> Vec<u8> {
    values
        .iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect()
}

fn scalar_texture(
    gpu: &Gpu,
    label: &str,
    dims: [usize; 3],
    values: &[f32],
    fidelity: Fidelity,
) -> GlResult<Texture> {
    match fidelity {
        Fidelity::Faithful => Texture::new(
            gpu,
            label,
            dims_u32(dims),
            TexelFormat::R8,
            Filter::Linear,
            TexelData::U8(&bytes(values)),
        ),
        Fidelity::Precise => Texture::new(
            gpu,
            label,
            dims_u32(dims),
            TexelFormat::R32f,
            Filter::Linear,
            TexelData::F32(values),
        ),
    }
}

impl ClipStage {
    /// Upload what the lookup of `textures` needs at `fidelity` (nothing else: the
    /// single-resolution texture is not uploaded when INDEX-DATA is used).
    pub fn new(gpu: &Gpu, textures: &ClipTextures, fidelity: Fidelity) -> RenderResult<ClipStage> {
        match &textures.multires {
            None => ClipStage::single(gpu, &textures.single, fidelity),
            Some(m) => ClipStage::multires(gpu, m, fidelity),
        }
    }

    fn single(gpu: &Gpu, single: &ClipTexture, fidelity: Fidelity) -> RenderResult<ClipStage> {
        let t = scalar_texture(
            gpu,
            "clip single-resolution texture",
            single.grid.dims,
            &single.values,
            fidelity,
        )?;
        Ok(ClipStage {
            lookup: Lookup::Single,
            textures: vec![(INDEX_UNIT, t)],
            constants: Vec::new(),
        })
    }

    fn multires(gpu: &Gpu, m: &MultiRes, fidelity: Fidelity) -> RenderResult<ClipStage> {
        let encoding = match fidelity {
            Fidelity::Faithful => IndexEncoding::SlotCentre,
            Fidelity::Precise => IndexEncoding::Offset,
        };
        let index: Vec<f32> = m.index_texels(encoding).into_iter().flatten().collect();
        let index = Texture::new(
            gpu,
            "clip INDEX",
            dims_u32(m.index_dims),
            TexelFormat::Rgba32f,
            Filter::Nearest,
            TexelData::F32(&index),
        )?;
        let mut textures = vec![(INDEX_UNIT, index)];
        // An empty or full clip has no DATA: a 1-texel stand-in keeps the program's
        // sampler valid (it is never read: every INDEX alpha is 0 or 1).
        let (data_dims, data) = if m.data.is_empty() {
            ([1, 1, 1], vec![0.0])
        } else {
            (m.data_dims, m.data.clone())
        };
        textures.push((
            DATA_UNIT,
            scalar_texture(gpu, "clip DATA", data_dims, &data, fidelity)?,
        ));
        let v = |d: DVec3| [d.x, d.y, d.z, 0.0];
        let n = DVec3::from_array(m.dims.map(|x| x as f64));
        let b = m.block as f64;
        let constants = vec![
            (FIRST_LOCAL, v(m.index_scale())),
            (FIRST_LOCAL + 1, v(m.data_scale())),
            (FIRST_LOCAL + 2, v(n / b)),
            (FIRST_LOCAL + 3, v(b / n)),
        ];
        Ok(ClipStage {
            lookup: Lookup::Multires(encoding),
            textures,
            constants,
        })
    }

    /// The textures and their units.
    pub fn textures(&self) -> impl Iterator<Item = (u32, &Texture)> {
        self.textures.iter().map(|(u, t)| (*u, t))
    }

    /// Send the lookup's constants to `program`'s fragment locals.
    pub fn send(&self, gpu: &Gpu, program: &Program) -> RenderResult<()> {
        for (i, c) in &self.constants {
            program.set_local(gpu, *i, *c)?;
        }
        Ok(())
    }

    /// The ARB prologue (reads `coord`, e.g. `fragment.texcoord[0]`).
    pub fn arb_prologue(&self, coord: &str) -> String {
        arb_prologue(self.lookup, coord)
    }

    /// The GLSL `clip_value(p)` function of this stage's lookup
    /// (`programs/clip/*.glsl`).
    pub fn glsl_function(&self) -> String {
        glsl_function(self.lookup)
    }
}

/// The ARB program `text` with `prologue` inserted right after its `!!ARBfp1.0` header;
/// the rest stays byte for byte.
pub fn compose_arb(text: &str, prologue: &str) -> Result<String, ComposeError> {
    const HEADER: &str = "!!ARBfp1.0";
    let body = text.strip_prefix(HEADER).ok_or(ComposeError::NoArbHeader)?;
    Ok(format!("{HEADER}\n{prologue}{body}"))
}

/// The GLSL program `text` with `function` inserted before `void main()`, the first
/// statement of `main` discarding where `clip_value(coord) < 0.5`, and its
/// `program_local` array widened to hold the clip's constants.
pub fn compose_glsl(text: &str, function: &str, coord: &str) -> Result<String, ComposeError> {
    compose_glsl_at(
        text,
        function,
        "void main()",
        &format!("if (clip_value({coord}) < 0.5) discard;"),
    )
}

/// The GLSL program `text` with `function` inserted before the function whose header
/// starts with `signature`, `statement` made the first statement of that function (e.g.
/// a ray caster's `if (clip_value(tc) < 0.5) return vec4(0.0);` in its per-sample
/// function), and `program_local` widened to hold the clip's constants.
pub fn compose_glsl_at(
    text: &str,
    function: &str,
    signature: &str,
    statement: &str,
) -> Result<String, ComposeError> {
    let main = text
        .find(signature)
        .ok_or_else(|| ComposeError::NoFunction(signature.to_string()))?;
    let open = text[main..]
        .find('{')
        .map(|o| main + o + 1)
        .ok_or_else(|| ComposeError::NoBody(signature.to_string()))?;
    let locals = format!("uniform vec4 program_local[{}];", arbvis_gl::MAX_LOCALS);
    let mut head = text[..main].to_string();
    match head.find("uniform vec4 program_local[") {
        Some(at) => {
            let end = head[at..].find(';').map_or(head.len(), |e| at + e + 1);
            head.replace_range(at..end, &locals);
        }
        None => head.push_str(&format!("{locals}\n")),
    }
    Ok(format!(
        "{head}{function}{}\n    {statement}{}",
        &text[main..open],
        &text[open..]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_verbatim_body_is_kept_byte_for_byte() {
        let verbatim = crate::programs::OPACITY3D_SUM_ARBFP.text.to_string();
        let composed = compose_arb(&verbatim, "TEMP x;\nKIL x;\n").unwrap();
        assert!(composed.ends_with(&verbatim["!!ARBfp1.0".len()..]));
        assert!(composed.starts_with("!!ARBfp1.0\nTEMP x;\nKIL x;\n"));
        assert!(compose_arb("void main() {}", "").is_err());
    }

    #[test]
    fn glsl_gets_the_function_the_discard_and_wider_locals() {
        let text = "#version 330\nuniform vec4 program_local[6];\nin vec4 v;\nvoid main() {\n    x();\n}\n";
        let out =
            compose_glsl(text, "float clip_value(vec3 p) { return 1.0; }\n", "v.xyz").unwrap();
        assert!(out.contains("uniform vec4 program_local[24];"), "{out}");
        assert!(!out.contains("program_local[6]"));
        let f = out.find("float clip_value").unwrap();
        let m = out.find("void main()").unwrap();
        let d = out.find("if (clip_value(v.xyz) < 0.5) discard;").unwrap();
        assert!(f < m && m < d && d < out.find("x();").unwrap(), "{out}");
    }

    #[test]
    fn a_ray_caster_gets_the_test_in_its_per_sample_function() {
        let text = "#version 330\nuniform vec4 program_local[10];\nvec4 classify(vec3 tc) {\n    return vec4(1.0);\n}\nvoid main() {\n    frag_color = classify(vec3(0.5));\n}\n";
        let out = compose_glsl_at(
            text,
            "float clip_value(vec3 p) { return 1.0; }\n",
            "vec4 classify(vec3 tc)",
            "if (clip_value(tc) < 0.5) return vec4(0.0);",
        )
        .unwrap();
        let f = out.find("float clip_value").unwrap();
        let c =
            out.find("vec4 classify(vec3 tc) {\n    if (clip_value(tc) < 0.5) return vec4(0.0);");
        assert!(c.is_some_and(|c| f < c), "{out}");
        assert!(!out.contains("discard"), "{out}");
        assert!(out.contains("program_local[24]"), "{out}");
        assert!(compose_glsl_at(text, "", "vec4 shade(", "").is_err());
    }
}
