//! The per-point scalar the cell projection interpolates, normalized to [0, 1] (the seed
//! passes "the normalized scalar" per vertex).
//!
//! A scene names it as `scalars = { array = "temperature" }`, with optional
//! `component = 1` (a vector's component; without it a vector gives its magnitude and a
//! one-component array its value), `from_cells = "average"` and `range = [lo, hi]`.
//!
//! Decisions:
//! - No `array`: the mesh's first point array (a generated grid's field).
//! - Cell arrays are used only when asked for with `from_cells = "average"`: each point
//!   gets the volume-weighted average of the values of the tetrahedra around it,
//!   `sum(|V_t| s_t) / sum(|V_t|)`, so a big neighbour counts more than a sliver; where
//!   every tetrahedron around a point is flat, the plain mean is used. A point that no
//!   tetrahedron uses gets the lower end of the range (0 after normalization). Non-finite
//!   cell values are left out of the average.
//! - Normalization: `(v - lo) / (hi - lo)` with `[lo, hi]` the finite range of the chosen
//!   values (as the seed did), or the scene's fixed `range`, values outside it falling
//!   outside [0, 1] (not clamped: the renderer's lookup clamps). A constant array
//!   (`lo == hi`) gives 0 everywhere, never NaN. Non-finite values stay NaN/±inf and are
//!   counted in [`PointScalars::non_finite`].

use serde::{Deserialize, Serialize};

use super::quality::{mesh_scale, signed_volume_scaled};
use super::{DataArray, Mesh, MeshError};

/// How a cell array becomes a point array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FromCells {
    /// Volume-weighted average of the tetrahedra around each point.
    Average,
}

/// Which scalar to use, as in a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ScalarSpec {
    /// Array name (a point array, or a cell array with `from_cells`); none: the first
    /// point array.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub array: Option<String>,
    /// Component of a multi-component array; none: the magnitude.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub component: Option<usize>,
    /// Convert a cell array to points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from_cells: Option<FromCells>,
    /// Fixed normalization range instead of the values' finite range.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
}

/// Normalized per-point scalars.
#[derive(Debug, Clone, PartialEq)]
pub struct PointScalars {
    /// The array they came from (with the component or conversion, e.g. `DISPL[1]`).
    pub name: String,
    /// One value per point, `(v - lo) / (hi - lo)`.
    pub values: Vec<f64>,
    /// The range `[lo, hi]` that was mapped to [0, 1].
    pub range: [f64; 2],
    /// Values that are NaN or infinite.
    pub non_finite: usize,
}

/// Smallest and largest finite value (`None` when there is none).
pub fn finite_range(v: &[f64]) -> Option<(f64, f64)> {
    v.iter()
        .filter(|x| x.is_finite())
        .fold(None, |r, &x| match r {
            None => Some((x, x)),
            Some((lo, hi)) => Some((lo.min(x), hi.max(x))),
        })
}

