//! `arbvis bench --breakdown`: where a slicing frame's time goes. The scene's slices
//! (its slice count and view) are drawn with probe programs that each do a part of the
//! work (`programs/opacity3d/probe.frag`): a constant colour (rasterization and blending
//! alone, blended and not), one fetch of a small 2D texture (the fill-rate baseline the
//! design asks for), one fetch of the packed volume (RGB8 as faithful mode stores it, and
//! one 16-bit channel as precise mode stores one attribute), then one and three dependent
//! table fetches after it; each into an RGBA8 and an RGBA32F target. GLSL only: on llvmpipe
//! ARB and GLSL programs compile to the same code (the study measured them alike:
//! docs/benchmarks.md, "3D opacity: figures behind its settings").

use std::time::Instant;

use anyhow::Result;

use super::measured::Measured;
use crate::programs::{self, with_transform};
use crate::scene::Scene;
use crate::techniques::opacity3d::prepare::Prepared;
use crate::techniques::opacity3d::programs::specialize;
use crate::techniques::opacity3d::proxy::toward_viewer;
use crate::techniques::opacity3d::renderer::model_view_projection;
use crate::techniques::opacity3d::slicing::slice_box;
use crate::techniques::opacity3d::Opacity3dScene;
use crate::techniques::Frame;
use arbvis_core::vocab::TargetFormat;
use arbvis_gl::{
    self, Blend, DrawCall, Extent, Headless, Mesh, Program, ProgramKind, Surface, TexelData,
    TexelFormat, Texture,
};

/// One probe: a name, its tags, which volume it reads, its target and blend.
struct Probe {
    name: &'static str,
    tags: &'static [&'static str],
    r16: bool,
    target: TargetFormat,
    blend: Blend,
}

fn probes() -> Vec<Probe> {
    let mut out = Vec::new();
    for target in [TargetFormat::Rgba8, TargetFormat::Rgba32f] {
        let p = |name, tags, r16, blend| Probe {
            name,
            tags,
            r16,
            target,
            blend,
        };
        out.push(p(
            "constant colour, no blending",
            &[][..],
            false,
            Blend::Replace,
        ));
        out.push(p("constant colour", &[], false, Blend::Over));
        out.push(p(
            "one 2D fetch (fill-rate baseline)",
            &["fetch2d"],
            false,
            Blend::Over,
        ));
        out.push(p("3D fetch, RGB8 volume", &["fetch3d"], false, Blend::Over));
        out.push(p("3D fetch, R16 volume", &["fetch3d"], true, Blend::Over));
        out.push(p(
            "3D fetch + 1 table",
            &["fetch3d", "table1"],
            false,
            Blend::Over,
        ));
        out.push(p(
            "3D fetch + 3 tables",
            &["fetch3d", "table3"],
            false,
            Blend::Over,
        ));
    }
    out
}

/// Time every probe on the scene's slices, `frames` frames each, `rounds` times over.
pub fn run(
    headless: &Headless,
    scene: &Scene,
    prepared: &Prepared,
    frames: usize,
    rounds: usize,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Measured>> {
    let gpu = headless.gpu();
    let Some(params) = scene.technique.get::<Opacity3dScene>() else {
        anyhow::bail!("--breakdown needs a 3D-opacity scene");
    };
    let [w, h] = scene.size;
    let frame = Frame {
        camera: scene.camera,
        width: w,
        height: h,
    };
    let slices = slice_box(prepared.half, toward_viewer(&frame), params.slices);
    let mesh = Mesh::new(gpu, "probe slices", &[4, 4], &slices.triangle_vertices())?;
    let [ni, nj, nk] = prepared.dims.map(|d| d as u32);
    let rgb8 = Texture::new(
        gpu,
        "probe volume RGB8",
        Extent::D3(ni, nj, nk),
        TexelFormat::Rgb8,
        params.volume_filter,
        TexelData::U8(&prepared.packed),
    )?;
    let primary: Vec<u8> = (0..prepared.packed.len() / 3)
        .map(|v| prepared.byte(v, 0))
        .collect();
    let r16 = Texture::new(
        gpu,
        "probe volume R16",
        Extent::D3(ni, nj, nk),
        TexelFormat::R16FromU8,
        params.volume_filter,
        TexelData::U8(&primary),
    )?;
    let table = Texture::new(
        gpu,
        "probe table",
        Extent::D2(256, 1),
        TexelFormat::Rgba8,
        params.table_filter,
        TexelData::U8(&[96u8; 1024]),
    )?;
    let probes = probes();
    let mut programs_of = Vec::new();
    for p in &probes {
        let text = specialize(&programs::OPACITY3D_PROBE_FRAG, p.tags, ['g', 'b', 'r']);
        let pair = with_transform(ProgramKind::Glsl, &text, &text);
        let program = Program::new(gpu, ProgramKind::Glsl, &pair.vertex, &pair.fragment)?;
        program.set_transform(gpu, model_view_projection(&frame))?;
        programs_of.push(program);
    }
    let targets =
        [TargetFormat::Rgba8, TargetFormat::Rgba32f].map(|f| arbvis_gl::Target::new(gpu, w, h, f));
    let [t8, t32] = targets;
    let (t8, t32) = (t8?, t32?);
    let mut out: Vec<Measured> = Vec::new();
    for round in 0..rounds.max(1) {
        for (i, p) in probes.iter().enumerate() {
            let target = if p.target == TargetFormat::Rgba8 {
                &t8
            } else {
                &t32
            };
            let volume = if p.r16 { &r16 } else { &rgb8 };
            let textures = [(0, volume), (2, &table), (3, &table), (4, &table)];
            let one = || -> Result<f64> {
                let t0 = Instant::now();
                target.clear(gpu, scene.clear_colour())?;
                arbvis_gl::draw(
                    gpu,
                    Surface::Target(target),
                    &DrawCall {
                        textures: &textures,
                        blend: p.blend,
                        primitive: Default::default(),
                        ..DrawCall::new(&programs_of[i], &mesh)
                    },
                )?;
                gpu.finish();
                Ok(t0.elapsed().as_secs_f64() * 1e3)
            };
            let first = one()?;
            let times: Vec<f64> = (0..frames.max(1)).map(|_| one()).collect::<Result<_>>()?;
            if round == 0 {
                out.push(Measured::probe(
                    format!("probe: {} ({})", p.name, p.target.name()),
                    p.target,
                    params.slices,
                    first,
                ));
            }
            out[i].frames_ms.extend_from_slice(&times);
            progress(&format!(
                "round {} probe {:<40} {:>6} {:>8.1} ms",
                round + 1,
                p.name,
                p.target.name(),
                times.iter().copied().fold(f64::INFINITY, f64::min)
            ));
        }
    }
    arbvis_gl::gl_check!(gpu)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_probe_has_a_target_and_the_tags_it_needs() {
        let p = probes();
        assert_eq!(p.len(), 14);
        assert!(p
            .iter()
            .all(|p| !p.tags.contains(&"table1") || p.tags.contains(&"fetch3d")));
        assert_eq!(p.iter().filter(|p| p.r16).count(), 2);
    }
}
