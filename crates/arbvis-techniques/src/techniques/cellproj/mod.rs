//! Isosurfaces of tetrahedral meshes by view-independent cell projection (seed
//! `001_633e9ef4ec0dfd02.txt`, after Weiler, Kraus and Ertl, "Hardware-Based
//! View-Independent Cell Projection", IEEE VolVis 2002), as the 2004 PUC-Rio talk drew
//! them: the front faces of every tetrahedron are rasterized; each fragment knows the
//! scalar where its ray enters the tetrahedron (`sf`, interpolated by the rasterizer),
//! finds where the ray leaves it (the smallest positive `t` among the other three face
//! planes), extrapolates the scalar there with the tetrahedron's constant gradient
//! (`sb = sf + t G·D`), and looks up the isosurface colour in a 2D table indexed by
//! `(sf, sb)`: the colour of the first isovalue crossed between the two.
//!
//! # How it works
//! 1. [`prepare`] (CPU, no GL): the mesh (generated or read by [`arbvis_data::mesh`]) is
//!    moved into the object box (centred, longest side [-1, 1], in f64 before anything
//!    becomes f32, so coordinates far from the origin keep their precision); each
//!    tetrahedron gives four faces of three vertices with what the seed's vertex program
//!    takes: position, scalar, the vertex opposite the face, the normals of the other
//!    three faces and the gradient. Flat and sliver tetrahedra are counted.
//!    [`prepare::iso_table`] builds the `(sf, sb)` table from the isovalues.
//! 2. [`renderer`] draws every face once with back-face culling (what makes the method
//!    view independent: no sorting) and a depth test, and discards fragments whose
//!    table entry is empty. By default only *active* tetrahedra are drawn, those whose
//!    scalar range `[min, max]` over their corners holds an isovalue: a crossing
//!    `sf → sb` lies inside that range, so the others could only be discarded. The
//!    faces stay uploaded once; an index buffer lists the active ones, rebuilt (a scan
//!    of the per-tetrahedron ranges) when the isovalues change. In faithful mode this
//!    also drops the table's false crossings in inactive tetrahedra (texel centres are
//!    up to 1/512 off the exact `sf`, `sb`); `active_only = false` draws every face as
//!    the seed did.
//! 3. [`reference`] ray-casts the same mesh in f64 (a bounding-volume hierarchy over the
//!    tetrahedra) and finds the exact first isovalue crossing along each pixel's ray.
//!
//! # Programs (`programs/cellproj/`)
//! - `seed_vertex.cg`, `seed_fragment.cg`: the talk's Cg text, kept as reference.
//! - `perspective.*`: the seed's programs ported to ARB and GLSL as the Cg compiler's
//!   `arbvp1`/`arbfp1` profiles would compile them: the exit parameters per fragment,
//!   the ray direction `vertex - EyePos` un-normalized, `t` starting at 10000.
//! - `orthographic.*`: the seed's orthographic case: the view direction is constant, so
//!   each `t_i` is computed per vertex and interpolated (exact: `t_i` is affine on a face).
//! - `precise.*` (GLSL only: it loops over the isovalues, and ARB fragment programs have
//!   no loops; precise mode draws with GLSL whatever program kind the scene asks for, and
//!   says so in the picture's `arbvis:programs`): normalized direction, guarded divisions (grazing rays, degenerate faces),
//!   the exact crossing `t_iso = t (iso - sf) / (sb - sf)` against each isovalue (no
//!   table quantization), depth written at the crossing, optional shading.
//!
//! # Decisions the seed leaves open
//! - The table: `table_size`² RGBA8 (default 256²), texel `(i, j)` for `sf = (i+½)/N`,
//!   `sb = (j+½)/N`, read with NEAREST (a LINEAR read would blend colours across an
//!   isovalue). Its alpha is 0 where nothing is crossed; the ported fragment programs
//!   `KIL` there, standing in for the alpha test the talk's pipeline leaves unstated.
//! - "Crossed between sf and sb": an isovalue `v` is crossed when it lies in `(sf, sb]`
//!   (rising) or `[sb, sf)` (falling). The interval is open at the entry, so a crossing
//!   exactly on a shared face belongs to exactly one of the two tetrahedra.
//! - **Isosurfaces on shared faces are partly lost in faithful mode** (kept: it is the
//!   seed's table at work). The table applies that rule at texel centres, so for an
//!   isovalue `v` lying on a face two tetrahedra share (an isovalue equal to the vertex
//!   values of a grid plane of a planar field, say), the one behind the face draws it
//!   only if its extrapolated exit scalar `sb` reads the texel above `v`, the one in
//!   front only if its rasterized entry scalar `sf` reads the texel below; where the f32
//!   rounding of the two sends `sb` down and `sf` up, neither does and the ray sees
//!   through the surface. On the 17³ planar grid with `v = 0.5` this loses a large share
//!   of the surface's pixels in some views and almost none in others, how much being the
//!   driver's rounding; an isovalue nearer the face than half a texel (0.5 + 1e-3)
//!   loses as much, one a texel or more away (0.5 + 1e-2) only the table's usual
//!   quantization (`tests/it/cellproj.rs`,
//!   `faithful_loses_isosurfaces_on_shared_faces_as_the_seeds_table_does`, which bounds
//!   both loosely; measured: docs/benchmarks.md, "Figures behind cell projection's
//!   settings"). Precise mode crosses exactly and draws such surfaces whole (the test
//!   allows a loss under 2e-3 of the pixels).
//! - The exit direction of the orthographic variant is the view direction; the seed's Cg
//!   (`vertex - EyePos`) is the perspective variant. Used in an orthographic view, the
//!   per-fragment programs get an eye 10^6 box units back along the view direction, so
//!   `vertex - EyePos` is the parallel ray to within 10^-6 radians.
//! - Shading (precise only; the seed drew unlit colours): Lambert with a headlight and
//!   an ambient term, the normal being the gradient turned toward the viewer.
//!
//! # Extremes (DESIGN §4), each with a test
//! Grazing rays (`dot(D, n) → 0`: faithful divides as the seed did, precise skips the
//! plane); flat tetrahedra (zero gradient: `sf = sb`, nothing crossed) and slivers;
//! `sf = sb`; isovalues exactly at vertex values (the half-open rule); coordinates far
//! from the origin (re-centred in f64); a one-tetrahedron mesh; isovalues outside the
//! data range (nothing drawn).

