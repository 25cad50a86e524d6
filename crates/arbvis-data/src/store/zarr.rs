//! Reading zarr v3 arrays as the bounded input every other file is: metadata and chunks
//! are opened through [`arbvis_core::input`]'s regular-file check (a FIFO, a device or a link to
//! `/dev/zero` is refused with its true cause, never waited on), every number in a
//! `zarr.json` is checked before it sizes anything, a chunk file longer than its codecs
//! can produce is refused before it is read, and a chunk is decoded into a buffer of its
//! known size, each codec stopping at the first byte past what it may produce (a zstd
//! frame declaring a terabyte, or inflating without end, fails in microseconds).
//!
//! Supported: data types bool, (u)int8-64, float16/32/64; the `regular` chunk grid; the
//! `default` and `v2` chunk key encodings; codecs `bytes` (either byte order), `blosc`
//! (MDIO's: decoded by the `zarrs` crate after its header is checked here), `zstd`, `gzip`,
//! `crc32c` and an identity `transpose`. Others are refused by name. zarr v2 arrays
//! (`.zarray`, as MDIO v0 datasets hold them) are read too ([`v2`]). Writing
//! stays with the `zarrs` crate.

use std::io::Read;
use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::StoreError;
use crate::fetch::FetchError;

/// Why a chunk's bytes could not be decoded: the codec that refused them and its words.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct CodecError {
    /// The codec (`zstd`, `gzip`, `crc32c`, `blosc`, `zfpy`).
    pub codec: &'static str,
    /// What is wrong, in words that name the codec.
    pub message: String,
}

impl CodecError {
    /// `codec`'s refusal, in `message`.
    pub fn new(codec: &'static str, message: impl Into<String>) -> CodecError {
        CodecError {
            codec,
            message: message.into(),
        }
    }
}

/// Why a chunk could not be read (the caller names its file, array and index).
#[derive(Debug, Clone, thiserror::Error)]
pub enum ChunkError {
    /// Its file or object could not be read.
    #[error(transparent)]
    Fetch(#[from] FetchError),
    /// Its file holds more than its codecs can make of a chunk.
    #[error(
        "the file holds {bytes} bytes; its codecs ({codecs}) can make at most {max} of a chunk"
    )]
    TooLarge {
        /// The file's size.
        bytes: u64,
        /// The most its codecs can make.
        max: u64,
        /// The codecs, in words.
        codecs: String,
    },
    /// A codec refused its bytes.
    #[error("cannot be decoded: {0}")]
    Codec(#[from] CodecError),
    /// It decoded to another size than a chunk's.
    #[error("decodes to {got} bytes, not the {want} of a {chunks:?} chunk of {data_type}")]
    Size {
        /// Bytes decoded.
        got: usize,
        /// Bytes of a chunk.
        want: usize,
        /// The chunk's shape.
        chunks: Vec<u64>,
        /// The element type's name.
        data_type: &'static str,
    },
}

/// Largest `zarr.json` read (arbvis writes a few KiB; MDIO's statistics and histograms
/// stay far below this).
pub const MAX_METADATA_BYTES: u64 = 16 << 20;

/// Largest chunk, decoded (a 512³ brick of float32 is 512 MiB).
pub const MAX_CHUNK_BYTES: u64 = 1 << 30;

/// A `zarr.json` read and parsed: bounded, regular files only, JSON errors with their
/// line and column.
pub fn read_json(file: &Path) -> Result<Value, StoreError> {
    let text =
        crate::fetch::read_text(file, MAX_METADATA_BYTES).map_err(|e| StoreError::io(file, e))?;
    serde_json::from_str(&text).map_err(|e| {
        StoreError::invalid(
            file,
            format!("line {}, column {}: {e}", e.line(), e.column()),
        )
    })
}

/// The element types arbvis reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataType {
    Bool,
    Int8,
    Int16,
    Int32,
    Int64,
    UInt8,
    UInt16,
    UInt32,
    UInt64,
    Float16,
    Float32,
    Float64,
}

