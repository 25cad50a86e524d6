//! The zarr reader against arrays zarrs writes, and against hostile metadata and chunks.

use std::path::Path;
use std::sync::Arc;

use zarrs::array::codec::{
    BloscCodec, BloscCompressor, BloscShuffleMode, Crc32cCodec, GzipCodec, ZstdCodec,
};
use zarrs::array::{data_type, ArrayBuilder};
use zarrs::filesystem::FilesystemStore;

use super::*;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("arbvis-zarr-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 5 x 6 x 7 float32 array in chunks of 4³ (partial edge chunks), values not smooth.
fn write_array(
    dir: &Path,
    codecs: Vec<Arc<dyn zarrs::array::BytesToBytesCodecTraits>>,
) -> Vec<f32> {
    let storage = Arc::new(FilesystemStore::new(dir).unwrap());
    let mut b = ArrayBuilder::new(vec![5, 6, 7], vec![4, 4, 4], data_type::float32(), f32::NAN);
    b.bytes_to_bytes_codecs(codecs);
    let array = b.build(storage, "/a").unwrap();
    array.store_metadata().unwrap();
    let values: Vec<f32> = (0..5 * 6 * 7)
        .map(|n| ((n * 7919) % 211) as f32 - 100.5)
        .collect();
    array
        .store_array_subset(
            &zarrs::array::ArraySubset::new_with_shape(vec![5, 6, 7]),
            values.as_slice(),
        )
        .unwrap();
    values
}

/// Every chunk of `a` read back and placed: equals what was written.
fn read_all(a: &ArrayMeta) -> Vec<f32> {
    let mut out = vec![0f32; 5 * 6 * 7];
    for ck in 0..2u64 {
        for cj in 0..2u64 {
            for ci in 0..2u64 {
                let chunk = a.read_chunk(&[ck, cj, ci]).unwrap().unwrap();
                for z in 0..4 {
                    for y in 0..4 {
                        for x in 0..4 {
                            let (k, j, i) = (ck * 4 + z, cj * 4 + y, ci * 4 + x);
                            if k < 5 && j < 6 && i < 7 {
                                out[(i + 7 * (j + 6 * k)) as usize] =
                                    chunk[(x + 4 * (y + 4 * z)) as usize];
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

#[test]
fn reads_what_zarrs_writes_with_each_codec() {
    let cases: Vec<(&str, Vec<Arc<dyn zarrs::array::BytesToBytesCodecTraits>>)> = vec![
        ("none", vec![]),
        ("zstd", vec![Arc::new(ZstdCodec::new(3, true))]),
        ("gzip", vec![Arc::new(GzipCodec::new(5).unwrap())]),
        (
            "zstd-crc",
            vec![
                Arc::new(ZstdCodec::new(1, false)),
                Arc::new(Crc32cCodec::new()),
            ],
        ),
        (
            "blosc",
            vec![blosc(BloscCompressor::Zstd, BloscShuffleMode::Shuffle)],
        ),
        (
            "blosc-lz4",
            vec![blosc(BloscCompressor::LZ4, BloscShuffleMode::BitShuffle)],
        ),
        (
            "blosc-blosclz",
            vec![blosc(BloscCompressor::BloscLZ, BloscShuffleMode::NoShuffle)],
        ),
        (
            "blosc-zlib",
            vec![blosc(BloscCompressor::Zlib, BloscShuffleMode::Shuffle)],
        ),
    ];
    for (name, codecs) in cases {
        let dir = temp(&format!("codec-{name}"));
        let values = write_array(&dir, codecs);
        let a = open_array(&dir.join("a")).unwrap();
        assert_eq!(
            (a.shape.clone(), a.chunks.clone()),
            (vec![5, 6, 7], vec![4, 4, 4])
        );
        assert!(a.fill_value.is_nan(), "{name}");
        assert_eq!(read_all(&a), values, "{name}");
        assert_eq!(
            a.read_chunk(&[5, 0, 0]).ok(),
            Some(None),
            "an absent chunk is the fill value"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// A blosc codec as MDIO and numcodecs write it (level 5, 4-byte elements).
fn blosc(
    c: BloscCompressor,
    shuffle: BloscShuffleMode,
) -> Arc<dyn zarrs::array::BytesToBytesCodecTraits> {
    Arc::new(BloscCodec::new(c, 5.try_into().unwrap(), None, shuffle, Some(4)).unwrap())
}

#[test]
fn a_blosc_header_declaring_more_than_the_chunk_is_refused_before_decoding() {
    let dir = temp("blosc-header");
    write_array(
        &dir,
        vec![blosc(BloscCompressor::Zstd, BloscShuffleMode::Shuffle)],
    );
    let a = open_array(&dir.join("a")).unwrap();
    let file = a.chunk_file(&[0, 0, 0]);
    let mut bytes = std::fs::read(&file).unwrap();
    bytes[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&file, &bytes).unwrap();
    let e = a.read_chunk(&[0, 0, 0]).unwrap_err().to_string();
    assert!(
        e.contains("its blosc header declares 4294967295 bytes"),
        "{e}"
    );
    bytes[4..8].copy_from_slice(&256u32.to_le_bytes());
    bytes[12..16].copy_from_slice(&7u32.to_le_bytes());
    std::fs::write(&file, &bytes).unwrap();
    let e = a.read_chunk(&[0, 0, 0]).unwrap_err().to_string();
    assert!(e.contains("does not fit"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Write `bytes` as chunk 0/0/0 of a fresh zstd array and read it.
fn read_hostile_chunk(name: &str, bytes: &[u8]) -> String {
    let dir = temp(name);
    write_array(&dir, vec![Arc::new(ZstdCodec::new(1, false))]);
    let a = open_array(&dir.join("a")).unwrap();
    std::fs::write(a.chunk_file(&[0, 0, 0]), bytes).unwrap();
    let e = a.read_chunk(&[0, 0, 0]).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    e
}

#[test]
fn a_zstd_frame_declaring_a_terabyte_is_refused_before_decoding() {
    // A frame header: magic, descriptor (single segment, an 8-byte content size), 1 TiB.
    let mut frame = vec![0x28, 0xb5, 0x2f, 0xfd, 0xe0];
    frame.extend_from_slice(&(1u64 << 40).to_le_bytes());
    frame.extend_from_slice(&[0; 30]);
    let e = read_hostile_chunk("declares", &frame);
    assert!(e.contains("declares 1099511627776 bytes"), "{e}");
}

#[test]
fn a_chunk_inflating_past_its_size_stops_at_the_first_byte_past() {
    // 64 KiB of zeros in a few hundred bytes, without a declared size: the decoder must stop
    // at the chunk's 256 bytes, not inflate it all.
    let mut encoder = zstd::stream::write::Encoder::new(Vec::new(), 3).unwrap();
    encoder.include_contentsize(false).unwrap();
    // A small window, as a chunk's own would be: the frame passes that check.
    encoder.window_log(10).unwrap();
    std::io::Write::write_all(&mut encoder, &vec![0u8; 1 << 16]).unwrap();
    let bomb = encoder.finish().unwrap();
    let t = std::time::Instant::now();
    let e = read_hostile_chunk("bomb", &bomb);
    assert!(e.contains("inflates it past the 256 bytes"), "{e}");
    // A frame asking for a larger window than the chunk could need is refused as such.
    let mut encoder = zstd::stream::write::Encoder::new(Vec::new(), 3).unwrap();
    encoder.include_contentsize(false).unwrap();
    encoder.window_log(20).unwrap();
    std::io::Write::write_all(&mut encoder, &vec![1u8; 1 << 20]).unwrap();
    let e = read_hostile_chunk("window", &encoder.finish().unwrap());
    assert!(e.contains("window"), "{e}");
    // Far below the time to inflate 8 MiB many times over.
    assert!(t.elapsed().as_millis() < 500, "{:?}", t.elapsed());
}

#[test]
fn a_chunk_file_longer_than_its_codecs_can_make_is_refused_unread() {
    let e = read_hostile_chunk("long", &vec![7u8; 100_000]);
    assert!(
        e.contains("holds 100000 bytes; its codecs (bytes + zstd) can make at most"),
        "{e}"
    );
}

#[test]
fn a_fifo_as_a_chunk_is_refused_at_once() {
    let dir = temp("fifo");
    write_array(&dir, vec![]);
    let a = open_array(&dir.join("a")).unwrap();
    let chunk = a.chunk_file(&[0, 0, 0]);
    std::fs::remove_file(&chunk).unwrap();
    let status = std::process::Command::new("mkfifo")
        .arg(&chunk)
        .status()
        .unwrap();
    assert!(status.success());
    let e = a.read_chunk(&[0, 0, 0]).unwrap_err().to_string();
    assert!(e.contains("FIFO"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The error of opening an array whose `zarr.json` is `text`.
fn open_error(name: &str, text: &str) -> String {
    let dir = temp(name);
    std::fs::create_dir_all(dir.join("a")).unwrap();
    std::fs::write(dir.join("a/zarr.json"), text).unwrap();
    let e = open_array(&dir.join("a")).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    e
}

fn array_json(shape: &str, chunks: &str, dtype: &str, codecs: &str) -> String {
    format!(
        r#"{{"zarr_format": 3, "node_type": "array", "shape": {shape}, "data_type": "{dtype}",
        "chunk_grid": {{"name": "regular", "configuration": {{"chunk_shape": {chunks}}}}},
        "chunk_key_encoding": {{"name": "default", "configuration": {{"separator": "/"}}}},
        "fill_value": 0, "codecs": {codecs}}}"#
    )
}

#[test]
fn metadata_numbers_are_checked_before_they_size_anything() {
    let bytes = r#"[{"name": "bytes", "configuration": {"endian": "little"}}]"#;
    let e = open_error(
        "overflow",
        &array_json(
            "[10, 10, 10]",
            "[4294967296, 4294967296, 4294967296]",
            "float32",
            bytes,
        ),
    );
    assert!(
        e.contains("chunk_shape[0]` is 4294967296") || e.contains("more than the 1024 MiB"),
        "{e}"
    );
    let e = open_error(
        "huge-chunk",
        &array_json("[10, 10, 10]", "[1048576, 1048576, 4]", "float32", bytes),
    );
    assert!(e.contains("more than the 1024 MiB"), "{e}");
    let e = open_error(
        "zero-chunk",
        &array_json("[10, 10, 10]", "[0, 4, 4]", "float32", bytes),
    );
    assert!(e.contains("chunk_shape[0]` is 0"), "{e}");
    let e = open_error(
        "negative",
        &array_json("[10, -1, 10]", "[4, 4, 4]", "float32", bytes),
    );
    assert!(e.contains("`shape[1]` is -1"), "{e}");
    let e = open_error(
        "axes",
        &array_json("[10, 10]", "[4, 4, 4]", "float32", bytes),
    );
    assert!(e.contains("has 3 axes, the shape [10, 10] 2"), "{e}");
    let e = open_error("dtype", &array_json("[10]", "[4]", "complex64", bytes));
    assert!(e.contains("`data_type` \"complex64\""), "{e}");
    let e = open_error(
        "bz2",
        &array_json(
            "[10]",
            "[4]",
            "float32",
            r#"[{"name": "bytes"}, {"name": "numcodecs.bz2", "configuration": {"level": 1}}]"#,
        ),
    );
    assert!(
        e.contains("`codecs[1]` \"numcodecs.bz2\": not a codec arbvis reads"),
        "{e}"
    );
    let e = open_error(
        "zfp",
        &array_json(
            "[10]",
            "[4]",
            "float32",
            r#"[{"name": "bytes"}, {"name": "numcodecs.zfpy", "configuration": {"mode": 4}}]"#,
        ),
    );
    assert!(e.contains("takes the place of `bytes`"), "{e}");
    // A blosc configuration the codec cannot take is refused at open, naming it.
    let e = open_error(
        "blosc-config",
        &array_json(
            "[10]",
            "[4]",
            "float32",
            r#"[{"name": "bytes"}, {"name": "blosc", "configuration": {"cname": "nope"}}]"#,
        ),
    );
    assert!(e.contains("`codecs[1]` \"blosc\""), "{e}");
    let e = open_error(
        "shard",
        &array_json(
            "[10]",
            "[4]",
            "float32",
            r#"[{"name": "sharding_indexed"}]"#,
        ),
    );
    assert!(e.contains("sharded arrays are not read"), "{e}");
    let e = open_error(
        "no-bytes",
        &array_json("[10]", "[4]", "float32", r#"[{"name": "zstd"}]"#),
    );
    assert!(e.contains("`codecs[0]` \"zstd\""), "{e}");
    let e = open_error("json", "{\"zarr_format\": 3,\n \"shape\": [1,");
    assert!(e.contains("line 2, column"), "{e}");
    let e = open_error("v2", r#"{"zarr_format": 2}"#);
    assert!(e.contains("arbvis reads zarr v3"), "{e}");
}

#[test]
fn fill_values_in_every_spelling() {
    let f = |v: Value, t| fill(&v, t, Path::new("z")).unwrap();
    assert!(f(Value::from("NaN"), DataType::Float32).is_nan());
    assert_eq!(
        f(Value::from("-Infinity"), DataType::Float64),
        f64::NEG_INFINITY
    );
    assert_eq!(f(Value::from("0x3f800000"), DataType::Float32), 1.0);
    assert_eq!(f(Value::from("0x3c00"), DataType::Float16), 1.0);
    assert_eq!(f(Value::from(true), DataType::Bool), 1.0);
    assert_eq!(f(Value::from(-3), DataType::Int16), -3.0);
    assert!(fill(&Value::from("zero"), DataType::Float32, Path::new("z")).is_err());
}

#[test]
fn big_endian_and_integer_types_decode() {
    assert_eq!(DataType::Int16.value(&[0xff, 0xfe], true), -2.0);
    assert_eq!(DataType::UInt32.value(&[1, 0, 0, 0], false), 1.0);
    assert_eq!(DataType::Float64.value(&1.5f64.to_be_bytes(), true), 1.5);
    assert_eq!(DataType::Bool.value(&[2], false), 1.0);
}

#[test]
fn fields_a_reader_must_understand_are_refused_as_the_spec_says() {
    let bytes = r#"[{"name": "bytes", "configuration": {"endian": "little"}}]"#;
    let plain = array_json("[4]", "[4]", "float32", bytes);
    let with = |field: &str| format!("{}, {field}}}", &plain[..plain.len() - 1]);
    // An extension that says it may be ignored is.
    let dir = temp("must-understand-false");
    std::fs::create_dir_all(dir.join("a")).unwrap();
    std::fs::write(
        dir.join("a/zarr.json"),
        with(r#""my_extension": {"must_understand": false, "x": 1}"#),
    )
    .unwrap();
    assert!(open_array(&dir.join("a")).is_ok());
    std::fs::remove_dir_all(&dir).unwrap();
    // One that says it must be understood, or says nothing (the default is true), is not.
    for (name, field) in [
        (
            "must-understand-true",
            r#""my_extension": {"must_understand": true}"#,
        ),
        ("must-understand-absent", r#""my_extension": {"x": 1}"#),
        ("unknown-number", r#""my_extension": 3"#),
    ] {
        let e = open_error(name, &with(field));
        assert!(
            e.contains("field `my_extension`") && e.contains("must_understand"),
            "{name}: {e}"
        );
    }
    // A group alike.
    let group = serde_json::json!({"zarr_format": 3, "node_type": "group", "attributes": {},
        "future": {"must_understand": true}});
    let e = check_group(&group, Path::new("g/zarr.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("field `future`"), "{e}");
    let group = serde_json::json!({"zarr_format": 3, "node_type": "group",
        "future": {"must_understand": false}});
    assert!(check_group(&group, Path::new("g/zarr.json")).is_ok());
}
