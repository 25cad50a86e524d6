//! Precise `grid` (issue 27): the mesh resampled onto a regular grid once (the scalar
//! interpolated in the tetrahedron holding each grid point) and ray cast with a
//! pre-integrated table of the step's length (`volume_grid.frag`). Not cell projection:
//! its work is pixels times steps, not fragments of every cell, so it is the fast choice
//! where the cells are about the grid's size (the seed's 17³ grid), and its error is the
//! resampling's (trilinear between grid points instead of linear in each tetrahedron, the
//! boundary to within a grid spacing) and the table's.

use crate::error::RenderResult;
use arbvis_gl::GlResult;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

use super::super::preint;
use super::super::prepare::Prepared;
use super::super::transfer::{Build, Transfer, VolumeSpec};
use crate::programs::{self, ProgramPair};
use crate::techniques::cellproj::locals;
use crate::techniques::quad::quad_mesh;
use crate::techniques::Frame;
use arbvis_gl::{
    self, Blend, DrawCall, Extent, Filter, Gpu, Mesh, Program, ProgramKind, Surface, TexelData,
    TexelFormat, Texture,
};

/// The mesh's scalar on a regular grid.
#[derive(Debug, Clone)]
pub struct Resampled {
    /// Points along x, y, z.
    pub dims: [usize; 3],
    /// The first point (the object box's low corner).
    pub lo: DVec3,
    /// Distance between neighbouring points along x, y, z, in object units: the box's
    /// side over its points less one, so the last points lie on the box's upper faces (a
    /// box-shaped mesh's faces, and a thin mesh's two, fall on grid points).
    pub spacing: DVec3,
    /// `(s m, m)` per point, x fastest: `m` is 1 where a tetrahedron holds the point and
    /// 0 elsewhere (`s m` then 0).
    pub texels: Vec<f32>,
}

impl Resampled {
    /// Scalar and inside weight at point `(i, j, k)`.
    pub fn at(&self, [i, j, k]: [usize; 3]) -> [f32; 2] {
        let [nx, ny, _] = self.dims;
        let o = 2 * (i + nx * (j + ny * k));
        [self.texels[o], self.texels[o + 1]]
    }
}

/// The points along x, y, z of a grid over the box of half-extents `half` with `points`
/// along its longest side (at least 2 each), and their spacing (each side over its points
/// less one).
pub fn layout(half: DVec3, points: u32) -> ([usize; 3], DVec3) {
    let longest = 2.0 * half.max_element().max(1e-300) / (points.max(2) - 1) as f64;
    let dims = (2.0 * half / longest)
        .to_array()
        .map(|e| (e - 1e-9).ceil().max(1.0) as usize + 1);
    let spacing = DVec3::from_array(std::array::from_fn(|a| {
        (2.0 * half[a] / (dims[a] - 1) as f64).max(1e-300)
    }));
    (dims, spacing)
}

/// Bytes per grid point: `(s m, m)` as two f32.
const POINT_BYTES: u64 = 8;

/// Z planes per parallel slab of the resampling.
const PLANES: usize = 2;

/// `prepared`'s scalar at the points of a grid over its box with `points` points along
/// the box's longest side (at least 2), each point's value from the tetrahedron holding
/// it (barycentric weights, 1e-9 tolerance, so points on shared and boundary faces are
/// held).
pub fn resample(prepared: &Prepared, points: u32) -> Resampled {
    let half = prepared.half;
    let (dims, spacing) = layout(half, points);
    let lo = -half;
    let [nx, ny, nz] = dims;
    let index = |v: f64| (v - 1e-9).ceil().max(0.0) as usize;
    let last = |v: f64, n: usize| ((v + 1e-9).floor().max(-1.0) as i64).min(n as i64 - 1);
    let mut slabs: Vec<Vec<u32>> = vec![Vec::new(); nz.div_ceil(PLANES)];
    for t in 0..prepared.tets.len() {
        let (p, _) = prepared.tet(t);
        let z = p.map(|q| (q.z - lo.z) / spacing.z);
        let k0 = index(z.iter().copied().fold(f64::MAX, f64::min));
        let k1 = last(z.iter().copied().fold(f64::MIN, f64::max), nz);
        if k1 < k0 as i64 {
            continue;
        }
        for slab in &mut slabs[k0 / PLANES..=k1 as usize / PLANES] {
            slab.push(t as u32);
        }
    }
    let mut texels = vec![0f32; 2 * nx * ny * nz];
    texels
        .par_chunks_mut(2 * nx * ny * PLANES)
        .zip(&slabs)
        .enumerate()
        .for_each(|(c, (slab, tets))| {
            let first_k = c * PLANES;
            let planes = slab.len() / (2 * nx * ny);
            for &t in tets {
                let (p, s) = prepared.tet(t as usize);
                let inverse = DMat3::from_cols(p[1] - p[0], p[2] - p[0], p[3] - p[0]).inverse();
                let g = p.map(|q| (q - lo) / spacing);
                let min = g[1..].iter().fold(g[0], |a, &b| a.min(b));
                let max = g[1..].iter().fold(g[0], |a, &b| a.max(b));
                let k0 = index(min.z).max(first_k);
                let k1 = last(max.z, nz).min((first_k + planes) as i64 - 1);
                let (j0, j1) = (index(min.y), last(max.y, ny));
                let (i0, i1) = (index(min.x), last(max.x, nx));
                for k in k0 as i64..=k1 {
                    for j in j0 as i64..=j1 {
                        for i in i0 as i64..=i1 {
                            let q = lo + spacing * DVec3::new(i as f64, j as f64, k as f64);
                            let w = inverse * (q - p[0]);
                            let w0 = 1.0 - w.x - w.y - w.z;
                            if w.min_element() < -1e-9 || w0 < -1e-9 {
                                continue;
                            }
                            let value = w0 * s[0] + w.x * s[1] + w.y * s[2] + w.z * s[3];
                            let local = k as usize - first_k;
                            let o = 2 * (i as usize + nx * (j as usize + ny * local));
                            slab[o] = value.clamp(0.0, 1.0) as f32;
                            slab[o + 1] = 1.0;
                        }
                    }
                }
            }
        });
    Resampled {
        dims,
        lo,
        spacing,
        texels,
    }
}

