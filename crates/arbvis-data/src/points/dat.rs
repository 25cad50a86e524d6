//! The seed's `.dat` text: one point per line, whitespace-separated numbers (19 in
//! ReconMS's export), of which x, y, z and six properties are used.
//!
//! Decisions:
//! - **Default column order.** The seed names the properties it used but not their
//!   columns, so this order is ours (1-based): x 1, y 2, z 3, layer 4, facies 5, fault 6,
//!   porosity 7, amplitude 8, joint dip 9; columns 10-19 are ReconMS's other properties,
//!   unknown, and dropped unless listed in `keep` (kept as attributes `col10`, ...). A
//!   scene overrides any of these, and `0` leaves a property out:
//!   `columns = { count = 5, layer = 0, facies = 0, fault = 0, porosity = 4, amplitude = 5, joint_dip = 0 }`.
//! - **Lines.** Blank lines and lines whose first non-blank character is `#` are
//!   skipped; `\r\n` endings are accepted. Every other line must hold exactly `count`
//!   values, each a number (Rust's float syntax: `3`, `-1.5e3`, `NaN`, `inf`); every
//!   value is checked, used or not, so a damaged file is noticed. Bytes that are not
//!   UTF-8 are accepted in comments (Windows exports often carry Latin-1 there).
//! - **Values.** x, y, z must be finite. Layer, facies and fault are ids: integers
//!   (written `3` or `3.0`) within i32. Other properties are f32 and may be NaN or
//!   infinite: they are kept and counted in the statistics.
//! - **Errors** give the line and the column (character) of the value, its number on
//!   the line and its name.
//! - **Speed.** The text is cut at line ends into chunks parsed in parallel (rayon);
//!   line numbers are put back together afterwards.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::progress::Progress;
use super::{
    read_file, CloudParts, PointCloud, PointsError, Values, AMPLITUDE, FACIES, FAULT, JOINT_DIP,
    LAYER, POROSITY,
};

/// A `.dat` file as a scene names it: `{ path = "s.dat", columns = { ... } }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatSpec {
    /// The file (relative to the scene's folder).
    pub path: PathBuf,
    /// Which column holds what; the defaults above when left out.
    #[serde(default)]
    pub columns: DatColumns,
}

/// Which 1-based column holds what; `0` for a property that is not in the file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DatColumns {
    /// Values on every point line (19 in the seed).
    pub count: usize,
    /// Column of x.
    pub x: usize,
    /// Column of y.
    pub y: usize,
    /// Column of z.
    pub z: usize,
    /// Column of the layer id (integer).
    pub layer: usize,
    /// Column of the facies id (integer, -999 = undefined).
    pub facies: usize,
    /// Column of the fault id (integer, negative = not a fault).
    pub fault: usize,
    /// Column of the porosity.
    pub porosity: usize,
    /// Column of the seismic amplitude.
    pub amplitude: usize,
    /// Column of the joint dip.
    pub joint_dip: usize,
    /// Further columns kept as real attributes named `col<N>`.
    pub keep: Vec<usize>,
}

impl Default for DatColumns {
    fn default() -> Self {
        DatColumns {
            count: 19,
            x: 1,
            y: 2,
            z: 3,
            layer: 4,
            facies: 5,
            fault: 6,
            porosity: 7,
            amplitude: 8,
            joint_dip: 9,
            keep: Vec::new(),
        }
    }
}

/// Most values a line may be declared to hold.
const MAX_COUNT: usize = 4096;

/// What one column becomes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slot {
    Unused,
    Coord(usize),
    Int(usize),
    Float(usize),
}

/// The columns resolved: one slot per column and the attribute names in order.
struct Layout {
    slots: Vec<Slot>,
    names: Vec<(String, bool)>,
}

