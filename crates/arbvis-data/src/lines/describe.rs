//! `arbvis inspect` of a lines file (`.csv`): which of the three kinds it is, by its
//! first line of names (a deviation survey's measured depth, inclination and azimuth; a
//! log's measured depth and one value; otherwise x, y, z polylines), and what it holds.

use std::path::Path;

use super::{
    dogleg, parse_log, parse_polylines, parse_survey, read, tangent, Polyline, Station, Well,
};
use crate::surface::SurfaceError;

/// What a file of lines holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinesKind {
    /// A deviation survey: measured depth, inclination, azimuth.
    Survey,
    /// A log: measured depth and a value.
    Log,
    /// Polylines: x, y, z and an optional value.
    Polylines,
}

/// The kind a first line of names says, None for a line of numbers (a log's first value
/// column is the one read). Names are matched
/// by their first word, case aside (`MD`, `Measured Depth (m)`, `INC`, `Azimuth`).
pub fn kind_of_header(line: &str) -> Option<LinesKind> {
    let words = crate::surface::xyz::fields(line);
    let numbers = words
        .iter()
        .all(|(_, w)| w.eq_ignore_ascii_case("nan") || w.parse::<f64>().is_ok());
    if numbers {
        return None;
    }
    let names: Vec<String> = words
        .iter()
        .map(|(_, w)| {
            w.trim_matches(|c| c == '"' || c == '\'')
                .to_ascii_lowercase()
        })
        .collect();
    let first_word = |n: &str| {
        n.split([' ', '(', '[', '_'])
            .next()
            .unwrap_or("")
            .to_string()
    };
    let has = |keys: &[&str]| names.iter().any(|n| keys.contains(&first_word(n).as_str()));
    let md = has(&["md", "measured", "dept", "depth", "mdepth"]);
    // Either of a survey's names makes it one (`MD,INC` is a survey short of a column).
    let survey = has(&["inc", "incl", "inclination"]) || has(&["azi", "az", "azim", "azimuth"]);
    Some(match (md, survey) {
        (true, true) => LinesKind::Survey,
        (true, false) => LinesKind::Log,
        (false, _) => LinesKind::Polylines,
    })
}

/// `arbvis inspect` text for the lines file at `path`.
pub fn describe_file(path: &Path) -> Result<String, SurfaceError> {
    let bytes = read(path)?;
    let text = crate::surface::utf8(path, &bytes)?;
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    let named = first.and_then(kind_of_header);
    let kind = named.unwrap_or(match first.map(|l| crate::surface::xyz::fields(l).len()) {
        Some(2) => LinesKind::Log,
        _ => LinesKind::Polylines,
    });
    let how = match named {
        Some(_) => "by its first line of names",
        None => "by its number of columns (no first line of names: name them MD, INC, AZI for a deviation survey)",
    };
    let body = match kind {
        LinesKind::Survey => survey_text(&parse_survey(path, &bytes)?),
        LinesKind::Log => log_text(&parse_log(path, &bytes)?),
        LinesKind::Polylines => polylines_text(&parse_polylines(path, &bytes)?),
    };
    Ok(format!("read as {} ({how})\n{body}", kind_name(kind)))
}

fn kind_name(kind: LinesKind) -> &'static str {
    match kind {
        LinesKind::Survey => "a deviation survey",
        LinesKind::Log => "a log",
        LinesKind::Polylines => "polylines",
    }
}

/// Stations, depths, the largest inclination and dogleg, and where the well ends by
/// minimum curvature.
fn survey_text(stations: &[Station]) -> String {
    let well = Well::of(stations.to_vec());
    let (first, last) = (stations[0], stations[stations.len() - 1]);
    // The first station at the largest inclination (where a build ends, not the hold's
    // last station).
    let steepest = stations.iter().fold(&stations[0], |s, t| {
        if t.inclination > s.inclination {
            t
        } else {
            s
        }
    });
    let severity = stations
        .windows(2)
        .map(|w| dogleg(tangent(&w[0]), tangent(&w[1])).to_degrees() * 30.0 / (w[1].md - w[0].md))
        .fold(0.0, f64::max);
    let [east, north, tvd] = *well.offsets.last().expect("one per station");
    format!(
        "stations: {}, measured depth {} to {}\nlargest inclination: {:.2} degrees at measured depth {}\nlargest dogleg: {severity:.2} degrees per 30 of measured depth\nat total depth (minimum curvature): {east:.2} east, {north:.2} north of the wellhead, true vertical depth {tvd:.2} below the datum\nhorizontal displacement: {:.2}\n",
        stations.len(),
        first.md,
        last.md,
        steepest.inclination,
        steepest.md,
        east.hypot(north)
    )
}

/// Rows, depths and the values' range.
fn log_text(log: &[(f64, f64)]) -> String {
    let defined: Vec<f64> = log.iter().map(|r| r.1).filter(|v| v.is_finite()).collect();
    let range = match range(defined.iter().copied()) {
        Some([lo, hi]) => format!("values: {lo} to {hi}"),
        None => "values: none".into(),
    };
    match (log.first(), log.last()) {
        (Some(a), Some(b)) => format!(
            "rows: {}, measured depth {} to {}\n{range} ({} rows without a value)\n",
            log.len(),
            a.0,
            b.0,
            log.len() - defined.len()
        ),
        _ => "rows: 0\n".into(),
    }
}

/// Lines, points, their bounds and length, and the values' range.
fn polylines_text(lines: &[Polyline]) -> String {
    let points = lines.iter().map(|l| l.points.len()).sum::<usize>();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in lines.iter().flat_map(|l| &l.points) {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let length: f64 = lines
        .iter()
        .flat_map(|l| l.points.windows(2))
        .map(|w| {
            (0..3)
                .map(|a| (w[1][a] - w[0][a]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .sum();
    let values = lines.iter().filter_map(|l| l.values.as_ref()).flatten();
    let values = match range(values.copied().filter(|v| v.is_finite())) {
        Some([a, b]) => format!("values: {a} to {b}"),
        None => "values: none".into(),
    };
    format!(
        "lines: {}, points: {points}, length {length:.2}\nbounds: {lo:?} .. {hi:?}\n{values}\n",
        lines.len()
    )
}

fn range(values: impl Iterator<Item = f64>) -> Option<[f64; 2]> {
    values.fold(None, |r, v| match r {
        None => Some([v, v]),
        Some([lo, hi]) => Some([lo.min(v), hi.max(v)]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_say_which_kind() {
        let cases = [
            ("MD,INC,AZI", Some(LinesKind::Survey)),
            (
                "\"Measured Depth (m)\" Inclination Azimuth",
                Some(LinesKind::Survey),
            ),
            ("md;incl;azim;tvd", Some(LinesKind::Survey)),
            ("MD,INC", Some(LinesKind::Survey)),
            ("DEPT GR", Some(LinesKind::Log)),
            ("MD,GR,RHOB", Some(LinesKind::Log)),
            ("x,y,z,value", Some(LinesKind::Polylines)),
            ("0,1,2", None),
        ];
        for (line, kind) in cases {
            assert_eq!(kind_of_header(line), kind, "{line}");
        }
    }
}
