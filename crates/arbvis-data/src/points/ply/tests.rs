use super::*;

fn name() -> &'static Path {
    Path::new("t.ply")
}

fn put(out: &mut Vec<u8>, ty: ScalarType, v: f64, big: bool) {
    macro_rules! bytes {
        ($x:expr) => {
            if big {
                out.extend($x.to_be_bytes())
            } else {
                out.extend($x.to_le_bytes())
            }
        };
    }
    match ty {
        ScalarType::Char => bytes!(v as i8),
        ScalarType::UChar => bytes!(v as u8),
        ScalarType::Short => bytes!(v as i16),
        ScalarType::UShort => bytes!(v as u16),
        ScalarType::Int => bytes!(v as i32),
        ScalarType::UInt => bytes!(v as u32),
        ScalarType::Float => bytes!(v as f32),
        ScalarType::Double => bytes!(v),
    }
}

/// Type names as written in the header, one per type and alias.
const TYPES: [(&str, ScalarType); 16] = [
    ("char", ScalarType::Char),
    ("uchar", ScalarType::UChar),
    ("short", ScalarType::Short),
    ("ushort", ScalarType::UShort),
    ("int", ScalarType::Int),
    ("uint", ScalarType::UInt),
    ("float", ScalarType::Float),
    ("double", ScalarType::Double),
    ("int8", ScalarType::Char),
    ("uint8", ScalarType::UChar),
    ("int16", ScalarType::Short),
    ("uint16", ScalarType::UShort),
    ("int32", ScalarType::Int),
    ("uint32", ScalarType::UInt),
    ("float32", ScalarType::Float),
    ("float64", ScalarType::Double),
];

/// Two rows of extreme and fractional values for each type.
fn sample(ty: ScalarType, row: usize) -> f64 {
    let (lo, hi) = ty.range();
    match (ty, row) {
        (ScalarType::Float, 0) => 1.1,
        (ScalarType::Float, _) => -3.4e38,
        (ScalarType::Double, 0) => -2.25e300,
        (ScalarType::Double, _) => 0.1,
        (_, 0) => lo,
        _ => hi,
    }
}

/// Faces: row 0 is a triangle, row 1 an empty polygon; `w` holds doubles.
const FACES: [&[f64]; 2] = [&[0.0, 1.0, 1.0], &[]];
const WEIGHTS: [&[f64]; 2] = [&[0.5], &[1e-3, 2.0]];

fn header(format: &str) -> String {
    let mut h = format!(
        "ply\nformat {format} 1.0\ncomment made by a test\nobj_info  two rows\nelement vertex 2\n"
    );
    for (i, (t, _)) in TYPES.iter().enumerate() {
        h += &format!("property {t} p{i}\n");
    }
    h += "element face 2\nproperty list uchar int vertex_indices\nproperty list ushort double w\nelement empty 0\nproperty float q\nend_header\n";
    h
}

pub(crate) fn fixture(encoding: Encoding) -> Vec<u8> {
    let mut out = header(encoding.name()).into_bytes();
    let big = encoding == Encoding::BinaryBigEndian;
    for row in 0..2 {
        let mut line = Vec::new();
        for (_, ty) in TYPES {
            let v = sample(ty, row);
            if encoding == Encoding::Ascii {
                let v = if ty == ScalarType::Float {
                    v as f32 as f64
                } else {
                    v
                };
                line.push(format!("{v:?}"));
            } else {
                put(&mut out, ty, v, big);
            }
        }
        if encoding == Encoding::Ascii {
            out.extend(line.join(" ").as_bytes());
            out.push(b'\n');
        }
    }
    for row in 0..2 {
        if encoding == Encoding::Ascii {
            let mut parts = vec![FACES[row].len().to_string()];
            parts.extend(FACES[row].iter().map(|v| v.to_string()));
            parts.push(WEIGHTS[row].len().to_string());
            parts.extend(WEIGHTS[row].iter().map(|v| v.to_string()));
            // Rows need not be one per line in ASCII.
            out.extend(parts.join("\n  ").as_bytes());
            out.push(b'\n');
        } else {
            put(&mut out, ScalarType::UChar, FACES[row].len() as f64, big);
            for &v in FACES[row] {
                put(&mut out, ScalarType::Int, v, big);
            }
            put(&mut out, ScalarType::UShort, WEIGHTS[row].len() as f64, big);
            for &v in WEIGHTS[row] {
                put(&mut out, ScalarType::Double, v, big);
            }
        }
    }
    out
}