impl DataType {
    /// The zarr v3 name's type, if arbvis reads it.
    pub fn parse(name: &str) -> Option<DataType> {
        use DataType::*;
        Some(match name {
            "bool" => Bool,
            "int8" => Int8,
            "int16" => Int16,
            "int32" => Int32,
            "int64" => Int64,
            "uint8" => UInt8,
            "uint16" => UInt16,
            "uint32" => UInt32,
            "uint64" => UInt64,
            "float16" => Float16,
            "float32" => Float32,
            "float64" => Float64,
            _ => return None,
        })
    }

    /// The zarr v3 name.
    pub fn name(self) -> &'static str {
        use DataType::*;
        match self {
            Bool => "bool",
            Int8 => "int8",
            Int16 => "int16",
            Int32 => "int32",
            Int64 => "int64",
            UInt8 => "uint8",
            UInt16 => "uint16",
            UInt32 => "uint32",
            UInt64 => "uint64",
            Float16 => "float16",
            Float32 => "float32",
            Float64 => "float64",
        }
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        use DataType::*;
        match self {
            Bool | Int8 | UInt8 => 1,
            Int16 | UInt16 | Float16 => 2,
            Int32 | UInt32 | Float32 => 4,
            Int64 | UInt64 | Float64 => 8,
        }
    }

    /// Element `bytes` (exactly [`DataType::size`] of them) as f64.
    fn value(self, bytes: &[u8], big_endian: bool) -> f64 {
        use DataType::*;
        let mut b = [0u8; 8];
        let n = self.size();
        b[..n].copy_from_slice(&bytes[..n]);
        if big_endian {
            b[..n].reverse();
        }
        match self {
            Bool => (b[0] != 0) as u8 as f64,
            Int8 => b[0] as i8 as f64,
            UInt8 => b[0] as f64,
            Int16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            UInt16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Float16 => half::f16::from_le_bytes([b[0], b[1]]).to_f64(),
            Int32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            UInt32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Float32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Int64 => i64::from_le_bytes(b) as f64,
            UInt64 => u64::from_le_bytes(b) as f64,
            Float64 => f64::from_le_bytes(b),
        }
    }
}

/// A bytes-to-bytes codec, as it encoded.
#[derive(Debug, Clone, PartialEq)]
pub enum Codec {
    Zstd,
    Gzip,
    Crc32c,
    /// Blosc 1 (MDIO's codec), decoded by the `zarrs` crate's codec after its header is
    /// checked here; the configuration as the array states it.
    Blosc(Value),
}

impl Codec {
    /// The zarr name.
    pub fn name(&self) -> &'static str {
        match self {
            Codec::Zstd => "zstd",
            Codec::Gzip => "gzip",
            Codec::Crc32c => "crc32c",
            Codec::Blosc(_) => "blosc",
        }
    }

    /// The most bytes this codec can make of `n` bytes (generous: zstd's and deflate's
    /// worst cases are under n/256 and n/1000 plus a header).
    fn bound(&self, n: u64) -> u64 {
        match self {
            Codec::Zstd | Codec::Gzip | Codec::Blosc(_) => {
                n.saturating_add(n / 64).saturating_add(1024)
            }
            Codec::Crc32c => n.saturating_add(4),
        }
    }

    /// Undo this codec on `data`, which must decode to at most `limit` bytes.
    fn decode(&self, data: Vec<u8>, limit: u64) -> Result<Vec<u8>, CodecError> {
        let fail = |m: String| CodecError::new(self.name(), m);
        match self {
            Codec::Blosc(config) => blosc_decode(config, data, limit),
            Codec::Zstd => {
                if let Ok(Some(declared)) = zstd::zstd_safe::get_frame_content_size(&data) {
                    if declared > limit {
                        return Err(fail(format!(
                            "its zstd frame declares {declared} bytes, more than the {limit} it may hold"
                        )));
                    }
                }
                let mut decoder = zstd::stream::read::Decoder::with_buffer(data.as_slice())
                    .map_err(|e| fail(format!("zstd: {e}")))?;
                // The window a frame may ask for: no more than the chunk needs (2^10 at least).
                let log = (64 - limit.max(1024).leading_zeros()).min(31);
                decoder
                    .window_log_max(log)
                    .map_err(|e| fail(format!("zstd: {e}")))?;
                bounded_read(decoder, limit, "zstd").map_err(|e| {
                    if e.message.contains("too much memory") {
                        fail(format!("its zstd frame asks for a window larger than a chunk of {limit} bytes needs"))
                    } else {
                        e
                    }
                })
            }
            Codec::Gzip => bounded_read(
                flate2::read::MultiGzDecoder::new(data.as_slice()),
                limit,
                "gzip",
            ),
            Codec::Crc32c => {
                if data.len() < 4 {
                    return Err(fail("crc32c: shorter than its 4-byte checksum".into()));
                }
                let (body, sum) = data.split_at(data.len() - 4);
                let want = u32::from_le_bytes([sum[0], sum[1], sum[2], sum[3]]);
                let got = crc32c::crc32c(body);
                if got != want {
                    return Err(fail(format!(
                        "crc32c checksum {got:#010x}, the chunk says {want:#010x}: the chunk is damaged"
                    )));
                }
                Ok(body.to_vec())
            }
        }
    }
}

