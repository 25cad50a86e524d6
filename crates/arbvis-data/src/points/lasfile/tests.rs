use super::*;
use crate::le::{u32_at, u64_at};
use las::point::{Classification, Format};
use las::{Builder, Color, Point, Transform, Vector, Vlr, Writer};

fn name() -> &'static Path {
    Path::new("t.las")
}

/// One Extra Bytes descriptor (LAS 1.4 R15, 192 bytes).
pub(crate) fn descriptor(
    ty: u8,
    options: u8,
    label: &str,
    no_data: [u8; 8],
    scale: f64,
    offset: f64,
) -> Vec<u8> {
    let mut d = vec![0u8; 192];
    d[2] = ty;
    d[3] = options;
    d[4..4 + label.len()].copy_from_slice(label.as_bytes());
    d[40..48].copy_from_slice(&no_data);
    d[112..120].copy_from_slice(&scale.to_le_bytes());
    d[136..144].copy_from_slice(&offset.to_le_bytes());
    d
}

/// Extra bytes of the 1.4 fixture: a scaled i16 with no-data (2 bytes), an unscaled u8
/// (1), two undocumented bytes (2), a deprecated 3-array of f64 (24): 29 bytes.
const EXTRA: usize = 29;

fn extra_vlr() -> Vlr {
    let mut data = descriptor(
        4,
        1 | 8 | 16,
        "temperature",
        (-32768i64).to_le_bytes(),
        0.01,
        -10.0,
    );
    data.extend(descriptor(1, 0, "flags", [0; 8], 0.0, 0.0));
    data.extend(descriptor(0, 2, "", [0; 8], 0.0, 0.0));
    data.extend(descriptor(30, 0, "velocity", [0; 8], 0.0, 0.0));
    Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "extra bytes".into(),
        data,
    }
}

fn extra_bytes_of(i: usize) -> Vec<u8> {
    let mut e = Vec::new();
    let t: i16 = if i == 2 {
        -32768
    } else {
        1000 + 7 * (i % 1000) as i16
    };
    e.extend(t.to_le_bytes());
    e.push((i as u8).wrapping_add(200));
    e.extend([0xAA, 0xBB]);
    for k in 0..3 {
        e.extend((i as f64 * 10.0 + k as f64 + 0.25).to_le_bytes());
    }
    assert_eq!(e.len(), EXTRA);
    e
}

/// Point `i` of the fixtures: georeferenced at 1e5-1e6 m with millimetres.
fn fixture_point(i: usize) -> [f64; 3] {
    [
        512_345.678 + 13.001 * (i % 97) as f64,
        7_401_234.567 - 2.5 * ((i % 50) * (i % 50)) as f64,
        -1_234.005 + 0.333 * (i % 1000) as f64,
    ]
}