/// The grid caster's program pair (GLSL).
pub fn grid_pair() -> ProgramPair {
    ProgramPair {
        kind: ProgramKind::Glsl,
        vertex: programs::TRANSFORM_VERT,
        fragment: programs::CELLPROJ_VOLUME_GRID_FRAG,
    }
}

/// Length layers of the step table, from 0 to the step: the short pieces (a ray's last
/// step, a step cut at the boundary) read between two; full steps read the last exactly.
const LENGTHS: u32 = 16;

/// Precise `grid`'s program, grid and tables.
pub(super) struct GridCaster {
    program: Program,
    quad: Mesh,
    grid: Texture,
    /// The pre-integrated table, lengths 0 to the step ([`LENGTHS`] layers).
    table: Texture,
    dims: [usize; 3],
    lo: DVec3,
    spacing: DVec3,
    /// The step along a ray, in object units (the longest side's spacing over the scene's
    /// `grid_steps`).
    step: f64,
}

impl GridCaster {
    /// Resample `prepared` at the scene's `grid` and build the tables.
    pub(super) fn new(
        gpu: &Gpu,
        prepared: &Prepared,
        spec: &VolumeSpec,
        transfer: &Transfer,
    ) -> RenderResult<GridCaster> {
        let pair = grid_pair();
        let program = Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment)?;
        program.set_transform(gpu, glam::DMat4::IDENTITY)?;
        let ([nx, ny, nz], _) = layout(prepared.half, spec.grid);
        arbvis_core::budget::check(
            format!("precise grid's {nx} x {ny} x {nz} points"),
            arbvis_core::budget::times((nx * ny * nz) as u64, POINT_BYTES),
        )?;
        let resampled = resample(prepared, spec.grid);
        let [nx, ny, nz] = resampled.dims.map(|n| n as u32);
        let grid = Texture::new(
            gpu,
            "cellproj volume grid (s m, m)",
            Extent::D3(nx, ny, nz),
            TexelFormat::Rg32f,
            Filter::Linear,
            TexelData::F32(&resampled.texels),
        )?;
        let quad = quad_mesh(gpu, "cellproj volume grid full-screen quad")?;
        let step = resampled.spacing.max_element() / spec.grid_steps;
        Ok(GridCaster {
            program,
            quad,
            table: step_table(gpu, spec, transfer, step)?,
            grid,
            dims: resampled.dims,
            lo: resampled.lo,
            spacing: resampled.spacing,
            step,
        })
    }

    /// Remake the table for a new transfer function.
    pub(super) fn set_transfer(
        &mut self,
        gpu: &Gpu,
        spec: &VolumeSpec,
        transfer: &Transfer,
    ) -> RenderResult<()> {
        self.table = step_table(gpu, spec, transfer, self.step)?;
        Ok(())
    }

    /// Cast every pixel's ray of `frame` onto `surface`.
    pub(super) fn draw(
        &self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        spec: &VolumeSpec,
    ) -> RenderResult<()> {
        let p = &self.program;
        let mvp = frame.camera.view_projection(frame.aspect());
        let inv = mvp.inverse().transpose();
        for (i, row) in [inv.x_axis, inv.y_axis, inv.z_axis, inv.w_axis]
            .iter()
            .enumerate()
        {
            p.set_local(gpu, locals::MVP_ROWS + i, row.to_array())?;
        }
        let corner = match surface {
            Surface::Target(_) => [0.0, 0.0],
            Surface::Window([x, y, _, _]) => [x as f64, y as f64],
        };
        let (w, h) = (frame.width as f64, frame.height as f64);
        p.set_local(gpu, locals::PIXELS, [w, h, corner[0], corner[1]])?;
        let lo = self.lo;
        p.set_local(gpu, locals::GRID_LOW, [lo.x, lo.y, lo.z, 0.0])?;
        let inv = 1.0 / self.spacing;
        p.set_local(
            gpu,
            locals::GRID_INVERSE_SPACING,
            [inv.x, inv.y, inv.z, 0.0],
        )?;
        let [nx, ny, nz] = self.dims.map(|n| n as f64);
        p.set_local(gpu, locals::GRID_DIMS, [nx, ny, nz, self.step])?;
        let sides = [spec.table_size[0] as f64, LENGTHS as f64];
        p.set_local(
            gpu,
            locals::GRID_TABLE,
            [sides[0], sides[1], spec.termination, 0.0],
        )?;
        Ok(arbvis_gl::draw(
            gpu,
            surface,
            &DrawCall {
                textures: &[(0, &self.grid), (1, &self.table)],
                blend: Blend::PremultipliedOver,
                covers_frame: true,
                ..DrawCall::new(p, &self.quad)
            },
        )?)
    }
}

