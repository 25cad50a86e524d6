//! A PLY file's vertices as a point cloud (the faces, if any, are left to surface
//! loaders; see [`super::ply`]).
//!
//! - `x`, `y`, `z` are required and must be finite (the error gives the byte or line of
//!   the first that is not).
//! - `red`, `green`, `blue` (or `diffuse_red`, ...) become the colour: 8-bit integers are
//!   scaled by 257 (255 → 65535), 16-bit ones kept, wider integers clamped to 0..65535,
//!   reals taken as 0..1 and scaled to 0..65535. All three or none.
//! - `nx`, `ny`, `nz` become the normals (all three or none).
//! - Every other scalar property (`alpha`, `confidence`, `intensity`, ...) becomes an
//!   attribute of its name: integers (`uint` only when every value fits i32) stay
//!   integers, reals become f32. List properties of vertices are skipped.

use std::path::Path;

use super::ply::{self, Encoding, Ply, Position, PropertyData, ScalarType};
use super::{CloudParts, PointCloud, PointsError, Values};

/// The cloud of a PLY file and facts about the file.
#[derive(Debug, Clone)]
pub struct PlyCloud {
    /// The vertices.
    pub cloud: PointCloud,
    /// Data encoding.
    pub encoding: Encoding,
    /// Every element's name and row count, in file order.
    pub elements: Vec<(String, usize)>,
    /// `comment` lines.
    pub comments: Vec<String>,
}

impl PlyCloud {
    /// The format lines of `arbvis inspect`.
    pub fn describe_format(&self) -> String {
        let elements: Vec<String> = self
            .elements
            .iter()
            .map(|(n, c)| format!("{n} {c}"))
            .collect();
        let mut s = format!(
            "format: PLY 1.0 {}\nelements: {}\n",
            self.encoding.name(),
            elements.join(", ")
        );
        for c in &self.comments {
            s += &format!("comment: {}\n", arbvis_core::input::shorten(c, 100));
        }
        s
    }
}

/// Read a PLY file's vertices.
pub fn read(path: &Path) -> Result<PlyCloud, PointsError> {
    let bytes = super::read_file(path)?;
    parse(path, &bytes)
}

/// Parse PLY bytes named `name` and take their vertices.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<PlyCloud, PointsError> {
    let ply = ply::parse(name, bytes)?;
    let cloud = cloud(name, &ply)?;
    Ok(PlyCloud {
        cloud,
        encoding: ply.encoding,
        elements: ply
            .elements
            .iter()
            .map(|e| (e.name.clone(), e.count))
            .collect(),
        comments: ply.comments,
    })
}

/// A scalar property's type and values.
type Channel<'a> = (ScalarType, &'a [f64]);

const COLOUR: [[&str; 3]; 2] = [
    ["red", "green", "blue"],
    ["diffuse_red", "diffuse_green", "diffuse_blue"],
];
const NORMAL: [&str; 3] = ["nx", "ny", "nz"];

/// The vertex element of `ply` as a cloud.
pub fn cloud(name: &Path, ply: &Ply) -> Result<PointCloud, PointsError> {
    let unsupported = |m: String| PointsError::unsupported(name, m);
    let vertex = ply
        .element("vertex")
        .ok_or_else(|| unsupported("no \"vertex\" element: not a point cloud".into()))?;
    let n = vertex.count;
    let at = |p: Position, message: String| match p {
        Position::Byte(b) => PointsError::format(name, b, message),
        Position::Line { line, column } => PointsError::text(name, line, column, message),
    };
    let mut xyz = Vec::with_capacity(3);
    for axis in ["x", "y", "z"] {
        let property = vertex.property(axis).ok_or_else(|| {
            at(
                vertex.declared,
                format!("the vertex element has no scalar property \"{axis}\""),
            )
        })?;
        let PropertyData::Scalar { values, .. } = &property.data else {
            return Err(at(
                property.declared,
                format!(
                    "vertex property \"{axis}\" is declared as a list (property list ...), \
                     a coordinate must be a scalar (property float {axis})"
                ),
            ));
        };
        if let Some((row, at)) = property.first_non_finite {
            let message = format!(
                "vertex {row}: coordinate {axis} is {}, coordinates must be finite",
                values[row]
            );
            return Err(match at {
                Position::Byte(b) => PointsError::format(name, b, message),
                Position::Line { line, column } => PointsError::text(name, line, column, message),
            });
        }
        xyz.push(values);
    }
    // The cloud is built while the PLY's f64 columns are held: both count. (Every other
    // scalar property becomes an attribute; colours and normals take no more than that.)
    let held: u64 = ply.elements.iter().fold(0, |sum, e| {
        sum.saturating_add(arbvis_core::budget::times(
            e.count as u64,
            8 * e.properties.len() as u64,
        ))
    });
    let estimate =
        super::footprint(n as u64, vertex.properties.len(), false, false).saturating_add(held);
    arbvis_core::budget::check(format!("the cloud of {n} vertices"), estimate).map_err(|e| {
        at(
            vertex.declared,
            format!("the vertex element declares {n} rows: {e}"),
        )
    })?;
    let positions = (0..n).map(|i| [xyz[0][i], xyz[1][i], xyz[2][i]]).collect();
    let all_three = |names: [&str; 3]| -> Result<Option<[Channel; 3]>, PointsError> {
        let found: Vec<_> = names
            .iter()
            .filter_map(|&p| match &vertex.property(p)?.data {
                PropertyData::Scalar { ty, values } => Some((*ty, values.as_slice())),
                PropertyData::List { .. } => None,
            })
            .collect();
        match found.len() {
            0 => Ok(None),
            3 => Ok(Some([found[0], found[1], found[2]])),
            k => Err(at(
                vertex.declared,
                format!(
                    "the vertex element has {k} of the 3 scalar properties {}",
                    names.join(", ")
                ),
            )),
        }
    };
    let mut used: Vec<&str> = vec!["x", "y", "z"];
    let mut rgb = None;
    for names in COLOUR {
        if let Some(channels) = all_three(names)? {
            rgb = Some(
                (0..n)
                    .map(|i| std::array::from_fn(|c| colour16(channels[c].0, channels[c].1[i])))
                    .collect(),
            );
            used.extend(names);
            break;
        }
    }
    let normals = all_three(NORMAL)?.map(|c| {
        used.extend(NORMAL);
        (0..n)
            .map(|i| std::array::from_fn(|a| c[a].1[i] as f32))
            .collect()
    });
    let mut attributes = Vec::new();
    for p in &vertex.properties {
        let PropertyData::Scalar { ty, values } = &p.data else {
            continue;
        };
        if used.contains(&p.name.as_str()) {
            continue;
        }
        let fits = |v: &f64| *v <= i32::MAX as f64;
        let values = if ty.is_integer() && (*ty != ScalarType::UInt || values.iter().all(fits)) {
            Values::Int(values.iter().map(|&v| v as i32).collect())
        } else {
            Values::Float(values.iter().map(|&v| v as f32).collect())
        };
        attributes.push((p.name.clone(), values));
    }
    PointCloud::from_parts(CloudParts {
        positions,
        attributes,
        rgb,
        normals,
    })
    .map_err(|m| PointsError::Invalid(format!("{}: {m}", name.display())))
}

