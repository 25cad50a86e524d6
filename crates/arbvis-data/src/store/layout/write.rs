//! Writing the layout's nodes: each level's group, coordinates, data arrays and brick
//! ranges, the trace mask and map coordinates, and the root last.

use std::path::Path;
use std::sync::Arc;

use serde_json::{json, Map, Value};
use zarrs::array::{data_type, Array, ArraySubset};
use zarrs::filesystem::FilesystemStore;

use super::Stats;
use super::{
    array, coarsen, coordinates, group, root_attributes, stats_v1, storage_error, LayoutOptions,
    NAN_FILL_VALUE,
};
use crate::store::compression::Compression;
use crate::store::meta::StoreMeta;
use crate::store::StoreError;

/// What a conversion writes chunks into: per attribute and level the data array, and
/// (level 0, chunked by columns) the trace mask and map coordinates.
pub struct Writers {
    /// Data arrays by attribute, then level (none where an MDIO dataset's own variable is
    /// level 0 of the attribute).
    pub data: Vec<Vec<Option<Array<FilesystemStore>>>>,
    /// `trace_mask`, chunks of `B x B` traces (none beside an MDIO dataset's own).
    pub mask: Option<Array<FilesystemStore>>,
    /// `cdp_x` and `cdp_y`, chunks of `B x B` traces, where the survey gives them.
    pub cdp: Option<[Array<FilesystemStore>; 2]>,
}

/// Every node's metadata (and the coordinate arrays' values), for `meta` and, once the
/// conversion ends, the statistics; returns the arrays to write chunks into. `beside`: the
/// root attributes of an MDIO dataset converted in place, whose own variable, coordinates
/// and mask are level 0 and are left as they are (its root gains the `arbvis` attribute).
pub fn write_layout(
    storage: &Arc<FilesystemStore>,
    store: &Path,
    meta: &StoreMeta,
    options: &LayoutOptions,
    stats: Option<&[Stats]>,
    beside: Option<&Map<String, Value>>,
) -> Result<Writers, StoreError> {
    let w = Layout {
        storage,
        store,
        meta,
        options,
        stats,
        beside,
        dims: ["inline", "crossline", meta.domain().as_str()].map(str::to_string),
    };
    let coords = coordinates(meta);
    // By attribute, then level.
    let mut data: Vec<Vec<Option<Array<FilesystemStore>>>> =
        meta.attributes.iter().map(|_| Vec::new()).collect();
    for level in 0..meta.levels {
        let names = LevelNames::new(&w.dims, level);
        if level > 0 {
            w.level_group(level, &names.prefix)?;
        }
        w.level_coordinates(level, &names, &coords)?;
        for (attr, arrays) in data.iter_mut().enumerate() {
            arrays.push(w.attribute(level, attr, &names)?);
        }
    }
    let mask = w.trace_mask()?;
    let cdp = w.cdp()?;
    w.root()?;
    Ok(Writers { data, mask, cdp })
}

/// What every node is written with.
struct Layout<'a> {
    storage: &'a Arc<FilesystemStore>,
    store: &'a Path,
    meta: &'a StoreMeta,
    options: &'a LayoutOptions,
    stats: Option<&'a [Stats]>,
    beside: Option<&'a Map<String, Value>>,
    /// `inline`, `crossline` and the domain (`time`, `depth`, `sample`).
    dims: [String; 3],
}

/// A level's group and dimension names.
struct LevelNames {
    /// The group (`""` for level 0, `/level_L`).
    prefix: String,
    /// Its dimensions (`inline_L`, ...): xarray's data tree aligns a group's dimensions
    /// with its parent's of the same name, so each level has its own.
    dims: Vec<String>,
    /// Its brick ranges' dimensions (`inline_brick_L`, ..., `min_max`).
    bricks: Vec<String>,
}