#[test]
fn all_types_and_lists_agree_in_the_three_encodings() {
    let mut parsed = Vec::new();
    for encoding in [
        Encoding::Ascii,
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
    ] {
        let ply = parse(name(), &fixture(encoding)).unwrap();
        assert_eq!(ply.encoding, encoding);
        assert_eq!(ply.version, "1.0");
        assert_eq!(ply.comments, vec!["made by a test"]);
        assert_eq!(ply.obj_info, vec!["two rows"]);
        assert_eq!(ply.elements.len(), 3);
        let v = ply.element("vertex").unwrap();
        assert_eq!(v.count, 2);
        for (i, (_, ty)) in TYPES.iter().enumerate() {
            let values = v.scalar(&format!("p{i}")).unwrap();
            let expect: Vec<f64> = (0..2)
                .map(|r| match ty {
                    ScalarType::Float => sample(*ty, r) as f32 as f64,
                    _ => sample(*ty, r),
                })
                .collect();
            assert_eq!(values, expect.as_slice(), "{encoding:?} p{i} {ty:?}");
            assert!(
                matches!(v.property(&format!("p{i}")).unwrap().data, PropertyData::Scalar { ty: t, .. } if t == *ty)
            );
        }
        let f = ply.element("face").unwrap();
        let faces = f.face_indices().unwrap();
        assert_eq!(faces.len(), 2);
        assert_eq!(faces.get(0).unwrap(), FACES[0]);
        assert_eq!(faces.get(1).unwrap(), FACES[1]);
        assert!(faces.get(2).is_none());
        let w: Vec<&[f64]> = f.list("w").unwrap().iter().collect();
        assert_eq!(w, WEIGHTS.to_vec());
        assert_eq!(f.list("w").unwrap().values(), &[0.5, 1e-3, 2.0]);
        assert!(f.scalar("w").is_none() && v.list("p0").is_none());
        assert_eq!(ply.element("empty").unwrap().count, 0);
        parsed.push(ply.elements);
    }
    for e in &mut parsed {
        for el in e.iter_mut() {
            el.start = Position::Byte(0);
        }
    }
    assert_eq!(parsed[0], parsed[1]);
    assert_eq!(parsed[1], parsed[2]);
}

#[test]
fn crlf_headers_vertex_index_alias_and_non_finite_positions() {
    let text = "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\nelement face 1\r\nproperty list uint8 uint32 vertex_index\r\nend_header\r\n1\r\nnan\r\n-inf\r\n3 0 1 2\r\n";
    let ply = parse(name(), text.as_bytes()).unwrap();
    let x = ply.element("vertex").unwrap();
    assert!(x.scalar("x").unwrap()[1].is_nan());
    assert_eq!(
        x.property("x").unwrap().first_non_finite,
        Some((1, Position::Line { line: 9, column: 1 }))
    );
    assert_eq!(x.start, Position::Line { line: 8, column: 1 });
    let faces = ply.element("face").unwrap().face_indices().unwrap();
    assert_eq!(faces.get(0).unwrap(), &[0.0, 1.0, 2.0]);
}

