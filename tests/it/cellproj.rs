//! Cell projection end to end: ARB vs GLSL, GPU vs the f64 ray-cast reference (precise
//! and faithful, orthographic and perspective, both seed fields), depth at the crossing,
//! the extremes of DESIGN §4, and what gets built.

use crate::common;

use arbvis::camera::{Camera, Projection};
use arbvis::gl::{Backend, Headless, ProgramChoice, ProgramKind, TargetFormat};
use arbvis::image::Image;
use arbvis::mesh::grid::{generate, Field, GridSpec};
use arbvis::mesh::scalars::ScalarSpec;
use arbvis::mesh::Mesh;
use arbvis::render::render_on;
use arbvis::scene::{Fidelity, Scene, TechniqueScene};
use arbvis::techniques::cellproj::prepare::{from_mesh, Prepared};
use arbvis::techniques::cellproj::reference::{agreement, reference, silhouette_pixels, Agreement};
use arbvis::techniques::cellproj::{CellprojRenderer, CellprojScene, Isovalue, IsovalueUnits};
use arbvis::techniques::Renderer;
use arbvis::vocab::Interpolation;
use common::frame::Shot;
use common::headless;

const BACKGROUND: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

fn seed_isovalues() -> Vec<Isovalue> {
    [
        (0.3, [1.0, 0.0, 0.0, 1.0]),
        (0.5, [0.0, 1.0, 0.0, 1.0]),
        (0.9, [0.0, 0.0, 1.0, 1.0]),
    ]
    .map(|(value, color)| Isovalue { value, color })
    .to_vec()
}

fn params(field: Field, isovalues: Vec<Isovalue>) -> CellprojScene {
    CellprojScene {
        mesh: arbvis::mesh::MeshSource::Grid(GridSpec {
            points: [17, 17, 17],
            field,
        }),
        scalars: ScalarSpec::default(),
        mode: Default::default(),
        volume: None,
        isovalues,
        isovalue_units: IsovalueUnits::Normalized,
        exit: Default::default(),
        table_size: 256,
        shading: false,
        active_only: true,
        order: Default::default(),
        depth: Default::default(),
        interpolation: Default::default(),
    }
}

fn prepared_of(mesh: &Mesh) -> Prepared {
    let s = ScalarSpec::default().evaluate(mesh).unwrap();
    from_mesh(mesh, &s.values, s.name, s.range).unwrap()
}

fn seed_mesh(field: Field) -> Prepared {
    prepared_of(
        &generate(&GridSpec {
            points: [17, 17, 17],
            field,
        })
        .unwrap(),
    )
}

/// A rotated camera that sees all three axes (no face is edge-on).
fn camera(projection: Projection) -> Camera {
    common::seed_grid_camera(projection)
}

/// Draw `prepared` and read colour and depth.
fn draw(
    h: &Headless,
    params: &CellprojScene,
    prepared: Prepared,
    fidelity: Fidelity,
    kind: ProgramKind,
    camera: Camera,
    size: [u32; 2],
) -> (Image, Vec<f32>) {
    let gpu = h.gpu();
    let mut r = CellprojRenderer::from_prepared(gpu, kind, fidelity, params, prepared).unwrap();
    Shot::new(size, TargetFormat::Rgba8)
        .with_depth()
        .on(BACKGROUND)
        .draw_with_depth(gpu, &mut r, &camera)
}

/// [`draw`] in precise mode with GLSL (the only precise programs).
fn draw_precise(
    h: &Headless,
    params: &CellprojScene,
    prepared: Prepared,
    camera: Camera,
    size: [u32; 2],
) -> (Image, Vec<f32>) {
    draw(
        h,
        params,
        prepared,
        Fidelity::Precise,
        ProgramKind::Glsl,
        camera,
        size,
    )
}

fn score(
    prepared: &Prepared,
    isovalues: &[Isovalue],
    image: &Image,
    depth: &[f32],
    camera: &Camera,
    size: [u32; 2],
) -> Agreement {
    let hits = reference(prepared, isovalues, camera, size);
    let mut sorted = isovalues.to_vec();
    sorted.sort_by(|a, b| a.value.total_cmp(&b.value));
    // Within 1.5 px of a boundary edge the colour depends on which side of the
    // silhouette a pixel centre falls, and rasterization rules decide that.
    let silhouette = silhouette_pixels(prepared, camera, size, 1.5);
    agreement(image, Some(depth), &hits, &sorted, BACKGROUND, &silhouette)
}