/// An error of the blosc codec.
fn blosc_error(message: String) -> CodecError {
    CodecError::new("blosc", message)
}

/// The `zarrs` blosc codec of an array's configuration.
fn blosc_codec(config: &Value) -> Result<zarrs::array::codec::BloscCodec, CodecError> {
    let configuration: zarrs::metadata_ext::codec::blosc::BloscCodecConfiguration =
        serde_json::from_value(config.clone())
            .map_err(|e| blosc_error(format!("configuration {config}: {e}")))?;
    zarrs::array::codec::BloscCodec::new_with_configuration(&configuration)
        .map_err(|e| blosc_error(format!("configuration {config}: {e}")))
}

/// A blosc 1 buffer decoded, its 16-byte header checked first: what it declares to hold
/// (at most `limit`), its block size (within that), and its compressed length (the
/// buffer's own), so that the decoder never allocates more than the chunk may hold.
fn blosc_decode(config: &Value, data: Vec<u8>, limit: u64) -> Result<Vec<u8>, CodecError> {
    use zarrs::array::BytesToBytesCodecTraits;
    if data.len() < 16 {
        return Err(blosc_error(format!(
            "blosc: {} bytes, shorter than its 16-byte header",
            data.len()
        )));
    }
    let word =
        |at: usize| u32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]) as u64;
    let (nbytes, blocksize, cbytes) = (word(4), word(8), word(12));
    if nbytes > limit {
        return Err(blosc_error(format!(
            "its blosc header declares {nbytes} bytes, more than the {limit} it may hold"
        )));
    }
    if blocksize == 0 || blocksize > nbytes.max(1) || cbytes != data.len() as u64 {
        return Err(blosc_error(format!(
            "its blosc header (block size {blocksize}, {cbytes} compressed bytes) does not fit its {nbytes} bytes in a buffer of {}",
            data.len()
        )));
    }
    let decoded = blosc_codec(config)?
        .decode(
            std::borrow::Cow::Borrowed(&data),
            &zarrs::array::BytesRepresentation::BoundedSize(limit),
            &zarrs::array::CodecOptions::default(),
        )
        .map_err(|e| blosc_error(format!("blosc: {e}")))?;
    Ok(decoded.into_owned())
}

/// Read all of `reader` into a buffer, failing at the first byte past `limit`.
fn bounded_read(reader: impl Read, limit: u64, codec: &'static str) -> Result<Vec<u8>, CodecError> {
    let fail = |m: String| CodecError::new(codec, m);
    let mut out = Vec::new();
    let cap = usize::try_from(limit.min(MAX_CHUNK_BYTES)).unwrap_or(0);
    out.try_reserve(cap)
        .map_err(|_| fail(format!("cannot allocate {limit} bytes to decode it")))?;
    reader
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| fail(format!("{codec}: {e}")))?;
    if out.len() as u64 > limit {
        return Err(fail(format!(
            "{codec} inflates it past the {limit} bytes a chunk of this array holds"
        )));
    }
    Ok(out)
}

