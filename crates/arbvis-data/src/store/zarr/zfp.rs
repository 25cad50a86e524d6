//! ZFP chunks as numcodecs' `zfpy` writes them (zarr v3 `numcodecs.zfpy`, zarr v2
//! compressor `zfpy`; mdio-python's ZFP option): decoded by the `zarrs` crate's codec
//! (its `zfp` feature, the zfp C library), after the stream's header is checked here.
//!
//! zfp trusts its stream: the header's field (type and sizes) says where it writes, and
//! the bit stream is read without an end. So before zarrs decodes a chunk, its header
//! must be zfp's (magic `zfp`, codec 5), name the chunk's own type and sizes (zfpy writes
//! the last axis as x), and a mode; and the bytes handed over are padded with zeros to
//! the most a stream of that mode can read (every block at its most bits), so a cut or
//! damaged chunk decodes to garbage values, never to a read past its buffer.
//!
//! Modes: reversible (lossless: the decoded values are the written ones, bit for bit),
//! fixed accuracy, rate and precision (lossy: [`Zfp::lossy`], said by `inspect` and by
//! the precise mode's reference, which is of the decoded values).

use serde_json::Value;

use super::{CodecError, DataType};

/// An error of the zfpy codec.
fn zfp_error(message: impl Into<String>) -> CodecError {
    CodecError::new("zfpy", message)
}

/// zfp's most bits per block in its short modes but fixed rate (`ZFP_MAX_BITS`).
const MAX_BITS: u64 = 16658;

/// The codec version of zfp 1.0's streams (`ZFP_CODEC`).
const CODEC: u64 = 5;

/// A `zfpy` codec as an array states it.
#[derive(Debug, Clone, PartialEq)]
pub struct Zfp {
    /// The configuration (numcodecs' keys: `mode` 2 rate, 3 precision, 4 accuracy, 5
    /// reversible, and the mode's parameter), without v2's `id` and `compression_kwargs`.
    pub config: Value,
    /// numcodecs' mode number.
    mode: i64,
}

impl Zfp {
    /// Read a configuration (v3's `configuration`, or v2's compressor object) for an
    /// array of `data_type`.
    pub fn new(config: &Value, data_type: DataType) -> Result<Zfp, CodecError> {
        let mut config = config.clone();
        if let Some(map) = config.as_object_mut() {
            map.remove("id");
            map.remove("compression_kwargs");
        }
        let mode = config.get("mode").and_then(Value::as_i64).ok_or_else(|| {
            zfp_error(format!(
                "configuration {config}: no `mode` (2 rate, 3 precision, 4 accuracy, 5 reversible)"
            ))
        })?;
        if !(2..=5).contains(&mode) {
            return Err(zfp_error(format!(
                "mode {mode}: numcodecs' zfpy modes are 2 (fixed rate), 3 (fixed precision), 4 (fixed accuracy) and 5 (reversible)"
            )));
        }
        if !matches!(
            data_type,
            DataType::Float32 | DataType::Float64 | DataType::Int32 | DataType::Int64
        ) {
            return Err(zfp_error(format!(
                "zfpy on {}: zfp compresses float32, float64, int32 and int64",
                data_type.name()
            )));
        }
        let zfp = Zfp { config, mode };
        zfp.check_configuration()?;
        Ok(zfp)
    }

    /// Whether decoded values may differ from the written ones (every mode but reversible).
    pub fn lossy(&self) -> bool {
        self.mode != 5
    }

    /// `zfpy (reversible: lossless)`, `zfpy (fixed accuracy 0.5: lossy)`.
    pub fn describe(&self) -> String {
        let number = |k: &str| self.config.get(k).map_or("?".into(), Value::to_string);
        match self.mode {
            2 => format!("zfpy (fixed rate {} bits a value: lossy)", number("rate")),
            3 => format!("zfpy (fixed precision {} bits: lossy)", number("precision")),
            4 => format!("zfpy (fixed accuracy {}: lossy)", number("tolerance")),
            _ => "zfpy (reversible: lossless)".into(),
        }
    }

    /// The most bytes a stream for a chunk of `shape` can hold: the header and every block
    /// at zfp's most bits.
    pub fn bound(&self, shape: &[u64]) -> u64 {
        let blocks: u64 = shape.iter().map(|n| n.div_ceil(4)).product();
        (148 + blocks.saturating_mul(1 << 15)).div_ceil(8) + 16
    }

    #[cfg(feature = "zfp")]
    fn codec(&self) -> Result<zarrs::array::codec::ZfpyCodec, CodecError> {
        let configuration: zarrs::metadata_ext::codec::zfpy::ZfpyCodecConfiguration =
            serde_json::from_value(self.config.clone())
                .map_err(|e| zfp_error(format!("zfpy configuration {}: {e}", self.config)))?;
        zarrs::array::codec::ZfpyCodec::new_with_configuration(&configuration)
            .map_err(|e| zfp_error(format!("zfpy configuration {}: {e}", self.config)))
    }

