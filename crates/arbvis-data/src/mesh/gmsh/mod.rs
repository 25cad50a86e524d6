//! gmsh `.msh` files, formats 2.2 (also 2.0 and 2.1) and 4.1, ASCII and binary.
//!
//! What is read: `$MeshFormat` (version, file type, data size; in binary files the
//! integer 1 that follows tells the byte order), `$Nodes`, `$Elements`, and every
//! `$NodeData` section as a point array named by its first string tag (`"temperature"`),
//! `$ElementData` as a cell array. Other sections (`$PhysicalNames`, `$Entities`,
//! `$InterpolationScheme`, `$Periodic`, ...) are skipped up to their `$End` line; in
//! binary files that search could in principle stop early at bytes that spell the end
//! line, which then shows as an error, never as a wrong mesh.
//!
//! Decisions:
//! - Node tags may be sparse and in any order; points keep the file's node order and tags
//!   are mapped to indices (a repeated tag is an error, as is an element or data entry
//!   naming an unknown tag).
//! - Element types map to VTK cell kinds (see [`super::cells::gmsh_kind`]): tetrahedra,
//!   hexahedra, prisms, pyramids and their second-order forms become tetrahedra; points,
//!   lines, triangles and quadrangles are skipped and counted; others are refused.
//! - Data entries missing for some nodes leave NaN there. A repeated data name (several
//!   time steps) gets ` #2`, ` #3`, ... appended.
//! - Binary 4.1 uses `data-size` bytes for `size_t` values (4 or 8); binary 2.2 needs 8.
//!   Data sections store their tags as 4-byte integers in both versions.
//! - Format 4.0, 3.0 and MSH1 are refused by name (gmsh can re-save them as 4.1).

mod data;
mod reader;

use std::path::Path;

use self::data::PendingData;
use self::reader::{Reader, TagMap};
use super::cells::{gmsh_kind, RawCells};
use super::read::{quote, vec_for, Cursor};
use super::{Mesh, MeshError, MeshInfo};
use arbvis_core::budget;

#[derive(Default)]
struct State {
    points: Vec<[f64; 3]>,
    node_index: TagMap,
    node_room: usize,
    cells: RawCells,
    cell_index: TagMap,
    cell_room: usize,
    data: Vec<PendingData>,
    have_nodes: bool,
    have_elements: bool,
}

/// Parse a gmsh `.msh` file held in memory; `name` is used in errors.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    let mut c = Cursor::new(name, bytes);
    c.keyword("$MeshFormat")?;
    let (vat, version) = c.need("the format version")?;
    let version = String::from_utf8_lossy(version).into_owned();
    let v4 = match version.as_str() {
        "4.1" => true,
        "2" | "2.0" | "2.1" | "2.2" => false,
        _ => {
            return Err(c.err(vat, format!(
                "MSH format {} is not supported: arbvis reads 2.2 and 4.1 (gmsh can re-save a mesh as either)",
                quote(version.as_bytes())
            )))
        }
    };
    let (fat, file_type) = c.parse::<i64>("the file type (0 ASCII, 1 binary)")?;
    let (sat, size_t) = c.parse::<i64>("the data size")?;
    let binary = match file_type {
        0 => false,
        1 => true,
        _ => {
            return Err(c.err(
                fat,
                format!("file type {file_type} is neither 0 (ASCII) nor 1 (binary)"),
            ))
        }
    };
    if binary && !(size_t == 8 || (v4 && size_t == 4)) {
        return Err(c.err(
            sat,
            format!(
                "data size {size_t} is not supported in binary MSH {version} (8{})",
                if v4 { " or 4" } else { "" }
            ),
        ));
    }
    let mut big = false;
    if binary {
        c.end_line()?;
        let at = c.pos;
        let one = c.take(4, "the byte-order integer 1")?;
        big = match one {
            [1, 0, 0, 0] => false,
            [0, 0, 0, 1] => true,
            _ => {
                return Err(c.err_bin(
                    at,
                    format!("expected the integer 1 in either byte order, found bytes {one:02x?}"),
                ))
            }
        };
    }
    let mut r = Reader {
        c,
        binary,
        big,
        size_t: size_t.max(4) as usize,
    };
    r.end("MeshFormat")?;
    let mut st = State::default();
    while !r.c.at_end() {
        let (at, t) = r.c.need("a section")?;
        match t {
            b"$Nodes" => {
                if v4 {
                    nodes_v4(&mut r, &mut st)?
                } else {
                    nodes_v2(&mut r, &mut st)?
                }
                st.have_nodes = true;
                r.end("Nodes")?;
            }
            b"$Elements" => {
                if !st.have_nodes {
                    return Err(r.c.err(at, "$Elements before $Nodes"));
                }
                if v4 {
                    elements_v4(&mut r, &mut st)?
                } else {
                    elements_v2(&mut r, &mut st)?
                }
                st.have_elements = true;
                r.end("Elements")?;
            }
            b"$NodeData" | b"$ElementData" => {
                let nodes = t == b"$NodeData";
                st.data.push(data::read(&mut r, nodes, at)?);
                r.end(if nodes { "NodeData" } else { "ElementData" })?;
            }
            _ if t.first() == Some(&b'$') && !t.starts_with(b"$End") => {
                let end = [b"\n$End", &t[1..]].concat();
                let rest = &r.c.bytes[r.c.pos..];
                let found = rest.windows(end.len()).position(|w| w == end.as_slice());
                match found {
                    Some(p) => r.c.pos += p + end.len(),
                    None => {
                        return Err(r.c.err(
                            at,
                            format!("section {} has no {} line", quote(t), quote(&end[1..])),
                        ))
                    }
                }
            }
            _ => {
                return Err(r.c.err(
                    at,
                    format!(
                        "expected a section such as $Nodes or $Elements, found {}",
                        quote(t)
                    ),
                ))
            }
        }
    }
    let end = r.c.bytes.len();
    if !st.have_nodes || !st.have_elements {
        return Err(r
            .c
            .err(end, "the file needs both a $Nodes and an $Elements section"));
    }
    let info = MeshInfo {
        format: "gmsh MSH".into(),
        version,
        encoding: if binary {
            format!("binary ({}-endian)", if big { "big" } else { "little" })
        } else {
            "ascii".into()
        },
        ..MeshInfo::default()
    };
    st.cells.text = !binary;
    let (point_arrays, cell_arrays) = data::resolve(
        &r,
        &st.data,
        (st.points.len(), &st.node_index),
        (st.cells.kinds.len(), &st.cell_index),
    )?;
    Mesh::assemble(
        name,
        r.c.bytes,
        st.points,
        &st.cells,
        point_arrays,
        cell_arrays,
        info,
    )
}