/// How chunk keys are spelled.
#[derive(Debug, Clone, PartialEq, Eq)]
enum ChunkKeys {
    /// `c/0/1/2` (or with another separator).
    Default(char),
    /// `0.1.2` (zarr v2's, in a v3 array).
    V2(char),
}

/// One array's `zarr.json`, checked.
#[derive(Debug, Clone)]
pub struct ArrayMeta {
    /// The array's folder.
    pub folder: PathBuf,
    /// Its shape, slowest axis first.
    pub shape: Vec<u64>,
    /// Its chunk shape.
    pub chunks: Vec<u64>,
    /// The element type.
    pub data_type: DataType,
    /// The fill value (absent chunks hold it), as f64.
    pub fill_value: f64,
    /// `bytes` codec's byte order.
    pub big_endian: bool,
    /// The array-to-bytes codec when it is numcodecs' `zfpy` (else `bytes`).
    pub zfp: Option<zfp::Zfp>,
    /// Bytes-to-bytes codecs, in the order they encoded.
    pub codecs: Vec<Codec>,
    /// `dimension_names`, where given.
    pub dimension_names: Option<Vec<Option<String>>>,
    /// `attributes`.
    pub attributes: Map<String, Value>,
    keys: ChunkKeys,
    /// Read from a zarr v2 `.zarray` (an MDIO v0 dataset's) rather than a `zarr.json`.
    v2: bool,
}

/// `value` as `field` of `file`, or an error naming both.
fn field<'a>(doc: &'a Value, name: &str, file: &Path) -> Result<&'a Value, StoreError> {
    doc.get(name)
        .ok_or_else(|| StoreError::invalid(file, format!("no `{name}`: not a zarr v3 array")))
}

/// A chunk shape (each side at least 1) with one side per axis of `shape`, whose chunks of
/// `data_type` hold at most [`MAX_CHUNK_BYTES`].
fn chunk_sizes(
    v: &Value,
    name: &str,
    (shape, data_type): (&[u64], DataType),
    file: &Path,
) -> Result<Vec<u64>, StoreError> {
    let chunks = sizes(v, name, file, 1)?;
    if chunks.len() != shape.len() {
        return Err(StoreError::invalid(
            file,
            format!(
                "`{name}` {chunks:?} has {} axes, the shape {shape:?} {}",
                chunks.len(),
                shape.len()
            ),
        ));
    }
    let bytes = chunks
        .iter()
        .try_fold(1u64, |a, &c| a.checked_mul(c))
        .and_then(|n| n.checked_mul(data_type.size() as u64))
        .filter(|&b| b <= MAX_CHUNK_BYTES);
    if bytes.is_none() {
        return Err(StoreError::invalid(
            file,
            format!(
                "chunks of {chunks:?} {} elements: more than the {} MiB arbvis reads in one chunk",
                data_type.name(),
                MAX_CHUNK_BYTES >> 20
            ),
        ));
    }
    Ok(chunks)
}

/// A list of sizes (`shape`, `chunk_shape`), each checked.
fn sizes(v: &Value, name: &str, file: &Path, min: u64) -> Result<Vec<u64>, StoreError> {
    let list = v
        .as_array()
        .ok_or_else(|| StoreError::invalid(file, format!("`{name}`: expected a list of sizes")))?;
    if list.len() > 32 {
        return Err(StoreError::invalid(
            file,
            format!("`{name}`: {} axes, more than 32", list.len()),
        ));
    }
    list.iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_u64()
                .filter(|&n| n >= min && n <= 1 << 40)
                .ok_or_else(|| {
                    StoreError::invalid(
                        file,
                        format!("`{name}[{i}]` is {x}: expected a whole number {min}..=2^40"),
                    )
                })
        })
        .collect()
}

