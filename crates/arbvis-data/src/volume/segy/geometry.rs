//! A survey's proportions: the size of one grid step along the samples, the crosslines and
//! the inlines, so that a box drawn from a SEG-Y file has the survey's shape.
//!
//! Traces: the distance between the CDP coordinates (trace bytes 181-188, scaled by the
//! coordinate scalar of bytes 71-72) of the grid's corner traces, over the steps between
//! them. Where the file has none (all zero, equal, or in arc seconds, byte 89-90 = 2) the
//! bins are taken as [`ASSUMED_BIN_M`], the commonest bin of land and marine surveys, and
//! `inspect` says so. Samples: the sample interval in time shown as depth at
//! [`VELOCITY_M_S`] (one millisecond of two-way time as one metre), the convention of
//! seismic viewers' default vertical scale; a scene's `vertical_exaggeration` stretches it.

/// The velocity that turns two-way time into depth for display: 2000 m/s, so one
/// millisecond of two-way time is one metre.
pub const VELOCITY_M_S: f64 = 2000.0;

/// The bin size taken where the file has no usable CDP coordinates (metres).
pub const ASSUMED_BIN_M: f64 = 25.0;

/// Where the trace spacing came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BinsFrom {
    /// The CDP coordinates of the corner traces.
    Coordinates,
    /// None usable: [`ASSUMED_BIN_M`].
    Assumed,
}

/// One grid step along the samples, crosslines and inlines, in metres (samples as depth
/// at [`VELOCITY_M_S`]), and where the trace steps came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Metres per sample, crossline step and inline step.
    pub spacing: [f64; 3],
    /// Whether the trace steps were measured.
    pub bins: BinsFrom,
    /// Where the grid lies on the map, from its corner traces' CDP coordinates.
    pub map: Option<MapFrame>,
}

/// A survey grid on the map: its first trace's CDP coordinates and the unit directions in
/// which crossline and inline indices grow (what places it in a layered scene's world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapFrame {
    /// CDP x and y of the trace at the first inline and crossline.
    pub origin: [f64; 2],
    /// Unit map direction of growing crossline index.
    pub crossline: [f64; 2],
    /// Unit map direction of growing inline index.
    pub inline: [f64; 2],
}

impl MapFrame {
    /// The frame of a grid of `nj` crosslines by `nk` inlines from the CDP coordinates of
    /// three corner traces (`at(k, j)`); None where one is missing or the grid has a
    /// single line either way (no direction), or the two directions are not independent.
    pub fn of_corners(
        nj: usize,
        nk: usize,
        mut at: impl FnMut(usize, usize) -> Option<[f64; 2]>,
    ) -> Option<MapFrame> {
        if nj < 2 || nk < 2 {
            return None;
        }
        let origin = at(0, 0)?;
        let unit = |p: [f64; 2]| {
            let d = [p[0] - origin[0], p[1] - origin[1]];
            let n = d[0].hypot(d[1]);
            (n > 0.0 && n.is_finite()).then(|| [d[0] / n, d[1] / n])
        };
        let crossline = unit(at(0, nj - 1)?)?;
        let inline = unit(at(nk - 1, 0)?)?;
        let cross = crossline[0] * inline[1] - crossline[1] * inline[0];
        (cross.abs() > 0.1).then_some(MapFrame {
            origin,
            crossline,
            inline,
        })
    }
}

impl Geometry {
    /// What `inspect` prints.
    pub fn describe(&self) -> String {
        let [s, x, i] = self.spacing;
        let from = match self.bins {
            BinsFrom::Coordinates => "from the CDP coordinates of the corner traces".to_string(),
            BinsFrom::Assumed => format!(
                "no usable CDP coordinates (bytes 181-188): {ASSUMED_BIN_M} m bins assumed; a scene's spacing sets them"
            ),
        };
        let map = match &self.map {
            Some(m) => {
                let azimuth = |d: [f64; 2]| round(d[0].atan2(d[1]).to_degrees().rem_euclid(360.0));
                format!(
                    "\nmap: first trace at CDP ({}, {}); inline numbers grow toward {} degrees, crossline numbers toward {} (from grid north, clockwise); placed there in a layered scene",
                    round(m.origin[0]),
                    round(m.origin[1]),
                    azimuth(m.inline),
                    azimuth(m.crossline)
                )
            }
            None => "\nmap: no corner CDP coordinates; in a layered scene the first trace lies at the origin".into(),
        };
        format!(
            "trace spacing: {} m between crosslines, {} m between inlines ({from})\nsample spacing shown: {} m ({} ms of two-way time at {VELOCITY_M_S} m/s){map}",
            round(x),
            round(i),
            round(s),
            round(s * 2000.0 / VELOCITY_M_S)
        )
    }
}

