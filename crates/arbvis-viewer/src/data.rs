//! What the viewer keeps beside the renderer: the prepared (quantized, packed) voxels, the
//! axes in the data's numbers, a histogram of each attribute's quantized values, the
//! colour tables as built from the scene (and as egui textures), and the CPU-made section
//! images (inline, crossline, time slice) of one attribute coloured by its table.
//!
//! Decisions: for 3D opacity the viewer prepares the data itself and hands a copy to the
//! technique's renderer ([`catalog::renderer`]), so switching programs or fidelity re-uploads
//! without reading files again, and histograms and sections read the same bytes the GPU
//! samples. Sections show the table's colour opaque (its alpha would hide the section where
//! the volume is clear); pixels are voxels, stretched to the box's physical aspect. A survey
//! streamed from a store has no prepared voxels: its sections are read from the store at
//! level 0 ([`super::store_sections`]).

use egui::{Color32, ColorImage, TextureHandle, TextureOptions};

use super::store_sections::{MapPositions, SectionKey, StoreSections};
use arbvis_core::colortable::{ColorTable, TableSpec};
use arbvis_data::volume::axes::{self, section_axes, section_voxels, Axis};
use arbvis_gl::{Gpu, ProgramKind};
use arbvis_techniques::catalog;
use arbvis_techniques::error::RenderResult;
use arbvis_techniques::scene::Scene;
use arbvis_techniques::summary::{CloudSummary, DataBox, MeshSummary, Summary};
use arbvis_techniques::techniques::opacity3d::prepare::{prepare, Prepared};
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;
use arbvis_techniques::techniques::Renderer;

/// The 3D-opacity data behind the panels.
pub struct Volume3d {
    /// The voxels as uploaded.
    pub prepared: Prepared,
    /// The axes, in the data's numbers.
    pub axes: [Axis; 3],
    /// Per attribute, how many voxels hold each quantized value.
    pub histograms: [Option<Vec<u32>>; 3],
}

/// One section image and what it shows.
struct Section {
    key: (usize, usize, usize, Vec<[u8; 4]>),
    texture: TextureHandle,
}

/// Everything the viewer keeps besides the renderer.
#[derive(Default)]
pub struct ViewData {
    /// 3D-opacity data (none for other techniques).
    pub volume: Option<Volume3d>,
    /// A cloud's box and key (splats).
    pub cloud: Option<CloudSummary>,
    /// A mesh's box and scalar (cell projection).
    pub mesh: Option<MeshSummary>,
    /// Per attribute: the spec the table was built from, the table, its colours as a
    /// 256 x 1 texture.
    tables: [Option<(TableSpec, ColorTable, TextureHandle)>; 3],
    sections: [Option<Section>; 3],
    histograms: [Option<TextureHandle>; 3],
    /// A store's sections (3D opacity drawn from a store).
    pub store: Option<StoreSections>,
    /// Per axis, the last section read from the store and its levels.
    store_levels: [Option<(SectionKey, Vec<u8>)>; 3],
}

/// What the sections panel needs to know of the data: axes, voxels per axis, the box's
/// half extents, and the attributes present.
pub struct SectionGrid {
    /// The axes in the data's numbers.
    pub axes: [Axis; 3],
    /// Voxels per axis.
    pub dims: [usize; 3],
    /// Half extents of the box.
    pub half: glam::DVec3,
    /// Attributes present (0 primary, 1 secondary, 2 tertiary).
    pub present: Vec<usize>,
    /// Each trace's map position, where the store has one.
    pub positions: Option<std::sync::Arc<MapPositions>>,
}

impl SectionGrid {
    /// What the pointer at `(across, down)` (fractions of the picture, 0..1) over the
    /// section at `index` along `axis` points at: the voxel's numbers on the three axes,
    /// inline first, and the trace's map position where the data has one.
    pub fn point(&self, axis: usize, index: usize, across: f32, down: f32) -> String {
        let (u, w) = arbvis_data::volume::axes::section_axes(axis);
        let at = |f: f32, n: usize| ((f.max(0.0) * n as f32) as usize).min(n.saturating_sub(1));
        let mut v = [0usize; 3];
        v[axis] = index.min(self.dims[axis].saturating_sub(1));
        v[u] = at(across, self.dims[u]);
        v[w] = at(down, self.dims[w]);
        let mut text = [2, 1, 0]
            .map(|a| format!("{} {}", self.axes[a].name, self.axes[a].label(v[a])))
            .join(", ");
        if let Some([x, y]) = self.positions.as_ref().and_then(|p| p.at(v[1], v[2])) {
            text.push_str(&format!("\nmap x {x:.1}, y {y:.1}"));
        }
        text
    }
}