/// A fill value as f64: numbers, `"NaN"`, `"Infinity"`, `"-Infinity"`, hex bit
/// patterns (`"0x7fc00000"`), booleans.
fn fill(v: &Value, t: DataType, file: &Path) -> Result<f64, StoreError> {
    let bad = || StoreError::invalid(file, format!("`fill_value` {v}: not a {} value", t.name()));
    match v {
        Value::Bool(b) => Ok(*b as u8 as f64),
        Value::Number(n) => n.as_f64().ok_or_else(bad),
        Value::String(s) => match s.as_str() {
            "NaN" => Ok(f64::NAN),
            "Infinity" => Ok(f64::INFINITY),
            "-Infinity" => Ok(f64::NEG_INFINITY),
            hex if hex.starts_with("0x") => {
                let bits = u64::from_str_radix(&hex[2..], 16).map_err(|_| bad())?;
                Ok(match t {
                    DataType::Float16 => half::f16::from_bits(bits as u16).to_f64(),
                    DataType::Float32 => f32::from_bits(bits as u32) as f64,
                    DataType::Float64 => f64::from_bits(bits),
                    _ => return Err(bad()),
                })
            }
            _ => Err(bad()),
        },
        Value::Null => Ok(0.0),
        _ => Err(bad()),
    }
}

/// The names a zarr v3 array's metadata may hold (the spec's; any other is refused
/// unless it is an object saying `"must_understand": false`).
const ARRAY_FIELDS: &[&str] = &[
    "zarr_format",
    "node_type",
    "shape",
    "data_type",
    "chunk_grid",
    "chunk_key_encoding",
    "fill_value",
    "codecs",
    "attributes",
    "storage_transformers",
    "dimension_names",
];

/// The names a zarr v3 group's metadata may hold.
const GROUP_FIELDS: &[&str] = &[
    "zarr_format",
    "node_type",
    "attributes",
    "consolidated_metadata",
];

/// A field of a zarr v3 metadata document that is not one of `known`: the spec (2.1,
/// "extension definitions") says an implementation must fail to open a node with one,
/// unless the field is an object whose `must_understand` is `false`.
fn unknown_fields(file: &Path, doc: &Value, known: &[&str]) -> Result<(), StoreError> {
    let Some(fields) = doc.as_object() else {
        return Err(StoreError::invalid(
            file,
            "the metadata is not a JSON object",
        ));
    };
    for (name, value) in fields {
        let optional = value.get("must_understand").and_then(Value::as_bool) == Some(false);
        if !known.contains(&name.as_str()) && !optional {
            return Err(StoreError::invalid(file, format!(
                "field `{name}` is not one arbvis knows, and it does not say `\"must_understand\": false`: the zarr v3 spec has a reader refuse such a node"
            )));
        }
    }
    Ok(())
}

/// Check a group's `zarr.json` (`doc`, read from `file`) as the spec asks: zarr v3, a
/// group, no field the reader must understand and does not.
pub fn check_group(doc: &Value, file: &Path) -> Result<(), StoreError> {
    if doc.get("zarr_format").and_then(Value::as_u64) != Some(3) {
        return Err(StoreError::invalid(
            file,
            format!(
                "`zarr_format` is {}: arbvis reads zarr v3",
                doc.get("zarr_format").unwrap_or(&Value::Null)
            ),
        ));
    }
    unknown_fields(file, doc, GROUP_FIELDS)
}

