//! The fuzz harness: every loader and the scene parser, fed mutated copies of a corpus
//! (the real files in ../shared/data and fixtures generated here), must return a value or
//! an error: no panic, no allocation beyond a cap, no case slower than a bound.
//!
//! `cargo test --test fuzz` runs a fixed number of cases per target (deterministic: case
//! `N` of a target is always the same input). For a longer run:
//!
//! ```sh
//! ARBVIS_FUZZ_SECONDS=600 cargo test --release --test fuzz -- --nocapture
//! ```
//!
//! spreads the time over the targets with fresh seeds and prints the cases per target.
//! `ARBVIS_FUZZ_TARGETS=points-las,surface-stl` runs only the targets named (a comma list
//! of names or prefixes: `points` runs every cloud target), in a plain run too.
//! `ARBVIS_FUZZ_VERBOSE=1` prints each case before running it (to find the one that
//! aborts), and `ARBVIS_FUZZ_CASE=TARGET:SEED:INDEX` replays one case.
//!
//! Allocation: a counting global allocator refuses any single allocation above
//! [`ALLOCATION_CAP`] while a case runs, so a loader that sizes memory from a header
//! without checking it against the input fails here (a `try_reserve` sees an error; an
//! infallible allocation aborts the test with "memory allocation of N bytes failed"). The
//! memory budget (`arbvis::budget`) is set to the same cap, so a loader that checks its
//! estimate refuses before it asks.

mod common;
#[path = "../src/mesh/tests/fixtures.rs"]
mod mesh_fixtures;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use arbvis::colortable::ColorTable;
use arbvis::scene::Scene;
use arbvis::volume::{nifti_file, segy, Limits, Volume};

/// Largest single allocation while a case runs. The biggest legitimate one is a decoded
/// volume: at most the corpus's f32 copy of its largest file (ICBM152, 35 MB).
const ALLOCATION_CAP: usize = 256 << 20;

/// Slowest case allowed (the debug-profile build; real inputs parse in milliseconds).
const CASE_TIME: Duration = Duration::from_secs(5);

/// Cases per target in a plain `cargo test`.
const DEFAULT_CASES: usize = 300;

struct Capped;

static PEAK_REQUEST: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static CAPPING: Cell<bool> = const { Cell::new(false) };
}