const SIZE: [u32; 2] = [160, 120];

/// The seed's mesh and isovalues on `field`, drawn from the rotated camera in
/// `projection` and scored against the f64 reference.
fn seed_agreement(
    h: &Headless,
    field: Field,
    projection: Projection,
    fidelity: Fidelity,
    kind: ProgramKind,
    interpolation: Interpolation,
) -> Agreement {
    let isos = seed_isovalues();
    let p = CellprojScene {
        interpolation,
        ..params(field, isos.clone())
    };
    let prepared = seed_mesh(field);
    let cam = camera(projection);
    let (image, depth) = draw(h, &p, prepared.clone(), fidelity, kind, cam, SIZE);
    score(&prepared, &isos, &image, &depth, &cam, SIZE)
}

#[test]
fn precise_agrees_with_the_reference_on_both_seed_fields() {
    let h = headless(Backend::Egl);
    // Auto: the interpolated entry on llvmpipe (it interpolates from the true vertices),
    // the pixel's own ray where the rasterizer snaps them; Shader: the pixel's ray always.
    for interpolation in [Interpolation::Auto, Interpolation::Shader] {
        for field in [Field::Oblique, Field::Spherical, Field::Planar] {
            for projection in [Projection::Orthographic, Projection::Perspective] {
                let (precise, glsl) = (Fidelity::Precise, ProgramKind::Glsl);
                let a = seed_agreement(&h, field, projection, precise, glsl, interpolation);
                let what = format!("{field:?} {projection:?} {interpolation:?}");
                // The bar is 99 % of interior pixels; measured on llvmpipe and on
                // an NVIDIA H100: every one but one. 99.9 % leaves room for rounding.
                eprintln!("{what}: {a:?}");
                assert!(a.interior_fraction() >= 0.999, "{what}: {a:?}");
                // Depth at the crossing: f32 arithmetic and a 24-bit buffer (6e-8) against
                // f64. Measured at most 4.8e-6 of the depth range on llvmpipe from the
                // interpolated entry, 1.0e-5 from the pixel's ray (a derivative-made
                // plane); on an NVIDIA H100 3.3e-6 from the pixel's ray, where the
                // interpolated entry had been 7e-4 off. 2e-5 holds all.
                assert!(a.max_depth_error < 2e-5, "{what}: {a:?}");
            }
        }
    }
}

#[test]
fn faithful_agrees_with_the_reference_within_its_table_quantization() {
    let h = headless(Backend::Egl);
    for field in [Field::Oblique, Field::Spherical] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let a = seed_agreement(
                &h,
                field,
                projection,
                Fidelity::Faithful,
                ProgramKind::Arb,
                Default::default(),
            );
            // The 256² table decides crossings at texel centres: pixels whose ray passes
            // within 1/256 of an isovalue inside a tetrahedron may flip. Measured above
            // 99.3-99.9 % on these fields.
            eprintln!("faithful {field:?} {projection:?}: {a:?}");
            assert!(
                a.interior_fraction() >= 0.985,
                "{field:?} {projection:?}: {a:?}"
            );
        }
    }
}

#[test]
fn arb_and_glsl_ports_agree() {
    let h = headless(Backend::Egl);
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let isos = seed_isovalues();
        let p = params(Field::Spherical, isos);
        let prepared = seed_mesh(Field::Spherical);
        let cam = camera(projection);
        let draw_kind = |kind| {
            draw(
                &h,
                &p,
                prepared.clone(),
                Fidelity::Faithful,
                kind,
                cam,
                SIZE,
            )
            .0
        };
        let (arb, glsl) = (draw_kind(ProgramKind::Arb), draw_kind(ProgramKind::Glsl));
        let d = arb.compare(&glsl, 0.0).unwrap();
        // Same arithmetic in f32, but RCP vs 1/x and the order of operations may move a
        // fragment's sb across a texel boundary of the table: a few pixels may differ.
        let total = (SIZE[0] * SIZE[1]) as usize;
        assert!(
            d.pixels_over * 1000 <= total,
            "{projection:?}: {} of {total} pixels differ",
            d.pixels_over
        );
    }
}

