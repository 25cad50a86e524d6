//! `[technique.lines]` / `[layer.lines]`: polylines and wells drawn as tubes or ribbons
//! of a set width in metres or pixels, coloured by a constant or by a value along them (a
//! log along a well): the wells that tie a survey, picked fault traces, cables (issue 57
//! item 3).
//!
//! # How it works
//! The lines come from a CSV file (`x, y, z[, value]`, a blank line between lines) or a
//! well: its deviation survey by minimum curvature ([`arbvis_data::lines::Well`]), placed
//! at its wellhead below its datum, the path taken every 2 m of measured depth and at
//! every station, with a log's value at each point. Each line becomes a tube: a ring of
//! `sides` vertices around each point, square to the path and turned along it by parallel
//! transport, joined ring to ring; each vertex takes its point's colour (the table over
//! `range`, else the values' own span; the constant where there is no value). The tube
//! is then drawn and referenced as a surface is ([`super::surface`]: a headlight per
//! vertex faithful, per pixel precise; opaque, with depth), in the file's coordinates, z up.
//! A ribbon is a flat band turned to face the viewer, unlit; ribbons, and tubes as wide
//! as a number of pixels, are shaped again for each view ([`shape`]).

pub mod renderer;
pub mod shape;

use std::path::PathBuf;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::surface::{self, Lighting, SurfaceScene};
use crate::error::RenderResult;
use crate::programs::ProgramPair;
use crate::techniques::world::World;
use crate::techniques::{ReferenceView, Renderer, Settings, Technique};
use arbvis_core::colortable::TableSpec;
use arbvis_core::vocab::{Fidelity, FieldError};
use arbvis_data::lines::{Polyline, Well};
use arbvis_data::surface::TriangleMesh;
use arbvis_gl::{Gpu, ProgramChoice, ProgramKind};
use shape::PreparedLines;
pub use shape::{LineStyle, Shape, Width};

/// `[technique.lines]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinesScene {
    /// Polylines: `x, y, z[, value]` rows, a blank line between lines.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Or a well from its deviation survey.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub well: Option<WellScene>,
    /// Or the polylines themselves: each a list of `[x, y, z]` or `[x, y, z, value]`
    /// points (lines typed in a scene, or arrays handed over from Python); a value of
    /// `nan` (null from JSON, as Python's NaN crosses) is none.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "null_is_nan::polylines"
    )]
    pub polylines: Option<Vec<Points>>,
    /// The tubes' radius in the data's units (metres), where `width` is not given.
    #[serde(default = "default_radius")]
    pub radius: f64,
    /// `"tube"` (lit, round) or `"ribbon"` (a flat band facing the viewer, unlit).
    #[serde(default, skip_serializing_if = "is_tube")]
    pub style: LineStyle,
    /// Across the line: `{ metres = 20 }` or `{ pixels = 3 }` (the same on screen at
    /// every zoom); by default twice `radius`, in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<Width>,
    /// Vertices around each ring (3 to 64).
    #[serde(default = "default_sides")]
    pub sides: usize,
    /// The colour where there is no value, RGB in [0, 1].
    #[serde(default = "default_colour")]
    pub colour: [f64; 3],
    /// The table values are coloured through (by default `viridis`).
    #[serde(default = "default_table")]
    pub table: TableSpec,
    /// The values the table's ends stand for (by default the values' own lowest and
    /// highest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
}

fn is_tube(style: &LineStyle) -> bool {
    *style == LineStyle::Tube
}

/// Numbers that may be null: JSON, through which Python hands a scene over, has no NaN
/// (numpy arrays' NaN cross as null), TOML has `nan`; both are NaN here.
mod null_is_nan {
    use serde::{Deserialize, Deserializer};

    /// A number, or null.
    #[derive(Deserialize)]
    #[serde(transparent)]
    struct OrNull(Option<f64>);

    impl OrNull {
        fn value(self) -> f64 {
            self.0.unwrap_or(f64::NAN)
        }
    }

    /// `polylines`: lines of points of numbers.
    pub fn polylines<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Vec<super::Points>>, D::Error> {
        let lines: Option<Vec<Vec<Vec<OrNull>>>> = Option::deserialize(d)?;
        Ok(lines.map(|lines| {
            let point = |p: Vec<OrNull>| p.into_iter().map(OrNull::value).collect();
            lines
                .into_iter()
                .map(|l| l.into_iter().map(point).collect())
                .collect()
        }))
    }