fn round(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// The CDP x and y of a trace header, scaled; `None` in arc seconds.
fn cdp(header: &[u8], big: bool) -> Option<[f64; 2]> {
    let i16_at = |at: usize| {
        let a = [header[at], header[at + 1]];
        if big {
            i16::from_be_bytes(a)
        } else {
            i16::from_le_bytes(a)
        }
    };
    let i32_at = |at: usize| super::header_i32(header, at, big);
    if i16_at(88) == 2 {
        return None;
    }
    let scalar = match i16_at(70) {
        0 => 1.0,
        s if s < 0 => 1.0 / -(s as f64),
        s => s as f64,
    };
    Some([i32_at(180) as f64 * scalar, i32_at(184) as f64 * scalar])
}

/// The geometry of a grid of `nj` crosslines by `nk` inlines sampled every `interval_us`;
/// `header(k, j)` is the header of the trace at inline index `k`, crossline index `j`
/// (`None` where no trace is); the trace steps from their CDP coordinates
/// ([`trace_steps`], the live traces at `spread` where a corner is missing).
pub(crate) fn geometry(
    interval_us: u32,
    nj: usize,
    nk: usize,
    big: bool,
    spread: &[(usize, usize)],
    mut header: impl FnMut(usize, usize) -> Option<[u8; 240]>,
) -> Geometry {
    let sample = interval_us as f64 / 1000.0 * VELOCITY_M_S / 2000.0;
    let sample = if sample > 0.0 { sample } else { 1.0 };
    let mut at = |k, j| header(k, j).and_then(|h| cdp(&h, big));
    let map = MapFrame::of_corners(nj, nk, &mut at);
    let ([crossline, inline], bins) = trace_steps(nj, nk, spread, at);
    Geometry {
        spacing: [sample, crossline, inline],
        bins,
        map,
    }
}

/// A survey's proportions `[sample, crossline, inline]` in metres, as a SEG-Y file's are
/// drawn: a sample axis `(domain, step)` in time (ms) at [`VELOCITY_M_S`] two-way (one
/// millisecond as one metre), one in depth as it is (else one metre a sample); the trace
/// steps from the live traces' map coordinates (`cdp[0]` x, `cdp[1]` y, at `k * nj + j`
/// for inline index `k`, crossline index `j`) as a SEG-Y's from its CDP coordinates
/// ([`trace_steps`]), else [`ASSUMED_BIN_M`] bins. What MDIO datasets and surveys handed
/// over in memory are measured by.
pub fn survey_spacing(
    cdp: Option<&[Vec<f64>; 2]>,
    live: Option<&[bool]>,
    [nj, nk]: [usize; 2],
    axis: Option<(&str, f64)>,
) -> [f64; 3] {
    let sample = match axis {
        Some(("time", step)) => step.abs() * VELOCITY_M_S / 2000.0,
        Some(("depth", step)) => step.abs(),
        _ => 1.0,
    };
    let sample = if sample.is_finite() && sample > 0.0 {
        sample
    } else {
        1.0
    };
    // A live trace with finite coordinates (one at the map's origin is a dead one's zeros).
    let at = |k: usize, j: usize| {
        let t = k * nj + j;
        let [x, y] = cdp?;
        let (x, y) = (*x.get(t)?, *y.get(t)?);
        let live = live.is_none_or(|l| l.get(t) == Some(&true));
        (live && x.is_finite() && y.is_finite() && (x, y) != (0.0, 0.0)).then_some([x, y])
    };
    let spread: Vec<(usize, usize)> = (0..nk).flat_map(|k| (0..nj).map(move |j| (k, j))).collect();
    let ([crossline, inline], _) = trace_steps(nj, nk, &spread, at);
    [sample, crossline, inline]
}

/// The trace steps `[crossline, inline]` in map units of a grid of `nj` crosslines by
/// `nk` inlines whose trace at inline index `k`, crossline index `j` lies at `at(k, j)`
/// (`None`: no trace, or no coordinates): from the three corners (0, 0), (0, nj - 1) and
/// (nk - 1, 0) where all three hold a trace, else (an irregular survey's missing corner)
/// from a plane fitted through the traces at `spread` ([`fit_steps`]); one measured step
/// stands for the other where the grid has a single line that way, else
/// [`ASSUMED_BIN_M`]. What SEG-Y files and MDIO datasets are both measured by.
pub(crate) fn trace_steps(
    nj: usize,
    nk: usize,
    spread: &[(usize, usize)],
    mut at: impl FnMut(usize, usize) -> Option<[f64; 2]>,
) -> ([f64; 2], BinsFrom) {
    let step = |a: Option<[f64; 2]>, b: Option<[f64; 2]>, n: usize| -> Option<f64> {
        let (a, b) = (a?, b?);
        let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt() / (n - 1) as f64;
        (d.is_finite() && d > 0.0).then_some(d)
    };
    let origin = at(0, 0);
    let far_j = (nj > 1).then(|| at(0, nj - 1));
    let far_k = (nk > 1).then(|| at(nk - 1, 0));
    let corners_live = origin.is_some() && far_j != Some(None) && far_k != Some(None);
    let (crossline, inline) = if corners_live {
        (
            far_j.and_then(|b| step(origin, b, nj)),
            far_k.and_then(|b| step(origin, b, nk)),
        )
    } else {
        let points: Vec<_> = spread
            .iter()
            .filter_map(|&(k, j)| at(k, j).map(|c| (j as f64, k as f64, c)))
            .collect();
        fit_steps(&points)
    };
    // One measured step stands for the other where the grid has a single line that way.
    match (crossline, inline) {
        (Some(x), Some(i)) => ([x, i], BinsFrom::Coordinates),
        (Some(x), None) if nk == 1 => ([x, x], BinsFrom::Coordinates),
        (None, Some(i)) if nj == 1 => ([i, i], BinsFrom::Coordinates),
        _ => ([ASSUMED_BIN_M, ASSUMED_BIN_M], BinsFrom::Assumed),
    }
}

/// A live trace for [`fit_steps`]: its crossline index, inline index and CDP `[x, y]`.
pub(crate) type TracePoint = (f64, f64, [f64; 2]);

/// The CDP step per crossline index and per inline index of a plane `c = o + j u + k v`
/// fitted by least squares through the points; `None` along an axis the points do not
/// span (or whose step is zero or not finite).
pub(crate) fn fit_steps(points: &[TracePoint]) -> (Option<f64>, Option<f64>) {
    let Some(first) = points.first() else {
        return (None, None);
    };
    let vary_j = points.iter().any(|p| p.0 != first.0);
    let vary_k = points.iter().any(|p| p.1 != first.1);
    // Centred sums: the normal equations of the varying columns only.
    let n = points.len() as f64;
    let sum = |f: &dyn Fn(&TracePoint) -> f64| points.iter().map(f).sum::<f64>();
    let (mj, mk) = (sum(&|p| p.0) / n, sum(&|p| p.1) / n);
    let mc = [sum(&|p| p.2[0]) / n, sum(&|p| p.2[1]) / n];
    let sjj = sum(&|p| (p.0 - mj) * (p.0 - mj));
    let skk = sum(&|p| (p.1 - mk) * (p.1 - mk));
    let sjk = sum(&|p| (p.0 - mj) * (p.1 - mk));
    let mut u = [0.0; 2];
    let mut v = [0.0; 2];
    for a in 0..2 {
        let sjc = sum(&|p| (p.0 - mj) * (p.2[a] - mc[a]));
        let skc = sum(&|p| (p.1 - mk) * (p.2[a] - mc[a]));
        match (vary_j, vary_k) {
            (true, true) => {
                let det = sjj * skk - sjk * sjk;
                if det.abs() <= 1e-12 * sjj * skk {
                    return (None, None);
                }
                u[a] = (sjc * skk - skc * sjk) / det;
                v[a] = (skc * sjj - sjc * sjk) / det;
            }
            (true, false) => u[a] = sjc / sjj,
            (false, true) => v[a] = skc / skk,
            (false, false) => {}
        }
    }
    let length = |w: [f64; 2]| {
        let d = (w[0] * w[0] + w[1] * w[1]).sqrt();
        (d.is_finite() && d > 0.0).then_some(d)
    };
    (
        vary_j.then(|| length(u)).flatten(),
        vary_k.then(|| length(v)).flatten(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(x: i32, y: i32, scalar: i16) -> [u8; 240] {
        let mut h = [0u8; 240];
        h[70..72].copy_from_slice(&scalar.to_be_bytes());
        h[180..184].copy_from_slice(&x.to_be_bytes());
        h[184..188].copy_from_slice(&y.to_be_bytes());
        h
    }

    /// The header of trace (k, j) of a grid rotated 30 degrees, 12.5 m crossline and 37.5 m
    /// inline steps, scalar -100.
    fn rotated(k: usize, j: usize) -> [u8; 240] {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (u, v) = (j as f64 * 12.5, k as f64 * 37.5);
        let (x, y) = (500_000.0 + u * c - v * s, 6_000_000.0 + u * s + v * c);
        header((x * 100.0).round() as i32, (y * 100.0).round() as i32, -100)
    }

    #[test]
    fn steps_from_rotated_corner_coordinates() {
        let g = geometry(2000, 7, 5, true, &[], |k, j| Some(rotated(k, j)));
        assert_eq!(g.bins, BinsFrom::Coordinates);
        assert!(
            (g.spacing[1] - 12.5).abs() < 1e-3 && (g.spacing[2] - 37.5).abs() < 1e-3,
            "{g:?}"
        );
        // 2 ms of two-way time at 2000 m/s: 2 m.
        assert_eq!(g.spacing[0], 2.0);
    }

    #[test]
    fn no_coordinates_assume_the_common_bin_and_say_so() {
        let g = geometry(4000, 3, 4, true, &[], |_, _| Some(header(0, 0, 0)));
        assert_eq!(g.spacing, [4.0, ASSUMED_BIN_M, ASSUMED_BIN_M]);
        assert!(
            g.describe().contains("25 m bins assumed"),
            "{}",
            g.describe()
        );
        // Arc seconds are no lengths.
        let mut h = header(100, 200, 1);
        h[88..90].copy_from_slice(&2i16.to_be_bytes());
        let g = geometry(4000, 3, 4, true, &[], |k, j| {
            let mut h = h;
            h[180..184].copy_from_slice(&(100 + 10 * (j + k) as i32).to_be_bytes());
            Some(h)
        });
        assert_eq!(g.bins, BinsFrom::Assumed);
        // One inline: its crossline step stands for both.
        let g = geometry(4000, 3, 1, true, &[], |_, j| {
            Some(header(10 * j as i32, 0, 1))
        });
        assert_eq!(
            (g.spacing[1], g.spacing[2], g.bins),
            (10.0, 10.0, BinsFrom::Coordinates)
        );
    }

    #[test]
    fn a_missing_corner_fits_the_steps_through_the_live_traces() {
        // The rotated grid again, its (0, 0) corner dead: the plane through the live
        // traces at the spread gives the same steps.
        let at = |k: usize, j: usize| (k >= 2 || j >= 3).then(|| rotated(k, j));
        let spread = [(0, 3), (0, 6), (2, 0), (2, 6), (4, 0), (4, 6)];
        let g = geometry(2000, 7, 5, true, &spread, at);
        assert_eq!(g.bins, BinsFrom::Coordinates);
        assert!(
            (g.spacing[1] - 12.5).abs() < 1e-3 && (g.spacing[2] - 37.5).abs() < 1e-3,
            "{g:?}"
        );
        // Points on one inline measure the crossline step only; none, nothing.
        let one = [(0.0, 0.0, [0.0, 0.0]), (4.0, 0.0, [30.0, 40.0])];
        assert_eq!(fit_steps(&one), (Some(12.5), None));
        assert_eq!(fit_steps(&[]), (None, None));
    }
}
