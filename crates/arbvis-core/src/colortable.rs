//! 256-entry RGBA colour tables, as v3o2 used one per attribute: built-ins (the seismic
//! red-white-blue, grey, and the common scientific maps from the `colorous` crate), table
//! files a user edits and saves, and an optional piecewise-linear alpha curve from the
//! scene. Entries are 8-bit in both fidelity modes: v3o2's tables were.
//!
//! Table file format (`.table`): text, `#` starts a comment, 256 lines of four integers
//! 0..255 (`r g b a`), entry 0 first.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// Names of the built-in tables.
pub const BUILTINS: &[&str] = &[
    "seismic", "grey", "viridis", "magma", "inferno", "plasma", "cividis", "turbo", "red", "green",
    "blue",
];

/// A table as a scene names it: a built-in or a file, and an optional alpha curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// A built-in name (see [`BUILTINS`]), used when `file` is absent.
    #[serde(default = "default_builtin")]
    pub builtin: String,
    /// A table file (relative to the scene's folder); wins over `colors` and `builtin`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// The table's colours written out, `[r, g, b, a]` in 0..1 from the lowest value to
    /// the highest, 2 to [`MAX_COLORS`] of them, spread evenly and interpolated linearly
    /// to the 256 entries (a matplotlib colormap sampled, an array from Python); wins over
    /// `builtin`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub colors: Vec<[f64; 4]>,
    /// Alpha as a piecewise-linear curve through `[position 0..1, alpha 0..1]` points,
    /// replacing the table's own alpha.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub alpha: Vec<[f64; 2]>,
    /// Alpha from the data's own distribution ([`alpha_from_histogram`]) instead of the
    /// table's: by default (`None`) for a survey's attribute (SEG-Y, a store) whose scene gives no
    /// `alpha`, no `file` and no `colors`; `false` keeps the table's own alpha, `true` asks for it on
    /// any volume.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_from_data: Option<bool>,
}

fn default_builtin() -> String {
    "grey".into()
}

impl TableSpec {
    /// A built-in table with its own alpha.
    pub fn builtin(name: &str) -> TableSpec {
        TableSpec {
            builtin: name.into(),
            file: None,
            colors: Vec::new(),
            alpha: Vec::new(),
            alpha_from_data: None,
        }
    }

    /// Whether the alpha is made from the data's distribution, for a volume that is (or
    /// is not) a survey.
    pub fn wants_alpha_from_data(&self, survey: bool) -> bool {
        self.alpha.is_empty()
            && self.file.is_none()
            && self.colors.is_empty()
            && self.alpha_from_data.unwrap_or(survey)
    }

    /// Check what can be checked without reading files: the built-in name and the alpha
    /// curve. The error names the key (`builtin` or `alpha`).
    pub fn validate(&self) -> Result<(), crate::vocab::FieldError> {
        use crate::vocab::FieldError;
        if !self.colors.is_empty() {
            check_colors(&self.colors).map_err(|e| FieldError::new("colors", e.to_string()))?;
        }
        if self.file.is_none()
            && self.colors.is_empty()
            && !BUILTINS.contains(&self.builtin.as_str())
        {
            return Err(FieldError::new(
                "builtin",
                format!(
                    "no built-in colour table {:?}; built-ins: {}",
                    crate::input::shorten(&self.builtin, 40),
                    BUILTINS.join(", ")
                ),
            ));
        }
        if !self.alpha.is_empty() {
            check_alpha_curve(&self.alpha).map_err(|m| FieldError::new("alpha", m.to_string()))?;
        }
        Ok(())
    }

    /// Build the table; relative files are read from `base`.
    pub fn build(&self, base: &Path) -> Result<ColorTable, TableError> {
        let mut table = match &self.file {
            Some(f) => ColorTable::load(&base.join(f))?,
            None if !self.colors.is_empty() => {
                ColorTable::from_colors(&self.colors).map_err(TableError::Colors)?
            }
            None => ColorTable::builtin(&self.builtin)?,
        };
        if !self.alpha.is_empty() {
            table.set_alpha_curve(&self.alpha)?;
        }
        Ok(table)
    }
}

/// The most colours a table's `colors` may list.
pub const MAX_COLORS: usize = 4096;

/// Colours written out that cannot make a table.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ColorsError {
    /// Too few or too many.
    #[error("{0} colours; a table lists 2 to {MAX_COLORS}")]
    Count(usize),
    /// A channel outside 0..1 (or not a number).
    #[error("colour {index} is {color:?}: r, g, b and a are in 0..1")]
    Channel {
        /// Which colour.
        index: usize,
        /// Its channels.
        color: [f64; 4],
    },
}

