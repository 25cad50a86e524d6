//! The precise volume's neighbour walk (see the parent module): the mesh in textures,
//! the entry layers peeled from the boundary, and the full-screen passes that walk every
//! pixel's ray through the tetrahedra and integrate it exactly.

use crate::error::{texture_rows, RenderResult};
use arbvis_gl::GlResult;
use glam::DVec3;
use rayon::prelude::*;

use super::super::indices::eye_and_direction;
use super::super::order::BOUNDARY;
use super::super::prepare::{gradient, normal, Prepared, FACES};
use super::super::transfer::{Transfer, VolumeSpec};
use super::super::Isovalue;
use crate::programs::{self, ProgramPair};
use crate::techniques::cellproj::locals;
use crate::techniques::Frame;
use arbvis_core::camera::Projection;
use arbvis_gl::ProgramText;
use arbvis_gl::{
    self, Blend, DrawCall, Extent, Filter, Gpu, Mesh, Program, ProgramKind, Surface, Target,
    TargetFormat, TexelData, TexelFormat, Texture,
};

/// `volume_integral.glsl` joined before the main of `fragment` (after its `#version`).
pub fn with_integral(fragment: &ProgramText) -> ProgramText {
    let text = &fragment.text;
    let cut = text.find('\n').map_or(0, |i| i + 1);
    ProgramText {
        name: fragment.name.clone(),
        text: format!(
            "{}{}\n{}",
            &text[..cut],
            programs::CELLPROJ_VOLUME_INTEGRAL_GLSL.text,
            &text[cut..]
        )
        .into(),
    }
}

/// The precise pairs: entry layers, the walk, and the projected variant (the integral
/// joined to the last two).
pub fn precise_pairs() -> [ProgramPair; 3] {
    use programs::*;
    [
        ProgramPair {
            kind: ProgramKind::Glsl,
            vertex: CELLPROJ_VOLUME_PEEL_VERT,
            fragment: CELLPROJ_VOLUME_PEEL_FRAG,
        },
        ProgramPair {
            kind: ProgramKind::Glsl,
            vertex: TRANSFORM_VERT,
            fragment: with_integral(&CELLPROJ_VOLUME_WALK_FRAG),
        },
        ProgramPair {
            kind: ProgramKind::Glsl,
            vertex: CELLPROJ_PRECISE_VERT,
            fragment: with_integral(&CELLPROJ_VOLUME_PROJECTED_FRAG),
        },
    ]
}

/// The transfer function as a float texture of its control points (see [`tf_texels`]).
pub(super) fn tf_texture(gpu: &Gpu, transfer: &Transfer) -> GlResult<Texture> {
    Texture::new(
        gpu,
        "cellproj volume transfer function",
        Extent::D2(transfer.s.len() as u32, 2),
        TexelFormat::Rgba32f,
        Filter::Nearest,
        TexelData::F32(&tf_texels(transfer)),
    )
}

/// The transfer function as `count x 2` RGBA32F texels (row 0 colour and opacity value,
/// row 1 positions).
fn tf_texels(tf: &Transfer) -> Vec<f32> {
    let mut v: Vec<f32> = tf.rgba.iter().flat_map(|c| c.map(|x| x as f32)).collect();
    v.extend(tf.s.iter().flat_map(|&s| [s as f32, 0.0, 0.0, 0.0]));
    v
}

/// Texels per row of the precise mode's mesh textures (`ROW` in `volume_walk.frag`).
pub const ROW: usize = 4096;

/// The neighbour walk's programs, mesh textures and targets.
pub(super) struct Precise {
    peel: Program,
    walk: Program,
    boundary: Mesh,
    quad: Mesh,
    tets: Texture,
    neighbours: Texture,
    /// Per tetrahedron (first, count) into `reentry` ([`reentry_candidates`]).
    reentry_offsets: Texture,
    reentry: Texture,
    pub(super) tf: Texture,
    isos: Texture,
    iso_count: usize,
    /// Up to [`BATCH`] entry layers.
    layers: Vec<Target>,
    /// The sums of earlier batches (ping-pong), made when a view needs them.
    sums: Vec<Target>,
    /// The most entries followed (the scene's `entries`; `None`: every one).
    pub(super) cap: Option<usize>,
    /// Entry layers the last frame peeled.
    pub(super) peeled: usize,
    /// Whether the mesh's boundary is convex (one entry per ray).
    convex: bool,
}

/// Entry layers one walk pass reads (texture units 4..11 of `volume_walk.frag`).
const BATCH: usize = 8;

/// The most entry layers the precise walk peels: the scene's cap, one for a convex
/// boundary (a ray enters it once), else every entry the view has (`None`).
pub(super) fn entry_cap(spec: &VolumeSpec, convex: bool) -> Option<usize> {
    match spec.entries {
        0 if convex => Some(1),
        0 => None,
        e => Some(e as usize),
    }
}

