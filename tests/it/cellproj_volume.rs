//! Volume rendering by cell projection (issue 16) end to end, on small meshes and images:
//! precise (the neighbour walk) and faithful (pre-integrated table, RGBA8) against the
//! f64 reference, ARB against GLSL, the order on a non-convex mesh, both isosurfaces and
//! volume, the extremes, and malformed transfer functions.

use crate::common;

use arbvis::camera::{Camera, Projection};
use arbvis::gl::{Backend, Headless, ProgramKind, Surface};
use arbvis::image::Image;
use arbvis::mesh::grid::{generate, Field, GridSpec};
use arbvis::mesh::scalars::ScalarSpec;
use arbvis::mesh::Mesh;
use arbvis::scene::{Fidelity, Scene};
use arbvis::techniques::cellproj::prepare::{from_mesh, Prepared};
use arbvis::techniques::cellproj::reference::silhouette_pixels;
use arbvis::techniques::cellproj::transfer::{Precise, Sort, VolumeSpec};
use arbvis::techniques::cellproj::volume_reference::{interior_mask, reference, score};
use arbvis::techniques::cellproj::{
    CellprojRenderer, CellprojScene, Exit, Isovalue, IsovalueUnits, Mode,
};
use arbvis::techniques::Renderer;
use common::frame::Shot;
use common::headless;

const BACKGROUND: [f32; 4] = [0.1, 0.1, 0.15, 1.0];
const SIZE: [u32; 2] = [96, 72];

pub(crate) fn prepared_of(mesh: &Mesh) -> Prepared {
    let s = ScalarSpec::default().evaluate(mesh).unwrap();
    from_mesh(mesh, &s.values, s.name, s.range).unwrap()
}

pub(crate) fn grid(n: usize, field: Field) -> Mesh {
    generate(&GridSpec {
        points: [n; 3],
        field,
    })
    .unwrap()
}

/// A transfer function of control points `[s, r, g, b, a]`, the rest default.
pub(crate) fn points_spec(points: &[[f64; 5]], unit_distance: f64, sort: Sort) -> VolumeSpec {
    VolumeSpec {
        points: points.to_vec(),
        unit_distance,
        sort,
        ..VolumeSpec::default()
    }
}

/// A transfer function with a narrow bright band (the kind pre-integration exists for)
/// over a faint ramp; unit distance in the grid's units (the grid spans [0, 1]).
pub(crate) fn spec(sort: Sort) -> VolumeSpec {
    let points = [
        [0.0, 0.1, 0.2, 0.9, 0.0],
        [0.45, 0.2, 0.6, 0.8, 0.3],
        [0.5, 1.0, 0.9, 0.2, 1.0],
        [0.55, 0.9, 0.3, 0.1, 0.3],
        [1.0, 0.8, 0.1, 0.1, 0.6],
    ];
    points_spec(&points, 0.25, sort)
}

pub(crate) fn scene(mode: Mode, volume: VolumeSpec, isovalues: Vec<Isovalue>) -> CellprojScene {
    CellprojScene {
        mesh: arbvis::mesh::MeshSource::Grid(GridSpec {
            points: [9, 9, 9],
            field: Field::Spherical,
        }),
        scalars: ScalarSpec::default(),
        mode,
        isovalues,
        isovalue_units: IsovalueUnits::Normalized,
        volume: Some(volume),
        exit: Default::default(),
        table_size: 256,
        shading: false,
        active_only: true,
        order: Default::default(),
        depth: Default::default(),
        interpolation: Default::default(),
    }
}

/// A rotated camera that sees all three axes (no face is edge-on).
pub(crate) fn camera(projection: Projection) -> Camera {
    common::seed_grid_camera(projection)
}

pub(crate) fn draw(
    h: &Headless,
    params: &CellprojScene,
    prepared: &Prepared,
    fidelity: Fidelity,
    kind: ProgramKind,
    camera: Camera,
) -> Image {
    draw_counting_entries(h, params, prepared, fidelity, kind, camera).0
}

/// How the tests take a frame: their size, the target format of `fidelity` (RGBA8
/// faithful, RGBA32F precise) with depth, their background.
fn shot(fidelity: Fidelity) -> Shot {
    Shot::for_fidelity(SIZE, fidelity)
        .with_depth()
        .on(BACKGROUND)
}

/// A GLSL renderer of `params` on `prepared`.
fn glsl_renderer(
    gpu: &arbvis::gl::Gpu,
    fidelity: Fidelity,
    params: &CellprojScene,
    prepared: &Prepared,
) -> CellprojRenderer {
    CellprojRenderer::from_prepared(gpu, ProgramKind::Glsl, fidelity, params, prepared.clone())
        .unwrap()
}

/// [`draw`], and the entry layers the precise walk peeled.
pub(crate) fn draw_counting_entries(
    h: &Headless,
    params: &CellprojScene,
    prepared: &Prepared,
    fidelity: Fidelity,
    kind: ProgramKind,
    camera: Camera,
) -> (Image, usize) {
    let gpu = h.gpu();
    let mut r =
        CellprojRenderer::from_prepared(gpu, kind, fidelity, params, prepared.clone()).unwrap();
    let image = shot(fidelity).draw(gpu, &mut r, &camera);
    (image, r.volume().map_or(0, |v| v.entries()))
}