/// The array at `folder` (its `zarr.json`), every field checked.
pub fn open_array(folder: &Path) -> Result<ArrayMeta, StoreError> {
    let file = folder.join("zarr.json");
    if !crate::fetch::exists(&file) && crate::fetch::exists(&folder.join(".zarray")) {
        return v2::open_array(folder);
    }
    let doc = read_json(&file)?;
    let invalid = |m: String| StoreError::invalid(&file, m);
    if doc.get("zarr_format").and_then(Value::as_u64) != Some(3) {
        return Err(invalid(format!(
            "`zarr_format` is {}: arbvis reads zarr v3",
            doc.get("zarr_format").unwrap_or(&Value::Null)
        )));
    }
    if doc.get("node_type").and_then(Value::as_str) != Some("array") {
        return Err(invalid("`node_type` is not \"array\"".into()));
    }
    unknown_fields(&file, &doc, ARRAY_FIELDS)?;
    let shape = sizes(field(&doc, "shape", &file)?, "shape", &file, 0)?;
    let type_name = field(&doc, "data_type", &file)?;
    let data_type = type_name
        .as_str()
        .and_then(DataType::parse)
        .ok_or_else(|| {
            let shown = arbvis_core::input::shorten(&type_name.to_string(), 60);
            invalid(format!(
                "`data_type` {shown}: arbvis reads bool, (u)int8-64 and float16-64"
            ))
        })?;
    let grid = field(&doc, "chunk_grid", &file)?;
    if grid.get("name").and_then(Value::as_str) != Some("regular") {
        return Err(invalid(format!(
            "`chunk_grid` {grid}: arbvis reads the \"regular\" grid"
        )));
    }
    let chunk_shape = grid
        .pointer("/configuration/chunk_shape")
        .ok_or_else(|| invalid("`chunk_grid.configuration.chunk_shape` is missing".into()))?;
    let chunks = chunk_sizes(
        chunk_shape,
        "chunk_grid.configuration.chunk_shape",
        (&shape, data_type),
        &file,
    )?;
    let keys = chunk_keys(doc.get("chunk_key_encoding"), &file)?;
    let fill_value = fill(field(&doc, "fill_value", &file)?, data_type, &file)?;
    if doc
        .get("storage_transformers")
        .and_then(Value::as_array)
        .is_some_and(|t| !t.is_empty())
    {
        return Err(invalid("storage transformers: arbvis reads none".into()));
    }
    let (big_endian, zfp, codecs) = codecs(
        field(&doc, "codecs", &file)?,
        (shape.len(), data_type),
        &file,
    )?;
    let dimension_names = match doc.get("dimension_names") {
        None | Some(Value::Null) => None,
        Some(Value::Array(names)) if names.len() == shape.len() => Some(
            names
                .iter()
                .map(|n| n.as_str().map(str::to_string))
                .collect(),
        ),
        Some(other) => {
            return Err(invalid(format!(
                "`dimension_names` {other}: expected {} names",
                shape.len()
            )))
        }
    };
    let attributes = match doc.get("attributes") {
        Some(Value::Object(m)) => m.clone(),
        _ => Map::new(),
    };
    Ok(ArrayMeta {
        folder: folder.to_path_buf(),
        shape,
        chunks,
        data_type,
        fill_value,
        big_endian,
        zfp,
        codecs,
        dimension_names,
        attributes,
        keys,
        v2: false,
    })
}

fn chunk_keys(v: Option<&Value>, file: &Path) -> Result<ChunkKeys, StoreError> {
    let Some(v) = v else {
        return Ok(ChunkKeys::Default('/'));
    };
    let separator = match v.pointer("/configuration/separator") {
        None => None,
        Some(Value::String(s)) if s == "/" || s == "." => s.chars().next(),
        Some(other) => {
            return Err(StoreError::invalid(
                file,
                format!("`chunk_key_encoding` separator {other}: expected \"/\" or \".\""),
            ))
        }
    };
    match v.get("name").and_then(Value::as_str) {
        Some("default") => Ok(ChunkKeys::Default(separator.unwrap_or('/'))),
        Some("v2") => Ok(ChunkKeys::V2(separator.unwrap_or('.'))),
        _ => Err(StoreError::invalid(
            file,
            format!("`chunk_key_encoding` {v}: arbvis reads \"default\" and \"v2\""),
        )),
    }
}