pub mod indices;
pub mod locals;
pub mod order;
pub mod preint;
pub mod prepare;
pub mod reference;
pub mod renderer;
pub mod study;
pub mod transfer;
pub mod volume;
pub mod volume_reference;

use serde::{Deserialize, Serialize};

use arbvis_core::camera::Projection;
use arbvis_core::vocab::{significant, Fidelity, FieldError};
use arbvis_data::mesh::scalars::ScalarSpec;
use arbvis_data::mesh::MeshSource;
use arbvis_gl::ProgramChoice;

pub use renderer::CellprojRenderer;

/// One isosurface: the scalar value and its colour.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Isovalue {
    /// The value in the scalar's own units, or normalized to [0, 1] over its range (as the
    /// seed wrote them) where the scene says `isovalue_units = "normalized"`.
    pub value: f64,
    /// RGBA colour, each in [0, 1].
    pub color: [f64; 4],
}

/// The units of a scene's isovalues.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IsovalueUnits {
    /// The scalar's own units: `value = 1.5` is where the scalar is 1.5.
    #[default]
    Data,
    /// Normalized over the scalar's range (`scalars.range`, else its minimum and
    /// maximum): 0 is the low end, 1 the high end, as the seed wrote them.
    Normalized,
}

impl IsovalueUnits {
    fn is_data(&self) -> bool {
        *self == IsovalueUnits::Data
    }
}

/// Where the exit point is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Exit {
    /// Per vertex for orthographic cameras, per fragment for perspective ones.
    #[default]
    Auto,
    /// Per vertex, interpolated (orthographic only: the direction must be constant).
    Vertex,
    /// Per fragment.
    Fragment,
}

impl Exit {
    /// Whether the exit is computed per vertex for `projection`; per vertex in perspective
    /// is an error (the seed's own caveat).
    pub fn per_vertex(self, projection: Projection) -> Result<bool, FieldError> {
        match (self, projection) {
            (Exit::Fragment, _) | (Exit::Auto, Projection::Perspective) => Ok(false),
            (Exit::Auto | Exit::Vertex, Projection::Orthographic) => Ok(true),
            (Exit::Vertex, Projection::Perspective) => Err(FieldError::new(
                "exit",
                "\"vertex\" needs an orthographic camera: in perspective the ray direction varies over a face, so the exit parameters are not affine (the seed computes them per fragment there)",
            )),
        }
    }
}

