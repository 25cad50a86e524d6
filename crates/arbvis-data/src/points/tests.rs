//! Tests across the readers: precision far from the origin, statistics, the real files,
//! `inspect`, the scene syntax and a seeded mutation test of every parser.

use super::*;
use crate::points::section::SplitMix64;
use arbvis_core::input::data_file;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("arbvis-points-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 2 km x 1.5 km x 300 m cloud at UTM-like offsets (x ~ 5e5, y ~ 7.4e6 m) with
/// millimetre detail.
fn georeferenced(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let mm = |rng: &mut SplitMix64, base: f64, extent: f64| {
                base + (rng.range(0.0, extent) * 1000.0).round() / 1000.0
            };
            [
                mm(&mut rng, 512_345.0, 2_000.0),
                mm(&mut rng, 7_401_000.0, 1_500.0),
                mm(&mut rng, 1_000_000.0, 300.0),
            ]
        })
        .collect()
}

#[test]
fn georeferenced_coordinates_keep_their_millimetres() {
    let points = georeferenced(20_000, 11);
    let cloud = PointCloud::from_parts(CloudParts {
        positions: points.clone(),
        ..Default::default()
    })
    .unwrap();
    // The longest side (x, 2 km) spans [-1, 1]: the scale is half of it.
    assert!((cloud.scale - 1000.0).abs() < 1.0, "{}", cloud.scale);
    assert!(cloud.positions.iter().flatten().all(|v| v.abs() <= 1.0));
    let worst = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let q = cloud.original(i).unwrap();
            (0..3).map(|a| (p[a] - q[a]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    // f32 steps of scale * 2^-24 (0.06 mm here); well inside a millimetre.
    assert!(
        worst <= cloud.scale * 2f64.powi(-24),
        "worst error {worst} m"
    );
    assert!(worst < 1e-4, "worst error {worst} m");
    // A naive f32 of the coordinate itself would lose them: 7.4e6 m has 0.5 m steps.
    assert!((7_401_000.123f64 as f32 as f64 - 7_401_000.123).abs() > 0.1);
    // The same through .dat text.
    let columns: dat::DatColumns = toml::from_str(
        "count = 3\nlayer = 0\nfacies = 0\nfault = 0\nporosity = 0\namplitude = 0\njoint_dip = 0",
    )
    .unwrap();
    let text: String = points
        .iter()
        .map(|p| format!("{:.3} {:.3} {:.3}\n", p[0], p[1], p[2]))
        .collect();
    let back = dat::parse(Path::new("geo.dat"), text.as_bytes(), &columns).unwrap();
    for (i, p) in points.iter().enumerate().step_by(7) {
        let q = back.original(i).unwrap();
        assert!((0..3).all(|a| (p[a] - q[a]).abs() < 1e-3), "{p:?} {q:?}");
    }
}

#[test]
fn degenerate_clouds() {
    let empty = PointCloud::from_parts(CloudParts::default()).unwrap();
    assert!(empty.is_empty());
    assert_eq!((empty.origin, empty.scale), ([0.0; 3], 1.0));
    assert!(empty.original(0).is_none());
    let one = PointCloud::from_parts(CloudParts {
        positions: vec![[1e6, -2.5, 3.0]],
        ..Default::default()
    })
    .unwrap();
    assert_eq!((one.origin, one.scale), ([1e6, -2.5, 3.0], 1.0));
    assert_eq!(one.positions, vec![[0.0; 3]]);
    assert_eq!(one.original(0).unwrap(), [1e6, -2.5, 3.0]);
    let e = PointCloud::from_parts(CloudParts {
        positions: vec![[0.0; 3], [f64::NAN, 0.0, 0.0]],
        ..Default::default()
    })
    .unwrap_err();
    assert!(matches!(e, PartsError::NonFinite { point: 1, .. }), "{e}");
    assert!(
        e.to_string()
            .contains("point 1 has a non-finite coordinate"),
        "{e}"
    );
    let e = PointCloud::from_parts(CloudParts {
        positions: vec![[0.0; 3]],
        attributes: vec![("a".into(), Values::Int(vec![1, 2]))],
        ..Default::default()
    })
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("attribute a has 2 values for 1 points"),
        "{e}"
    );
}

#[test]
fn statistics_as_the_seed_computed_them() {
    let s = Stats::of_floats(&[5.0, f32::NAN, -1.0, 3.0, f32::INFINITY, 4.0]);
    assert_eq!((s.min, s.max, s.median, s.non_finite), (-1.0, 5.0, 4.0, 2));
    assert!(!s.zero_range());
    let s = Stats::of_floats(&[0.25, 0.25, f32::NAN]);
    assert!(s.zero_range());
    assert_eq!(s.median, 0.25);
    let s = Stats::of_floats(&[f32::NAN]);
    assert!(s.min.is_nan() && s.median.is_nan() && s.zero_range());
    assert_eq!(s.non_finite, 1);
    let s = Stats::of_ints(&[7, -999, 3, 3, 12]);
    assert_eq!((s.min, s.max, s.median), (-999.0, 12.0, 3.0));
    // Even counts: the upper median (element n / 2), as nth_element at size / 2.
    assert_eq!(Stats::of_ints(&[4, 1, 3, 2]).median, 3.0);
    assert!(Stats::of_ints(&[]).zero_range());
    // On a real-sized cloud, against a full sort.
    let c = section::generate(&section::SectionSpec {
        points: 30_001,
        seed: 4,
    })
    .unwrap();
    let mut sorted = c.floats(POROSITY).unwrap().to_vec();
    sorted.sort_by(f32::total_cmp);
    let st = c.attribute(POROSITY).unwrap().stats;
    assert_eq!(st.median, sorted[15_000] as f64);
    assert_eq!((st.min, st.max), (sorted[0] as f64, sorted[30_000] as f64));
}

#[test]
fn bunny_vertices() {
    let path = data_file("points/bunny.ply");
    let p = plycloud::read(&path).unwrap();
    let c = &p.cloud;
    assert_eq!(c.len(), 35_947);
    assert_eq!(
        p.elements,
        vec![("vertex".into(), 35_947), ("face".into(), 69_451)]
    );
    // Bounds from plyfile, read independently: the ASCII values rounded to float32.
    let f = |v: f32| v as f64;
    assert_eq!(
        c.bounds,
        [
            [f(-0.0946899), f(0.0329874), f(-0.0618736)],
            [f(0.0610091), f(0.187321), f(0.0587997)]
        ]
    );
    assert!((c.original(0).unwrap()[1] - f(0.12794)).abs() <= c.scale * 2f64.powi(-24));
    assert!(c.rgb.is_none() && c.normals.is_none());
    let names: Vec<&str> = c.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["confidence", "intensity"]);
    let conf = c.attribute("confidence").unwrap().stats;
    assert_eq!(
        (conf.min, conf.max, conf.median),
        (0.0, f(0.999238), f(0.592026))
    );
    let intensity = c.attribute("intensity").unwrap().stats;
    assert_eq!((intensity.max, intensity.median), (0.5, 0.5));
}

