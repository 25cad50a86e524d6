//! A surface's GL state: one program pair (per-vertex lighting faithful, per-pixel
//! precise) and its corners, drawn with a depth test and depth writes.

use std::path::PathBuf;

use glam::DVec3;

use super::prepare::Prepared;
use super::{ColourBy, SurfaceScene};
use crate::error::RenderResult;
use crate::programs::{self, ProgramPair};
use crate::techniques::{Frame, Params, Renderer};
use arbvis_core::vocab::Fidelity;
use arbvis_gl::{DrawCall, Gpu, Mesh, Program, ProgramKind, Surface};

/// The program pair of `fidelity` and `kind`: faithful lights each vertex, precise each
/// pixel.
pub fn pair(fidelity: Fidelity, kind: ProgramKind) -> ProgramPair {
    use programs::*;
    let (vertex, fragment) = match (fidelity, kind) {
        (Fidelity::Faithful, ProgramKind::Arb) => (SURFACE_GOURAUD_ARBVP, SURFACE_GOURAUD_ARBFP),
        (Fidelity::Faithful, ProgramKind::Glsl) => (SURFACE_GOURAUD_VERT, SURFACE_GOURAUD_FRAG),
        (Fidelity::Precise, ProgramKind::Arb) => (SURFACE_PHONG_ARBVP, SURFACE_PHONG_ARBFP),
        (Fidelity::Precise, ProgramKind::Glsl) => (SURFACE_PHONG_VERT, SURFACE_PHONG_FRAG),
    };
    ProgramPair {
        kind,
        vertex,
        fragment,
    }
}

/// Every pair a surface draws with.
pub fn program_pairs() -> Vec<ProgramPair> {
    programs::each_fidelity_and_kind(pair)
}

/// The corners as the mesh's floats: position (x y z 1), normal (x y z 0), colour
/// (r g b 1).
pub fn vertex_floats(prepared: &Prepared) -> Vec<f32> {
    prepared
        .corners
        .iter()
        .flat_map(|c| {
            let (p, n, k) = (c.position, c.normal, c.colour);
            [p.x, p.y, p.z, 1.0, n.x, n.y, n.z, 0.0, k.x, k.y, k.z, 1.0].map(|v| v as f32)
        })
        .collect()
}

/// A surface's GL state.
pub struct SurfaceRenderer {
    program: Program,
    mesh: Mesh,
    fidelity: Fidelity,
    params: SurfaceScene,
    /// The folder its file is read from (a new file is read on update).
    base: PathBuf,
    /// The corners as prepared (a translucent surface's triangles are sorted from them).
    prepared: Prepared,
    /// The view the uploaded triangles are sorted for (translucent surfaces).
    sorted_for: Option<[f64; 4]>,
}

