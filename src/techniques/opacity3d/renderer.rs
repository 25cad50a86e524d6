//! The GL side of 3D opacity: the packed volume on unit 0, tables on units 2/3/4, the
//! sum or product program of the scene's fidelity, and the slice mesh rebuilt when the
//! view direction or the slice count changes.

use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3};

use super::prepare::{prepare, Prepared};
use super::slicing::slice_box;
use super::{Combine, Opacity3dScene};
use crate::colortable::ColorTable;
use crate::gl::{
    self, Blend, DrawCall, Extent, Filter, GlError, GlResult, Gpu, Mesh, Program, ProgramKind,
    Surface, TexelData, TexelFormat, Texture,
};
use crate::programs;
use crate::scene::{Fidelity, TechniqueScene};
use crate::techniques::{Frame, Renderer};

/// Texture unit of the packed volume and of the three tables (unit 1 is v3o2's
/// lighting, unused here).
pub const VOLUME_UNIT: u32 = 0;
/// Units of the primary, secondary and tertiary tables.
pub const TABLE_UNITS: [u32; 3] = [2, 3, 4];

/// The fragment program pair for a combination and fidelity.
pub fn program_pair(
    kind: ProgramKind,
    combine: Combine,
    fidelity: Fidelity,
) -> programs::ProgramPair {
    use programs::*;
    let (arb, glsl) = match (combine, fidelity) {
        (Combine::Sum, Fidelity::Faithful) => (OPACITY3D_SUM_ARBFP, OPACITY3D_SUM_FRAG),
        (Combine::Product, Fidelity::Faithful) => (OPACITY3D_PRODUCT_ARBFP, OPACITY3D_PRODUCT_FRAG),
        (Combine::Sum, Fidelity::Precise) => {
            (OPACITY3D_SUM_PRECISE_ARBFP, OPACITY3D_SUM_PRECISE_FRAG)
        }
        (Combine::Product, Fidelity::Precise) => (
            OPACITY3D_PRODUCT_PRECISE_ARBFP,
            OPACITY3D_PRODUCT_PRECISE_FRAG,
        ),
    };
    with_transform(kind, &arb, &glsl)
}

/// The coefficient vectors sent to `program.local[1..3]`: the scene's for present
/// attributes; for absent ones 0 in a sum and 1 in a product (neutral either way).
pub fn coefficients(params: &Opacity3dScene) -> [[f64; 4]; 3] {
    let absent = match params.combine {
        Combine::Sum => [0.0; 4],
        Combine::Product => [1.0; 4],
    };
    params
        .attributes()
        .map(|a| a.map_or(absent, |a| a.coefficients))
}

/// Opacity-correction exponent for slices `spacing` apart (1 = no correction).
pub fn correction_exponent(
    params: &Opacity3dScene,
    fidelity: Fidelity,
    spacing: f64,
    reference: f64,
) -> f64 {
    let on = params
        .opacity_correction
        .unwrap_or(fidelity == Fidelity::Precise);
    if on && spacing > 0.0 && reference > 0.0 {
        spacing / reference
    } else {
        1.0
    }
}

/// Object space to clip space: the camera's view-projection (the box sits in [-1, 1]³).
pub fn model_view_projection(frame: &Frame) -> DMat4 {
    frame.camera.view_projection(frame.aspect())
}

/// Direction toward the viewer in object space (the slices' normal).
pub fn toward_viewer(frame: &Frame) -> DVec3 {
    frame.camera.quat().inverse() * DVec3::Z
}

/// The 3D-opacity renderer.
pub struct Opacity3dRenderer {
    kind: ProgramKind,
    fidelity: Fidelity,
    base: PathBuf,
    params: Opacity3dScene,
    prepared: Prepared,
    program: Program,
    volume: Texture,
    tables: [Option<Texture>; 3],
    neutral: Option<Texture>,
    mesh: Option<Mesh>,
    mesh_key: Option<([u64; 3], usize)>,
    spacing: f64,
}

