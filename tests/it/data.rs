//! Loaders on real files from the project's `data/`, and bad input: a truncated SEG-Y, truncated
//! NIfTI files and raw files of the wrong size, each ending in an error that names the
//! file and position, and no output file.

use crate::common;

use std::io::{Read, Write};
use std::path::Path;
use std::process::Command;

use arbvis::gl::{Backend, ProgramChoice, TargetFormat};
use arbvis::render::render_on;
use arbvis::scene::{Scene, TechniqueScene};
use arbvis::volume::raw::RawSpec;
use arbvis::volume::{nifti_file, raw, segy, Endian, SampleType, VolumeError};
use common::{data_file, headless, inspect, temp_dir, LEVEL};

#[test]
fn f3_grids_from_its_trace_headers() {
    let path = data_file("seismic/f3.sgy");
    let cube = segy::read(&path, &Default::default()).unwrap();
    // data/README.md: 23 inlines x 18 crosslines x 75 samples, format 3.
    assert_eq!(cube.volume.dims, [75, 18, 23]);
    assert_eq!(cube.format, segy::SampleFormat::Int16);
    assert!(cube.big_endian);
    assert_eq!((cube.inlines[0], cube.inlines[22]), (111, 133));
    assert_eq!((cube.crosslines[0], cube.crosslines[17]), (875, 892));
    assert_eq!(cube.interval_us, 4000);
    let s = cube.volume.stats();
    assert_eq!((s.min, s.max), (-10239.0, 10827.0));
    // The same crop re-encoded as IBM float decodes to the same numbers.
    let ibm = data_file("seismic/Format1msb.sgy");
    let ibm = segy::read(&ibm, &Default::default()).unwrap();
    assert_eq!(ibm.format, segy::SampleFormat::IbmFloat);
    assert_eq!(ibm.volume, cube.volume);
}

#[test]
fn small_and_tiny_ibm_files() {
    for (file, dims) in [
        ("seismic/small.sgy", [50, 5, 5]),
        ("seismic/tiny.sgy", [4, 2, 3]),
    ] {
        let path = data_file(file);
        let cube = segy::read(&path, &Default::default()).unwrap();
        assert_eq!(cube.volume.dims, dims, "{file}");
        // segyio's synthetic files hold inline.crossline0sample-like values: 1.2 at the
        // first sample of inline 1, crossline 20.
        assert!((cube.volume.values[0] - 1.2).abs() < 1e-6, "{file}");
    }
}

#[test]
fn broken_segy_is_a_clear_error() {
    let path = data_file("seismic/broken.sgy");
    let e = segy::read(&path, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("broken.sgy") && e.contains("at byte 10836"),
        "{e}"
    );
    assert!(e.contains("truncated") && e.contains("trace 4"), "{e}");
    // And through the CLI: an error naming the file, no PNG.
    let dir = temp_dir("broken-segy");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "[technique.opacity3d.primary]\nvolume = {{ segy = {:?} }}\n",
            path.display().to_string()
        ),
    )
    .unwrap();
    let png = dir.join("out.png");
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("broken.sgy") && stderr.contains("truncated"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "only the scene file remains"
    );
}

fn gunzip(path: &Path) -> Vec<u8> {
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(std::fs::File::open(path).unwrap())
        .read_to_end(&mut out)
        .unwrap();
    out
}

#[test]
fn icbm152_volumes_share_one_grid() {
    for name in ["t1", "gm", "wm"] {
        let file = format!("volumes/mni_icbm152_{name}_tal_nlin_sym_09a_converted.nii.gz");
        let path = data_file(&file);
        let v = nifti_file::read(&path, &Default::default()).unwrap();
        assert_eq!(v.dims, [197, 233, 189], "{name}");
        assert_eq!(v.spacing, [1.0; 3]);
        let s = v.stats();
        assert!(
            s.min >= 0.0 && s.max <= 255.0 && s.max > 100.0,
            "{name}: {s:?}"
        );
    }
}