#[test]
fn header_errors_name_line_and_column() {
    let cases = [
        (
            "plx\nformat ascii 1.0\nend_header\n",
            "line 1, column 1: not a PLY file",
        ),
        ("ply", "line 1, column 1: not a PLY file: no \"ply\" line"),
        (
            "ply\nformat ascii 1.0\nelement v 1\nproperty float x\n",
            "line 5, column 1: the file ends inside the header",
        ),
        (
            "ply\nformat binary 1.0\nend_header\n",
            "line 2, column 8: expected ascii, binary_little_endian",
        ),
        (
            "ply\nformat ascii 2.0\nend_header\n",
            "line 2, column 14: expected format version 1.0",
        ),
        (
            "ply\nend_header\n",
            "line 2, column 1: end_header before any format line",
        ),
        (
            "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            "line 3, column 1: a property before any element",
        ),
        (
            "ply\nformat ascii 1.0\nelement v 1\nproperty flaot x\nend_header\n",
            "line 4, column 10: expected a PLY type",
        ),
        (
            "ply\nformat ascii 1.0\nelement v 1\nproperty list float int x\nend_header\n",
            "line 4, column 15: a list's length must have an integer type",
        ),
        (
            "ply\nformat ascii 1.0\nelement v 1\nproperty list uchar int\nend_header\n",
            "line 4, column 1: expected \"property TYPE NAME\"",
        ),
        (
            "ply\nformat ascii 1.0\nelement v 1\nproperty float x\nproperty int x\nend_header\n",
            "line 5, column 14: property x of element v is declared twice",
        ),
        (
            "ply\nformat ascii 1.0\nelement v 1\nelement v 2\nend_header\n",
            "line 4, column 9: element v is declared twice",
        ),
        (
            "ply\nformat ascii 1.0\nelement v -1\nend_header\n",
            "line 3, column 11: expected the element's row count, found \"-1\"",
        ),
        (
            "ply\nformat ascii 1.0\nelement v 99999999999999999999999\nend_header\n",
            "expected the element's row count",
        ),
        (
            "ply\nformat ascii 1.0\nelement v\nend_header\n",
            "line 3, column 10: expected the element's row count, found \"\"",
        ),
        (
            "ply\nformat ascii 1.0\nelemnt v 1\nend_header\n",
            "line 3, column 1: expected format, comment, obj_info",
        ),
        (
            "ply\nformat ascii 1.0\n\nend_header\n",
            "line 3, column 1: an empty line in the header",
        ),
    ];
    for (text, expect) in cases {
        let e = parse(name(), text.as_bytes()).unwrap_err().to_string();
        assert!(e.starts_with("t.ply: "), "{e}");
        assert!(e.contains(expect), "{text:?}\n got: {e}\nwant: {expect}");
    }
    let e = parse(name(), b"ply\nformat ascii 1.0\ncomment \xff\nend_header\n").unwrap_err();
    assert!(
        e.to_string()
            .contains("line 3, column 1: the header holds bytes that are not text"),
        "{e}"
    );
}

#[test]
fn ascii_data_errors_name_line_and_column() {
    let head = "ply\nformat ascii 1.0\nelement v 2\nproperty uchar a\nproperty float b\nelement f 1\nproperty list uchar int i\nend_header\n";
    let cases = [
        ("1 2\n3 x\n1 0\n", "line 10, column 3: element v row 1 property b: expected a number, found \"x\""),
        ("1 2\n256 1\n1 0\n", "line 10, column 1: element v row 1 property a: expected an integer of 0..255"),
        ("1 2\n2.5 1\n1 0\n", "line 10, column 1: element v row 1 property a: expected an integer"),
        ("1 2\n-1 1\n1 0\n", "expected an integer of 0..255 (UChar), found \"-1\""),
        ("1 2\n3 4\n2 0\n", "line 12, column 1: element f row 0 property i: the file ends where a list item was expected"),
        ("1 2\n3 4\n1 0 7\n", "line 11, column 5: more values than the header declares"),
        ("1 2\n3 4\n255 0\n", "line 11, column 1: element f row 0 property i: a list of 255 items, but only 3 bytes remain"),
        ("1 2\n3 4\n1 99999999999\n", "expected an integer of -2147483648..2147483647"),
        ("1 2 3", "line 9, column 1: element v declares 2 rows of 2 values, more than the 5 bytes left"),
        ("1 2\n3          \n", "line 11, column 1: element v row 1 property b: the file ends where a value was expected"),
    ];
    for (body, expect) in cases {
        let e = parse(name(), format!("{head}{body}").as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains(expect), "{body:?}\n got: {e}\nwant: {expect}");
    }
    let long = format!("{head}{} 2\n3 4\n1 0\n", "7".repeat(5000));
    let e = parse(name(), long.as_bytes()).unwrap_err().to_string();
    assert!(e.len() < 300 && e.contains("more characters"), "{e}");
}