/// Why `colors` cannot make a table, if they cannot.
fn check_colors(colors: &[[f64; 4]]) -> Result<(), ColorsError> {
    if !(2..=MAX_COLORS).contains(&colors.len()) {
        return Err(ColorsError::Count(colors.len()));
    }
    if let Some(index) = colors
        .iter()
        .position(|c| c.iter().any(|v| !(0.0..=1.0).contains(v)))
    {
        return Err(ColorsError::Channel {
            index,
            color: colors[index],
        });
    }
    Ok(())
}

impl Default for TableSpec {
    fn default() -> Self {
        TableSpec::builtin("grey")
    }
}

/// An alpha per level from how often the levels occur (`counts`, 256 of them). With `p`
/// the share of values lying closer to the median level than this one: clear for the
/// closer half (`p <= 0.5`), then `((p - 0.5) / 0.5)^2`, opaque for the farthest. The
/// common amplitudes (noise, the weak background of a seismic section) vanish and the
/// rare strong ones (reflections, on either side for signed data) stand out, whatever
/// the quantization did to the range.
pub fn alpha_from_histogram(counts: &[u64; 256]) -> [u8; 256] {
    let total: u64 = counts.iter().sum();
    if total == 0 {
        return [0; 256];
    }
    let mut seen = 0;
    let median = counts
        .iter()
        .position(|&c| {
            seen += c;
            2 * seen >= total
        })
        .unwrap_or(128) as i32;
    // Values at each distance from the median, then the share strictly closer.
    let mut at_distance = [0u64; 257];
    for (k, &c) in counts.iter().enumerate() {
        at_distance[(k as i32 - median).unsigned_abs() as usize] += c;
    }
    let mut closer = [0f64; 257];
    let mut sum = 0;
    for d in 0..257 {
        closer[d] = sum as f64 / total as f64;
        sum += at_distance[d];
    }
    std::array::from_fn(|k| {
        let share = closer[(k as i32 - median).unsigned_abs() as usize];
        let ramp = ((share - 0.5) / 0.5).max(0.0);
        (ramp * ramp * 255.0).round() as u8
    })
}

/// A colour table that cannot be made: an unknown built-in, a table file that cannot be
/// read or is not 256 lines of `r g b a`, or an alpha curve out of range.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// No built-in table of this name.
    #[error("no built-in colour table {0:?}; built-ins: {builtins}", builtins = BUILTINS.join(", "))]
    NoBuiltin(String),
    /// The table file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A line that is not four integers 0..255.
    #[error("{origin}:{line}: expected four integers 0..255 (r g b a), found {found:?}")]
    Line {
        /// The file (or text) the table came from.
        origin: String,
        /// 1-based line.
        line: usize,
        /// What the line holds (shortened).
        found: String,
    },
    /// A 257th entry.
    #[error("{origin}:{line}: more than 256 entries")]
    TooMany {
        /// The file (or text) the table came from.
        origin: String,
        /// 1-based line of the 257th entry.
        line: usize,
    },
    /// Fewer than 256 entries.
    #[error("{origin}: {entries} entries; a colour table has exactly 256")]
    Count {
        /// The file (or text) the table came from.
        origin: String,
        /// How many it holds.
        entries: usize,
    },
    /// Colours written out that cannot make a table.
    #[error("colors: {0}")]
    Colors(#[from] ColorsError),
    /// An alpha curve whose points are outside 0..1 or not ascending.
    #[error("alpha curve {0}: points must be [position, alpha] in 0..1, positions ascending")]
    AlphaCurve(String),
}

/// 256 RGBA entries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColorTable {
    /// Entry `k` is the colour of quantized value `k`.
    pub entries: Vec<[u8; 4]>,
}

impl ColorTable {
    /// The table of `colors` (`[r, g, b, a]` in 0..1, 2 to [`MAX_COLORS`]) spread evenly
    /// over the 256 entries and interpolated linearly between them.
    pub fn from_colors(colors: &[[f64; 4]]) -> Result<ColorTable, ColorsError> {
        check_colors(colors)?;
        let last = (colors.len() - 1) as f64;
        let entries = (0..256)
            .map(|k| {
                let t = k as f64 / 255.0 * last;
                let i = (t.floor() as usize).min(colors.len() - 2);
                let f = t - i as f64;
                std::array::from_fn(|c| {
                    let v = colors[i][c] * (1.0 - f) + colors[i + 1][c] * f;
                    (v * 255.0).round().clamp(0.0, 255.0) as u8
                })
            })
            .collect();
        Ok(ColorTable { entries })
    }