fn add_node(r: &Reader, st: &mut State, at: usize, tag: i64, p: [f64; 3]) -> Result<(), MeshError> {
    if let Some(a) = p.iter().position(|v| !v.is_finite()) {
        return Err(r.err(
            at,
            format!("node {tag} has a coordinate that is not finite ({})", p[a]),
        ));
    }
    let index = st.points.len() as u32;
    if !st.node_index.insert(tag, index, st.node_room) {
        return Err(r.err(at, format!("node tag {tag} appears twice")));
    }
    st.points.push(p);
    Ok(())
}

fn reserve_nodes(r: &Reader, st: &mut State, n: usize, at: usize) -> Result<(), MeshError> {
    st.node_room = st.node_room.saturating_add(2 * n + 1024);
    budget::reserve(&mut st.points, n, "the nodes").map_err(|e| r.err(at, e.to_string()))
}

fn nodes_v2(r: &mut Reader, st: &mut State) -> Result<(), MeshError> {
    let at = r.c.pos;
    // The count is ASCII even in binary files.
    let n = r.c.count("the node count", if r.binary { 28 } else { 8 })?;
    reserve_nodes(r, st, n, at)?;
    if r.binary {
        r.c.end_line()?;
    }
    for _ in 0..n {
        let (at, tag) = r.int(4, "a node tag")?;
        let x = r.f64("the node's x")?.1;
        let y = r.f64("the node's y")?.1;
        let z = r.f64("the node's z")?.1;
        add_node(r, st, at, tag, [x, y, z])?;
    }
    Ok(())
}

fn nodes_v4(r: &mut Reader, st: &mut State) -> Result<(), MeshError> {
    let s = r.size_t;
    if r.binary {
        r.c.end_line()?;
    }
    let blocks = r.count(s, "the node block count", 3 * 4 + s, 8)?;
    let at = r.c.pos;
    let n = r.count(s, "the node count", s + 24, 8)?;
    r.int(s, "the smallest node tag")?;
    r.int(s, "the largest node tag")?;
    reserve_nodes(r, st, n, at)?;
    let mut total = 0usize;
    for _ in 0..blocks {
        let (dat, dim) = r.int(4, "the block's entity dimension")?;
        r.int(4, "the block's entity tag")?;
        let (_, parametric) = r.int(4, "the parametric flag")?;
        let m = r.count(s, "the block's node count", s + 24, 8)?;
        if !(0..=3).contains(&dim) || !(0..=1).contains(&parametric) {
            return Err(r.err(
                dat,
                format!("entity dimension {dim} / parametric flag {parametric} out of range"),
            ));
        }
        total = total.saturating_add(m);
        if total > n {
            return Err(r.err(
                dat,
                format!("the node blocks hold more than the {n} nodes announced"),
            ));
        }
        let extra = if parametric == 1 { dim as usize } else { 0 };
        let tags_at = r.c.pos;
        let mut tags = vec_for(m, "node tags").map_err(|e| r.err(tags_at, e))?;
        for _ in 0..m {
            tags.push(r.int(s, "a node tag")?);
        }
        for (at, tag) in tags {
            let x = r.f64("the node's x")?.1;
            let y = r.f64("the node's y")?.1;
            let z = r.f64("the node's z")?.1;
            for _ in 0..extra {
                r.f64("a parametric coordinate")?;
            }
            add_node(r, st, at, tag, [x, y, z])?;
        }
    }
    if total != n {
        return Err(r.err(
            r.c.pos,
            format!("the node blocks hold {total} nodes, but {n} were announced"),
        ));
    }
    Ok(())
}