/// The order the faces are drawn in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// The mesh's order, uploaded once, the same for every view (the seed's
    /// view-independent draw; isovalue edits rewrite an index list).
    #[default]
    Mesh,
    /// Per view: the active tetrahedra front to back (by centroid), only their faces
    /// that can face the viewer, copied into one vertex buffer. The depth test then
    /// rejects hidden fragments before their program runs, and half the vertices are
    /// never processed; the picture is the same, but every change of view rebuilds the
    /// buffer (a sort and a copy on the CPU).
    View,
}

/// What the precise programs write to the depth buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Depth {
    /// The depth of the isovalue crossing (exact; the program writes `gl_FragDepth`,
    /// which makes the rasterizer test depth after the program, for every fragment).
    #[default]
    Crossing,
    /// The depth of the entry face, as rasterized. The colours are the same: in a mesh of
    /// non-overlapping tetrahedra a ray meets them one after another, so the nearest
    /// entry holds the nearest crossing. The depth test can then run before the program.
    Entry,
}

/// What a cell-projection scene draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// The isosurfaces (the seed's picture).
    #[default]
    Isosurfaces,
    /// Volume rendering with `[technique.cellproj.volume]`'s transfer function.
    Volume,
    /// Opaque isosurfaces inside the translucent volume.
    Both,
}

impl Mode {
    /// Whether isosurfaces are drawn.
    pub fn isosurfaces(self) -> bool {
        self != Mode::Volume
    }

    /// Whether the volume is drawn.
    pub fn volume(self) -> bool {
        self != Mode::Isosurfaces
    }
}

/// `[technique.cellproj]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellprojScene {
    /// The mesh.
    pub mesh: MeshSource,
    /// Which point scalar (default: the first point array).
    #[serde(default)]
    pub scalars: ScalarSpec,
    /// Isosurfaces, volume or both.
    #[serde(default)]
    pub mode: Mode,
    /// The isosurfaces, any order.
    #[serde(default)]
    pub isovalues: Vec<Isovalue>,
    /// The units of `isovalues`: the scalar's own (the default) or normalized.
    #[serde(default, skip_serializing_if = "IsovalueUnits::is_data")]
    pub isovalue_units: IsovalueUnits,
    /// The volume's transfer function and settings (`mode = "volume"` or `"both"`;
    /// defaults when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<transfer::VolumeSpec>,
    /// Where the exit point is computed.
    #[serde(default)]
    pub exit: Exit,
    /// Side of the `(sf, sb)` table of the faithful programs.
    #[serde(default = "default_table_size")]
    pub table_size: u32,
    /// Shade with the gradient as the normal (precise only).
    #[serde(default)]
    pub shading: bool,
    /// Draw only the tetrahedra that can add to the picture: for the isosurfaces those
    /// whose scalar range holds an isovalue (the others can cross nothing), for the
    /// volume those whose range the transfer function does not map to zero attenuation
    /// throughout ([`volume::contributing`]); `false` draws every face, as the seed did.
    #[serde(default = "yes")]
    pub active_only: bool,
    /// Face order: the mesh's (view independent) or front to back per view.
    #[serde(default)]
    pub order: Order,
    /// Depth written by the precise programs.
    #[serde(default)]
    pub depth: Depth,
    /// Precise isosurfaces: whether each fragment's entry is the interpolated position
    /// (`hardware`) or where the pixel's own ray meets the face (`shader`; `auto`: where
    /// the rasterizer interpolates from snapped vertices).
    #[serde(default)]
    pub interpolation: arbvis_core::vocab::Interpolation,
}