// SAFETY: forwards to the system allocator; only refuses (returns null) large requests
// while the current thread runs a fuzz case.
unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if CAPPING.try_with(Cell::get).unwrap_or(false) {
            PEAK_REQUEST.fetch_max(layout.size(), Ordering::Relaxed);
            if layout.size() > ALLOCATION_CAP {
                return std::ptr::null_mut();
            }
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if CAPPING.try_with(Cell::get).unwrap_or(false) {
            PEAK_REQUEST.fetch_max(new_size, Ordering::Relaxed);
            if new_size > ALLOCATION_CAP {
                return std::ptr::null_mut();
            }
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Capped = Capped;

/// SplitMix64: the mutations must not change with a random-number crate's version.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that break size arithmetic, written into binary inputs.
const INTERESTING: &[u64] = &[
    0,
    1,
    0x7f,
    0x80,
    0xff,
    0x7fff,
    0x8000,
    0xffff,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    1 << 40,
    u64::MAX,
];

/// Numbers that break parsers and size checks, written into text inputs.
const INTERESTING_TEXT: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "4294967296",
    "18446744073709551616",
    "9223372036854775807",
    "1e-300",
    "0.5",
    "\"x\"",
    "[]",
];

/// One mutation of `input`.
fn mutate(input: &[u8], rng: &mut Rng, text: bool) -> Vec<u8> {
    let mut out = input.to_vec();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        let at = rng.below(out.len() + 1);
        match rng.below(if text { 8 } else { 7 }) {
            0 if !out.is_empty() => {
                let i = at.min(out.len() - 1);
                out[i] ^= 1 << rng.below(8);
            }
            1 if !out.is_empty() => {
                let i = at.min(out.len() - 1);
                out[i] = [0, 0xff, 0x7f, 0x80, b'\n', b'9'][rng.below(6)];
            }
            2 => {
                let v = INTERESTING[rng.below(INTERESTING.len())];
                let width = [1, 2, 4, 8][rng.below(4)];
                let bytes = if rng.below(2) == 0 {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                };
                let start = at.min(out.len().saturating_sub(width));
                for (k, b) in bytes.iter().take(width).enumerate() {
                    if let Some(o) = out.get_mut(start + k) {
                        *o = *b;
                    }
                }
            }
            3 => out.truncate(at),
            4 => {
                let n = rng.below(16);
                let junk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                out.splice(at..at, junk);
            }
            5 if !out.is_empty() => {
                let len = rng.below(64).min(out.len() - at.min(out.len()));
                let chunk = out[at.min(out.len())..at.min(out.len()) + len].to_vec();
                let to = rng.below(out.len() + 1);
                out.splice(to..to, chunk);
            }
            6 if !out.is_empty() => {
                let end = (at + rng.below(64)).min(out.len());
                out.drain(at.min(end)..end);
            }
            7 => {
                // Text: replace a number (or any word) with an interesting one.
                let s = String::from_utf8_lossy(&out).to_string();
                let starts: Vec<usize> = s
                    .char_indices()
                    .filter(|(i, c)| {
                        (c.is_ascii_digit() || *c == '"')
                            && s[..*i]
                                .chars()
                                .last()
                                .is_none_or(|p| !p.is_ascii_alphanumeric())
                    })
                    .map(|(i, _)| i)
                    .collect();
                if !starts.is_empty() {
                    let i = starts[rng.below(starts.len())];
                    let end = s[i..]
                        .find(|c: char| c.is_whitespace() || c == ',' || c == ']' || c == '}')
                        .map_or(s.len(), |e| i + e);
                    let word = INTERESTING_TEXT[rng.below(INTERESTING_TEXT.len())];
                    out = format!("{}{}{}", &s[..i], word, &s[end..]).into_bytes();
                }
            }
            _ => {}
        }
    }
    out
}

/// A fuzz target: a name, whether its inputs are text, its corpus and the call.
struct Target {
    name: &'static str,
    text: bool,
    corpus: Vec<Vec<u8>>,
    run: fn(&[u8]),
}

/// Limits small enough that a mutated header cannot make a case slow: 2^22 voxels.
fn fuzz_limits() -> Limits {
    Limits {
        max_side: 4096,
        max_voxels: 1 << 22,
    }
}

fn segy_corpus() -> Vec<Vec<u8>> {
    let mut corpus = Vec::new();
    for name in ["f3.sgy", "small.sgy", "tiny.sgy", "broken.sgy"] {
        if let Some(p) = common::shared_data(&format!("seismic/{name}")) {
            corpus.push(std::fs::read(p).unwrap());
        }
    }
    let v = Volume::new([6, 3, 2], [1.0; 3], (0..36).map(|n| n as f32).collect()).unwrap();
    for code in [1, 3, 5, 16] {
        let o = segy::WriteOptions {
            format: segy::SampleFormat::from_code(code).unwrap(),
            big_endian: code != 5,
            revision: 2,
            first_inline: 10,
            first_crossline: 20,
            interval_us: 4000,
        };
        corpus.push(segy::write(&v, &o));
    }
    corpus
}

fn nifti_corpus() -> Vec<Vec<u8>> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3i16, 5, 4, 3, 1, 1, 1, 1].iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&4i16.to_le_bytes());
    h[72..74].copy_from_slice(&16i16.to_le_bytes());
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[112..116].copy_from_slice(&1.5f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend((0..60u16).flat_map(|v| (v * 7).to_le_bytes()));
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut gz, &h).unwrap();
    vec![h, gz.finish().unwrap()]
}

