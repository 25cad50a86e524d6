//! Lines: polylines from CSV text (`x, y, z` and an optional value, a blank line between
//! lines), and wells from a deviation survey (measured depth, inclination, azimuth) by the
//! minimum-curvature method, with a log along them.
//!
//! # Decisions
//! - Text as the surface readers take it: numbers separated by commas, semicolons or
//!   whitespace, `#` lines are comments, a first line of names is skipped where it is not
//!   numbers; every line of a file has as many numbers as its first; errors name the line
//!   and column ([`crate::surface::SurfaceError`], the text readers' positioned error).
//! - A deviation survey: measured depth (increasing), inclination from vertical and
//!   azimuth clockwise from north, in degrees; the wellhead's map x (east), y (north) and
//!   the datum's elevation (z of measured depth 0) given with it. Between stations the path
//!   is the circular arc of minimum curvature (SPE 3362, Taylor and Mason 1972), exact at
//!   any depth along it ([`Well::at`]); z is up (datum minus true vertical depth).
//! - A log is `md, value` rows; values between its rows are linear in measured depth,
//!   beyond its ends the end value; NaN (or a value of -999.25, LAS's null) is no value.

use std::path::Path;

pub mod describe;

pub use describe::describe_file;

use crate::surface::{Position, SurfaceError};

/// Largest file of lines read (16 MiB: a million rows).
pub const MAX_LINES_BYTES: u64 = 16 << 20;

/// Largest measured depth a survey may give, in its units (100 km: eight times the
/// deepest hole drilled).
pub const MAX_DEPTH: f64 = 1e5;

/// A polyline's points and the value at each, where the file gives one.
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// Points in the file's coordinates (z up).
    pub points: Vec<[f64; 3]>,
    /// One value per point, or none.
    pub values: Option<Vec<f64>>,
}

/// One station of a deviation survey.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Station {
    /// Measured depth along the hole.
    pub md: f64,
    /// Inclination from vertical, degrees.
    pub inclination: f64,
    /// Azimuth clockwise from north, degrees.
    pub azimuth: f64,
}

/// A well's stations and where each lies (east, north, true vertical depth from the datum).
#[derive(Debug, Clone, PartialEq)]
pub struct Well {
    /// The survey, measured depth increasing.
    pub stations: Vec<Station>,
    /// East, north and true vertical depth of each station from the wellhead at the datum.
    pub offsets: Vec<[f64; 3]>,
}