impl crate::techniques::Technique for CellprojScene {
    const NAME: &'static str = "cellproj";
    const STUDIES: &'static [(&'static str, &'static str)] = &[
        (
            "cellproj",
            "cell projection: mesh sizes, exit per vertex / per fragment, faithful / precise, mesh / view order, isovalue-edit latency",
        ),
        (
            "cellproj-volume",
            "cell projection's volume: faithful (both sorts, table sizes) and precise, still and turning, ortho and perspective, against the f64 reference, on the --grids meshes and any --scenes (e.g. scenes/data/bracket-volume.toml)",
        ),
    ];
    const DEMOS: &'static [(&'static str, &'static str)] = &[
        crate::techniques::demo!("cellproj-planar"),
        crate::techniques::demo!("cellproj-spherical"),
        crate::techniques::demo!("cellproj-spherical-precise"),
    ];

    fn validate(&self, _: Fidelity, _: ProgramChoice) -> Result<(), FieldError> {
        CellprojScene::validate(self)
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut std::path::PathBuf)) {
        if let Some(p) = self.mesh.path_mut() {
            f("mesh.file", p);
        }
    }

    fn memory_estimate(&self, _: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        CellprojScene::memory_estimate(self)
    }

    /// A volume's pre-integrated table a quarter (half quality) or an eighth (quarter)
    /// of each side: 64 to 512 times fewer integrals while a transfer-function drag
    /// rebuilds it every frame (the renderer remakes it only when it draws).
    fn for_interaction(&mut self, scale: f64) {
        if self.mode.volume() && scale >= 1.5 {
            let mut spec = self.volume_spec();
            let cut = |s: u32| ((s as f64 / (2.0 * scale.round())) as u32).max(8).min(s);
            spec.table_size = spec.table_size.map(cut);
            self.volume = Some(spec);
        }
    }

    fn program_pairs() -> Vec<crate::programs::ProgramPair> {
        renderer::program_pairs()
    }

    type Prepared = prepare::Prepared;

    /// The mesh's box in its file's coordinates (no units: mesh formats name none), its
    /// scalar, and the scalar's histogram over its range.
    fn summary(
        &self,
        mesh: &prepare::Prepared,
        _: &std::path::Path,
    ) -> Option<crate::summary::Summary> {
        use crate::summary::{data_box, histogram, MeshSummary, Summary};
        let [lo, hi] = mesh.bounds;
        let longest = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        let scale = if longest > 0.0 { 2.0 / longest } else { 1.0 };
        Some(Summary::Mesh(MeshSummary {
            data_box: data_box(lo, hi, scale, &Default::default()),
            scalar: mesh.scalar_name.clone(),
            range: mesh.scalar_range,
            histogram: histogram(&mesh.scalars, mesh.scalar_range),
        }))
    }

    fn draws_opaque(&self) -> bool {
        self.mode == Mode::Isosurfaces
    }

    /// The neighbour walk and the grid pass over the whole frame: the projected cells'
    /// exact integral per fragment instead (exact where the projection's order is).
    fn occludable(&mut self) {
        use transfer::Precise;
        if let Some(v) = self.volume.as_mut() {
            if matches!(v.precise, Precise::Walk | Precise::Grid) {
                v.precise = Precise::Projected;
            }
        }
    }

    /// The mesh in its file's coordinates.
    fn world(&self, mesh: &prepare::Prepared) -> Option<crate::techniques::world::World> {
        let [lo, hi] = mesh.bounds;
        Some(crate::techniques::world::World::of_box(lo, hi))
    }

    fn prepare(
        &self,
        settings: &crate::techniques::Settings<'_>,
        _: &arbvis_data::volume::Limits,
    ) -> crate::error::RenderResult<prepare::Prepared> {
        CellprojScene::validate(self)?;
        prepare::prepare(self, settings.base)
    }

    /// The f64 ray walk through the cells ([`volume_reference::reference`]) of a volume
    /// (or of both, with its opaque isosurfaces); none for isosurfaces alone, whose
    /// reference is per-pixel hits rather than a picture.
    fn reference(
        &self,
        prepared: &prepare::Prepared,
        view: &crate::techniques::ReferenceView<'_>,
    ) -> Option<arbvis_core::image::Image> {
        if self.mode == Mode::Isosurfaces {
            return None;
        }
        let tf = self.volume_spec().build(view.base, prepared.scale).ok()?;
        let isovalues = match self.mode {
            Mode::Both => self.isovalues.clone(),
            _ => Vec::new(),
        };
        Some(volume_reference::reference(
            prepared,
            &tf,
            &isovalues,
            &view.camera,
            view.size,
            view.background,
        ))
    }

    fn renderer(
        &self,
        gpu: &arbvis_gl::Gpu,
        settings: &crate::techniques::Settings<'_>,
        kind: arbvis_gl::ProgramKind,
        prepared: prepare::Prepared,
    ) -> crate::error::RenderResult<Box<dyn crate::techniques::Renderer>> {
        Ok(Box::new(CellprojRenderer::upload(
            gpu,
            kind,
            settings.fidelity,
            self,
            prepared,
            settings.base,
        )?))
    }
}

