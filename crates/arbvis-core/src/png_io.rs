//! PNG files: written atomically (temporary file in the same folder, then rename) with
//! text chunks saying what made them; read back for golden-image tests.

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::image::Image;
use crate::vocab::TargetFormat;

/// Errors reading or writing PNG files; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum PngError {
    /// An I/O failure.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// What failed.
        error: std::io::Error,
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
    let bytes = encode_png(&name, image, text)?;
    write_atomic(path, &bytes).map_err(|error| PngError::Io { path: name, error })
}

/// `image` as PNG bytes with `text` chunks, as [`write_png`] writes them (`name` is the
/// file named in errors).
pub fn encode_png(name: &str, image: &Image, text: &[(&str, String)]) -> Result<Vec<u8>, PngError> {
    let fmt = |e: png::EncodingError| PngError::Format {
        path: name.to_string(),
        message: e.to_string(),
    };
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, image.width, image.height);
        enc.set_color(png::ColorType::Rgba);
        let sixteen = image.format != TargetFormat::Rgba8;
        enc.set_depth(if sixteen {
            png::BitDepth::Sixteen
        } else {
            png::BitDepth::Eight
        });
        let mut writer = enc.write_header().map_err(fmt)?;
        for (k, v) in text {
            writer.write_text_chunk(&text_chunk(k, v)).map_err(fmt)?;
        }
        if sixteen {
            let data: Vec<u8> = image
                .to_rgba16()
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect();
            writer.write_image_data(&data).map_err(fmt)?;
        } else {
            writer.write_image_data(&image.to_rgba8()).map_err(fmt)?;
        }
        writer.finish().map_err(fmt)?;
    }
    Ok(bytes)
}

/// Largest text embedded in one chunk; longer texts (a scene with a huge inline table)
/// are cut there, with a note saying so.
pub const MAX_TEXT_BYTES: usize = 256 * 1024;

/// One text chunk: iTXt (UTF-8, so paths in any script survive), compressed when long.
fn text_chunk(key: &str, value: &str) -> png::text_metadata::ITXtChunk {
    // A scene naming a URL with a password or a signature embeds it hidden.
    let value = &crate::secrets::redact(value);
    let value = if value.len() > MAX_TEXT_BYTES {
        let mut cut = MAX_TEXT_BYTES;
        while !value.is_char_boundary(cut) {
            cut -= 1;
        }
        format!(
            "{}\n# ... cut: {} of {} bytes embedded\n",
            &value[..cut],
            cut,
            value.len()
        )
    } else {
        value.to_string()
    };
    let long = value.len() > 1024;
    let mut chunk = png::text_metadata::ITXtChunk::new(key, value);
    chunk.compressed = long;
    chunk
}

/// Read an RGB(A) PNG of 8 or 16 bits per sample as an [`Image`] (RGBA8 or RGBA16F),
/// with its text chunks.
pub fn read_png(path: &Path) -> Result<(Image, Vec<(String, String)>), PngError> {
    let name = path.display().to_string();
    let fmt = |message: String| PngError::Format {
        path: name.clone(),
        message,
    };
    let file = File::open(path).map_err(|error| PngError::Io {
        path: name.clone(),
        error,
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
    let meta = reader.info();
    let mut text: Vec<(String, String)> = meta
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    for t in &meta.utf8_text {
        let mut t = t.clone();
        if t.decompress_text_with_limit(2 * MAX_TEXT_BYTES).is_ok() {
            if let Ok(v) = t.get_text() {
                text.push((t.keyword.clone(), v));
            }
        }
    }
    let (w, h) = (info.width, info.height);
    let channels = match info.color_type {
        png::ColorType::Rgba => 4,
        png::ColorType::Rgb => 3,
        ct => return Err(fmt(format!("expected RGB or RGBA, found {ct:?}"))),
    };
    // 16-bit files (what float targets are written as) come back as RGBA16F images.
    let (samples, format): (Vec<f32>, TargetFormat) = match info.bit_depth {
        png::BitDepth::Eight => (
            buf[..info.buffer_size()]
                .iter()
                .map(|&b| b as f32 / 255.0)
                .collect(),
            TargetFormat::Rgba8,
        ),
        png::BitDepth::Sixteen => (
            buf[..info.buffer_size()]
                .chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]) as f32 / 65535.0)
                .collect(),
            TargetFormat::Rgba16f,
        ),
        bd => {
            return Err(fmt(format!(
                "expected 8 or 16 bits per sample, found {bd:?}"
            )))
        }
    };
    let mut image = Image::filled(w, h, format, [0.0; 4]);
    for (o, px) in image
        .data
        .chunks_exact_mut(4)
        .zip(samples.chunks_exact(channels))
    {
        for c in 0..4 {
            o[c] = if c < channels { px[c] } else { 1.0 };
        }
    }
    Ok((image, text))
}