    /// A built-in table by name. Alpha: `seismic` is opaque at both extremes and clear in
    /// the middle (`|2t - 1|`); the others ramp from 0 to 1.
    pub fn builtin(name: &str) -> Result<ColorTable, TableError> {
        let gradient = match name {
            "viridis" => Some(colorous::VIRIDIS),
            "magma" => Some(colorous::MAGMA),
            "inferno" => Some(colorous::INFERNO),
            "plasma" => Some(colorous::PLASMA),
            "cividis" => Some(colorous::CIVIDIS),
            "turbo" => Some(colorous::TURBO),
            _ => None,
        };
        let byte = |t: f64| (t * 255.0).round().clamp(0.0, 255.0) as u8;
        let entries = (0..256)
            .map(|k| {
                let t = k as f64 / 255.0;
                let ramp = byte(t);
                if let Some(g) = gradient {
                    let c = g.eval_continuous(t);
                    return Ok([c.r, c.g, c.b, ramp]);
                }
                Ok(match name {
                    "grey" => [ramp, ramp, ramp, ramp],
                    "red" => [255, 0, 0, ramp],
                    "green" => [0, 255, 0, ramp],
                    "blue" => [0, 0, 255, ramp],
                    "seismic" => {
                        // Blue (negative) through white to red (positive).
                        let (r, g, b) = if t < 0.5 {
                            let s = t * 2.0;
                            (s, s, 1.0)
                        } else {
                            let s = (1.0 - t) * 2.0;
                            (1.0, s, s)
                        };
                        [byte(r), byte(g), byte(b), byte((2.0 * t - 1.0).abs())]
                    }
                    _ => return Err(TableError::NoBuiltin(name.to_string())),
                })
            })
            .collect::<Result<Vec<_>, TableError>>()?;
        Ok(ColorTable { entries })
    }

    /// Replace alpha by the piecewise-linear curve through `points` (`[position, alpha]`,
    /// both in 0..1, positions ascending); constant beyond the ends.
    pub fn set_alpha_curve(&mut self, points: &[[f64; 2]]) -> Result<(), TableError> {
        check_alpha_curve(points)?;
        for (k, e) in self.entries.iter_mut().enumerate() {
            let t = k as f64 / 255.0;
            let a = alpha_at(points, t);
            e[3] = (a * 255.0).round() as u8;
        }
        Ok(())
    }

    /// The entries as RGBA8 bytes (a 256 x 1 texture).
    pub fn texels(&self) -> Vec<u8> {
        self.entries.iter().flatten().copied().collect()
    }

    /// Parse table text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<ColorTable, TableError> {
        let mut entries = Vec::with_capacity(256);
        for (n, line) in text.lines().enumerate() {
            let content = line.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let fields: Vec<&str> = content.split_whitespace().collect();
            let values: Option<Vec<u8>> = fields.iter().map(|f| f.parse::<u8>().ok()).collect();
            match values {
                Some(v) if v.len() == 4 && entries.len() < 256 => {
                    entries.push([v[0], v[1], v[2], v[3]])
                }
                Some(v) if v.len() == 4 => {
                    return Err(TableError::TooMany {
                        origin: origin.to_string(),
                        line: n + 1,
                    })
                }
                _ => {
                    return Err(TableError::Line {
                        origin: origin.to_string(),
                        line: n + 1,
                        found: crate::input::shorten(content, 60),
                    })
                }
            }
        }
        if entries.len() != 256 {
            return Err(TableError::Count {
                origin: origin.to_string(),
                entries: entries.len(),
            });
        }
        Ok(ColorTable { entries })
    }

    /// Read a table file.
    pub fn load(path: &Path) -> Result<ColorTable, TableError> {
        // 256 lines of four numbers with comments: 1 MiB is far beyond any real table.
        let text = crate::input::read_text(path, crate::input::MAX_SMALL_TEXT_BYTES).map_err(
            |source| TableError::Io {
                path: path.to_path_buf(),
                source,
            },
        )?;
        ColorTable::parse(&text, &path.display().to_string())
    }

    /// The table as file text.
    pub fn to_text(&self) -> String {
        let mut s =
            String::from("# arbvis colour table: 256 lines of r g b a (0..255), entry 0 first\n");
        for e in &self.entries {
            s += &format!("{} {} {} {}\n", e[0], e[1], e[2], e[3]);
        }
        s
    }

    /// Write the table file atomically.
    pub fn save(&self, path: &Path) -> Result<(), TableError> {
        crate::png_io::write_atomic(path, self.to_text().as_bytes()).map_err(|source| {
            TableError::Io {
                path: path.to_path_buf(),
                source,
            }
        })
    }
}

/// An alpha curve is at least one `[position, alpha]` point, both in 0..1, positions
/// ascending.
fn check_alpha_curve(points: &[[f64; 2]]) -> Result<(), TableError> {
    let valid = points
        .iter()
        .all(|p| p.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)))
        && points.windows(2).all(|w| w[0][0] <= w[1][0]);
    if points.is_empty() || !valid {
        let shown = crate::input::shorten(&format!("{points:?}"), 120);
        return Err(TableError::AlphaCurve(shown));
    }
    Ok(())
}