/// The array-to-bytes codec (`bytes`' byte order, or numcodecs' `zfpy`, little-endian)
/// and the bytes-to-bytes codecs, checked.
fn codecs(
    v: &Value,
    (axes, data_type): (usize, DataType),
    file: &Path,
) -> Result<(bool, Option<zfp::Zfp>, Vec<Codec>), StoreError> {
    let list = v
        .as_array()
        .ok_or_else(|| StoreError::invalid(file, "`codecs`: expected a list"))?;
    let mut big_endian = None;
    let mut zfp = None;
    let mut after = Vec::new();
    for (i, c) in list.iter().enumerate() {
        let name = c.get("name").and_then(Value::as_str).unwrap_or("");
        let config = c.get("configuration");
        let refuse =
            |why: &str| StoreError::invalid(file, format!("`codecs[{i}]` {name:?}: {why}"));
        match (name, big_endian.is_some()) {
            ("transpose", false) => {
                let identity: Vec<Value> = (0..axes).map(Value::from).collect();
                let order = config.and_then(|c| c.get("order"));
                if order.and_then(Value::as_array) != Some(&identity) {
                    return Err(refuse("arbvis reads only the identity order"));
                }
            }
            ("bytes", false) => {
                let endian = config.and_then(|c| c.get("endian")).and_then(Value::as_str);
                big_endian = Some(match endian {
                    Some("big") => true,
                    Some("little") | None => false,
                    Some(other) => return Err(refuse(&format!("endian {other:?}"))),
                });
            }
            ("zstd", true) => after.push(Codec::Zstd),
            ("gzip", true) => after.push(Codec::Gzip),
            ("crc32c", true) => after.push(Codec::Crc32c),
            ("blosc", true) => {
                let config = config.cloned().unwrap_or(Value::Null);
                blosc_codec(&config).map_err(|e| refuse(&e.message))?;
                after.push(Codec::Blosc(config));
            }
            ("numcodecs.zfpy", false) => {
                let config = config.cloned().unwrap_or(Value::Null);
                zfp = Some(zfp::Zfp::new(&config, data_type).map_err(|e| refuse(&e.message))?);
                big_endian = Some(false);
            }
            ("numcodecs.zfpy", true) => {
                return Err(refuse(
                    "zfpy turns the array into bytes: it takes the place of `bytes`, not a place after it",
                ))
            }
            ("zfp" | "zfpy" | "numcodecs.zfp", _) => {
                return Err(refuse(
                    "not read: arbvis reads numcodecs' zfpy (`numcodecs.zfpy`, as mdio-python \
                     and zarr-python write ZFP) in place of the `bytes` codec",
                ))
            }
            ("sharding_indexed", _) => {
                return Err(refuse(
                    "sharded arrays are not read; rewrite the store without sharding",
                ))
            }
            _ => {
                return Err(refuse(
                    "not a codec arbvis reads (bytes, blosc, zstd, gzip, crc32c, identity \
                     transpose); rewrite the store with those, e.g. zarr-python's default zstd",
                ))
            }
        }
    }
    let big_endian =
        big_endian.ok_or_else(|| StoreError::invalid(file, "`codecs` has no `bytes` codec"))?;
    Ok((big_endian, zfp, after))
}

impl ArrayMeta {
    /// Elements in one chunk.
    pub fn chunk_elements(&self) -> usize {
        self.chunks.iter().product::<u64>() as usize
    }

    /// The file this array's metadata was read from: `zarr.json`, or v2's `.zarray`.
    pub fn metadata_file(&self) -> PathBuf {
        self.folder
            .join(if self.v2 { ".zarray" } else { "zarr.json" })
    }

    /// Chunks per axis.
    pub fn chunk_counts(&self) -> Vec<u64> {
        self.shape
            .iter()
            .zip(&self.chunks)
            .map(|(s, c)| s.div_ceil(*c))
            .collect()
    }

    /// The file of chunk `index` (slowest axis first).
    pub fn chunk_file(&self, index: &[u64]) -> PathBuf {
        let parts: Vec<String> = index.iter().map(u64::to_string).collect();
        match self.keys {
            ChunkKeys::Default(sep) => {
                let mut key = String::from("c");
                for p in &parts {
                    key.push(sep);
                    key.push_str(p);
                }
                self.folder.join(key)
            }
            ChunkKeys::V2(sep) => self.folder.join(parts.join(&sep.to_string())),
        }
    }

    /// The most bytes a chunk file may hold: the decoded size grown by each codec's bound.
    pub fn max_encoded_bytes(&self) -> u64 {
        self.codecs
            .iter()
            .fold(self.serialized_bound(), |n, c| c.bound(n))
    }