impl DatColumns {
    fn layout(&self) -> Result<Layout, PointsError> {
        if self.count < 3 || self.count > MAX_COUNT {
            return Err(PointsError::Invalid(format!(
                ".dat columns: count = {} must be between 3 and {MAX_COUNT}",
                self.count
            )));
        }
        let mut slots = vec![Slot::Unused; self.count];
        let mut names = Vec::new();
        let mut place = |what: String, column: usize, slot: Slot| {
            if column == 0 || column > self.count {
                return Err(PointsError::Invalid(format!(
                    ".dat columns: {what} = {column} is not a column of 1..{}",
                    self.count
                )));
            }
            if slots[column - 1] != Slot::Unused {
                return Err(PointsError::Invalid(format!(
                    ".dat columns: column {column} is mapped twice ({what} and another)"
                )));
            }
            slots[column - 1] = slot;
            Ok(())
        };
        for (a, (name, column)) in [("x", self.x), ("y", self.y), ("z", self.z)]
            .into_iter()
            .enumerate()
        {
            place(name.to_string(), column, Slot::Coord(a))?;
        }
        let seed = [
            (LAYER, self.layer, true),
            (FACIES, self.facies, true),
            (FAULT, self.fault, true),
            (POROSITY, self.porosity, false),
            (AMPLITUDE, self.amplitude, false),
            (JOINT_DIP, self.joint_dip, false),
        ];
        for (name, column, int) in seed {
            if column == 0 {
                continue;
            }
            let k = names.len();
            place(
                name.to_string(),
                column,
                if int { Slot::Int(k) } else { Slot::Float(k) },
            )?;
            names.push((name.to_string(), int));
        }
        for &column in &self.keep {
            let k = names.len();
            place(format!("keep {column}"), column, Slot::Float(k))?;
            names.push((format!("col{column}"), false));
        }
        Ok(Layout { slots, names })
    }
}

/// Read a `.dat` file with `columns`.
pub fn read(path: &Path, columns: &DatColumns) -> Result<PointCloud, PointsError> {
    let bytes = read_file(path)?;
    parse(path, &bytes, columns)
}

/// Parse `.dat` text named `name` with `columns`.
pub fn parse(name: &Path, bytes: &[u8], columns: &DatColumns) -> Result<PointCloud, PointsError> {
    let layout = columns.layout().map_err(|e| match e {
        PointsError::Invalid(m) => PointsError::Invalid(format!("{}: {m}", name.display())),
        other => other,
    })?;
    let chunks = split_lines(bytes, chunk_size(bytes.len()));
    let lines: usize = chunks.par_iter().map(|c| count_lines(c)).sum();
    // Every line may be a point: the chunks' columns and the joined ones are held
    // together, then the cloud is made from the joined ones.
    let attributes = layout.names.len() as u64;
    let estimate = arbvis_core::budget::times(lines as u64, 2 * (24 + 4 * attributes))
        .max(super::footprint(
            lines as u64,
            layout.names.len(),
            false,
            false,
        ))
        .saturating_add(bytes.len() as u64);
    arbvis_core::budget::check(format!("the points of {lines} lines"), estimate).map_err(|e| {
        PointsError::text(
            name,
            1,
            1,
            format!("the file's {lines} lines may each hold a point: {e}"),
        )
    })?;
    // A bar only where it will be drawn (a point line has 16+ bytes).
    let progress =
        if bytes.len() as u64 >= super::progress::MIN_POINTS * 16 && super::progress::enabled() {
            Progress::new(lines as u64, &format!("reading {}", name.display()))
        } else {
            Progress::hidden()
        };
    let parsed: Vec<Chunk> = chunks
        .par_iter()
        .map(|c| {
            let chunk = parse_chunk(c, &layout);
            progress.inc(chunk.lines as u64);
            chunk
        })
        .collect();
    drop(progress);
    let mut first_line = 1;
    for chunk in &parsed {
        if let Some(e) = &chunk.error {
            return Err(PointsError::text(
                name,
                first_line + e.line,
                e.column,
                e.message.clone(),
            ));
        }
        first_line += chunk.lines;
    }
    let total: usize = parsed.iter().map(|c| c.positions.len()).sum();
    let too_big = |_| {
        PointsError::Invalid(format!(
            "{}: cannot allocate memory for {total} points",
            name.display()
        ))
    };
    let mut positions = Vec::new();
    positions.try_reserve_exact(total).map_err(too_big)?;
    let mut attributes: Vec<(String, Values)> = Vec::new();
    for (name, int) in &layout.names {
        let values = if *int {
            let mut v = Vec::new();
            v.try_reserve_exact(total).map_err(too_big)?;
            Values::Int(v)
        } else {
            let mut v = Vec::new();
            v.try_reserve_exact(total).map_err(too_big)?;
            Values::Float(v)
        };
        attributes.push((name.clone(), values));
    }
    for chunk in parsed {
        positions.extend_from_slice(&chunk.positions);
        for ((_, all), part) in attributes.iter_mut().zip(chunk.columns) {
            match (all, part) {
                (Values::Int(a), Values::Int(p)) => a.extend_from_slice(&p),
                (Values::Float(a), Values::Float(p)) => a.extend_from_slice(&p),
                _ => unreachable!("chunks share one layout"),
            }
        }
    }
    PointCloud::from_parts(CloudParts {
        positions,
        attributes,
        rgb: None,
        normals: None,
    })
    .map_err(|m| PointsError::Invalid(format!("{}: {m}", name.display())))
}