/// The segment table for steps up to `step` long: `table_size[0]` texels along sf and sb,
/// [`LENGTHS`] along the length, each texel the exact segment integral.
fn step_table(gpu: &Gpu, spec: &VolumeSpec, transfer: &Transfer, step: f64) -> GlResult<Texture> {
    let n = spec.table_size[0];
    let texels = preint::table_f32(transfer, n as usize, LENGTHS as usize, step, Build::Exact);
    Texture::new(
        gpu,
        "cellproj volume grid step table (sf, sb, length up to the step)",
        Extent::D3(n, n, LENGTHS),
        TexelFormat::Rgba32f,
        Filter::Linear,
        TexelData::F32(&texels),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::cellproj::indices::tests::random_cells;

    /// Barycentric weights of `q` in tetrahedron `t`, by volumes (independent of the
    /// resampling's matrix inverse).
    fn weights(prepared: &Prepared, t: usize, q: DVec3) -> [f64; 4] {
        let (p, _) = prepared.tet(t);
        let volume = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| (b - a).dot((c - a).cross(d - a));
        let whole = volume(p[0], p[1], p[2], p[3]);
        [
            volume(q, p[1], p[2], p[3]) / whole,
            volume(p[0], q, p[2], p[3]) / whole,
            volume(p[0], p[1], q, p[3]) / whole,
            volume(p[0], p[1], p[2], q) / whole,
        ]
    }

    #[test]
    fn every_grid_point_takes_the_value_of_a_tetrahedron_holding_it() {
        // Overlapping random tetrahedra of unequal sizes, slivers among them, on grids
        // of odd and even sizes (the box is not a cube: fewer points along its short
        // sides).
        let prepared = random_cells(150, 11);
        for points in [7u32, 20, 33] {
            let r = resample(&prepared, points);
            let [nx, ny, nz] = r.dims;
            assert_eq!(r.dims.iter().max(), Some(&(points as usize)));
            let top =
                r.lo + r.spacing * DVec3::new(nx as f64 - 1.0, ny as f64 - 1.0, nz as f64 - 1.0);
            assert!(
                top.cmpge(prepared.half - 1e-9).all(),
                "{top} covers {}",
                prepared.half
            );
            let (mut inside, mut checked) = (0, 0);
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let q = r.lo + r.spacing * DVec3::new(i as f64, j as f64, k as f64);
                        let holding: Vec<(usize, [f64; 4])> = (0..prepared.tets.len())
                            .map(|t| (t, weights(&prepared, t, q)))
                            .filter(|(_, w)| w.iter().all(|&v| v >= -1e-9))
                            .collect();
                        // Points within 1e-7 of a face of a tetrahedron they are not
                        // clearly in or out of are left (either answer is right there).
                        let near_face = (0..prepared.tets.len()).any(|t| {
                            let w = weights(&prepared, t, q);
                            w.iter().all(|&v| v >= -1e-7) && w.iter().any(|&v| v < 1e-7)
                        });
                        let [s, m] = r.at([i, j, k]);
                        if near_face {
                            continue;
                        }
                        checked += 1;
                        assert_eq!(m, if holding.is_empty() { 0.0 } else { 1.0 }, "{q}");
                        if holding.is_empty() {
                            assert_eq!(s, 0.0);
                            continue;
                        }
                        inside += 1;
                        // The value of one of the tetrahedra holding it (they overlap
                        // and disagree), to f32 rounding, within [0, 1] as the tables
                        // read it (these scalars run 0..2).
                        let matches = holding.iter().any(|&(t, w)| {
                            let (_, v) = prepared.tet(t);
                            let want = (0..4).map(|c| w[c] * v[c]).sum::<f64>().clamp(0.0, 1.0);
                            (s as f64 - want).abs() < 1e-6
                        });
                        assert!(matches, "{q}: {s} from none of {holding:?}");
                    }
                }
            }
            // Held points: 6 of 343 at 7 points a side, thousands at 33.
            assert!(
                inside > 0 && checked > nx * ny * nz / 2,
                "{inside} {checked}"
            );
        }
    }
}
