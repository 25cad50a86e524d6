//! The length unit of a LAS/LAZ file's coordinates, for the axis names (`x (ft)`), from
//! the projection records the file carries: an OGC WKT record (`LASF_Projection` 2112)
//! or the GeoTIFF keys (`LASF_Projection` 34735: `ProjLinearUnitsGeoKey` 3076 and
//! `VerticalUnitsGeoKey` 4099). A file that says nothing gets no unit: LAS does not fix
//! one (autzen's coordinates are in feet).
//!
//! The VLRs are found by the data crate's LAS reader
//! ([`arbvis_data::points::lasfile::layout::vlrs_in_head`]).
//!
//! Decisions: only the VLRs between the header and the points are read (at most
//! [`MAX_HEADER_BYTES`]; a LAS 1.4 WKT kept in an extended VLR after the points is not
//! looked for); every offset and length is checked against the bytes read, and any
//! damage means "no unit", never an error: the viewer shows the points either way.

use std::io::Read;
use std::path::Path;

use arbvis_data::le::u16_get as u16_at;
use arbvis_data::points::lasfile::layout::vlrs_in_head;

/// Most bytes read from the start of the file for its header and VLRs.
pub const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Units of a cloud's coordinates: horizontal (x, y) and vertical (z).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Units {
    /// x and y (`m`, `ft`, `US ft`, `°`).
    pub horizontal: Option<String>,
    /// z.
    pub vertical: Option<String>,
}

/// The units a LAS/LAZ file at `path` states (none when unreadable or unstated).
pub fn las_units(path: &Path) -> Units {
    let Ok((file, _)) = arbvis_core::input::open_regular(path) else {
        return Units::default();
    };
    let mut bytes = Vec::new();
    if file.take(MAX_HEADER_BYTES).read_to_end(&mut bytes).is_err() {
        return Units::default();
    }
    from_header(&bytes)
}

/// The units stated by the VLRs of a LAS header held in `b` (the file's first bytes).
pub fn from_header(b: &[u8]) -> Units {
    let mut units = Units::default();
    let mut wkt = None;
    let mut keys = None;
    for vlr in vlrs_in_head(b) {
        if vlr.user_raw.starts_with(b"LASF_Projection") {
            let body = &b[vlr.data];
            match vlr.record_id {
                2112 => wkt = Some(String::from_utf8_lossy(body).into_owned()),
                34735 => keys = Some(body.to_vec()),
                _ => {}
            }
        }
    }
    if let Some(text) = wkt {
        units = from_wkt(&text);
    }
    if let Some(k) = keys {
        let geo = from_geokeys(&k);
        units.horizontal = units.horizontal.or(geo.horizontal);
        units.vertical = units.vertical.or(geo.vertical);
    }
    units
}

/// A unit's short name from its WKT or EPSG name.
fn short(name: &str) -> Option<String> {
    let n = name.to_ascii_lowercase().replace(['_', ' '], "");
    Some(
        match n.as_str() {
            "metre" | "meter" | "metres" | "meters" | "m" => "m",
            "foot" | "feet" | "internationalfoot" | "ft" => "ft",
            "usfoot" | "footus" | "ussurveyfoot" | "ftus" | "usft" => "US ft",
            "degree" | "degrees" => "°",
            _ => return None,
        }
        .to_string(),
    )
}

/// The last `UNIT["name"` in `text`.
fn last_unit(text: &str) -> Option<String> {
    let at = text.rfind("UNIT[\"")? + 6;
    let end = text[at..].find('"')? + at;
    short(&text[at..end])
}

/// Units from OGC WKT: the projected system's last unit (x, y), the vertical system's
/// (z; the horizontal one when there is none).
pub fn from_wkt(text: &str) -> Units {
    let (horizontal, vertical) = match text.find("VERT_CS") {
        Some(v) => (last_unit(&text[..v]), last_unit(&text[v..])),
        None => (last_unit(text), None),
    };
    Units {
        vertical: vertical.or_else(|| horizontal.clone()),
        horizontal,
    }
}

