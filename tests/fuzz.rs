//! The fuzz harness: every loader and the scene parser, fed mutated copies of a corpus
//! (the real files in data/ and fixtures generated here), must return a value or
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
//! `ARBVIS_FUZZ_TARGETS=mesh,scene` runs only the named targets (a name also selects the
//! targets it prefixes: `mesh` is `mesh-legacy`, `mesh-vtu` and `mesh-gmsh`).
//!
//! Allocation: a counting global allocator refuses any single allocation above
//! [`ALLOCATION_CAP`], and any allocation that would make the bytes a case holds at once
//! exceed [`LIVE_CAP`], while a case runs, so a loader that sizes memory from a header
//! without checking it against the input, or that amplifies a small input by many
//! medium allocations, fails here (a `try_reserve` sees an error; an infallible
//! allocation aborts the test with "memory allocation of N bytes failed"). The memory
//! budget (`arbvis::budget`) is set to [`FUZZ_BUDGET`] so that loaders refuse first.

#[path = "it/common/mod.rs"]
mod common;
#[path = "../crates/arbvis-data/src/mesh/tests/fixtures.rs"]
mod mesh_fixtures;
#[path = "../crates/arbvis-data/src/mesh/tests/hostile_files.rs"]
mod mesh_hostile;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;
use std::time::{Duration, Instant};

use arbvis::colortable::ColorTable;
use arbvis::scene::Scene;
use arbvis::volume::{nifti_file, segy, Limits, Volume};

/// Largest single allocation while a case runs. The biggest legitimate one is a decoded
/// volume: at most the corpus's f32 copy of its largest file (ICBM152, 35 MB).
const ALLOCATION_CAP: usize = 256 << 20;

/// Most bytes a case may hold at once (allocated and not yet freed, on its thread): four
/// allocations at [`ALLOCATION_CAP`].
const LIVE_CAP: usize = 1 << 30;

/// The memory budget loaders are held to while fuzzing: each of their checked
/// allocations (or groups) must fit [`ALLOCATION_CAP`], so a refusal comes from the
/// loader, with its message, before the allocator refuses.
const FUZZ_BUDGET: u64 = 256 << 20;

/// Slowest case allowed (the debug-profile build; real inputs parse in milliseconds).
const CASE_TIME: Duration = Duration::from_secs(5);

/// Cases per target in a plain `cargo test`.
const DEFAULT_CASES: usize = 300;

struct Capped;

thread_local! {
    static CAPPING: Cell<bool> = const { Cell::new(false) };
    /// Largest single request of the running case.
    static PEAK_REQUEST: Cell<usize> = const { Cell::new(0) };
    /// Bytes the running case holds (what it allocated minus what it freed).
    static LIVE: Cell<isize> = const { Cell::new(0) };
    /// The most it held at once.
    static PEAK_LIVE: Cell<isize> = const { Cell::new(0) };
}

fn capping() -> bool {
    CAPPING.try_with(Cell::get).unwrap_or(false)
}

/// Account for `grow` more bytes (negative: freed) in a request of `size`; false when
/// the request must be refused (and then nothing is counted).
fn admit(size: usize, grow: isize) -> bool {
    let _ = PEAK_REQUEST.try_with(|p| p.set(p.get().max(size)));
    let live = LIVE.try_with(Cell::get).unwrap_or(0) + grow;
    if size > ALLOCATION_CAP || (grow > 0 && live > LIVE_CAP as isize) {
        return false;
    }
    let _ = LIVE.try_with(|l| l.set(live));
    let _ = PEAK_LIVE.try_with(|p| p.set(p.get().max(live)));
    true
}

