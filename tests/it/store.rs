//! Survey stores (src/store/, issue 19) on small stores: the conversion's round trip
//! (values, levels, ranges, geometry), an interrupted and resumed conversion, corrupt and
//! missing chunks, and the bricked renderer: seams (bricked against whole), eviction
//! under a tiny budget, a survey larger than the GPU budget, streaming until complete,
//! and each LOD policy's error against the f64 reference.

use crate::common;

use std::path::{Path, PathBuf};

use arbvis::camera::Projection;
use arbvis::catalog::TechniqueScene;
use arbvis::gl::{Backend, Headless};
use arbvis::gl::{ProgramChoice, TargetFormat};
use arbvis::image::Image;
use arbvis::render::render_on;
use arbvis::scene::Scene;
use arbvis::store::convert::{convert, ConvertOptions};
use arbvis::store::{Store, StoreError};
use arbvis::techniques::opacity3d::Raycast;
use arbvis::vocab::Fidelity;
use arbvis::volume::attributes::{derive, Attribute};
use arbvis::volume::segy::{write, SampleFormat, WriteOptions};
use arbvis::volume::synthetic::{amplitude, SyntheticSpec};
use arbvis::volume::{Limits, Volume};
use common::{headless, temp_dir, LEVEL};

/// A seismic-like cube of uneven sides (no axis a multiple of the brick).
pub(crate) fn survey(dims: [usize; 3]) -> Volume {
    amplitude(
        &SyntheticSpec {
            size: dims,
            seed: 7,
            peak: 12.0,
            noise: 0.05,
        },
        &Limits::default(),
    )
    .unwrap()
}

/// The cube as an inline-sorted SEG-Y file (IEEE float, inlines from 100, crosslines
/// from 20, 2 ms).
pub(crate) fn write_segy(dir: &Path, v: &Volume) -> PathBuf {
    let o = WriteOptions {
        format: SampleFormat::IeeeFloat,
        big_endian: true,
        revision: 1,
        first_inline: 100,
        first_crossline: 20,
        interval_us: 2000,
    };
    let path = dir.join("survey.sgy");
    std::fs::write(&path, write(v, &o)).unwrap();
    path
}

/// Conversion options with every derived attribute (the default is envelope alone).
pub(crate) fn options(brick: usize) -> ConvertOptions {
    ConvertOptions {
        brick,
        derived: vec![Attribute::Envelope, Attribute::Phase, Attribute::Frequency],
        progress: false,
        ..Default::default()
    }
}

/// Every voxel of every level and attribute, decoded.
pub(crate) fn all_values(store: &Store) -> Vec<Vec<f32>> {
    let mut out = Vec::new();
    for a in 0..store.meta.attributes.len() {
        for level in 0..store.meta.levels {
            let d = store.meta.level_dims(level);
            out.push(store.region(a, level, [0; 3], d).unwrap());
        }
    }
    out
}