impl LevelNames {
    fn new(dims: &[String; 3], level: usize) -> LevelNames {
        let (prefix, suffix) = if level == 0 {
            (String::new(), String::new())
        } else {
            (format!("/level_{level}"), format!("_{level}"))
        };
        LevelNames {
            prefix,
            dims: dims.iter().map(|d| format!("{d}{suffix}")).collect(),
            bricks: dims
                .iter()
                .map(|d| format!("{d}_brick{suffix}"))
                .chain(["min_max".to_string()])
                .collect(),
        }
    }
}

impl Layout<'_> {
    /// Level `level`'s group, described.
    fn level_group(&self, level: usize, prefix: &str) -> Result<(), StoreError> {
        let mut attributes = Map::new();
        attributes.insert(
            "description".into(),
            json!(format!(
                "arbvis level {level}: every axis halved {level} times from the root's"
            )),
        );
        group(self.storage, self.store, prefix, attributes)
    }

    /// A level's coordinates: integers where they are whole, else float64 (an MDIO
    /// dataset's own at its level 0).
    fn level_coordinates(
        &self,
        level: usize,
        names: &LevelNames,
        coords: &[Vec<f64>; 3],
    ) -> Result<(), StoreError> {
        if level == 0 && self.beside.is_some() {
            return Ok(());
        }
        for (axis, name) in [
            (2usize, &names.dims[0]),
            (1, &names.dims[1]),
            (0, &names.dims[2]),
        ] {
            let values = coarsen(&coords[axis], level);
            self.coordinate(&format!("{}/{name}", names.prefix), name, &values)?;
        }
        Ok(())
    }

    /// One coordinate array `node` on dimension `name`, its values written: int32 where
    /// every value is whole (and fits), else float64.
    fn coordinate(&self, node: &str, name: &str, values: &[f64]) -> Result<(), StoreError> {
        let (storage, store) = (self.storage, self.store);
        let n = values.len() as u64;
        let whole = values.iter().all(|v| v.fract() == 0.0 && v.abs() < 2e9);
        let make = |kind, fill| {
            array(
                storage,
                store,
                node,
                vec![n],
                vec![n],
                kind,
                fill,
                &[name],
                self.options.compression,
                Map::new(),
            )
        };
        let subset = ArraySubset::new_with_shape(vec![n]);
        let stored = if whole {
            let v: Vec<i32> = values.iter().map(|&x| x as i32).collect();
            make(
                data_type::int32(),
                zarrs::array::builder::ArrayBuilderFillValue::from(i32::MAX),
            )?
            .store_array_subset(&subset, v.as_slice())
        } else {
            make(
                data_type::float64(),
                zarrs::array::builder::ArrayBuilderFillValue::from(f64::NAN),
            )?
            .store_array_subset(&subset, values)
        };
        stored.map_err(|e| storage_error(store, e))
    }

    /// Level 0's attributes of data variable `attr`: its map coordinates, fill value and
    /// statistics where known.
    fn variable_attributes(&self, attr: usize) -> Map<String, Value> {
        let mut m = Map::new();
        if self.options.has_cdp {
            m.insert("coordinates".into(), json!("cdp_x cdp_y"));
        }
        m.insert("_FillValue".into(), json!(NAN_FILL_VALUE));
        if let Some(s) = self.stats {
            m.insert("statsV1".into(), stats_v1(self.meta, attr, &s[attr]));
        }
        m
    }

    /// Attribute `attr`'s data array at `level` (none where it is an MDIO dataset's
    /// own) and its brick ranges.
    fn attribute(
        &self,
        level: usize,
        attr: usize,
        names: &LevelNames,
    ) -> Result<Option<Array<FilesystemStore>>, StoreError> {
        let (storage, store, meta) = (self.storage, self.store, self.meta);
        let compression = self.options.compression;
        let am = &meta.attributes[attr];
        let b = meta.brick as u64;
        let level_dims: Vec<&str> = names.dims.iter().map(String::as_str).collect();
        let d = meta.level_dims(level);
        let shape = vec![d[2] as u64, d[1] as u64, d[0] as u64];
        let attributes = if level == 0 {
            self.variable_attributes(attr)
        } else {
            Map::new()
        };
        let node = format!("{}/{}", names.prefix, am.name);
        let own = level == 0 && attr == 0 && self.beside.is_some();
        let a = if own {
            None
        } else if am.dtype == "float16" {
            Some(array(
                storage,
                store,
                &node,
                shape,
                vec![b; 3],
                data_type::float16(),
                half::f16::NAN,
                &level_dims,
                compression,
                attributes,
            )?)
        } else {
            Some(array(
                storage,
                store,
                &node,
                shape,
                vec![b; 3],
                data_type::float32(),
                f32::NAN,
                &level_dims,
                compression,
                attributes,
            )?)
        };
        let c = meta.brick_counts(level);
        let rshape = vec![c[2] as u64, c[1] as u64, c[0] as u64, 2];
        let brick_dims: Vec<&str> = names.bricks.iter().map(String::as_str).collect();
        array(
            storage,
            store,
            &format!("{}/{}_range", names.prefix, am.name),
            rshape.clone(),
            rshape,
            data_type::float32(),
            f32::NAN,
            &brick_dims,
            Compression::None,
            Map::new(),
        )?;
        Ok(a)
    }

    /// The traces' shape (crossline, inline) and chunks (`B x B`).
    fn traces(&self) -> (Vec<u64>, Vec<u64>) {
        let [_, nj, nk] = self.meta.dims;
        let b = self.meta.brick as u64;
        (vec![nk as u64, nj as u64], vec![b, b])
    }

    /// `trace_mask` (none beside an MDIO dataset's own).
    fn trace_mask(&self) -> Result<Option<Array<FilesystemStore>>, StoreError> {
        if self.beside.is_some() {
            return Ok(None);
        }
        let (traces, chunks) = self.traces();
        let dims = [self.dims[0].as_str(), self.dims[1].as_str()];
        Ok(Some(array(
            self.storage,
            self.store,
            "/trace_mask",
            traces,
            chunks,
            data_type::bool(),
            zarrs::array::FillValue::from(false),
            &dims,
            self.options.compression,
            if self.options.has_cdp {
                json!({"coordinates": "cdp_x cdp_y"})
                    .as_object()
                    .cloned()
                    .unwrap_or_default()
            } else {
                Map::new()
            },
        )?))
    }

    /// `cdp_x` and `cdp_y`, where the survey has them; in place, the dataset's own trace
    /// mask and map coordinates stay as they are.
    fn cdp(&self) -> Result<Option<[Array<FilesystemStore>; 2]>, StoreError> {
        if !self.options.has_cdp || self.beside.is_some() {
            return Ok(None);
        }
        let (traces, chunks) = self.traces();
        let dims = [self.dims[0].as_str(), self.dims[1].as_str()];
        let coordinate = |name: &str| {
            array(
                self.storage,
                self.store,
                name,
                traces.clone(),
                chunks.clone(),
                data_type::float64(),
                f64::NAN,
                &dims,
                self.options.compression,
                json!({"unitsV1": {"length": "m"}, "_FillValue": NAN_FILL_VALUE})
                    .as_object()
                    .cloned()
                    .unwrap_or_default(),
            )
        };
        Ok(Some([coordinate("/cdp_x")?, coordinate("/cdp_y")?]))
    }

    /// The root last: its `complete` flag only once every other node is written.
    fn root(&self) -> Result<(), StoreError> {
        let store = self.store;
        let mut root = root_attributes(self.meta, &self.options.created_on)
            .map_err(|e| storage_error(store, e))?;
        if let Some(own) = self.beside {
            let arbvis = root.remove("arbvis");
            root = own.clone();
            if let Some(a) = arbvis {
                root.insert("arbvis".into(), a);
            }
        }
        group(self.storage, store, "/", root)
    }
}