    /// The most bytes the array-to-bytes codec makes of a chunk: its raw bytes, or the
    /// longest zfp stream of its size.
    fn serialized_bound(&self) -> u64 {
        match &self.zfp {
            Some(z) => z.bound(&self.chunks),
            None => (self.chunk_elements() * self.data_type.size()) as u64,
        }
    }

    /// Chunk `index` decoded to f32 values (the last axis fastest), or `None` where its
    /// file is absent (zarr's "all fill value"). Errors say what is wrong, without the
    /// file's name (the caller names it).
    pub fn read_chunk(&self, index: &[u64]) -> Result<Option<Vec<f32>>, ChunkError> {
        let Some(data) = self.read_chunk_bytes(index)? else {
            return Ok(None);
        };
        // The store's own types directly; any other through f64.
        Ok(Some(match (self.data_type, self.big_endian) {
            (DataType::Float32, false) => data
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
            (DataType::Float16, false) => data
                .chunks_exact(2)
                .map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32())
                .collect(),
            _ => self.values(&data).map(|v| v as f32).collect(),
        }))
    }

    /// [`ArrayMeta::read_chunk`] in f64 (coordinates that need it).
    pub fn read_chunk_f64(&self, index: &[u64]) -> Result<Option<Vec<f64>>, ChunkError> {
        Ok(self
            .read_chunk_bytes(index)?
            .map(|data| self.values(&data).collect()))
    }

    /// Decoded bytes as values.
    fn values<'a>(&self, data: &'a [u8]) -> impl Iterator<Item = f64> + 'a {
        let (t, big) = (self.data_type, self.big_endian);
        data.chunks_exact(t.size()).map(move |b| t.value(b, big))
    }

    /// Chunk `index`'s decoded bytes, exactly one chunk's worth, or `None` where absent.
    fn read_chunk_bytes(&self, index: &[u64]) -> Result<Option<Vec<u8>>, ChunkError> {
        let file = self.chunk_file(index);
        let max = self.max_encoded_bytes();
        let data = match crate::fetch::read_object(&file, max) {
            Ok(Some(data)) => data,
            Ok(None) => return Ok(None),
            Err(FetchError::TooLarge { bytes, .. }) => {
                let codecs = self.codec_names();
                return Err(ChunkError::TooLarge { bytes, max, codecs });
            }
            Err(e) => return Err(e.into()),
        };
        let mut data = std::sync::Arc::unwrap_or_clone(data);
        let decoded = self.chunk_elements() * self.data_type.size();
        let mut limits = vec![self.serialized_bound()];
        for c in &self.codecs {
            let last = *limits.last().unwrap_or(&0);
            limits.push(c.bound(last));
        }
        for (k, codec) in self.codecs.iter().enumerate().rev() {
            data = codec.decode(data, limits[k])?;
        }
        if let Some(z) = &self.zfp {
            data = z.decode(&data, &self.chunks, self.data_type)?;
        }
        if data.len() != decoded {
            return Err(ChunkError::Size {
                got: data.len(),
                want: decoded,
                chunks: self.chunks.clone(),
                data_type: self.data_type.name(),
            });
        }
        Ok(Some(data))
    }

    /// The codecs, in words.
    pub fn codec_names(&self) -> String {
        let bytes = match (&self.zfp, self.big_endian) {
            (Some(z), _) => z.describe(),
            (None, true) => "bytes (big-endian)".into(),
            (None, false) => "bytes".into(),
        };
        let mut names = vec![bytes];
        names.extend(self.codecs.iter().map(|c| match c {
            // Blosc's compressor and shuffle, as its configuration names them.
            Codec::Blosc(config) => {
                let field = |k: &str| config.get(k).and_then(Value::as_str).unwrap_or("?");
                format!("blosc ({}, {})", field("cname"), field("shuffle"))
            }
            other => other.name().to_string(),
        }));
        names.join(" + ")
    }
}

#[cfg(test)]
mod tests;
mod v2;
pub mod zfp;
