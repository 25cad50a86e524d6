//! Precise 3D opacity of a store in one pass: the ray caster (`raycast.frag`, tag `paged`)
//! walks the survey's bricks through a page table, as seed 002's INDEX-DATA clip texture
//! does (the shared layout and offset are [`arbvis_data::volume::index_data`]).
//!
//! # How it works
//! 1. The brick cache keeps its resident bricks in one atlas texture of `(B+2)³` slots
//!    (16-bit unorm, the precise volume's format: the same 8-bit levels, filtered in
//!    float), each brick with one voxel of its neighbours.
//! 2. Each frame the page table gets one RGBA32F entry per level-0 brick of the window:
//!    for the resident brick of level `l` that covers it, `w = 2^-l` and the offset
//!    `xyz` ([`index_data::offset`]) so that level-0 voxel coordinate `v` reads the atlas
//!    at `v * w / atlas + xyz`; `w = 0` where nothing is drawn (bricks the tables make
//!    transparent, or not in view), which the rays skip.
//! 3. Rays are the whole-volume ray caster's (exact entry, the chord cut into equal steps
//!    no longer than the step length, samples at the steps' middles, front to back,
//!    stopping at the termination alpha). In a page of level `l` one sample stands for
//!    `2^l` steps: it sits at their middle and its opacity is corrected for their length,
//!    `1 - (1 - a)^(2^l h / reference)`. At level 0 every sample is where the
//!    whole-volume ray caster puts it.
//!
//! # Seams and level transitions
//! A sample within a brick reads only that brick's slot (its border voxels are the
//! neighbours' first voxels), so at a seam between two bricks of one level both sides
//! read the same voxels with the same weights: exact. Where levels meet, the coarse
//! page's sample may stand for steps that reach up to `2^l - 1` steps into the finer
//! page, and each side shows its own level's data (the data's difference, not a crack).
//!
//! # Budget
//! One pass needs every brick of the frame resident at once: offscreen the cut is chosen
//! to fit the atlas (coarser levels where the budget is short; `store.level` forcing more
//! bricks than fit is refused with the count), and streaming draws what is resident with
//! the nearest resident ancestors standing in.

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use glam::DVec3;

use super::locals;
use super::programs::{raycast_pair, InShader, Variant};
use super::proxy::{eye, far_faces, toward_viewer};
use super::{corrected, Combine, Opacity3dScene};
use crate::techniques::Frame;
use arbvis_core::camera::Projection;
use arbvis_data::store::lod::{BrickId, Pyramid};
use arbvis_data::volume::index_data::{self, SlotGrid};
use arbvis_gl::{
    self, Blend, DrawCall, Gpu, Mesh, Program, Surface, TexelData, TexelFormat, Texture,
};

/// Unit of the page table (the clip's INDEX unit; a store scene has no clip).
pub const PAGE_UNIT: u32 = 7;

/// The page table of one frame: entries over the window's level-0 bricks.
#[derive(Debug, Clone, PartialEq)]
pub struct PageTable {
    /// The first page (level-0 brick) the table holds.
    pub first: [usize; 3],
    /// Pages per axis.
    pub dims: [usize; 3],
    /// RGBA entries, i fastest: offset and `2^-level`, or zeros.
    pub entries: Vec<[f32; 4]>,
}

impl PageTable {
    /// The table for the resident bricks `drawn`, `slot` giving each one's atlas slot;
    /// where bricks overlap (a stand-in and finer bricks under it), the finest wins.
    pub fn build(
        pyr: &Pyramid,
        grid: SlotGrid,
        drawn: &[BrickId],
        slot: &mut dyn FnMut(BrickId) -> Option<usize>,
    ) -> PageTable {
        let b = pyr.brick;
        let first: [usize; 3] = std::array::from_fn(|a| pyr.window[0][a] / b);
        let end: [usize; 3] = std::array::from_fn(|a| pyr.window[1][a].div_ceil(b));
        let dims: [usize; 3] = std::array::from_fn(|a| end[a].saturating_sub(first[a]).max(1));
        let mut entries = vec![[0f32; 4]; dims.iter().product()];
        let atlas = DVec3::from_array(grid.texels().map(|t| t.max(1) as f64));
        let mut coarse_first = drawn.to_vec();
        coarse_first.sort_by_key(|id| std::cmp::Reverse(id.level));
        for id in coarse_first {
            let Some(s) = slot(id) else { continue };
            let scale = 1u64 << id.level;
            let c = id.c.map(|x| x as usize);
            // The brick's centre in level-0 voxels; `p * S + O` with S = 2^-l / atlas.
            let centre =
                DVec3::from_array(c.map(|x| (x * b) as f64 + b as f64 / 2.0)) * scale as f64;
            let s_scale = DVec3::splat(1.0 / scale as f64) / atlas;
            let o = index_data::offset(grid.slot_centre(s), centre, s_scale);
            let entry = [o.x as f32, o.y as f32, o.z as f32, 1.0 / scale as f32];
            let lo: [usize; 3] = std::array::from_fn(|a| (c[a] * scale as usize).max(first[a]));
            let hi: [usize; 3] = std::array::from_fn(|a| ((c[a] + 1) * scale as usize).min(end[a]));
            for k in lo[2]..hi[2] {
                for j in lo[1]..hi[1] {
                    for i in lo[0]..hi[0] {
                        let at =
                            (i - first[0]) + dims[0] * ((j - first[1]) + dims[1] * (k - first[2]));
                        entries[at] = entry;
                    }
                }
            }
        }
        PageTable {
            first,
            dims,
            entries,
        }
    }
}