#[test]
fn isovalues_exactly_at_vertex_values_are_drawn_whole_in_precise_mode() {
    // x on the 17-point grid: 0.5 is exactly the middle layer of vertices, so every ray
    // crossing it leaves one tetrahedron and enters the next exactly there.
    let h = headless(Backend::Egl);
    let isos = vec![Isovalue {
        value: 0.5,
        color: [0.0, 1.0, 0.0, 1.0],
    }];
    let p = params(Field::Planar, isos.clone());
    let prepared = seed_mesh(Field::Planar);
    let cam = camera(Projection::Orthographic);
    let (image, depth) = draw_precise(&h, &p, prepared.clone(), cam, SIZE);
    let a = score(&prepared, &isos, &image, &depth, &cam, SIZE);
    assert!(a.interior_fraction() >= 0.995, "{a:?}");
}

#[test]
fn far_from_the_origin_the_picture_is_the_same() {
    let h = headless(Backend::Egl);
    let isos = seed_isovalues();
    let p = params(Field::Spherical, isos);
    let mut mesh = generate(&GridSpec {
        points: [9, 9, 9],
        field: Field::Spherical,
    })
    .unwrap();
    let near = prepared_of(&mesh);
    // 1e6 offsets with the grid scaled to millimetres: f32 alone could not hold it.
    for q in &mut mesh.points {
        *q = q.map(|v| 1.0e6 + v * 1e-3);
    }
    let far = prepared_of(&mesh);
    let cam = camera(Projection::Perspective);
    let draw_one = |prepared| draw_precise(&h, &p, prepared, cam, SIZE).0;
    let d = draw_one(near).compare(&draw_one(far), 0.0).unwrap();
    assert_eq!(d.pixels_over, 0, "{d:?}");
}

#[test]
fn extremes_give_finite_documented_pictures() {
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let isos = seed_isovalues();
    // One tetrahedron with the field rising along the view axis (z): every ray through
    // it crosses isovalues, and the pictures show them as the reference does.
    let one = Mesh {
        points: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        tets: vec![[0, 1, 2, 3]],
        ..Mesh::default()
    };
    let one = from_mesh(&one, &[0.1, 0.0, 0.2, 1.0], "s".into(), [0.0, 1.0]).unwrap();
    let p = params(Field::Spherical, isos.clone());
    for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
        let kind = if fidelity == Fidelity::Precise {
            ProgramKind::Glsl
        } else {
            ProgramKind::Arb
        };
        let cam = Camera {
            projection: Projection::Perspective,
            rotation: [0.1, 0.1, 0.0, 1.0],
            ..Camera::default()
        };
        let (image, _) = draw(&h, &p, one.clone(), fidelity, kind, cam, SIZE);
        let hits = reference(&one, &isos, &cam, SIZE);
        let drawn = image
            .data
            .chunks_exact(4)
            .filter(|px| px[..3] != BACKGROUND[..3])
            .count();
        let expected = hits.iter().filter(|h| h.is_some()).count();
        assert!(expected > 100, "the tetrahedron shows isosurfaces");
        assert!(
            (drawn as f64 - expected as f64).abs() <= 0.05 * expected as f64,
            "{fidelity:?}: drew {drawn}, reference {expected}"
        );
    }
    // A constant field (sf = sb everywhere) and isovalues outside the range draw nothing.
    for (field, values) in [
        (Field::Spherical, vec![1.5, -0.5]),
        (Field::Planar, vec![0.5]),
    ] {
        let mut mesh = generate(&GridSpec {
            points: [5, 5, 5],
            field,
        })
        .unwrap();
        if values == [0.5] {
            mesh.point_arrays[0]
                .values
                .iter_mut()
                .for_each(|v| *v = 0.5);
        }
        let isos: Vec<Isovalue> = values
            .iter()
            .map(|&value| Isovalue {
                value,
                color: [1.0; 4],
            })
            .collect();
        let p = params(field, isos);
        for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
            let kind = if fidelity == Fidelity::Precise {
                ProgramKind::Glsl
            } else {
                ProgramKind::Arb
            };
            let (image, _) = draw(
                &h,
                &p,
                prepared_of(&mesh),
                fidelity,
                kind,
                camera(Projection::Orthographic),
                [32, 32],
            );
            assert!(
                image
                    .data
                    .chunks_exact(4)
                    .all(|px| px[..3] == BACKGROUND[..3]),
                "{field:?} {values:?} {fidelity:?}"
            );
        }
    }
    // Grazing rays: looking straight down an axis of the grid, half the faces are
    // edge-on (dot(D, n) = 0). Faithful divides by zero as the seed did; precise skips
    // those planes. Both stay finite and precise still agrees with the reference.
    let axis = Camera {
        projection: Projection::Orthographic,
        zoom: 0.9,
        ..Camera::default()
    };
    let isos = seed_isovalues();
    let p = params(Field::Oblique, isos.clone());
    let prepared = seed_mesh(Field::Oblique);
    let (image, depth) = draw_precise(&h, &p, prepared.clone(), axis, SIZE);
    let a = score(&prepared, &isos, &image, &depth, &axis, SIZE);
    assert!(a.interior_fraction() >= 0.99, "axis view: {a:?}");
    assert!(image.data.iter().all(|v| v.is_finite()));
    let _ = gpu;
}