    /// `log_rows`: pairs of numbers.
    pub fn rows<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 2]>>, D::Error> {
        let rows: Option<Vec<[OrNull; 2]>> = Option::deserialize(d)?;
        Ok(rows.map(|rows| {
            rows.into_iter()
                .map(|[m, v]| [m.value(), v.value()])
                .collect()
        }))
    }
}

/// The widest line in pixels (a band wider than most pictures is a mistake).
const MAX_PIXELS: f64 = 1024.0;

/// One line's points, each `[x, y, z]` or `[x, y, z, value]`.
pub type Points = Vec<Vec<f64>>;

/// A well: its deviation survey, where it starts, and a log along it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WellScene {
    /// `md, inclination, azimuth` rows (degrees; azimuth clockwise from north).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub survey: Option<PathBuf>,
    /// Or the stations themselves, `[md, inclination, azimuth]` each.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stations: Option<Vec<[f64; 3]>>,
    /// The wellhead's map x (east) and y (north).
    pub head: [f64; 2],
    /// The elevation of measured depth 0 (z up).
    #[serde(default)]
    pub datum: f64,
    /// `md, value` rows: the values the tube is coloured by.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub log: Option<PathBuf>,
    /// Or the log's rows themselves, `[md, value]` each (a value of `nan` or null: none).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "null_is_nan::rows"
    )]
    pub log_rows: Option<Vec<[f64; 2]>>,
}

fn default_radius() -> f64 {
    10.0
}

fn default_sides() -> usize {
    8
}

fn default_colour() -> [f64; 3] {
    [0.9, 0.85, 0.3]
}

fn default_table() -> TableSpec {
    TableSpec::builtin("viridis")
}

/// Measured depth between a well's drawn points (and at every station).
pub const WELL_STEP: f64 = 2.0;

/// Most rings a scene's tubes hold (a million rings of 64 sides is 128 M triangles).
const MAX_RINGS: usize = 1 << 20;

impl LinesScene {
    /// The width across the lines: `width`, else twice `radius` in metres.
    pub fn width(&self) -> Width {
        self.width.unwrap_or(Width::Metres(2.0 * self.radius))
    }

    /// The lines' shape: style, width and a tube's sides.
    pub fn shape(&self) -> Shape {
        Shape {
            style: self.style,
            width: self.width(),
            sides: self.sides,
        }
    }

    /// The parameters the lines are drawn with as a surface: opaque, their colours their
    /// own; tubes lit, ribbons not.
    pub fn as_surface(&self) -> SurfaceScene {
        SurfaceScene {
            file: None,
            synthetic: None,
            colour: self.colour,
            colour_by: None,
            range: None,
            colour_from: None,
            table: self.table.clone(),
            z_down: false,
            lighting: match self.style {
                LineStyle::Tube => Lighting::Phong,
                LineStyle::Ribbon => Lighting::None,
            },
            opacity: 1.0,
        }
    }
}

/// The lines `scene` names, read relative to `base`.
pub fn polylines(scene: &LinesScene, base: &std::path::Path) -> RenderResult<Vec<Polyline>> {
    if let Some(file) = &scene.file {
        return Ok(arbvis_data::lines::read_polylines(&base.join(file))?);
    }
    if let Some(rows) = &scene.polylines {
        return Ok(lines_of(rows)?);
    }
    let Some(w) = &scene.well else {
        return Err(FieldError::new(
            "file",
            "lines read a file (file = \"faults.csv\") or a well (well = { survey = ... })",
        )
        .into());
    };
    let stations = match (&w.survey, &w.stations) {
        (Some(file), None) => arbvis_data::lines::read_survey(&base.join(file))?,
        (None, Some(rows)) => stations_of(rows)?,
        _ => {
            return Err(FieldError::new(
                "well.survey",
                "a well's survey is a file (survey = \"w.csv\") or its stations (stations = [[md, inclination, azimuth], ...]), one of them",
            )
            .into())
        }
    };
    let well = Well::of(stations);
    let path = well.path(w.head, w.datum, WELL_STEP);
    let log = match (&w.log, &w.log_rows) {
        (Some(file), None) => Some(arbvis_data::lines::read_log(&base.join(file))?),
        (None, Some(rows)) => Some(log_of(rows)?),
        (None, None) => None,
        (Some(_), Some(_)) => {
            return Err(FieldError::new(
                "well.log",
                "a well's log is a file (log = \"gr.csv\") or its rows (log_rows = [[md, value], ...]), one of them",
            )
            .into())
        }
    };
    let values = log.map(|log| {
        path.iter()
            .map(|(md, _)| arbvis_data::lines::log_at(&log, *md))
            .collect()
    });
    Ok(vec![Polyline {
        points: path.into_iter().map(|(_, p)| p).collect(),
        values,
    }])
}

