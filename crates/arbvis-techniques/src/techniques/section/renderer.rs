//! A section's GL state: the plane (two triangles), its samples as a texture (8-bit levels
//! faithful, floats precise) and the table; moving the section uploads the new plane.

use std::path::PathBuf;

use super::prepare::{Plane, Prepared};
use super::SectionScene;
use crate::error::RenderResult;
use crate::programs::{self, ProgramPair};
use crate::techniques::{Frame, Params, Renderer};
use arbvis_core::vocab::Fidelity;
use arbvis_data::volume::quantize::quantize_value;
use arbvis_gl::{
    DrawCall, Extent, Filter, Gpu, Mesh, Program, ProgramKind, Surface, TexelData, TexelFormat,
    Texture,
};

/// The program pair of `fidelity` and `kind`: the common transform and the section's
/// fragment stage.
pub fn pair(fidelity: Fidelity, kind: ProgramKind) -> ProgramPair {
    use programs::*;
    match fidelity {
        Fidelity::Faithful => with_transform(kind, &SECTION_FAITHFUL_ARBFP, &SECTION_FAITHFUL_FRAG),
        Fidelity::Precise => with_transform(kind, &SECTION_PRECISE_ARBFP, &SECTION_PRECISE_FRAG),
    }
}

/// Every pair a section draws with.
pub fn program_pairs() -> Vec<ProgramPair> {
    programs::each_fidelity_and_kind(pair)
}

/// The plane's two triangles: position (x y z 1) and texture coordinates (s t 0 1).
pub fn vertex_floats(prepared: &Prepared) -> Vec<f32> {
    let c = prepared.corners();
    [0, 1, 2, 0, 2, 3]
        .iter()
        .flat_map(|&i| {
            let (p, [s, t]) = c[i];
            [p.x, p.y, p.z, 1.0, s, t, 0.0, 1.0].map(|v| v as f32)
        })
        .collect()
}

/// The plane's texels: faithful RGBA8 (the level in r, 255 in a where there is data),
/// precise RG32F (the value, 1 where there is data; 0 and 0 where none).
fn plane_texels(plane: &Plane, range: (f64, f64), fidelity: Fidelity) -> PlaneTexels {
    match fidelity {
        Fidelity::Faithful => PlaneTexels::Levels(
            plane
                .values
                .iter()
                .flat_map(|&v| match v.is_nan() {
                    true => [0, 0, 0, 0],
                    false => [quantize_value(v, range.0, range.1), 0, 0, 255],
                })
                .collect(),
        ),
        Fidelity::Precise => PlaneTexels::Values(
            plane
                .values
                .iter()
                .flat_map(|&v| match v.is_nan() {
                    true => [0.0, 0.0],
                    false => [v, 1.0],
                })
                .collect(),
        ),
    }
}

enum PlaneTexels {
    Levels(Vec<u8>),
    Values(Vec<f32>),
}

/// The plane's texture: 8-bit levels filtered by the unit (faithful), or floats read
/// sample by sample (precise).
fn plane_texture(
    gpu: &Gpu,
    plane: &Plane,
    range: (f64, f64),
    fidelity: Fidelity,
) -> RenderResult<Texture> {
    let extent = Extent::D2(plane.size[0] as u32, plane.size[1] as u32);
    let texture = match plane_texels(plane, range, fidelity) {
        PlaneTexels::Levels(bytes) => Texture::new(
            gpu,
            "section plane",
            extent,
            TexelFormat::Rgba8,
            Filter::Linear,
            TexelData::U8(&bytes),
        )?,
        PlaneTexels::Values(floats) => Texture::new(
            gpu,
            "section plane",
            extent,
            TexelFormat::Rg32f,
            Filter::Nearest,
            TexelData::F32(&floats),
        )?,
    };
    Ok(texture)
}

/// The table: its 256 entries as bytes (faithful) or floats k/255 (precise), read entry
/// by entry.
fn table_texture(gpu: &Gpu, prepared: &Prepared, fidelity: Fidelity) -> RenderResult<Texture> {
    let bytes: Vec<u8> = prepared.table.entries.iter().flatten().copied().collect();
    let format = match fidelity {
        Fidelity::Faithful => TexelFormat::Rgba8,
        Fidelity::Precise => TexelFormat::Rgba32fFromU8,
    };
    Ok(Texture::new(
        gpu,
        "section table",
        Extent::D1(prepared.table.entries.len() as u32),
        format,
        Filter::Nearest,
        TexelData::U8(&bytes),
    )?)
}

/// A section's GL state.
pub struct SectionRenderer {
    program: Program,
    mesh: Mesh,
    plane: Texture,
    table: Texture,
    fidelity: Fidelity,
    params: SectionScene,
    base: PathBuf,
    prepared: Prepared,
}