/// Temporaries being written now, removed by [`remove_temporaries`] when the process is
/// interrupted.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The lock files of [`WriterLock`]s held, removed with the temporaries on SIGINT/SIGTERM.
static LOCKS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The marker in temporary names: `.NAME.arbvis-tmp.PID`.
/// What marks a temporary file of an atomic write (`.NAME.arbvis-tmp.PID`).
pub const TMP_MARK: &str = ".arbvis-tmp.";

/// `path`'s folder (`.` for a bare name) and file name.
fn dir_and_name(path: &Path) -> std::io::Result<(PathBuf, String)> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| crate::input::invalid("not a file path"))?
        .to_string_lossy()
        .to_string();
    Ok((dir, file_name))
}

/// Write bytes to `path` atomically: a temporary file in the same folder, synced, then
/// renamed over `path`. Nothing is left behind on error; on SIGINT/SIGTERM the handler
/// installed by [`remove_temporaries_on_signals`] removes the temporary; a temporary left
/// by a process that died harder (SIGKILL, power loss) is removed by the next write to
/// the same path, once its process is gone.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let (dir, file_name) = dir_and_name(path)?;
    remove_stale(&dir, &file_name);
    let tmp = dir.join(format!(".{file_name}{TMP_MARK}{}", std::process::id()));
    lock_temporaries().push(tmp.clone());
    let result = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    lock_temporaries().retain(|t| t != &tmp);
    result
}

/// Write `bytes` to `path` only if no file has that name: it appears whole (a temporary,
/// synced, then hard-linked to the name, which fails if the name is taken) or not at all,
/// and two writers, in one process or two, never both take a name. An error of kind
/// [`std::io::ErrorKind::AlreadyExists`] says the name was taken. On file systems
/// without hard links the name is claimed by creating it empty (create-new) and the
/// temporary renamed over it.
pub fn write_new(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let (dir, file_name) = dir_and_name(path)?;
    remove_stale(&dir, &file_name);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = dir.join(format!(".{file_name}{TMP_MARK}{}.{n}", std::process::id()));
    lock_temporaries().push(tmp.clone());
    let result = (|| {
        let mut f = File::create_new(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        match std::fs::hard_link(&tmp, path) {
            Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => {
                std::fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(path)?;
                std::fs::rename(&tmp, path)
            }
            other => other,
        }
    })();
    let _ = std::fs::remove_file(&tmp);
    lock_temporaries().retain(|t| t != &tmp);
    result
}

/// A temporary file or folder beside `path` (`.NAME.arbvis-tmp.PID` and a suffix) for a
/// large write done piece by piece: removed when dropped unless committed, on
/// SIGINT/SIGTERM by [`remove_temporaries_on_signals`]'s handler, and, if its process
/// died harder, by the next temporary or write for the same name.
pub struct Temporary {
    path: PathBuf,
    committed: bool,
}

impl Temporary {
    /// Name a temporary beside `path`; nothing is created.
    pub fn beside(path: &Path, suffix: &str) -> std::io::Result<Temporary> {
        let (dir, file_name) = dir_and_name(path)?;
        remove_stale(&dir, &file_name);
        let tmp = dir.join(format!(
            ".{file_name}{TMP_MARK}{}{suffix}",
            std::process::id()
        ));
        remove_path(&tmp);
        lock_temporaries().push(tmp.clone());
        Ok(Temporary {
            path: tmp,
            committed: false,
        })
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rename it to `to` (replacing a file there).
    pub fn commit(mut self, to: &Path) -> std::io::Result<()> {
        std::fs::rename(&self.path, to)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if !self.committed {
            remove_path(&self.path);
        }
        lock_temporaries().retain(|t| t != &self.path);
    }
}

/// Remove a file, or a folder and what it holds.
fn remove_path(path: &Path) {
    if path.is_dir() {
        let _ = std::fs::remove_dir_all(path);
    } else {
        let _ = std::fs::remove_file(path);
    }
}

fn lock_temporaries() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner())
}