/// Memory per tetrahedron of a generated grid while it is prepared and drawn: the mesh, the
/// per-face vertex data and the renderer's copies; the growth of peak resident memory per
/// tetrahedron, faithful and precise alike, rounded up (measured: docs/benchmarks.md,
/// "Memory estimates and work limits").
pub const BYTES_PER_TET: u64 = 2000;

impl CellprojScene {
    /// The large allocations this scene makes that the scene alone determines (a generated
    /// grid, a mesh in memory); mesh files are held to the budget by their loaders once
    /// their headers are read.
    pub fn memory_estimate(&self) -> Vec<arbvis_core::budget::Estimate> {
        match &self.mesh {
            arbvis_data::mesh::MeshSource::Grid(g) => {
                let tets = g
                    .points
                    .iter()
                    .fold(6u64, |a, &n| a.saturating_mul(n.saturating_sub(1) as u64));
                vec![arbvis_core::budget::Estimate::of(
                    format!("the generated grid's {tets} tetrahedra"),
                    tets,
                    BYTES_PER_TET,
                )]
            }
            // A mesh in memory: its tetrahedra are known.
            arbvis_data::mesh::MeshSource::Memory(name) => arbvis_data::mesh::memory::MESHES
                .get(name)
                .map(|m| {
                    vec![arbvis_core::budget::Estimate::of(
                        format!("the {} tetrahedra of {name}", m.tets.len()),
                        m.tets.len() as u64,
                        BYTES_PER_TET,
                    )]
                })
                .unwrap_or_default(),
            arbvis_data::mesh::MeshSource::File(_) => Vec::new(),
        }
    }
}

fn yes() -> bool {
    true
}

fn default_table_size() -> u32 {
    256
}

/// Most isovalues: the precise programs loop over them; the faithful table can separate
/// at most one per texel row, so more than `table_size` would be lost anyway.
pub const MAX_ISOVALUES: usize = 256;

impl CellprojScene {
    /// Check values that parse but cannot render; the error names the key.
    pub fn validate(&self) -> Result<(), FieldError> {
        if self.isovalues.len() > MAX_ISOVALUES {
            return Err(FieldError::new(
                "isovalues",
                format!(
                    "{} isovalues: at most {MAX_ISOVALUES}",
                    self.isovalues.len()
                ),
            ));
        }
        for (i, iso) in self.isovalues.iter().enumerate() {
            if !iso.value.is_finite() {
                return Err(FieldError::new(
                    format!("isovalues.{i}.value"),
                    format!("{}: must be finite", iso.value),
                ));
            }
            if iso.color.iter().any(|c| !(0.0..=1.0).contains(c)) {
                return Err(FieldError::new(
                    format!("isovalues.{i}.color"),
                    format!("{:?}: each component in [0, 1]", iso.color),
                ));
            }
        }
        if let Some([lo, hi]) = self.scalars.range {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(FieldError::new(
                    "scalars.range",
                    format!("[{lo}, {hi}]: must be finite, the low end first"),
                ));
            }
        }
        if let Some(v) = &self.volume {
            v.validate().map_err(|e| e.within("volume"))?;
            if self.mode == Mode::Both && v.precise == transfer::Precise::Grid {
                return Err(FieldError::new(
                    "volume.precise",
                    "grid casts the volume alone (mode = \"volume\"); the walk and table \
                     draw it with isosurfaces",
                ));
            }
        }
        if !(2..=4096).contains(&self.table_size) {
            return Err(FieldError::new(
                "table_size",
                format!("{}: must be 2..=4096", self.table_size),
            ));
        }
        Ok(())
    }

    /// The volume settings (the defaults when the scene gives none).
    pub fn volume_spec(&self) -> transfer::VolumeSpec {
        self.volume.clone().unwrap_or_default()
    }

    /// The scene with its isovalues normalized over `range` (the prepared scalar range,
    /// [`prepare::Prepared::scalar_range`]): what the renderers and references draw.
    pub fn normalized(&self, range: [f64; 2]) -> CellprojScene {
        let mut scene = self.clone();
        if scene.isovalue_units == IsovalueUnits::Data {
            let [lo, hi] = range;
            let span = hi - lo;
            for iso in &mut scene.isovalues {
                // A constant scalar (no span): at the value 0, above it 1, below it -1,
                // so that only an isovalue equal to the constant lies in [0, 1].
                iso.value = if span > 0.0 {
                    (iso.value - lo) / span
                } else {
                    (iso.value - lo).signum()
                };
            }
            scene.isovalue_units = IsovalueUnits::Normalized;
        }
        scene
    }

    /// One line for each isovalue outside the scalar's `range` (it can draw nothing),
    /// naming its key, its value and the range in the scene's units.
    pub fn range_warnings(&self, range: [f64; 2]) -> Vec<String> {
        let normalized = self.normalized(range);
        let (shown, units) = match self.isovalue_units {
            IsovalueUnits::Data => (range, "the scalar's units"),
            IsovalueUnits::Normalized => ([0.0, 1.0], "normalized"),
        };
        self.isovalues
            .iter()
            .zip(&normalized.isovalues)
            .enumerate()
            .filter(|(_, (_, n))| !(0.0..=1.0).contains(&n.value))
            .map(|(i, (iso, _))| {
                format!(
                    "technique.cellproj.isovalues.{i}.value = {} lies outside the scalar's range {}..{} ({units}; isovalue_units = \"{}\"): it draws nothing",
                    iso.value,
                    significant(shown[0]),
                    significant(shown[1]),
                    match self.isovalue_units {
                        IsovalueUnits::Data => "data",
                        IsovalueUnits::Normalized => "normalized",
                    }
                )
            })
            .collect()
    }

    /// The isovalues sorted by value (ties keep their order).
    pub fn sorted_isovalues(&self) -> Vec<Isovalue> {
        let mut v = self.isovalues.clone();
        v.sort_by(|a, b| a.value.total_cmp(&b.value));
        v
    }
}

