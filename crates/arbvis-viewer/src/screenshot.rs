//! Screenshots: what the view shows, under a name that was free.
//!
//! Decisions:
//! - **Names.** `arbvis-screenshot-NNN.png`, the first number from 001 on whose name is
//!   free in the folder (earlier sessions' pictures are never replaced); the file is
//!   written whole and then linked to its name, which fails if the name was taken
//!   meanwhile ([`arbvis_core::png_io::write_new`]), so two viewers writing into one folder at
//!   once take different names.
//! - **Content.** The 3D picture exactly as rendered (the full-quality picture, float
//!   precision kept in precise mode, or the transparent render), and, when the box, axes
//!   and legends are on, what egui drew over it and in the legends' margin: the window's
//!   pixels of the view are read before and after egui paints, and every pixel egui
//!   changed is taken from the window (opaque); the others are the picture's (or the
//!   background, in the margin). With the overlay off the screenshot is the render of
//!   the saved scene, as `arbvis render` writes it.

use std::io;
use std::path::{Path, PathBuf};

use arbvis_core::image::Image;
use arbvis_core::png_io;

/// The names' common start.
pub const PREFIX: &str = "arbvis-screenshot-";
/// The start of a whole window's picture (a script's `window-shot`).
pub const WINDOW_PREFIX: &str = "arbvis-window-";
/// The highest number tried.
pub const MAX_NUMBER: u32 = 99_999;

/// The name of screenshot `n`.
pub fn name(n: u32) -> String {
    numbered(PREFIX, n)
}

fn numbered(prefix: &str, n: u32) -> String {
    format!("{prefix}{n:03}.png")
}

/// Write `bytes` in `dir` under the first free name `PREFIXNNN.png` from number `from`
/// on; returns its path and number.
pub fn write_next(dir: &Path, prefix: &str, from: u32, bytes: &[u8]) -> io::Result<(PathBuf, u32)> {
    for n in from.max(1)..=MAX_NUMBER {
        let path = dir.join(numbered(prefix, n));
        // A cheap look first (a dangling link takes its name too).
        if path.symlink_metadata().is_ok() {
            continue;
        }
        match png_io::write_new(&path, bytes) {
            Ok(()) => return Ok((path, n)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::other(format!(
        "{}: every name up to {} is taken",
        dir.display(),
        numbered(prefix, MAX_NUMBER)
    )))
}

/// The view as a screenshot: `bare` and `painted` are the window's pixels of the whole
/// view before and after egui painted (same size, top row first); `picture` is the 3D
/// picture, whose top-left corner lies at `at` in the view; `margin` colours the rest
/// of the view where egui drew nothing. The result has the picture's format.
pub fn compose(
    picture: &Image,
    at: [u32; 2],
    bare: &Image,
    painted: &Image,
    margin: [f32; 4],
) -> Image {
    let mut out = Image::filled(bare.width, bare.height, picture.format, margin);
    for y in 0..bare.height {
        for x in 0..bare.width {
            let p = painted.pixel_u8(x, y);
            let colour = if p != bare.pixel_u8(x, y) {
                let c = painted.pixel(x, y);
                [c[0], c[1], c[2], 1.0]
            } else {
                let (px, py) = (x.wrapping_sub(at[0]), y.wrapping_sub(at[1]));
                if px < picture.width && py < picture.height {
                    picture.pixel(px, py)
                } else {
                    continue;
                }
            };
            out.set_pixel(x, y, colour);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use arbvis_core::vocab::TargetFormat;

    #[test]
    fn names_are_never_reused() {
        let dir = std::env::temp_dir().join(format!("arbvis-shots-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // An earlier session's 001 and 003 stay; 002, 004 and 005 are taken in turn.
        std::fs::write(dir.join(name(1)), b"earlier 1").unwrap();
        std::fs::write(dir.join(name(3)), b"earlier 3").unwrap();
        let mut from = 1;
        let mut got = Vec::new();
        for k in 0..3u8 {
            let (path, n) = write_next(&dir, PREFIX, from, &[k]).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), [k]);
            got.push(n);
            from = n + 1;
        }
        assert_eq!(got, [2, 4, 5]);
        assert_eq!(std::fs::read(dir.join(name(1))).unwrap(), b"earlier 1");
        assert_eq!(std::fs::read(dir.join(name(3))).unwrap(), b"earlier 3");
        // Two writers at once, each from 1, 30 pictures each: 60 different names.
        let numbers: Vec<u32> = std::thread::scope(|s| {
            let hs: Vec<_> = (0..2u8)
                .map(|t| {
                    let dir = dir.clone();
                    s.spawn(move || {
                        (0..30)
                            .map(|_| write_next(&dir, PREFIX, 1, &[t; 64]).unwrap().1)
                            .collect::<Vec<u32>>()
                    })
                })
                .collect();
            hs.into_iter().flat_map(|h| h.join().unwrap()).collect()
        });
        let mut unique = numbers.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), 60, "{numbers:?}");
        assert_eq!(*unique.last().unwrap(), 65, "the 60 after 1..=5");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn compose_keeps_the_picture_where_egui_drew_nothing() {
        let f = TargetFormat::Rgba32f;
        // A 4x2 view: a 3x2 picture at its left, a one-pixel margin at its right.
        let mut picture = Image::filled(3, 2, f, [0.25, 0.5, 0.75, 1.0]);
        picture.set_pixel(2, 1, [0.1234, 0.0, 0.0, 1.0]);
        let bare = Image::filled(4, 2, TargetFormat::Rgba8, [0.0, 0.0, 0.0, 1.0]);
        let mut painted = bare.clone();
        painted.set_pixel(1, 0, [1.0, 1.0, 1.0, 1.0]); // a box line
        painted.set_pixel(3, 1, [200.0 / 255.0, 0.0, 0.0, 1.0]); // a legend
        let margin = [0.0, 0.0, 0.0, 1.0];
        let out = compose(&picture, [0, 0], &bare, &painted, margin);
        assert_eq!((out.width, out.height, out.format), (4, 2, f));
        assert_eq!(out.pixel(0, 0), [0.25, 0.5, 0.75, 1.0]);
        assert_eq!(
            out.pixel(2, 1),
            [0.1234, 0.0, 0.0, 1.0],
            "float precision kept"
        );
        assert_eq!(out.pixel(1, 0), [1.0, 1.0, 1.0, 1.0]);
        assert_eq!(out.pixel(3, 1), [200.0 / 255.0, 0.0, 0.0, 1.0]);
        assert_eq!(out.pixel(3, 0), margin);
        // A transparent margin stays transparent; the picture may sit lower.
        let out = compose(&picture, [1, 1], &bare, &bare, [0.0; 4]);
        assert_eq!(out.pixel(0, 0), [0.0; 4]);
        assert_eq!(out.pixel(1, 1), [0.25, 0.5, 0.75, 1.0]);
    }
}
