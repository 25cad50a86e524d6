//! The two cell layouts of legacy files: the classic `CELLS n size` list (a count before
//! each cell's point indices) and VTK 9's `OFFSETS` / `CONNECTIVITY` arrays.

use super::reader::Reader;
use crate::mesh::cells::RawCells;
use crate::mesh::read::{vec_for, Num};
use crate::mesh::MeshError;

/// `CELLS n size` then `size` integers: for each cell a count and its point indices.
pub(super) fn classic_cells(r: &mut Reader, n: u64, size: u64) -> Result<RawCells, MeshError> {
    let t = if r.binary { Num::I32 } else { Num::I64 };
    let at = r.c.pos;
    let size =
        r.c.check_fits(at, "the cell list size", size, r.min_bytes(t))?;
    let n = r.c.check_fits(at, "the cell count", n, r.min_bytes(t))?;
    let (v, start) = r.ints(size, t, "the cell list")?;
    let mut cells = RawCells {
        text: !r.binary,
        token_base: (!r.binary).then_some(start),
        ..RawCells::default()
    };
    cells.offsets = vec_for(n + 1, "cell offsets").map_err(|m| r.c.err(at, m))?;
    cells.at = vec_for(n, "cell positions").map_err(|m| r.c.err(at, m))?;
    cells.nodes = vec_for(size.saturating_sub(n), "cell nodes").map_err(|m| r.c.err(at, m))?;
    cells.offsets.push(0);
    let mut j = 0;
    for i in 0..n {
        let k = *v.get(j).ok_or_else(|| {
            r.int_err(
                start,
                j,
                Num::I32,
                format!("the cell list of size {size} ends before cell {i} of {n}"),
            )
        })?;
        if k < 0 || (k as u64) > (size - j - 1) as u64 {
            return Err(r.int_err(
                start,
                j,
                Num::I32,
                format!(
                    "cell {i} has {k} points, but only {} values are left in the cell list",
                    size - j - 1
                ),
            ));
        }
        cells.at.push(if r.binary { start + j * 4 } else { j });
        for (m, &p) in v[j + 1..j + 1 + k as usize].iter().enumerate() {
            cells.nodes.push(index(r, start, j + 1 + m, p, i)?);
        }
        j += 1 + k as usize;
        cells.offsets.push(cells.nodes.len());
    }
    if j != size {
        return Err(r.int_err(
            start,
            j,
            Num::I32,
            format!("CELLS declares {size} values but its {n} cells use {j}"),
        ));
    }
    Ok(cells)
}

fn index(r: &Reader, start: usize, j: usize, p: i64, cell: usize) -> Result<u32, MeshError> {
    u32::try_from(p)
        .ok()
        .filter(|&p| p < u32::MAX)
        .ok_or_else(|| {
            r.int_err(
                start,
                j,
                Num::I32,
                format!("cell {cell} has point index {p}, outside 0 to 2^32 - 2"),
            )
        })
}

/// VTK 9's layout: `CELLS nOffsets nConnectivity`, `OFFSETS type` and
/// `CONNECTIVITY type` arrays.
pub(super) fn modern_cells(r: &mut Reader, n_off: u64, n_conn: u64) -> Result<RawCells, MeshError> {
    let kw_at = r.c.keyword("OFFSETS")?;
    let args = r.args();
    let t = r.type_arg(&args, 0, kw_at)?;
    let n_off =
        r.c.check_fits(kw_at, "the offset count", n_off, r.min_bytes(t))?;
    let (offsets, off_start) = r.ints(n_off, t, "the cell offsets")?;
    let kw_at = r.c.keyword("CONNECTIVITY")?;
    let args = r.args();
    let tc = r.type_arg(&args, 0, kw_at)?;
    let n_conn =
        r.c.check_fits(kw_at, "the connectivity size", n_conn, r.min_bytes(tc))?;
    let (conn, conn_start) = r.ints(n_conn, tc, "the connectivity")?;
    let n = n_off.saturating_sub(1);
    let mut cells = RawCells {
        text: !r.binary,
        token_base: (!r.binary).then_some(conn_start),
        ..RawCells::default()
    };
    cells.offsets = vec_for(n + 1, "cell offsets").map_err(|m| r.c.err(kw_at, m))?;
    cells.at = vec_for(n, "cell positions").map_err(|m| r.c.err(kw_at, m))?;
    cells.offsets.push(0);
    if offsets.first().is_some_and(|&o| o != 0) {
        return Err(r.int_err(
            off_start,
            0,
            t,
            format!("the first offset must be 0, found {}", offsets[0]),
        ));
    }
    for i in 0..n {
        let (a, b) = (offsets[i], offsets[i + 1]);
        if b < a || b as u64 > n_conn as u64 {
            return Err(r.int_err(off_start, i + 1, t, format!(
                "offset {} is {b}: offsets must not decrease and must stay within the {n_conn} connectivity values", i + 1
            )));
        }
        cells.offsets.push(b as usize);
        cells.at.push(if r.binary {
            conn_start + a as usize * tc.size()
        } else {
            a as usize
        });
    }
    if n > 0 && offsets[n] as usize != n_conn {
        return Err(r.int_err(
            off_start,
            n,
            t,
            format!(
                "the last offset is {} but CONNECTIVITY has {n_conn} values",
                offsets[n]
            ),
        ));
    }
    cells.nodes = vec_for(n_conn, "cell nodes").map_err(|m| r.c.err(kw_at, m))?;
    let mut cell = 0;
    for (j, &p) in conn.iter().enumerate() {
        while cell + 1 < cells.offsets.len() && cells.offsets[cell + 1] <= j {
            cell += 1;
        }
        let m = u32::try_from(p)
            .ok()
            .filter(|&p| p < u32::MAX)
            .ok_or_else(|| {
                r.int_err(
                    conn_start,
                    j,
                    tc,
                    format!("cell {cell} has point index {p}, outside 0 to 2^32 - 2"),
                )
            })?;
        cells.nodes.push(m);
    }
    Ok(cells)
}