/// Most re-entry candidates kept per tetrahedron (the walk tests each).
const MAX_REENTRY: usize = 64;

/// Where a ray that leaves the mesh may enter it again at once: for each tetrahedron
/// with a boundary face, the other tetrahedra with a boundary face that share a vertex
/// with one of its boundary faces (at most [`MAX_REENTRY`], nearest first by index
/// distance kept as found). A ray grazing the boundary past an edge leaves through one
/// and re-enters through another within a hair, and the rasterized entry layers can
/// miss that re-entry (the entry face covers a sliver of the pixel); the walk tests these
/// instead. Returns (first, count) per tetrahedron and the list.
fn reentry_candidates(prepared: &Prepared, neighbours: &[[u32; 4]]) -> (Vec<u32>, Vec<u32>) {
    let n = neighbours.len();
    // Boundary tetrahedra around each vertex of a boundary face.
    let mut around: std::collections::HashMap<u32, Vec<u32>> = Default::default();
    let boundary_vertices = |t: usize| {
        let row = neighbours[t];
        let mut v: Vec<u32> = (0..4)
            .filter(|&k| row[k] == BOUNDARY)
            .flat_map(|k| FACES[k].0.map(|i| prepared.tets[t][i]))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    for t in 0..n {
        for v in boundary_vertices(t) {
            around.entry(v).or_default().push(t as u32);
        }
    }
    let mut offsets = vec![0u32; 2 * n];
    let mut list = Vec::new();
    for t in 0..n {
        let mut found: Vec<u32> = boundary_vertices(t)
            .iter()
            .flat_map(|v| around[v].iter().copied())
            .filter(|&c| c as usize != t)
            .collect();
        found.sort_unstable();
        found.dedup();
        found.truncate(MAX_REENTRY);
        offsets[2 * t] = list.len() as u32;
        offsets[2 * t + 1] = found.len() as u32;
        list.extend(found);
    }
    (offsets, list)
}

fn rows_texture(
    gpu: &Gpu,
    label: &str,
    format: TexelFormat,
    data: TexelData<'_>,
    texels: usize,
) -> RenderResult<Texture> {
    let rows = texture_rows(gpu, label, texels, ROW)?;
    let texture = Texture::empty_2d(gpu, label, ROW as u32, rows as u32, format)?;
    texture.update_texels(gpu, data)?;
    Ok(texture)
}

impl Precise {
    /// The walk's programs and `prepared`'s mesh in textures.
    pub(super) fn new(
        gpu: &Gpu,
        prepared: &Prepared,
        adjacent: &[[u32; 4]],
        spec: &VolumeSpec,
        transfer: &Transfer,
        convex: bool,
        isovalues: &[Isovalue],
    ) -> RenderResult<Precise> {
        let [peel, walk, _] = precise_pairs();
        let peel = Program::new(gpu, peel.kind, &peel.vertex, &peel.fragment)?;
        let walk = Program::new(gpu, walk.kind, &walk.vertex, &walk.fragment)?;
        walk.set_transform(gpu, glam::DMat4::IDENTITY)?;
        let n = prepared.tets.len();
        let data: Vec<f32> = (0..n)
            .into_par_iter()
            .flat_map_iter(|t| {
                let (p, s) = prepared.tet(t);
                let mut v = Vec::with_capacity(20);
                for (f, _) in FACES {
                    let nrm = normal(p[f[0]], p[f[1]], p[f[2]]);
                    v.extend([nrm.x, nrm.y, nrm.z, nrm.dot(p[f[0]])]);
                }
                let g = gradient(p, s);
                v.extend([g.x, g.y, g.z, s[0] - g.dot(p[0])]);
                v.into_iter().map(|x| x as f32)
            })
            .collect();
        let tets = rows_texture(
            gpu,
            "cellproj volume tetrahedra (4 planes, scalar)",
            TexelFormat::Rgba32f,
            TexelData::F32(&data),
            n * 5,
        )?;
        let nb: Vec<u32> = adjacent.iter().flatten().copied().collect();
        let neighbours = rows_texture(
            gpu,
            "cellproj volume neighbours",
            TexelFormat::Rgba32ui,
            TexelData::U32(&nb),
            n,
        )?;
        let (offsets, list) = reentry_candidates(prepared, adjacent);
        let reentry_offsets = rows_texture(
            gpu,
            "cellproj volume re-entry candidates (first, count) per tetrahedron",
            TexelFormat::Rg32ui,
            TexelData::U32(&offsets),
            n,
        )?;
        let reentry = rows_texture(
            gpu,
            "cellproj volume re-entry candidates",
            TexelFormat::R32ui,
            TexelData::U32(&list),
            list.len(),
        )?;
        let tf = tf_texture(gpu, transfer)?;
        let iso_count = isovalues.len();
        let mut list = super::super::prepare::iso_list(isovalues);
        list.resize(iso_count.max(1) * 8, 0.0);
        let isos = Texture::new(
            gpu,
            "cellproj volume isovalues",
            Extent::D2(iso_count.max(1) as u32, 2),
            TexelFormat::Rgba32f,
            Filter::Nearest,
            TexelData::F32(&list),
        )?;
        let mut boundary = Vec::new();
        for (t, row) in adjacent.iter().enumerate() {
            let (p, _) = prepared.tet(t);
            for (k, &m) in row.iter().enumerate() {
                if m == BOUNDARY {
                    // The face's plane as the tetrahedra texture holds it, so the entry
                    // layers intersect the pixel's ray with it exactly.
                    let f = FACES[k].0;
                    let nrm = normal(p[f[0]], p[f[1]], p[f[2]]);
                    let plane = [nrm.x, nrm.y, nrm.z, nrm.dot(p[f[0]])].map(|v| v as f32);
                    for &c in &f {
                        boundary.extend([p[c].x as f32, p[c].y as f32, p[c].z as f32, t as f32]);
                        boundary.extend(plane);
                    }
                }
            }
        }
        let boundary = Mesh::new(gpu, "cellproj volume boundary faces", &[3, 1, 4], &boundary)?;
        // The walk reads gl_FragCoord, not the quad's texture coordinates.
        let quad = crate::techniques::quad::quad_mesh(gpu, "cellproj volume full-screen quad")?;
        let cap = entry_cap(spec, convex);
        Ok(Precise {
            peel,
            walk,
            boundary,
            quad,
            tets,
            neighbours,
            reentry_offsets,
            reentry,
            tf,
            isos,
            iso_count,
            layers: Vec::new(),
            sums: Vec::new(),
            cap,
            peeled: 0,
            convex,
        })
    }

    /// Peel up to a pool of entry layers, at most `most` in all; returns how many. Layer 0
    /// of a later batch reads the previous batch's last (the pool's last), which it
    /// overwrites only at its own end.
    fn peel_batch(&mut self, gpu: &Gpu, most: usize) -> RenderResult<usize> {
        let p = self;
        let mut n = 0;
        while n < p.layers.len() && p.peeled < most {
            let k = n;
            p.layers[k].clear(gpu, [-1.0, -1.0, 0.0, 0.0])?;
            let after = p.peeled > 0;
            p.peel.set_local(
                gpu,
                locals::PEEL_AFTER_FIRST,
                [after as u8 as f64, 0.0, 0.0, 0.0],
            )?;
            let previous = if k > 0 { k - 1 } else { p.layers.len() - 1 };
            let textures: Vec<(u32, &Texture)> = if after {
                vec![(3, p.layers[previous].color())]
            } else {
                Vec::new()
            };
            let call = DrawCall {
                textures: &textures,
                depth_test: true,
                cull_back: true,
                ..DrawCall::new(&p.peel, &p.boundary)
            };
            // Without a cap the layers go on until one is empty; with one (a convex
            // boundary's single layer), no count is needed.
            let target = Surface::Target(&p.layers[k]);
            if p.cap.is_none() {
                if arbvis_gl::draw_counted(gpu, target, &call)? == 0 {
                    break;
                }
            } else {
                arbvis_gl::draw(gpu, target, &call)?;
            }
            n += 1;
            p.peeled += 1;
        }
        Ok(n)
    }

    /// Peel the entry layers of `frame`'s view and walk every pixel's ray.
    pub(super) fn draw(
        &mut self,
        gpu: &Gpu,
        surface: Surface<'_>,
        frame: &Frame,
        prepared: &Prepared,
        spec: &VolumeSpec,
        transfer: &Transfer,
    ) -> RenderResult<()> {
        let (w, h) = (frame.width, frame.height);
        let convex = self.convex;
        let p = self;
        let pool = p.cap.map_or(BATCH, |c| c.min(BATCH));
        let sized = |t: &[Target]| t.first().is_some_and(|l| l.width() == w && l.height() == h);
        if !sized(&p.layers) || p.layers.len() != pool {
            p.layers.clear();
            p.sums.clear();
            for _ in 0..pool {
                p.layers
                    .push(Target::with_depth(gpu, w, h, TargetFormat::Rgba32f)?);
            }
        }
        let mvp = frame.camera.view_projection(frame.aspect());
        let inv = mvp.inverse().transpose();
        let rows = [inv.x_axis, inv.y_axis, inv.z_axis, inv.w_axis].map(|r| r.to_array());
        p.peel.set_transform(gpu, mvp)?;
        for (i, row) in rows.iter().enumerate() {
            p.peel.set_local(gpu, locals::MVP_ROWS + i, *row)?;
            p.walk.set_local(gpu, locals::MVP_ROWS + i, *row)?;
        }
        p.peel
            .set_local(gpu, locals::PIXELS, [w as f64, h as f64, 0.0, 0.0])?;
        let corner = match surface {
            Surface::Target(_) => [0.0, 0.0],
            Surface::Window([x, y, _, _]) => [x as f64, y as f64],
        };
        let eye_tet = match frame.camera.projection {
            Projection::Perspective => {
                locate(prepared, eye_and_direction(frame).0).map_or(-1.0, |t| t as f64)
            }
            Projection::Orthographic => -1.0,
        };
        let s = spec;
        let walk_transfer = [transfer.s.len() as f64, p.iso_count as f64, s.termination];
        let inv_unit = 1.0 / transfer.unit;
        // Every boundary face at most once per ray: no more layers than that.
        let most = p
            .cap
            .unwrap_or(usize::MAX)
            .min(p.boundary.draw_count() / 3 + 1);
        p.peeled = 0;
        let mut batch = 0;
        loop {
            let n = p.peel_batch(gpu, most)?;
            // The last batch: fewer than a full pool, or at the cap.
            let last = n < p.layers.len() || p.peeled >= most;
            if !last && p.sums.is_empty() {
                // (C, 1 - T), and how far each pixel's walk reached (output 1).
                for _ in 0..2 {
                    p.sums
                        .push(Target::with_second_color(gpu, w, h, TargetFormat::Rgba32f)?);
                }
            }
            let (sum_in, sum_out) = (batch % 2, (batch + 1) % 2);
            let eye = if batch == 0 { eye_tet } else { -1.0 };
            // The surface's corner for the last pass; the sums are targets of their own.
            let at = if last { corner } else { [0.0, 0.0] };
            p.walk
                .set_local(gpu, locals::PIXELS, [w as f64, h as f64, at[0], at[1]])?;
            p.walk.set_local(
                gpu,
                locals::WALK_TRANSFER,
                [walk_transfer[0], walk_transfer[1], walk_transfer[2], eye],
            )?;
            p.walk.set_local(
                gpu,
                locals::WALK_PASS,
                [
                    n as f64,
                    inv_unit,
                    prepared.tets.len() as f64 + 16.0,
                    (batch > 0) as u8 as f64,
                ],
            )?;
            // Re-entries exist only where the boundary is not one convex body; what a
            // pass's walks reached goes to the next, so every pass looks for them.
            let search = !convex;
            p.walk.set_local(
                gpu,
                locals::WALK_SEARCH,
                [search as u8 as f64, 0.0, 0.0, 0.0],
            )?;
            let mut textures: Vec<(u32, &Texture)> = vec![
                (0, &p.tets),
                (1, &p.neighbours),
                (2, &p.tf),
                (3, &p.isos),
                (13, &p.reentry_offsets),
                (14, &p.reentry),
            ];
            for (k, l) in p.layers[..n].iter().enumerate() {
                textures.push((4 + k as u32, l.color()));
            }
            if batch > 0 {
                textures.push((12, p.sums[sum_in].color()));
                if let Some(reached) = p.sums[sum_in].second_color() {
                    textures.push((15, reached));
                }
            }
            if last {
                return Ok(arbvis_gl::draw(
                    gpu,
                    surface,
                    &DrawCall {
                        textures: &textures,
                        blend: Blend::PremultipliedOver,
                        covers_frame: true,
                        ..DrawCall::new(&p.walk, &p.quad)
                    },
                )?);
            }
            p.sums[sum_out].clear(gpu, [0.0; 4])?;
            arbvis_gl::draw(
                gpu,
                Surface::Target(&p.sums[sum_out]),
                &DrawCall {
                    textures: &textures,
                    ..DrawCall::new(&p.walk, &p.quad)
                },
            )?;
            batch += 1;
        }
    }
}

/// The tetrahedron holding `point` (barycentric test with a 1e-12 tolerance), if any.
pub fn locate(prepared: &Prepared, point: DVec3) -> Option<usize> {
    let (lo, hi) = (-prepared.half - 1e-9, prepared.half + 1e-9);
    if point.cmplt(lo).any() || point.cmpgt(hi).any() {
        return None;
    }
    (0..prepared.tets.len()).into_par_iter().find_first(|&t| {
        let (p, _) = prepared.tet(t);
        FACES.iter().all(|(f, _)| {
            let n = normal(p[f[0]], p[f[1]], p[f[2]]);
            n != DVec3::ZERO && n.dot(point - p[f[0]]) <= 1e-12
        })
    })
}
