//! A SEG-Y file as a scene names it: `{ segy = "f3.sgy" }`, or with a pre-stack choice
//! `{ segy = { path = "gather.sgy", prestack = { offset = 400 } } }` /
//! `prestack = "stack"`. Written back in the short form when there is no choice.

use std::fmt;
use std::path::PathBuf;

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::Prestack;

/// A SEG-Y file and what to do with several traces per inline/crossline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SegySource {
    /// The file (relative to the scene's folder).
    pub path: PathBuf,
    /// Several traces at one inline/crossline: refuse, pick an offset, or stack.
    pub prestack: Prestack,
}

/// The long form, with the usual unknown-key errors.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Long {
    path: PathBuf,
    #[serde(default)]
    prestack: Prestack,
}

impl Serialize for SegySource {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.prestack == Prestack::Refuse {
            self.path.serialize(s)
        } else {
            Long {
                path: self.path.clone(),
                prestack: self.prestack,
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
                f.write_str("a file path, or a table with `path` and `prestack`")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<SegySource, E> {
                Ok(SegySource {
                    path: v.into(),
                    prestack: Prestack::Refuse,
                })
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<SegySource, A::Error> {
                let long = Long::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(SegySource {
                    path: long.path,
                    prestack: long.prestack,
                })
            }
        }
        d.deserialize_any(Either)
    }
}