/// Remove the temporaries of writes in progress and the lock files held (called on
/// SIGINT/SIGTERM: an interrupted conversion leaves its folder as it found it, but for
/// what it finished).
pub fn remove_temporaries() {
    for t in lock_temporaries().drain(..) {
        remove_path(&t);
    }
    for lock in LOCKS.lock().unwrap_or_else(|e| e.into_inner()).drain(..) {
        let _ = std::fs::remove_file(lock);
    }
}

/// Install a SIGINT/SIGTERM handler that removes temporaries and exits with 130.
pub fn remove_temporaries_on_signals() {
    let _ = ctrlc::set_handler(|| {
        remove_temporaries();
        std::process::exit(130);
    });
}

/// Remove `.NAME.arbvis-tmp.PID` (and `.PID.N`, [`write_new`]'s) files in `dir` whose
/// process no longer runs.
fn remove_stale(dir: &Path, file_name: &str) {
    let prefix = format!(".{file_name}{TMP_MARK}");
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().to_string();
        let Some(pid) = name
            .strip_prefix(&prefix)
            .and_then(|p| p.split('.').next())
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !process_alive(pid) {
            remove_path(&entry.path());
        }
    }
}

/// The exclusive right to write an output (a store, a COPC file), held until dropped: an
/// advisory lock (`flock`) on a lock file holding the holder's pid, so that a second
/// writer is refused naming the first. The kernel releases the lock when its process
/// ends, however it ends; the file goes when the lock is dropped.
pub struct WriterLock {
    file: File,
    path: PathBuf,
    taken_over: Option<u32>,
}

/// The process holding a [`WriterLock`]: `pid 1234`, or `a process` when its lock file
/// names none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LockHolder {
    /// The process whose id the lock file holds.
    Pid(u32),
    /// A process that wrote no id (yet).
    Unnamed,
}

impl std::fmt::Display for LockHolder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LockHolder::Pid(pid) => write!(f, "pid {pid}"),
            LockHolder::Unnamed => write!(f, "a process"),
        }
    }
}

impl WriterLock {
    /// Take the lock at `path` (created if absent). `Ok(Err(holder))`: another process
    /// holds it, `holder` says which (`pid 1234`, or `a process` when it wrote none). A
    /// lock file left by a process that is gone (killed) is taken over, and
    /// [`WriterLock::taken_over`] says whose it was.
    pub fn acquire(path: &Path) -> std::io::Result<Result<WriterLock, LockHolder>> {
        use std::io::Read;
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = (&file).take(64).read_to_string(&mut holder);
                let holder = holder.trim();
                return Ok(Err(match holder.trim().parse::<u32>() {
                    Ok(pid) => LockHolder::Pid(pid),
                    Err(_) => LockHolder::Unnamed,
                }));
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(e),
        }
        // Held: from here a signal removes the file (its pid is written after, and fsync
        // may take milliseconds: a SIGINT in them left the file behind), and so does an
        // error below, through Drop.
        LOCKS
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(path.to_path_buf());
        let mut lock = WriterLock {
            file,
            path: path.to_path_buf(),
            taken_over: None,
        };
        let mut before = String::new();
        let _ = (&lock.file).take(64).read_to_string(&mut before);
        lock.taken_over = before
            .trim()
            .parse::<u32>()
            .ok()
            .filter(|&pid| pid != std::process::id() && !process_alive(pid));
        lock.file.set_len(0)?;
        write!(lock.file, "{}", std::process::id())?;
        lock.file.sync_data()?;
        Ok(Ok(lock))
    }

    /// The pid of the process, no longer running, whose lock file this lock took over.
    pub fn taken_over(&self) -> Option<u32> {
        self.taken_over
    }
}