fn chunk_size(len: usize) -> usize {
    (len / (4 * rayon::current_num_threads().max(1))).clamp(1 << 16, 1 << 24)
}

/// `bytes` cut into pieces of about `target` bytes, each ending after a `\n` (the last
/// one at the end of the text).
fn split_lines(bytes: &[u8], target: usize) -> Vec<&[u8]> {
    let mut chunks = Vec::new();
    let mut rest = bytes;
    while !rest.is_empty() {
        let end = if rest.len() <= target {
            rest.len()
        } else {
            rest[target..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |p| target + p + 1)
        };
        let (head, tail) = rest.split_at(end);
        chunks.push(head);
        rest = tail;
    }
    chunks
}

/// Lines in a chunk: its `\n`s, plus one for a last line without one.
fn count_lines(chunk: &[u8]) -> usize {
    let newlines = chunk.iter().filter(|&&b| b == b'\n').count();
    newlines + usize::from(chunk.last().is_some_and(|&b| b != b'\n'))
}

struct ChunkError {
    /// 0-based line within the chunk.
    line: usize,
    column: usize,
    message: String,
}

struct Chunk {
    lines: usize,
    positions: Vec<[f64; 3]>,
    columns: Vec<Values>,
    error: Option<ChunkError>,
}

fn parse_chunk(text: &[u8], layout: &Layout) -> Chunk {
    let mut chunk = Chunk {
        lines: 0,
        positions: Vec::new(),
        columns: layout
            .names
            .iter()
            .map(|(_, int)| {
                if *int {
                    Values::Int(Vec::new())
                } else {
                    Values::Float(Vec::new())
                }
            })
            .collect(),
        error: None,
    };
    for line in text.split_inclusive(|&b| b == b'\n') {
        let index = chunk.lines;
        chunk.lines += 1;
        if let Err((column, message)) = parse_line(line, layout, &mut chunk) {
            chunk.error = Some(ChunkError {
                line: index,
                column,
                message,
            });
            return chunk;
        }
    }
    chunk
}