fn scene_corpus() -> Vec<Vec<u8>> {
    let mut corpus: Vec<Vec<u8>> = arbvis::scene::DEMOS
        .iter()
        .map(|(_, t)| t.as_bytes().to_vec())
        .collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data");
    for entry in std::fs::read_dir(root).unwrap().flatten() {
        corpus.push(std::fs::read(entry.path()).unwrap());
    }
    corpus.push(
        b"[technique.opacity3d.primary]\nvolume = { raw = { path = \"v.raw\", dims = [4, 4, 4], type = \"f64\", offset = 8 } }\n[technique.opacity3d]\nslices = 3\n"
            .to_vec(),
    );
    corpus
}

fn mesh_corpus() -> Vec<Vec<u8>> {
    let mut corpus: Vec<Vec<u8>> = mesh_fixtures::all_fixtures()
        .into_iter()
        .map(|(_, b)| b)
        .collect();
    for name in ["tetraMesh.vtk", "Tetrahedron.vtu"] {
        if let Some(p) = common::shared_data(&format!("tets/{name}")) {
            corpus.push(std::fs::read(p).unwrap());
        }
    }
    corpus
}

fn dat_corpus() -> Vec<Vec<u8>> {
    use arbvis::points::{dat, section};
    let cloud = section::generate(&section::SectionSpec {
        points: 40,
        seed: 3,
    })
    .unwrap();
    let text = dat::write(&cloud, &dat::DatColumns::default()).unwrap();
    vec![format!("# a comment\n{text}").into_bytes()]
}

fn las_corpus() -> Vec<Vec<u8>> {
    use las::{Builder, Point, Writer};
    let mut corpus = Vec::new();
    for (format, compressed) in [(3, false), (1, true), (6, false)] {
        let mut b = Builder::from((1, if format >= 6 { 4 } else { 2 }));
        b.point_format = las::point::Format::new(format).unwrap();
        b.point_format.is_compressed = compressed;
        let t = |offset: f64| las::Transform {
            scale: 0.001,
            offset,
        };
        b.transforms = las::Vector {
            x: t(500_000.0),
            y: t(4_000_000.0),
            z: t(0.0),
        };
        let mut w =
            Writer::new(std::io::Cursor::new(Vec::new()), b.into_header().unwrap()).unwrap();
        for i in 0..20 {
            let f = i as f64;
            let mut p = Point {
                x: 500_000.0 + 1.25 * f,
                y: 4_000_000.0 - 0.5 * f * f,
                z: 12.0 + f,
                intensity: 100 * i,
                ..Default::default()
            };
            if w.header().point_format().has_color {
                p.color = Some(las::Color::new(i * 300, 65535 - i, 7));
            }
            if w.header().point_format().has_gps_time {
                p.gps_time = Some(f);
            }
            w.write_point(p).unwrap();
        }
        w.close().unwrap();
        corpus.push(w.into_inner().unwrap().into_inner());
    }
    corpus
}

fn ply_corpus() -> Vec<Vec<u8>> {
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\ncomment fuzz\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let ascii = header("ascii") + "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1.5 0.25 0 0 255\n3 0 1 2\n";
    let mut binary = header("binary_little_endian").into_bytes();
    for (x, y, z, c) in [
        (0f32, 0f32, 0f32, 255u8),
        (1.0, 0.0, 0.0, 9),
        (0.0, 1.5, 0.25, 70),
    ] {
        for v in [x, y, z] {
            binary.extend(v.to_le_bytes());
        }
        binary.extend([c, 0, 255 - c]);
    }
    binary.push(3);
    for i in [0i32, 1, 2] {
        binary.extend(i.to_le_bytes());
    }
    vec![ascii.into_bytes(), binary]
}

fn obj_corpus() -> Vec<Vec<u8>> {
    let mut corpus = vec![b"# a cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n".to_vec()];
    if let Some(p) = common::shared_data("surfaces/cow.obj") {
        corpus.push(std::fs::read(p).unwrap());
    }
    corpus
}