/// Stations given in the scene, checked as a survey file's rows are.
fn stations_of(rows: &[[f64; 3]]) -> Result<Vec<arbvis_data::lines::Station>, FieldError> {
    let text: String = rows
        .iter()
        .map(|[m, i, a]| format!("{m},{i},{a}\n"))
        .collect();
    arbvis_data::lines::parse_survey(std::path::Path::new("stations"), text.as_bytes()).map_err(
        |e| {
            FieldError::new(
                "well.stations",
                e.to_string().replace("stations: line ", "station "),
            )
        },
    )
}

/// A log given in the scene, checked as a log file's rows are.
fn log_of(rows: &[[f64; 2]]) -> Result<Vec<(f64, f64)>, FieldError> {
    let text: String = rows.iter().map(|[m, v]| format!("{m},{v}\n")).collect();
    arbvis_data::lines::parse_log(std::path::Path::new("rows"), text.as_bytes()).map_err(|e| {
        FieldError::new(
            "well.log_rows",
            e.to_string().replace("rows: line ", "row "),
        )
    })
}

/// Polylines given in the scene: every point of a line three numbers (x, y, z) or four
/// (and a value; NaN or infinite: none), x, y and z finite; one line of two points at
/// least. Errors name the line and point (`polylines.1.4`, from 0).
fn lines_of(rows: &[Vec<Vec<f64>>]) -> Result<Vec<Polyline>, FieldError> {
    let mut lines = Vec::with_capacity(rows.len());
    for (l, line) in rows.iter().enumerate() {
        let width = line.first().map_or(3, Vec::len);
        for (k, p) in line.iter().enumerate() {
            let key = || format!("polylines.{l}.{k}");
            if p.len() != width || !(3..=4).contains(&p.len()) {
                return Err(FieldError::new(
                    key(),
                    format!(
                        "{} numbers: x, y, z (and a value), as the line's first point ({width})",
                        p.len()
                    ),
                ));
            }
            if !p[..3].iter().all(|v| v.is_finite()) {
                return Err(FieldError::new(key(), format!("{p:?}: x, y and z finite")));
            }
        }
        lines.push(Polyline {
            points: line.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            values: (width == 4).then(|| {
                line.iter()
                    .map(|p| if p[3].is_finite() { p[3] } else { f64::NAN })
                    .collect()
            }),
        });
    }
    if lines.iter().all(|l| l.points.len() < 2) {
        return Err(FieldError::new(
            "polylines",
            "no line of two points or more",
        ));
    }
    Ok(lines)
}

/// A line's distinct points (a point equal to the one before adds nothing), each with its
/// value (NaN where none).
fn distinct(line: &Polyline) -> Vec<(DVec3, f64)> {
    let mut kept: Vec<(DVec3, f64)> = Vec::new();
    for (i, p) in line.points.iter().enumerate() {
        let p = DVec3::from_array(*p);
        let v = line.values.as_ref().map_or(f64::NAN, |v| v[i]);
        if kept.last().is_none_or(|(q, _)| *q != p) {
            kept.push((p, v));
        }
    }
    kept
}

