//! VTK legacy files (`# vtk DataFile Version 1.0` to `5.1`), `DATASET UNSTRUCTURED_GRID`,
//! ASCII or BINARY.
//!
//! What is read:
//! - `POINTS n type`; cells in both layouts: the classic `CELLS n size` (each cell as a
//!   count and its point indices; versions up to 4.2) and VTK 9's `CELLS nOffsets
//!   nConnectivity` followed by `OFFSETS type` and `CONNECTIVITY type` arrays (version 5.1,
//!   `vtktypeint64` or `vtktypeint32`); the layout is chosen by the keyword that follows
//!   `CELLS`, not by the version. `CELL_TYPES n`.
//! - In `POINT_DATA n` and `CELL_DATA n`: `SCALARS name type [components]` (with or
//!   without its `LOOKUP_TABLE` line), `VECTORS`, `NORMALS`, `TENSORS`, `TENSORS6`,
//!   `TEXTURE_COORDINATES`, `COLOR_SCALARS`, `GLOBAL_IDS`, `PEDIGREE_IDS`, and `FIELD`
//!   arrays; names are %-decoded (`%20` is a space). Lookup-table definitions, the
//!   dataset's own `FIELD` data and `METADATA` blocks (up to their blank line) are skipped.
//! - BINARY data are big-endian, as VTK writes them, and start right after the line end
//!   of their header line. Type widths: `long`/`unsigned_long` 8 bytes (VTK on 64-bit
//!   Unix), `vtkIdType` 4 bytes (VTK writes id arrays as 32-bit in legacy files).
//! - `bit` arrays and binary string arrays are refused; ASCII string arrays in `FIELD`
//!   data are skipped (one value per line).

use std::path::Path;

mod cells;
mod reader;

use self::cells::{classic_cells, modern_cells};
use self::reader::Reader;
use super::cells::{vtk_kind, RawCells};
use super::read::{quote, vec_for, Cursor, Num};
use super::{DataArray, Mesh, MeshError, MeshInfo, ReadArray};

/// Which attribute section arrays go to.
#[derive(Clone, Copy, PartialEq)]
enum Target {
    None,
    Points(usize),
    Cells(usize),
}