#[test]
fn inspect_reports_format_bounds_origin_and_attributes() {
    let s = inspect(&data_file("points/autzen_trim.laz")).unwrap();
    for line in [
        "format: LAS 1.2, point format 3, compressed (LAZ), 34-byte records",
        "header: 110000 points, scale 0.01 0.01 0.01",
        "points: 110000",
        "bounds: x 636001.76 .. 637179.22",
        "colour: RGB, 16 bits per channel (largest value 236)",
        "attribute intensity (int): min 0 max 254 median 107",
        "attribute classification (int): min 1 max 2 median 1",
    ] {
        assert!(s.contains(line), "{line}\n{s}");
    }
    let s = inspect(&data_file("points/bunny.ply")).unwrap();
    for line in [
        "format: PLY 1.0 ascii",
        "elements: vertex 35947, face 69451",
        "comment: zipper output",
        "points: 35947",
        "attribute confidence (float): min 0 max 0.99923",
    ] {
        assert!(s.contains(line), "{line}\n{s}");
    }
    let dir = temp_dir("inspect");
    let path = dir.join("s.dat");
    let cloud = section::generate(&section::SectionSpec {
        points: 500,
        seed: 9,
    })
    .unwrap();
    std::fs::write(
        &path,
        dat::write(&cloud, &dat::DatColumns::default()).unwrap(),
    )
    .unwrap();
    let s = inspect(&path).unwrap();
    for line in [
        "format: .dat text, 19 values per line",
        "points: 500",
        "attribute layer (int): min 0 max 7",
        "attribute facies (int): min -999",
        "attribute fault (int): min -1",
        "origin: ",
    ] {
        assert!(s.contains(line), "{line}\n{s}");
    }
    let las = dir.join("f.las");
    std::fs::write(&las, lasfile::tests::fixture(6, 3, false)).unwrap();
    let s = inspect(&las).unwrap();
    assert!(s.contains("LAS 1.4, point format 6, uncompressed"), "{s}");
    assert!(
        s.contains("attribute temperature (float)") && s.contains("1 NaN or infinite"),
        "{s}"
    );
    assert!(
        s.contains("extra bytes: temperature, flags, velocity[0]"),
        "{s}"
    );
    let e = inspect(&dir.join("missing.ply")).unwrap_err().to_string();
    assert!(e.contains("missing.ply"), "{e}");
    assert!(inspect(Path::new("/dev/zero"))
        .unwrap_err()
        .to_string()
        .contains("character device"));
}