/// The unit direction of a station: east, north, down.
fn tangent(s: &Station) -> [f64; 3] {
    let (i, a) = (s.inclination.to_radians(), s.azimuth.to_radians());
    [i.sin() * a.sin(), i.sin() * a.cos(), i.cos()]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The dogleg between two unit tangents (radians).
fn dogleg(t1: [f64; 3], t2: [f64; 3]) -> f64 {
    dot(t1, t2).clamp(-1.0, 1.0).acos()
}

/// The offset (east, north, down) along the arc from `s1` after `length` of measured depth
/// towards `s2`: the circle tangent to both directions, or the straight line where they
/// agree.
fn along(s1: &Station, s2: &Station, length: f64) -> [f64; 3] {
    let (t1, t2) = (tangent(s1), tangent(s2));
    let beta = dogleg(t1, t2);
    let span = s2.md - s1.md;
    if beta < 1e-9 || span <= 0.0 {
        return t1.map(|c| c * length);
    }
    let radius = span / beta;
    let phi = length / radius;
    // The unit normal in the arc's plane, toward t2.
    let n: [f64; 3] = std::array::from_fn(|k| (t2[k] - t1[k] * beta.cos()) / beta.sin());
    std::array::from_fn(|k| radius * (phi.sin() * t1[k] + (1.0 - phi.cos()) * n[k]))
}

impl Well {
    /// The well of `stations` (measured depth increasing) by minimum curvature.
    pub fn of(stations: Vec<Station>) -> Well {
        let mut offsets = vec![[0.0; 3]];
        for w in stations.windows(2) {
            let last = *offsets.last().expect("one at least");
            let d = along(&w[0], &w[1], w[1].md - w[0].md);
            offsets.push(std::array::from_fn(|k| last[k] + d[k]));
        }
        // The first station is at the wellhead only where its depth is 0: above it the
        // hole is taken as straight down to it.
        let first = stations[0].md;
        for o in &mut offsets {
            o[2] += first;
        }
        Well { stations, offsets }
    }

    /// The offset (east, north, true vertical depth) at measured depth `md` within the
    /// survey's span (clamped to it).
    pub fn at(&self, md: f64) -> [f64; 3] {
        let s = &self.stations;
        let k = s
            .partition_point(|st| st.md <= md)
            .clamp(1, s.len().max(2) - 1);
        if s.len() < 2 {
            return self.offsets[0];
        }
        let (a, b) = (&s[k - 1], &s[k]);
        let length = (md - a.md).clamp(0.0, b.md - a.md);
        let d = along(a, b, length);
        std::array::from_fn(|c| self.offsets[k - 1][c] + d[c])
    }

    /// The path every `step` of measured depth (and at every station), placed at the
    /// wellhead `head` (map x, y) below the datum's elevation `datum`, z up; each point
    /// with its measured depth.
    pub fn path(&self, head: [f64; 2], datum: f64, step: f64) -> Vec<(f64, [f64; 3])> {
        let (first, last) = (
            self.stations[0].md,
            self.stations[self.stations.len() - 1].md,
        );
        let mut depths: Vec<f64> = self.stations.iter().map(|s| s.md).collect();
        let n = ((last - first) / step.max(1e-3)).ceil().min(1e6) as usize;
        depths.extend((1..n).map(|i| first + i as f64 * step));
        depths.sort_by(f64::total_cmp);
        depths.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        depths
            .into_iter()
            .map(|md| {
                let [e, n, tvd] = self.at(md);
                (md, [head[0] + e, head[1] + n, datum - tvd])
            })
            .collect()
    }
}

/// Numeric rows of a text file: each row's numbers with its line and the column each
/// starts at; a first line of names skipped; `width` numbers a row (the first row's count
/// where None), at least `least`.
fn rows(name: &Path, bytes: &[u8], least: usize) -> Result<Vec<(usize, Vec<f64>)>, SurfaceError> {
    let text = crate::surface::utf8(name, bytes)?;
    let error = |line: usize, column: usize, message: String| {
        SurfaceError::format(name, Position::Line { line, column }, message)
    };
    let mut out: Vec<(usize, Vec<f64>)> = Vec::new();
    let mut width = None;
    let mut first = true;
    let mut count = 0usize;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let trimmed = line.trim();
        if trimmed.starts_with('#') {
            continue;
        }
        if trimmed.is_empty() {
            // A blank line ends a polyline: kept as an empty row.
            out.push((n, Vec::new()));
            continue;
        }
        let words = crate::surface::xyz::fields(line);
        let numbers: Vec<Option<f64>> = words
            .iter()
            .map(|(_, w)| match w.to_ascii_lowercase().as_str() {
                "nan" => Some(f64::NAN),
                w => w.parse().ok(),
            })
            .collect();
        if first && numbers.iter().any(Option::is_none) {
            first = false;
            continue;
        }
        first = false;
        if let Some(k) = numbers.iter().position(Option::is_none) {
            let (column, word) = words[k];
            return Err(error(
                n,
                column,
                format!(
                    "expected a number, found {:?}",
                    arbvis_core::input::shorten(word, 24)
                ),
            ));
        }
        let width = *width.get_or_insert(words.len());
        if words.len() != width || width < least {
            // Too many: the first value past the row's width; too few: the last given.
            let column = words
                .get(width.min(words.len().saturating_sub(1)))
                .map_or(1, |w| w.0);
            return Err(error(
                n,
                column,
                format!("{} values, expected {}", words.len(), width.max(least)),
            ));
        }
        count += 1;
        if count > (MAX_LINES_BYTES / 4) as usize {
            return Err(error(n, 1, "too many rows".into()));
        }
        out.push((
            n,
            numbers.into_iter().map(|v| v.expect("checked")).collect(),
        ));
    }
    Ok(out)
}