#[test]
fn truncated_nifti_is_a_clear_error() {
    let path = data_file("volumes/mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz");
    let dir = temp_dir("truncated-nifti");
    let bytes = gunzip(&path);
    // Uncompressed, cut in the middle of the voxel data.
    let cut = dir.join("cut.nii");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = nifti_file::read(&cut, &Default::default()).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, VolumeError::Format { .. }), "{msg}");
    assert!(
        msg.contains("cut.nii") && msg.contains("truncated"),
        "{msg}"
    );
    assert!(
        msg.contains(&format!("at byte {}", bytes.len() / 2)),
        "{msg}"
    );
    // Compressed, the gzip stream cut short.
    let gz = dir.join("cut.nii.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(&bytes).unwrap();
    let packed = enc.finish().unwrap();
    std::fs::write(&gz, &packed[..packed.len() / 2]).unwrap();
    let msg = nifti_file::read(&gz, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("cut.nii.gz") && msg.contains("truncated"),
        "{msg}"
    );
    // A header cut short.
    let header = dir.join("header.nii");
    std::fs::write(&header, &bytes[..100]).unwrap();
    let msg = nifti_file::read(&header, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("header.nii") && msg.contains("truncated"),
        "{msg}"
    );
}

#[test]
fn raw_size_mismatch_is_a_clear_error() {
    let dir = temp_dir("raw-mismatch");
    std::fs::write(dir.join("v.raw"), vec![0u8; 1000]).unwrap();
    let spec = RawSpec {
        path: "v.raw".into(),
        dims: [10, 10, 6],
        sample: SampleType::U16,
        endian: Endian::Big,
        offset: 0,
        spacing: [1.0; 3],
    };
    let msg = raw::read(&dir, &spec, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("v.raw") && msg.contains("1000 bytes") && msg.contains("need 1200"),
        "{msg}"
    );
    let spec = RawSpec {
        dims: [10, 10, 10],
        ..spec
    };
    let msg = raw::read(&dir, &spec, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(msg.contains("need 2000"), "{msg}");
    // With matching dims it loads, big-endian.
    std::fs::write(dir.join("v.raw"), [0u8, 1, 1, 0]).unwrap();
    let ok = raw::read(
        &dir,
        &RawSpec {
            dims: [2, 1, 1],
            ..spec.clone()
        },
        &Default::default(),
    )
    .unwrap();
    assert_eq!(ok.values, vec![1.0, 256.0]);
    // dims whose byte count wraps 64 bits (2^61 - 1 samples of 8 bytes + 8) on an empty
    // file: an error naming the file, not a panic (the fuzzer found this one).
    std::fs::write(dir.join("empty.raw"), []).unwrap();
    // With offset 8 the size overflows; with offset 0 it fits 64 bits and the texture
    // limit refuses it, still before the file is read.
    for (offset, cause) in [(8, "64 bits"), (0, "GL_MAX_3D_TEXTURE_SIZE")] {
        let huge = RawSpec {
            path: "empty.raw".into(),
            dims: [2305843009213693951, 1, 1],
            sample: SampleType::F64,
            offset,
            ..spec.clone()
        };
        let msg = raw::read(&dir, &huge, &Default::default())
            .unwrap_err()
            .to_string();
        assert!(msg.contains("empty.raw") && msg.contains(cause), "{msg}");
    }
}

#[test]
fn data_scenes_render_and_their_arb_and_glsl_agree() {
    let h = headless(Backend::Egl);
    for file in ["scenes/data/f3.toml", "scenes/data/icbm152.toml"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let mut scene = Scene::load(&path).unwrap();
        scene.size = [128, 128];
        scene.target = Some(TargetFormat::Rgba8);
        scene.programs = ProgramChoice::Arb;
        let arb = render_on(&h, &scene).unwrap();
        scene.programs = ProgramChoice::Glsl;
        let glsl = render_on(&h, &scene).unwrap();
        let d = arb.image.compare(&glsl.image, LEVEL).unwrap();
        // Same instructions, both 8-bit: one level (see tests/opacity3d.rs).
        assert!(d.max_abs <= LEVEL as f64 * 1.01, "{file}: {d:?}");
        // Something is drawn: at least a tenth of the pixels differ from the background.
        let lit = (0..128 * 128)
            .filter(|i| {
                arb.image.data[i * 4..i * 4 + 3]
                    .iter()
                    .any(|&v| v > 2.0 * LEVEL)
            })
            .count();
        assert!(lit > 128 * 128 / 10, "{file}: only {lit} pixels lit");
    }
}

#[test]
fn inspect_prints_what_the_loader_sees() {
    let path = data_file("seismic/f3.sgy");
    let text = inspect(&path);
    for expect in [
        "SEG-Y rev 1.0",
        "int16 (3)",
        "big-endian",
        "inlines: 111..=133 (23 values",
        "crosslines: 875..=892 (18 values",
        "samples: 75 per trace, interval 4000 us",
        "min -10239 max 10827",
    ] {
        assert!(text.contains(expect), "missing {expect:?} in\n{text}");
    }
}

#[test]
fn inspect_reads_meshes_point_clouds_and_surfaces() {
    for (file, expect) in [
        (
            "tets/post.vtk",
            &["VTK legacy 3.0", "tetrahedra: 8750", "\"Pressure\""][..],
        ),
        (
            "tets/can.vtu",
            &[
                "UInt64 headers",
                "VTK_HEXAHEDRON: 4800",
                "tetrahedra: 28800",
            ],
        ),
        (
            "tets/bracket-2.2.msh",
            &["gmsh MSH 2.2", "tetrahedra: 40710", "\"temperature\""],
        ),
        (
            "points/autzen_trim.laz",
            &["LAS 1.2", "compressed (LAZ)", "points: 110000"],
        ),
        ("points/bunny.ply", &["PLY 1.0 ascii", "points: 35947"]),
        (
            "surfaces/cow.obj",
            &["triangles: 5804", "open edges (one triangle): 0"],
        ),
        (
            "surfaces/42400-IDGH.stl",
            &["triangles: 11036", "closed: yes"],
        ),
    ] {
        let path = data_file(file);
        let text = inspect(&path);
        for e in expect {
            assert!(text.contains(e), "{file}: missing {e:?} in\n{text}");
        }
    }
}

#[test]
fn mesh_scenes_render_and_agree_with_the_reference() {
    use arbvis::techniques::cellproj::prepare::prepare;
    use arbvis::techniques::cellproj::reference::{agreement, reference, silhouette_pixels};
    let h = headless(Backend::Egl);
    for file in ["post", "bracket", "can", "tetrahedron"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/data/{file}.toml"));
        let mut scene = Scene::load(&path).unwrap();
        scene.size = [96, 72];
        let TechniqueScene::Cellproj(c) = &scene.technique else {
            panic!("{file} is not a cell-projection scene");
        };
        let mut unshaded = (**c).clone();
        unshaded.shading = false;
        let c = unshaded;
        scene.technique = TechniqueScene::Cellproj(Box::new(c.clone()));
        let r = render_on(&h, &scene).unwrap();
        let prepared = prepare(&c, &scene.base).unwrap();
        // The scenes write isovalues in the scalar's units; the reference takes them normalized.
        let c = c.normalized(prepared.scalar_range);
        let hits = reference(&prepared, &c.isovalues, &scene.camera, scene.size);
        let expected = hits.iter().filter(|h| h.is_some()).count();
        assert!(
            expected > 40,
            "{file}: the scene shows isosurfaces ({expected} pixels)"
        );
        let silhouette = silhouette_pixels(&prepared, &scene.camera, scene.size, 1.5);
        let a = agreement(
            &r.image,
            None,
            &hits,
            &c.sorted_isovalues(),
            scene.background,
            &silhouette,
        );
        // Precise: every interior pixel on the seed grids; on real meshes with slivers
        // (post.vtk has 2,200) 99 %. Faithful (can): the table's quantization, 98 %.
        let bar = if scene.fidelity == arbvis::scene::Fidelity::Precise {
            0.99
        } else {
            0.98
        };
        assert!(a.interior_fraction() >= bar, "{file}: {a:?}");
    }
}

#[test]
fn point_cloud_scenes_render() {
    let h = headless(Backend::Egl);
    for file in ["autzen", "bunny"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/data/{file}.toml"));
        let mut scene = Scene::load(&path).unwrap();
        scene.size = [160, 120];
        let r = render_on(&h, &scene).unwrap();
        let bg = scene.background;
        let lit = r
            .image
            .data
            .chunks_exact(4)
            .filter(|p| (0..3).any(|c| (p[c] - bg[c]).abs() > 0.05))
            .count();
        // The cloud covers a good part of the picture, in colours (autzen's 8-bit RGB in
        // 16-bit fields once came out black).
        assert!(lit > 160 * 120 / 10, "{file}: {lit} pixels drawn");
    }
}
