//! How a conversion compresses the chunks it writes.
//!
//! The default is blosc with LZ4 over shuffled bytes (the codec family MDIO writes): on a
//! float survey it made smaller chunks than zstd level 1 for less CPU time, and decodes
//! faster (measured: docs/benchmarks.md, "Figures behind the store's settings").

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use zarrs::array::codec::api::BytesToBytesCodecTraits;
use zarrs::array::codec::ZstdCodec;
use zarrs::array::codec::{BloscCodec, BloscCompressionLevel, BloscCompressor, BloscShuffleMode};

/// A store's chunk compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// Chunks as their bytes.
    None,
    /// zstd at the given level (1-22).
    Zstd(i32),
    /// blosc: LZ4 at level 5 over bytes shuffled by the element size.
    #[default]
    Lz4,
}

impl Compression {
    /// The bytes-to-bytes codecs for an array of `typesize`-byte elements (none where the
    /// size is not fixed).
    pub fn codecs(self, typesize: Option<usize>) -> Vec<Arc<dyn BytesToBytesCodecTraits>> {
        match self {
            Compression::None => vec![],
            Compression::Zstd(level) => vec![Arc::new(ZstdCodec::new(level, false))],
            Compression::Lz4 => {
                let shuffle = match typesize {
                    Some(n) if n > 1 => BloscShuffleMode::Shuffle,
                    _ => BloscShuffleMode::NoShuffle,
                };
                let level = BloscCompressionLevel::try_from(5u8).expect("5 is a blosc level");
                // LZ4 is in every blosc build; typesize is given wherever shuffling is.
                let codec = BloscCodec::new(BloscCompressor::LZ4, level, None, shuffle, typesize)
                    .expect("blosc LZ4 with its element size");
                vec![Arc::new(codec)]
            }
        }
    }
}

impl fmt::Display for Compression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Compression::None => write!(f, "none"),
            Compression::Zstd(level) => write!(f, "zstd:{level}"),
            Compression::Lz4 => write!(f, "lz4"),
        }
    }
}

/// A compression's name that is not one ([`Compression::from_str`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{0}': expected lz4, zstd, zstd:LEVEL (1-22) or none")]
pub struct UnknownCompression(pub String);

impl FromStr for Compression {
    type Err = UnknownCompression;

    /// `lz4`, `zstd` (level 1), `zstd:LEVEL` (1-22) or `none`.
    fn from_str(s: &str) -> Result<Self, UnknownCompression> {
        match s {
            "none" => Ok(Compression::None),
            "lz4" => Ok(Compression::Lz4),
            "zstd" => Ok(Compression::Zstd(1)),
            _ => match s.strip_prefix("zstd:").map(str::parse::<i32>) {
                Some(Ok(level)) if (1..=22).contains(&level) => Ok(Compression::Zstd(level)),
                _ => Err(UnknownCompression(s.to_string())),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back() {
        for c in [
            Compression::None,
            Compression::Lz4,
            Compression::Zstd(1),
            Compression::Zstd(22),
        ] {
            assert_eq!(c.to_string().parse::<Compression>(), Ok(c));
        }
        assert_eq!("zstd".parse::<Compression>(), Ok(Compression::Zstd(1)));
        for bad in ["zstd:0", "zstd:23", "zstd:x", "gzip", "", "LZ4"] {
            let e = bad.parse::<Compression>().unwrap_err().to_string();
            assert!(e.contains("expected lz4"), "{bad}: {e}");
        }
    }

    #[test]
    fn lz4_shuffles_only_multibyte_elements() {
        assert_eq!(Compression::None.codecs(Some(4)).len(), 0);
        assert_eq!(Compression::Lz4.codecs(Some(4)).len(), 1);
        assert_eq!(Compression::Lz4.codecs(Some(1)).len(), 1);
        assert_eq!(Compression::Lz4.codecs(None).len(), 1);
    }
}