    #[cfg(feature = "zfp")]
    fn check_configuration(&self) -> Result<(), CodecError> {
        self.codec().map(|_| ())
    }

    #[cfg(not(feature = "zfp"))]
    fn check_configuration(&self) -> Result<(), CodecError> {
        Ok(())
    }

    /// The chunk of `shape` and `data_type` in `data` (a zfpy stream), decoded to its
    /// little-endian bytes.
    pub fn decode(
        &self,
        data: &[u8],
        shape: &[u64],
        data_type: DataType,
    ) -> Result<Vec<u8>, CodecError> {
        let header = Header::read(data)?;
        let want_type = match data_type {
            DataType::Int32 => 1,
            DataType::Int64 => 2,
            DataType::Float32 => 3,
            _ => 4,
        };
        let sizes: Vec<u64> = shape.iter().rev().copied().collect();
        if header.scalar != want_type || header.sizes != sizes {
            return Err(zfp_error(format!(
                "its zfp header describes {} values of type {} ({}), not the chunk's {:?} of {}",
                header
                    .sizes
                    .iter()
                    .map(u64::to_string)
                    .collect::<Vec<_>>()
                    .join(" x "),
                header.scalar,
                ["int32", "int64", "float", "double"]
                    .get(header.scalar as usize - 1)
                    .unwrap_or(&"?"),
                shape,
                data_type.name()
            )));
        }
        let blocks: u64 = shape.iter().map(|n| n.div_ceil(4)).product();
        let most = (header.bits + blocks.saturating_mul(header.max_bits)).div_ceil(8) + 16;
        self.decode_padded(data, most, shape, data_type)
    }

    #[cfg(feature = "zfp")]
    fn decode_padded(
        &self,
        data: &[u8],
        most: u64,
        shape: &[u64],
        data_type: DataType,
    ) -> Result<Vec<u8>, CodecError> {
        use std::num::NonZeroU64;
        use zarrs::array::ArrayToBytesCodecTraits;
        let mut padded = Vec::new();
        let len = usize::try_from(most.max(data.len() as u64))
            .map_err(|_| zfp_error("its zfp stream is too large"))?;
        padded
            .try_reserve_exact(len)
            .map_err(|_| zfp_error(format!("cannot allocate {len} bytes to decode it")))?;
        padded.extend_from_slice(data);
        padded.resize(len, 0);
        let shape: Vec<NonZeroU64> = shape
            .iter()
            .map(|&n| NonZeroU64::new(n).ok_or_else(|| zfp_error("a chunk side of 0")))
            .collect::<Result<_, _>>()?;
        let (zarrs_type, fill) = match data_type {
            DataType::Int32 => (
                zarrs::array::data_type::int32(),
                0i32.to_le_bytes().to_vec(),
            ),
            DataType::Int64 => (
                zarrs::array::data_type::int64(),
                0i64.to_le_bytes().to_vec(),
            ),
            DataType::Float32 => (
                zarrs::array::data_type::float32(),
                0f32.to_le_bytes().to_vec(),
            ),
            _ => (
                zarrs::array::data_type::float64(),
                0f64.to_le_bytes().to_vec(),
            ),
        };
        let decoded = self
            .codec()?
            .decode(
                std::borrow::Cow::Borrowed(&padded),
                &shape,
                &zarrs_type,
                &zarrs::array::FillValue::new(fill),
                &zarrs::array::CodecOptions::default(),
            )
            .map_err(|e| zfp_error(format!("zfp: {e}")))?;
        let bytes = decoded
            .into_fixed()
            .map_err(|e| zfp_error(format!("zfp: {e}")))?;
        Ok(bytes.into_owned())
    }

    #[cfg(not(feature = "zfp"))]
    fn decode_padded(
        &self,
        _: &[u8],
        _: u64,
        _: &[u64],
        _: DataType,
    ) -> Result<Vec<u8>, CodecError> {
        Err(zfp_error("this arbvis was built without its `zfp` feature (a default feature; it needs cmake and libclang to build), so it cannot decode ZFP chunks"))
    }
}

/// What a zfp stream's full header says.
#[derive(Debug, Clone, PartialEq)]
struct Header {
    /// zfp's scalar type: 1 int32, 2 int64, 3 float, 4 double.
    scalar: u64,
    /// Values along x (fastest), y, z, w, as many as the field has axes.
    sizes: Vec<u64>,
    /// The most bits a block may take in the stream's mode.
    max_bits: u64,
    /// The header's length in bits.
    bits: u64,
}

/// `n` bits (at most 64) of zfp's bit stream from bit `at`: 64-bit little-endian words
/// filled from their lowest bit, so bit `k` is bit `k % 8` of byte `k / 8`.
fn bits(data: &[u8], at: u64, n: u32) -> Option<u64> {
    let mut v = 0u64;
    for i in 0..n as u64 {
        let k = at + i;
        let byte = *data.get(usize::try_from(k / 8).ok()?)?;
        v |= u64::from((byte >> (k % 8)) & 1) << i;
    }
    Some(v)
}