impl SectionRenderer {
    /// Compile the pair of `fidelity` and `kind`, upload the plane and the table.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &SectionScene,
        prepared: Prepared,
    ) -> RenderResult<SectionRenderer> {
        let pair = pair(fidelity, kind);
        let program = Program::new(gpu, kind, &pair.vertex, &pair.fragment)?;
        let mesh = Mesh::new(gpu, "section", &[4, 4], &vertex_floats(&prepared))?;
        let plane = plane_texture(gpu, &prepared.plane, prepared.range, fidelity)?;
        let table = table_texture(gpu, &prepared, fidelity)?;
        Ok(SectionRenderer {
            program,
            mesh,
            plane,
            table,
            fidelity,
            params: params.clone(),
            base: PathBuf::new(),
            prepared,
        })
    }

    /// Read files named relative to `base` when parameters change.
    pub fn with_base(mut self, base: &std::path::Path) -> SectionRenderer {
        self.base = base.to_path_buf();
        self
    }

    /// The prepared survey and plane drawn.
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }
}

impl Renderer for SectionRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        self.program
            .set_transform(gpu, frame.camera.view_projection(frame.aspect()))?;
        let opacity = self.params.opacity;
        match self.fidelity {
            Fidelity::Faithful => self.program.set_local(gpu, 0, [opacity, 0.0, 0.0, 0.0])?,
            Fidelity::Precise => {
                let [nu, nw] = self.prepared.plane.size.map(|n| n.max(1) as f64);
                let (low, high) = self.prepared.range;
                let scale = if high > low {
                    255.0 / (high - low)
                } else {
                    0.0
                };
                self.program
                    .set_local(gpu, 0, [nu, nw, 1.0 / nu, 1.0 / nw])?;
                self.program.set_local(gpu, 1, [low, scale, opacity, 0.0])?;
            }
        }
        let translucent = opacity < 1.0;
        let textures = [(0, &self.plane), (1, &self.table)];
        let call = DrawCall {
            textures: &textures,
            ..DrawCall::new(&self.program, &self.mesh)
        }
        .sheet(translucent);
        Ok(arbvis_gl::draw(gpu, surface, &call)?)
    }

    /// A new position uploads the plane's samples; a new table or range the textures; a
    /// new volume or attribute prepares the survey again.
    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let params = params.get::<SectionScene>()?;
        let old = &self.params;
        if params.volume != old.volume || params.attribute != old.attribute {
            let limits = arbvis_data::volume::Limits::default();
            *self = SectionRenderer::new(
                gpu,
                self.program.kind(),
                self.fidelity,
                params,
                super::prepare::prepare(params, &self.base, &limits)?,
            )?
            .with_base(&self.base.clone());
            return Ok(());
        }
        if params.quantize != old.quantize {
            self.prepared.range = self.prepared.range_of(params.quantize)?;
        }
        if params.table != old.table {
            self.prepared.table = params
                .table
                .build(&self.base)
                .map_err(|e| arbvis_core::vocab::FieldError::new("table", e.to_string()))?;
            self.table = table_texture(gpu, &self.prepared, self.fidelity)?;
        }
        if params.cuts() != old.cuts() {
            self.prepared.plane = self.prepared.plane_at(params.cut()?)?;
            self.mesh = Mesh::new(gpu, "section", &[4, 4], &vertex_floats(&self.prepared))?;
        }
        if params.cuts() != old.cuts() || params.quantize != old.quantize {
            self.plane = plane_texture(
                gpu,
                &self.prepared.plane,
                self.prepared.range,
                self.fidelity,
            )?;
        }
        self.params = params.clone();
        Ok(())
    }

    fn program_kind(&self) -> ProgramKind {
        self.program.kind()
    }

    fn needs_depth(&self) -> bool {
        true
    }

    /// The table over the range, titled by the attribute and where the section lies.
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{Annotations, Legend};
        let (low, high) = self.prepared.range;
        let title = match self.params.cut() {
            Ok(cut) => format!(
                "{} ({} {})",
                self.params.attribute.name(),
                cut.key,
                cut.number
            ),
            Err(_) => self.params.attribute.name().to_string(),
        };
        Annotations {
            legends: vec![Legend::Bar {
                title,
                colours: self
                    .prepared
                    .table
                    .entries
                    .iter()
                    .map(|&[r, g, b, _]| [r, g, b])
                    .collect(),
                low,
                high,
            }],
            axes: None,
        }
    }

    fn opaque(&self) -> bool {
        self.params.opacity >= 1.0
    }
}