/// Parse one line into `chunk`; on error the column (characters, 1-based) and message
/// (the chunk is then dropped, so values pushed before the error do not matter).
fn parse_line(line: &[u8], layout: &Layout, chunk: &mut Chunk) -> Result<(), (usize, String)> {
    let body = line.strip_suffix(b"\n").unwrap_or(line);
    let body = body.strip_suffix(b"\r").unwrap_or(body);
    let first = body.iter().position(|b| !b.is_ascii_whitespace());
    let Some(first) = first else {
        return Ok(()); // blank
    };
    if body[first] == b'#' {
        return Ok(());
    }
    let count = layout.slots.len();
    let mut position = [0.0f64; 3];
    let mut found = 0;
    let mut start = first;
    while start < body.len() {
        let end = body[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .map_or(body.len(), |p| start + p);
        let token = &body[start..end];
        if found == count {
            let total = found + tokens(&body[start..]);
            return Err((
                column(body, start),
                format!("expected {count} values on the line, found {total}"),
            ));
        }
        let slot = layout.slots[found];
        let what = || describe_column(found, slot, layout);
        let value = std::str::from_utf8(token)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| {
                (
                    column(body, start),
                    format!(
                        "{}: expected a number, found \"{}\"",
                        what(),
                        arbvis_core::input::shorten(&String::from_utf8_lossy(token), 40)
                    ),
                )
            })?;
        match slot {
            Slot::Unused => {}
            Slot::Coord(a) => {
                if !value.is_finite() {
                    return Err((
                        column(body, start),
                        format!("{}: a coordinate must be finite, found {value}", what()),
                    ));
                }
                position[a] = value;
            }
            Slot::Int(k) => {
                if value.fract() != 0.0 || !(i32::MIN as f64..=i32::MAX as f64).contains(&value) {
                    return Err((
                        column(body, start),
                        format!(
                            "{}: expected an integer id, found \"{}\"",
                            what(),
                            arbvis_core::input::shorten(&String::from_utf8_lossy(token), 40)
                        ),
                    ));
                }
                if let Values::Int(c) = &mut chunk.columns[k] {
                    c.push(value as i32);
                }
            }
            Slot::Float(k) => {
                if let Values::Float(c) = &mut chunk.columns[k] {
                    c.push(value as f32);
                }
            }
        }
        found += 1;
        start = body[end..]
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .map_or(body.len(), |p| end + p);
    }
    if found < count {
        return Err((
            column(body, body.len()),
            format!("expected {count} values on the line, found {found}"),
        ));
    }
    chunk.positions.push(position);
    Ok(())
}

fn tokens(text: &[u8]) -> usize {
    text.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
        .count()
}

/// 1-based character column of byte `at` of `line` (UTF-8 continuation bytes do not
/// start a character; counted without copying the line, which may be huge).
fn column(line: &[u8], at: usize) -> usize {
    line[..at].iter().filter(|&&b| b & 0xC0 != 0x80).count() + 1
}

fn describe_column(index: usize, slot: Slot, layout: &Layout) -> String {
    let name = match slot {
        Slot::Unused => "unused".to_string(),
        Slot::Coord(a) => ["x", "y", "z"][a].to_string(),
        Slot::Int(k) | Slot::Float(k) => layout.names[k].0.clone(),
    };
    format!("value {} ({name})", index + 1)
}