/// Add one element of gmsh type `ty` whose node tags are read by `node`.
fn element(
    r: &mut Reader,
    st: &mut State,
    at: usize,
    tag: i64,
    ty: i64,
    width: usize,
) -> Result<(), MeshError> {
    let kind = gmsh_kind(ty).map_err(|m| r.err(at, format!("element {tag}: {m}")))?;
    let cell = st.cells.kinds.len() as u32;
    if !st.cell_index.insert(tag, cell, st.cell_room) {
        return Err(r.err(at, format!("element tag {tag} appears twice")));
    }
    for _ in 0..kind.nodes.unwrap_or(0) {
        let (nat, t) = r.int(width, "a node tag")?;
        let i = st.node_index.get(t).ok_or_else(|| {
            r.err(
                nat,
                format!(
                    "element {tag} ({}) refers to node {t}, which is not in $Nodes",
                    kind.name
                ),
            )
        })?;
        st.cells.nodes.push(i);
    }
    st.cells.kinds.push(kind);
    st.cells.at.push(at);
    st.cells.offsets.push(st.cells.nodes.len());
    Ok(())
}

fn reserve_cells(r: &Reader, st: &mut State, n: usize, at: usize) -> Result<(), MeshError> {
    let e = |e: budget::OverBudget| r.err(at, e.to_string());
    budget::reserve(&mut st.cells.kinds, n, "the elements").map_err(e)?;
    budget::reserve(&mut st.cells.at, n, "the elements' positions").map_err(e)?;
    budget::reserve(&mut st.cells.offsets, n + 1, "the elements' offsets").map_err(e)?;
    st.cell_room = st.cell_room.saturating_add(2 * n + 1024);
    if st.cells.offsets.is_empty() {
        st.cells.offsets.push(0);
    }
    Ok(())
}

fn elements_v2(r: &mut Reader, st: &mut State) -> Result<(), MeshError> {
    let at = r.c.pos;
    let n =
        r.c.count("the element count", if r.binary { 16 } else { 10 })?;
    reserve_cells(r, st, n, at)?;
    if !r.binary {
        for _ in 0..n {
            let (at, tag) = r.int(4, "an element tag")?;
            let (_, ty) = r.int(4, "the element type")?;
            let (_, ntags) = r.c.parse::<u32>("the number of element tags")?;
            for _ in 0..ntags {
                r.int(4, "an element tag value")?;
            }
            element(r, st, at, tag, ty, 4)?;
        }
        return Ok(());
    }
    r.c.end_line()?;
    let mut done = 0usize;
    while done < n {
        let hat = r.c.pos;
        let (_, ty) = r.int(4, "the element type")?;
        let m = r.count(4, "the elements in this block", 8, 0)?;
        let (_, ntags) = r.int(4, "the number of tags")?;
        if m == 0 || m > n - done || !(0..=1 << 16).contains(&ntags) {
            return Err(r.err(hat, format!("element block of {m} elements with {ntags} tags does not fit the {} elements left", n - done)));
        }
        for _ in 0..m {
            let (at, tag) = r.int(4, "an element tag")?;
            for _ in 0..ntags {
                r.int(4, "an element tag value")?;
            }
            element(r, st, at, tag, ty, 4)?;
        }
        done += m;
    }
    Ok(())
}

fn elements_v4(r: &mut Reader, st: &mut State) -> Result<(), MeshError> {
    let s = r.size_t;
    if r.binary {
        r.c.end_line()?;
    }
    let blocks = r.count(s, "the element block count", 12 + s, 8)?;
    let at = r.c.pos;
    let n = r.count(s, "the element count", 2 * s, 4)?;
    r.int(s, "the smallest element tag")?;
    r.int(s, "the largest element tag")?;
    reserve_cells(r, st, n, at)?;
    let mut total = 0usize;
    for _ in 0..blocks {
        let bat = r.c.pos;
        r.int(4, "the block's entity dimension")?;
        r.int(4, "the block's entity tag")?;
        let (_, ty) = r.int(4, "the element type")?;
        let m = r.count(s, "the block's element count", 2 * s, 4)?;
        total = total.saturating_add(m);
        if total > n {
            return Err(r.err(
                bat,
                format!("the element blocks hold more than the {n} elements announced"),
            ));
        }
        for _ in 0..m {
            let (at, tag) = r.int(s, "an element tag")?;
            element(r, st, at, tag, ty, s)?;
        }
    }
    if total != n {
        return Err(r.err(
            r.c.pos,
            format!("the element blocks hold {total} elements, but {n} were announced"),
        ));
    }
    Ok(())
}
