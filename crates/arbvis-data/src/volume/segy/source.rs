//! A SEG-Y file as a scene names it: `{ segy = "f3.sgy" }`, or with a pre-stack choice
//! `{ segy = { path = "gather.sgy", prestack = { offset = 400 } } }` /
//! `prestack = "stack"`, or with the trace-header bytes of the inline and crossline numbers
//! `{ segy = { path = "survey.sgy", iline = 9, xline = 21 } }` (else detected,
//! [`super::keys`]). Written back in the short form when there is no choice.

use std::fmt;
use std::path::PathBuf;

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{KeyBytes, Prestack};

/// A SEG-Y file and what to do with several traces per inline/crossline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SegySource {
    /// The file (relative to the scene's folder).
    pub path: PathBuf,
    /// Several traces at one inline/crossline: refuse, pick an offset, or stack.
    pub prestack: Prestack,
    /// The inline and crossline bytes, where the scene names them.
    pub keys: KeyBytes,
}

impl SegySource {
    /// A file read with every choice at its default.
    pub fn new(path: impl Into<PathBuf>) -> SegySource {
        SegySource {
            path: path.into(),
            prestack: Prestack::Refuse,
            keys: KeyBytes::default(),
        }
    }
}

/// The long form, with the usual unknown-key errors.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Long {
    path: PathBuf,
    #[serde(default)]
    prestack: Prestack,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    iline: Option<u16>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    xline: Option<u16>,
}

impl Serialize for SegySource {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.prestack == Prestack::Refuse && self.keys.is_default() {
            self.path.serialize(s)
        } else {
            Long {
                path: self.path.clone(),
                prestack: self.prestack,
                iline: self.keys.iline,
                xline: self.keys.xline,
            }
            .serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for SegySource {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<SegySource, D::Error> {
        struct Either;
        impl<'de> Visitor<'de> for Either {
            type Value = SegySource;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a file path, or a table with `path`, `prestack`, `iline` and `xline`")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<SegySource, E> {
                Ok(SegySource::new(v))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<SegySource, A::Error> {
                let long = Long::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(SegySource {
                    path: long.path,
                    prestack: long.prestack,
                    keys: KeyBytes {
                        iline: long.iline,
                        xline: long.xline,
                    },
                })
            }
        }
        d.deserialize_any(Either)
    }
}