#[test]
fn flat_and_sliver_tetrahedra_are_counted_and_harmless() {
    let mesh = Mesh {
        points: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.5, 0.0], // on the face 0-1-2's plane: a flat tetrahedron with 0, 1, 2
            [1.0, 1.0, 1e-7], // a sliver with 1, 2, 3? no: nearly flat with 0, 1, 2
        ],
        tets: vec![[0, 1, 2, 3], [0, 1, 4, 2], [0, 1, 5, 2]],
        ..Mesh::default()
    };
    let p = from_mesh(
        &mesh,
        &[0.0, 1.0, 0.2, 0.6, 0.5, 0.7],
        "s".into(),
        [0.0, 1.0],
    )
    .unwrap();
    assert!(p.quality.flat >= 1, "{:?}", p.quality);
    assert!(p.quality.flat + p.quality.slivers >= 2, "{:?}", p.quality);
    let h = headless(Backend::Egl);
    let isos = seed_isovalues();
    let params = params(Field::Spherical, isos);
    let (image, _) = draw_precise(&h, &params, p, camera(Projection::Perspective), [64, 48]);
    assert!(image.data.iter().all(|v| v.is_finite()));
}

#[test]
fn the_scene_builds_only_what_it_draws_and_isovalue_edits_touch_only_the_table() {
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("cellproj-spherical").unwrap();
    scene.size = [64, 48];
    scene.programs = ProgramChoice::Arb;
    let r = render_on(&h, &scene).unwrap();
    let kinds: Vec<&str> = r.resources.iter().map(|r| r.kind).collect();
    assert_eq!(
        kinds,
        [
            "buffer",
            "texture",
            "buffer",
            "framebuffer",
            "renderbuffer",
            "program"
        ],
        "{:?}",
        r.resources
    );
    assert_eq!(
        r.resources[0].bytes,
        24_576 * 12 * 19 * 4,
        "12 vertices of 19 floats per tetrahedron"
    );
    // The active tetrahedra of the three spherical shells: a quarter of the mesh.
    let active = r.resources[2].bytes as usize / (12 * 4);
    assert!(
        (5_000..8_000).contains(&active),
        "{active} active tetrahedra"
    );
    // An edit of the isovalues: the renderer rewrites its table and nothing else.
    let gpu = h.gpu();
    let TechniqueScene::Cellproj(c) = &scene.technique else {
        unreachable!()
    };
    let before = gpu.resources().len();
    let mut r =
        CellprojRenderer::new(gpu, ProgramKind::Arb, Fidelity::Faithful, c, &scene.base).unwrap();
    let built = gpu.resources().len() - before;
    let mut edited = (**c).clone();
    edited.isovalues[0].value = 0.35;
    edited.isovalues[1].color = [1.0, 1.0, 0.0, 1.0];
    r.update(gpu, arbvis::techniques::Params::of(&edited))
        .unwrap();
    let after: Vec<_> = gpu.resources()[before + built..].to_vec();
    assert_eq!(after.len(), 1, "{after:?}");
    assert_eq!(after[0].kind, "texture");
}

