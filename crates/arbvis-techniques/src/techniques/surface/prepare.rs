//! A surface's CPU preparation (no GL): its triangles in the object frame with smooth
//! normals and a colour per corner.

use std::path::Path;

use glam::DVec3;

use super::{ColourBy, SurfaceScene};
use crate::error::RenderResult;
use crate::techniques::world::World;
use arbvis_data::surface::TriangleMesh;

/// A triangle's corner as drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// In the object frame (the longest side spans [-1, 1]).
    pub position: DVec3,
    /// The vertex's smooth normal (unit, or zero where every triangle at it is flat).
    pub normal: DVec3,
    /// RGB in [0, 1].
    pub colour: DVec3,
}

/// What the renderer and the reference draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Three corners per triangle.
    pub corners: Vec<Corner>,
    /// Where the object frame lies in the world (the file's coordinates).
    pub world: World,
    /// The values the table spans (lowest and highest z or property value, or the scene's
    /// `range`), and the table's colours where the surface is coloured by them (its
    /// legend).
    pub elevation: ([f64; 2], Option<Vec<[u8; 3]>>),
}

/// Memory per drawn corner: the prepared [`Corner`] (three f64 vectors) and its twelve
/// uploaded floats.
pub const BYTES_PER_CORNER: u64 = 72 + 48;

/// Read `scene.file` (relative to `base`) and prepare it, its corners held to the memory
/// budget.
pub fn prepare(scene: &SurfaceScene, base: &Path) -> RenderResult<Prepared> {
    let mesh = match (&scene.file, &scene.synthetic) {
        (Some(super::SurfaceFile::Path(file)), _) => arbvis_data::surface::read(&base.join(file))?,
        (Some(super::SurfaceFile::Memory { memory }), _) => arbvis_data::surface::SURFACES
            .copy(memory)
            .map_err(|e| arbvis_core::vocab::FieldError::new("file", e.to_string()))?,
        (None, Some(s)) => synthetic_horizon(s),
        (None, None) => {
            return Err(
                arbvis_core::vocab::FieldError::new("file", "a surface needs a file").into(),
            )
        }
    };
    let mesh = match scene.z_down {
        true => mesh.map_vertices(|[x, y, z]| [x, y, -z]),
        false => mesh,
    };
    let corners = 3 * mesh.triangles.len() as u64;
    arbvis_core::budget::check(
        format!("the surface's {corners} corners"),
        arbvis_core::budget::times(corners, BYTES_PER_CORNER),
    )?;
    let table = match &scene.colour_by {
        Some(_) => Some(scene.table.build(base)?),
        None => None,
    };
    if let Some(ColourBy::Property(name)) = &scene.colour_by {
        if mesh.property(name).is_none() {
            let has: Vec<String> = mesh
                .properties
                .iter()
                .map(|p| format!("{:?}", p.name))
                .collect();
            let has = match has.is_empty() {
                true => "it has none".to_string(),
                false => format!("it has {}", has.join(", ")),
            };
            return Err(arbvis_core::vocab::FieldError::new(
                "colour_by.property",
                format!("{name:?}: the surface has no vertex property of that name ({has})"),
            )
            .into());
        }
    }
    Ok(of_mesh(&mesh, scene, table.as_ref()))
}

/// [`prepare`] of a surface already read; `table` colours it by `scene.colour_by` where
/// given (a property it lacks colours nothing: [`prepare`] refuses it).
pub fn of_mesh(
    mesh: &TriangleMesh,
    scene: &SurfaceScene,
    table: Option<&arbvis_core::colortable::ColorTable>,
) -> Prepared {
    let values: Vec<f64> = match &scene.colour_by {
        Some(ColourBy::Property(name)) => match mesh.property(name) {
            Some(p) => p.values.clone(),
            None => vec![f64::NAN; mesh.vertices.len()],
        },
        _ => mesh.vertices.iter().map(|p| p[2]).collect(),
    };
    let [low, high] = scene.range.unwrap_or_else(|| {
        let used = mesh.triangles.iter().flatten().map(|&v| values[v as usize]);
        used.filter(|v| v.is_finite())
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], v| {
                [lo.min(v), hi.max(v)]
            })
    });
    let constant = DVec3::from_array(scene.colour);
    let colours: Vec<DVec3> = values
        .iter()
        .map(|&v| match table {
            Some(t) if v.is_finite() => {
                let s = if high > low {
                    (v - low) / (high - low)
                } else {
                    0.5
                };
                table_colour(t, s)
            }
            _ => constant,
        })
        .collect();
    let legend = table.map(|t| crate::techniques::annotations::colours(&t.entries));
    let span = match low <= high {
        true => [low, high],
        false => [0.0, 0.0],
    };
    of_coloured_mesh(mesh, &colours, (span, legend))
}