#[test]
fn point_sources_from_scenes() {
    #[derive(serde::Deserialize)]
    struct Scene {
        points: PointSource,
    }
    let parse = |t: &str| toml::from_str::<Scene>(t).map(|s| s.points);
    assert_eq!(
        parse("points = { las = \"x.laz\" }").unwrap(),
        PointSource::Las("x.laz".into())
    );
    assert_eq!(
        parse("points = { section = { points = 1000, seed = 3 } }").unwrap(),
        PointSource::Section(section::SectionSpec {
            points: 1000,
            seed: 3
        })
    );
    let d =
        parse("points = { dat = { path = \"s.dat\", columns = { porosity = 12, keep = [15] } } }")
            .unwrap();
    let PointSource::Dat(spec) = &d else {
        panic!("{d:?}")
    };
    assert_eq!((spec.columns.porosity, spec.columns.x), (12, 1));
    assert_eq!(spec.columns.keep, vec![15]);
    assert_eq!(d.path(), Some(Path::new("s.dat")));
    for bad in [
        "points = { LAS = \"x.laz\" }",
        "points = { las = \"x.laz\", ply = \"y.ply\" }",
        "points = { dat = { path = \"s.dat\", column = {} } }",
        "points = { section = { points = 10, seeds = 1 } }",
        "points = { xyz = \"p.xyz\" }",
    ] {
        assert!(parse(bad).is_err(), "{bad}");
    }
    // Relative paths resolve from the scene's folder.
    let dir = temp_dir("sources");
    std::fs::write(dir.join("p.ply"), b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n4 2 1\n").unwrap();
    let cloud = PointSource::Ply("p.ply".into()).load(&dir).unwrap();
    assert_eq!(
        (cloud.len(), cloud.scale, cloud.origin),
        (2, 2.0, [2.0, 1.0, 0.5])
    );
    std::fs::write(dir.join("f.laz"), lasfile::tests::fixture(3, 10, true)).unwrap();
    assert_eq!(
        PointSource::Las("f.laz".into()).load(&dir).unwrap().len(),
        10
    );
    let e = PointSource::Las("nope.las".into())
        .load(&dir)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&dir.join("nope.las").display().to_string()),
        "{e}"
    );
    let s = PointSource::Section(section::SectionSpec {
        points: 10,
        seed: 1,
    });
    assert_eq!(s.load(&dir).unwrap().len(), 10);
    assert!(
        PointSource::Section(section::SectionSpec { points: 0, seed: 1 })
            .load(&dir)
            .is_err()
    );
}

