//! GOCAD TSurf (`.ts`): the triangulated surfaces interpretation tools export for
//! horizons and faults (Petrel, OpendTect, SKUA-GOCAD, GemPy).
//!
//! # Decisions
//! - A file may hold several objects (`GOCAD TSurf 1` ... `END`), each with its own vertex
//!   ids; they are read into one surface. Within an object, `TFACE` starts another face
//!   of the same surface (its vertices stay shared).
//! - `VRTX id x y z` and `PVRTX id x y z values...` define vertices; `ATOM id ref` and
//!   `PATOM id ref values...` reuse vertex `ref`'s position (an `ATOM` its values too);
//!   `TRGL a b c` names three vertex ids. Other keywords (`HEADER { ... }`, the
//!   coordinate system, `BSTONE`, `BORDER`, ...) are skipped.
//! - Properties: `PROPERTIES a b` names an object's per-vertex values, `ESIZES` their
//!   sizes (a vector property takes that many values and is not kept), `NO_DATA_VALUES`
//!   the value that marks none (NaN). Objects' properties of one name are one property;
//!   vertices without it (a `VRTX`, another object) have NaN.
//! - `ZPOSITIVE Depth` (z grows downwards: depth, or time in ms) is turned into z up, as
//!   every layer is placed: `z = -z`. `ZPOSITIVE Elevation` (the default) is kept.
//! - Every error names the line and column of the token at fault.

use std::collections::HashMap;
use std::path::Path;

use super::{Position, SurfaceError, TriangleMesh, VertexProperty};
use arbvis_core::input::words as tokens;

/// What the reader found besides the triangles (`inspect`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TsurfFacts {
    /// Objects (`GOCAD TSurf` headers) read.
    pub objects: usize,
    /// Whether z was given positive downwards (and turned).
    pub depth_positive: bool,
    /// Properties of more than one value (`ESIZES`), with their sizes: not kept.
    pub vectors: Vec<(String, usize)>,
    /// The coordinate system's lines as the first object gives them (`NAME Default`,
    /// `AXIS_UNIT "m" "m" "ms"`, `PROJECTION ...`, `DATUM ...`): shown, not applied.
    pub coordinate_system: Vec<String>,
}

/// One object's vertex ids to the surface's vertex indices.
type Ids = HashMap<u64, u32>;

/// Parse TSurf text (`name` names it in errors).
pub fn parse(name: &Path, bytes: &[u8]) -> Result<TriangleMesh, SurfaceError> {
    parse_with_facts(name, bytes).map(|(mesh, _)| mesh)
}

/// [`parse`], and what else the file said.
pub fn parse_with_facts(
    name: &Path,
    bytes: &[u8],
) -> Result<(TriangleMesh, TsurfFacts), SurfaceError> {
    let text = super::utf8(name, bytes)?;
    let mut reader = Reader::new(name);
    for (index, line) in text.lines().enumerate() {
        reader.line(index + 1, line)?;
    }
    if reader.facts.objects == 0 {
        return Err(reader.error(1, 1, "not a GOCAD TSurf: expected a `GOCAD TSurf 1` header"));
    }
    let Reader {
        vertices,
        triangles,
        facts,
        properties,
        ..
    } = reader;
    let properties = properties
        .into_iter()
        .filter(|p| !facts.vectors.iter().any(|(v, _)| *v == p.name))
        .collect();
    let mesh =
        TriangleMesh::from_indexed(name, vertices, triangles)?.with_properties(name, properties)?;
    Ok((mesh, facts))
}

/// The reader's state line by line.
struct Reader<'a> {
    name: &'a Path,
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    ids: Ids,
    /// Inside an object (after its header, before its `END`).
    open: bool,
    /// Inside a `HEADER { ... }` block.
    in_header: bool,
    /// z is positive downwards in the current object.
    depth: bool,
    facts: TsurfFacts,
    /// Every object's properties, one value per vertex read so far.
    properties: Vec<VertexProperty>,
    /// The current object's properties: index into `properties`, size, no-data value.
    object: Vec<(usize, usize, Option<f64>)>,
}