/// Units from a GeoKeyDirectory: `ProjLinearUnitsGeoKey` and `VerticalUnitsGeoKey`
/// (EPSG 9001 metre, 9002 foot, 9003 US survey foot).
pub fn from_geokeys(b: &[u8]) -> Units {
    let code = |key: u16| -> Option<String> {
        let n = u16_at(b, 6)? as usize;
        (0..n)
            .find_map(|i| {
                let e = 8 + i * 8;
                (u16_at(b, e)? == key && u16_at(b, e + 2)? == 0).then(|| u16_at(b, e + 6))?
            })
            .and_then(|v| match v {
                9001 => Some("m".to_string()),
                9002 => Some("ft".to_string()),
                9003 => Some("US ft".to_string()),
                _ => None,
            })
    };
    let horizontal = code(3076);
    Units {
        vertical: code(4099).or_else(|| horizontal.clone()),
        horizontal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A LAS header of 227 bytes followed by `vlrs` (user id, record id, data).
    fn las(vlrs: &[(&str, u16, Vec<u8>)]) -> Vec<u8> {
        let mut b = vec![0u8; 227];
        b[0..4].copy_from_slice(b"LASF");
        b[94..96].copy_from_slice(&227u16.to_le_bytes());
        b[100..104].copy_from_slice(&(vlrs.len() as u32).to_le_bytes());
        for (user, id, data) in vlrs {
            let mut h = vec![0u8; 54];
            h[2..2 + user.len()].copy_from_slice(user.as_bytes());
            h[18..20].copy_from_slice(&id.to_le_bytes());
            h[20..22].copy_from_slice(&(data.len() as u16).to_le_bytes());
            b.extend(h);
            b.extend(data);
        }
        b
    }

    fn keys(entries: &[(u16, u16)]) -> Vec<u8> {
        let mut v = vec![1u16, 1, 0, entries.len() as u16];
        for &(k, value) in entries {
            v.extend([k, 0, 1, value]);
        }
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn wkt_and_geokeys() {
        // autzen's WKT: degrees in its GEOGCS, feet for the projection.
        let autzen = "PROJCS[\"NAD_1983_HARN_Lambert_Conformal_Conic\",GEOGCS[\"GCS\",UNIT[\"degree\",0.0174532925199433]],PARAMETER[\"false_northing\",0],UNIT[\"foot\",0.3048,AUTHORITY[\"EPSG\",\"9002\"]]]";
        let u = from_header(&las(&[
            ("LASF_Projection", 34735, keys(&[(1024, 1)])),
            ("LASF_Projection", 2112, autzen.as_bytes().to_vec()),
        ]));
        assert_eq!(u.horizontal.as_deref(), Some("ft"));
        assert_eq!(u.vertical.as_deref(), Some("ft"));
        // A compound system: metres across, US feet up.
        let compound = "COMPD_CS[\"x\",PROJCS[\"utm\",UNIT[\"metre\",1]],VERT_CS[\"navd88\",UNIT[\"US survey foot\",0.3048006]]]";
        let u = from_wkt(compound);
        assert_eq!(
            (u.horizontal.as_deref(), u.vertical.as_deref()),
            (Some("m"), Some("US ft"))
        );
        // GeoTIFF keys only.
        let u = from_header(&las(&[(
            "LASF_Projection",
            34735,
            keys(&[(3076, 9001), (4099, 9002)]),
        )]));
        assert_eq!(
            (u.horizontal.as_deref(), u.vertical.as_deref()),
            (Some("m"), Some("ft"))
        );
    }

    #[test]
    fn silence_and_damage_give_no_unit() {
        assert_eq!(from_header(&las(&[])), Units::default());
        assert_eq!(from_header(b"LASF"), Units::default());
        assert_eq!(from_header(b"not a las file at all"), Units::default());
        // A VLR whose length runs past the bytes: ignored, no panic.
        let mut b = las(&[("LASF_Projection", 2112, b"UNIT[\"metre\"".to_vec())]);
        b.truncate(b.len() - 3);
        assert_eq!(from_header(&b), Units::default());
        // Many VLRs declared, none there.
        let mut b = las(&[]);
        b[100..104].copy_from_slice(&u32::MAX.to_le_bytes());
        assert_eq!(from_header(&b), Units::default());
        // An unknown unit and a truncated key directory.
        assert_eq!(from_wkt("UNIT[\"furlong\",201.168]"), Units::default());
        assert_eq!(from_geokeys(&[1, 0, 1, 0, 0, 0, 9, 0]), Units::default());
    }

    #[test]
    fn autzen_is_in_feet() {
        let path = arbvis_core::input::data_file("points/autzen_trim.laz");
        assert_eq!(las_units(&path).horizontal.as_deref(), Some("ft"));
    }
}