impl Header {
    /// The full header zfpy writes: 32 bits of magic (`zfp` and the codec version), 52 of
    /// the field (type, axes, sizes), 12 or 64 of the mode.
    fn read(data: &[u8]) -> Result<Header, CodecError> {
        let short = || zfp_error(format!("{} bytes: shorter than a zfp header", data.len()));
        let magic = bits(data, 0, 32).ok_or_else(short)?;
        if magic & 0xff_ffff != u64::from_le_bytes(*b"zfp\0\0\0\0\0") || magic >> 24 != CODEC {
            return Err(zfp_error(format!(
                "no zfp header (expected the magic `zfp` and codec {CODEC}, found bytes {:02x?})",
                &data[..4.min(data.len())]
            )));
        }
        let meta = bits(data, 32, 52).ok_or_else(short)?;
        let scalar = (meta & 3) + 1;
        let axes = ((meta >> 2) & 3) + 1;
        let field = meta >> 4;
        let width = match axes {
            1 => 48,
            2 => 24,
            3 => 16,
            _ => 12,
        };
        let sizes = (0..axes)
            .map(|a| ((field >> (width * a)) & ((1 << width) - 1)) + 1)
            .collect();
        let mode = bits(data, 84, 12).ok_or_else(short)?;
        // zfp_stream_set_mode: short modes below 2048 are fixed rate (mode + 1 bits a
        // block); the others take up to ZFP_MAX_BITS; 4095 announces the 64-bit form.
        let (max_bits, bits_read) = if mode <= 4094 {
            (if mode < 2048 { mode + 1 } else { MAX_BITS }, 96)
        } else {
            let long = mode | bits(data, 96, 52).ok_or_else(short)? << 12;
            (((long >> 27) & 0x7fff) + 1, 148)
        };
        Ok(Header {
            scalar,
            sizes,
            max_bits,
            bits: bits_read,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A header as zfp writes it, bit by bit.
    fn header(scalar: u64, sizes: &[u64], mode: u64) -> Vec<u8> {
        let width = [48, 24, 16, 12][sizes.len() - 1];
        let mut field = 0u64;
        for (a, n) in sizes.iter().enumerate() {
            field |= (n - 1) << (width * a);
        }
        let meta = field << 4 | ((sizes.len() as u64 - 1) << 2) | (scalar - 1);
        let mut stream = Vec::new();
        let mut push = |v: u64, n: u32| {
            for i in 0..n {
                stream.push((v >> i) & 1);
            }
        };
        push(u64::from_le_bytes(*b"zfp\x05\0\0\0\0"), 32);
        push(meta, 52);
        push(mode, 12);
        stream
            .chunks(8)
            .map(|b| b.iter().enumerate().map(|(i, &x)| (x << i) as u8).sum())
            .collect()
    }

    #[test]
    fn headers_are_read_and_held_to_the_chunk() {
        // 3D float, x = 7 (the last axis), y = 5, z = 300, fixed accuracy (a short mode).
        let h = Header::read(&header(3, &[7, 5, 300], 2048 + 128 + 1 + 40)).unwrap();
        assert_eq!(
            (h.scalar, h.sizes.clone(), h.max_bits, h.bits),
            (3, vec![7, 5, 300], MAX_BITS, 96)
        );
        // Fixed rate: mode + 1 bits a block.
        assert_eq!(Header::read(&header(4, &[9], 63)).unwrap().max_bits, 64);
        let z = Zfp::new(&serde_json::json!({"id": "zfpy", "mode": 4, "tolerance": 0.5, "compression_kwargs": {"tolerance": 0.5}}), DataType::Float32).unwrap();
        assert!(
            z.lossy() && z.describe().contains("accuracy 0.5"),
            "{}",
            z.describe()
        );
        let r = Zfp::new(
            &serde_json::json!({"mode": 5, "tolerance": null}),
            DataType::Float32,
        )
        .unwrap();
        assert!(!r.lossy() && r.describe().contains("lossless"));
        // A header for another chunk, another type, or none, is refused before zfp runs.
        let e = r
            .decode(
                &header(3, &[4, 4, 8], 2048 + 128),
                &[4, 4, 4],
                DataType::Float32,
            )
            .unwrap_err();
        assert!(
            e.message.contains("4 x 4 x 8") && e.message.contains("[4, 4, 4]"),
            "{e}"
        );
        let e = r
            .decode(
                &header(4, &[4, 4, 4], 2048 + 128),
                &[4, 4, 4],
                DataType::Float32,
            )
            .unwrap_err();
        assert!(e.message.contains("type 4 (double)"), "{e}");
        assert!(r
            .decode(b"zfq\x05abcdefghijkl", &[4], DataType::Float32)
            .unwrap_err()
            .message
            .contains("no zfp header"));
        assert!(r
            .decode(b"zf", &[4], DataType::Float32)
            .unwrap_err()
            .message
            .contains("shorter"));
        assert!(Zfp::new(&serde_json::json!({"mode": 1}), DataType::Float32).is_err());
        assert!(Zfp::new(&serde_json::json!({"mode": 5}), DataType::UInt8).is_err());
    }
}