/// A colour channel of type `ty` as 16 bits.
fn colour16(ty: ScalarType, v: f64) -> u16 {
    match ty {
        ScalarType::UChar | ScalarType::Char => (v.clamp(0.0, 255.0) * 257.0) as u16,
        ScalarType::Float | ScalarType::Double => {
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            (v * 65535.0).round() as u16
        }
        _ => v.clamp(0.0, 65535.0) as u16,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_normals_and_attributes() {
        let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uint label\nproperty list uchar int extra\nend_header\n1 2 3 255 128 0 7 0 0 1 4000000000 2 5 6\n-1.5 2 1e6 0 1 2 8 0 1 0 9 0\n";
        let c = parse(Path::new("c.ply"), text.as_bytes()).unwrap().cloud;
        assert_eq!(c.len(), 2);
        assert_eq!(
            c.rgb.as_ref().unwrap(),
            &vec![[65535, 32896, 0], [0, 257, 514]]
        );
        assert_eq!(
            c.normals.as_ref().unwrap(),
            &vec![[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(c.ints("alpha").unwrap(), &[7, 8]);
        assert_eq!(c.floats("label").unwrap(), &[4.0e9, 9.0]);
        assert!(c.attribute("extra").is_none());
        assert_eq!(c.attributes.len(), 2);
        assert_eq!(c.bounds, [[-1.5, 2.0, 3.0], [1.0, 2.0, 1e6]]);
    }

    #[test]
    fn float_and_16_bit_colours() {
        assert_eq!(colour16(ScalarType::Float, 1.0), 65535);
        assert_eq!(colour16(ScalarType::Float, 0.5), 32768);
        assert_eq!(colour16(ScalarType::Double, 7.0), 65535);
        assert_eq!(colour16(ScalarType::Float, f64::NAN), 0);
        assert_eq!(colour16(ScalarType::UShort, 1234.0), 1234);
        assert_eq!(colour16(ScalarType::Int, -5.0), 0);
    }

    #[test]
    fn missing_coordinates_partial_colours_and_non_finite_positions() {
        let head = "ply\nformat ascii 1.0\nelement vertex 2\n";
        let cases = [
            ("property float x\nproperty float y\nend_header\n1 2\n3 4\n", "no scalar property \"z\""),
            (
                "property float x\nproperty float y\nproperty float z\nproperty uchar red\nend_header\n1 2 3 4\n5 6 7 8\n",
                "1 of the 3 scalar properties red, green, blue",
            ),
            (
                "property float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n5 nan 7\n",
                "line 9, column 3: vertex 1: coordinate y is NaN",
            ),
        ];
        for (body, expect) in cases {
            let e = parse(Path::new("v.ply"), format!("{head}{body}").as_bytes())
                .unwrap_err()
                .to_string();
            assert!(e.contains(expect), "{e}");
        }
        let e = parse(
            Path::new("f.ply"),
            b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("no \"vertex\" element"), "{e}");
        // A binary NaN is reported at its byte.
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
        let start = b.len();
        for v in [1.0f32, f32::INFINITY, 0.0] {
            b.extend(v.to_le_bytes());
        }
        let e = parse(Path::new("b.ply"), &b).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "at byte {}: vertex 0: coordinate y is inf",
                start + 4
            )),
            "{e}"
        );
    }
}