/// The f64 reference picture of a scene (its volume, and its isosurfaces in `mode = "both"`).
pub(crate) fn reference_image(
    params: &CellprojScene,
    prepared: &Prepared,
    camera: Camera,
) -> Image {
    let spec = params.volume_spec();
    let tf = spec
        .build(std::path::Path::new("."), prepared.scale)
        .unwrap();
    let isos = if params.mode == Mode::Both {
        params.isovalues.clone()
    } else {
        Vec::new()
    };
    let bg = BACKGROUND.map(|v| v as f64);
    reference(prepared, &tf, &isos, &camera, SIZE, bg)
}

/// ((RMSE, max) over the image, (RMSE, max) over interior pixels) against the reference.
pub(crate) fn scored(
    params: &CellprojScene,
    prepared: &Prepared,
    image: &Image,
    camera: Camera,
) -> ((f64, f64), (f64, f64)) {
    let want = reference_image(params, prepared, camera);
    let silhouette = silhouette_pixels(prepared, &camera, SIZE, 1.5);
    let mask = interior_mask(prepared, &camera, SIZE, &silhouette);
    score(image, &want, &mask)
}

#[test]
fn precise_matches_the_reference_in_both_projections() {
    let h = headless(Backend::Egl);
    let mesh = grid(9, Field::Spherical);
    let prepared = prepared_of(&mesh);
    use arbvis::techniques::cellproj::transfer::Precise;
    for (method, projection) in [
        (Precise::Walk, Projection::Orthographic),
        (Precise::Walk, Projection::Perspective),
        (Precise::Projected, Projection::Orthographic),
        (Precise::Projected, Projection::Perspective),
    ] {
        // The projected variant is exact where its order is: on this convex grid.
        let p = scene(
            Mode::Volume,
            VolumeSpec {
                precise: method,
                ..spec(Sort::Mpvonc)
            },
            Vec::new(),
        );
        let cam = camera(projection);
        let image = draw(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
        let (all, inner) = scored(&p, &prepared, &image, cam);
        eprintln!("precise {method:?} {projection:?}: all {all:?} interior {inner:?}");
        // f32 arithmetic, the closed form's fits (1e-7) and early termination at 2^-12
        // transmittance (at most 2.4e-4 of a channel): the goal is 1e-3 RMSE.
        assert!(
            all.0 < 1e-3 && inner.0 < 1e-3,
            "{projection:?}: {all:?} {inner:?}"
        );
        assert!(all.1 < 5e-3, "{projection:?}: largest {all:?}");
    }
}

/// Precise `table`: the faithful projection through a float table into a float target.
/// Its error is the table's linear interpolation alone (no 8-bit entries, no 8-bit
/// blending): below faithful's at every table size, and falling as the table grows.
#[test]
fn precise_table_is_faithful_without_its_8_bit_losses() {
    use arbvis::techniques::cellproj::transfer::Precise;
    let h = headless(Backend::Egl);
    let prepared = prepared_of(&grid(9, Field::Spherical));
    let mut last = f64::INFINITY;
    for (n, projection) in [
        (32u32, Projection::Orthographic),
        (128, Projection::Perspective),
        (256, Projection::Orthographic),
    ] {
        let cam = camera(projection);
        let with = |precise| VolumeSpec {
            precise,
            table_size: [n, n / 2],
            ..spec(Sort::Mpvonc)
        };
        let table = scene(Mode::Volume, with(Precise::Table), Vec::new());
        let image = draw(
            &h,
            &table,
            &prepared,
            Fidelity::Precise,
            ProgramKind::Glsl,
            cam,
        );
        let (all, inner) = scored(&table, &prepared, &image, cam);
        let faithful = scene(Mode::Volume, with(Precise::Walk), Vec::new());
        let f = draw(
            &h,
            &faithful,
            &prepared,
            Fidelity::Faithful,
            ProgramKind::Glsl,
            cam,
        );
        let (fall, _) = scored(&faithful, &prepared, &f, cam);
        eprintln!("table {n} {projection:?}: all {all:?} interior {inner:?}; faithful {fall:?}");
        assert!(
            all.0 < fall.0,
            "{n}: table {all:?} not below faithful {fall:?}"
        );
        // The band (0.45..0.55 of the scalar) spans n/10 texels: at 32 a few texels, its
        // peak cut by interpolation (RMSE 0.0057 measured); at 256 some 25, the error a
        // few ten-thousandths (3.5e-4 measured, with the guarded exit).
        if projection == Projection::Orthographic {
            assert!(
                all.0 < last,
                "{n}: {all:?} not below the smaller table's {last}"
            );
            last = all.0;
        }
    }
    // Three times the measured 3.5e-4 (other drivers round the float table's reads
    // differently); a wrong segment on one pixel in 6912 alone would be ~2e-3.
    assert!(last < 1e-3, "256² x 128: RMSE {last}");
}

#[test]
fn faithful_is_within_its_table_and_target_quantization_and_arb_equals_glsl() {
    let h = headless(Backend::Egl);
    let mesh = grid(9, Field::Spherical);
    let prepared = prepared_of(&mesh);
    let base = scene(Mode::Volume, spec(Sort::Mpvonc), Vec::new());
    let per_fragment = CellprojScene {
        exit: Exit::Fragment,
        ..base.clone()
    };
    // Orthographic draws with the exit per vertex (the seed's orthographic case) unless
    // the scene asks for it per fragment; perspective per fragment.
    let cases = [
        (
            "orthographic, exit per vertex",
            &base,
            Projection::Orthographic,
        ),
        (
            "orthographic, exit per fragment",
            &per_fragment,
            Projection::Orthographic,
        ),
        (
            "perspective, exit per fragment",
            &base,
            Projection::Perspective,
        ),
    ];
    let mut ortho = Vec::new();
    for (name, p, projection) in cases {
        let cam = camera(projection);
        let arb = draw(&h, p, &prepared, Fidelity::Faithful, ProgramKind::Arb, cam);
        let glsl = draw(&h, p, &prepared, Fidelity::Faithful, ProgramKind::Glsl, cam);
        let (all, inner) = scored(p, &prepared, &arb, cam);
        eprintln!("faithful {name}: all {all:?} interior {inner:?}");
        // 8-bit table entries (1/510 each), linear interpolation across a 128 x 128 x 64
        // table whose band (0.45..0.55) spans 13 texels, and about 16 segments per ray
        // each rounded to 8 bits when blended: a few levels of RMSE. Measured on
        // llvmpipe: see the printout; 0.03 leaves room.
        assert!(all.0 < 0.03, "{name}: {all:?}");
        let d = arb.compare(&glsl, 2.0 / 255.0).unwrap();
        // Same arithmetic in f32 (RCP/RSQ against 1/x and length): a level on a few
        // pixels.
        assert!(
            d.pixels_over * 100 <= (SIZE[0] * SIZE[1]) as usize,
            "{name}: {} pixels differ by more than 2 levels",
            d.pixels_over
        );
        if projection == Projection::Orthographic {
            ortho.push(arb);
        }
    }
    // The same exit two ways: interpolated t_i against t_i from an eye 10^6 box units
    // back (a direction off by ~1e-6, then f32 rounding): each segment's table lookup
    // may round to the other 8-bit level, and ~16 segments blend per ray.
    let d = ortho[0].compare(&ortho[1], 3.0 / 255.0).unwrap();
    assert!(
        d.pixels_over * 100 <= (SIZE[0] * SIZE[1]) as usize,
        "exit per vertex and per fragment: {} pixels differ by more than 3 levels (max {})",
        d.pixels_over,
        d.max_abs
    );
    // Per vertex in perspective is the seed's own caveat: refused, not drawn wrong.
    let per_vertex = CellprojScene {
        exit: Exit::Vertex,
        ..base
    };
    let gpu = h.gpu();
    let mut r = CellprojRenderer::from_prepared(
        gpu,
        ProgramKind::Arb,
        Fidelity::Faithful,
        &per_vertex,
        prepared.clone(),
    )
    .unwrap();
    let shot = shot(Fidelity::Faithful);
    let target = shot.target(gpu);
    let frame = shot.frame(&camera(Projection::Perspective));
    let err = r
        .draw(gpu, Surface::Target(&target), &frame)
        .unwrap_err()
        .to_string();
    assert!(err.contains("orthographic"), "{err}");
}

/// The slotted mesh's transfer function, whose colour tells the order: red, green, blue
/// along the scalar, equally dense.
pub(crate) fn slotted_volume(sort: Sort) -> VolumeSpec {
    VolumeSpec {
        points: vec![
            [0.0, 1.0, 0.0, 0.0, 0.6],
            [0.5, 0.0, 1.0, 0.0, 0.6],
            [1.0, 0.0, 0.0, 1.0, 0.6],
        ],
        unit_distance: 0.05,
        ..spec(sort)
    }
}

/// A non-convex mesh of very unequal tetrahedra: the 7³ grid with a slot cut through it
/// and its points stretched (x -> x³, z -> z²), so long thin tetrahedra lie beside short
/// ones and centroids misorder them.
pub(crate) fn slotted() -> Prepared {
    prepared_of(&slotted_mesh())
}

/// [`slotted`]'s mesh.
pub(crate) fn slotted_mesh() -> Mesh {
    let mut mesh = grid(8, Field::Oblique);
    for q in &mut mesh.points {
        q[0] = q[0].powi(3);
        q[2] = q[2].powi(2);
    }
    let points = mesh.points.clone();
    let keep: Vec<bool> = mesh
        .tets
        .iter()
        .map(|t| {
            let c = t.iter().fold([0.0; 3], |a, &i| {
                let p = points[i as usize];
                [a[0] + p[0] / 4.0, a[1] + p[1] / 4.0, a[2] + p[2] / 4.0]
            });
            !(c[1] > 0.3 && c[1] < 0.7 && c[2] > 0.45)
        })
        .collect();
    let mut k = keep.iter();
    mesh.tets.retain(|_| *k.next().unwrap());
    let mut k = keep.iter();
    mesh.source_cell.retain(|_| *k.next().unwrap());
    mesh
}

#[test]
fn on_a_non_convex_mesh_mpvonc_and_precise_are_right_where_centroids_are_not() {
    let h = headless(Backend::Egl);
    let prepared = slotted();
    // A view found by scanning four rotations and both projections (the largest
    // centroid/MPVONC gap), and a transfer function whose colour tells the order: red,
    // green, blue along the scalar, equally dense.
    let cam = Camera {
        rotation: [0.45, -0.3, 0.1, 0.83],
        ..Camera::default()
    };
    let volume = slotted_volume;
    let mut rmse = Vec::new();
    for sort in [Sort::Centroid, Sort::Mpvonc] {
        let p = scene(Mode::Volume, volume(sort), Vec::new());
        let image = draw(&h, &p, &prepared, Fidelity::Faithful, ProgramKind::Arb, cam);
        let (all, _) = scored(&p, &prepared, &image, cam);
        eprintln!("faithful {sort:?}: {all:?}");
        rmse.push(all.0);
    }
    let p = scene(Mode::Volume, volume(Sort::Mpvonc), Vec::new());
    let image = draw(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
    let (all, inner) = scored(&p, &prepared, &image, cam);
    eprintln!("precise: {all:?} {inner:?}");
    // Every pixel within the goal, 1e-3 (f32 arithmetic and the 2^-12 termination), the
    // silhouettes included: one pixel's ray (77, 42) leaves tetrahedron 1287 through the
    // slot's wall and re-enters the mesh in 1285 1.6e-5 of its length later, a re-entry
    // no entry layer holds (rasterization gives its face no sample there); the walk finds
    // it among the boundary tetrahedra around the exit face (it was 0.51 off before).
    assert!(
        all.1 < 1e-3,
        "precise on the slotted mesh: {all:?} {inner:?}"
    );
    // Centroid order draws some thin tetrahedra over the ones in front of them: its
    // error is the table's plus the misordering, MPVONC's the table's (and the slot's
    // few heuristic choices). Measured without the slot: 0.0194 against 0.0085.
    assert!(
        rmse[1] * 1.5 < rmse[0],
        "MPVONC {} vs centroid {}",
        rmse[1],
        rmse[0]
    );
}

#[test]
fn isosurfaces_inside_the_volume() {
    let h = headless(Backend::Egl);
    let prepared = prepared_of(&grid(9, Field::Spherical));
    let isos = vec![Isovalue {
        value: 0.3,
        color: [1.0, 0.9, 0.0, 1.0],
    }];
    let p = scene(Mode::Both, spec(Sort::Mpvonc), isos);
    let cam = camera(Projection::Orthographic);
    let image = draw(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
    let (all, inner) = scored(&p, &prepared, &image, cam);
    eprintln!("both, precise: {all:?} {inner:?}");
    // Where a ray grazes the isosurface the crossing is ill-conditioned (as for the
    // isosurfaces alone): interior RMSE, not the largest error.
    assert!(inner.0 < 2e-3, "{inner:?}");
    // The middle pixel sees the sphere's shell at 0.3: yellow, opaque, under a little
    // volume in front of it.
    let px = image.pixel(SIZE[0] / 2, SIZE[1] / 2);
    assert!(px[0] > 0.6 && px[1] > 0.5 && px[2] < 0.4, "{px:?}");
    // Faithful draws the isosurfaces first, then the volume with their depth.
    let f = draw(&h, &p, &prepared, Fidelity::Faithful, ProgramKind::Arb, cam);
    let (fa, _) = scored(&p, &prepared, &f, cam);
    eprintln!("both, faithful: {fa:?}");
    assert!(fa.0 < 0.06, "{fa:?}");
    // Precise `table` in perspective draws each cell from its corners: here its front
    // faces, whose depth is tested against the isosurfaces' (not the one back face that
    // stands for three front faces elsewhere).
    let mut table = spec(Sort::Mpvonc);
    table.precise = Precise::Table;
    let p = scene(Mode::Both, table, p.isovalues.clone());
    let cam = camera(Projection::Perspective);
    let image = draw(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
    let (all, inner) = scored(&p, &prepared, &image, cam);
    eprintln!("both, precise table: {all:?} {inner:?}");
    // A cell the isosurface cuts adds its whole segment when its front face is in front
    // of the isosurface (the projection's limit, as faithful's): interior RMSE 0.0026
    // measured. Drawing the back face for three front faces here too would hide such
    // cells behind the isosurface: 0.035 measured.
    assert!(inner.0 < 6e-3, "{inner:?}");
}

#[test]
fn extremes_stay_finite_and_close_to_the_reference() {
    let h = headless(Backend::Egl);
    // Camera inside the mesh (a cell of the 9³ grid holds the eye): only the walk can
    // start there.
    let prepared = prepared_of(&grid(9, Field::Spherical));
    let p = scene(Mode::Volume, spec(Sort::Mpvonc), Vec::new());
    let inside = Camera {
        projection: Projection::Perspective,
        rotation: [0.1, 0.2, 0.0, 0.97],
        zoom: 8.0,
        ..Camera::default()
    };
    let image = draw(
        &h,
        &p,
        &prepared,
        Fidelity::Precise,
        ProgramKind::Glsl,
        inside,
    );
    let (all, _) = scored(&p, &prepared, &image, inside);
    eprintln!("camera inside: {all:?}");
    assert!(all.0 < 1e-3, "camera inside: {all:?}");
    // A constant field (sf = sb everywhere; homogeneous segments) and nearly opaque
    // cells (opacity value 1 per 0.002 units: every segment is opaque).
    // (The scalars handed over normalized: a constant's own range maps it to 0, which
    // the transfer function keeps clear, and the picture would be empty.)
    let flat = grid(5, Field::Planar);
    let flat = from_mesh(&flat, &vec![0.5; flat.points.len()], "s".into(), [0.0, 1.0]).unwrap();
    let mut opaque = spec(Sort::Mpvonc);
    opaque.unit_distance = 0.002;
    for (name, prepared, volume) in [
        ("constant field", &flat, spec(Sort::Mpvonc)),
        ("nearly opaque", &prepared, opaque),
    ] {
        let p = scene(Mode::Volume, volume, Vec::new());
        let cam = camera(Projection::Orthographic);
        for fidelity in [Fidelity::Precise, Fidelity::Faithful] {
            let kind = if fidelity == Fidelity::Precise {
                ProgramKind::Glsl
            } else {
                ProgramKind::Arb
            };
            let image = draw(&h, &p, prepared, fidelity, kind, cam);
            assert!(image.data.iter().all(|v| v.is_finite()), "{name}");
            let lit = image
                .data
                .chunks(4)
                .filter(|p| (p[0] - 0.1).abs() > 0.05)
                .count();
            assert!(lit > image.data.len() / 16, "{name}: {lit} pixels lit");
            let (all, _) = scored(&p, prepared, &image, cam);
            eprintln!("{name} {fidelity:?}: {all:?}");
            // Precise: the 1e-3 goal; faithful: 8-bit table and target (the first
            // segment of an opaque ray decides the pixel: a few levels).
            let bound = if fidelity == Fidelity::Precise {
                1e-3
            } else {
                0.03
            };
            assert!(all.0 < bound, "{name} {fidelity:?}: {all:?}");
        }
    }
    // 1e6 offsets in millimetres: the same picture as at the origin.
    let mut far = grid(7, Field::Spherical);
    let near = prepared_of(&far);
    for q in &mut far.points {
        *q = q.map(|v| 1.0e6 + v * 1e-3);
    }
    let far = prepared_of(&far);
    let mut mm = spec(Sort::Mpvonc);
    mm.unit_distance = 0.25e-3;
    let p_far = scene(Mode::Volume, mm, Vec::new());
    let p_near = scene(Mode::Volume, spec(Sort::Mpvonc), Vec::new());
    let cam = camera(Projection::Perspective);
    let a = draw(
        &h,
        &p_near,
        &near,
        Fidelity::Precise,
        ProgramKind::Glsl,
        cam,
    );
    let b = draw(&h, &p_far, &far, Fidelity::Precise, ProgramKind::Glsl, cam);
    let d = a.compare(&b, 1e-4).unwrap();
    // Re-centred in f64: equal up to f32 rounding of the same box coordinates.
    assert_eq!(d.pixels_over, 0, "{d:?}");
}

/// A boundary-layer mesh: 9 x 9 x 30 points, the layers thinning geometrically toward
/// z = 0 (the first 1/200 of the last), sheared in x, a wavy field: slivers whose faces
/// meet at edges every few pixels, as in CFD grids (NASA's Blunt Fin has 75,501 tetrahedra
/// of radius ratio below 0.1 in 187,395).
fn boundary_layers() -> Prepared {
    let mut mesh = generate(&GridSpec {
        points: [9, 9, 30],
        field: Field::Planar,
    })
    .unwrap();
    let layers = 29;
    let ratio = (0.2f64 / 1e-3).powf(1.0 / (layers - 1) as f64);
    let total: f64 = (0..layers).map(|k| 1e-3 * ratio.powi(k)).sum();
    let height = |z: f64| {
        let k = (z * layers as f64).round() as i32;
        (0..k).map(|j| 1e-3 * ratio.powi(j)).sum::<f64>() / total
    };
    for (q, v) in mesh
        .points
        .iter_mut()
        .zip(mesh.point_arrays[0].values.iter_mut())
    {
        q[2] = height(q[2]);
        q[0] += 0.3 * q[2] * q[2];
        *v = (5.0 * q[0]).sin() * (4.0 * q[1]).cos() + q[2];
    }
    prepared_of(&mesh)
}

#[test]
fn precise_table_takes_the_nearest_exit_on_slivers() {
    let h = headless(Backend::Egl);
    let prepared = boundary_layers();
    let mut volume = spec(Sort::Mpvonc);
    volume.precise = Precise::Table;
    // Precise `table` per fragment (perspective, or `exit = "fragment"`) bounds each
    // segment by all four of the cell's planes, drawing one triangle where three faces
    // face the viewer; per vertex (orthographic) it takes the nearest of three exits.
    for (projection, exit) in [
        (Projection::Perspective, Exit::Auto),
        (Projection::Orthographic, Exit::Auto),
        (Projection::Orthographic, Exit::Fragment),
    ] {
        let mut p = scene(Mode::Volume, volume.clone(), Vec::new());
        p.exit = exit;
        let cam = camera(projection);
        let table = draw(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
        let faithful = draw(&h, &p, &prepared, Fidelity::Faithful, ProgramKind::Arb, cam);
        let (t, _) = scored(&p, &prepared, &table, cam);
        let (f, _) = scored(&p, &prepared, &faithful, cam);
        eprintln!("slivers {projection:?} {exit:?}: table {t:?}, faithful (the seed's exit) {f:?}");
        // The seed's "smallest positive t_i" takes a far plane where rounding puts the
        // near exit just behind the entry (a ray entering a sliver at an edge): single
        // pixels 0.19 off here (faithful's printout; the float table before it took the
        // nearest leaving plane: 0.19 too, RMSE 0.002). The table's own error is its
        // interpolation: largest 0.0015-0.0018, RMSE < 1e-4 measured; the bounds leave
        // room and stay far below one wrong segment.
        assert!(t.1 < 0.03, "{projection:?}: {t:?}");
        assert!(t.0 < 1e-3, "{projection:?}: {t:?}");
    }
}

#[test]
fn a_spike_narrower_than_a_table_texel_is_not_missed() {
    let h = headless(Backend::Egl);
    let prepared = prepared_of(&grid(9, Field::Spherical));
    // Opacity only within 0.001 of s = 0.5: a fifth of one texel of the 128-wide table
    // (1/127), never at a vertex of the 9³ grid; every segment that crosses it must get
    // its integral (pre-integration's reason to exist), not the transfer function at the
    // segment's ends (zero at both).
    let spike = VolumeSpec {
        points: vec![
            [0.0, 1.0, 0.9, 0.2, 0.0],
            [0.499, 1.0, 0.9, 0.2, 0.0],
            [0.5, 1.0, 0.9, 0.2, 1.0],
            [0.501, 1.0, 0.9, 0.2, 0.0],
            [1.0, 1.0, 0.9, 0.2, 0.0],
        ],
        unit_distance: 0.001,
        table_size: [128, 64],
        ..spec(Sort::Mpvonc)
    };
    let p = scene(Mode::Volume, spike, Vec::new());
    let cam = camera(Projection::Orthographic);
    let bg = BACKGROUND.map(|v| v as f64);
    // Mean distance from the background over RGB: how much of the shell a picture shows.
    let signal = |image: &Image| {
        let n = image.data.len() / 4;
        image
            .data
            .chunks(4)
            .map(|px| (0..3).map(|c| (px[c] as f64 - bg[c]).abs()).sum::<f64>())
            .sum::<f64>()
            / n as f64
    };
    let want = reference_image(&p, &prepared, cam);
    let want_signal = signal(&want);
    // The shell is there: a third of an RGB unit on average over the whole image.
    assert!(want_signal > 0.2, "reference signal {want_signal}");
    let mut table = p.clone();
    if let Some(v) = &mut table.volume {
        v.precise = Precise::Table;
    }
    for (name, p, fidelity, kind) in [
        ("faithful", &p, Fidelity::Faithful, ProgramKind::Arb),
        (
            "precise table",
            &table,
            Fidelity::Precise,
            ProgramKind::Glsl,
        ),
        ("precise walk", &p, Fidelity::Precise, ProgramKind::Glsl),
    ] {
        let image = draw(&h, p, &prepared, fidelity, kind, cam);
        let (all, _) = scored(p, &prepared, &image, cam);
        let got = signal(&image);
        eprintln!("spike, {name}: {all:?}, signal {got} of {want_signal}");
        // Both tables catch every segment that crosses the spike, but one that starts or
        // ends within the spike's texel reads an interpolation between a texel whose
        // segment crosses it and one whose does not: RMSE 0.025 and single pixels up to
        // 0.77 off measured, in float as in 8 bits (the table's limit, not the
        // rounding), with 98 % of the shell's signal. The walk is exact: the 1e-3 goal.
        let (bound, kept) = match name {
            "faithful" | "precise table" => (0.04, 0.95),
            _ => (1e-3, 0.999),
        };
        assert!(all.0 < bound, "{name}: {all:?}");
        assert!(
            got > kept * want_signal,
            "{name}: signal {got} of {want_signal}"
        );
    }
}

#[test]
fn malformed_transfer_functions_are_refused_at_their_line_and_column() {
    let text = |volume: &str| {
        format!(
            "size = [32, 32]\n[technique.cellproj]\nmesh = {{ grid = {{ points = [5, 5, 5], field = \"planar\" }} }}\nmode = \"volume\"\n\n[technique.cellproj.volume]\n{volume}\n"
        )
    };
    for (volume, line, what) in [
        (
            // The array's element itself, on the line after the key.
            "points = [[0.0, 0, 0, 0, 0], [0.5, 1, 1, 1, 1],\n  [0.2, 1, 1, 1, 1]]",
            8,
            "ascending",
        ),
        ("points = [[0.0, 0, 0, 0, 2.0]]", 7, "points.0"),
        ("unit_distance = -1.0", 7, "unit_distance"),
        ("table = { builtin = \"nope\" }", 7, "builtin"),
        ("table_size = [1, 64]", 7, "table_size"),
        ("grid = 1", 7, "grid"),
        ("grid_steps = 0.1", 7, "grid_steps"),
        ("precise = \"grid\"\ngrid = 401", 8, "grid"),
    ] {
        let e = Scene::parse(&text(volume), "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&format!("bad.toml:{line}:")), "{e}");
        assert!(e.contains(what), "{e}");
    }
    // Precise `grid` casts the volume alone: with isosurfaces it is refused.
    let both = text("precise = \"grid\"").replace("mode = \"volume\"", "mode = \"both\"");
    let e = Scene::parse(&both, "both.toml").unwrap_err().to_string();
    assert!(
        e.starts_with("both.toml:") && e.contains("mode = \"volume\""),
        "{e}"
    );
    let ok = Scene::parse(
        &text("points = [[0.0, 0, 0, 0, 0], [1.0, 1, 1, 1, 1]]"),
        "ok.toml",
    );
    assert!(ok.is_ok(), "{ok:?}");
}

/// The viewer's edits: a transfer-function change through `update` keeps the mesh's
/// textures and remakes only the table, the coarse table of interactive frames and the
/// scene's swap without integrating again; each picture is exactly what a renderer made
/// fresh for that spec draws (faithful and precise, both sorts).
#[test]
fn transfer_function_edits_draw_what_a_fresh_renderer_draws() {
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let prepared = prepared_of(&grid(9, Field::Spherical));
    let cam = camera(Projection::Perspective);
    let first = spec(Sort::Centroid);
    // Another function (the band moved and recoloured), another unit, MPVONC.
    let mut second = spec(Sort::Mpvonc);
    second.points[2] = [0.48, 0.2, 1.0, 0.4, 0.8];
    second.unit_distance = 0.4;
    // What the viewer draws while the user drags: the table an eighth of each side.
    let mut coarse = second.clone();
    coarse.table_size = coarse.table_size.map(|s| s / 8);
    // Zero bands: the edit changes which tetrahedra are drawn.
    let bands = banded(Sort::Mpvonc);
    // Precise `grid` too, its grid's size edited among the rest (a new grid, not only
    // new tables).
    let as_grid = |v: &VolumeSpec, points| VolumeSpec {
        precise: Precise::Grid,
        grid: points,
        ..v.clone()
    };
    for (fidelity, grid) in [
        (Fidelity::Faithful, None),
        (Fidelity::Precise, None),
        (Fidelity::Precise, Some(13)),
    ] {
        let shot = shot(fidelity);
        let target = shot.target(gpu);
        let steps: Vec<VolumeSpec> = [
            &second, &coarse, &second, &bands, &coarse, &first, &bands, &second,
        ]
        .iter()
        .enumerate()
        .map(|(k, &v)| match grid {
            Some(n) => as_grid(v, if k == 4 { n + 8 } else { n }),
            None => v.clone(),
        })
        .collect();
        let first = grid.map_or(first.clone(), |n| as_grid(&first, n));
        let first_scene = scene(Mode::Volume, first, vec![]);
        let mut r = glsl_renderer(gpu, fidelity, &first_scene, &prepared);
        let picture = |r: &mut CellprojRenderer| shot.draw_on(gpu, r, &target, &cam);
        picture(&mut r);
        for step in &steps {
            let params = scene(Mode::Volume, step.clone(), vec![]);
            r.update(gpu, arbvis::techniques::Params::of(&params))
                .unwrap();
            let edited = picture(&mut r);
            let fresh = draw(&h, &params, &prepared, fidelity, ProgramKind::Glsl, cam);
            assert!(
                edited.data == fresh.data,
                "{fidelity:?}: table {:?}, unit {}: the edited renderer differs from a fresh one",
                step.table_size,
                step.unit_distance
            );
        }
    }
}

/// A transfer function that is zero on two bands and at the ends, with uneven colours:
/// the kind of function that leaves most of a CFD mesh clear.
fn banded(sort: Sort) -> VolumeSpec {
    let points = [
        [0.0, 0.3, 0.7, 0.2, 0.0],
        [0.31, 0.9, 0.1, 0.4, 0.0],
        [0.37, 0.2, 0.8, 0.6, 0.7],
        [0.44, 0.7, 0.3, 0.9, 0.0],
        [0.66, 0.1, 0.5, 0.3, 0.0],
        [0.71, 0.95, 0.85, 0.05, 0.9],
        [0.71, 0.4, 0.2, 0.8, 0.35],
        [0.83, 0.6, 0.6, 0.1, 0.0],
        [1.0, 0.2, 0.9, 0.9, 0.0],
    ];
    points_spec(&points, 0.2, sort)
}

/// `active_only` (the default) leaves out the tetrahedra whose range the transfer
/// function maps to zero attenuation, widened to the table texels a lookup may read: on
/// an uneven field with zero bands a fifth to a third are left out, and no pixel of the precise
/// projections moves (bit for bit: a left-out cell's fragments would blend zero). The
/// faithful picture differs only where the seed's exit takes a far plane in a clear cell
/// (its speckle, whose segment reads texels outside the cell's range): a few pixels.
#[test]
fn clear_tetrahedra_are_left_out_and_no_pixel_moves() {
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let prepared = prepared_of(&grid(13, Field::Waves));
    let total = prepared.tets.len();
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let cam = camera(projection);
        let mut params = scene(Mode::Volume, banded(Sort::Mpvonc), vec![]);
        params.mesh = arbvis::mesh::MeshSource::Grid(GridSpec {
            points: [13; 3],
            field: Field::Waves,
        });
        // The default table, and a coarse one whose lookups near a band's edge read
        // texels well beyond the cell's range (the widening must see them), with the
        // share each leaves clear on this mesh (32 % and 19 %) less a margin.
        for ((fidelity, method), (table_size, most_drawn)) in [
            (Fidelity::Faithful, Precise::Walk),
            (Fidelity::Precise, Precise::Table),
            (Fidelity::Precise, Precise::Projected),
        ]
        .into_iter()
        .flat_map(|m| [(m, ([128, 64], 0.75)), (m, ([16, 16], 0.9))])
        {
            let volume = params.volume.as_mut().unwrap();
            volume.precise = method;
            volume.table_size = table_size;
            let shot = shot(fidelity);
            let target = shot.target(gpu);
            let mut picture = |active_only: bool| {
                params.active_only = active_only;
                let mut r = glsl_renderer(gpu, fidelity, &params, &prepared);
                let image = shot.draw_on(gpu, &mut r, &target, &cam);
                (image, r.volume().unwrap().times().drawn)
            };
            let (culled, drawn) = picture(true);
            let (all, every) = picture(false);
            let what = format!("{fidelity:?} {method:?} {table_size:?} {projection:?}");
            assert_eq!(every, total, "{what}: active_only = false draws every one");
            assert!(
                drawn > 0 && (drawn as f64) < total as f64 * most_drawn,
                "{what}: {drawn} of {total} drawn"
            );
            if fidelity == Fidelity::Precise {
                assert!(culled.data == all.data, "{what}: a pixel moved");
                continue;
            }
            let moved: Vec<usize> = (0..culled.data.len() / 4)
                .filter(|&p| culled.data[4 * p..4 * p + 4] != all.data[4 * p..4 * p + 4])
                .collect();
            eprintln!(
                "{what}: {drawn} of {total} drawn, {} pixels moved",
                moved.len()
            );
            // Measured 1-4 of 6,912; the same cells without the seed's exit (precise
            // `table`, above) move none.
            assert!(
                moved.len() * 200 <= culled.data.len() / 4,
                "{what}: {} pixels moved, more than 0.5 %",
                moved.len()
            );
        }
    }
}

/// `active_only` switched on with one transfer function and the function changed back
/// before any draw: the drawn set is the function's that is drawn, not the undone one's
/// (a function clearer than it would leave out cells it colours).
#[test]
fn the_drawn_set_follows_an_edit_undone_before_the_draw() {
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let prepared = prepared_of(&grid(13, Field::Waves));
    let cam = camera(Projection::Orthographic);
    let mut table = spec(Sort::Mpvonc);
    table.precise = Precise::Table;
    let mut bands = banded(Sort::Mpvonc);
    bands.precise = Precise::Table;
    let mut all = scene(Mode::Volume, table.clone(), vec![]);
    all.active_only = false;
    let mut r = glsl_renderer(gpu, Fidelity::Precise, &all, &prepared);
    let shot = shot(Fidelity::Precise);
    let target = shot.target(gpu);
    shot.draw_on(gpu, &mut r, &target, &cam);
    // Culling on with the banded function, then the first function back, no draw between.
    let culled_bands = scene(Mode::Volume, bands, vec![]);
    r.update(gpu, arbvis::techniques::Params::of(&culled_bands))
        .unwrap();
    let back = scene(Mode::Volume, table, vec![]);
    r.update(gpu, arbvis::techniques::Params::of(&back))
        .unwrap();
    let undone = shot.draw_on(gpu, &mut r, &target, &cam);
    let fresh = draw(
        &h,
        &back,
        &prepared,
        Fidelity::Precise,
        ProgramKind::Glsl,
        cam,
    );
    assert!(undone.data == fresh.data);
}