impl<'a> Reader<'a> {
    fn new(name: &'a Path) -> Reader<'a> {
        Reader {
            name,
            vertices: Vec::new(),
            triangles: Vec::new(),
            ids: Ids::new(),
            open: false,
            in_header: false,
            depth: false,
            facts: TsurfFacts::default(),
            properties: Vec::new(),
            object: Vec::new(),
        }
    }

    fn error(&self, line: usize, column: usize, message: impl Into<String>) -> SurfaceError {
        SurfaceError::format(self.name, Position::Line { line, column }, message)
    }

    /// Read one line (1-based number `n`).
    fn line(&mut self, n: usize, text: &str) -> Result<(), SurfaceError> {
        let tokens = tokens(text);
        let Some(&(column, keyword)) = tokens.first() else {
            return Ok(());
        };
        if self.in_header {
            self.in_header = !text.trim_end().ends_with('}');
            return Ok(());
        }
        match keyword {
            "GOCAD" => {
                if tokens.get(1).map(|t| t.1) != Some("TSurf") {
                    return Err(self.error(
                        n,
                        column,
                        "expected `GOCAD TSurf`: only triangulated surfaces are read",
                    ));
                }
                self.open = true;
                self.ids.clear();
                self.object.clear();
                self.depth = false;
                self.facts.objects += 1;
            }
            _ if !self.open => {
                return Err(self.error(
                    n,
                    column,
                    format!("{keyword:?} outside a `GOCAD TSurf 1` object"),
                ));
            }
            "HEADER" => self.in_header = !text.trim_end().ends_with('}'),
            "NAME" | "AXIS_NAME" | "AXIS_UNIT" | "PROJECTION" | "DATUM"
                if self.facts.objects == 1 && self.facts.coordinate_system.len() < 16 =>
            {
                let line = arbvis_core::input::shorten(text.trim(), 80);
                self.facts.coordinate_system.push(line.to_string());
            }
            "ZPOSITIVE" => match tokens.get(1).map(|t| t.1) {
                Some("Depth") => {
                    self.depth = true;
                    self.facts.depth_positive = true;
                }
                Some("Elevation") => self.depth = false,
                other => {
                    let column = tokens.get(1).map_or(column, |t| t.0);
                    return Err(self.error(
                        n,
                        column,
                        format!("ZPOSITIVE {other:?}: expected Depth or Elevation"),
                    ));
                }
            },
            "PROPERTIES" => self.declare(n, &tokens)?,
            "ESIZES" | "NO_DATA_VALUES" => self.describe(n, &tokens)?,
            "VRTX" | "PVRTX" => self.vertex(n, &tokens)?,
            "ATOM" | "PATOM" => self.atom(n, &tokens)?,
            "TRGL" => self.triangle(n, &tokens)?,
            "END" => self.open = false,
            _ => {}
        }
        Ok(())
    }

    /// `VRTX id x y z`.
    fn vertex(&mut self, n: usize, tokens: &[(usize, &str)]) -> Result<(), SurfaceError> {
        let id = self.id(n, tokens, 1)?;
        let mut p = [0.0; 3];
        for (a, value) in p.iter_mut().enumerate() {
            let (column, token) = self.token(n, tokens, 2 + a, "x, y and z")?;
            *value = token
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    self.error(
                        n,
                        column,
                        format!("{token:?}: a coordinate must be a finite number"),
                    )
                })?;
        }
        if self.depth {
            p[2] = -p[2];
        }
        let values = match tokens[0].1 {
            "PVRTX" => self.values(n, tokens, 5)?,
            _ => Vec::new(),
        };
        self.add(n, tokens[1].0, id, p)?;
        self.set_values(&values);
        Ok(())
    }

    /// `ATOM id ref`: vertex `id` at vertex `ref`'s position.
    fn atom(&mut self, n: usize, tokens: &[(usize, &str)]) -> Result<(), SurfaceError> {
        let id = self.id(n, tokens, 1)?;
        let of = self.index(n, tokens, 2)? as usize;
        let p = self.vertices[of];
        let values = match tokens[0].1 {
            "PATOM" => self.values(n, tokens, 3)?,
            _ => Vec::new(),
        };
        self.add(n, tokens[1].0, id, p)?;
        match tokens[0].1 {
            "PATOM" => self.set_values(&values),
            _ => {
                for property in &mut self.properties {
                    *property.values.last_mut().expect("added") = property.values[of];
                }
            }
        }
        Ok(())
    }

    /// `PROPERTIES a b ...`: the current object's properties, each of size 1 until
    /// `ESIZES` says otherwise.
    fn declare(&mut self, n: usize, tokens: &[(usize, &str)]) -> Result<(), SurfaceError> {
        self.object.clear();
        for (k, &(column, name)) in tokens.iter().enumerate().skip(1) {
            if tokens[1..k].iter().any(|t| t.1 == name) {
                return Err(self.error(n, column, format!("property {name:?} named twice")));
            }
            let index = match self.properties.iter().position(|p| p.name == name) {
                Some(i) => i,
                None => {
                    self.properties.push(VertexProperty {
                        name: name.to_string(),
                        values: vec![f64::NAN; self.vertices.len()],
                    });
                    self.properties.len() - 1
                }
            };
            self.object.push((index, 1, None));
        }
        Ok(())
    }

    /// `ESIZES n ...` or `NO_DATA_VALUES v ...`, one per declared property.
    fn describe(&mut self, n: usize, tokens: &[(usize, &str)]) -> Result<(), SurfaceError> {
        let sizes = tokens[0].1 == "ESIZES";
        if tokens.len() - 1 != self.object.len() {
            let column = tokens.last().map_or(1, |t| t.0);
            return Err(self.error(
                n,
                column,
                format!(
                    "{} gives {} values for {} properties ({})",
                    tokens[0].1,
                    tokens.len() - 1,
                    self.object.len(),
                    self.declared()
                ),
            ));
        }
        for (k, &(column, token)) in tokens[1..].iter().enumerate().take(self.object.len()) {
            if sizes {
                let size = token.parse::<usize>().ok().filter(|s| (1..=64).contains(s));
                let size = size.ok_or_else(|| {
                    self.error(n, column, format!("{token:?}: a size is 1 to 64"))
                })?;
                self.object[k].1 = size;
                let name = &self.properties[self.object[k].0].name;
                if size > 1 && !self.facts.vectors.iter().any(|(v, _)| v == name) {
                    self.facts.vectors.push((name.clone(), size));
                }
            } else {
                self.object[k].2 = token.parse::<f64>().ok();
            }
        }
        Ok(())
    }

    /// The property values of a `PVRTX`/`PATOM` from token `first` on: one per declared
    /// property (NaN for no data and vector properties).
    fn values(
        &self,
        n: usize,
        tokens: &[(usize, &str)],
        first: usize,
    ) -> Result<Vec<f64>, SurfaceError> {
        let mut at = first;
        let mut out = Vec::with_capacity(self.object.len());
        for &(index, size, no_data) in &self.object {
            let Some(&(column, token)) = tokens.get(at + size - 1) else {
                let what = format!("its values ({})", self.declared());
                return Err(self.token(n, tokens, at + size - 1, &what).unwrap_err());
            };
            let value = token.parse::<f64>().map_err(|_| {
                let name = &self.properties[index].name;
                self.error(n, column, format!("{token:?}: {name} is a number"))
            })?;
            let defined = size == 1 && value.is_finite() && Some(value) != no_data;
            out.push(if defined { value } else { f64::NAN });
            at += size;
        }
        if let Some(&(column, token)) = tokens.get(at) {
            let extra = tokens.len() - at;
            return Err(self.error(
                n,
                column,
                format!(
                    "{token:?}: {extra} value(s) past the ones {} declares",
                    self.declared()
                ),
            ));
        }
        Ok(out)
    }

    /// The current object's property names, for messages.
    fn declared(&self) -> String {
        let names: Vec<&str> = self
            .object
            .iter()
            .map(|&(i, _, _)| self.properties[i].name.as_str())
            .collect();
        format!("PROPERTIES {}", names.join(" "))
    }

    /// The last vertex's values of the current object's properties (the others NaN).
    fn set_values(&mut self, values: &[f64]) {
        for (&(index, _, _), &v) in self.object.iter().zip(values) {
            *self.properties[index].values.last_mut().expect("added") = v;
        }
    }

    /// `TRGL a b c`.
    fn triangle(&mut self, n: usize, tokens: &[(usize, &str)]) -> Result<(), SurfaceError> {
        let t = [
            self.index(n, tokens, 1)?,
            self.index(n, tokens, 2)?,
            self.index(n, tokens, 3)?,
        ];
        self.triangles.push(t);
        Ok(())
    }

    fn add(&mut self, n: usize, column: usize, id: u64, p: [f64; 3]) -> Result<(), SurfaceError> {
        let index = u32::try_from(self.vertices.len())
            .map_err(|_| self.error(n, column, "more vertices than 2^32"))?;
        if self.ids.insert(id, index).is_some() {
            return Err(self.error(
                n,
                column,
                format!("vertex id {id} defined twice in this object"),
            ));
        }
        self.vertices.push(p);
        for property in &mut self.properties {
            property.values.push(f64::NAN);
        }
        Ok(())
    }

    fn token<'t>(
        &self,
        n: usize,
        tokens: &[(usize, &'t str)],
        at: usize,
        what: &str,
    ) -> Result<(usize, &'t str), SurfaceError> {
        tokens.get(at).copied().ok_or_else(|| {
            let column = tokens.last().map_or(1, |t| t.0 + t.1.chars().count());
            self.error(n, column, format!("{} needs {what}", tokens[0].1))
        })
    }

    /// The vertex id at token `at`.
    fn id(&self, n: usize, tokens: &[(usize, &str)], at: usize) -> Result<u64, SurfaceError> {
        let (column, token) = self.token(n, tokens, at, "a vertex id")?;
        token.parse::<u64>().map_err(|_| {
            self.error(
                n,
                column,
                format!("{token:?}: a vertex id is a whole number"),
            )
        })
    }

    /// The index of the vertex whose id is at token `at` (defined earlier in the object).
    fn index(&self, n: usize, tokens: &[(usize, &str)], at: usize) -> Result<u32, SurfaceError> {
        let id = self.id(n, tokens, at)?;
        self.ids.get(&id).copied().ok_or_else(|| {
            self.error(
                n,
                tokens[at].0,
                format!("vertex id {id} is not defined above in this object"),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO: &str = "GOCAD TSurf 1\nHEADER {\nname: top F3 {odd}\n}\nGOCAD_ORIGINAL_COORDINATE_SYSTEM\nNAME Default\nZPOSITIVE Depth\nEND_ORIGINAL_COORDINATE_SYSTEM\nPROPERTIES amp\nTFACE\nVRTX 10 620000.5 6074000.25 812.5\nPVRTX 11 620025.5 6074000.25 815 0.3\nVRTX 12 620000.5 6074025.25 809\nATOM 13 11\nTRGL 10 11 12\nTFACE\nVRTX 14 620025.5 6074025.25 811\nTRGL 12 13 14\nEND\nGOCAD TSurf 1\nVRTX 1 0 0 5\nVRTX 2 1 0 5\nVRTX 3 0 1 6\nTRGL 1 2 3\nEND\n";

    #[test]
    fn objects_faces_atoms_and_depth_are_read() {
        let (mesh, facts) = parse_with_facts(Path::new("h.ts"), TWO.as_bytes()).unwrap();
        assert_eq!(
            facts,
            TsurfFacts {
                objects: 2,
                depth_positive: true,
                vectors: Vec::new(),
                coordinate_system: vec!["NAME Default".into()],
            }
        );
        assert_eq!(mesh.vertices.len(), 8);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [2, 3, 4], [5, 6, 7]]);
        // Depth turned upwards; the atom at its vertex's position; the second object
        // keeps its own ids and its z (elevation).
        assert_eq!(mesh.vertices[0], [620000.5, 6074000.25, -812.5]);
        assert_eq!(mesh.vertices[3], mesh.vertices[1]);
        assert_eq!(mesh.vertices[7], [0.0, 1.0, 6.0]);
    }

    /// A property's values with NaN as None (NaN != NaN in assert_eq).
    fn values(mesh: &TriangleMesh, name: &str) -> Vec<Option<f64>> {
        let p = mesh.property(name).expect(name);
        p.values
            .iter()
            .map(|v| v.is_finite().then_some(*v))
            .collect()
    }

    #[test]
    fn properties_follow_their_vertices() {
        let mesh = parse(Path::new("h.ts"), TWO.as_bytes()).unwrap();
        // PVRTX 11 has 0.3, its ATOM 13 the same; VRTX and the second object's vertices
        // have none.
        let mut amp = vec![None; 8];
        amp[1] = Some(0.3);
        amp[3] = Some(0.3);
        assert_eq!(values(&mesh, "amp"), amp);
        // Two properties, one a vector (ESIZES 3: skipped, not kept), a no-data value,
        // a PATOM with its own values, an object that declares one of them again.
        let text = "GOCAD TSurf 1\nPROPERTIES throw dir dip\nESIZES 1 3 1\nNO_DATA_VALUES -999 -999 -99\n\
                    PVRTX 1 0 0 0 12.5 1 0 0 40\nPVRTX 2 1 0 0 -999 0 1 0 -99\nPVRTX 3 0 1 0 7 0 0 1 45.5\n\
                    PATOM 4 3 8 0 0 1 50\nTRGL 1 2 3\nTRGL 2 4 1\nEND\n\
                    GOCAD TSurf 1\nPROPERTIES dip\nPVRTX 1 5 5 5 30\nPVRTX 2 6 5 5 nan\nVRTX 3 5 6 5\nTRGL 1 2 3\nEND\n";
        let (mesh, facts) = parse_with_facts(Path::new("f.ts"), text.as_bytes()).unwrap();
        let names: Vec<&str> = mesh.properties.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["throw", "dip"]);
        assert_eq!(facts.vectors, [("dir".to_string(), 3)], "told, not drawn");
        assert_eq!(
            values(&mesh, "throw"),
            [Some(12.5), None, Some(7.0), Some(8.0), None, None, None]
        );
        assert_eq!(
            values(&mesh, "dip"),
            [
                Some(40.0),
                None,
                Some(45.5),
                Some(50.0),
                Some(30.0),
                None,
                None
            ]
        );
        assert_eq!(mesh.property("dip").unwrap().range(), Some([30.0, 50.0]));
        let cases = [
            (
                "GOCAD TSurf 1\nPROPERTIES a b\nPVRTX 1 0 0 0 1\n",
                3,
                16,
                "needs its values (PROPERTIES a b)",
            ),
            (
                "GOCAD TSurf 1\nPROPERTIES a\nPVRTX 1 0 0 0 x\n",
                3,
                15,
                "a is a number",
            ),
            (
                "GOCAD TSurf 1\nPROPERTIES a\nESIZES 0\n",
                3,
                8,
                "a size is 1 to 64",
            ),
            (
                "GOCAD TSurf 1\nPROPERTIES a b\nNO_DATA_VALUES -99999\n",
                3,
                16,
                "1 values for 2 properties (PROPERTIES a b)",
            ),
            (
                "GOCAD TSurf 1\nPROPERTIES a\nESIZES 1 1\n",
                3,
                10,
                "2 values for 1 properties",
            ),
            (
                "GOCAD TSurf 1\nPROPERTIES a b a\n",
                2,
                16,
                "property \"a\" named twice",
            ),
            (
                "GOCAD TSurf 1\nPROPERTIES a\nPVRTX 1 0 0 0 4 5 6\n",
                3,
                17,
                "2 value(s) past the ones PROPERTIES a declares",
            ),
        ];
        for (text, line, column, says) in cases {
            crate::surface::assert_refused_at("bad.ts", text, line, column, says);
        }
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let cases = [
            ("VRTX 1 0 0 0\n", 1, 1, "outside"),
            ("GOCAD TSurf 1\nVRTX 1 0 nan 0\n", 2, 10, "finite"),
            ("GOCAD TSurf 1\nVRTX 1 0 0\n", 2, 11, "needs x, y and z"),
            (
                "GOCAD TSurf 1\nVRTX 1 0 0 0\nVRTX 2 1 0 0\nTRGL 1 2 7\n",
                4,
                10,
                "vertex id 7",
            ),
            ("GOCAD TSurf 1\nVRTX 1 0 0 0\nVRTX 1 1 0 0\n", 3, 6, "twice"),
            ("GOCAD TSurf 1\nZPOSITIVE Up\n", 2, 11, "Depth or Elevation"),
            ("GOCAD PLine 1\n", 1, 1, "only triangulated"),
            ("GOCAD TSurf 1\nVRTX -1 0 0 0\n", 2, 6, "whole number"),
            ("hello\n", 1, 1, "outside"),
            ("", 1, 1, "not a GOCAD TSurf"),
        ];
        for (text, line, column, says) in cases {
            crate::surface::assert_refused_at("bad.ts", text, line, column, says);
        }
        // No triangles: named by the first polygon, there is no line to name.
        let text = "GOCAD TSurf 1\nVRTX 1 0 0 0\nEND\n";
        let e = parse(Path::new("bad.ts"), text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("polygon 0") && e.contains("no triangles"), "{e}");
    }
}