/// Build the scene's renderer with programs of `kind` through the catalog
/// ([`catalog::prepare`], then [`catalog::renderer`]), keeping what the panels show of
/// the prepared data: a cloud's or a mesh's summary; for 3D opacity the voxels themselves
/// ([`build_volume`]).
pub fn build(
    gpu: &Gpu,
    scene: &Scene,
    kind: ProgramKind,
    data: &mut ViewData,
) -> RenderResult<Box<dyn Renderer>> {
    if scene.is_layered() {
        // The panels' data are one technique's: a layered scene shows its layers' editors.
        (data.volume, data.cloud, data.mesh) = (None, None, None);
        let layers: Vec<_> = scene.layers().collect();
        return arbvis_techniques::layered::build_any(gpu, &layers, &scene.settings(), kind);
    }
    if let Some(params) = scene.technique.get::<Opacity3dScene>() {
        return build_volume(gpu, scene, params, kind, data);
    }
    data.volume = None;
    let settings = scene.settings();
    let limits = arbvis_data::volume::Limits::for_max_side(gpu.caps().max_3d_texture_size);
    let prepared = catalog::prepare(&scene.technique, &settings, &limits)?;
    (data.cloud, data.mesh) = match catalog::summary(&scene.technique, &prepared, &scene.base) {
        Some(Summary::Cloud(cloud)) => (Some(cloud), None),
        Some(Summary::Mesh(mesh)) => (None, Some(mesh)),
        None => (None, None),
    };
    catalog::renderer(&scene.technique, gpu, &settings, kind, prepared)
}

/// 3D opacity's renderer: a survey store streamed, else the volume prepared once and kept,
/// so that switching programs or fidelity re-uploads without reading files again.
fn build_volume(
    gpu: &Gpu,
    scene: &Scene,
    params: &Opacity3dScene,
    kind: ProgramKind,
    data: &mut ViewData,
) -> RenderResult<Box<dyn Renderer>> {
    // A survey store is streamed: frames draw what is resident and refine.
    if arbvis_techniques::techniques::opacity3d::bricked::store_of(params)
        .ok()
        .flatten()
        .is_some()
    {
        data.volume = None;
        let mut r = arbvis_techniques::render::build(gpu, scene, kind)?;
        r.set_streaming(true);
        data.store = StoreSections::open(params, &scene.base)?;
        data.store_levels = [None, None, None];
        data.sections = [None, None, None];
        return Ok(r);
    }
    data.store = None;
    let volume = match data.volume.take() {
        Some(volume) => volume,
        None => {
            params.validate()?;
            let limits = arbvis_data::volume::Limits::for_max_side(gpu.caps().max_3d_texture_size);
            let prepared = prepare(params, &scene.base, &limits)?;
            let axes = axes::describe(&params.primary.volume, &scene.base, prepared.dims);
            let histograms = std::array::from_fn(|a| {
                prepared.tables[a].as_ref().map(|_| {
                    let mut h = vec![0u32; 256];
                    for v in 0..prepared.packed.len() / 3 {
                        h[prepared.byte(v, a) as usize] += 1;
                    }
                    h
                })
            });
            Volume3d {
                prepared,
                axes,
                histograms,
            }
        }
    };
    let v = data.volume.insert(volume);
    let mut prepared = v.prepared.clone();
    for (a, attr) in params.attributes().into_iter().enumerate() {
        if let Some(attr) = attr {
            prepared.tables[a] = Some(attr.table.build(&scene.base)?);
        }
    }
    catalog::renderer(
        &scene.technique,
        gpu,
        &scene.settings(),
        kind,
        Box::new(arbvis_techniques::techniques::opacity3d::Prepared3d {
            whole: Some(prepared),
            store_world: None,
        }),
    )
}

impl ViewData {
    /// The box the overlay draws and its axes: the volume's, the cloud's or the mesh's.
    pub fn data_box(&self) -> Option<DataBox> {
        if let Some(g) = self.section_grid() {
            return Some(DataBox {
                half: g.half,
                axes: g.axes,
            });
        }
        let cloud = self.cloud.as_ref().map(|c| &c.data_box);
        cloud.or(self.mesh.as_ref().map(|m| &m.data_box)).cloned()
    }

    /// The table of attribute `a` as the scene now names it, and its colour texture
    /// (rebuilt when the spec changed; `None` for an absent attribute or a table that
    /// cannot be built).
    pub fn table(
        &mut self,
        ctx: &egui::Context,
        scene: &Scene,
        a: usize,
    ) -> Option<(&ColorTable, &TextureHandle)> {
        let o = scene.technique.get::<Opacity3dScene>()?;
        let spec = &o.attributes()[a]?.table;
        let stale = self.tables[a].as_ref().is_none_or(|(s, _, _)| s != spec);
        if stale {
            let table = spec.build(&scene.base).ok()?;
            let texture = super::curve::colour_strip(
                ctx,
                format!("table {a}"),
                &table.entries,
                TextureOptions::NEAREST,
            );
            self.tables[a] = Some((spec.clone(), table, texture));
        }
        self.tables[a].as_ref().map(|(_, t, x)| (t, x))
    }