/// Texel formats of the packed volume and the tables: 8-bit when faithful (filtering in
/// 8-bit arithmetic, as the original hardware); when precise the same 8-bit values as
/// 16-bit unorm (k·257/65535 = k/255 exactly, so a level's texel-centre lookup lands on
/// its entry; half floats put it up to 0.06 texel off) and f32 tables, filtered in float.
pub fn texel_formats(fidelity: Fidelity) -> (TexelFormat, TexelFormat) {
    match fidelity {
        Fidelity::Faithful => (TexelFormat::Rgb8, TexelFormat::Rgba8),
        Fidelity::Precise => (TexelFormat::Rgb16FromU8, TexelFormat::Rgba32fFromU8),
    }
}

fn table_texture(
    gpu: &Gpu,
    label: &str,
    table: &ColorTable,
    filter: Filter,
    fidelity: Fidelity,
) -> GlResult<Texture> {
    Texture::new(
        gpu,
        label,
        Extent::D2(256, 1),
        texel_formats(fidelity).1,
        filter,
        TexelData::U8(&table.texels()),
    )
}

impl Opacity3dRenderer {
    /// Load and prepare the scene's data (relative paths from `base`), then upload.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &Opacity3dScene,
        base: &Path,
    ) -> GlResult<Opacity3dRenderer> {
        params
            .validate()
            .map_err(|e| GlError::Data(e.to_string()))?;
        let prepared = prepare(params, base, &gpu.volume_limits()).map_err(GlError::Data)?;
        Opacity3dRenderer::from_prepared(gpu, kind, fidelity, params, base, prepared)
    }

    /// Upload data prepared elsewhere (tests craft volumes in memory).
    pub fn from_prepared(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &Opacity3dScene,
        base: &Path,
        prepared: Prepared,
    ) -> GlResult<Opacity3dRenderer> {
        params
            .validate()
            .map_err(|e| GlError::Data(e.to_string()))?;
        let [ni, nj, nk] = prepared.dims;
        let max = gpu.caps().max_3d_texture_size.max(1) as usize;
        if prepared.dims.iter().any(|&d| d > max) {
            return Err(GlError::Unsupported(format!(
                "volume {ni}x{nj}x{nk} exceeds GL_MAX_3D_TEXTURE_SIZE {max}"
            )));
        }
        let pair = program_pair(kind, params.combine, fidelity);
        let program = Program::new(gpu, kind, &pair.vertex, &pair.fragment)?;
        let volume = Texture::new(
            gpu,
            "opacity3d packed volume (R tertiary, G primary, B secondary)",
            Extent::D3(ni as u32, nj as u32, nk as u32),
            texel_formats(fidelity).0,
            params.volume_filter,
            TexelData::U8(&prepared.packed),
        )?;
        let mut renderer = Opacity3dRenderer {
            kind,
            fidelity,
            base: base.to_path_buf(),
            params: params.clone(),
            prepared,
            program,
            volume,
            tables: [None, None, None],
            neutral: None,
            mesh: None,
            mesh_key: None,
            spacing: 0.0,
        };
        renderer.build_tables(gpu)?;
        renderer.send_constants(gpu)?;
        Ok(renderer)
    }

    /// The prepared data (for references and the viewer's readouts).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    fn build_tables(&mut self, gpu: &Gpu) -> GlResult<()> {
        let names = super::ATTRIBUTE_NAMES;
        for (a, name) in names.iter().enumerate() {
            self.tables[a] = match &self.prepared.tables[a] {
                Some(t) => Some(table_texture(
                    gpu,
                    &format!("opacity3d {name} table"),
                    t,
                    self.params.table_filter,
                    self.fidelity,
                )?),
                None => None,
            };
        }
        let missing = self.tables.iter().any(Option::is_none);
        self.neutral = if missing && self.params.combine == Combine::Product {
            Some(Texture::new(
                gpu,
                "opacity3d neutral table (absent attribute in a product)",
                Extent::D2(1, 1),
                TexelFormat::Rgba8,
                Filter::Nearest,
                TexelData::U8(&[255; 4]),
            )?)
        } else {
            None
        };
        Ok(())
    }

    fn send_constants(&self, gpu: &Gpu) -> GlResult<()> {
        for (i, c) in coefficients(&self.params).iter().enumerate() {
            self.program.set_local(gpu, i + 1, *c)?;
        }
        if self.fidelity == Fidelity::Precise {
            self.program
                .set_local(gpu, 5, [255.0 / 256.0, 0.5 / 256.0, 1.0 / 3.0, 0.0])?;
        }
        Ok(())
    }

    fn update_mesh(&mut self, gpu: &Gpu, frame: &Frame) -> GlResult<()> {
        let dir = toward_viewer(frame);
        let key = (dir.to_array().map(f64::to_bits), self.params.slices);
        if self.mesh_key == Some(key) && self.mesh.is_some() {
            return Ok(());
        }
        let slices = slice_box(self.prepared.half, dir, self.params.slices);
        let vertices = slices.triangle_vertices();
        self.spacing = slices.spacing;
        match &mut self.mesh {
            Some(mesh) => mesh.update(gpu, &vertices)?,
            None => {
                self.mesh = Some(Mesh::new(gpu, "opacity3d slices", &[4, 4], &vertices)?);
            }
        }
        self.mesh_key = Some(key);
        Ok(())
    }
}