/// A LAS file of `n` points in `format` (6-10 make it 1.4 with extra bytes), LAZ when
/// `compressed`.
pub(crate) fn fixture(format: u8, n: usize, compressed: bool) -> Vec<u8> {
    let mut b = Builder::default();
    let extended = format >= 6;
    b.version = if extended { (1, 4) } else { (1, 2) }.into();
    b.point_format = Format::new(format).unwrap();
    b.point_format.is_compressed = compressed;
    let t = |offset: f64| Transform {
        scale: 0.001,
        offset,
    };
    b.transforms = Vector {
        x: t(500_000.0),
        y: t(7_400_000.0),
        z: t(0.0),
    };
    if extended {
        b.point_format.extra_bytes = EXTRA as u16;
        b.vlrs.push(extra_vlr());
    }
    let header = b.into_header().unwrap();
    let mut w = Writer::new(Cursor::new(Vec::new()), header).unwrap();
    for i in 0..n {
        let [x, y, z] = fixture_point(i);
        let color = Format::new(format).unwrap().has_color.then(|| {
            Color::new(
                (i as u16).wrapping_mul(300),
                65535u16.wrapping_sub(i as u16),
                7,
            )
        });
        w.write_point(Point {
            x,
            y,
            z,
            intensity: (i as u16).wrapping_mul(100),
            return_number: 1 + (i % 3) as u8,
            number_of_returns: 3,
            classification: Classification::new(if extended { 40 + i as u8 % 3 } else { 2 })
                .unwrap(),
            gps_time: Format::new(format)
                .unwrap()
                .has_gps_time
                .then_some(i as f64),
            color,
            extra_bytes: if extended {
                extra_bytes_of(i)
            } else {
                Vec::new()
            },
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
    w.into_inner().unwrap().into_inner()
}

fn check_fixture_points(c: &LasCloud, n: usize, format: u8) {
    assert_eq!(c.cloud.len(), n);
    for i in 0..n {
        let (p, q) = (c.cloud.original(i).unwrap(), fixture_point(i));
        for a in 0..3 {
            assert!((p[a] - q[a]).abs() < 1e-3, "point {i}: {p:?} vs {q:?}");
        }
    }
    let intensity: Vec<i32> = (0..n)
        .map(|i| (i as u16).wrapping_mul(100) as i32)
        .collect();
    assert_eq!(c.cloud.ints("intensity").unwrap(), intensity.as_slice());
    assert_eq!(c.cloud.ints("return_number").unwrap()[..3], [1, 2, 3]);
    assert_eq!(c.cloud.ints("number_of_returns").unwrap()[0], 3);
    if format >= 6 {
        assert_eq!(c.cloud.ints("classification").unwrap()[..3], [40, 41, 42]);
    }
    if Format::new(format).unwrap().has_color {
        let rgb = c.cloud.rgb.as_ref().unwrap();
        assert_eq!(rgb[2], [600, 65533, 7]);
    } else {
        assert!(c.cloud.rgb.is_none());
    }
}

#[test]
fn las_1_4_format_7_with_extra_bytes() {
    let bytes = fixture(7, 5, false);
    let c = parse(name(), &bytes).unwrap();
    assert_eq!(c.info.version, (1, 4));
    assert_eq!(c.info.point_format, 7);
    assert!(!c.info.compressed);
    assert_eq!(c.info.record_length as usize, 36 + EXTRA);
    assert_eq!(c.info.points, 5);
    // A writer that keeps the legacy count at 0 (as LAS 1.4 allows): the 64-bit one counts.
    assert_eq!(u64_at(&bytes, 247), 5);
    let mut zero = bytes.clone();
    zero[107..111].fill(0);
    assert_eq!(parse(name(), &zero).unwrap().cloud.len(), 5);
    assert_eq!(
        c.info.extra_bytes,
        [
            "temperature",
            "flags",
            "velocity[0]",
            "velocity[1]",
            "velocity[2]"
        ]
    );
    check_fixture_points(&c, 5, 7);
    let t = c.cloud.floats("temperature").unwrap();
    assert!(
        (t[0] - 0.0).abs() < 1e-6 && (t[1] - 0.07).abs() < 1e-6,
        "{t:?}"
    );
    assert!(t[2].is_nan());
    assert_eq!(
        c.cloud.attribute("temperature").unwrap().stats.non_finite,
        1
    );
    assert_eq!(c.cloud.ints("flags").unwrap(), &[200, 201, 202, 203, 204]);
    assert_eq!(c.cloud.floats("velocity[2]").unwrap()[3], 32.25);
    assert!(c.cloud.attribute("extra2").is_none());
    assert!(c
        .info
        .describe()
        .contains("LAS 1.4, point format 7, uncompressed, 65-byte records"));
}

#[test]
fn laz_1_2_and_1_4_decode_like_las() {
    for (format, n) in [(3, 300), (1, 70_000), (6, 200), (7, 130)] {
        let bytes = fixture(format, n, true);
        let c = parse(name(), &bytes).unwrap();
        assert!(c.info.compressed, "{format}");
        assert_eq!(c.info.point_format, format);
        check_fixture_points(&c, n, format);
        let plain = parse(name(), &fixture(format, n, false)).unwrap();
        assert_eq!(c.cloud.positions, plain.cloud.positions, "format {format}");
        assert_eq!(c.cloud.rgb, plain.cloud.rgb, "format {format}");
        for (a, b) in c.cloud.attributes.iter().zip(&plain.cloud.attributes) {
            assert_eq!(a.name, b.name);
            let same = (0..n).all(|i| {
                let (x, y) = (a.values.get(i).unwrap(), b.values.get(i).unwrap());
                x == y || (x.is_nan() && y.is_nan())
            });
            assert!(same, "format {format}: attribute {} differs", a.name);
        }
        assert_eq!(c.cloud.attributes.len(), plain.cloud.attributes.len());
    }
}

fn set(bytes: &mut [u8], at: usize, value: &[u8]) {
    bytes[at..at + value.len()].copy_from_slice(value);
}

fn error(bytes: &[u8]) -> String {
    parse(name(), bytes).unwrap_err().to_string()
}

#[test]
fn hostile_headers_are_refused_before_reading() {
    let good = fixture(6, 4, false);
    let offset = u32_at(&good, 96) as usize;
    // 2^40 points in the 64-bit count of LAS 1.4.
    let mut b = good.clone();
    set(&mut b, 107, &0u32.to_le_bytes());
    set(&mut b, 247, &(1u64 << 40).to_le_bytes());
    let e = error(&b);
    assert!(
        e.contains("declares 1099511627776 points, more than the 100000000"),
        "{e}"
    );
    // A legacy count that disagrees with the 64-bit one: refused, not trusted.
    let mut b = good.clone();
    set(&mut b, 107, &1_000_000u32.to_le_bytes());
    let e = error(&b);
    assert!(
        e.contains("t.las: at byte 107: the legacy point count 1000000 disagrees with LAS 1.4's 64-bit count 4 at byte 247"),
        "{e}"
    );
    // A count the data cannot hold (both fields).
    let mut b = good.clone();
    set(&mut b, 107, &1_000_000u32.to_le_bytes());
    set(&mut b, 247, &1_000_000u64.to_le_bytes());
    let e = error(&b);
    assert!(
        e.contains(&format!(
            "t.las: at byte {offset}: the header declares 1000000 points of 59 bytes"
        )),
        "{e}"
    );
    assert!(e.contains("hold only 4"), "{e}");
    // Offset to the points past the end.
    let mut b = good.clone();
    let past = b.len() as u32 + 1;
    set(&mut b, 96, &past.to_le_bytes());
    assert!(error(&b).contains("at byte 96: offset to point data"));
    // A VLR longer than the room before the points.
    let mut b = good.clone();
    set(&mut b, 375 + 20, &u16::MAX.to_le_bytes());
    assert!(
        error(&b).contains("at byte 375: VLR 0 holds 65535 bytes"),
        "{}",
        error(&b)
    );
    // 2^32 - 1 VLRs.
    let mut b = good.clone();
    set(&mut b, 100, &u32::MAX.to_le_bytes());
    assert!(error(&b).contains("VLR 1 (of 4294967295)"), "{}", error(&b));
    // An EVLR of 2^60 bytes.
    let mut b = good.clone();
    let evlr = b.len();
    b.extend(vec![0u8; 60]);
    set(&mut b, evlr + 20, &(1u64 << 60).to_le_bytes());
    set(&mut b, 235, &(evlr as u64).to_le_bytes());
    set(&mut b, 243, &1u32.to_le_bytes());
    assert!(error(&b).contains(&format!(
        "at byte {evlr}: EVLR 0 (of 1) declares 1152921504606846976 bytes"
    )));
    set(&mut b, 235, &u64::MAX.to_le_bytes());
    assert!(error(&b).contains("at byte 235: the first EVLR"));
    // Versions, formats, lengths.
    let mut b = good.clone();
    b[25] = 5;
    assert!(error(&b).contains("LAS version 1.5: 1.0 to 1.4 are read"));
    let mut b = good.clone();
    b[104] = 11;
    assert!(error(&b).contains("point data format 11"));
    let mut b = good.clone();
    set(&mut b, 105, &29u16.to_le_bytes());
    assert!(error(&b).contains("at byte 105: point record length 29 is less than the 30 bytes"));
    let mut b = good.clone();
    set(&mut b, 94, &200u16.to_le_bytes());
    assert!(error(&b).contains("at byte 94: header size 200"));
    let mut b = good.clone();
    set(&mut b, 139, &f64::NAN.to_le_bytes());
    assert!(error(&b).contains("must be finite"));
    assert!(error(b"LASF").contains("at byte 4: the file ends inside the LAS header"));
    assert!(error(&[b'x'; 300]).contains("at byte 0: not a LAS file"));
}

#[test]
fn bad_extra_bytes_descriptors() {
    let good = fixture(6, 2, false);
    // The Extra Bytes VLR is the first, its data at 375 + 54.
    let data = 375 + 54;
    let mut b = good.clone();
    b[data + 2] = 31;
    assert!(error(&b).contains(&format!(
        "at byte {}: extra bytes \"temperature\": data type 31",
        data + 2
    )));
    let mut b = good.clone();
    b[data + 192 * 2 + 3] = 200; // the undocumented block grows past the record
    assert!(
        error(&b).contains(&format!(
            "at byte {}: extra bytes descriptor 3 ends at byte 203 of the record, but the records have 29",
            data + 192 * 2 + 2
        )),
        "{}",
        error(&b)
    );
    let mut b = good.clone();
    set(&mut b, 375 + 20, &(4u16 * 192 - 1).to_le_bytes());
    let e = error(&b);
    assert!(
        e.contains("VLR 0 holds 767 bytes") || e.contains("not a multiple"),
        "{e}"
    );
}

#[test]
fn hostile_laz_chunk_tables_and_items() {
    let good = fixture(3, 300, true);
    let data_start = u32_at(&good, 96) as usize;
    let table = u64_at(&good, data_start) as usize;
    // More points than the chunk table holds.
    let mut b = good.clone();
    set(&mut b, 107, &100_000_000u32.to_le_bytes());
    let e = error(&b);
    assert!(
        e.contains("but the LAZ chunk table holds at most 50000"),
        "{e}"
    );
    // 2^32 - 1 chunks.
    let mut b = good.clone();
    set(&mut b, table + 4, &u32::MAX.to_le_bytes());
    assert!(error(&b).contains(&format!(
        "at byte {table}: the LAZ chunk table lists 4294967295 chunks"
    )));
    // A chunk table offset past the end.
    let mut b = good.clone();
    set(&mut b, data_start, &(u64::MAX / 2).to_le_bytes());
    let e = error(&b);
    assert!(
        e.contains("chunk table offset") && e.contains("past the end"),
        "{e}"
    );
    // Item sizes that do not match the record.
    let vlr = 227 + 54; // the laszip VLR is the only one
    let mut b = good.clone();
    set(&mut b, vlr + 36, &3u16.to_le_bytes());
    assert!(
        error(&b).contains("LAZ item 0 (type 6) declares 3 bytes"),
        "{}",
        error(&b)
    );
    let mut b = good.clone();
    set(&mut b, vlr + 32, &0u16.to_le_bytes());
    assert!(error(&b).contains("at least one item"));
    let mut b = good.clone();
    b[104] = 3; // says uncompressed: the LAZ data is read as records and the count fails
    assert!(parse(name(), &b).is_err());
    // LAZ 1.4: a layer size of 4 GB in the first chunk.
    let good = fixture(6, 50, true);
    let data_start = u32_at(&good, 96) as usize;
    let sizes = data_start + 8 + (30 + EXTRA) + 4;
    let mut b = good.clone();
    set(&mut b, sizes + 4, &u32::MAX.to_le_bytes());
    assert!(
        error(&b).contains("LAZ chunk 0 declares layers of"),
        "{}",
        error(&b)
    );
}

#[test]
fn every_truncation_fails_cleanly() {
    for (format, compressed) in [(6, false), (3, true), (7, true)] {
        let full = fixture(format, 40, compressed);
        for cut in 0..full.len() {
            let e = parse(name(), &full[..cut])
                .err()
                .unwrap_or_else(|| panic!("format {format} cut at {cut} of {}", full.len()));
            assert!(e.to_string().starts_with("t.las: "), "{e}");
        }
    }
}

#[test]
fn autzen_laz() {
    let path = arbvis_core::input::data_file("points/autzen_trim.laz");
    let t = std::time::Instant::now();
    let c = read(&path).unwrap();
    eprintln!(
        "autzen_trim.laz: {} points in {:?}",
        c.cloud.len(),
        t.elapsed()
    );
    assert_eq!(c.info.version, (1, 2));
    assert_eq!(c.info.point_format, 3);
    assert!(c.info.compressed);
    assert_eq!(c.info.points, 110_000);
    assert_eq!(c.cloud.len(), 110_000);
    // Bounds of the points (laspy: raw X 63600176..63717922 at scale 0.01, offset 0).
    let expect = [
        [636_001.76, 848_935.20, 406.26],
        [637_179.22, 849_497.90, 520.51],
    ];
    let close =
        |b: [[f64; 3]; 2]| (0..6).all(|i| (b[i / 3][i % 3] - expect[i / 3][i % 3]).abs() < 1e-6);
    assert!(close(c.cloud.bounds), "{:?}", c.cloud.bounds);
    assert!(close(c.info.header_bounds), "{:?}", c.info.header_bounds);
    let first = c.cloud.original(0).unwrap();
    for (a, v) in [637_177.98, 849_393.95, 411.19].iter().enumerate() {
        assert!((first[a] - v).abs() < 1e-3, "{first:?}");
    }
    let last = c.cloud.original(109_999).unwrap();
    for (a, v) in [636_037.88, 849_336.94, 423.2].iter().enumerate() {
        assert!((last[a] - v).abs() < 1e-3, "{last:?}");
    }
    assert_eq!(c.cloud.rgb.as_ref().unwrap()[0], [84, 102, 93]);
    let stats = |n: &str| c.cloud.attribute(n).unwrap().stats;
    assert_eq!(
        (
            stats("intensity").min,
            stats("intensity").max,
            stats("intensity").median
        ),
        (0.0, 254.0, 107.0)
    );
    assert_eq!(
        (
            stats("classification").min,
            stats("classification").max,
            stats("classification").median
        ),
        (1.0, 2.0, 1.0)
    );
    assert_eq!(
        (stats("return_number").min, stats("return_number").max),
        (1.0, 4.0)
    );
    assert_eq!(c.cloud.ints("intensity").unwrap()[0], 4);
    let max = |k: usize| {
        c.cloud
            .rgb
            .as_ref()
            .unwrap()
            .iter()
            .map(|p| p[k])
            .max()
            .unwrap()
    };
    assert_eq!((max(0), max(1), max(2)), (236, 228, 219));
}

#[test]
fn empty_files_give_empty_clouds() {
    for (format, compressed) in [(0, false), (6, false), (3, true), (7, true)] {
        let c = parse(name(), &fixture(format, 0, compressed)).unwrap();
        assert!(c.cloud.is_empty(), "format {format}");
        assert_eq!(c.info.points, 0);
    }
}

// --- issue 17: clouds and surfaces ---

/// The 1.4 fixture with its four extra-bytes descriptors split over two records: the
/// first two in one VLR, the other two in a second VLR (`in_evlr` false) or an EVLR.
fn split_extra_bytes_fixture(n: usize, in_evlr: bool) -> Vec<u8> {
    let whole = extra_vlr();
    let (first, second) = whole.data.split_at(2 * 192);
    let record = |data: &[u8]| Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "extra bytes".into(),
        data: data.to_vec(),
    };
    let mut b = Builder::default();
    b.version = (1, 4).into();
    b.point_format = Format::new(6).unwrap();
    b.point_format.extra_bytes = EXTRA as u16;
    b.transforms = Vector {
        x: Transform {
            scale: 0.001,
            offset: 500_000.0,
        },
        y: Transform {
            scale: 0.001,
            offset: 7_400_000.0,
        },
        z: Transform {
            scale: 0.001,
            offset: 0.0,
        },
    };
    b.vlrs.push(record(first));
    if in_evlr {
        b.evlrs.push(record(second));
    } else {
        b.vlrs.push(record(second));
    }
    let mut w = Writer::new(Cursor::new(Vec::new()), b.into_header().unwrap()).unwrap();
    for i in 0..n {
        let [x, y, z] = fixture_point(i);
        w.write_point(Point {
            x,
            y,
            z,
            gps_time: Some(i as f64),
            extra_bytes: extra_bytes_of(i),
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
    w.into_inner().unwrap().into_inner()
}

#[test]
fn every_extra_bytes_record_is_read() {
    let one = parse(name(), &fixture(6, 4, false)).unwrap();
    for in_evlr in [false, true] {
        let bytes = split_extra_bytes_fixture(4, in_evlr);
        // The layout is what the test means: two records of LASF_Spec 4, one in an EVLR.
        let evlrs = u32_at(&bytes, 243);
        assert_eq!(evlrs, u32::from(in_evlr), "EVLRs in the fixture");
        let c = parse(name(), &bytes).unwrap();
        assert_eq!(
            c.info.extra_bytes, one.info.extra_bytes,
            "in_evlr {in_evlr}"
        );
        assert_eq!(c.info.extra_bytes.len(), 5);
        for e in ["temperature", "flags", "velocity[0]", "velocity[2]"] {
            let (a, b) = (
                c.cloud.attribute(e).unwrap(),
                one.cloud.attribute(e).unwrap(),
            );
            assert_eq!(a.values.kind(), b.values.kind(), "{e}");
            for i in 0..4 {
                let (x, y) = (a.values.get(i).unwrap(), b.values.get(i).unwrap());
                assert!(x == y || (x.is_nan() && y.is_nan()), "{e}[{i}]: {x} vs {y}");
            }
        }
        // Values the second record describes, as written.
        assert_eq!(c.cloud.floats("velocity[1]").unwrap()[3], 31.25);
    }
    // The second record's descriptors run past the record: named at its data type byte.
    let mut bytes = split_extra_bytes_fixture(2, false);
    let second = 375 + 54 + 2 * 192 + 54; // the second VLR's data
    bytes[second + 3] = 100; // the undocumented block grows
    let e = error(&bytes);
    assert!(
        e.contains(&format!(
            "at byte {}: extra bytes descriptor 3 ends",
            second + 2
        )),
        "{e}"
    );
}

#[test]
fn header_errors_name_their_byte() {
    let good = fixture(6, 4, false);
    let mut b = good.clone();
    b[25] = 9;
    assert!(
        error(&b).contains("t.las: at byte 24: LAS version 1.9"),
        "{}",
        error(&b)
    );
    let mut b = good.clone();
    b[104] = 12;
    assert!(
        error(&b).contains("t.las: at byte 104: point data format 12"),
        "{}",
        error(&b)
    );
    // 2^63 points in the 64-bit count (the legacy one at 0).
    let mut b = good.clone();
    set(&mut b, 107, &0u32.to_le_bytes());
    set(&mut b, 247, &(1u64 << 63).to_le_bytes());
    assert!(
        error(&b).contains("t.las: at byte 247: the header declares 9223372036854775808 points"),
        "{}",
        error(&b)
    );
    // A legacy count past the limit is named at its own field.
    let mut b = fixture(1, 3, false);
    set(&mut b, 107, &u32::MAX.to_le_bytes());
    assert!(error(&b).contains("t.las: at byte 107: the header declares 4294967295 points"));
    // A LAZ item of no laszip type: at the item's type.
    let mut b = fixture(3, 20, true);
    let item = 227 + 54 + 34;
    set(&mut b, item, &99u16.to_le_bytes());
    assert!(
        error(&b).contains(&format!("at byte {item}: LAZ item 0: type 99")),
        "{}",
        error(&b)
    );
}

#[test]
fn extreme_scales_and_offsets() {
    // A scale that makes i32 coordinates overflow f64 is refused at its field.
    let good = fixture(1, 3, false);
    let mut b = good.clone();
    set(&mut b, 139, &1e300f64.to_le_bytes()); // y scale
    let e = error(&b);
    assert!(e.contains("t.las: at byte 139: y scale 1e300"), "{e}");
    // An offset near f64::MAX with a small scale is legal: positions stay finite and in
    // [-1, 1]^3, and the originals keep f64's precision of the offset.
    let mut b = good;
    let huge = 1.7e308f64;
    set(&mut b, 155, &huge.to_le_bytes()); // x offset
    set(&mut b, 163, &(-huge).to_le_bytes()); // y offset
    let c = parse(name(), &b).unwrap();
    assert!(c
        .cloud
        .positions
        .iter()
        .flatten()
        .all(|v| v.is_finite() && v.abs() <= 1.0));
    let p = c.cloud.original(0).unwrap();
    // x and y coincide with the offsets to f64 precision (the i32 parts vanish in them).
    assert_eq!((p[0], p[1]), (huge, -huge));
    assert!(c
        .cloud
        .describe()
        .contains("positions stored as f32 in [-1, 1]^3"));
}

/// The hostile clouds the integration tests share (equal points and the like).
#[path = "../../../../../tests/it/common/hostile_files.rs"]
mod hostile_files;
use hostile_files::equal_points_laz as equal_points;

/// A LAZ 1.4 file (format 6) of `n` equal points with `extras` one-byte attributes.
fn equal_points_with_extras(n: usize, extras: usize) -> Vec<u8> {
    let mut b = Builder::default();
    b.version = (1, 4).into();
    b.point_format = Format::new(6).unwrap();
    b.point_format.is_compressed = true;
    b.point_format.extra_bytes = extras as u16;
    b.vlrs.push(Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "extra bytes".into(),
        data: (0..extras)
            .flat_map(|k| descriptor(1, 0, &format!("e{k}"), [0; 8], 0.0, 0.0))
            .collect(),
    });
    let mut w = Writer::new(Cursor::new(Vec::new()), b.into_header().unwrap()).unwrap();
    for _ in 0..n {
        w.write_point(Point {
            x: 1.0,
            y: 2.0,
            z: 3.0,
            gps_time: Some(0.0),
            extra_bytes: vec![9; extras],
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
    w.into_inner().unwrap().into_inner()
}

#[test]
fn laz_denser_than_a_point_a_byte_past_a_million_is_refused() {
    // 1.1 million equal points in about 13 KB: past 1,000,000 + 1 a byte.
    let dense = equal_points(1_100_000);
    let data = dense.len() - u32_at(&dense, 96) as usize;
    assert!(data < 20_000, "{data} bytes");
    let e = error(&dense);
    assert!(
        e.starts_with(&format!(
            "t.las: at byte 107: the header declares 1100000 points in {data} bytes of LAZ data"
        )),
        "{e}"
    );
    assert!(e.contains(&format!("({} here)", 1_000_000 + data)), "{e}");
    // Extra-bytes attributes count a third of a point each: with 6 of them, 700,000 points
    // cost as much as 2.1 million plain ones.
    let b = equal_points_with_extras(700_000, 6);
    let data = b.len() - u32_at(&b, 96) as usize;
    let allowed = 1_000_000 + data;
    assert!(
        700_000 <= allowed && 700_000 * 9 > 3 * allowed,
        "{data} bytes"
    );
    let e = error(&b);
    assert!(
        e.contains(&format!(
            "700000 points with 6 extra-bytes attributes in {data} bytes of LAZ data"
        )) && e.contains(&format!(
            "({allowed} here, {} with 6 attributes",
            allowed * 3 / 9
        )),
        "{e}"
    );
    // Within the bound the same stream is read.
    let c = parse(name(), &equal_points(50_000)).unwrap();
    assert_eq!(c.cloud.len(), 50_000);
    assert_eq!(c.cloud.bounds, [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]);
}