#[test]
fn precise_runs_glsl_and_per_vertex_exit_needs_an_orthographic_camera() {
    let h = headless(Backend::Egl);
    let mut scene = Scene::demo("cellproj-planar").unwrap();
    scene.size = [32, 24];
    scene.fidelity = Fidelity::Precise;
    scene.programs = ProgramChoice::Arb;
    // Precise runs GLSL whatever is asked (it loops over isovalues), and says so.
    assert_eq!(
        render_on(&h, &scene).unwrap().program_kind,
        ProgramKind::Glsl
    );
    scene.fidelity = Fidelity::Faithful;
    scene.camera.projection = Projection::Perspective;
    if let TechniqueScene::Cellproj(c) = &mut scene.technique {
        c.exit = arbvis::techniques::cellproj::Exit::Vertex;
    }
    let e = render_on(&h, &scene).err().unwrap().to_string();
    assert!(e.contains("orthographic"), "{e}");
}

#[test]
fn view_order_and_entry_depth_draw_the_same_picture_from_fewer_vertices() {
    use arbvis::techniques::cellproj::{Depth, Order};
    let h = headless(Backend::Egl);
    let isos = seed_isovalues();
    for (fidelity, kind, projection) in [
        (
            Fidelity::Faithful,
            ProgramKind::Arb,
            Projection::Orthographic,
        ),
        (
            Fidelity::Precise,
            ProgramKind::Glsl,
            Projection::Orthographic,
        ),
        (
            Fidelity::Precise,
            ProgramKind::Glsl,
            Projection::Perspective,
        ),
    ] {
        let prepared = seed_mesh(Field::Oblique);
        let cam = camera(projection);
        let base = params(Field::Oblique, isos.clone());
        let (want, _) = draw(&h, &base, prepared.clone(), fidelity, kind, cam, SIZE);
        let fast = CellprojScene {
            order: Order::View,
            depth: Depth::Entry,
            ..base.clone()
        };
        let (got, _) = draw(&h, &fast, prepared.clone(), fidelity, kind, cam, SIZE);
        // In a mesh of non-overlapping tetrahedra the nearest entry face holds the nearest
        // crossing, so colours match pixel for pixel. The one freedom is a crossing on a
        // shared face, drawn by both neighbours at equal depth, where draw order picks one
        // of two (equal or nearly equal) colours. Measured on llvmpipe: 0 pixels in all
        // three settings; 0.5 % leaves room for a driver that rounds those ties otherwise.
        let differing = want
            .data
            .chunks_exact(4)
            .zip(got.data.chunks_exact(4))
            .filter(|(a, b)| {
                a.iter()
                    .zip(b.iter())
                    .any(|(x, y)| (x - y).abs() > 0.5 / 255.0)
            })
            .count();
        let total = (SIZE[0] * SIZE[1]) as usize;
        eprintln!("{fidelity:?} {projection:?}: {differing} of {total} pixels differ");
        assert!(
            differing * 200 <= total,
            "{fidelity:?} {projection:?}: {differing} of {total} pixels differ"
        );
        // And it sent fewer vertices: only faces that may face the viewer (about half).
        let gpu = h.gpu();
        let mut r =
            CellprojRenderer::from_prepared(gpu, kind, fidelity, &fast, prepared.clone()).unwrap();
        Shot::new(SIZE, TargetFormat::Rgba8)
            .with_depth()
            .draw(gpu, &mut r, &cam);
        let all = 12 * r.drawn_tets();
        assert!(
            r.drawn_vertices() < all * 3 / 5,
            "{} of {all} vertices",
            r.drawn_vertices()
        );
    }
}

/// Of the interior pixels (away from the silhouette) where the f64 reference crosses an
/// isovalue, the fraction `image` leaves at the background; and how many there are.
fn lost_fraction(
    prepared: &Prepared,
    isos: &[Isovalue],
    image: &Image,
    camera: &Camera,
    size: [u32; 2],
) -> (f64, usize) {
    let hits = reference(prepared, isos, camera, size);
    let silhouette = silhouette_pixels(prepared, camera, size, 1.5);
    let (mut crossed, mut lost) = (0usize, 0usize);
    for (n, px) in image.data.chunks_exact(4).enumerate() {
        if hits[n].is_some() && !silhouette[n] {
            crossed += 1;
            lost += (px[..3] == BACKGROUND[..3]) as usize;
        }
    }
    (lost as f64 / crossed.max(1) as f64, crossed)
}