/// The tubes of `lines` (radius `radius`, `sides` around) in the lines' coordinates, and
/// each vertex's value; lines of fewer than two distinct points are left out.
pub fn tubes(lines: &[Polyline], radius: f64, sides: usize) -> (TriangleMesh, Vec<f64>) {
    let kept: Vec<Vec<(DVec3, f64)>> = lines
        .iter()
        .map(distinct)
        .filter(|l| l.len() >= 2)
        .collect();
    let points: Vec<Vec<DVec3>> = kept
        .iter()
        .map(|l| l.iter().map(|(p, _)| *p).collect())
        .collect();
    let values: Vec<f64> = kept.iter().flatten().map(|(_, v)| *v).collect();
    (
        shape::tubes(&points, sides, |_| radius),
        shape::per_vertex(&values, sides),
    )
}

/// Read the lines and colour their points; make their tubes when they are drawn in metres.
pub fn prepare(scene: &LinesScene, base: &std::path::Path) -> RenderResult<PreparedLines> {
    let lines = polylines(scene, base)?;
    let rings: usize = lines.iter().map(|l| l.points.len()).sum();
    if rings > MAX_RINGS {
        return Err(FieldError::new("file", format!("{rings} points: at most {MAX_RINGS}")).into());
    }
    // Each point's quads to the next: two triangles, six drawn corners a side (a ribbon
    // has one side).
    let per_point = scene.shape().vertices_per_point() as u64;
    let corners = (rings as u64).saturating_mul(6 * per_point);
    arbvis_core::budget::check(
        format!("the lines' {rings} points of {per_point} vertices"),
        arbvis_core::budget::times(corners, surface::prepare::BYTES_PER_CORNER),
    )?;
    let kept: Vec<Vec<(DVec3, f64)>> = lines
        .iter()
        .map(distinct)
        .filter(|l| l.len() >= 2)
        .collect();
    if kept.is_empty() {
        return Err(FieldError::new("file", "no line of two distinct points").into());
    }
    let values: Vec<f64> = kept.iter().flatten().map(|(_, v)| *v).collect();
    let (colours, legend) = colours(scene, base, &values)?;
    let points: Vec<Vec<DVec3>> = kept
        .iter()
        .map(|l| l.iter().map(|(p, _)| *p).collect())
        .collect();
    let (world, fixed) = match (scene.shape().fixed(), scene.width()) {
        (true, Width::Metres(w)) => {
            let mesh = shape::tubes(&points, scene.sides, |_| w / 2.0);
            let per_vertex = shape::per_vertex(&colours, scene.sides);
            let tubes = surface::prepare::of_coloured_mesh(&mesh, &per_vertex, legend.clone());
            (tubes.world, Some(tubes))
        }
        // Shaped for each view: the frame of the points, widened by half a width in metres.
        (_, width) => {
            let half = match width {
                Width::Metres(w) => w / 2.0,
                Width::Pixels(_) => 0.0,
            };
            let all = points.iter().flatten();
            let lo = all.clone().fold(DVec3::INFINITY, |a, p| a.min(*p)) - half;
            let hi = all.fold(DVec3::NEG_INFINITY, |a, p| a.max(*p)) + half;
            (World::of_box(lo.to_array(), hi.to_array()), None)
        }
    };
    let in_frame = |p: &DVec3| (*p - world.centre) / world.units;
    Ok(PreparedLines {
        lines: points
            .iter()
            .map(|l| l.iter().map(in_frame).collect())
            .collect(),
        colours,
        world,
        legend,
        fixed,
    })
}

/// The legend's range and colours.
type Legend = ([f64; 2], Option<Vec<[u8; 3]>>);

/// Each point's colour from its value (the table over `range`, else over the values' own
/// span; the constant where it has none), and the legend.
fn colours(
    scene: &LinesScene,
    base: &std::path::Path,
    values: &[f64],
) -> RenderResult<(Vec<DVec3>, Legend)> {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let span = finite.fold(None, |s: Option<[f64; 2]>, v| {
        Some(s.map_or([v, v], |[lo, hi]| [lo.min(v), hi.max(v)]))
    });
    let constant = DVec3::from_array(scene.colour);
    let Some([lo, hi]) = scene.range.or(span) else {
        return Ok((vec![constant; values.len()], ([0.0, 0.0], None)));
    };
    let table = scene.table.build(base)?;
    let colours = values
        .iter()
        .map(|&v| match v.is_finite() {
            true => {
                let s = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
                surface::prepare::table_colour(&table, s)
            }
            false => constant,
        })
        .collect();
    let legend = crate::techniques::annotations::colours(&table.entries);
    Ok((colours, ([lo, hi], Some(legend))))
}