/// The piecewise-linear curve through `points` at `t`.
pub fn alpha_at(points: &[[f64; 2]], t: f64) -> f64 {
    let first = points[0];
    let last = points[points.len() - 1];
    if t <= first[0] {
        return first[1];
    }
    if t >= last[0] {
        return last[1];
    }
    for w in points.windows(2) {
        let ([x0, a0], [x1, a1]) = (w[0], w[1]);
        if t >= x0 && t <= x1 {
            return if x1 > x0 {
                a0 + (a1 - a0) * (t - x0) / (x1 - x0)
            } else {
                a1
            };
        }
    }
    last[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_has_256_entries() {
        for name in BUILTINS {
            let t = ColorTable::builtin(name).unwrap();
            assert_eq!(t.entries.len(), 256);
        }
        assert!(ColorTable::builtin("nope")
            .unwrap_err()
            .to_string()
            .contains("seismic"));
        let s = ColorTable::builtin("seismic").unwrap();
        assert_eq!(s.entries[0], [0, 0, 255, 255]);
        assert_eq!(s.entries[255], [255, 0, 0, 255]);
        assert!(s.entries[128][3] <= 1);
    }

    #[test]
    fn text_round_trip_and_errors() {
        let t = ColorTable::builtin("viridis").unwrap();
        assert_eq!(ColorTable::parse(&t.to_text(), "t").unwrap(), t);
        let mut bad = t.to_text();
        bad = bad.replacen("\n", "\n1 2 three 4\n", 1);
        let e = ColorTable::parse(&bad, "my.table").unwrap_err().to_string();
        assert!(
            e.starts_with("my.table:2:") && e.contains("four integers"),
            "{e}"
        );
        let short: String = t.to_text().lines().take(100).collect::<Vec<_>>().join("\n");
        assert!(ColorTable::parse(&short, "s")
            .unwrap_err()
            .to_string()
            .contains("99 entries"));
    }

    #[test]
    fn alpha_curve() {
        let mut t = ColorTable::builtin("grey").unwrap();
        t.set_alpha_curve(&[[0.25, 0.0], [0.5, 1.0], [0.75, 0.0]])
            .unwrap();
        assert_eq!(t.entries[0][3], 0);
        // t = 128/255 lies just past the peak: 1 - (128/255 - 0.5) / 0.25 = 0.99216 -> 253.
        assert_eq!(t.entries[128][3], 253);
        assert_eq!(t.entries[255][3], 0);
        assert!(t.set_alpha_curve(&[[0.5, 2.0]]).is_err());
        assert!(t.set_alpha_curve(&[[0.5, 0.0], [0.2, 0.0]]).is_err());
    }

    #[test]
    fn colours_written_out_spread_over_the_entries_and_win_over_the_builtin() {
        // Black to white: entry k is k (t * 255 exactly at every entry).
        let t = ColorTable::from_colors(&[[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0]]).unwrap();
        assert!(t
            .entries
            .iter()
            .enumerate()
            .all(|(k, e)| *e == [k as u8; 4]));
        // Three uneven colours: the middle entry lands between the last two (127.5 of
        // 255 is 1.0 of the 2 steps: the second colour); the ends are the ends.
        let c = [
            [0.1, 0.9, 0.3, 1.0],
            [0.7, 0.2, 0.5, 0.25],
            [1.0, 0.0, 0.0, 0.5],
        ];
        let t = ColorTable::from_colors(&c).unwrap();
        let level = |v: f64| (v * 255.0).round() as u8;
        assert_eq!(t.entries[0], c[0].map(level));
        assert_eq!(t.entries[255], c[2].map(level));
        let mid = 127.0 / 255.0 * 2.0; // entry 127 is 0.996 of the way to the second colour
        let want: [u8; 4] = std::array::from_fn(|i| level(c[0][i] * (1.0 - mid) + c[1][i] * mid));
        assert_eq!(t.entries[127], want);
        for bad in [
            vec![[0.0; 4]],
            vec![[0.0; 4]; MAX_COLORS + 1],
            vec![[0.0; 4], [1.2, 0.0, 0.0, 1.0]],
            vec![[0.0; 4], [f64::NAN, 0.0, 0.0, 1.0]],
        ] {
            assert!(ColorTable::from_colors(&bad).is_err());
        }
        let spec = TableSpec {
            builtin: "no such".into(),
            colors: c.to_vec(),
            ..TableSpec::default()
        };
        spec.validate().unwrap();
        assert_eq!(spec.build(Path::new(".")).unwrap(), t);
        assert!(
            !spec.wants_alpha_from_data(true),
            "the colours' own alpha is kept"
        );
        let e = TableSpec {
            colors: vec![[0.0; 4]],
            ..TableSpec::default()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.key, "colors");
    }
}