/// Views of the planar field's isosurface x = 0.5 from several sides (none edge-on).
fn planar_views() -> Vec<Camera> {
    let rotations = [
        [0.2391, 0.3696, 0.0990, 0.8924],
        [0.0, 0.3827, 0.0, 0.9239],
        [0.1, 0.5, 0.0, 0.86],
        [-0.3, 0.2, 0.4, 0.84],
        [0.35, -0.45, 0.1, 0.81],
        [0.05, 0.62, -0.2, 0.75],
    ];
    let mut views = Vec::new();
    for projection in [Projection::Orthographic, Projection::Perspective] {
        for r in rotations {
            let norm = r.iter().map(|v: &f64| v * v).sum::<f64>().sqrt();
            views.push(Camera {
                projection,
                rotation: r.map(|v| v / norm),
                zoom: 0.9,
                ..Camera::default()
            });
        }
    }
    views
}

#[test]
fn faithful_loses_isosurfaces_on_shared_faces_as_the_seeds_table_does() {
    // x on the 17-point grid: 0.5 is the middle layer of vertices, so its isosurface lies
    // on faces shared by two tetrahedra. The table decides crossings at texel centres
    // (sf, sb) = ((i + 1/2) / 256, (j + 1/2) / 256): the tetrahedron behind the plane
    // draws it only if its extrapolated exit scalar sb rounds to at least 0.5, the one
    // in front only if its interpolated entry sf rounds below 0.5; where the first
    // rounds down and the second up, neither does.
    let h = headless(Backend::Egl);
    let prepared = seed_mesh(Field::Planar);
    for offset in [0.0, 1e-3, 1e-2] {
        let isos = vec![Isovalue {
            value: 0.5 + offset,
            color: [0.0, 1.0, 0.0, 1.0],
        }];
        let p = params(Field::Planar, isos.clone());
        let mut faithful = Vec::new();
        for cam in planar_views() {
            let (image, _) = draw(
                &h,
                &p,
                prepared.clone(),
                Fidelity::Faithful,
                ProgramKind::Arb,
                cam,
                SIZE,
            );
            let (lost, crossed) = lost_fraction(&prepared, &isos, &image, &cam, SIZE);
            let (image, _) = draw_precise(&h, &p, prepared.clone(), cam, SIZE);
            let (precise, _) = lost_fraction(&prepared, &isos, &image, &cam, SIZE);
            eprintln!(
                "iso 0.5 + {offset}, {:?} {:?}: {crossed} pixels cross it; faithful loses \
                 {lost:.4}, precise {precise:.4}",
                cam.projection, cam.rotation
            );
            // Precise finds the exact crossing (the half-open rule gives it to exactly
            // one of the two tetrahedra). Measured: none lost but in one view, 5 of
            // 10,020 pixels (5e-4); 2e-3 is that with room, far below faithful's loss.
            assert!(precise < 2e-3, "{offset} {cam:?}: precise lost {precise}");
            assert!(
                crossed > 2000,
                "{cam:?}: the isosurface covers {crossed} pixels"
            );
            faithful.push(lost);
        }
        let worst = faithful.iter().copied().fold(0.0, f64::max);
        let best = faithful.iter().copied().fold(1.0, f64::min);
        eprintln!("iso 0.5 + {offset}: faithful loses {best:.4} to {worst:.4}");
        if offset < 1.0 / 512.0 && !common::faithful_models_hold(&h, "the seed table's loss") {
            // Another driver's table reads (NVIDIA: 8-bit filter weights) lose more of
            // the face (measured up to 91 % on an H100): the quirk shows, its size is the
            // hardware's.
            assert!(worst >= 0.2, "{offset}: worst {worst}");
        } else if offset < 1.0 / 512.0 {
            // On the face, or nearer to it than half a texel (the table cannot tell them
            // apart): measured 0 to 43 % (0.5) and 0.03 to 43 % (0.5 + 1e-3) over these
            // twelve views, a quarter to two fifths in all but one. Pinned loosely: a
            // fifth or more in the worst view, at most 3 % in the best, never over half.
            assert!((0.2..=0.5).contains(&worst), "{offset}: worst {worst}");
            assert!(best <= 0.03, "{offset}: best {best}");
        } else {
            // A texel and more off the face, the surface lies inside tetrahedra and only
            // the table's quantization is left (as in
            // faithful_agrees_with_the_reference_within_its_table_quantization):
            // measured at most 0.33 % lost.
            assert!(worst <= 0.01, "{offset}: worst {worst}");
        }
    }
}
