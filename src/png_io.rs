//! PNG files: written atomically (temporary file in the same folder, then rename) with
//! text chunks saying what made them; read back for golden-image tests.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

use crate::gl::TargetFormat;
use crate::image::Image;

/// Errors reading or writing PNG files; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum PngError {
    /// An I/O failure.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What failed.
        source: std::io::Error,
    },
    /// The PNG encoder or decoder failed.
    #[error("{path}: {message}")]
    Format {
        /// The file.
        path: String,
        /// What the codec said.
        message: String,
    },
}

/// Write `image` to `path` atomically with `text` chunks (key, value). RGBA8 images are
/// written as 8-bit PNG, float images as 16-bit PNG (values clamped to 0..1).
pub fn write_png(path: &Path, image: &Image, text: &[(&str, String)]) -> Result<(), PngError> {
    let name = path.display().to_string();
    let io = |source| PngError::Io {
        path: name.clone(),
        source,
    };
    let fmt = |e: png::EncodingError| PngError::Format {
        path: name.clone(),
        message: e.to_string(),
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let file_name = path.file_name().ok_or_else(|| PngError::Format {
        path: name.clone(),
        message: "not a file path".into(),
    })?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let file = File::create(&tmp).map_err(io)?;
        let mut w = BufWriter::new(file);
        {
            let mut enc = png::Encoder::new(&mut w, image.width, image.height);
            enc.set_color(png::ColorType::Rgba);
            let sixteen = image.format != TargetFormat::Rgba8;
            enc.set_depth(if sixteen {
                png::BitDepth::Sixteen
            } else {
                png::BitDepth::Eight
            });
            for (k, v) in text {
                enc.add_text_chunk(k.to_string(), v.clone()).map_err(fmt)?;
            }
            let mut writer = enc.write_header().map_err(fmt)?;
            if sixteen {
                let bytes: Vec<u8> = image
                    .to_rgba16()
                    .iter()
                    .flat_map(|v| v.to_be_bytes())
                    .collect();
                writer.write_image_data(&bytes).map_err(fmt)?;
            } else {
                writer.write_image_data(&image.to_rgba8()).map_err(fmt)?;
            }
            writer.finish().map_err(fmt)?;
        }
        let file = w.into_inner().map_err(|e| io(e.into_error()))?;
        file.sync_all().map_err(io)?;
        std::fs::rename(&tmp, path).map_err(io)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Read a PNG as an RGBA8 [`Image`] (8-bit RGBA files only, as this crate writes for
/// RGBA8 targets), with its text chunks.
pub fn read_png(path: &Path) -> Result<(Image, Vec<(String, String)>), PngError> {
    let name = path.display().to_string();
    let fmt = |message: String| PngError::Format {
        path: name.clone(),
        message,
    };
    let file = File::open(path).map_err(|source| PngError::Io {
        path: name.clone(),
        source,
    })?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| fmt(e.to_string()))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| fmt("image too large".into()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| fmt(e.to_string()))?;
    let text = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    let (w, h) = (info.width, info.height);
    let channels = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
        (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
        (ct, bd) => return Err(fmt(format!("expected 8-bit RGB(A), found {ct:?} {bd:?}"))),
    };
    let mut image = Image::filled(w, h, TargetFormat::Rgba8, [0.0; 4]);
    for (o, px) in image
        .data
        .chunks_exact_mut(4)
        .zip(buf[..info.buffer_size()].chunks_exact(channels))
    {
        for c in 0..4 {
            o[c] = if c < channels {
                px[c] as f32 / 255.0
            } else {
                1.0
            };
        }
    }
    Ok((image, text))
}

/// Write bytes to `path` atomically (temporary file + rename), e.g. CSV or TOML output.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        path.file_name()
            .map(|f| f.to_string_lossy())
            .unwrap_or_default(),
        std::process::id()
    ));
    let result = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