/// Mutate `bytes` in one of several ways chosen by `rng`.
fn mutate(bytes: &[u8], rng: &mut SplitMix64) -> Vec<u8> {
    let mut b = bytes.to_vec();
    let pick = |rng: &mut SplitMix64, n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    for _ in 0..1 + pick(rng, 3) {
        let at = pick(rng, b.len());
        match pick(rng, 7) {
            0 => {
                if let Some(x) = b.get_mut(at) {
                    *x ^= 1 << pick(rng, 8);
                }
            }
            1 => {
                if let Some(x) = b.get_mut(at) {
                    *x = [0, 0xff, 0x7f, 0x80, b'-', b'9', b' ', b'\n'][pick(rng, 8)];
                }
            }
            2 => {
                // An extreme 4- or 8-byte value (counts, offsets, lengths).
                let v: [u8; 8] =
                    [u64::MAX, 1 << 40, 1 << 31, u32::MAX as u64, 0][pick(rng, 5)].to_le_bytes();
                let n = if rng.next_u64().is_multiple_of(2) {
                    4
                } else {
                    8
                };
                for (k, &byte) in v.iter().enumerate().take(n) {
                    if let Some(x) = b.get_mut(at + k) {
                        *x = byte;
                    }
                }
            }
            3 => b.truncate(at),
            4 => {
                let end = (at + 1 + pick(rng, 64)).min(b.len());
                let copy = b[at.min(end)..end].to_vec();
                b.splice(at.min(b.len())..at.min(b.len()), copy);
            }
            5 => {
                let end = (at + 1 + pick(rng, 32)).min(b.len());
                b.drain(at.min(end)..end);
            }
            _ => {
                let junk: Vec<u8> = (0..1 + pick(rng, 16))
                    .map(|_| rng.next_u64() as u8)
                    .collect();
                b.splice(at.min(b.len())..at.min(b.len()), junk);
            }
        }
    }
    b
}

#[test]
fn seeded_mutations_never_panic() {
    let t = std::time::Instant::now();
    let section = section::generate(&section::SectionSpec {
        points: 40,
        seed: 2,
    })
    .unwrap();
    let dat_text = format!(
        "# header comment\n{}",
        dat::write(&section, &dat::DatColumns::default()).unwrap()
    );
    let fixtures: Vec<(&str, Vec<u8>)> = vec![
        ("dat", dat_text.into_bytes()),
        ("ply ascii", ply::tests::fixture(ply::Encoding::Ascii)),
        (
            "ply le",
            ply::tests::fixture(ply::Encoding::BinaryLittleEndian),
        ),
        (
            "ply be",
            ply::tests::fixture(ply::Encoding::BinaryBigEndian),
        ),
        ("las 1.4", lasfile::tests::fixture(7, 30, false)),
        ("laz 1.2", lasfile::tests::fixture(3, 30, true)),
        ("laz 1.4", lasfile::tests::fixture(6, 30, true)),
    ];
    let mut rng = SplitMix64::new(2024);
    let mut outcomes = [0usize; 2];
    for (kind, bytes) in &fixtures {
        for round in 0..500 {
            let m = mutate(bytes, &mut rng);
            let result = std::panic::catch_unwind(|| {
                let name = Path::new("m.bin");
                match *kind {
                    "dat" => dat::parse(name, &m, &dat::DatColumns::default()).is_ok(),
                    k if k.starts_with("ply") => {
                        let a = ply::parse(name, &m).is_ok();
                        a && plycloud::parse(name, &m).is_ok()
                    }
                    _ => lasfile::parse(name, &m).is_ok(),
                }
            });
            match result {
                Ok(ok) => outcomes[ok as usize] += 1,
                Err(_) => panic!("{kind}: mutation {round} panicked ({} bytes)", m.len()),
            }
        }
    }
    // Garbage of every length.
    for n in 0..300 {
        let g: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
        let name = Path::new("g");
        if let Ok(c) = dat::parse(name, &g, &dat::DatColumns::default()) {
            assert!(c.is_empty(), "garbage of {n} bytes gave points");
        }
        assert!(ply::parse(name, &g).is_err());
        assert!(lasfile::parse(name, &g).is_err());
    }
    eprintln!(
        "mutations: {} rejected, {} accepted, in {:?}",
        outcomes[0],
        outcomes[1],
        t.elapsed()
    );
    assert!(outcomes[0] > 2000, "{outcomes:?}");
}

// --- issue 17: clouds and surfaces ---