#[test]
fn conversion_round_trip_keeps_values_levels_ranges_and_geometry() {
    let dir = temp_dir("store-round-trip");
    let v = survey([37, 23, 19]);
    let sgy = write_segy(&dir, &v);
    let store_path = dir.join("s.zarr");
    let report = convert(&sgy, &store_path, &options(8)).unwrap();
    assert_eq!(report.resumed, 0);
    let s = Store::open(&store_path).unwrap();
    let m = &s.meta;
    assert_eq!(m.dims, [37, 23, 19]);
    // 37 -> 19 -> 10 -> 5: four levels of 8³ bricks.
    assert_eq!(m.levels, 4);
    assert_eq!(m.source.inlines, Some([100, 1]));
    assert_eq!(m.source.crosslines, Some([20, 1]));
    assert_eq!(m.source.interval_us, Some(2000));
    assert_eq!(m.source.facts["traces"], "437");
    let names: Vec<&str> = m.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["amplitude", "envelope", "phase", "frequency"]);
    // Level 0 amplitude: the source's values exactly (float32 throughout).
    let whole = s.window(0, [0; 3], m.dims).unwrap();
    assert_eq!(whole.values, v.values);
    // Envelope: float32, the same per-trace transform as the in-memory path.
    let env = derive(&v, Attribute::Envelope);
    assert_eq!(s.window(1, [0; 3], m.dims).unwrap().values, env.values);
    // Phase and frequency are float16: within half a unit of 2^-11 relative.
    let phase = derive(&v, Attribute::Phase);
    let stored = s.window(2, [0; 3], m.dims).unwrap();
    for (a, b) in stored.values.iter().zip(&phase.values) {
        // f16 near 180 has a spacing of 0.125: rounding is within half of it.
        assert!((a - b).abs() <= 0.0625 + 1e-6, "{a} vs {b}");
    }
    // Statistics from level 0.
    let st = v.stats();
    assert_eq!(m.attributes[0].min, Some(st.min));
    assert_eq!(m.attributes[0].max, Some(st.max));
    assert!((m.attributes[0].mean.unwrap() - st.mean).abs() < 1e-9);
    // Level 1 is the 2x2x2 mean of level 0 (a partial cell at the odd far faces).
    let l1 = s.region(0, 1, [0; 3], m.level_dims(1)).unwrap();
    let d1 = m.level_dims(1);
    for (x, y, z) in [(0, 0, 0), (18, 11, 9), (5, 7, 3), (18, 0, 9)] {
        let mut sum = 0.0f64;
        let mut n = 0;
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let (i, j, k) = (2 * x + dx, 2 * y + dy, 2 * z + dz);
                    if i < 37 && j < 23 && k < 19 {
                        sum += v.values[v.index(i, j, k)] as f64;
                        n += 1;
                    }
                }
            }
        }
        let got = l1[x + d1[0] * (y + d1[1] * z)];
        // The mean is taken in f64 and stored as f32: half an f32 unit.
        assert!(
            ((sum / n as f64) as f32 - got).abs() <= f32::EPSILON * got.abs(),
            "({x},{y},{z})"
        );
    }
    // Per-brick ranges: brick (2, 1, 0) of level 0 holds voxels 16..24 x 8..16 x 0..8.
    let ranges = s.ranges(0, 0).unwrap();
    let counts = m.brick_counts(0);
    let r = ranges[2 + counts[0]]; // (2, 1, 0): i + counts[0] * j
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for k in 0..8 {
        for j in 8..16 {
            for i in 16..24 {
                let x = v.values[v.index(i, j, k)];
                lo = lo.min(x);
                hi = hi.max(x);
            }
        }
    }
    assert_eq!(r, [lo, hi]);
    // A brick with its border: voxels c B - 1 ..= (c + 1) B, clamped at the faces.
    let b = s.brick(0, 0, [4, 2, 2]).unwrap();
    let at = |i: usize, j: usize, k: usize| b[i + 10 * (j + 10 * k)];
    assert_eq!(at(1, 1, 1), v.values[v.index(32, 16, 16)]);
    assert_eq!(at(0, 0, 0), v.values[v.index(31, 15, 15)]);
    // Past the last voxel (i 36, k 18) the border repeats it.
    assert_eq!(at(9, 1, 9), v.values[v.index(36, 16, 18)]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Level 1 is filtered in memory from each quad of level-0 columns where the brick side
/// is even, and read back from the store where it is odd (a cell would straddle two
/// columns): the filter does not depend on the brick, so every level of every attribute
/// is the same bit for bit. Odd sizes on every axis, phase (decimated) and float16
/// attributes included.
#[test]
fn levels_filtered_in_memory_are_the_levels_read_back() {
    let dir = temp_dir("store-in-memory-levels");
    let v = survey([45, 29, 35]);
    let sgy = write_segy(&dir, &v);
    let (even, odd) = (dir.join("even.zarr"), dir.join("odd.zarr"));
    convert(&sgy, &even, &options(8)).unwrap();
    convert(&sgy, &odd, &options(7)).unwrap();
    let (a, b) = (Store::open(&even).unwrap(), Store::open(&odd).unwrap());
    // 45 -> 23 -> 12 -> 6 (one brick of either side).
    assert_eq!((a.meta.levels, b.meta.levels), (4, 4));
    let (va, vb) = (all_values(&a), all_values(&b));
    assert_eq!(va.len(), 16);
    for (n, (x, y)) in va.iter().zip(&vb).enumerate() {
        let same = x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
        assert!(same, "attribute {} level {} differs", n / 4, n % 4);
    }
    // Both means from the same finite values (only the order of the sums differs).
    for (p, q) in a.meta.attributes.iter().zip(&b.meta.attributes) {
        assert_eq!((p.min, p.max), (q.min, q.max));
        assert!((p.mean.unwrap() - q.mean.unwrap()).abs() <= 1e-9 * (1.0 + p.mean.unwrap().abs()));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn raw_input_and_refusals() {
    let dir = temp_dir("store-raw");
    let v = survey([12, 9, 7]);
    let raw = dir.join("v.raw");
    let bytes: Vec<u8> = v.values.iter().flat_map(|x| x.to_be_bytes()).collect();
    std::fs::write(&raw, bytes).unwrap();
    let o = ConvertOptions {
        raw: Some(arbvis::volume::raw::RawSpec {
            path: raw.clone(),
            dims: [12, 9, 7],
            sample: arbvis::volume::SampleType::F32,
            endian: arbvis::volume::Endian::Big,
            offset: 0,
            spacing: [1.0, 2.0, 2.0],
        }),
        derived: vec![],
        ..options(4)
    };
    convert(&raw, &dir.join("r.zarr"), &o).unwrap();
    let s = Store::open(&dir.join("r.zarr")).unwrap();
    assert_eq!(s.meta.spacing, [1.0, 2.0, 2.0]);
    assert_eq!(s.meta.attributes.len(), 1);
    assert_eq!(s.window(0, [0; 3], [12, 9, 7]).unwrap().values, v.values);
    // A store is never overwritten.
    let e = convert(&raw, &dir.join("r.zarr"), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("r.zarr") && e.contains("already exists"), "{e}");
    // Something that is not a store.
    let e = Store::open(&dir).err().unwrap().to_string();
    assert!(e.contains("no zarr.json"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A conversion interrupted by a build from before `--compression` (its log names a zstd
/// level) resumes with `--compression zstd:LEVEL`, and the default (lz4) is refused naming
/// the level to give.
#[test]
fn a_log_from_before_compression_resumes_with_its_zstd_level() {
    use arbvis::store::convert::Compression;
    let dir = temp_dir("store-legacy-log");
    let v = survey([30, 21, 18]);
    let sgy = write_segy(&dir, &v);
    let path = dir.join("old.zarr");
    let zstd = ConvertOptions {
        compression: Compression::Zstd(1),
        ..options(8)
    };
    let stopped = ConvertOptions {
        stop_after: Some(3),
        ..zstd.clone()
    };
    assert!(convert(&sgy, &path, &stopped).is_err());
    let log = path.join(arbvis::store::convert::PROGRESS_LOG);
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.contains("\"compression\":\"zstd:1\""), "{text}");
    std::fs::write(
        &log,
        text.replacen("\"compression\":\"zstd:1\"", "\"zstd\":1", 1),
    )
    .unwrap();
    let e = convert(&sgy, &path, &options(8)).unwrap_err().to_string();
    assert!(
        e.contains("compression zstd:1") && e.contains("compression lz4"),
        "{e}"
    );
    let report = convert(&sgy, &path, &zstd).unwrap();
    assert_eq!(report.resumed, 3);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_interrupted_conversion_resumes_to_the_same_store() {
    let dir = temp_dir("store-resume");
    let v = survey([30, 21, 18]);
    let sgy = write_segy(&dir, &v);
    let fresh = dir.join("fresh.zarr");
    convert(&sgy, &fresh, &options(8)).unwrap();
    let path = dir.join("resumed.zarr");
    let stopped = ConvertOptions {
        stop_after: Some(4),
        ..options(8)
    };
    let e = convert(&sgy, &path, &stopped).unwrap_err();
    assert!(matches!(e, StoreError::Interrupted(_)), "{e}");
    // Half done: not a store yet, and it says how to go on.
    let e = Store::open(&path).err().unwrap().to_string();
    assert!(e.contains("resume"), "{e}");
    // A chunk torn by the interruption (a column not in the log: which four columns
    // finished depends on the threads' order): garbage on disk.
    let log = std::fs::read_to_string(path.join(arbvis::store::convert::PROGRESS_LOG)).unwrap();
    // Four columns logged, of any level: a level-1 column whose one child (an edge
    // column) finished early may be among them.
    assert_eq!(
        log.lines().filter(|l| l.contains("\"u\":[")).count(),
        4,
        "{log}"
    );
    let done: Vec<String> = log
        .lines()
        .filter_map(|l| l.split("\"u\":[0,").nth(1))
        .map(|rest| rest.split(']').next().unwrap().replace(',', "/"))
        .collect();
    // Chunk keys run (inline column k, crossline column j, brick along the samples i):
    // brick 1 of a column (j, k) not logged.
    let torn = (0..3)
        .flat_map(|j| (0..3).map(move |k| (j, k)))
        .find(|(j, k)| !done.contains(&format!("{j}/{k}")))
        .map(|(j, k)| path.join(format!("amplitude/c/{k}/{j}/1")))
        .unwrap();
    std::fs::create_dir_all(torn.parent().unwrap()).unwrap();
    std::fs::write(&torn, b"torn write").unwrap();
    // Other options are refused, naming both.
    let e = convert(&sgy, &path, &options(16)).unwrap_err().to_string();
    assert!(e.contains("brick 8") && e.contains("brick 16"), "{e}");
    let report = convert(&sgy, &path, &options(8)).unwrap();
    // Levels of 30 x 21 x 18 in 8³ bricks: 3 x 3 level-0 columns, 2 x 2 at level 1, one
    // at level 2; 4 were done before.
    assert_eq!(report.meta.levels, 3);
    assert_eq!(report.resumed, 4);
    assert_eq!(report.written, 9 + 4 + 1 - 4);
    assert!(!path.join(arbvis::store::convert::PROGRESS_LOG).exists());
    let (a, b) = (Store::open(&fresh).unwrap(), Store::open(&path).unwrap());
    assert_eq!(a.meta.attributes, b.meta.attributes);
    assert!(all_values(&a) == all_values(&b), "resumed store differs");
    for level in 0..a.meta.levels {
        let (ra, rb) = (a.ranges(1, level).unwrap(), b.ranges(1, level).unwrap());
        assert_eq!(format!("{ra:?}"), format!("{rb:?}"));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A store scene: amplitude (seismic table, transparent mid-range) and envelope.
fn store_scene(dir: &Path, volume: &str, extra: &str, size: u32) -> Scene {
    let mut scene = Scene::parse(&store_scene_text(volume, extra, size), "test").unwrap();
    scene.base = dir.to_path_buf();
    scene
}

/// [`store_scene`]'s text: both attributes from `volume` (`{ store = "..." }`, ...).
pub(crate) fn store_scene_text(volume: &str, extra: &str, size: u32) -> String {
    format!(
        r#"size = [{size}, {size}]
background = [0.0, 0.0, 0.0, 1.0]
[camera]
rotation = [0.2241, -0.3696, 0.0747, 0.8986]
[technique.opacity3d]
slices = 80
[technique.opacity3d.primary]
volume = {volume}
attribute = "amplitude"
table = {{ builtin = "seismic", alpha = [[0.0, 0.6], [0.4, 0.0], [0.6, 0.0], [1.0, 0.6]] }}
[technique.opacity3d.secondary]
volume = {volume}
attribute = "envelope"
table = {{ builtin = "viridis", alpha = [[0.0, 0.0], [0.5, 0.05], [1.0, 0.4]] }}
coefficients = [0.8, 0.8, 0.8, 0.8]
{extra}"#
    )
}

/// A converted survey and the same values as a raw file, for bricked-against-whole tests.
pub(crate) fn fixture(name: &str, dims: [usize; 3], brick: usize) -> (PathBuf, Volume) {
    let dir = temp_dir(name);
    let v = survey(dims);
    let sgy = write_segy(&dir, &v);
    let o = ConvertOptions {
        derived: vec![Attribute::Envelope],
        ..options(brick)
    };
    convert(&sgy, &dir.join("s.zarr"), &o).unwrap();
    let bytes: Vec<u8> = v.values.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(dir.join("v.raw"), bytes).unwrap();
    // The store has the survey's proportions (the SEG-Y reader's geometry: the writer puts
    // no CDP coordinates, so 25 m bins): so does the raw twin.
    let mut v = v;
    v.spacing = arbvis::volume::segy::read(&sgy, &Default::default())
        .unwrap()
        .volume
        .spacing;
    (dir, v)
}

fn raw_volume(v: &Volume) -> String {
    format!(
        "{{ raw = {{ path = \"v.raw\", dims = [{}, {}, {}], type = \"f32\", spacing = {:?} }} }}",
        v.dims[0], v.dims[1], v.dims[2], v.spacing
    )
}

fn max_diff(a: &Image, b: &Image) -> (f32, usize) {
    let mut worst = 0f32;
    let mut over = 0;
    for y in 0..a.height {
        for x in 0..a.width {
            let (p, q) = (a.pixel_u8(x, y), b.pixel_u8(x, y));
            let d = (0..3)
                .map(|c| (p[c] as f32 - q[c] as f32).abs() / 255.0)
                .fold(0f32, f32::max);
            worst = worst.max(d);
            if d > LEVEL + 1e-6 {
                over += 1;
            }
        }
    }
    (worst, over)
}

#[test]
fn bricked_at_level_zero_draws_the_whole_volume_and_a_tiny_budget_the_same_picture() {
    let h: Headless = headless(Backend::Egl);
    let (dir, v) = fixture("store-seams", [40, 28, 24], 8);
    let whole = render_on(&h, &store_scene(&dir, &raw_volume(&v), "", 96)).unwrap();
    let level0 = "[technique.opacity3d.store]\nlevel = 0\ngpu_memory = \"64M\"\n";
    let bricked = render_on(&h, &store_scene(&dir, "{ store = \"s.zarr\" }", level0, 96)).unwrap();
    let (worst, over) = max_diff(&bricked.image, &whole.image);
    // Seams: every brick's slices are the whole volume's planes cut at shared edges, and
    // the border voxels give the same filtering. What is left is llvmpipe's 8-bit texel
    // weights: a brick's texture coordinates are the whole texture's shifted by whole
    // texels but rounded differently in f32, so a weight can round to the next 1/256,
    // the filtered level to the next one, and a steep table entry step shows: measured
    // 7 of 9216 pixels over one level, by at most 7 levels. The bound: 0.2 % of the
    // pixels, 10 levels.
    eprintln!(
        "bricked vs whole: largest {:.1} levels, {over} pixels over one level",
        worst / LEVEL
    );
    assert!(
        over <= 96 * 96 / 500,
        "bricked vs whole: {over} pixels over a level"
    );
    assert!(worst <= 10.0 * LEVEL, "bricked vs whole: {worst}");
    let lit = (0..96 * 96)
        .filter(|&p| bricked.image.pixel_u8(p % 96, p / 96)[..3] != [0, 0, 0])
        .count();
    assert!(
        lit > 96 * 96 / 4,
        "the survey covers the view ({lit} pixels lit)"
    );
    // The same store with room for 3 bricks (10³ RGB = 3000 bytes each) of its 5 x 4 x 3:
    // drawn in back-to-front batches, evicting as it goes: the same picture, bit for bit.
    let tiny = "[technique.opacity3d.store]\nlevel = 0\ngpu_memory = \"9000\"\n";
    let small = render_on(&h, &store_scene(&dir, "{ store = \"s.zarr\" }", tiny, 96)).unwrap();
    assert_eq!(
        small.image.data, bricked.image.data,
        "tiny budget changed the picture"
    );
    let status = small.status.clone().unwrap();
    assert!(status.contains("of 3 slots"), "{status}");
    // The context's resource log holds every render's: the big budget made one slot per
    // brick (60), the tiny one 3 more.
    let slots = |r: &arbvis::render::Rendered| {
        r.resources
            .iter()
            .filter(|r| r.label.starts_with("store brick slot"))
            .count()
    };
    assert_eq!(slots(&bricked), 5 * 4 * 3);
    assert_eq!(
        slots(&small) - slots(&bricked),
        3,
        "the budget bounds the textures made"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Largest and root-mean-square difference of two float pictures' RGB.
fn float_diff(a: &Image, b: &Image) -> (f64, f64) {
    let (mut worst, mut sq, mut n) = (0f64, 0f64, 0usize);
    for y in 0..a.height {
        for x in 0..a.width {
            let (p, q) = (a.pixel(x, y), b.pixel(x, y));
            for c in 0..3 {
                let d = (p[c] as f64 - q[c] as f64).abs();
                worst = worst.max(d);
                sq += d * d;
                n += 1;
            }
        }
    }
    (worst, (sq / n as f64).sqrt())
}

/// `scene` in precise mode, GLSL, a float target, the point-sampling ray caster (no
/// jitter: the page table's ray caster has none), through `projection`.
fn precise(mut scene: Scene, projection: Projection) -> Scene {
    scene.fidelity = Fidelity::Precise;
    scene.programs = ProgramChoice::Glsl;
    scene.target = Some(TargetFormat::Rgba32f);
    scene.camera.projection = projection;
    if let TechniqueScene::Opacity3d(p) = &mut scene.technique {
        p.raycast = Some(Raycast {
            jitter: false,
            margins: true,
            bake: false,
            ..Raycast::default()
        });
    }
    scene
}

#[test]
fn precise_through_the_page_table_is_the_whole_volume_ray_caster_at_level_zero() {
    let h: Headless = headless(Backend::Egl);
    // Odd sizes in bricks of 8 (partial bricks on every axis), two attributes (G and B
    // of the atlas), a rotated camera, both projections.
    let (dir, v) = fixture("store-precise", [41, 27, 22], 8);
    let level0 = "[technique.opacity3d.store]\nlevel = 0\ngpu_memory = \"64M\"\n";
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let whole = render_on(
            &h,
            &precise(store_scene(&dir, &raw_volume(&v), "", 80), projection),
        )
        .unwrap();
        let paged = render_on(
            &h,
            &precise(
                store_scene(&dir, "{ store = \"s.zarr\" }", level0, 80),
                projection,
            ),
        )
        .unwrap();
        let (worst, rmse) = float_diff(&paged.image, &whole.image);
        eprintln!("{projection:?}: paged vs whole: largest {worst:.2e}, RMSE {rmse:.2e}");
        // The same 8-bit levels as 16-bit unorm, filtered in float, at the same sample
        // positions: what is left is f32 rounding of the atlas coordinates (offsets of a
        // few atlas sizes, 2^-24 relative: under 1e-4 texel) times the data's slope,
        // accumulated along the ray (measured: largest 5.1e-7, RMSE 5.4e-8). The
        // issue's bound for seams, 1e-5, on every pixel.
        assert!(worst <= 1e-5, "{projection:?}: largest {worst:.2e}");
        assert!(rmse <= 1e-6, "{projection:?}: RMSE {rmse:.2e}");
        let lit = (0..80 * 80)
            .filter(|&p| paged.image.pixel(p % 80, p / 80)[3] > 0.05)
            .count();
        assert!(
            lit > 80 * 80 / 4,
            "the survey covers the view ({lit} pixels)"
        );
    }
    // One pass needs its bricks at once: level 0 forced into 3 slots (16-bit, 10³ x 6
    // bytes each) is refused with the count; without the forced level the cut coarsens
    // to fit and draws.
    let tiny = "[technique.opacity3d.store]\nlevel = 0\ngpu_memory = \"18000\"\n";
    let scene = precise(
        store_scene(&dir, "{ store = \"s.zarr\" }", tiny, 80),
        Projection::Orthographic,
    );
    let e = match render_on(&h, &scene) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("60 bricks drawn from 3 slots in one pass"),
    };
    assert!(
        e.contains("more than the 3") && e.contains("--gpu-memory"),
        "{e}"
    );
    let fit = "[technique.opacity3d.store]\ngpu_memory = \"18000\"\n";
    let scene = precise(
        store_scene(&dir, "{ store = \"s.zarr\" }", fit, 80),
        Projection::Orthographic,
    );
    let r = render_on(&h, &scene).unwrap();
    let status = r.status.unwrap();
    assert!(
        status.contains("of 3 slots") && !status.contains("L0"),
        "{status}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Levels are means of the level below, so a coarse brick's own range is narrower than
/// its children's: a table clear over the middle must not prune a coarse brick whose
/// children reach the opaque ends.
#[test]
fn a_table_clear_in_the_middle_keeps_the_bricks_whose_children_reach_its_ends() {
    let h: Headless = headless(Backend::Egl);
    let (dir, _) = fixture("store-ranges", [40, 28, 24], 8);
    let store = Store::open(&dir.join("s.zarr")).unwrap();
    let m = &store.meta;
    let (lo, hi) = (m.attributes[0].min.unwrap(), m.attributes[0].max.unwrap());
    // The premise: the top level's range stays inside the middle 60 % of the survey's.
    let top = store.ranges(0, m.levels - 1).unwrap();
    let inner = |v: f32| ((v as f64 - lo) / (hi - lo) - 0.5).abs() < 0.3;
    assert!(top.iter().all(|r| inner(r[0]) && inner(r[1])), "{top:?}");
    // Opaque only over the outer 15 % at each end, at the LOD's own choice of level.
    let text = r#"size = [64, 64]
background = [0.0, 0.0, 0.0, 1.0]
[camera]
rotation = [0.2241, -0.3696, 0.0747, 0.8986]
[technique.opacity3d]
slices = 64
[technique.opacity3d.primary]
volume = { store = "s.zarr" }
attribute = "amplitude"
table = { builtin = "seismic", alpha = [[0.0, 0.9], [0.15, 0.0], [0.85, 0.0], [1.0, 0.9]] }
"#;
    let mut scene = Scene::parse(text, "test").unwrap();
    scene.base = dir.clone();
    let r = render_on(&h, &scene).unwrap();
    let status = r.status.unwrap();
    assert!(!status.contains("MB; 0 drawn"), "{status}");
    let lit = (0..64 * 64)
        .filter(|&p| r.image.pixel_u8(p % 64, p / 64)[..3] != [0, 0, 0])
        .count();
    assert!(lit > 64, "{lit} pixels lit: {status}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The viewer's sections of a store: read at level 0 by the reader thread, in the
/// survey's numbers, the same levels as the whole volume quantized over the same range.
#[cfg(feature = "viewer")]
#[test]
fn viewer_sections_read_the_store_at_level_zero() {
    use arbvis::viewer::store_sections::StoreSections;
    use arbvis::volume::quantize::quantize_value;
    let (dir, v) = fixture("store-sections", [41, 27, 22], 8);
    // Room for one brick on the GPU: the sections do not depend on what is resident.
    let extra = "[technique.opacity3d.store]\ngpu_memory = \"3000\"\n";
    let scene = store_scene(&dir, "{ store = \"s.zarr\" }", extra, 64);
    let TechniqueScene::Opacity3d(params) = &scene.technique else {
        unreachable!()
    };
    let mut sections = StoreSections::open(params, &dir).unwrap().unwrap();
    assert_eq!(sections.dims, [41, 27, 22]);
    let names: Vec<&str> = sections.axes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["time (ms)", "crossline", "inline"]);
    // SEG-Y inlines from 100, crosslines from 20, 2 ms samples (the fixture's headers).
    assert_eq!(sections.axes[2].label(3), "103");
    assert_eq!(sections.axes[1].label(0), "20");
    assert_eq!(sections.axes[0].label(5), "10");
    let (low, high) = (
        sections.attributes[0].unwrap().1,
        sections.attributes[0].unwrap().2,
    );
    // An inline (fixed k = 7: crossline across, time down) and a time slice (fixed i =
    // 30: crossline across, inline down).
    for (axis, index, across, down) in [(2usize, 7usize, 1usize, 0usize), (0, 30, 1, 2)] {
        sections.ask((axis, index, 0));
        let mut got = None;
        for _ in 0..500 {
            if let Some((key, levels)) = sections.arrived().pop() {
                assert_eq!(key, (axis, index, 0));
                got = Some(levels.unwrap());
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let got = got.expect("the reader thread answered within 5 s");
        let mut expected = Vec::new();
        for y in 0..v.dims[down] {
            for x in 0..v.dims[across] {
                let mut ijk = [0; 3];
                ijk[axis] = index;
                ijk[across] = x;
                ijk[down] = y;
                expected.push(quantize_value(
                    v.values[v.index(ijk[0], ijk[1], ijk[2])],
                    low,
                    high,
                ));
            }
        }
        assert_eq!(got, expected, "section {axis} {index}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn streaming_refines_to_the_full_picture_and_survives_a_corrupt_chunk() {
    use arbvis::render::build;
    use arbvis::techniques::Frame;
    let h: Headless = headless(Backend::Egl);
    let (dir, _) = fixture("store-stream", [40, 28, 24], 8);
    let scene = store_scene(&dir, "{ store = \"s.zarr\" }", "", 64);
    let full = render_on(&h, &scene).unwrap();
    let gpu = h.gpu();
    let kind = scene.programs.resolve(gpu);
    let frame = Frame {
        camera: scene.camera,
        width: 64,
        height: 64,
    };
    let target = arbvis::gl::Target::create(gpu, 64, 64, scene.target_format(), false).unwrap();
    let mut frames = 0;
    let mut renderer = build(gpu, &scene, kind).unwrap();
    renderer.set_streaming(true);
    let mut first: Option<Image> = None;
    loop {
        target.clear(gpu, scene.clear_colour()).unwrap();
        renderer
            .draw(gpu, arbvis::gl::Surface::Target(&target), &frame)
            .unwrap();
        gpu.finish();
        frames += 1;
        if first.is_none() {
            first = Some(target.read(gpu).unwrap());
        }
        if !renderer.pending() || frames > 400 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // The loader ran beside the frames: more than one frame, and the last is the
    // offscreen picture exactly (same bricks, same order).
    assert!(frames > 1 && frames <= 400, "{frames} frames");
    let last = target.read(gpu).unwrap();
    assert_eq!(last.data, full.image.data);
    drop(renderer);
    // Corrupt one chunk and delete another: offscreen names the chunk; streaming keeps
    // drawing and says which bricks failed.
    let store = dir.join("s.zarr");
    let chunk = store.join("amplitude/c/1/1/2");
    std::fs::write(&chunk, b"not zstd").unwrap();
    std::fs::remove_file(store.join("envelope/c/2/2/4")).unwrap();
    let level0 = "[technique.opacity3d.store]\nlevel = 0\n";
    let scene0 = store_scene(&dir, "{ store = \"s.zarr\" }", level0, 64);
    let e = match render_on(&h, &scene0) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a corrupt chunk rendered"),
    };
    assert!(
        e.contains("amplitude/c/1/1/2") && e.contains("cannot be decoded"),
        "{e}"
    );
    let s = Store::open(&store).unwrap();
    let e = s.chunk(1, 0, [4, 2, 2]).unwrap_err().to_string();
    assert!(
        e.contains("envelope/c/2/2/4") && e.contains("missing"),
        "{e}"
    );
    let mut renderer = build(gpu, &scene0, kind).unwrap();
    renderer.set_streaming(true);
    for _ in 0..200 {
        target.clear(gpu, scene.clear_colour()).unwrap();
        renderer
            .draw(gpu, arbvis::gl::Surface::Target(&target), &frame)
            .unwrap();
        gpu.finish();
        if !renderer.pending() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let status = renderer.status().unwrap();
    assert!(status.contains("2 bricks failed"), "{status}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The README's zarr-python lines, run on a small store: another tool reads what arbvis
/// wrote. Skipped (SKIPPED on stderr) without `python3 -c "import zarr"`; `.ci/run`
/// installs zarr from PyPI and sets ARBVIS_NO_SKIP=1, which makes a skip a failure.
#[test]
fn zarr_python_reads_the_store() {
    if !crate::common::python_has(
        "import zarr",
        "python3 with zarr is missing (pip install zarr)",
    ) {
        return;
    }
    let dir = temp_dir("store-zarr-python");
    let v = survey([21, 13, 11]);
    let sgy = write_segy(&dir, &v);
    convert(&sgy, &dir.join("survey.zarr"), &options(8)).unwrap();
    // The README's lines, then what they read, printed for comparison.
    let script = r#"
import zarr
root = zarr.open_group("survey.zarr", mode="r")
meta = root.attrs["arbvis"]
amplitude = root["amplitude"]
section = amplitude[5, :, :]
coarse = root["level_1/amplitude"][:]
ranges = root["amplitude_range"][:]
print(meta["dims"], amplitude.shape, amplitude.chunks, str(amplitude.dtype))
print(repr(float(section[3, 17])), repr(float(amplitude[10, 12, 20])))
print(coarse.shape, ranges.shape, str(root["phase"].dtype))
"#;
    let out = std::process::Command::new("python3")
        .args(["-c", script])
        .current_dir(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0], "[21, 13, 11] (11, 13, 21) (8, 8, 8) float32",
        "{text}"
    );
    // zarr's [inline, crossline, sample] is arbvis's (k, j, i): exactly the f32 values.
    let read: Vec<f64> = lines[1]
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let expect = [v.values[v.index(17, 3, 5)], v.values[v.index(20, 12, 10)]];
    assert_eq!(read, expect.map(f64::from), "{text}");
    assert_eq!(lines[2], "(6, 7, 11) (2, 2, 3, 2) float16", "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A store of the layout before MDIO (version 1: every level under `ATTRIBUTE/LEVEL`, the
/// ranges under `ATTRIBUTE/range/LEVEL`) still opens and reads the same values: made here
/// by moving a version 2 store's arrays to those paths.
#[test]
fn a_store_of_the_layout_before_mdio_still_reads() {
    let dir = temp_dir("store-v1");
    let sgy = write_segy(&dir, &survey([21, 13, 11]));
    let s = dir.join("s.zarr");
    convert(&sgy, &s, &options(8)).unwrap();
    let want = all_values(&Store::open(&s).unwrap());
    let meta = Store::open(&s).unwrap().meta;
    let group = r#"{"zarr_format": 3, "node_type": "group", "attributes": {}}"#;
    for a in &meta.attributes {
        let name = &a.name;
        let tmp = dir.join(format!("{name}-0"));
        std::fs::rename(s.join(name), &tmp).unwrap();
        std::fs::create_dir_all(s.join(name).join("range")).unwrap();
        std::fs::write(s.join(name).join("zarr.json"), group).unwrap();
        std::fs::write(s.join(name).join("range/zarr.json"), group).unwrap();
        std::fs::rename(&tmp, s.join(name).join("0")).unwrap();
        std::fs::rename(
            s.join(format!("{name}_range")),
            s.join(name).join("range/0"),
        )
        .unwrap();
        for level in 1..meta.levels {
            std::fs::rename(
                s.join(format!("level_{level}/{name}")),
                s.join(name).join(level.to_string()),
            )
            .unwrap();
            std::fs::rename(
                s.join(format!("level_{level}/{name}_range")),
                s.join(name).join(format!("range/{level}")),
            )
            .unwrap();
        }
    }
    let root = s.join("zarr.json");
    let text = std::fs::read_to_string(&root).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["attributes"]["arbvis"]["version"] = serde_json::json!(1);
    std::fs::write(&root, v.to_string()).unwrap();
    let old = Store::open(&s).unwrap();
    assert_eq!(old.meta.version, 1);
    assert_eq!(all_values(&old), want);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A store takes its table's alpha from its own data as the survey read whole does (a
/// survey's default: the common amplitudes clear, the strong ones opaque): F3 and the
/// store converted from it, drawn with the default table over one min-max range, give one
/// picture. Before, the store kept the grey table's own ramp and drew a near-opaque box
/// (136 levels apart, 27 on average). Read from level 0 here (the survey is small); a store
/// over 4 M voxels reads the finest level under that.
#[test]
fn a_store_takes_its_alpha_from_its_data_as_its_segy_does() {
    let h: Headless = headless(Backend::Egl);
    let (_dir, f3, store) = crate::mdio::f3_store("store-data-alpha");
    let scene = |volume: String, fidelity: &str| {
        let text = format!(
            "size = [96, 80]\nfidelity = \"{fidelity}\"\nprograms = \"glsl\"\ntarget = \"rgba32f\"\n[camera]\nrotation = [0.31, -0.22, 0.12, 0.917]\n[technique.opacity3d.primary]\nvolume = {volume}\nattribute = \"amplitude\"\nquantize = \"min-max\"\n[technique.opacity3d.raycast]\njitter = false\nmargins = true\nbake = false\n[technique.opacity3d.store]\nlevel = 0\n"
        );
        Scene::parse(&text, "alpha.toml").unwrap()
    };
    for fidelity in ["precise", "faithful"] {
        let mut whole = scene(format!("{{ segy = \"{}\" }}", f3.display()), fidelity);
        // The SEG-Y read whole has no store table: its own key left out.
        if let TechniqueScene::Opacity3d(p) = &mut whole.technique {
            p.store = None;
        }
        let paged = scene(format!("{{ store = \"{}\" }}", store.display()), fidelity);
        let (a, b) = (
            render_on(&h, &whole).unwrap().image,
            render_on(&h, &paged).unwrap().image,
        );
        let d = b.compare(&a, crate::common::LEVEL).unwrap();
        let lit = crate::common::lit_pixels(&a, 0.05);
        assert!(lit > 1000, "{fidelity}: the survey is in view ({lit})");
        match fidelity {
            // The same samples, the same alpha, the same ray caster: f32 rounding of the
            // atlas coordinates (measured 6.6e-6 at most), under the 1e-5 the page
            // table's own test holds it to.
            "precise" => assert!(d.max_abs < 1e-5, "{d:?}"),
            // Bricks against one texture, sliced alike: a few pixels along brick faces
            // (measured: RMSE 0.0008, 4 pixels over a level, 0.08 at most).
            _ => assert!(d.rmse < 0.005 && d.pixels_over < 40, "{d:?}"),
        }
    }
}