/// The ray caster's program, box and page-table texture.
pub struct PagedPass {
    program: Program,
    projection: Projection,
    combine: Combine,
    present: [bool; 3],
    filter: InShader,
    mesh: Option<Mesh>,
    table: Option<(Texture, [usize; 3])>,
}

fn program(
    gpu: &Gpu,
    combine: Combine,
    present: [bool; 3],
    projection: Projection,
    filter: InShader,
) -> GlResult<Program> {
    let pair = raycast_pair(Variant {
        combine,
        present,
        projection,
        skip: false,
        preint: false,
        jitter: false,
        baked: false,
        paged: true,
        neighbours: false,
        filter,
    });
    Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)
}

impl PagedPass {
    /// The pass for `params` (GLSL: ARB fragment programs have no loops).
    pub fn new(gpu: &Gpu, params: &Opacity3dScene) -> RenderResult<PagedPass> {
        let present = params.attributes().map(|a| a.is_some());
        let projection = Projection::Orthographic;
        let filter =
            super::renderer::shader_filter(gpu, params, arbvis_core::vocab::Fidelity::Precise)?;
        Ok(PagedPass {
            program: program(gpu, params.combine, present, projection, filter)?,
            projection,
            combine: params.combine,
            present,
            filter,
            mesh: None,
            table: None,
        })
    }

    /// The program, rebuilt when the combination changed.
    pub fn program_for(&mut self, gpu: &Gpu, params: &Opacity3dScene) -> RenderResult<&Program> {
        let present = params.attributes().map(|a| a.is_some());
        let filter =
            super::renderer::shader_filter(gpu, params, arbvis_core::vocab::Fidelity::Precise)?;
        if params.combine != self.combine || present != self.present || filter != self.filter {
            self.combine = params.combine;
            self.present = present;
            self.filter = filter;
            self.program = program(gpu, self.combine, present, self.projection, filter)?;
        }
        Ok(&self.program)
    }

