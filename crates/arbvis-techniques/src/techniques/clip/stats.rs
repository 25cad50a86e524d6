//! What a built clip costs, for the viewer's clip editor: how long the last build took,
//! the bytes of the textures uploaded (INDEX + DATA, or the single-resolution texture)
//! and the compression ratio against the single-resolution texture, in the texel formats
//! the stage uploads at the scene's fidelity ([`super::stage::ClipStage::new`]: faithful
//! single and DATA R8, precise R32F; the INDEX RGBA32F at both).

use super::multires::TexelFormat;
use super::ClipTextures;
use arbvis_core::vocab::Fidelity;

/// The label of [`ClipStats::line`] among a renderer's facts (the viewer's panel).
pub const LABEL: &str = "Clip stats";

/// A built clip's cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClipStats {
    /// Wall-clock seconds of the last build (distances, INDEX-DATA and upload).
    pub build_seconds: f64,
    /// Block side `B` when INDEX-DATA is used, `None` for the single texture.
    pub block: Option<usize>,
    /// Bytes of the INDEX (0 for the single texture).
    pub index_bytes: usize,
    /// Bytes of the DATA, or of the single texture when that is what is uploaded.
    pub data_bytes: usize,
    /// Bytes the single-resolution texture takes (uploaded or not).
    pub single_bytes: usize,
    /// `(INDEX + DATA) / single`; 1 for the single texture.
    pub ratio: f64,
}

/// Bytes per texel of the single texture and of DATA at `fidelity`.
pub fn scalar_format(fidelity: Fidelity) -> TexelFormat {
    match fidelity {
        Fidelity::Faithful => TexelFormat::R8,
        Fidelity::Precise => TexelFormat::R32F,
    }
}

impl ClipStats {
    /// The cost of `textures` uploaded at `fidelity`, built in `build_seconds`.
    pub fn of(textures: &ClipTextures, fidelity: Fidelity, build_seconds: f64) -> ClipStats {
        let scalar = scalar_format(fidelity);
        let single_bytes = textures.single.values.len() * scalar.bytes();
        match &textures.multires {
            Some(m) => {
                let (index_bytes, data_bytes) = m.bytes(TexelFormat::Rgba32F, scalar);
                ClipStats {
                    build_seconds,
                    block: Some(m.block),
                    index_bytes,
                    data_bytes,
                    single_bytes,
                    ratio: m.compression_ratio(TexelFormat::Rgba32F, scalar, scalar),
                }
            }
            None => ClipStats {
                build_seconds,
                block: None,
                index_bytes: 0,
                data_bytes: single_bytes,
                single_bytes,
                ratio: 1.0,
            },
        }
    }

    /// Bytes uploaded in all.
    pub fn bytes(&self) -> usize {
        self.index_bytes + self.data_bytes
    }

    /// One line for the viewer, e.g. `INDEX-DATA (B = 8): built in 12 ms; INDEX 8.0 KiB +
    /// DATA 96.0 KiB = 104.0 KiB, ratio 0.406 of the single texture (256.0 KiB)`.
    pub fn line(&self) -> String {
        let ms = self.build_seconds * 1e3;
        match self.block {
            Some(b) => format!(
                "INDEX-DATA (B = {b}): built in {ms:.0} ms; INDEX {} + DATA {} = {}, ratio {:.3} of the single texture ({})",
                kib(self.index_bytes),
                kib(self.data_bytes),
                kib(self.bytes()),
                self.ratio,
                kib(self.single_bytes)
            ),
            None => format!(
                "single texture: built in {ms:.0} ms; {}, ratio 1 (uncompressed)",
                kib(self.single_bytes)
            ),
        }
    }
}

fn kib(bytes: usize) -> String {
    format!("{:.1} KiB", bytes as f64 / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::clip::{ClipSpec, ShapeSpec};

    #[test]
    fn the_stats_count_what_the_stage_uploads() {
        let mut spec = ClipSpec {
            shape: ShapeSpec::Sphere {
                center: [0.0; 3],
                radius: 0.5,
            },
            invert: false,
            block: 4,
            multires: true,
            resolution: None,
        };
        let base = std::path::Path::new(".");
        let t = spec.build(base, [16, 16, 16], [1.0; 3], 2048).unwrap();
        let s = ClipStats::of(&t, Fidelity::Precise, 0.25);
        let m = t.multires.as_ref().unwrap();
        assert_eq!(s.block, Some(4));
        assert_eq!(s.index_bytes, 4 * 4 * 4 * 16);
        assert_eq!(s.data_bytes, m.data.len() * 4);
        assert_eq!(s.single_bytes, 16 * 16 * 16 * 4);
        assert_eq!(s.ratio, s.bytes() as f64 / s.single_bytes as f64);
        assert!(s
            .line()
            .starts_with("INDEX-DATA (B = 4): built in 250 ms; INDEX 1.0 KiB"));
        spec.multires = false;
        let t = spec.build(base, [16, 16, 16], [1.0; 3], 2048).unwrap();
        let s = ClipStats::of(&t, Fidelity::Faithful, 0.0);
        assert_eq!((s.index_bytes, s.data_bytes, s.ratio), (0, 4096, 1.0));
        assert_eq!(
            s.line(),
            "single texture: built in 0 ms; 4.0 KiB, ratio 1 (uncompressed)"
        );
    }
}
