//! What 3D opacity's texture units hold, made once per scene and shared by its drawing
//! paths: the volume on unit 0 (v3o2's packing, the present attributes, or the ray
//! caster's neighbour words) and the colour tables on units 2, 3 and 4, in the formats
//! of the fidelity (8-bit faithful, float precise).

use super::prepare::Prepared;
use super::programs::InShader;
use super::{path, Opacity3dScene, Path3d};
use arbvis_core::colortable::ColorTable;
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{Extent, Filter, GlResult, Gpu, TexelData, TexelFormat, Texture};

/// Texel formats of the packed volume and the tables: 8-bit when faithful (filtering in
/// 8-bit arithmetic, as the original hardware); when precise the same 8-bit values as
/// 16-bit unorm (k·257/65535 = k/255 exactly, so a level's texel-centre lookup lands on
/// its entry; half floats put it up to 0.06 texel off) and f32 tables, filtered in float.
/// The precise volume holds only the present attributes (`count` channels); one
/// attribute is stored as f32 (the same k/255, 4 bytes a voxel), which llvmpipe filters
/// faster than 16-bit unorm (measured: docs/benchmarks.md, "3D opacity: figures behind
/// its settings").
pub fn texel_formats(fidelity: Fidelity, count: usize) -> (TexelFormat, TexelFormat) {
    match fidelity {
        Fidelity::Faithful => (TexelFormat::Rgb8, TexelFormat::Rgba8),
        Fidelity::Precise => (
            match count {
                1 => TexelFormat::R32fFromU8,
                2 => TexelFormat::Rg16FromU8,
                _ => TexelFormat::Rgb16FromU8,
            },
            TexelFormat::Rgba32fFromU8,
        ),
    }
}

pub fn table_texture(
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
        texel_formats(fidelity, 1).1,
        filter,
        TexelData::U8(&table.texels()),
    )
}

/// Whether the volume unit holds neighbour words ([`Prepared::neighbour_words`]): the
/// precise ray caster of one attribute read linearly (a clip's test reads its own units
/// only; a nearest volume keeps the plain texture).
pub fn uses_neighbours(params: &Opacity3dScene, fidelity: Fidelity, prepared: &Prepared) -> bool {
    fidelity == Fidelity::Precise
        && path(params, fidelity) == Path3d::Raycast
        && prepared.count() == 1
        && params.volume_filter == Filter::Linear
}

/// The volume on [`VOLUME_UNIT`]: v3o2's packing (faithful), the present attributes'
/// levels (precise), or one attribute's neighbour words (the ray caster, `neighbours`;
/// 8 bytes a voxel against 4, checked against the memory budget before they are made).
pub fn volume_texture(
    gpu: &Gpu,
    fidelity: Fidelity,
    params: &Opacity3dScene,
    prepared: &Prepared,
    filter: InShader,
    neighbours: bool,
) -> GlResult<Texture> {
    let [ni, nj, nk] = prepared.dims;
    let extent = Extent::D3(ni as u32, nj as u32, nk as u32);
    if neighbours {
        let bytes = (ni * nj * nk) as u64 * 8;
        arbvis_core::budget::check(
            "the ray caster's neighbour texture (8 bytes a voxel)",
            bytes,
        )?;
        return Texture::new(
            gpu,
            "opacity3d neighbour words (each voxel's 2x2x2 levels)",
            extent,
            TexelFormat::Rg32ui,
            Filter::Nearest,
            TexelData::U32(&prepared.neighbour_words()),
        );
    }
    match fidelity {
        Fidelity::Faithful => Texture::new(
            gpu,
            "opacity3d packed volume (R tertiary, G primary, B secondary)",
            extent,
            TexelFormat::Rgb8,
            params.volume_filter,
            TexelData::U8(&prepared.packed),
        ),
        Fidelity::Precise => Texture::new(
            gpu,
            "opacity3d packed volume (present attributes in order)",
            extent,
            texel_formats(fidelity, prepared.count()).0,
            unit_filter(params.volume_filter, filter.volume),
            TexelData::U8(&prepared.present_levels()),
        ),
    }
}

/// The neutral table a faithful product needs where an attribute's table is missing
/// (`tables`), or none.
pub fn neutral_for(
    gpu: &Gpu,
    tables: &[Option<Texture>; 3],
    combine: super::Combine,
    fidelity: Fidelity,
) -> GlResult<Option<Texture>> {
    // Precise programs leave absent attributes out; the verbatim product reads all three.
    let missing = tables.iter().any(Option::is_none);
    if missing && combine == super::Combine::Product && fidelity == Fidelity::Faithful {
        Ok(Some(neutral_table(gpu)?))
    } else {
        Ok(None)
    }
}

/// The white table a product reads for an absent attribute (so it multiplies by one).
pub fn neutral_table(gpu: &Gpu) -> GlResult<Texture> {
    Texture::new(
        gpu,
        "opacity3d neutral table (absent attribute in a product)",
        Extent::D2(1, 1),
        TexelFormat::Rgba8,
        Filter::Nearest,
        TexelData::U8(&[255; 4]),
    )
}

/// The filter a texture is made with: NEAREST where the program interpolates it itself
/// (the ARB programs read texel centres; `texelFetch` ignores the filter).
pub fn unit_filter(filter: Filter, in_shader: bool) -> Filter {
    if in_shader {
        Filter::Nearest
    } else {
        filter
    }
}