impl Renderer for Opacity3dRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> GlResult<()> {
        self.update_mesh(gpu, frame)?;
        self.program
            .set_transform(gpu, model_view_projection(frame))?;
        let k = correction_exponent(
            &self.params,
            self.fidelity,
            self.spacing,
            self.prepared.reference_spacing(),
        );
        if self.fidelity == Fidelity::Precise {
            self.program.set_local(gpu, 4, [k, 0.0, 0.0, 0.0])?;
        }
        let mut textures: Vec<(u32, &Texture)> = vec![(VOLUME_UNIT, &self.volume)];
        for (a, t) in self.tables.iter().enumerate() {
            match (t, &self.neutral) {
                (Some(t), _) | (None, Some(t)) => textures.push((TABLE_UNITS[a], t)),
                (None, None) => {}
            }
        }
        let Some(mesh) = &self.mesh else {
            return Ok(());
        };
        gl::draw(
            gpu,
            surface,
            &DrawCall {
                program: &self.program,
                mesh,
                range: None,
                textures: &textures,
                blend: Blend::Over,
                depth_test: false,
                cull_back: false,
            },
        )
    }

    fn update(&mut self, gpu: &Gpu, technique: &TechniqueScene) -> GlResult<()> {
        let TechniqueScene::Opacity3d(new) = technique else {
            return Err(GlError::Invalid(format!(
                "opacity3d renderer given a {} scene",
                technique.name()
            )));
        };
        new.validate().map_err(|e| GlError::Data(e.to_string()))?;
        let new: &Opacity3dScene = new;
        let old = std::mem::replace(&mut self.params, new.clone());
        let data = |p: &Opacity3dScene| {
            p.attributes()
                .map(|a| a.map(|a| (a.volume.clone(), a.attribute, a.quantize)))
        };
        if data(&old) != data(new) || old.volume_filter != new.volume_filter {
            let prepared = prepare(new, &self.base, &gpu.volume_limits()).map_err(GlError::Data)?;
            let fresh = Opacity3dRenderer::from_prepared(
                gpu,
                self.kind,
                self.fidelity,
                new,
                &self.base.clone(),
                prepared,
            )?;
            *self = fresh;
            return Ok(());
        }
        if old.combine != new.combine {
            let pair = program_pair(self.kind, new.combine, self.fidelity);
            self.program = Program::new(gpu, self.kind, &pair.vertex, &pair.fragment)?;
        }
        let tables = |p: &Opacity3dScene| p.attributes().map(|a| a.map(|a| a.table.clone()));
        if tables(&old) != tables(new)
            || old.table_filter != new.table_filter
            || old.combine != new.combine
        {
            for (a, attr) in new.attributes().into_iter().enumerate() {
                if let Some(attr) = attr {
                    self.prepared.tables[a] =
                        Some(attr.table.build(&self.base).map_err(GlError::Data)?);
                }
            }
            self.build_tables(gpu)?;
        }
        self.send_constants(gpu)
    }

    fn program_kind(&self) -> ProgramKind {
        self.program.kind()
    }
}
