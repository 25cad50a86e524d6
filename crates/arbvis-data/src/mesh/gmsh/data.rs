//! `$NodeData` and `$ElementData` sections: read as they come, matched with the nodes and
//! elements of the whole file at its end.

use std::collections::{HashMap, HashSet};

use super::reader::{Reader, TagMap};
use crate::mesh::read::vec_for;
use crate::mesh::{DataArray, MeshError, ReadArray};
use arbvis_core::budget;

/// A `$NodeData` / `$ElementData` section as read. Its entries name nodes and elements
/// by tag; they are matched at the end of the file, when every `$Nodes` and `$Elements`
/// section has been read (gmsh writes data after the mesh, but nothing in the format
/// says so), and the dense array (NaN where no entry is) is made only then, all arrays
/// at once within the memory budget: a section holds only what its entries hold.
pub(super) struct PendingData {
    nodes: bool,
    /// The section keyword.
    at: usize,
    /// The entry count's position.
    entries_at: usize,
    name: Option<String>,
    k: usize,
    /// Each entry's tag and position.
    tags: Vec<(usize, i64)>,
    /// `k` values per entry.
    values: Vec<f64>,
}

/// `$NodeData` (`nodes`) or `$ElementData` whose keyword is at `at`: string, real and
/// integer tags, then `tag value...` rows.
pub(super) fn read(r: &mut Reader, nodes: bool, at: usize) -> Result<PendingData, MeshError> {
    let (sat, ns) = r.c.parse::<i64>("the number of string tags")?;
    if !(0..=1024).contains(&ns) {
        return Err(r.c.err(sat, format!("{ns} string tags")));
    }
    r.c.end_line()?;
    let mut name = None;
    for _ in 0..ns {
        let (_, l) = r.c.line();
        let s = String::from_utf8_lossy(l.trim_ascii())
            .trim_matches('"')
            .to_string();
        name.get_or_insert(s);
    }
    let (rat, nr) = r.c.parse::<i64>("the number of real tags")?;
    if !(0..=1024).contains(&nr) {
        return Err(r.c.err(rat, format!("{nr} real tags")));
    }
    for _ in 0..nr {
        r.c.parse::<f64>("a real tag")?;
    }
    let (iat, ni) = r.c.parse::<i64>("the number of integer tags")?;
    if !(3..=1024).contains(&ni) {
        return Err(r.c.err(
            iat,
            format!(
                "expected at least 3 integer tags (time step, components, entries), found {ni}"
            ),
        ));
    }
    let mut ints = Vec::new();
    for _ in 0..ni {
        ints.push(r.c.parse::<i64>("an integer tag")?);
    }
    let (kat, k) = ints[1];
    let (eat, entries) = ints[2];
    if !(1..=9).contains(&k) {
        return Err(r
            .c
            .err(kat, format!("{k} components per entry (expected 1 to 9)")));
    }
    if entries < 0 {
        return Err(r
            .c
            .err(eat, format!("the entry count is negative: {entries}")));
    }
    let k = k as usize;
    let per = if r.binary { 4 + 8 * k } else { 2 * (k + 1) };
    let entries =
        r.c.check_fits(eat, "the data entries", entries as u64, per)?;
    if r.binary {
        r.c.end_line()?;
    }
    let what = "the data entries";
    let mut tags = vec_for(entries, what).map_err(|m| r.c.err(eat, m))?;
    let mut values = vec_for(entries * k, what).map_err(|m| r.c.err(eat, m))?;
    for _ in 0..entries {
        tags.push(r.int(4, "an entry's tag")?);
        for _ in 0..k {
            values.push(r.f64("a data value")?.1);
        }
    }
    Ok(PendingData {
        nodes,
        at,
        entries_at: eat,
        name,
        k,
        tags,
        values,
    })
}

/// Match every data section's entries with the nodes and elements of the whole file and
/// make the point and cell arrays.
/// `nodes` and `elements`: how many there are and their tags.
pub(super) fn resolve(
    r: &Reader,
    pending: &[PendingData],
    nodes: (usize, &TagMap),
    elements: (usize, &TagMap),
) -> Result<(Vec<ReadArray>, Vec<ReadArray>), MeshError> {
    let count = |d: &PendingData| if d.nodes { nodes.0 } else { elements.0 };
    let total = pending.iter().fold(0u64, |sum, d| {
        sum.saturating_add(budget::times(count(d) as u64, 8 * d.k as u64))
    });
    if let Some(first) = pending.first() {
        budget::check(
            format!(
                "making the {} $NodeData/$ElementData sections into arrays (a value per node or element and component)",
                pending.len()
            ),
            total,
        )
        .map_err(|e| r.c.err(first.at, e.to_string()))?;
    }
    let (mut point_arrays, mut cell_arrays) = (Vec::<ReadArray>::new(), Vec::<ReadArray>::new());
    let (mut point_names, mut cell_names) = (HashSet::new(), HashSet::new());
    let (mut point_next, mut cell_next) = (HashMap::new(), HashMap::new());
    for d in pending {
        let (n, what, map) = if d.nodes {
            (nodes.0, "node", nodes.1)
        } else {
            (elements.0, "element", elements.1)
        };
        if d.tags.len() > n {
            return Err(r.c.err(
                d.entries_at,
                format!("{} entries for the {n} {what}s of the file", d.tags.len()),
            ));
        }
        let k = d.k;
        let mut values = vec_for(n * k, "data values").map_err(|m| r.c.err(d.at, m))?;
        values.resize(n * k, f64::NAN);
        for (e, &(tat, tag)) in d.tags.iter().enumerate() {
            let i = map.get(tag).ok_or_else(|| {
                r.err(
                    tat,
                    format!(
                        "data entry for {what} {tag}, which is in no ${}s section",
                        if d.nodes { "Node" } else { "Element" }
                    ),
                )
            })? as usize;
            values[i * k..i * k + k].copy_from_slice(&d.values[e * k..e * k + k]);
        }
        let list = if d.nodes {
            &mut point_arrays
        } else {
            &mut cell_arrays
        };
        let base = d.name.clone().unwrap_or_else(|| {
            if d.nodes {
                "NodeData".into()
            } else {
                "ElementData".into()
            }
        });
        // A repeated name (time steps) gets " #2", " #3", ...: the next number per name
        // is kept, so thousands of sections of one name cost no rescans.
        let (used, next) = if d.nodes {
            (&mut point_names, &mut point_next)
        } else {
            (&mut cell_names, &mut cell_next)
        };
        let mut m = next.get(&base).copied().unwrap_or(1);
        let mut unique = if m == 1 {
            base.clone()
        } else {
            format!("{base} #{m}")
        };
        while used.contains(&unique) {
            m += 1;
            unique = format!("{base} #{m}");
        }
        next.insert(base, m + 1);
        used.insert(unique.clone());
        list.push(ReadArray {
            array: DataArray {
                name: unique,
                components: k,
                values,
            },
            at: d.at,
        });
    }
    Ok((point_arrays, cell_arrays))
}