/// The cloud as `.dat` text in `columns`' layout: coordinates from
/// [`PointCloud::original`] with as many decimals as the f32 positions resolve
/// (`scale * 2^-24`), attributes by name, `0` in columns that map nothing or whose
/// attribute the cloud lacks. For tests and benchmarks of the reader.
pub fn write(cloud: &PointCloud, columns: &DatColumns) -> Result<String, PointsError> {
    use std::fmt::Write;
    let layout = columns.layout()?;
    let sources: Vec<Option<&Values>> = layout
        .names
        .iter()
        .map(|(name, _)| cloud.attribute(name).map(|a| &a.values))
        .collect();
    let decimals = super::decimals_for(cloud.scale * 2f64.powi(-24));
    let mut out = String::new();
    for i in 0..cloud.len() {
        let p = cloud.original(i).unwrap_or([0.0; 3]);
        for (j, slot) in layout.slots.iter().enumerate() {
            if j > 0 {
                out.push(' ');
            }
            let _ = match *slot {
                Slot::Unused => write!(out, "0"),
                Slot::Coord(a) => write!(out, "{:.*}", decimals, p[a]),
                Slot::Int(k) | Slot::Float(k) => match sources[k] {
                    Some(Values::Int(v)) => write!(out, "{}", v[i]),
                    Some(Values::Float(v)) => write!(out, "{}", v[i]),
                    None => write!(out, "0"),
                },
            };
        }
        out.push('\n');
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name() -> &'static Path {
        Path::new("t.dat")
    }

    fn line(values: &[&str]) -> String {
        values.join(" ") + "\n"
    }

    /// A 19-value line: x y z layer facies fault porosity amplitude dip + 10 more.
    fn point(x: &str, layer: &str, porosity: &str) -> String {
        let mut v = vec![
            x, "20.5", "-300.25", layer, "3", "-1", porosity, "0.7", "12",
        ];
        v.extend(["9"; 10]);
        line(&v)
    }

    #[test]
    fn default_columns_with_comments_blank_lines_and_crlf() {
        let text = format!(
            "# ReconMS export\n\n{}   \t\n# ç comment\r\n{}{}",
            point("1000.5", "0", "0.004"),
            point("1010.5", "7", "nan").replace('\n', "\r\n"),
            point("990.25", "3", "0.012").trim_end()
        );
        let c = parse(name(), text.as_bytes(), &DatColumns::default()).unwrap();
        assert_eq!(c.len(), 3);
        assert_eq!(c.ints(LAYER).unwrap(), &[0, 7, 3]);
        assert_eq!(c.ints(FACIES).unwrap(), &[3, 3, 3]);
        assert_eq!(c.ints(FAULT).unwrap(), &[-1, -1, -1]);
        let por = c.attribute(POROSITY).unwrap();
        assert_eq!(por.stats.non_finite, 1);
        assert_eq!(por.stats.min, 0.004f32 as f64);
        assert_eq!(por.stats.max, 0.012f32 as f64);
        assert_eq!(c.bounds, [[990.25, 20.5, -300.25], [1010.5, 20.5, -300.25]]);
        assert_eq!(c.origin, [1000.375, 20.5, -300.25]);
        assert_eq!(c.scale, 10.125);
        assert_eq!(c.original(2).unwrap(), [990.25, 20.5, -300.25]);
        assert!(c.attribute(LAYER).unwrap().stats.median == 3.0);
        assert!(c.attribute(JOINT_DIP).unwrap().stats.zero_range());
        assert_eq!(c.attributes.len(), 6);
    }

    #[test]
    fn latin1_bytes_in_comments_are_accepted() {
        let mut text = b"# por\xe7\xe3o\n".to_vec();
        text.extend(point("1", "0", "0.1").as_bytes());
        assert_eq!(
            parse(name(), &text, &DatColumns::default()).unwrap().len(),
            1
        );
    }

    #[test]
    fn columns_are_overridable_and_keep_adds_attributes() {
        let columns: DatColumns = toml::from_str(
            "count = 5\nx = 3\ny = 1\nz = 2\nlayer = 0\nfacies = 0\nfault = 4\nporosity = 0\namplitude = 0\njoint_dip = 0\nkeep = [5]",
        )
        .unwrap();
        let c = parse(name(), b"1 2 3 4 5.5\n-1 -2 -3 -4 6.5\n", &columns).unwrap();
        let p = c.original(0).unwrap();
        assert!(
            (0..3).all(|a| (p[a] - [3.0, 1.0, 2.0][a]).abs() < 1e-6),
            "{p:?}"
        );
        assert_eq!(c.ints(FAULT).unwrap(), &[4, -4]);
        assert_eq!(c.floats("col5").unwrap(), &[5.5, 6.5]);
        assert!(c.attribute(LAYER).is_none());
        assert_eq!(c.attributes.len(), 2);
    }

    #[test]
    fn bad_column_mappings_are_refused() {
        for (toml_text, expect) in [
            ("x = 0", "x = 0 is not a column"),
            ("porosity = 20", "porosity = 20 is not a column of 1..19"),
            ("fault = 1", "column 1 is mapped twice"),
            ("keep = [7]", "column 7 is mapped twice"),
            ("count = 2", "count = 2 must be between"),
            ("count = 100000", "must be between"),
        ] {
            let columns: DatColumns = toml::from_str(toml_text).unwrap();
            let e = parse(name(), b"", &columns).unwrap_err().to_string();
            assert!(e.contains(expect), "{toml_text}: {e}");
        }
        assert!(toml::from_str::<DatColumns>("colour = 3").is_err());
    }

    #[test]
    fn errors_name_line_and_column() {
        let good = point("1", "0", "0.1");
        let cases: Vec<(String, &str)> = vec![
            (
                format!("{good}# c\n1 2 3\n"),
                "line 3, column 6: expected 19 values on the line, found 3",
            ),
            (
                good.replace('\n', " 77\n"),
                "line 1, column 54: expected 19 values on the line, found 20",
            ),
            (
                format!("{good}{}", good.replace("0.7", "abc")),
                "line 2, column 27: value 8 (amplitude): expected a number, found \"abc\"",
            ),
            (
                good.replacen("1 ", "NaN ", 1),
                "line 1, column 1: value 1 (x): a coordinate must be finite, found NaN",
            ),
            (
                good.replace("-300.25", "-inf"),
                "line 1, column 8: value 3 (z): a coordinate must be finite, found -inf",
            ),
            (
                format!("\n\n{}", point("1", "2.5", "0")),
                "line 3, column 16: value 4 (layer): expected an integer id, found \"2.5\"",
            ),
            (
                point("1", "1e10", "0"),
                "value 4 (layer): expected an integer id, found \"1e10\"",
            ),
            (
                good.replace("12", "1,2"),
                "value 9 (joint_dip): expected a number, found \"1,2\"",
            ),
            (
                good.replace("9 9 9 9 9 9 9 9 9 9", &"x".repeat(500)),
                "(unused): expected a number, found \"xxxx",
            ),
        ];
        for (text, expect) in cases {
            let e = parse(name(), text.as_bytes(), &DatColumns::default())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("t.dat: "), "{e}");
            assert!(e.contains(expect), "{text:?}\n got: {e}\nwant: {expect}");
            assert!(e.len() < 300, "long values are shortened: {e}");
        }
    }

    #[test]
    fn ids_written_as_reals_are_accepted() {
        let text = point("1", "3.000", "0").replace(" 3 ", " -999.0 ");
        let c = parse(name(), text.as_bytes(), &DatColumns::default()).unwrap();
        assert_eq!(c.ints(LAYER).unwrap(), &[3]);
        assert_eq!(c.ints(FACIES).unwrap(), &[-999]);
    }

    #[test]
    fn empty_and_comment_only_files_give_empty_clouds() {
        for text in ["", "\n\n", "# only\n# comments"] {
            let c = parse(name(), text.as_bytes(), &DatColumns::default()).unwrap();
            assert!(c.is_empty());
            assert_eq!(c.attributes.len(), 6);
        }
    }

    #[test]
    fn line_numbers_survive_parallel_chunks() {
        let good = point("1.5", "2", "0.01");
        let mut text = good.repeat(30_000);
        text += "# note\n";
        text += &good.repeat(20_000);
        text += "1 2 3\n";
        assert!(text.len() > 2 << 20);
        let e = parse(name(), text.as_bytes(), &DatColumns::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 50002, column 6"), "{e}");
        let chunks = split_lines(text.as_bytes(), 1 << 16);
        assert!(chunks.len() > 10);
        assert!(chunks.iter().all(|c| c.ends_with(b"\n")));
    }

    #[test]
    fn written_section_reads_back() {
        let cloud = super::super::section::generate(&super::super::section::SectionSpec {
            points: 2000,
            seed: 5,
        })
        .unwrap();
        let text = write(&cloud, &DatColumns::default()).unwrap();
        assert_eq!(text.lines().count(), 2000);
        assert_eq!(text.lines().next().unwrap().split(' ').count(), 19);
        let back = parse(name(), text.as_bytes(), &DatColumns::default()).unwrap();
        assert_eq!(back.len(), 2000);
        for name in [LAYER, FACIES, FAULT] {
            assert_eq!(back.ints(name), cloud.ints(name), "{name}");
        }
        for name in [POROSITY, AMPLITUDE, JOINT_DIP] {
            assert_eq!(back.floats(name), cloud.floats(name), "{name}");
        }
        for i in (0..2000).step_by(97) {
            let (a, b) = (cloud.original(i).unwrap(), back.original(i).unwrap());
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-3, "{i}: {a:?} {b:?}");
            }
        }
    }
}