impl Technique for LinesScene {
    const NAME: &'static str = "lines";
    const DEMOS: &'static [(&'static str, &'static str)] =
        &[crate::techniques::demo!("lines-well")];

    fn validate(&self, _: Fidelity, _: ProgramChoice) -> Result<(), FieldError> {
        let sources = [
            self.file.is_some(),
            self.well.is_some(),
            self.polylines.is_some(),
        ];
        if sources.iter().filter(|&&s| s).count() != 1 {
            return Err(FieldError::new(
                "file",
                "lines read a file (file = \"faults.csv\"), a well (well = { survey = \"w.csv\", head = [x, y] }) or their points (polylines = [[[x, y, z], ...], ...]), one of them",
            ));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(FieldError::new(
                "radius",
                format!("{}: above 0", self.radius),
            ));
        }
        match self.width {
            Some(Width::Metres(w)) if !(w.is_finite() && w > 0.0) => {
                return Err(FieldError::new("width.metres", format!("{w}: above 0")));
            }
            Some(Width::Pixels(w)) if !(w.is_finite() && w > 0.0 && w <= MAX_PIXELS) => {
                return Err(FieldError::new(
                    "width.pixels",
                    format!("{w}: above 0, at most {MAX_PIXELS}"),
                ));
            }
            _ => {}
        }
        if !(3..=64).contains(&self.sides) {
            return Err(FieldError::new("sides", format!("{}: 3 to 64", self.sides)));
        }
        if self.colour.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err(FieldError::new(
                "colour",
                format!("{:?}: each of r, g, b in [0, 1]", self.colour),
            ));
        }
        if let Some(w) = &self.well {
            if !(w.head.iter().all(|v| v.is_finite()) && w.datum.is_finite()) {
                return Err(FieldError::new(
                    "well.head",
                    "the wellhead's x, y and the datum: finite",
                ));
            }
        }
        if let Some([lo, hi]) = self.range {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(FieldError::new(
                    "range",
                    format!("[{lo}, {hi}]: finite, low below high"),
                ));
            }
        }
        self.table.validate().map_err(|e| e.within("table"))
    }

    fn for_each_data_path(&mut self, f: &mut dyn FnMut(&str, &mut PathBuf)) {
        if let Some(p) = self.file.as_mut() {
            f("file", p);
        }
        if let Some(w) = self.well.as_mut() {
            if let Some(p) = w.survey.as_mut() {
                f("well.survey", p);
            }
            if let Some(p) = w.log.as_mut() {
                f("well.log", p);
            }
        }
        if let Some(p) = self.table.file.as_mut() {
            f("table.file", p);
        }
    }

    fn program_pairs() -> Vec<ProgramPair> {
        surface::renderer::program_pairs()
    }

    fn draws_opaque(&self) -> bool {
        true
    }

    type Prepared = PreparedLines;

    fn prepare(
        &self,
        settings: &Settings<'_>,
        _: &arbvis_data::volume::Limits,
    ) -> RenderResult<PreparedLines> {
        Technique::validate(self, settings.fidelity, settings.programs)?;
        prepare(self, settings.base)
    }

    fn renderer(
        &self,
        gpu: &Gpu,
        settings: &Settings<'_>,
        kind: ProgramKind,
        prepared: PreparedLines,
    ) -> RenderResult<Box<dyn Renderer>> {
        Ok(Box::new(renderer::LinesRenderer::new(
            gpu,
            kind,
            settings.fidelity,
            self,
            settings.base,
            prepared,
        )?))
    }

    /// The lines' nearest hit at each pixel centre (shaped for the view), lit as the
    /// precise programs light it.
    fn reference(
        &self,
        prepared: &PreparedLines,
        view: &ReferenceView<'_>,
    ) -> Option<arbvis_core::image::Image> {
        Some(surface::reference::reference(
            &prepared.shaped(self.shape(), &view.camera, view.size),
            &self.as_surface(),
            Fidelity::Precise,
            &view.camera,
            view.size,
            view.background,
        ))
    }

    fn world(&self, prepared: &PreparedLines) -> Option<World> {
        Some(prepared.world)
    }
}
