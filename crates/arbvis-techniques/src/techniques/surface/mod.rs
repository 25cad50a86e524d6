//! `[technique.surface]` / `[layer.surface]`: a triangle surface (OBJ, STL, PLY), a
//! horizon, a fault, a body's boundary, coloured by a constant, its elevation or one of
//! its own vertex properties (a TSurf's `PROPERTIES`, an x y z grid's columns), unlit or lit, opaque or translucent; the layer a scene draws beside its volumes,
//! meshes and clouds (issue 55; the seismic readers of issue 57 feed it).
//!
//! # How it works
//! The file's triangles are read ([`arbvis_data::surface`]), centred and scaled so that
//! the longest side spans [-1, 1] (its world frame: the file's coordinates, z up), and
//! given smooth normals (each vertex the area-weighted mean of its triangles' normals)
//! and a colour per vertex (the constant, or the colour table at the vertex's height
//! between the surface's lowest and highest z). Lighting is a headlight: ambient 0.2
//! plus 0.8 of `|n . v|` (two-sided: a horizon lights from above and below), no
//! specular. **Faithful** lights each vertex and interpolates the colour, as the era's
//! fixed-function pipeline did (`programs/surface/gouraud.*`); **precise** interpolates
//! the normal and lights each pixel (`phong.*`). Drawn with a depth test and depth
//! writes: in a layered scene an opaque surface hides what lies behind it. A translucent
//! surface (`opacity` below 1) blends premultiplied over what is drawn, its nearest
//! sheet only where it does not overlap itself in the view (a horizon seen from above);
//! [`reference`] is its f64 CPU twin (nearest hit per pixel centre, the same lighting).

pub mod prepare;
pub mod reference;
pub mod renderer;

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::RenderResult;
use crate::programs::ProgramPair;
use crate::techniques::world::World;
use crate::techniques::{ReferenceView, Renderer, Settings, Technique};
use arbvis_core::colortable::TableSpec;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_gl::{Gpu, ProgramChoice, ProgramKind};

/// `[technique.surface]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceScene {
    /// The triangle file (`.obj`, `.stl`, `.ply`, `.ts`), relative to the scene's
    /// folder, or a surface handed over in memory (`{ memory = NAME }`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<SurfaceFile>,
    /// Or a generated horizon (the demos' surface, no file needed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub synthetic: Option<SyntheticHorizon>,
    /// The constant colour, RGB in [0, 1] (where `colour_by` is absent).
    #[serde(default = "default_colour")]
    pub colour: [f64; 3],
    /// Colour through `table` by the surface's own elevation (`"elevation"`: its z) or
    /// one of its vertex properties (`{ property = "throw" }`), over `range`; vertices
    /// without a value take `colour`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour_by: Option<ColourBy>,
    /// The values the table spans, low to high (by default the lowest to the highest
    /// the surface has); values beyond take the table's ends.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
    /// Colour by the colours another layer of the scene shows where the surface lies (a
    /// survey's primary attribute through its table: "seismic on the horizon");
    /// `colour`, or `colour_by`, where the surface lies outside it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour_from: Option<ColourFrom>,
    /// The table `colour_by` reads (by default `viridis`).
    #[serde(default = "default_table")]
    pub table: TableSpec,
    /// The file's z grows downwards (a grid of time in ms or depth, as ZMap+ grids often
    /// are, which do not say): drawn as z = -z, z up as every layer. A TSurf says so itself
    /// (`ZPOSITIVE Depth`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub z_down: bool,
    /// `"phong"` (a headlight) or `"none"` (the colour as given).
    #[serde(default)]
    pub lighting: Lighting,
    /// In (0, 1]: below 1 the surface is translucent.
    #[serde(default = "one")]
    pub opacity: f64,
}

/// Where a surface's triangles are: a file, or a surface handed over in memory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "a surface file's path, or { memory = NAME } (an arbvis.Surface)"
)]
pub enum SurfaceFile {
    /// A file, relative to the scene's folder.
    Path(PathBuf),
    /// A surface handed over in memory, by its name.
    Memory {
        /// Its name (`surface-1`).
        memory: String,
    },
}

/// A generated horizon: a height field of `size` nodes 25 m apart, folded and cut by a
/// fault (a 120 m step across x), depths around -1000 m; `seed` turns the folds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SyntheticHorizon {
    /// Nodes along x and y (2 to 2048 each).
    pub size: [usize; 2],
    /// Turns the folds.
    #[serde(default)]
    pub seed: u64,
}

/// `colour_from = { layer = "F3" }`: the layer (by name) whose colours a surface takes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColourFrom {
    /// The layer's name.
    pub layer: String,
}

/// What a surface's colour follows besides the constant.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourBy {
    /// Its z, lowest to highest, through the table.
    Elevation,
    /// One of its vertex properties, by name.
    Property(String),
}

impl ColourBy {
    /// What the legend calls the values.
    pub fn title(&self) -> String {
        match self {
            ColourBy::Elevation => "elevation (z)".into(),
            ColourBy::Property(name) => name.clone(),
        }
    }
}

/// How a surface is lit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Lighting {
    /// A headlight: ambient plus two-sided diffuse.
    #[default]
    Phong,
    /// Unlit: the colour as given.
    None,
}

fn default_colour() -> [f64; 3] {
    [0.8, 0.8, 0.8]
}

fn default_table() -> TableSpec {
    TableSpec::builtin("viridis")
}

fn one() -> f64 {
    1.0
}

/// The headlight's ambient term.
pub const AMBIENT: f64 = 0.2;
/// The headlight's diffuse weight.
pub const DIFFUSE: f64 = 0.8;