    /// Attribute `a`'s histogram as an image (made once).
    pub fn histogram(&mut self, ctx: &egui::Context, a: usize) -> Option<egui::TextureId> {
        if self.histograms[a].is_none() {
            let counts = self.volume.as_ref()?.histograms[a].as_ref()?;
            let image = super::curve::histogram_image(counts);
            self.histograms[a] =
                Some(ctx.load_texture(format!("histogram {a}"), image, TextureOptions::NEAREST));
        }
        self.histograms[a].as_ref().map(|t| t.id())
    }

    /// The grid the sections cut: the prepared volume's, or the store's window.
    pub fn section_grid(&self) -> Option<SectionGrid> {
        if let Some(v) = &self.volume {
            return Some(SectionGrid {
                axes: v.axes.clone(),
                dims: v.prepared.dims,
                half: v.prepared.half,
                present: (0..3).filter(|&a| v.prepared.tables[a].is_some()).collect(),
                positions: None,
            });
        }
        let s = self.store.as_ref()?;
        Some(SectionGrid {
            axes: s.axes.clone(),
            dims: s.dims,
            half: s.half,
            present: (0..3).filter(|&a| s.attributes[a].is_some()).collect(),
            positions: s.positions.clone(),
        })
    }

    /// The section at `index` along `axis` of attribute `a` from the store, read at
    /// level 0 by the reader thread: the newest one read for this axis meanwhile.
    fn store_section(
        &mut self,
        ctx: &egui::Context,
        entries: Vec<[u8; 4]>,
        axis: usize,
        index: usize,
        a: usize,
    ) -> Option<TextureHandle> {
        let store = self.store.as_mut()?;
        let index = index.min(store.dims[axis].saturating_sub(1));
        store.ask((axis, index, a));
        for (key, levels) in store.arrived() {
            match levels {
                Ok(levels) => self.store_levels[key.0] = Some((key, levels)),
                Err(e) => eprintln!("section {key:?}: {e}"),
            }
        }
        let (key, levels) = self.store_levels[axis].as_ref()?;
        let full = (key.0, key.1, key.2, entries);
        if let Some(s) = &self.sections[axis] {
            if s.key == full {
                return Some(s.texture.clone());
            }
        }
        let (u, w) = section_axes(axis);
        let (nu, nw) = (self.store.as_ref()?.dims[u], self.store.as_ref()?.dims[w]);
        if levels.len() != nu * nw {
            return None;
        }
        let pixels = levels
            .iter()
            .map(|&l| {
                let e = full.3[l as usize];
                Color32::from_rgb(e[0], e[1], e[2])
            })
            .collect();
        let image = ColorImage::new([nu, nw], pixels);
        let texture = ctx.load_texture(format!("section {axis}"), image, TextureOptions::NEAREST);
        self.sections[axis] = Some(Section {
            key: full,
            texture: texture.clone(),
        });
        Some(texture)
    }

    /// The section at `index` along `axis` of attribute `a`, coloured by its table.
    pub fn section(
        &mut self,
        ctx: &egui::Context,
        scene: &Scene,
        axis: usize,
        index: usize,
        a: usize,
    ) -> Option<TextureHandle> {
        let entries = self.table(ctx, scene, a)?.0.entries.clone();
        if self.volume.is_none() {
            return self.store_section(ctx, entries, axis, index, a);
        }
        let v = self.volume.as_ref()?;
        let p = &v.prepared;
        let index = index.min(p.dims[axis].saturating_sub(1));
        let key = (axis, index, a, entries);
        if let Some(s) = &self.sections[axis] {
            if s.key == key {
                return Some(s.texture.clone());
            }
        }
        let ([nu, nw], voxels) = section_voxels(p.dims, axis, index);
        let pixels = voxels
            .map(|ijk| {
                let voxel = ijk[0] + p.dims[0] * (ijk[1] + p.dims[1] * ijk[2]);
                let e = key.3[p.byte(voxel, a) as usize];
                Color32::from_rgb(e[0], e[1], e[2])
            })
            .collect();
        let image = ColorImage::new([nu, nw], pixels);
        let texture = ctx.load_texture(format!("section {axis}"), image, TextureOptions::NEAREST);
        self.sections[axis] = Some(Section {
            key,
            texture: texture.clone(),
        });
        Some(texture)
    }
}