fn stl_corpus() -> Vec<Vec<u8>> {
    let tris: [[[f32; 3]; 3]; 4] = [
        [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    ];
    let mut binary = vec![b' '; 80];
    binary.extend((tris.len() as u32).to_le_bytes());
    let mut ascii = String::from("solid tet\n");
    for t in &tris {
        binary.extend([0u8; 12]);
        ascii += " facet normal 0 0 0\n  outer loop\n";
        for v in t {
            for c in v {
                binary.extend(c.to_le_bytes());
            }
            ascii += &format!("   vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        binary.extend([0u8; 2]);
        ascii += "  endloop\n endfacet\n";
    }
    ascii += "endsolid tet\n";
    vec![binary, ascii.into_bytes()]
}

fn targets() -> Vec<Target> {
    vec![
        Target {
            name: "segy",
            text: false,
            corpus: segy_corpus(),
            run: |b| {
                let options = segy::ReadOptions {
                    limits: fuzz_limits(),
                    ..Default::default()
                };
                let _ = segy::parse(Path::new("fuzz.sgy"), b, &options);
            },
        },
        Target {
            name: "nifti",
            text: false,
            corpus: nifti_corpus(),
            run: |b| {
                let _ = nifti_file::parse(Path::new("fuzz.nii"), b, &fuzz_limits());
            },
        },
        Target {
            name: "scene",
            text: true,
            corpus: scene_corpus(),
            run: |b| {
                let text = String::from_utf8_lossy(b);
                if let Ok(scene) = Scene::parse(&text, "fuzz.toml") {
                    // Generated volumes are made from scene numbers alone: make them too.
                    if let arbvis::scene::TechniqueScene::Opacity3d(o) = &scene.technique {
                        for a in o.attributes().into_iter().flatten() {
                            if let arbvis::volume::VolumeSource::Synthetic(_) = a.volume {
                                let _ = a.volume.load(Path::new("."), &fuzz_limits());
                            }
                        }
                    }
                    let _ = Scene::parse(&scene.to_toml(), "again.toml");
                }
            },
        },
        Target {
            name: "mesh",
            text: false,
            corpus: mesh_corpus(),
            run: |b| {
                let _ = arbvis::mesh::parse(Path::new("fuzz.mesh"), b);
            },
        },
        Target {
            name: "points-dat",
            text: true,
            corpus: dat_corpus(),
            run: |b| {
                let columns = arbvis::points::dat::DatColumns::default();
                let _ = arbvis::points::dat::parse(Path::new("fuzz.dat"), b, &columns);
            },
        },
        Target {
            name: "points-las",
            text: false,
            corpus: las_corpus(),
            run: |b| {
                let _ = arbvis::points::lasfile::parse(Path::new("fuzz.laz"), b);
            },
        },
        Target {
            name: "points-ply",
            text: false,
            corpus: ply_corpus(),
            run: |b| {
                let _ = arbvis::points::plycloud::parse(Path::new("fuzz.ply"), b);
            },
        },
        Target {
            name: "surface-obj",
            text: true,
            corpus: obj_corpus(),
            run: |b| surface(b, "fuzz.obj"),
        },
        Target {
            name: "surface-stl",
            text: false,
            corpus: stl_corpus(),
            run: |b| surface(b, "fuzz.stl"),
        },
        Target {
            name: "surface-ply",
            text: false,
            corpus: ply_corpus(),
            run: |b| surface(b, "fuzz.ply"),
        },
        Target {
            name: "points-laz",
            text: false,
            corpus: laz_corpus(),
            run: |b| {
                let _ = arbvis::points::lasfile::parse(Path::new("fuzz.laz"), b);
            },
        },
        Target {
            name: "table",
            text: true,
            corpus: vec![ColorTable::builtin("viridis")
                .unwrap()
                .to_text()
                .into_bytes()],
            run: |b| {
                let _ = ColorTable::parse(&String::from_utf8_lossy(b), "fuzz.table");
            },
        },
    ]
}

/// Run case `index` of `target` with `seed`; panics with the case's name on failure.
fn run_case(target: &Target, seed: u64, index: usize) {
    let mut rng = Rng(seed ^ (index as u64).wrapping_mul(0x2545_F491_4F6C_DD1D));
    let base = &target.corpus[rng.below(target.corpus.len())];
    let input = mutate(base, &mut rng, target.text);
    let case = format!("{}:{seed}:{index}", target.name);
    if std::env::var_os("ARBVIS_FUZZ_VERBOSE").is_some() {
        eprintln!("case {case} ({} bytes)", input.len());
    }
    PEAK_REQUEST.store(0, Ordering::Relaxed);
    let t0 = Instant::now();
    CAPPING.with(|c| c.set(true));
    let outcome = std::panic::catch_unwind(|| (target.run)(&input));
    CAPPING.with(|c| c.set(false));
    let elapsed = t0.elapsed();
    if let Err(panic) = outcome {
        let what = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        panic!("case {case} panicked: {what}; replay with ARBVIS_FUZZ_CASE={case}");
    }
    assert!(
        elapsed < CASE_TIME,
        "case {case} took {elapsed:?} (bound {CASE_TIME:?}); replay with ARBVIS_FUZZ_CASE={case}"
    );
    let peak = PEAK_REQUEST.load(Ordering::Relaxed);
    assert!(
        peak <= ALLOCATION_CAP,
        "case {case} asked for {peak} bytes at once; replay with ARBVIS_FUZZ_CASE={case}"
    );
}

#[test]
fn loaders_and_scenes_survive_mutated_inputs() {
    // Panics are expected and caught: keep their messages off the output.
    let hook = std::panic::take_hook();
    if std::env::var_os("ARBVIS_FUZZ_CASE").is_none() {
        std::panic::set_hook(Box::new(|_| {}));
    }
    arbvis::budget::set(ALLOCATION_CAP as u64);
    let targets = selected(targets());
    let result = std::panic::catch_unwind(|| {
        if let Ok(case) = std::env::var("ARBVIS_FUZZ_CASE") {
            let mut parts = case.split(':');
            let (name, seed, index) = (parts.next(), parts.next(), parts.next());
            let target = targets
                .iter()
                .find(|t| Some(t.name) == name)
                .expect("target");
            run_case(
                target,
                seed.and_then(|s| s.parse().ok()).expect("seed"),
                index.and_then(|s| s.parse().ok()).expect("index"),
            );
            return;
        }
        let seconds: Option<u64> = std::env::var("ARBVIS_FUZZ_SECONDS")
            .ok()
            .and_then(|s| s.parse().ok());
        match seconds {
            None => {
                for t in &targets {
                    for index in 0..DEFAULT_CASES {
                        run_case(t, 1, index);
                    }
                }
            }
            Some(s) => {
                let seed = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(2, |d| d.as_secs());
                let budget = Duration::from_secs(s) / targets.len() as u32;
                for t in &targets {
                    let t0 = Instant::now();
                    let mut index = 0;
                    while t0.elapsed() < budget {
                        run_case(t, seed, index);
                        index += 1;
                    }
                    println!("fuzz {}: {index} cases, seed {seed}", t.name);
                }
            }
        }
    });
    std::panic::set_hook(hook);
    if let Err(e) = result {
        let message = e
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        panic!("{message}");
    }
}

/// The targets `ARBVIS_FUZZ_TARGETS` names (all when it is not set).
fn selected(targets: Vec<Target>) -> Vec<Target> {
    let Ok(list) = std::env::var("ARBVIS_FUZZ_TARGETS") else {
        return targets;
    };
    let wanted: Vec<&str> = list
        .split(',')
        .map(str::trim)
        .filter(|w| !w.is_empty())
        .collect();
    let chosen: Vec<Target> = targets
        .into_iter()
        .filter(|t| wanted.iter().any(|w| t.name.starts_with(w)))
        .collect();
    assert!(
        !chosen.is_empty(),
        "ARBVIS_FUZZ_TARGETS={list:?} names no target"
    );
    chosen
}

#[test]
fn the_mutator_changes_inputs_and_is_deterministic() {
    let base = b"size = [64, 64]\nslices = 128\n".to_vec();
    let a: Vec<Vec<u8>> = (0..50).map(|i| mutate(&base, &mut Rng(i), true)).collect();
    let b: Vec<Vec<u8>> = (0..50).map(|i| mutate(&base, &mut Rng(i), true)).collect();
    assert_eq!(a, b);
    assert!(a.iter().filter(|m| **m != base).count() > 40);
}

// --- issue 17: clouds and surfaces ---

/// A surface target: parse, then inspect what parsed (edges, volume, the bounded
/// self-intersection search), as `arbvis inspect` does.
fn surface(bytes: &[u8], name: &str) {
    if let Ok(mesh) = arbvis::surface::parse(Path::new(name), bytes) {
        let _ = arbvis::surface::inspect(&mesh);
    }
}

/// LAZ and LAS 1.4 files for `points-laz`: compressed 1.2 and 1.4, with and without
/// extra bytes, and a stream of equal points (85 a compressed byte).
fn laz_corpus() -> Vec<Vec<u8>> {
    vec![
        common::hostile_files::las14(30, 3, true),
        common::hostile_files::las14(12, 0, true),
        common::hostile_files::las14(9, 2, false),
        common::hostile_files::equal_points_laz(2_000),
    ]
}

/// Run `f` as a fuzz case runs (allocation cap, time bound), naming `what` on failure.
fn reproduce<T>(what: &str, f: impl FnOnce() -> T) -> Result<T, String> {
    PEAK_REQUEST.store(0, Ordering::Relaxed);
    let t0 = Instant::now();
    CAPPING.with(|c| c.set(true));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    CAPPING.with(|c| c.set(false));
    let (elapsed, peak) = (t0.elapsed(), PEAK_REQUEST.load(Ordering::Relaxed));
    let value = outcome.map_err(|_| format!("{what}: panicked"))?;
    if elapsed >= CASE_TIME {
        return Err(format!("{what}: took {elapsed:?} (bound {CASE_TIME:?})"));
    }
    if peak > ALLOCATION_CAP {
        return Err(format!("{what}: asked for {peak} bytes at once"));
    }
    Ok(value)
}

/// `result` must be an error whose message contains every one of `parts`.
fn refused<T, E: std::fmt::Display>(
    what: &str,
    result: Result<T, E>,
    parts: &[&str],
) -> Result<(), String> {
    let message = match result {
        Ok(_) => return Err(format!("{what}: accepted")),
        Err(e) => e.to_string(),
    };
    match parts.iter().find(|p| !message.contains(*p)) {
        Some(p) => Err(format!("{what}: expected {p:?} in: {message}")),
        None => Ok(()),
    }
}

/// Each class of issue 17 that clouds and surfaces had, as a fixed case under the fuzz
/// harness's bounds. (A `Result`, not panics: the fuzz test silences the panic hook.)
#[test]
fn issue_17_cloud_and_surface_reproducers() -> Result<(), String> {
    use arbvis::points::{lasfile, plycloud};
    use arbvis::surface;
    use common::hostile_files::*;
    arbvis::budget::set(ALLOCATION_CAP as u64);
    // Amplification: an OBJ face of 1.6 million corners (3.2 MB of text) is estimated at
    // about 330 MB while read: over the 256 MiB budget, refused at the face's line.
    let fan = format!(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf {}\n",
        "1 2 3 ".repeat(540_000)
    );
    let r = reproduce("big face", || {
        surface::parse(Path::new("f.obj"), fan.as_bytes())
    })?;
    refused(
        "big face",
        r,
        &[
            "f.obj: line 4, column 1: reading 3 vertices and 1 faces of 1620000 corners",
            "memory budget",
        ],
    )?;
    // Time: a small LAZ whose 250,000 points carry 120 extra bytes (a third of a point
    // each): past the LAZ bound.
    let extras = las14(250_000, 120, true);
    if extras.len() > 1 << 20 {
        return Err(format!("the extra-bytes LAZ is {} bytes", extras.len()));
    }
    let r = reproduce("extra bytes LAZ", || {
        lasfile::parse(Path::new("x.laz"), &extras)
    })?;
    refused(
        "extra bytes LAZ",
        r,
        &["x.laz: at byte 107: the header declares 250000 points with 120 extra-bytes attributes"],
    )?;
    // Time: equal points past 1,000,000 + 1 a compressed byte.
    let dense = equal_points_laz(1_200_000);
    let r = reproduce("dense LAZ", || lasfile::parse(Path::new("d.laz"), &dense))?;
    refused(
        "dense LAZ",
        r,
        &["d.laz: at byte 107: the header declares 1200000 points"],
    )?;
    // Time: 2,400 copies of one face (2.9 million pairs, each tested): the search stops.
    let copies = binary_stl(&face_copies(2_400));
    let report = reproduce("face copies", || {
        surface::parse(Path::new("c.stl"), &copies).map(|m| surface::inspect(&m))
    })?
    .map_err(|e| e.to_string())?;
    if report.self_intersection_search_complete
        || report.self_intersection_work > surface::topology::MAX_WORK + 64
    {
        return Err(format!("face copies: {report}"));
    }
    // Time: one ASCII STL line of 12,000 facets (1 MB), linear.
    let line = one_line_ascii_stl(12_000);
    let mesh = reproduce("one long line", || {
        surface::parse(Path::new("l.stl"), line.as_bytes())
    })?
    .map_err(|e| e.to_string())?;
    if mesh.triangles.len() != 12_000 {
        return Err(format!("one long line: {} triangles", mesh.triangles.len()));
    }
    // Messages: a two-corner OBJ face among good ones; a LAS version; a 2^63 count; a
    // PLY coordinate declared as a list.
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n";
    let r = reproduce("two corners", || surface::parse(Path::new("t.obj"), obj))?;
    refused(
        "two corners",
        r,
        &["t.obj: line 5, column 1: a face with 2 corners"],
    )?;
    let mut las = las14(4, 0, false);
    las[25] = 7;
    let r = reproduce("LAS version", || lasfile::parse(Path::new("v.las"), &las))?;
    refused("LAS version", r, &["v.las: at byte 24: LAS version 1.7"])?;
    let mut las = las14(4, 0, false);
    set(&mut las, 107, &0u32.to_le_bytes());
    set(&mut las, 247, &(1u64 << 63).to_le_bytes());
    let r = reproduce("2^63 points", || lasfile::parse(Path::new("n.las"), &las))?;
    refused(
        "2^63 points",
        r,
        &["n.las: at byte 247: the header declares 9223372036854775808"],
    )?;
    let ply = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n1 0 0 0\n";
    let r = reproduce("list coordinate", || {
        plycloud::parse(Path::new("l.ply"), ply)
    })?;
    refused(
        "list coordinate",
        r,
        &["l.ply: line 4, column 27: vertex property \"x\""],
    )?;
    // Extreme numbers: a cloud at ±1.7e308 is stored in [-1, 1]³, finite.
    let ply = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n1.7e308 -1.7e308 0\n-1.7e308 1.7e308 1\n";
    let cloud = reproduce("huge cloud", || plycloud::parse(Path::new("h.ply"), ply))?
        .map_err(|e| e.to_string())?
        .cloud;
    if !cloud.positions.iter().flatten().all(|v| v.abs() <= 1.0) {
        return Err(format!("huge cloud: {:?}", cloud.positions));
    }
    Ok(())
}