/// The first isovalue crossed going from `sf` toward `sb`: in `(sf, sb]` when rising,
/// `[sb, sf)` when falling, none when equal; the exit end widened by `slack` (an
/// isovalue on a shared face is computed at the exit of one tetrahedron as `sf + t G·D`,
/// which rounding may leave just short of it, and it is excluded at the entry of the
/// next: the slack keeps it from falling between the two). `sorted` ascending.
pub fn first_crossed(sorted: &[Isovalue], sf: f64, sb: f64, slack: f64) -> Option<usize> {
    if sb > sf {
        sorted
            .iter()
            .position(|i| i.value > sf && i.value <= sb + slack)
    } else if sb < sf {
        sorted
            .iter()
            .rposition(|i| i.value >= sb - slack && i.value < sf)
    } else {
        None
    }
}

/// [`first_crossed`]'s slack in the f64 reference (a few ulps of scalars near 1).
pub const REFERENCE_SLACK: f64 = 1e-12;

#[cfg(test)]
mod tests {
    use super::*;

    fn isos(values: &[f64]) -> Vec<Isovalue> {
        values
            .iter()
            .map(|&value| Isovalue {
                value,
                color: [1.0; 4],
            })
            .collect()
    }

    #[test]
    fn first_crossing_follows_the_ray_and_the_half_open_rule() {
        let s = isos(&[0.3, 0.5, 0.9]);
        assert_eq!(first_crossed(&s, 0.2, 0.6, 0.0), Some(0));
        assert_eq!(
            first_crossed(&s, 0.6, 0.2, 0.0),
            Some(1),
            "falling: 0.5 first"
        );
        assert_eq!(first_crossed(&s, 0.31, 0.49, 0.0), None);
        assert_eq!(
            first_crossed(&s, 0.4, 0.4, 0.0),
            None,
            "sf = sb crosses nothing"
        );
        // Exactly at a vertex value: counted where the ray leaves, not where it enters,
        // so two tetrahedra sharing the face do not both draw it.
        assert_eq!(first_crossed(&s, 0.2, 0.3, 0.0), Some(0));
        assert_eq!(first_crossed(&s, 0.3, 0.4, 0.0), None);
        assert_eq!(first_crossed(&s, 0.4, 0.3, 0.0), Some(0));
        assert_eq!(first_crossed(&s, 0.3, 0.2, 0.0), None);
        // Outside the data range.
        assert_eq!(first_crossed(&isos(&[1.5]), 0.0, 1.0, 0.0), None);
        // The slack reaches an isovalue just beyond a rounded exit, never one at the entry.
        assert_eq!(
            first_crossed(&s, 0.2, 0.3 - 1e-13, REFERENCE_SLACK),
            Some(0)
        );
        assert_eq!(first_crossed(&s, 0.3, 0.4, REFERENCE_SLACK), None);
    }
}