/// Decode `%XX` escapes in array names, as VTK writes spaces and other bytes.
fn decode_name(t: &[u8]) -> String {
    let mut out = Vec::with_capacity(t.len());
    let mut i = 0;
    while i < t.len() {
        if t[i] == b'%' && i + 3 <= t.len() {
            if let Ok(v) = u8::from_str_radix(&String::from_utf8_lossy(&t[i + 1..i + 3]), 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(t[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Parse a VTK legacy unstructured grid held in memory; `name` is used in errors.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    let mut c = Cursor::new(name, bytes);
    c.skip_space();
    let (at, first) = c.line();
    let head = b"# vtk datafile version";
    if first.len() < head.len() || !first[..head.len()].eq_ignore_ascii_case(head) {
        return Err(c.err(
            at,
            format!(
                "expected \"# vtk DataFile Version x.y\", found {}",
                quote(first)
            ),
        ));
    }
    let version = String::from_utf8_lossy(first[head.len()..].trim_ascii()).into_owned();
    let major = version
        .split('.')
        .next()
        .and_then(|m| m.parse::<u32>().ok())
        .ok_or_else(|| {
            c.err(
                at + head.len(),
                format!(
                    "expected a version number, found {}",
                    quote(version.as_bytes())
                ),
            )
        })?;
    if !(1..=5).contains(&major) {
        return Err(c.err(
            at + head.len(),
            format!("version {version} is not supported (arbvis reads legacy versions 1.0 to 5.1)"),
        ));
    }
    let _title = c.line();
    let (at, enc) = c.line();
    let binary = match enc.trim_ascii().to_ascii_uppercase().as_slice() {
        b"ASCII" => false,
        b"BINARY" => true,
        _ => {
            return Err(c.err(
                at,
                format!("expected ASCII or BINARY, found {}", quote(enc)),
            ))
        }
    };
    c.keyword("DATASET")?;
    let (at, kind) = c.need("a dataset type")?;
    if !kind.eq_ignore_ascii_case(b"UNSTRUCTURED_GRID") {
        return Err(c.err(
            at,
            format!(
                "DATASET {} is not a volume mesh: arbvis reads DATASET UNSTRUCTURED_GRID",
                String::from_utf8_lossy(kind)
            ),
        ));
    }
    c.end_line()?;
    let mut r = Reader { c, binary };
    let mut st = State::default();
    while !r.c.at_end() {
        let (kw_at, kw) = r.c.need("a section keyword")?;
        let kw = kw.to_ascii_uppercase();
        let args = r.args();
        section(&mut r, &mut st, &kw, kw_at, &args)?;
    }
    finish(r, st, version)
}

#[derive(Default)]
struct State {
    points: Option<(usize, Vec<[f64; 3]>)>,
    cells: Option<(usize, RawCells)>,
    types: Option<(usize, Vec<super::cells::Kind>)>,
    target: Option<(usize, Target)>,
    /// Every POINT_DATA and CELL_DATA line, checked against POINTS and CELLS at the end
    /// (they may come in any order).
    data_sections: Vec<(usize, Target)>,
    point_arrays: Vec<ReadArray>,
    cell_arrays: Vec<ReadArray>,
}

/// Refuse a second `kw` section (a second POINTS would silently replace the first, and
/// the arrays checked against it).
fn once<T>(r: &Reader, slot: &Option<(usize, T)>, kw: &str, at: usize) -> Result<(), MeshError> {
    match slot {
        Some((first, _)) => Err(r.c.err(
            at,
            format!(
                "a second {kw} section: the file already has one at line {}",
                super::read::line_column(r.c.bytes, *first).0
            ),
        )),
        None => Ok(()),
    }
}

fn section(
    r: &mut Reader,
    st: &mut State,
    kw: &[u8],
    kw_at: usize,
    args: &[(usize, &[u8])],
) -> Result<(), MeshError> {
    let target = st.target.map_or(Target::None, |t| t.1);
    match kw {
        b"POINTS" => {
            once(r, &st.points, "POINTS", kw_at)?;
            let t = r.type_arg(args, 1, kw_at)?;
            let n = r.count_arg(args, 0, kw_at, "the point count", 3 * r.min_bytes(t))?;
            let (v, bad) = r.values(3 * n, t, "the point coordinates")?;
            if let Some((i, at)) = bad {
                let m = format!("point {} has a coordinate that is not finite ({})", i / 3, v[i]);
                return Err(if r.binary { r.c.err_bin(at, m) } else { r.c.err(at, m) });
            }
            let pts = v.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            st.points = Some((kw_at, pts));
        }
        b"CELLS" => {
            once(r, &st.cells, "CELLS", kw_at)?;
            let a: i64 = r.arg(args, 0, kw_at, "the cell count")?;
            let b: i64 = r.arg(args, 1, kw_at, "the cell list size")?;
            if a < 0 || b < 0 {
                return Err(r.c.err(kw_at, format!("CELLS {a} {b}: negative count")));
            }
            let cells = if r.c.peek().is_some_and(|t| t.eq_ignore_ascii_case(b"OFFSETS")) {
                modern_cells(r, a as u64, b as u64)?
            } else {
                classic_cells(r, a as u64, b as u64)?
            };
            st.cells = Some((kw_at, cells));
        }
        b"CELL_TYPES" => {
            once(r, &st.types, "CELL_TYPES", kw_at)?;
            let t = if r.binary { Num::I32 } else { Num::I64 };
            let n = r.count_arg(args, 0, kw_at, "the cell type count", r.min_bytes(t))?;
            let (v, start) = r.ints(n, t, "the cell types")?;
            let mut kinds = vec_for(n, "cell types").map_err(|m| r.c.err(start, m))?;
            for (i, &v) in v.iter().enumerate() {
                kinds.push(vtk_kind(v).map_err(|m| r.int_err(start, i, Num::I32, format!("cell {i}: {m}")))?);
            }
            st.types = Some((kw_at, kinds));
        }
        b"POINT_DATA" | b"CELL_DATA" => {
            let n: i64 = r.arg(args, 0, kw_at, "the tuple count")?;
            let n = usize::try_from(n)
                .map_err(|_| r.c.err(args[0].0, format!("negative tuple count {n}")))?;
            let target = if kw == b"POINT_DATA" { Target::Points(n) } else { Target::Cells(n) };
            st.target = Some((kw_at, target));
            st.data_sections.push((kw_at, target));
        }
        b"METADATA" => {
            // Skip lines up to the first blank one.
            while r.c.remaining() > 0 {
                let (_, l) = r.c.line();
                if l.trim_ascii().is_empty() {
                    break;
                }
            }
        }
        b"FIELD" => {
            let n = r.count_arg(args, 1, kw_at, "the number of field arrays", 4)?;
            for _ in 0..n {
                field_array(r, st, target)?;
            }
        }
        b"SCALARS" | b"VECTORS" | b"NORMALS" | b"TENSORS" | b"TENSORS6" | b"TEXTURE_COORDINATES"
        | b"GLOBAL_IDS" | b"PEDIGREE_IDS" | b"COLOR_SCALARS" | b"LOOKUP_TABLE" => {
            attribute(r, st, target, kw, kw_at, args)?;
        }
        _ => {
            return Err(r.c.err(
                kw_at,
                format!(
                    "expected a section keyword (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, VECTORS, FIELD, METADATA, ...), found {}",
                    quote(kw)
                ),
            ))
        }
    }
    Ok(())
}

/// One array of a `FIELD` block: `name components tuples type`, then the values.
fn field_array(r: &mut Reader, st: &mut State, target: Target) -> Result<(), MeshError> {
    let (at, name) = r.c.need("a field array name")?;
    if name == b"NULL_ARRAY" {
        r.c.end_line()?;
        return Ok(());
    }
    let args = r.args();
    let comps: i64 = r.arg(&args, 0, at, "the number of components")?;
    let tuples: i64 = r.arg(&args, 1, at, "the number of tuples")?;
    let (t_at, t) = args
        .get(2)
        .copied()
        .ok_or_else(|| r.c.err(at, "expected a data type after the tuple count"))?;
    if comps < 0 || tuples < 0 {
        return Err(r.c.err(at, format!("negative size {comps} x {tuples}")));
    }
    let total = (comps as u64).saturating_mul(tuples as u64);
    let lower = String::from_utf8_lossy(t).to_ascii_lowercase();
    if lower == "string" || lower == "utf8_string" {
        if r.binary {
            return Err(r.c.err(t_at, "binary string arrays are not supported"));
        }
        r.c.check_fits(t_at, "the string count", total, 1)?;
        for _ in 0..total {
            r.c.line();
        }
        return Ok(());
    }
    let num = r.type_arg(&args, 2, at)?;
    let total =
        r.c.check_fits(at, "the field array size", total, r.min_bytes(num))?;
    let (values, _) = r.values(total, num, "the field array values")?;
    let array = DataArray {
        name: decode_name(name),
        components: comps as usize,
        values,
    };
    store(r, st, target, array, tuples as usize, at)
}

fn store(
    r: &Reader,
    st: &mut State,
    target: Target,
    array: DataArray,
    tuples: usize,
    at: usize,
) -> Result<(), MeshError> {
    let (want, list, what) = match target {
        Target::None => return Ok(()), // the dataset's own field data
        Target::Points(n) => (n, &mut st.point_arrays, "POINT_DATA"),
        Target::Cells(n) => (n, &mut st.cell_arrays, "CELL_DATA"),
    };
    if tuples != want || array.components == 0 {
        return Err(r.c.err(
            at,
            format!(
                "array \"{}\" has {tuples} tuples of {} components, but its {what} section has {want} tuples",
                array.name, array.components
            ),
        ));
    }
    list.push(ReadArray { array, at });
    Ok(())
}

fn attribute(
    r: &mut Reader,
    st: &mut State,
    target: Target,
    kw: &[u8],
    kw_at: usize,
    args: &[(usize, &[u8])],
) -> Result<(), MeshError> {
    let n = match target {
        Target::Points(n) | Target::Cells(n) => n,
        Target::None => {
            return Err(r.c.err(
                kw_at,
                format!(
                    "{} outside POINT_DATA or CELL_DATA",
                    String::from_utf8_lossy(kw)
                ),
            ))
        }
    };
    let (_, name) = args
        .first()
        .copied()
        .ok_or_else(|| r.c.err(kw_at, "expected a name on this line"))?;
    let name = decode_name(name);
    let (comps, num) = match kw {
        b"LOOKUP_TABLE" => {
            // A table definition: `size` RGBA entries (floats in ASCII, bytes in binary).
            let size = r.count_arg(
                args,
                1,
                kw_at,
                "the table size",
                4 * if r.binary { 1 } else { 2 },
            )?;
            r.values(4 * size, Num::U8, "the lookup table")?;
            return Ok(());
        }
        b"COLOR_SCALARS" => {
            let k: usize = r.arg(args, 1, kw_at, "the number of colour components")?;
            let total = r.c.check_fits(
                kw_at,
                "the colour values",
                (n as u64).saturating_mul(k as u64),
                if r.binary { 1 } else { 2 },
            )?;
            let (mut values, _) = r.values(total, Num::U8, "the colour values")?;
            if r.binary {
                values.iter_mut().for_each(|v| *v /= 255.0);
            }
            return store(
                r,
                st,
                target,
                DataArray {
                    name,
                    components: k,
                    values,
                },
                n,
                kw_at,
            );
        }
        b"SCALARS" => {
            let t = r.type_arg(args, 1, kw_at)?;
            let k = if args.len() > 2 {
                r.arg::<usize>(args, 2, kw_at, "the number of components")?
            } else {
                1
            };
            // The LOOKUP_TABLE line VTK writes after SCALARS (optional here).
            let save = r.c.pos;
            if r.c
                .token()
                .is_some_and(|(_, t)| t.eq_ignore_ascii_case(b"LOOKUP_TABLE"))
            {
                r.c.line();
            } else {
                r.c.pos = save;
            }
            (k, t)
        }
        b"TEXTURE_COORDINATES" => {
            let k: usize = r.arg(args, 1, kw_at, "the texture dimension")?;
            (k, r.type_arg(args, 2, kw_at)?)
        }
        b"VECTORS" | b"NORMALS" => (3, r.type_arg(args, 1, kw_at)?),
        b"TENSORS" => (9, r.type_arg(args, 1, kw_at)?),
        b"TENSORS6" => (6, r.type_arg(args, 1, kw_at)?),
        _ => (1, r.type_arg(args, 1, kw_at)?), // GLOBAL_IDS, PEDIGREE_IDS
    };
    if comps == 0 {
        return Err(r.c.err(kw_at, "an array needs at least one component"));
    }
    let total = (n as u64).saturating_mul(comps as u64);
    let total = r.c.check_fits(
        r.c.pos,
        &format!("the values of \"{name}\""),
        total,
        r.min_bytes(num),
    )?;
    let (values, _) = r.values(total, num, &format!("the values of \"{name}\""))?;
    store(
        r,
        st,
        target,
        DataArray {
            name,
            components: comps,
            values,
        },
        n,
        kw_at,
    )
}

fn finish(r: Reader, st: State, version: String) -> Result<Mesh, MeshError> {
    let end = r.c.bytes.len();
    let (points_at, points) = st
        .points
        .ok_or_else(|| r.c.err(end, "the file has no POINTS section"))?;
    let (cells_at, mut cells) = st
        .cells
        .ok_or_else(|| r.c.err(end, "the file has no CELLS section"))?;
    let (types_at, kinds) = st
        .types
        .ok_or_else(|| r.c.err(end, "the file has no CELL_TYPES section"))?;
    if kinds.len() != cells.offsets.len() - 1 {
        return Err(r.c.err(
            types_at,
            format!(
                "CELL_TYPES has {} entries but CELLS (line {}) has {} cells",
                kinds.len(),
                super::read::line_column(r.c.bytes, cells_at).0,
                cells.offsets.len() - 1
            ),
        ));
    }
    cells.kinds = kinds;
    let line = |at: usize| super::read::line_column(r.c.bytes, at).0;
    for &(at, target) in &st.data_sections {
        let (n, have, what, kw, kw_at) = match target {
            Target::Points(n) => (n, points.len(), "points", "POINTS", points_at),
            Target::Cells(n) => (n, cells.len(), "cells", "CELLS", cells_at),
            Target::None => continue,
        };
        if n != have {
            return Err(r.c.err(
                at,
                format!(
                    "{} {n} does not match the {have} {what} of {kw} (line {})",
                    if what == "points" {
                        "POINT_DATA"
                    } else {
                        "CELL_DATA"
                    },
                    line(kw_at)
                ),
            ));
        }
    }
    let info = MeshInfo {
        format: "VTK legacy".into(),
        version,
        encoding: if r.binary {
            "binary (big-endian)"
        } else {
            "ascii"
        }
        .into(),
        ..MeshInfo::default()
    };
    Mesh::assemble(
        r.c.name,
        r.c.bytes,
        points,
        &cells,
        st.point_arrays,
        st.cell_arrays,
        info,
    )
}