impl SurfaceScene {
    /// A surface from `file` with every other value at its default.
    pub fn of(file: impl Into<PathBuf>) -> SurfaceScene {
        SurfaceScene {
            file: Some(SurfaceFile::Path(file.into())),
            synthetic: None,
            colour: default_colour(),
            colour_by: None,
            range: None,
            colour_from: None,
            z_down: false,
            table: default_table(),
            lighting: Lighting::default(),
            opacity: 1.0,
        }
    }

    /// Ambient, diffuse and opacity as the programs take them (`program.local`).
    pub fn light_terms(&self) -> [f64; 4] {
        match self.lighting {
            Lighting::Phong => [AMBIENT, DIFFUSE, self.opacity, 0.0],
            Lighting::None => [1.0, 0.0, self.opacity, 0.0],
        }
    }
}

impl Technique for SurfaceScene {
    const NAME: &'static str = "surface";
    const DEMOS: &'static [(&'static str, &'static str)] =
        &[crate::techniques::demo!("surface-horizon")];

    fn validate(&self, _: Fidelity, _: ProgramChoice) -> Result<(), FieldError> {
        match (&self.file, &self.synthetic) {
            (Some(_), Some(_)) | (None, None) => {
                return Err(FieldError::new(
                    "file",
                    "a surface reads a file (file = \"top.obj\") or makes a horizon (synthetic = { size = [48, 32] }), one of them",
                ))
            }
            (None, Some(s)) if s.size.iter().any(|n| !(2..=2048).contains(n)) => {
                return Err(FieldError::new(
                    "synthetic.size",
                    format!("{:?}: 2 to 2048 nodes each way", s.size),
                ))
            }
            _ => {}
        }
        if self.colour.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err(FieldError::new(
                "colour",
                format!("{:?}: each of r, g, b in [0, 1]", self.colour),
            ));
        }
        if !(self.opacity > 0.0 && self.opacity <= 1.0) {
            return Err(FieldError::new(
                "opacity",
                format!("{}: above 0 and at most 1", self.opacity),
            ));
        }
        if let Some(r) = self.range {
            if !(r.iter().all(|v| v.is_finite()) && r[0] < r[1]) {
                return Err(FieldError::new(
                    "range",
                    format!("{r:?}: two finite numbers, low below high"),
                ));
            }
        }
        if self
            .colour_from
            .as_ref()
            .is_some_and(|c| c.layer.is_empty())
        {
            return Err(FieldError::new(
                "colour_from.layer",
                "the name of a layer of the scene",
            ));
        }
        self.table.validate().map_err(|e| e.within("table"))
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        if let Some(SurfaceFile::Path(p)) = self.file.as_mut() {
            f("file", p);
        }
        if let Some(p) = self.table.file.as_mut() {
            f("table.file", p);
        }
    }

    fn program_pairs() -> Vec<ProgramPair> {
        renderer::program_pairs()
    }

    fn draws_opaque(&self) -> bool {
        self.opacity >= 1.0
    }

    /// Another colour, table, lighting or opacity of the same triangles.
    fn keeps_place(&self, new: &Self) -> bool {
        self.file == new.file && self.synthetic == new.synthetic && self.z_down == new.z_down
    }

    /// A generated horizon's corners, as prepared and uploaded (a file's are checked
    /// when it is read).
    fn memory_estimate(&self, _: [u32; 2]) -> Vec<arbvis_core::budget::Estimate> {
        let Some(h) = &self.synthetic else {
            return Vec::new();
        };
        let [nx, ny] = h.size.map(|n| n.clamp(2, 2048) as u64);
        vec![arbvis_core::budget::Estimate::of(
            format!("the {nx}x{ny} generated horizon's corners"),
            6 * (nx - 1) * (ny - 1),
            prepare::BYTES_PER_CORNER,
        )]
    }

    type Prepared = prepare::Prepared;

    fn prepare(
        &self,
        settings: &Settings<'_>,
        _: &arbvis_data::volume::Limits,
    ) -> RenderResult<prepare::Prepared> {
        Technique::validate(self, settings.fidelity, settings.programs)?;
        prepare::prepare(self, settings.base)
    }

    fn renderer(
        &self,
        gpu: &Gpu,
        settings: &Settings<'_>,
        kind: ProgramKind,
        prepared: prepare::Prepared,
    ) -> RenderResult<Box<dyn Renderer>> {
        Ok(Box::new(
            renderer::SurfaceRenderer::new(gpu, kind, settings.fidelity, self, prepared)?
                .with_base(settings.base),
        ))
    }

    /// The nearest hit at each pixel centre, lit as `fidelity` lights it.
    fn reference(
        &self,
        prepared: &prepare::Prepared,
        view: &ReferenceView<'_>,
    ) -> Option<arbvis_core::image::Image> {
        Some(reference::reference(
            prepared,
            self,
            Fidelity::Precise,
            &view.camera,
            view.size,
            view.background,
        ))
    }

    fn world(&self, prepared: &prepare::Prepared) -> Option<World> {
        Some(prepared.world)
    }

    fn colour_source(&self) -> Option<&str> {
        self.colour_from.as_ref().map(|c| c.layer.as_str())
    }

    fn coloured_points(&self, prepared: &prepare::Prepared) -> Vec<glam::DVec3> {
        prepared.corners.iter().map(|c| c.position).collect()
    }

    fn take_colours(&self, prepared: &mut prepare::Prepared, colours: &[Option<[f64; 3]>]) {
        for (corner, colour) in prepared.corners.iter_mut().zip(colours) {
            if let Some(c) = colour {
                corner.colour = glam::DVec3::from_array(*c);
            }
        }
    }
}