impl Drop for WriterLock {
    fn drop(&mut self) {
        LOCKS
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|p| p != &self.path);
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Whether process `pid` runs (Linux: `/proc/PID` exists; elsewhere assume it does, so
/// nothing of a running process is ever removed).
fn process_alive(pid: u32) -> bool {
    if Path::new("/proc/self").exists() {
        Path::new(&format!("/proc/{pid}")).exists()
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_new_never_overwrites_and_one_racer_wins() {
        let dir = std::env::temp_dir().join(format!("arbvis-png-new-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let taken = dir.join("a.png");
        std::fs::write(&taken, b"first").unwrap();
        let e = write_new(&taken, b"second").unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::AlreadyExists);
        assert_eq!(std::fs::read(&taken).unwrap(), b"first");
        // Eight threads race for each of 20 names: each name goes to exactly one of
        // them, whole.
        for round in 0..20 {
            let path = dir.join(format!("race-{round}.png"));
            let wins: usize = std::thread::scope(|s| {
                let handles: Vec<_> = (0..8u8)
                    .map(|t| {
                        let path = path.clone();
                        s.spawn(move || write_new(&path, &[t; 4096]).is_ok() as usize)
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap()).sum()
            });
            assert_eq!(wins, 1, "round {round}");
            let bytes = std::fs::read(&path).unwrap();
            assert_eq!(bytes.len(), 4096);
            assert!(bytes.iter().all(|&b| b == bytes[0]), "one writer's bytes");
        }
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 21, "no temporaries left: {names:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = std::env::temp_dir().join(format!("arbvis-png-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A pid that cannot run: above Linux's pid_max limit (2^22).
        let dead = dir.join(format!(".out.csv{TMP_MARK}{}", (1u32 << 22) + 7));
        let other = dir.join(format!(".other.csv{TMP_MARK}{}", (1u32 << 22) + 7));
        std::fs::write(&dead, b"half").unwrap();
        std::fs::write(&other, b"half").unwrap();
        write_atomic(&dir.join("out.csv"), b"a,b\n").unwrap();
        assert!(!dead.exists(), "the stale temporary of out.csv is removed");
        assert!(other.exists(), "another file's temporary is left alone");
        assert_eq!(std::fs::read(dir.join("out.csv")).unwrap(), b"a,b\n");
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with(".out.csv"))
            .collect();
        assert!(leftovers.is_empty());
    }

    #[test]
    fn an_interrupt_removes_the_temporaries_in_progress() {
        let dir = std::env::temp_dir().join(format!("arbvis-png-int-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tmp = dir.join(format!(".x.png{TMP_MARK}{}", std::process::id()));
        std::fs::write(&tmp, b"half a png").unwrap();
        lock_temporaries().push(tmp.clone());
        remove_temporaries(); // what the SIGINT/SIGTERM handler runs before exiting
        assert!(!tmp.exists());
    }

    #[test]
    fn long_and_non_latin_texts_survive() {
        let dir = std::env::temp_dir().join(format!("arbvis-png-text-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        let image = Image::filled(2, 2, TargetFormat::Rgba8, [0.5; 4]);
        let long = "x = 1\n".repeat(100_000);
        write_png(
            &path,
            &image,
            &[
                ("arbvis:scene", long.clone()),
                ("path", "données/σ.sgy".into()),
            ],
        )
        .unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        assert!(
            size < 20_000,
            "600 kB of scene compressed and capped: {size} bytes"
        );
        let (_, text) = read_png(&path).unwrap();
        let scene = &text.iter().find(|(k, _)| k == "arbvis:scene").unwrap().1;
        assert!(scene.len() < long.len() && scene.contains("cut: 262144 of 600000"));
        assert!(text.contains(&("path".into(), "données/σ.sgy".into())));
    }
}
