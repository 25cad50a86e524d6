//! Reading the files users name, safely: regular files only (a FIFO would block forever,
//! `/dev/zero` never ends), never more bytes than the file holds or the format can need,
//! and text decoded with the position of the first invalid byte.
//!
//! Every loader opens its input through here, so one place decides what "bad input" costs:
//! an error naming the file, the position and the cause, in bounded time and memory.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// Largest scene file read (scenes are a few hundred bytes; this leaves room for
/// generated ones while refusing a runaway file before it is read).
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// Largest text file of small tables and scripts.
pub const MAX_SMALL_TEXT_BYTES: u64 = 1 << 20;

/// An I/O error whose message is `message` (shown after the file name by callers).
pub fn invalid(message: impl Into<String>) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message.into())
}

/// Open `path` for reading if it is a regular file; returns it with its length.
/// Directories, FIFOs, sockets and devices are refused by name (following symlinks).
pub fn open_regular(path: &Path) -> io::Result<(File, u64)> {
    let meta = std::fs::metadata(path).map_err(|e| not_found_where(path, e))?;
    let kind = meta.file_type();
    if !kind.is_file() {
        return Err(invalid(format!(
            "not a regular file but {}: arbvis reads data only from regular files",
            describe_kind(&kind)
        )));
    }
    let file = File::open(path)?;
    Ok((file, meta.len()))
}

/// A relative path that does not resolve: say which absolute path was tried (a scene's
/// data paths are relative to the scene's folder, not to the current one).
fn not_found_where(path: &Path, e: io::Error) -> io::Error {
    if e.kind() != io::ErrorKind::NotFound || path.is_absolute() {
        return e;
    }
    match std::path::absolute(path) {
        Ok(abs) => io::Error::new(
            io::ErrorKind::NotFound,
            format!("no such file (looked for {})", abs.display()),
        ),
        Err(_) => e,
    }
}

fn describe_kind(kind: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if kind.is_char_device() {
            return "a character device";
        }
        if kind.is_block_device() {
            return "a block device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}

/// Read a whole regular file of at most `max_bytes` bytes. A larger file is refused
/// before anything is read; the read itself stops at the length the file had when it
/// was opened (plus one byte, to notice a file that grows meanwhile).
pub fn read_regular(path: &Path, max_bytes: u64) -> io::Result<Vec<u8>> {
    let (file, len) = open_regular(path)?;
    if len > max_bytes {
        return Err(invalid(format!(
            "the file holds {len} bytes, more than the {max_bytes} bytes this reader accepts"
        )));
    }
    let capacity = usize::try_from(len).map_err(|_| invalid("file too large"))?;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(capacity)
        .map_err(|_| invalid(format!("cannot allocate {len} bytes for the file")))?;
    file.take(len + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > len {
        return Err(invalid("the file grew while it was read"));
    }
    Ok(bytes)
}

/// Read a regular text file of at most `max_bytes` bytes as UTF-8; invalid UTF-8 is
/// reported with its line, column and byte offset.
pub fn read_text(path: &Path, max_bytes: u64) -> io::Result<String> {
    let bytes = read_regular(path, max_bytes)?;
    utf8(bytes)
}

/// Bytes to text, naming the line, column and byte offset of the first invalid byte.
pub fn utf8(bytes: Vec<u8>) -> io::Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let valid = &e.as_bytes()[..at];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        let column = String::from_utf8_lossy(&valid[line_start..])
            .chars()
            .count()
            + 1;
        invalid(format!(
            "line {line}, column {column} (byte {at}): not UTF-8 text (byte 0x{:02x})",
            e.as_bytes()[at]
        ))
    })
}

/// `text` for an error message: whole when short, else its start, an ellipsis and how
/// many characters were left out (so a 50 MB value never reaches a terminal whole).
pub fn shorten(text: &str, max_chars: usize) -> String {
    let count = text.chars().count();
    if count <= max_chars {
        return text.to_string();
    }
    let head: String = text.chars().take(max_chars).collect();
    format!("{head}… ({} more characters)", count - max_chars)
}

/// Tests only (every crate's unit tests): a file under the repository's `data/` (real
/// files no one here wrote, which travel with the clone; `data/README.md` gives their
/// sources and licences).
#[doc(hidden)]
pub fn data_file(relative: &str) -> std::path::PathBuf {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(relative);
    assert!(path.is_file(), "{} is missing from data/", path.display());
    path
}

/// The whitespace-separated words of a text line with their 1-based columns (in
/// characters): what the line-oriented readers (PLY headers, TSurf, ZMap+) place their
/// errors by.
pub fn words(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (column, (byte, c)) in line.char_indices().enumerate() {
        match (c.is_whitespace(), start) {
            (false, None) => start = Some((column + 1, byte)),
            (true, Some((col, from))) => {
                out.push((col, &line[from..byte]));
                start = None;
            }
            _ => {}
        }
    }
    if let Some((col, from)) = start {
        out.push((col, &line[from..]));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("arbvis-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn special_files_are_refused_at_once() {
        for (path, what) in [
            ("/dev/zero", "character device"),
            ("/dev/urandom", "character device"),
            ("/", "directory"),
        ] {
            let e = read_regular(Path::new(path), u64::MAX).unwrap_err();
            assert!(e.to_string().contains(what), "{path}: {e}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = std::env::temp_dir().join(format!("arbvis-fifo-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("pipe");
        let _ = std::fs::remove_file(&fifo);
        let status = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !status.is_ok_and(|s| s.success()) {
            panic!("mkfifo is needed for this test (coreutils)");
        }
        let e = read_regular(&fifo, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("FIFO"), "{e}");
    }

    #[test]
    fn size_bound_is_checked_before_reading() {
        let p = temp("big.txt", &[b'a'; 100]);
        let e = read_regular(&p, 99).unwrap_err();
        assert!(e.to_string().contains("100 bytes"), "{e}");
        assert_eq!(read_regular(&p, 100).unwrap().len(), 100);
    }

    #[test]
    fn invalid_utf8_names_line_and_column() {
        let p = temp("bad.txt", b"ok\nab\xffc\n");
        let e = read_text(&p, 1000).unwrap_err().to_string();
        assert!(e.contains("line 2, column 3 (byte 5)"), "{e}");
    }

    #[test]
    fn long_values_are_shortened() {
        let long = "x".repeat(10_000);
        let s = shorten(&long, 20);
        assert!(s.starts_with("xxxxxxxxxxxxxxxxxxxx…"));
        assert!(s.contains("9980 more characters"), "{s}");
        assert_eq!(shorten("short", 20), "short");
    }
}