#[test]
fn hostile_counts_fail_before_allocating() {
    let huge = 1u64 << 40;
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let text = format!("ply\nformat {format} 1.0\nelement vertex {huge}\nproperty float x\nend_header\n1 2 3 4\n");
        let e = parse(name(), text.as_bytes()).unwrap_err().to_string();
        assert!(e.contains(&format!("declares {huge} rows")), "{e}");
        let text = format!(
            "ply\nformat {format} 1.0\nelement vertex {}\nproperty double x\nend_header\n",
            usize::MAX
        );
        let e = parse(name(), text.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("declares"), "{e}");
    }
    // A list length of 2^32 - 1 in binary.
    let mut b = b"ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uint int vertex_indices\nend_header\n".to_vec();
    let at = b.len();
    b.extend(u32::MAX.to_be_bytes());
    b.extend([0u8; 12]);
    let e = parse(name(), &b).unwrap_err().to_string();
    assert!(
        e.contains(&format!("at byte {at}: element face row 0 property vertex_indices: a list of 4294967295 items of 4 bytes, but only 12 bytes remain")),
        "{e}"
    );
    // A negative list length.
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list char int vertex_indices\nend_header\n".to_vec();
    b.push(0xff);
    assert!(parse(name(), &b)
        .unwrap_err()
        .to_string()
        .contains("a list of -1 items"));
    // Elements without properties hold no data whatever their count.
    let text = format!(
        "ply\nformat binary_little_endian 1.0\nelement nothing {}\nend_header\n",
        usize::MAX
    );
    let ply = parse(name(), text.as_bytes()).unwrap();
    assert_eq!(ply.elements[0].count, usize::MAX);
    assert!(ply.elements[0].properties.is_empty());
}

#[test]
fn trailing_data_is_an_error() {
    let mut b = fixture(Encoding::BinaryLittleEndian);
    let end = b.len();
    b.extend([0u8; 3]);
    let e = parse(name(), &b).unwrap_err().to_string();
    assert!(
        e.contains(&format!("at byte {end}: 3 bytes after the last element")),
        "{e}"
    );
}

#[test]
fn every_truncation_fails_cleanly() {
    for encoding in [
        Encoding::Ascii,
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
    ] {
        let full = fixture(encoding);
        let last = full.iter().rposition(|b| !b.is_ascii_whitespace()).unwrap();
        for cut in 0..full.len() {
            let r = parse(name(), &full[..cut]);
            if encoding != Encoding::Ascii || cut <= last {
                let e = r
                    .expect_err(&format!("{encoding:?} cut at {cut}"))
                    .to_string();
                assert!(e.starts_with("t.ply: "), "{e}");
            }
        }
        assert!(parse(name(), &full).is_ok());
    }
}

#[test]
fn bunny_faces_through_the_public_api() {
    let path = arbvis_core::input::data_file("points/bunny.ply");
    let ply = read(&path).unwrap();
    assert_eq!(ply.encoding, Encoding::Ascii);
    assert_eq!(ply.comments, vec!["zipper output", "modified by flipply"]);
    let vertex = ply.element("vertex").unwrap();
    assert_eq!(vertex.count, 35_947);
    let names: Vec<&str> = vertex.properties.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["x", "y", "z", "confidence", "intensity"]);
    let face = ply.element("face").unwrap();
    assert_eq!(face.count, 69_451);
    let faces = face.face_indices().unwrap();
    assert_eq!(faces.len(), 69_451);
    assert_eq!(faces.get(0).unwrap(), &[20399.0, 21215.0, 21216.0]);
    assert_eq!(faces.get(69_450).unwrap(), &[17345.0, 17346.0, 17277.0]);
    assert!(faces
        .iter()
        .all(|f| f.len() == 3 && f.iter().all(|&i| i >= 0.0 && (i as usize) < vertex.count)));
    assert_eq!(vertex.scalar("x").unwrap()[0], -0.0378297f32 as f64);
}