/// The file's bytes, a regular file of at most [`MAX_LINES_BYTES`].
fn read(path: &Path) -> Result<Vec<u8>, SurfaceError> {
    arbvis_core::input::read_regular(path, MAX_LINES_BYTES).map_err(|error| SurfaceError::Io {
        path: path.to_path_buf(),
        error,
    })
}

/// Polylines from `x, y, z[, value]` rows, a blank line between lines (`name` in errors).
pub fn parse_polylines(name: &Path, bytes: &[u8]) -> Result<Vec<Polyline>, SurfaceError> {
    let mut lines = Vec::new();
    let mut current: Vec<(usize, Vec<f64>)> = Vec::new();
    let all = rows(name, bytes, 3)?;
    let last_line = all.last().map_or(1, |r| r.0);
    for row in all
        .into_iter()
        .chain(std::iter::once((last_line, Vec::new())))
    {
        if !row.1.is_empty() {
            current.push(row);
            continue;
        }
        if current.is_empty() {
            continue;
        }
        if let Some((line, r)) = current
            .iter()
            .find(|(_, r)| r[..3].iter().any(|v| !v.is_finite()))
        {
            let _ = r;
            return Err(SurfaceError::format(
                name,
                Position::Line {
                    line: *line,
                    column: 1,
                },
                "x, y and z must be finite",
            ));
        }
        lines.push(Polyline {
            points: current.iter().map(|(_, r)| [r[0], r[1], r[2]]).collect(),
            values: (current[0].1.len() > 3).then(|| current.iter().map(|(_, r)| r[3]).collect()),
        });
        current.clear();
    }
    if lines.iter().all(|l| l.points.len() < 2) {
        return Err(SurfaceError::format(
            name,
            Position::Line {
                line: last_line,
                column: 1,
            },
            "no line of two points or more",
        ));
    }
    Ok(lines)
}

/// A deviation survey from `md, inclination, azimuth` rows (`name` in errors): depths
/// increasing, inclinations 0..=180, finite azimuths.
pub fn parse_survey(name: &Path, bytes: &[u8]) -> Result<Vec<Station>, SurfaceError> {
    let mut stations: Vec<Station> = Vec::new();
    for (line, r) in rows(name, bytes, 3)?
        .into_iter()
        .filter(|r| !r.1.is_empty())
    {
        let error = |column: usize, m: String| {
            SurfaceError::format(name, Position::Line { line, column }, m)
        };
        let s = Station {
            md: r[0],
            inclination: r[1],
            azimuth: r[2],
        };
        if !(s.md.is_finite() && stations.last().is_none_or(|p| s.md > p.md)) {
            return Err(error(
                1,
                format!("measured depth {}: finite and increasing", s.md),
            ));
        }
        if s.md.abs() > MAX_DEPTH {
            return Err(error(
                1,
                format!(
                    "measured depth {:e}: at most {MAX_DEPTH:e} (the deepest holes are 12 km)",
                    s.md
                ),
            ));
        }
        if !(0.0..=180.0).contains(&s.inclination) {
            return Err(error(
                2,
                format!(
                    "inclination {}: degrees from vertical, 0 to 180",
                    s.inclination
                ),
            ));
        }
        if !s.azimuth.is_finite() {
            return Err(error(3, "azimuth: degrees clockwise from north".into()));
        }
        // 360 and -10 are north and 350: reduced into 0..360 (as `inspect` says them).
        stations.push(Station {
            azimuth: s.azimuth.rem_euclid(360.0),
            ..s
        });
    }
    if stations.len() < 2 {
        return Err(SurfaceError::format(
            name,
            Position::Line { line: 1, column: 1 },
            "a survey of two stations or more",
        ));
    }
    Ok(stations)
}