/// A mesh with a colour per vertex, in the object frame of its box; `legend` is what
/// [`Prepared::elevation`] holds (the range a table spans and its colours).
pub fn of_coloured_mesh(
    mesh: &TriangleMesh,
    colours: &[DVec3],
    legend: ([f64; 2], Option<Vec<[u8; 3]>>),
) -> Prepared {
    let (lo, hi) = mesh.bounds();
    let world = World::of_box(lo, hi);
    let in_frame = |v: [f64; 3]| (DVec3::from_array(v) - world.centre) / world.units;
    corners_of(mesh, in_frame, colours, legend, world)
}

/// [`of_coloured_mesh`] of a mesh already in the object frame of `world` (a shape made
/// for each view keeps the frame of the lines it is drawn around).
pub fn of_frame_mesh(
    mesh: &TriangleMesh,
    colours: &[DVec3],
    legend: ([f64; 2], Option<Vec<[u8; 3]>>),
    world: World,
) -> Prepared {
    corners_of(mesh, DVec3::from_array, colours, legend, world)
}

/// The corners of `mesh`, each vertex taken into the object frame by `in_frame`.
fn corners_of(
    mesh: &TriangleMesh,
    in_frame: impl Fn([f64; 3]) -> DVec3,
    colours: &[DVec3],
    legend: ([f64; 2], Option<Vec<[u8; 3]>>),
    world: World,
) -> Prepared {
    let normals = vertex_normals(mesh);
    let corners = mesh
        .triangles
        .iter()
        .flat_map(|t| t.map(|v| v as usize))
        .map(|v| Corner {
            position: in_frame(mesh.vertices[v]),
            normal: normals[v],
            colour: colours[v],
        })
        .collect();
    Prepared {
        corners,
        world,
        elevation: legend,
    }
}

/// Each vertex's normal: the area-weighted sum of its triangles' normals, normalized
/// (zero where they cancel or every triangle is flat).
pub fn vertex_normals(mesh: &TriangleMesh) -> Vec<DVec3> {
    let mut sums = vec![DVec3::ZERO; mesh.vertices.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| DVec3::from_array(mesh.vertices[v as usize]));
        // The cross product's length is twice the area: area-weighted as it stands.
        let n = (b - a).cross(c - a);
        for &v in t {
            sums[v as usize] += n;
        }
    }
    sums.into_iter().map(|n| n.normalize_or_zero()).collect()
}

/// The table's colour at `s` in [0, 1]: linear between the two nearest of its 256
/// entries (entry k at s = k / 255).
pub fn table_colour(table: &arbvis_core::colortable::ColorTable, s: f64) -> DVec3 {
    let x = s.clamp(0.0, 1.0) * 255.0;
    let k = (x.floor() as usize).min(254);
    let f = x - k as f64;
    let entry = |k: usize| {
        let e = table.entries[k];
        DVec3::new(e[0] as f64, e[1] as f64, e[2] as f64) / 255.0
    };
    entry(k) * (1.0 - f) + entry(k + 1) * f
}

/// The triangles of a [`SyntheticHorizon`] (the fault's throw between two columns of
/// nodes, so the triangles across it are the fault's face).
pub fn synthetic_horizon(h: &super::SyntheticHorizon) -> TriangleMesh {
    let [nx, ny] = h.size.map(|n| n.clamp(2, 2048));
    let phase = (h.seed % 1000) as f64 * 0.618;
    let fault = 0.55 * (nx - 1) as f64 * 25.0;
    let depth = |x: f64, y: f64| {
        let fold = 150.0 * (x / 160.0 + phase).sin() * (y / 230.0 - phase / 2.0).cos();
        let dip = -0.05 * x - 0.02 * y;
        // A normal fault along a line of nodes: the far side thrown down 120 m.
        let throw = if x > fault { -120.0 } else { 0.0 };
        -1000.0 + fold + dip + throw
    };
    let mut vertices = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (i as f64 * 25.0, j as f64 * 25.0);
            vertices.push([x, y, depth(x, y)]);
        }
    }
    let node = |i: usize, j: usize| (j * nx + i) as u32;
    let mut triangles = Vec::with_capacity(2 * (nx - 1) * (ny - 1));
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            triangles.push([node(i, j), node(i + 1, j), node(i + 1, j + 1)]);
            triangles.push([node(i, j), node(i + 1, j + 1), node(i, j + 1)]);
        }
    }
    TriangleMesh {
        vertices,
        triangles,
        properties: Vec::new(),
    }
}
