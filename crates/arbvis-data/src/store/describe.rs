//! `arbvis inspect STORE`: what a store holds, read through the same checks as opening it
//! (its metadata and every array), finished or not: the format, the dimensions with the
//! survey's own coordinates, each attribute's type, chunks, codecs and statistics, the
//! levels, an interrupted conversion's progress, and the size on disk.

use std::fmt::Write;
use std::path::Path;

use super::meta::StoreMeta;
use super::StoreError;

/// Most files counted for the size on disk (a store of 10^6 chunks is counted whole).
const MAX_FILES_COUNTED: u64 = 10_000_000;

/// The description `inspect` prints for the store at `store`.
pub fn describe(store: &Path) -> Result<String, StoreError> {
    if let Some(flavour) = super::mdio::flavour(store)?.filter(|f| f.in_place()) {
        return describe_mdio(store, &flavour);
    }
    let meta = super::check::read_meta(store)?;
    let (arrays, _) = super::check::open_arrays(store, &meta)?;
    let mut s = String::new();
    let state = if meta.complete {
        "complete".to_string()
    } else {
        progress(store, &meta)
    };
    let _ = writeln!(s, "{}", store.display());
    let layout = if meta.version >= 2 {
        "zarr v3, the MDIO v1 layout"
    } else {
        "zarr v3, the layout before MDIO"
    };
    let _ = writeln!(
        s,
        "format: arbvis store version {} ({layout}), {state}",
        meta.version
    );
    let src = &meta.source;
    let _ = writeln!(s, "source: {} {} ({} bytes)", src.kind, src.path, src.bytes);
    for (k, v) in &src.facts {
        let _ = writeln!(s, "  {k}: {v}");
    }
    let _ = writeln!(s, "dimensions:");
    for line in axes(&meta) {
        let _ = writeln!(s, "  {line}");
    }
    let _ = writeln!(
        s,
        "levels: {} of {}³ bricks (filter: {})",
        meta.levels, meta.brick, meta.filter
    );
    for level in 0..meta.levels {
        let d = meta.level_dims(level);
        let c = meta.brick_counts(level);
        let _ = writeln!(
            s,
            "  level {level}: {} x {} x {} voxels, {} x {} x {} bricks",
            d[0], d[1], d[2], c[0], c[1], c[2]
        );
    }
    let _ = writeln!(s, "attributes:");
    for (a, attr) in meta.attributes.iter().enumerate() {
        let array = &arrays[a][0];
        let stats = match (attr.min, attr.max, attr.mean) {
            (Some(lo), Some(hi), Some(mean)) => format!("min {lo} max {hi} mean {mean:.6}"),
            _ => "statistics not yet written".into(),
        };
        let _ = writeln!(
            s,
            "  {}: {}, chunks {:?}, codecs {}, fill {}; {stats}, {} non-finite samples",
            attr.name,
            array.data_type.name(),
            array.chunks,
            array.codec_names(),
            array.fill_value,
            attr.non_finite
        );
    }
    size_line(&mut s, store);
    Ok(s)
}

/// An MDIO dataset: what arbvis draws of it, then every variable of the group.
fn describe_mdio(store: &Path, flavour: &super::mdio::Flavour) -> Result<String, StoreError> {
    use super::mdio::Flavour;
    let opened = super::Store::open(store)?;
    let meta = &opened.meta;
    let mut s = String::new();
    let _ = writeln!(s, "{}", store.display());
    let v0 = matches!(flavour, Flavour::V0);
    let zarr_v2 = matches!(flavour, Flavour::V0 | Flavour::V1 { zarr_v2: true, .. });
    let _ = writeln!(
        s,
        "format: {} (zarr {}), read in place: one level, no per-brick ranges",
        meta.source.kind,
        if zarr_v2 { "v2" } else { "v3" }
    );
    for (k, v) in &meta.source.facts {
        let _ = writeln!(s, "  {k}: {v}");
    }
    let _ = writeln!(s, "dimensions:");
    for line in axes(meta) {
        let _ = writeln!(s, "  {line}");
    }
    let a = &meta.attributes[0];
    if let (Some(lo), Some(hi)) = (a.min, a.max) {
        let _ = writeln!(
            s,
            "statistics ({}): min {lo} max {hi}",
            if v0 {
                "the dataset's"
            } else {
                "statsV1, non-zero samples"
            }
        );
    }
    if zarr_v2 {
        let _ = writeln!(
            s,
            "levels: none (MDIO keeps one resolution); `arbvis convert {} STORE` writes a store with levels, per-brick ranges and derived attributes (a zarr v2 dataset is not converted in place)",
            store.display()
        );
    } else {
        let _ = writeln!(
            s,
            "levels: none (MDIO keeps one resolution); `arbvis convert {}` adds levels, per-brick ranges and derived attributes beside its arrays, which makes turning faster",
            store.display()
        );
    }
    let _ = writeln!(s, "variables:");
    for folder in variables(store, v0, zarr_v2)? {
        let name = folder
            .strip_prefix(store)
            .unwrap_or(&folder)
            .to_string_lossy()
            .to_string();
        match super::zarr::open_array(&folder) {
            Ok(v) => {
                let dims = v
                    .dimension_names
                    .iter()
                    .flatten()
                    .map(|d| d.clone().unwrap_or_default())
                    .collect::<Vec<_>>()
                    .join(", ");
                let _ = writeln!(
                    s,
                    "  {name}: {}{} shape {:?}, chunks {:?}, codecs {}",
                    v.data_type.name(),
                    if dims.is_empty() {
                        String::new()
                    } else {
                        format!(" ({dims})")
                    },
                    v.shape,
                    v.chunks,
                    v.codec_names()
                );
            }
            Err(e) => {
                let _ = writeln!(s, "  {name}: not read by arbvis ({e})");
            }
        }
    }
    size_line(&mut s, store);
    Ok(s)
}