#[test]
fn coordinates_near_the_f64_limit_rescale_without_overflow() {
    // Finite coordinates whose extent (hi - lo) and centre sum (lo + hi) overflow f64.
    let big = 1.7e308;
    let points = vec![
        [big, -big, 1.0],
        [-big, big, -1.0],
        [0.25 * big, 0.0, 3e307],
    ];
    let cloud = PointCloud::from_parts(CloudParts {
        positions: points.clone(),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(cloud.scale, big, "half of the largest extent");
    assert_eq!(cloud.origin, [0.0, 0.0, 0.5 * 3e307 - 0.5]);
    assert!(cloud
        .positions
        .iter()
        .flatten()
        .all(|v| v.is_finite() && v.abs() <= 1.0));
    assert_eq!(cloud.positions[0][..2], [1.0, -1.0]);
    for (i, p) in points.iter().enumerate() {
        let q = cloud.original(i).unwrap();
        for a in 0..3 {
            // f32 positions resolve scale * 2^-24 (1e301 here).
            assert!((p[a] - q[a]).abs() <= big * 2f64.powi(-24), "{p:?} {q:?}");
        }
    }
    // Every point at the same huge coordinate: scale 1, all at the origin.
    let same = PointCloud::from_parts(CloudParts {
        positions: vec![[big; 3]; 2],
        ..Default::default()
    })
    .unwrap();
    assert_eq!((same.origin, same.scale), ([big; 3], 1.0));
    assert_eq!(same.positions, vec![[0.0; 3]; 2]);
    // Through the text readers and inspect's description.
    let columns: dat::DatColumns = toml::from_str(
        "count = 3\nlayer = 0\nfacies = 0\nfault = 0\nporosity = 0\namplitude = 0\njoint_dip = 0",
    )
    .unwrap();
    let text = "1.7e308 -1.7e308 0\n-1.7e308 1.7e308 5\n";
    let c = dat::parse(Path::new("big.dat"), text.as_bytes(), &columns).unwrap();
    assert!(c.positions.iter().flatten().all(|v| v.abs() <= 1.0));
    let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n1.7e308 -1.7e308 0\n-1.7e308 1.7e308 5\n";
    let c = plycloud::parse(Path::new("big.ply"), ply.as_bytes())
        .unwrap()
        .cloud;
    // z: (0 - 2.5) / 1.7e308 is below f32's range.
    assert_eq!(c.positions[0], [1.0, -1.0, 0.0]);
    let text = c.describe();
    assert!(!text.contains("inf") && !text.contains("NaN"), "{text}");
}

#[test]
fn a_coordinate_declared_as_a_list_is_named_at_its_line() {
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n  property list uchar float y\nproperty float z\nend_header\n0 2 1 1 3\n";
    let e = plycloud::parse(Path::new("l.ply"), text.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("l.ply: line 5, column 29: vertex property \"y\" is declared as a list"),
        "{e}"
    );
    // A missing coordinate is named at its element's count.
    let text = "ply\nformat ascii 1.0\nelement   vertex 1\nproperty float x\nproperty float y\nend_header\n0 2\n";
    let e = plycloud::parse(Path::new("m.ply"), text.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("m.ply: line 3, column 18: the vertex element has no scalar property \"z\""),
        "{e}"
    );
    // The same for a PLY surface.
    let surface = "ply\nformat ascii 1.0\nelement vertex 3\nproperty list uchar float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n1 0 0 0\n1 1 0 0\n1 0 1 0\n3 0 1 2\n";
    let e = crate::surface::parse(Path::new("s.ply"), surface.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("s.ply: line 4, column 27: vertex property x is declared as a list"),
        "{e}"
    );
}

#[test]
fn cloud_estimates_count_every_array() {
    // 36 bytes of positions (f64 in, f32 out), 8 per attribute (the values and the
    // median's copy), 6 of colour, 12 of normals.
    assert_eq!(footprint(1, 0, false, false), 36);
    assert_eq!(footprint(1000, 4, true, true), 1000 * (36 + 32 + 6 + 12));
    assert_eq!(footprint(u64::MAX, 1, false, false), u64::MAX);
    // The LAS reader's estimate for 20 million points of format 3 (the 1.7 GB LAZ of
    // issue 17): what it refuses with under a 1 GiB budget is checked in tests/hostile.rs.
    let las = footprint(20_000_000, 4, true, false);
    assert!(las > 1_400_000_000 && las < 1_600_000_000, "{las}");
}

#[test]
fn a_remote_cloud_that_is_not_copc_is_refused_by_name() {
    // No request is sent: the kind decides.
    for source in [
        PointSource::Las("https://example.org/a.laz".into()),
        PointSource::Ply("s3://bucket/a.ply".into()),
    ] {
        let Err(e) = source.load(Path::new(".")) else {
            panic!("a remote {} cloud was read", source.kind());
        };
        let e = e.to_string();
        assert!(e.contains("from a URL arbvis reads COPC"), "{e}");
        assert!(
            e.contains("example.org/a.laz") || e.contains("s3://bucket/a.ply"),
            "{e}"
        );
    }
}