    /// Draw the frame: the box's far faces, one ray per pixel, through `table` into the
    /// atlas; `tables` are the colour tables on units 2/3/4.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        params: &Opacity3dScene,
        pyr: &Pyramid,
        atlas: (&Texture, SlotGrid),
        table: &PageTable,
        tables: &[(u32, &Texture)],
    ) -> RenderResult<()> {
        if frame.camera.projection != self.projection {
            self.projection = frame.camera.projection;
            self.program = program(
                gpu,
                self.combine,
                self.present,
                self.projection,
                self.filter,
            )?;
        }
        let half = pyr.half();
        if self.mesh.is_none() {
            self.mesh = Some(Mesh::new(
                gpu,
                "store ray caster box",
                &[4, 4],
                &far_faces(half),
            )?);
        }
        let data = TexelData::F32(table.entries.as_flattened());
        match &self.table {
            Some((t, dims)) if *dims == table.dims => t.update_data(gpu, data)?,
            _ => {
                let [w, h, d] = table.dims.map(|v| v as u32);
                let t = Texture::new(
                    gpu,
                    "store page table",
                    arbvis_gl::Extent::D3(w, h, d),
                    TexelFormat::Rgba32f,
                    arbvis_gl::Filter::Nearest,
                    data,
                )?;
                self.table = Some((t, table.dims));
            }
        }
        let p = &self.program;
        for (i, c) in super::coefficients(params).iter().enumerate() {
            p.set_local(gpu, locals::COEFFICIENTS + i, *c)?;
        }
        let window: [f64; 3] =
            std::array::from_fn(|a| (pyr.window[1][a] - pyr.window[0][a]) as f64);
        let longest = (0..3)
            .max_by(|&a, &b| half[a].total_cmp(&half[b]))
            .unwrap_or(0);
        let reference = 2.0 * half[longest] / window[longest];
        let r = params.raycast.unwrap_or_default();
        let (scale, offset) = if corrected(params, arbvis_core::vocab::Fidelity::Precise) {
            (1.0 / reference, 0.0)
        } else {
            (0.0, 1.0)
        };
        p.set_local(
            gpu,
            locals::CORRECTION,
            [scale, reference / r.steps_per_voxel, offset, 0.0],
        )?;
        p.set_local(
            gpu,
            locals::LOOKUP,
            [255.0 / 256.0, 0.5 / 256.0, 1.0 / 3.0, 0.0],
        )?;
        p.set_local(gpu, locals::BOX_SIZE, (2.0 * half).extend(0.0).to_array())?;
        p.set_local(gpu, locals::BOX_HALF, half.extend(0.0).to_array())?;
        let ray = match frame.camera.projection {
            Projection::Perspective => eye(frame),
            Projection::Orthographic => -toward_viewer(frame).normalize(),
        };
        p.set_local(gpu, locals::RAY, ray.extend(0.0).to_array())?;
        p.set_local(gpu, locals::AXIS, [1.0, 1.0, 1.0, 1.0 - r.termination])?;
        let w = pyr.window;
        p.set_local(
            gpu,
            locals::PAGED_WINDOW,
            [window[0], window[1], window[2], pyr.brick as f64],
        )?;
        p.set_local(
            gpu,
            locals::PAGED_FIRST_VOXEL,
            [w[0][0] as f64, w[0][1] as f64, w[0][2] as f64, 0.0],
        )?;
        let texels = atlas.1.texels().map(|t| 1.0 / t.max(1) as f64);
        p.set_local(
            gpu,
            locals::PAGED_PER_TEXEL,
            [texels[0], texels[1], texels[2], 0.0],
        )?;
        let f = table.first.map(|v| v as f64);
        p.set_local(gpu, locals::PAGED_FIRST_PAGE, [f[0], f[1], f[2], 0.0])?;
        p.set_transform(gpu, super::renderer::model_view_projection(frame))?;
        super::renderer::send_pixel_rays(gpu, p, surface, frame)?;
        let (Some(mesh), Some((page, _))) = (&self.mesh, &self.table) else {
            return Ok(());
        };
        let mut textures: Vec<(u32, &Texture)> =
            vec![(super::renderer::VOLUME_UNIT, atlas.0), (PAGE_UNIT, page)];
        textures.extend_from_slice(tables);
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &textures,
                blend: Blend::PremultipliedOver,
                cull_back: true,
                ..DrawCall::new(&self.program, mesh)
            },
        )?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_page_reads_its_brick_s_slot_at_every_level() {
        // A 100 x 70 x 40 survey in bricks of 16, window from voxel (10, 0, 5): a level-0
        // brick and a level-1 brick; a voxel centre of each lands on its slot's texel.
        let pyr = Pyramid {
            dims: [100, 70, 40],
            brick: 16,
            levels: 4,
            window: [[10, 0, 5], [100, 70, 40]],
            spacing: [1.0; 3],
        };
        let grid = SlotGrid::arrange(5, 18, 2048).unwrap();
        let fine = BrickId {
            level: 0,
            c: [1, 2, 0],
        };
        let coarse = BrickId {
            level: 1,
            c: [2, 0, 1],
        };
        // A level-1 stand-in over the fine brick's pages (streaming draws both): the
        // fine brick wins its page whatever the order given.
        let stand_in = BrickId {
            level: 1,
            c: [0, 1, 0],
        };
        let slots = |id: BrickId| match id {
            id if id == fine => Some(3),
            id if id == coarse => Some(1),
            _ => Some(0),
        };
        let mut slot = slots;
        let t = PageTable::build(&pyr, grid, &[fine, coarse, stand_in], &mut slot);
        assert_eq!(t.first, [0, 0, 0]);
        assert_eq!(t.dims, [7, 5, 3]);
        let atlas = DVec3::from_array(grid.texels().map(|v| v as f64));
        for (id, voxel) in [(fine, [20.5, 33.5, 2.5]), (coarse, [70.0, 10.0, 38.0])] {
            let page = voxel.map(|v| (v / 16.0) as usize);
            let e = t.entries[page[0] + 7 * (page[1] + 5 * page[2])];
            let v = DVec3::from_array(voxel);
            let tc = v * (e[3] as f64) / atlas + DVec3::new(e[0] as f64, e[1] as f64, e[2] as f64);
            let texel = tc * atlas;
            // Expected: the brick's level-l voxel coordinate, its slot corner, one border.
            let s = slots(id).unwrap();
            let corner = DVec3::from_array(grid.slot_corner(s).map(|c| c as f64));
            let scale = (1u64 << id.level) as f64;
            let origin = DVec3::from_array(id.c.map(|c| (c * 16) as f64 - 1.0));
            let expected = corner + v / scale - origin;
            assert!(
                (texel - expected).abs().max_element() < 1e-3,
                "{id:?}: {texel} vs {expected}"
            );
            assert_eq!(e[3], 1.0 / scale as f32);
        }
        // The level-1 brick (2, 0, 1) covers pages 4..6 x 0..2 x 2..3 (clamped to 7 x 5 x
        // 3), the stand-in 0..2 x 2..4 x 0..2 less the fine brick's page.
        let covered = t.entries.iter().filter(|e| e[3] == 0.5).count();
        assert_eq!(covered, 2 * 2 + 2 * 2 * 2 - 1);
        // Nothing else is drawn: the rest is empty.
        let empty = t.entries.iter().filter(|e| e[3] == 0.0).count();
        assert_eq!(empty, 7 * 5 * 3 - 11 - 1);
    }
}