/// Triangle indices farthest first along the view: by each centroid's distance to
/// `eye` (perspective) or its depth along `toward` (orthographic, `eye` None).
pub fn back_to_front(prepared: &Prepared, toward: DVec3, eye: Option<DVec3>) -> Vec<usize> {
    let depth: Vec<f64> = prepared
        .corners
        .chunks_exact(3)
        .map(|c| {
            let centroid = (c[0].position + c[1].position + c[2].position) / 3.0;
            match eye {
                Some(e) => -(centroid - e).length(),
                None => centroid.dot(toward),
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..depth.len()).collect();
    order.sort_by(|&a, &b| depth[a].total_cmp(&depth[b]));
    order
}

impl SurfaceRenderer {
    /// Compile the pair of `fidelity` and `kind`, upload `prepared`.
    pub fn new(
        gpu: &Gpu,
        kind: ProgramKind,
        fidelity: Fidelity,
        params: &SurfaceScene,
        prepared: Prepared,
    ) -> RenderResult<SurfaceRenderer> {
        let pair = pair(fidelity, kind);
        let program = Program::new(gpu, kind, &pair.vertex, &pair.fragment)?;
        let mesh = Mesh::new(gpu, "surface", &[4, 4, 4], &vertex_floats(&prepared))?;
        Ok(SurfaceRenderer {
            program,
            mesh,
            fidelity,
            params: params.clone(),
            base: PathBuf::new(),
            prepared,
            sorted_for: None,
        })
    }

    /// The corners drawn (their colours' legend in `elevation`).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// Draw `prepared` from now on (a shape made again for a new view): its corners
    /// uploaded into the same buffer.
    pub fn replace(&mut self, gpu: &Gpu, prepared: Prepared) -> RenderResult<()> {
        self.mesh.update(gpu, &vertex_floats(&prepared))?;
        self.prepared = prepared;
        self.sorted_for = None;
        Ok(())
    }

    /// Read files named relative to `base` when parameters change.
    pub fn with_base(mut self, base: &std::path::Path) -> SurfaceRenderer {
        self.base = base.to_path_buf();
        self
    }
}

impl SurfaceRenderer {
    /// Upload the triangles sorted back to front for `camera`'s view, unless they are.
    fn sort_for(&mut self, gpu: &Gpu, camera: &arbvis_core::camera::Camera) -> RenderResult<()> {
        let perspective = camera.projection == arbvis_core::camera::Projection::Perspective;
        let (toward, eye) = (camera.toward_viewer(), perspective.then(|| camera.eye()));
        let key = match eye {
            Some(e) => [e.x, e.y, e.z, 1.0],
            None => [toward.x, toward.y, toward.z, 0.0],
        };
        if self.sorted_for == Some(key) {
            return Ok(());
        }
        let order = back_to_front(&self.prepared, toward, eye);
        let corners = &self.prepared.corners;
        let sorted = Prepared {
            corners: order
                .iter()
                .flat_map(|&t| corners[t * 3..t * 3 + 3].iter().copied())
                .collect(),
            world: self.prepared.world,
            elevation: self.prepared.elevation.clone(),
        };
        self.mesh.update(gpu, &vertex_floats(&sorted))?;
        self.sorted_for = Some(key);
        Ok(())
    }
}

impl Renderer for SurfaceRenderer {
    fn draw(&mut self, gpu: &Gpu, surface: Surface<'_>, frame: &Frame) -> RenderResult<()> {
        let camera = &frame.camera;
        self.program
            .set_transform(gpu, camera.view_projection(frame.aspect()))?;
        let light = camera.toward_viewer().normalize().extend(0.0).to_array();
        let terms = self.params.light_terms();
        match self.fidelity {
            Fidelity::Faithful => {
                self.program.set_vertex_local(gpu, 4, light)?;
                self.program.set_vertex_local(gpu, 5, terms)?;
            }
            Fidelity::Precise => {
                self.program.set_local(gpu, 0, light)?;
                self.program.set_local(gpu, 1, terms)?;
            }
        }
        let translucent = self.params.opacity < 1.0;
        if translucent {
            self.sort_for(gpu, camera)?;
        }
        // Opaque: the depth test keeps the nearest sheet. Translucent: every sheet blended
        // back to front (sorted above).
        let call = DrawCall::new(&self.program, &self.mesh).sheet(translucent);
        Ok(arbvis_gl::draw(gpu, surface, &call)?)
    }

    /// New colours, table, lighting or opacity; a new file is read and uploaded.
    fn update(&mut self, gpu: &Gpu, params: Params<'_>) -> RenderResult<()> {
        let params = params.get::<SurfaceScene>()?;
        let recoloured = params.file != self.params.file
            || params.synthetic != self.params.synthetic
            || params.z_down != self.params.z_down
            || params.colour != self.params.colour
            || params.colour_by != self.params.colour_by
            || params.range != self.params.range
            || params.table != self.params.table;
        if recoloured {
            let prepared = super::prepare::prepare(params, &self.base)?;
            self.mesh = Mesh::new(gpu, "surface", &[4, 4, 4], &vertex_floats(&prepared))?;
            self.prepared = prepared;
            self.sorted_for = None;
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

    /// The elevation table over the surface's z range, or its colour as a key.
    fn annotations(&self) -> crate::techniques::annotations::Annotations {
        use crate::techniques::annotations::{rgb8, Annotations, Legend};
        // Coloured by another layer: that layer's legend says what the colours mean.
        if self.params.colour_from.is_some() {
            return Annotations::default();
        }
        let legend = match &self.prepared.elevation {
            ([low, high], Some(colours)) => Legend::Bar {
                title: self
                    .params
                    .colour_by
                    .as_ref()
                    .map_or_else(|| "elevation (z)".into(), ColourBy::title),
                colours: colours.clone(),
                low: *low,
                high: *high,
            },
            (_, None) => {
                let [r, g, b] = self.params.colour;
                Legend::Keys {
                    title: "surface".into(),
                    keys: vec![(
                        rgb8([r, g, b, 1.0]),
                        match self.params.opacity {
                            o if o < 1.0 => format!("opacity {o}"),
                            _ => "opaque".into(),
                        },
                    )],
                }
            }
        };
        Annotations {
            legends: vec![legend],
            axes: None,
        }
    }

    fn opaque(&self) -> bool {
        self.params.opacity >= 1.0
    }
}