/// A log from `md, value` rows (`name` in errors): depths increasing; NaN and -999.25 are
/// no value.
pub fn parse_log(name: &Path, bytes: &[u8]) -> Result<Vec<(f64, f64)>, SurfaceError> {
    let mut log: Vec<(f64, f64)> = Vec::new();
    for (line, r) in rows(name, bytes, 2)?
        .into_iter()
        .filter(|r| !r.1.is_empty())
    {
        if !(r[0].is_finite() && log.last().is_none_or(|p| r[0] > p.0)) {
            return Err(SurfaceError::format(
                name,
                Position::Line { line, column: 1 },
                format!("measured depth {}: finite and increasing", r[0]),
            ));
        }
        let v = if r[1] == -999.25 { f64::NAN } else { r[1] };
        log.push((r[0], v));
    }
    if log.is_empty() {
        return Err(SurfaceError::format(
            name,
            Position::Line { line: 1, column: 1 },
            "a log of one row or more (md, value)",
        ));
    }
    Ok(log)
}

/// The log's value at `md`: linear between rows, the end values beyond; NaN where a row
/// either side has none.
pub fn log_at(log: &[(f64, f64)], md: f64) -> f64 {
    let k = log.partition_point(|r| r.0 <= md);
    match k {
        0 => log.first().map_or(f64::NAN, |r| r.1),
        k if k == log.len() => log[k - 1].1,
        k => {
            let (a, b) = (log[k - 1], log[k]);
            a.1 + (b.1 - a.1) * (md - a.0) / (b.0 - a.0)
        }
    }
}

/// Read polylines from a file.
pub fn read_polylines(path: &Path) -> Result<Vec<Polyline>, SurfaceError> {
    parse_polylines(path, &read(path)?)
}

/// Read a deviation survey from a file.
pub fn read_survey(path: &Path) -> Result<Vec<Station>, SurfaceError> {
    parse_survey(path, &read(path)?)
}