// SAFETY: forwards to the system allocator; only refuses (returns null) requests over
// the caps while the current thread runs a fuzz case.
unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if capping() && !admit(layout.size(), layout.size() as isize) {
            return std::ptr::null_mut();
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if capping() {
            let _ = LIVE.try_with(|l| l.set(l.get() - layout.size() as isize));
        }
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let grow = new_size as isize - layout.size() as isize;
        if capping() && !admit(new_size, grow) {
            return std::ptr::null_mut();
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

/// A fuzz target: a name, whether its inputs are text, whether cases also move whole
/// sections (mesh formats), its corpus and the call.
struct Target {
    name: &'static str,
    text: bool,
    sections: bool,
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
        corpus.push(std::fs::read(common::data_file(&format!("seismic/{name}"))).unwrap());
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
    let mut corpus: Vec<Vec<u8>> = arbvis::scene::demos()
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

/// The mesh fixtures and real files whose name ends in `.{ext}`.
fn mesh_corpus(ext: &str) -> Vec<Vec<u8>> {
    let suffix = format!(".{ext}");
    let mut corpus: Vec<Vec<u8>> = mesh_fixtures::all_fixtures()
        .into_iter()
        .filter(|(name, _)| name.ends_with(&suffix))
        .map(|(_, b)| b)
        .collect();
    for name in [
        "tetraMesh.vtk",
        "Tetrahedron.vtu",
        "bracket-2.2.msh",
        "bracket-4.1-binary.msh",
    ] {
        if !name.ends_with(&suffix) {
            continue;
        }
        corpus.push(std::fs::read(common::data_file(&format!("tets/{name}"))).unwrap());
    }
    corpus
}

/// `input` with one of its sections (see `mesh_fixtures::sections`: gmsh `$Name` blocks,
/// XML elements, legacy keyword sections) moved before another, repeated there, or
/// swapped with it.
fn reorder(input: &[u8], rng: &mut Rng) -> Vec<u8> {
    let blocks = mesh_fixtures::sections(input);
    if blocks.len() < 2 {
        return input.to_vec();
    }
    let (a0, a1) = blocks[rng.below(blocks.len())];
    let (b0, b1) = blocks[rng.below(blocks.len())];
    let block = &input[a0..a1];
    match rng.below(3) {
        // Move block a to where block b starts.
        0 if b0 <= a0 || b0 >= a1 => {
            let mut out: Vec<u8> = [&input[..a0], &input[a1..]].concat();
            let to = if b0 >= a1 { b0 - (a1 - a0) } else { b0 };
            out.splice(to..to, block.iter().copied());
            out
        }
        // Swap two blocks that do not overlap.
        1 if a1 <= b0 || b1 <= a0 => {
            let ((x0, x1), (y0, y1)) = if a1 <= b0 {
                ((a0, a1), (b0, b1))
            } else {
                ((b0, b1), (a0, a1))
            };
            [
                &input[..x0],
                &input[y0..y1],
                &input[x1..y0],
                &input[x0..x1],
                &input[y1..],
            ]
            .concat()
        }
        // Repeat block a where block b starts.
        _ => {
            let mut out = input.to_vec();
            out.splice(b0..b0, block.iter().copied());
            out
        }
    }
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
    corpus.push(std::fs::read(common::data_file("surfaces/cow.obj")).unwrap());
    corpus
}

fn tsurf_corpus() -> Vec<Vec<u8>> {
    vec![
        b"GOCAD TSurf 1\nHEADER {\nname:top\n}\nZPOSITIVE Depth\nTFACE\nVRTX 1 0 0 10\nPVRTX 2 1 0 11 0.5\nVRTX 3 0 1 12\nATOM 4 2\nTRGL 1 2 3\nTFACE\nVRTX 5 1 1 9\nTRGL 3 4 5\nEND\nGOCAD TSurf 1\nVRTX 1 5 5 5\nVRTX 2 6 5 5\nVRTX 3 5 6 5\nTRGL 1 2 3\nEND\n"
            .to_vec(),
        // Properties: a scalar, a vector (ESIZES 3), no-data values, PATOM and ATOM.
        b"GOCAD TSurf 1\nPROPERTIES throw dir\nESIZES 1 3\nNO_DATA_VALUES -99999 -99999\nPVRTX 1 0 0 0 12.5 1 0 0\nPVRTX 2 1 0 0 -99999 0 1 0\nPVRTX 3 0 1 0 7 0 0 1\nPATOM 4 3 8 0 0 1\nATOM 5 2\nTRGL 1 2 3\nTRGL 2 4 5\nEND\n"
            .to_vec(),
    ]
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
            sections: false,
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
            sections: false,
            corpus: nifti_corpus(),
            run: |b| {
                let _ = nifti_file::parse(Path::new("fuzz.nii"), b, &fuzz_limits());
            },
        },
        Target {
            name: "scene",
            text: true,
            sections: false,
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
            name: "mesh-legacy",
            text: false,
            sections: true,
            corpus: mesh_corpus("vtk"),
            run: |b| {
                let _ = arbvis::mesh::parse(Path::new("fuzz.vtk"), b);
            },
        },
        Target {
            name: "mesh-vtu",
            text: false,
            sections: true,
            corpus: mesh_corpus("vtu"),
            run: |b| {
                let _ = arbvis::mesh::parse(Path::new("fuzz.vtu"), b);
            },
        },
        Target {
            name: "mesh-gmsh",
            text: false,
            sections: true,
            corpus: mesh_corpus("msh"),
            run: |b| {
                let _ = arbvis::mesh::parse(Path::new("fuzz.msh"), b);
            },
        },
        Target {
            name: "points-dat",
            text: true,
            sections: false,
            corpus: dat_corpus(),
            run: |b| {
                let columns = arbvis::points::dat::DatColumns::default();
                let _ = arbvis::points::dat::parse(Path::new("fuzz.dat"), b, &columns);
            },
        },
        Target {
            name: "points-las",
            text: false,
            sections: false,
            corpus: las_corpus(),
            run: |b| {
                let _ = arbvis::points::lasfile::parse(Path::new("fuzz.laz"), b);
            },
        },
        Target {
            name: "points-ply",
            text: false,
            sections: false,
            corpus: ply_corpus(),
            run: |b| {
                let _ = arbvis::points::plycloud::parse(Path::new("fuzz.ply"), b);
            },
        },
        Target {
            name: "surface-obj",
            text: true,
            sections: false,
            corpus: obj_corpus(),
            run: |b| surface(b, "fuzz.obj"),
        },
        Target {
            name: "surface-tsurf",
            text: true,
            sections: false,
            corpus: tsurf_corpus(),
            run: |b| surface(b, "fuzz.ts"),
        },
        Target {
            name: "surface-zmap",
            text: true,
            sections: false,
            corpus: vec![b"! exported\n@top, GRID, 4\n15, -99999.0, , 4, 1\n3, 4, 100.0, 130.0, 200.0, 220.0\n0.0, 0.0, 0.0\n@\n  -1.0  -2.0  -3.0  -4.0\n  -5.0  -6.0  -7.0 -99999.0\n  -9.0 -10.0 -11.0 -12.0\n".to_vec()],
            run: |b| surface(b, "fuzz.zmap"),
        },
        Target {
            name: "surface-xyz",
            text: true,
            sections: false,
            corpus: vec![
                b"\"X\"\t\"Y\"\t\"Inline\"\t\"Crossline\"\t\"Z (ms)\"\n0\t0\t1\t1\t5\n25\t0\t2\t1\t6\n0\t25\t1\t2\t1e30\n25\t25\t2\t2\t7\n".to_vec(),
                b"# x, y, z\n0, 0, 5\n25, 0, 6\n0, 25, nan\n25, 25, 7\n50, 10, 8\n".to_vec(),
            ],
            run: |b| surface(b, "fuzz.xyz"),
        },
        Target {
            name: "lines-polylines",
            text: true,
            sections: false,
            corpus: vec![b"x,y,z,value\n0,0,0,1\n10,0,-5,2\n\n3,3,3,nan\n4,4,4,5\n".to_vec()],
            run: |b| {
                let _ = arbvis::lines::parse_polylines(Path::new("fuzz.csv"), b);
            },
        },
        Target {
            name: "lines-well",
            text: true,
            sections: false,
            corpus: vec![b"MD,INC,AZI\n0,0,0\n60,0,0\n90,6,125\n240,36,125\n330,36,125\n".to_vec()],
            run: |b| {
                if let Ok(stations) = arbvis::lines::parse_survey(Path::new("fuzz.csv"), b) {
                    let well = arbvis::lines::Well::of(stations);
                    let _ = well.path([0.0, 0.0], 0.0, 2.0);
                }
                let _ = arbvis::lines::parse_log(Path::new("fuzz.csv"), b);
            },
        },
        Target {
            name: "surface-stl",
            text: false,
            sections: false,
            corpus: stl_corpus(),
            run: |b| surface(b, "fuzz.stl"),
        },
        Target {
            name: "surface-ply",
            text: false,
            sections: false,
            corpus: ply_corpus(),
            run: |b| surface(b, "fuzz.ply"),
        },
        Target {
            name: "points-laz",
            text: false,
            sections: false,
            corpus: laz_corpus(),
            run: |b| {
                let _ = arbvis::points::lasfile::parse(Path::new("fuzz.laz"), b);
            },
        },
        Target {
            name: "store-meta",
            text: true,
            sections: false,
            corpus: vec![template_file("zarr.json")],
            run: |b| store_case("zarr.json", b),
        },
        Target {
            name: "store-array",
            text: true,
            sections: false,
            corpus: vec![
                template_file("amplitude/zarr.json"),
                template_file("level_1/envelope_range/zarr.json"),
            ],
            run: |b| store_case("amplitude/zarr.json", b),
        },
        Target {
            name: "store-chunk",
            text: false,
            sections: false,
            corpus: vec![
                template_file("amplitude/c/0/0/0"),
                template_file("envelope/c/1/0/1"),
            ],
            run: |b| store_case("amplitude/c/0/0/0", b),
        },
        Target {
            name: "store-log",
            text: true,
            sections: false,
            corpus: vec![template_log()],
            run: log_case,
        },
        Target {
            name: "points-copc",
            text: false,
            sections: false,
            corpus: ["simple.copc.laz", "simple_with_page.copc.laz"]
                .iter()
                .map(|n| std::fs::read(common::data_file(&format!("points/{n}"))).unwrap())
                .collect(),
            run: copc_case,
        },
        Target {
            name: "table",
            text: true,
            sections: false,
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

// --- stores: a small converted survey whose files the store targets mutate ---

/// The template: a 9 x 7 x 5 survey in 4³ bricks with envelope (3 x 2 x 2 bricks, 2
/// levels), converted whole into `complete.zarr` and stopped after two columns into
/// `part.zarr`, made once (outside the caps) when the corpus is built.
fn store_template() -> &'static Path {
    static DIR: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        use arbvis::store::convert::{convert, ConvertOptions};
        let dir = std::env::temp_dir().join(format!("arbvis-fuzz-store-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let v = Volume::new(
            [9, 7, 5],
            [1.0; 3],
            (0..315).map(|n| ((n * 37) % 23) as f32 - 11.0).collect(),
        )
        .unwrap();
        let sgy = dir.join("s.sgy");
        let w = segy::WriteOptions {
            format: segy::SampleFormat::IeeeFloat,
            big_endian: true,
            revision: 1,
            first_inline: 1,
            first_crossline: 1,
            interval_us: 4000,
        };
        std::fs::write(&sgy, segy::write(&v, &w)).unwrap();
        let o = ConvertOptions {
            brick: 4,
            derived: vec![arbvis::volume::attributes::Attribute::Envelope],
            progress: false,
            ..Default::default()
        };
        convert(&sgy, &dir.join("complete.zarr"), &o).unwrap();
        let stop = ConvertOptions {
            stop_after: Some(2),
            ..o
        };
        assert!(convert(&sgy, &dir.join("part.zarr"), &stop).is_err());
        dir
    })
}

fn template_file(name: &str) -> Vec<u8> {
    std::fs::read(store_template().join("complete.zarr").join(name)).unwrap()
}

fn template_log() -> Vec<u8> {
    std::fs::read(
        store_template()
            .join("part.zarr")
            .join(arbvis::store::progress::PROGRESS_LOG),
    )
    .unwrap()
}

/// A COPC file of `bytes` opened (header, VLRs, root page), a view's nodes chosen (the
/// child pages it reaches read), every page and node read.
fn copc_case(bytes: &[u8]) {
    let path = std::env::temp_dir().join(format!(
        "arbvis-fuzz-copc-{}-{:?}.copc.laz",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::write(&path, bytes).unwrap();
    if let Ok(c) = arbvis::points::copc::Copc::open(&path) {
        // A view first (child pages read as it reaches them), then every page.
        let camera = arbvis::camera::Camera {
            zoom: 3.0,
            ..Default::default()
        };
        let view = arbvis::points::copc_lod::View::of(&camera, [640, 480]);
        let _ = arbvis::points::copc_lod::select(&c, &view, 500, 0.0);
        for node in c.all_nodes().unwrap_or_default().iter() {
            let _ = c.read_node(node);
        }
        let _ = c.describe();
    }
    let _ = std::fs::remove_file(&path);
}

/// Write `bytes` as `name` of the complete store, open it and read every range and chunk,
/// then put the file back.
fn store_case(name: &str, bytes: &[u8]) {
    let store = store_template().join("complete.zarr");
    let file = store.join(name);
    let original = std::fs::read(&file).unwrap();
    std::fs::write(&file, bytes).unwrap();
    if let Ok(s) = arbvis::store::Store::open(&store) {
        for a in 0..s.meta.attributes.len() {
            for level in 0..s.meta.levels {
                let _ = s.ranges(a, level);
                let c = s.meta.brick_counts(level);
                for k in 0..c[2] {
                    for j in 0..c[1] {
                        for i in 0..c[0] {
                            let _ = s.brick(a, level, [i, j, k]);
                        }
                    }
                }
            }
        }
        let _ = arbvis::store::describe::describe(&store);
    }
    std::fs::write(&file, original).unwrap();
}

/// Copy the interrupted conversion, give it `bytes` as its progress log, and resume it.
fn log_case(bytes: &[u8]) {
    use arbvis::store::convert::{convert, ConvertOptions};
    let from = store_template().join("part.zarr");
    let to = store_template().join("resumed.zarr");
    let _ = std::fs::remove_dir_all(&to);
    common::copy_tree(&from, &to);
    std::fs::write(to.join(arbvis::store::progress::PROGRESS_LOG), bytes).unwrap();
    let o = ConvertOptions {
        brick: 4,
        derived: vec![arbvis::volume::attributes::Attribute::Envelope],
        progress: false,
        ..Default::default()
    };
    if convert(&store_template().join("s.sgy"), &to, &o).is_ok() {
        // A resumed store is whole: every chunk reads.
        let s = arbvis::store::Store::open(&to).expect("a finished conversion opens");
        for a in 0..s.meta.attributes.len() {
            let c = s.meta.brick_counts(0);
            for i in 0..c[0] {
                s.chunk(a, 0, [i, 0, 0])
                    .expect("a resumed conversion wrote every chunk");
            }
        }
    }
}

/// What one capped run of an input did.
struct CaseRun {
    /// The panic's message, if it panicked.
    panic: Option<String>,
    elapsed: Duration,
    /// Largest single request.
    peak_request: usize,
    /// Most bytes held at once.
    peak_live: isize,
}

/// Run `f` under the caps (and the fuzz budget), catching a panic.
fn capped(f: impl FnOnce()) -> CaseRun {
    arbvis::budget::set(FUZZ_BUDGET);
    PEAK_REQUEST.with(|p| p.set(0));
    LIVE.with(|l| l.set(0));
    PEAK_LIVE.with(|p| p.set(0));
    let t0 = Instant::now();
    CAPPING.with(|c| c.set(true));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    CAPPING.with(|c| c.set(false));
    let elapsed = t0.elapsed();
    CaseRun {
        panic: outcome.err().map(|panic| {
            panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        }),
        elapsed,
        peak_request: PEAK_REQUEST.with(Cell::get),
        peak_live: PEAK_LIVE.with(Cell::get),
    }
}

/// Run case `index` of `target` with `seed`; panics with the case's name on failure.
fn run_case(target: &Target, seed: u64, index: usize) {
    let mut rng = Rng(seed ^ (index as u64).wrapping_mul(0x2545_F491_4F6C_DD1D));
    let base = &target.corpus[rng.below(target.corpus.len())];
    let mut input = base.clone();
    // Mesh targets: a third of the cases first move, repeat or swap whole sections.
    if target.sections && rng.below(3) == 0 {
        input = reorder(&input, &mut rng);
    }
    let input = mutate(&input, &mut rng, target.text);
    let case = format!("{}:{seed}:{index}", target.name);
    if std::env::var_os("ARBVIS_FUZZ_VERBOSE").is_some() {
        eprintln!("case {case} ({} bytes)", input.len());
    }
    let run = target.run;
    let r = capped(|| run(&input));
    if let Some(what) = r.panic {
        panic!("case {case} panicked: {what}; replay with ARBVIS_FUZZ_CASE={case}");
    }
    assert!(
        r.elapsed < CASE_TIME,
        "case {case} took {:?} (bound {CASE_TIME:?}); replay with ARBVIS_FUZZ_CASE={case}",
        r.elapsed
    );
    assert!(
        r.peak_request <= ALLOCATION_CAP,
        "case {case} asked for {} bytes at once; replay with ARBVIS_FUZZ_CASE={case}",
        r.peak_request
    );
    assert!(
        r.peak_live <= LIVE_CAP as isize,
        "case {case} held {} bytes at once; replay with ARBVIS_FUZZ_CASE={case}",
        r.peak_live
    );
}

/// The targets `ARBVIS_FUZZ_TARGETS` selects (all when it is not set): a listed name,
/// or a prefix of names up to a `-`.
fn selected(name: &str) -> bool {
    match std::env::var("ARBVIS_FUZZ_TARGETS") {
        Err(_) => true,
        Ok(list) => list.split(',').map(str::trim).any(|want| {
            !want.is_empty() && (name == want || name.starts_with(&format!("{want}-")))
        }),
    }
}

#[test]
fn loaders_and_scenes_survive_mutated_inputs() {
    // Panics are expected and caught: keep their messages off the output.
    let hook = std::panic::take_hook();
    if std::env::var_os("ARBVIS_FUZZ_CASE").is_none() {
        std::panic::set_hook(Box::new(|_| {}));
    }
    let targets: Vec<Target> = targets().into_iter().filter(|t| selected(t.name)).collect();
    assert!(!targets.is_empty(), "ARBVIS_FUZZ_TARGETS selects no target");
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

#[test]
fn the_mutator_changes_inputs_and_is_deterministic() {
    let base = b"size = [64, 64]\nslices = 128\n".to_vec();
    let a: Vec<Vec<u8>> = (0..50).map(|i| mutate(&base, &mut Rng(i), true)).collect();
    let b: Vec<Vec<u8>> = (0..50).map(|i| mutate(&base, &mut Rng(i), true)).collect();
    assert_eq!(a, b);
    assert!(a.iter().filter(|m| **m != base).count() > 40);
}

// --- issue 17: meshes ---

/// One fixed mesh case: a name (its extension picks nothing: the content does), the
/// file, and `Ok(tetrahedra)` or a part of the error expected.
type MeshCase = (&'static str, Vec<u8>, Result<usize, &'static str>);

/// Issue 17's mesh reproducers, one or more per class, each read under the allocation
/// caps and the fuzz budget: the result and message they must give, no panic, and what
/// they may hold at once (a refusal must come before the big allocation, not from the
/// allocator).
fn issue17_mesh_cases() -> Vec<MeshCase> {
    use mesh_hostile::*;
    vec![
        // 1. Section order: data before what it names is read as if it came last.
        ("data-first.msh", gmsh_data_first(), Ok(2)),
        // 2. Amplification. 2,000 empty $NodeData sections of 9 components over 20,000
        // nodes: 2.9 GB of NaN from 0.4 MB, refused by the budget before any is made.
        (
            "empty-data.msh",
            empty_node_data(20_000, 2_000),
            Err("making the 2000 $NodeData/$ElementData sections into arrays"),
        ),
        // 10 million zero points (240 MB inflated): refused before inflating.
        (
            "no-cells.vtu",
            inflating_points_without_volume(10_000_000, 0),
            Err("the piece has no cells"),
        ),
        (
            "faces.vtu",
            inflating_points_without_volume(10_000_000, 3),
            Err("no volume cells"),
        ),
        // With a tetrahedron, the 10 million points are legal but need 720 MB decoded:
        // over the 256 MiB fuzz budget, refused before inflating.
        (
            "points.vtu",
            inflating_points(10_000_000, 1, 10),
            Err("decoding the piece's 10000000 points and 1 cells needs about"),
        ),
        // A 9-component cell array over 400,000 hexahedra: 2.4 million tetrahedra x 72
        // bytes once copied, refused by the budget from the piece's counts.
        (
            "cell-data.vtu",
            stacked_hexahedra_with(400_000, CUBE, 9),
            Err("decoding the piece's 8 points and 400000 cells needs about"),
        ),
        // 3. Complexity: stacked and collapsed hexahedra read in bounded time.
        (
            "stacked.vtu",
            stacked_hexahedra(200_000, CUBE),
            Ok(1_200_000),
        ),
        (
            "four.vtu",
            stacked_hexahedra(200_000, FOUR_PLACES),
            Ok(1_200_000),
        ),
        ("plates.vtk", stacked_plates(1_400, 1e-4), Ok(8_400)),
        // 5. Messages.
        (
            "collapsed.vtk",
            collapsed_hexahedron(),
            Err("all 1 volume cells are collapsed (degenerate)"),
        ),
        // 6. Extreme numbers.
        ("huge.vtk", huge_coordinates(), Ok(2)),
    ]
}

#[test]
fn issue17_mesh_reproducers_hold_under_the_caps() {
    for (name, bytes, want) in issue17_mesh_cases() {
        let mut got: Option<Result<usize, String>> = None;
        let r = capped(|| {
            got = Some(
                arbvis::mesh::parse(Path::new(name), &bytes)
                    .map(|m| m.tets.len())
                    .map_err(|e| e.to_string()),
            );
        });
        assert!(r.panic.is_none(), "{name} panicked: {:?}", r.panic);
        // Milliseconds in a release build; the debug build on two busy cores gets the
        // harness's per-case bound.
        assert!(r.elapsed < CASE_TIME, "{name} took {:?}", r.elapsed);
        let got = got.unwrap();
        match (&got, want) {
            (Ok(n), Ok(w)) => assert_eq!(*n, w, "{name}"),
            (Err(e), Err(w)) => {
                assert!(e.contains(w), "{name}: expected {w:?} in {e}");
                assert!(e.starts_with(&format!("{name}: ")), "{e}");
                // A refusal comes from the reader before the memory is taken: what the
                // case held stays near the size of its input (the largest here is the
                // 2.4 MB of inflated cell types and offsets of cell-data.vtu).
                assert!(r.peak_live < 64 << 20, "{name} held {} bytes", r.peak_live);
            }
            _ => panic!("{name}: expected {want:?}, got {got:?}"),
        }
        assert!(r.peak_request <= ALLOCATION_CAP && r.peak_live <= LIVE_CAP as isize);
    }
}

#[test]
fn issue17_reordering_moves_whole_sections() {
    // Every mesh fixture has sections to move, and moving them changes the file
    // without changing its length (a move or a swap) or adds a whole one (a repeat).
    for (name, bytes) in mesh_fixtures::all_fixtures() {
        let blocks = mesh_fixtures::sections(&bytes);
        assert!(blocks.len() >= 3, "{name}: {blocks:?}");
        for &(a, b) in &blocks {
            assert!(a < b && b <= bytes.len(), "{name}: {a}..{b}");
        }
        let mut changed = 0;
        for seed in 0..40 {
            let out = reorder(&bytes, &mut Rng(seed));
            changed += usize::from(out != bytes);
            let longer = out.len() - bytes.len();
            assert!(
                longer == 0 || blocks.iter().any(|&(a, b)| b - a == longer),
                "{name}: grew by {longer}"
            );
        }
        assert!(changed > 20, "{name}: {changed} of 40 reorders changed it");
    }
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

/// Run `f` as a fuzz case runs (allocation and live caps, time bound), naming `what` on
/// failure.
fn reproduce<T>(what: &str, f: impl FnOnce() -> T) -> Result<T, String> {
    let mut value = None;
    let run = capped(|| value = Some(f()));
    if let Some(panic) = run.panic {
        return Err(format!("{what}: panicked: {panic}"));
    }
    if run.elapsed >= CASE_TIME {
        return Err(format!(
            "{what}: took {:?} (bound {CASE_TIME:?})",
            run.elapsed
        ));
    }
    if run.peak_request > ALLOCATION_CAP || run.peak_live > LIVE_CAP as isize {
        return Err(format!(
            "{what}: asked for {} bytes at once, held {}",
            run.peak_request, run.peak_live
        ));
    }
    value.ok_or_else(|| format!("{what}: no value"))
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
        // LAS 1.4: the 64-bit count at byte 247 is the one in force.
        &["x.laz: at byte 247: the header declares 250000 points with 120 extra-bytes attributes"],
    )?;
    // Time: equal points past 1,000,000 + 1 a compressed byte.
    // Amplification: point-14 items (layered chunks) under a VLR whose compressor field
    // says 2 (point-wise chunks), with a first layer of 600 MB declared in a small file:
    // laz decodes by the items, so the layer sizes are checked by them too (found by a
    // 600 s fuzz run: laz aborted allocating 603,979,776 bytes).
    let mut layered = las14(30, 0, true);
    let tag = layered
        .windows(14)
        .position(|w| w == b"laszip encoded")
        .ok_or("no laszip VLR")?;
    let vlr_data = tag - 2 + 54;
    layered[vlr_data..vlr_data + 2].copy_from_slice(&2u16.to_le_bytes());
    let data_start = u32::from_le_bytes(layered[96..100].try_into().unwrap()) as usize;
    let record = u16::from_le_bytes(layered[105..107].try_into().unwrap()) as usize;
    let first_layer = data_start + 8 + record + 4;
    layered[first_layer..first_layer + 4].copy_from_slice(&0x2400_0000u32.to_le_bytes());
    let r = reproduce("layered LAZ under compressor 2", || {
        lasfile::parse(Path::new("l.laz"), &layered)
    })?;
    refused(
        "layered LAZ under compressor 2",
        r,
        &["l.laz: at byte", "LAZ chunk 0 declares layers of"],
    )?;
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