fn list(arrays: &[DataArray]) -> String {
    if arrays.is_empty() {
        "none".into()
    } else {
        arrays
            .iter()
            .map(|a| format!("\"{}\" ({} components)", a.name, a.components))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// One value per tuple of `a`: the component, or the magnitude of a vector.
fn pick(
    a: &DataArray,
    component: Option<usize>,
    mesh: &str,
) -> Result<(String, Vec<f64>), MeshError> {
    let k = a.components.max(1);
    match component {
        Some(c) if c >= k => Err(MeshError::Invalid(format!(
            "{mesh}: array \"{}\" has {k} components, so component {c} does not exist (0 to {})",
            a.name,
            k - 1
        ))),
        Some(c) => Ok((
            if k == 1 {
                a.name.clone()
            } else {
                format!("{}[{c}]", a.name)
            },
            a.values.chunks_exact(k).map(|t| t[c]).collect(),
        )),
        None if k == 1 => Ok((a.name.clone(), a.values.clone())),
        None => Ok((
            format!("|{}|", a.name),
            a.values.chunks_exact(k).map(magnitude).collect(),
        )),
    }
}

impl ScalarSpec {
    /// The normalized per-point scalars of `mesh`.
    pub fn evaluate(&self, mesh: &Mesh) -> Result<PointScalars, MeshError> {
        let src = &mesh.info.source;
        let arrays = format!(
            "point arrays: {}; cell arrays: {}",
            list(&mesh.point_arrays),
            list(&mesh.cell_arrays)
        );
        let (name, values) = match (&self.array, self.from_cells) {
            (None, None) => {
                let a = mesh.point_arrays.first().ok_or_else(|| {
                    MeshError::Invalid(format!("{src}: the mesh has no point array to use ({arrays})"))
                })?;
                pick(a, self.component, src)?
            }
            (None, Some(_)) => {
                return Err(MeshError::Invalid(format!(
                    "{src}: from_cells needs an array name ({arrays})"
                )))
            }
            (Some(n), None) => match mesh.point_array(n) {
                Some(a) => pick(a, self.component, src)?,
                None if mesh.cell_array(n).is_some() => {
                    return Err(MeshError::Invalid(format!(
                        "{src}: \"{n}\" is a cell array; add from_cells = \"average\" to use it per point"
                    )))
                }
                None => {
                    return Err(MeshError::Invalid(format!(
                        "{src}: no array \"{n}\" ({arrays})"
                    )))
                }
            },
            (Some(n), Some(FromCells::Average)) => {
                let a = mesh.cell_array(n).ok_or_else(|| {
                    MeshError::Invalid(format!("{src}: no cell array \"{n}\" ({arrays})"))
                })?;
                let (name, per_tet) = pick(a, self.component, src)?;
                (format!("{name} (cell average)"), average_to_points(mesh, &per_tet))
            }
        };
        let range = match self.range {
            Some([lo, hi]) => {
                if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                    return Err(MeshError::Invalid(format!(
                        "scalar range [{lo}, {hi}] must be finite with lo <= hi"
                    )));
                }
                [lo, hi]
            }
            None => finite_range(&values).map_or([0.0, 0.0], |(lo, hi)| [lo, hi]),
        };
        // Halves first: a range near ±1.7e308 has a span beyond the largest f64.
        let half_span = range[1] / 2.0 - range[0] / 2.0;
        let mut non_finite = 0;
        let values = values
            .into_iter()
            .map(|v| {
                if !v.is_finite() {
                    non_finite += 1;
                    v
                } else if half_span > 0.0 {
                    (v / 2.0 - range[0] / 2.0) / half_span
                } else {
                    0.0
                }
            })
            .collect();
        Ok(PointScalars {
            name,
            values,
            range,
            non_finite,
        })
    }
}

/// The length of a vector of any size, without overflow or underflow: the components are
/// scaled by a power of two first (NaN when one is NaN, infinite when one is).
fn magnitude(v: &[f64]) -> f64 {
    let largest = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if !largest.is_finite() || v.iter().any(|x| x.is_nan()) {
        return v.iter().map(|x| x.abs()).sum();
    }
    let s = super::cells::unit_scale(largest);
    v.iter().map(|x| (x * s) * (x * s)).sum::<f64>().sqrt() / s
}

/// Volume-weighted average of per-tetrahedron values at each point (see the module doc).
pub fn average_to_points(mesh: &Mesh, per_tet: &[f64]) -> Vec<f64> {
    let n = mesh.points.len();
    let scale = mesh_scale(&mesh.points);
    let mut sum = vec![0.0; n];
    let mut weight = vec![0.0; n];
    let mut plain = vec![0.0; n];
    let mut count = vec![0u32; n];
    for (t, &s) in mesh.tets.iter().zip(per_tet) {
        if !s.is_finite() {
            continue;
        }
        // Relative weights: volumes on scaled coordinates cannot overflow.
        let w = signed_volume_scaled(&mesh.points, *t, scale).abs();
        for &p in t {
            let p = p as usize;
            sum[p] += w * s;
            weight[p] += w;
            plain[p] += s;
            count[p] += 1;
        }
    }
    let lowest = finite_range(per_tet).map_or(0.0, |r| r.0);
    (0..n)
        .map(|p| {
            if weight[p] > 0.0 {
                sum[p] / weight[p]
            } else if count[p] > 0 {
                plain[p] / count[p] as f64
            } else {
                lowest
            }
        })
        .collect()
}