/// Read a log from a file.
pub fn read_log(path: &Path) -> Result<Vec<(f64, f64)>, SurfaceError> {
    parse_log(path, &read(path)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn station(md: f64, inclination: f64, azimuth: f64) -> Station {
        Station {
            md,
            inclination,
            azimuth,
        }
    }

    /// The worked example of drillingformulas.com ("Minimum Curvature Method", after
    /// Formulas and Calculations for Drilling, Production and Workover): 3500 to 3600 ft,
    /// inclination 15 to 25, azimuth 20 to 45 degrees: dogleg 0.22605 rad, north 27.22,
    /// east 19.45, TVD 94.01 ft (given to two decimals).
    #[test]
    fn minimum_curvature_matches_the_worked_example() {
        let (a, b) = (station(3500.0, 15.0, 20.0), station(3600.0, 25.0, 45.0));
        assert!((dogleg(tangent(&a), tangent(&b)) - 0.22605).abs() < 5e-6);
        let well = Well::of(vec![a, b]);
        let [east, north, tvd] = [0, 1, 2].map(|k| well.offsets[1][k] - well.offsets[0][k]);
        assert!((north - 27.22).abs() < 0.005, "{north}");
        assert!((east - 19.45).abs() < 0.005, "{east}");
        assert!((tvd - 94.01).abs() < 0.005, "{tvd}");
    }

    /// Minimum curvature is exact on a circular arc: a build from vertical at a constant
    /// rate, surveyed every 30 m, lies on its circle at every depth, between stations too;
    /// and a straight slant on its line.
    #[test]
    fn an_arc_and_a_line_are_reproduced_exactly_between_stations() {
        let (rate, azimuth) = (3.0 / 30.0, 63.0); // degrees per metre, east of north
        let stations: Vec<Station> = (0..=10)
            .map(|i| station(500.0 + i as f64 * 30.0, i as f64 * 30.0 * rate, azimuth))
            .collect();
        let well = Well::of(stations);
        let radius = 1.0 / rate.to_radians();
        for md in [500.0, 517.3, 620.0, 733.3, 800.0] {
            let theta = ((md - 500.0) * rate).to_radians();
            let horizontal = radius * (1.0 - theta.cos());
            let want = [
                horizontal * azimuth.to_radians().sin(),
                horizontal * azimuth.to_radians().cos(),
                500.0 + radius * theta.sin(),
            ];
            let got = well.at(md);
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-9, "md {md}: {got:?} {want:?}");
            }
        }
        let slant = Well::of(vec![station(0.0, 30.0, 200.0), station(100.0, 30.0, 200.0)]);
        let got = slant.at(40.0);
        let want = [
            40.0 * 0.5 * 200f64.to_radians().sin(),
            40.0 * 0.5 * 200f64.to_radians().cos(),
            40.0 * 3f64.sqrt() / 2.0,
        ];
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn malformed_surveys_logs_and_lines_are_refused_at_their_line() {
        let e = |r: Result<(), SurfaceError>| r.unwrap_err().to_string();
        let survey = |t: &str| parse_survey(Path::new("w.csv"), t.as_bytes()).map(|_| ());
        assert!(e(survey("MD,INC,AZI\n0,0,0\n10,0\n")).contains("line 3"));
        assert!(e(survey("0,0,0\n10,200,0\n")).contains("inclination 200"));
        assert!(e(survey("0,0,0\n0,1,0\n"))
            .contains("line 2, column 1: measured depth 0: finite and increasing"));
        assert!(e(survey("0,0,0\n")).contains("two stations"));
        let log = |t: &str| parse_log(Path::new("l.csv"), t.as_bytes()).map(|_| ());
        assert!(e(log("1,2\n1,3\n")).contains("line 2"));
        assert!(e(log("MD,GR\n")).contains("one row or more"));
        let turned = parse_survey(Path::new("w.csv"), b"0,0,-10\n10,1,370\n").unwrap();
        assert_eq!([turned[0].azimuth, turned[1].azimuth], [350.0, 10.0]);
        let lines = |t: &str| parse_polylines(Path::new("p.csv"), t.as_bytes()).map(|_| ());
        assert!(e(lines("0 0 0\n1 x 1\n")).contains("line 2, column 3: expected a number"));
        assert!(e(lines("0 0 0\n\n1 1 1\n")).contains("no line of two points"));
        assert!(e(lines("0 0 nan\n1 1 1\n")).contains("finite"));
        // Too many values: the column of the first one past the row's width.
        assert!(e(lines("0 0 0\n1 1 1 7 8\n")).contains("line 2, column 7: 5 values, expected 3"));
        assert!(e(lines("0 0 0 0\n1 1 1\n")).contains("line 2, column 5: 3 values, expected 4"));
        let two = parse_polylines(
            Path::new("p.csv"),
            b"x,y,z,v\n0,0,0,1\n1,0,0,2\n\n5,5,5,3\n6,6,6,4\n7,7,7,5\n",
        )
        .unwrap();
        assert_eq!(two.len(), 2);
        assert_eq!(two[1].values, Some(vec![3.0, 4.0, 5.0]));
    }

    #[test]
    fn a_log_is_linear_between_its_rows_and_held_beyond() {
        let log = parse_log(
            Path::new("l.csv"),
            b"DEPT GR\n100 10\n110 30\n120 -999.25\n",
        )
        .unwrap();
        assert_eq!(log_at(&log, 105.0), 20.0);
        assert_eq!(log_at(&log, 50.0), 10.0);
        assert!(log_at(&log, 115.0).is_nan());
    }
}