/// The folders of an MDIO dataset's variables, sorted: the group's children with a
/// `zarr.json` (v1), or those under `data/` and `metadata/` with a `.zarray` (v0).
fn variables(store: &Path, v0: bool, zarr_v2: bool) -> Result<Vec<std::path::PathBuf>, StoreError> {
    let parents = if v0 {
        vec![store.join("data"), store.join("metadata")]
    } else {
        vec![store.to_path_buf()]
    };
    let marker = if zarr_v2 { ".zarray" } else { "zarr.json" };
    let mut entries = Vec::new();
    for parent in parents {
        let Ok(list) = std::fs::read_dir(&parent) else {
            continue;
        };
        entries.extend(
            list.flatten()
                .map(|e| e.path())
                .filter(|p| p.join(marker).is_file()),
        );
    }
    entries.sort();
    Ok(entries)
}

/// The axes with their names, sizes and the survey's own coordinates where it gave them.
fn axes(meta: &StoreMeta) -> Vec<String> {
    let [ni, nj, nk] = meta.dims;
    let src = &meta.source;
    let numbers = |first_step: Option<[i64; 2]>, n: usize| {
        first_step.map_or(String::new(), |[first, step]| {
            let last = first.saturating_add(step.saturating_mul(n as i64 - 1));
            format!(", numbers {first}..{last} (step {step})")
        })
    };
    let s = src.sample_axis();
    let time = if s.unit.is_empty() {
        String::new()
    } else {
        let last = s.first + s.step * (ni as f64 - 1.0);
        format!(
            ", {} {}..{last} {} (every {} {})",
            s.domain, s.first, s.unit, s.step, s.unit
        )
    };
    vec![
        format!("sample: {ni}{time}"),
        format!("crossline: {nj}{}", numbers(src.crosslines, nj)),
        format!("inline: {nk}{}", numbers(src.inlines, nk)),
        format!(
            "spacing (sample, crossline, inline): {} {} {}",
            meta.spacing[0], meta.spacing[1], meta.spacing[2]
        ),
    ]
}

/// An interrupted conversion's progress, from its log.
fn progress(store: &Path, meta: &StoreMeta) -> String {
    let log = store.join(super::progress::PROGRESS_LOG);
    let total: u64 = (0..meta.levels)
        .map(|l| {
            let c = meta.brick_counts(l);
            (c[1] * c[2]) as u64
        })
        .sum();
    match super::progress::logged_columns(&log, meta) {
        Ok(done) => format!(
            "INCOMPLETE: an interrupted conversion, {done} of {total} columns written (run the same `arbvis convert` again to resume it)"
        ),
        Err(e) => format!("INCOMPLETE: no readable progress log ({e})"),
    }
}

/// The store's size on disk (a remote store's is not listed: HTTP has no listing).
fn size_line(s: &mut String, store: &Path) {
    if crate::fetch::url_of(store).is_some() {
        s.push_str("size: not listed (a remote store)\n");
        return;
    }
    let (bytes, files) = disk_use(store);
    let _ = writeln!(
        s,
        "size on disk: {:.1} MB in {files} files",
        bytes as f64 / 1e6
    );
}

/// Bytes and files under `folder` (links not followed).
fn disk_use(folder: &Path) -> (u64, u64) {
    let (mut bytes, mut files) = (0u64, 0u64);
    let mut stack = vec![folder.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let Ok(m) = std::fs::symlink_metadata(entry.path()) else {
                continue;
            };
            if m.is_dir() {
                stack.push(entry.path());
            } else {
                bytes += m.len();
                files += 1;
                if files >= MAX_FILES_COUNTED {
                    return (bytes, files);
                }
            }
        }
    }
    (bytes, files)
}
