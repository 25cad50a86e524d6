//! The precise walk follows every entry into a non-convex mesh, without a setting: a stack
//! of ten plates seen along the stack, so that rays enter the mesh ten times and more (more
//! than one walk pass takes, eight), is within 1e-3 of the f64 reference on every pixel,
//! silhouettes included, in three rotated views and both projections; capped at four
//! entries (the old default) the same views are far off. And the slotted mesh, whose
//! rays graze its slot's wall (a re-entry the entry layers miss), seen behind ten plates:
//! its entries come in the walk's second pass, and every pixel is within 1e-3 too, what
//! the walk reached carried from pass to pass so that the search for re-entries runs in
//! every pass.

use crate::cellproj_volume::{
    draw_counting_entries, points_spec, prepared_of, reference_image, scene, slotted, slotted_mesh,
    slotted_volume,
};
use crate::common::headless;
use arbvis::camera::{Camera, Projection};
use arbvis::gl::{Backend, ProgramKind};
use arbvis::mesh::grid::{generate, Field, GridSpec};
use arbvis::scene::Fidelity;
use arbvis::techniques::cellproj::prepare::Prepared;
use arbvis::techniques::cellproj::transfer::{Sort, VolumeSpec};
use arbvis::techniques::cellproj::Mode;

/// Ten plates, each two cells of a 7 x 6 x 41 point grid thick, two cells apart, with an
/// oblique field (no symmetry), stretched to a square and sheared: every tetrahedron
/// whose centroid lies in a gap goes.
fn plates() -> Prepared {
    let mut mesh = generate(&GridSpec {
        points: [7, 6, 41],
        field: Field::Oblique,
    })
    .unwrap();
    // The grid's points are evenly spaced (x and y span 0.15 and 0.125): plates as wide
    // as the stack is tall, sheared a little in x.
    for q in &mut mesh.points {
        q[0] = q[0] * 40.0 / 6.0 + 0.1 * q[2];
        q[1] *= 8.0;
    }
    let points = mesh.points.clone();
    let keep: Vec<bool> = mesh
        .tets
        .iter()
        .map(|t| {
            let z = t.iter().map(|&i| points[i as usize][2]).sum::<f64>() / 4.0;
            ((z * 40.0) as usize / 2).is_multiple_of(2)
        })
        .collect();
    let mut k = keep.iter();
    mesh.tets.retain(|_| *k.next().unwrap());
    let mut k = keep.iter();
    mesh.source_cell.retain(|_| *k.next().unwrap());
    prepared_of(&mesh)
}

/// The largest difference of any channel of any pixel, and how many pixels are over 1e-3.
fn worst(image: &arbvis::image::Image, want: &arbvis::image::Image) -> (f64, usize) {
    let mut most = 0f64;
    let mut over = 0;
    for (a, b) in image.data.chunks(4).zip(want.data.chunks(4)) {
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| (*x as f64 - *y as f64).abs())
            .fold(0.0, f64::max);
        most = most.max(d);
        over += usize::from(d > 1e-3);
    }
    (most, over)
}

#[test]
fn every_entry_is_followed_on_a_stack_of_plates() {
    let h = headless(Backend::Egl);
    let prepared = plates();
    // Faint enough that the tenth plate still shows: about 0.7 transmittance per plate.
    let points = [
        [0.0, 1.0, 0.2, 0.1, 0.25],
        [0.4, 0.1, 0.9, 0.3, 0.35],
        [0.7, 0.9, 0.8, 0.1, 0.15],
        [1.0, 0.2, 0.3, 1.0, 0.4],
    ];
    let volume = |entries| VolumeSpec {
        entries,
        ..points_spec(&points, 0.1, Sort::Mpvonc)
    };
    // Views along the stack, tilted three ways (rays through every plate, entering the
    // side walls too).
    let rotations = [
        [0.12, 0.2, 0.03, 0.972],
        [-0.18, 0.1, 0.3, 0.931],
        [0.22, -0.15, -0.1, 0.958],
    ];
    for rotation in rotations {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let cam = Camera {
                projection,
                rotation,
                zoom: 0.8,
                ..Camera::default()
            };
            let all = scene(Mode::Volume, volume(0), Vec::new());
            let want = reference_image(&all, &prepared, cam);
            let (image, entries) = draw_counting_entries(
                &h,
                &all,
                &prepared,
                Fidelity::Precise,
                ProgramKind::Glsl,
                cam,
            );
            let (most, over) = worst(&image, &want);
            eprintln!("{rotation:?} {projection:?}: {entries} entries, worst {most:.2e}, {over} pixels over 1e-3");
            assert!(
                entries >= 10,
                "{rotation:?} {projection:?}: {entries} entries"
            );
            // f32 arithmetic and the 2^-12 termination (2.4e-4 of a channel at most): the
            // issue's bound, on every pixel (measured at most 2.1e-4 on llvmpipe and on an
            // NVIDIA H100 alike, since each entry is where the pixel's ray meets the face's
            // plane; from the rasterized position it had been 2.9e-3 on the H100).
            assert!(
                most < 1e-3,
                "{rotation:?} {projection:?}: worst {most}, {over} pixels over 1e-3"
            );
            let capped = scene(Mode::Volume, volume(4), Vec::new());
            let (image, entries) = draw_counting_entries(
                &h,
                &capped,
                &prepared,
                Fidelity::Precise,
                ProgramKind::Glsl,
                cam,
            );
            assert_eq!(entries, 4);
            let (most, _) = worst(&image, &want);
            assert!(most > 0.02, "capped at 4 entries: worst {most}");
        }
    }
}

/// Rays that leave the slotted mesh through a wall and re-enter it within a hair: in eight
/// views (four rotations, both projections) every pixel within 1e-3 of the reference.
#[test]
fn rays_grazing_the_boundary_keep_their_path() {
    let h = headless(Backend::Egl);
    let prepared = slotted();
    let volume = slotted_volume(Sort::Mpvonc);
    let p = scene(Mode::Volume, volume, Vec::new());
    for rotation in [
        [0.45, -0.3, 0.1, 0.83],
        [0.1, 0.6, -0.2, 0.77],
        [-0.35, 0.25, 0.4, 0.81],
        [0.62, 0.05, 0.3, 0.72],
    ] {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            let cam = Camera {
                projection,
                rotation,
                ..Camera::default()
            };
            let want = reference_image(&p, &prepared, cam);
            let (image, entries) =
                draw_counting_entries(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
            let (most, over) = worst(&image, &want);
            eprintln!("slotted {rotation:?} {projection:?}: {entries} entries, worst {most:.2e}, {over} over 1e-3");
            // As above: f32 arithmetic and the 2^-12 termination.
            assert!(
                most < 1e-3,
                "{rotation:?} {projection:?}: worst {most}, {over} pixels over 1e-3"
            );
        }
    }
}

/// The slotted mesh with ten plates in front of it along the view of `rotation` (each a
/// slab of a 5 x 5 x 21 point grid, square and wide enough to cover it): a ray meets the
/// plates' ten entries before the slotted body's.
fn slotted_behind_plates(rotation: [f64; 4]) -> Prepared {
    use glam::{DQuat, DVec3};
    let mut mesh = slotted_mesh();
    let mut plates = generate(&GridSpec {
        points: [5, 5, 21],
        field: Field::Oblique,
    })
    .unwrap();
    let keep: Vec<bool> = plates
        .tets
        .iter()
        .map(|t| {
            let z = t.iter().map(|&i| plates.points[i as usize][2]).sum::<f64>() / 4.0;
            ((z * 20.0) as usize).is_multiple_of(2)
        })
        .collect();
    let mut k = keep.iter();
    plates.tets.retain(|_| *k.next().unwrap());
    let mut k = keep.iter();
    plates.source_cell.retain(|_| *k.next().unwrap());
    // Towards the eye, and two directions across it (right-handed: u x v = e).
    let q = DQuat::from_array(rotation).normalize();
    let e = q.inverse() * DVec3::Z;
    let u = e
        .cross(if e.x.abs() < 0.9 { DVec3::X } else { DVec3::Y })
        .normalize();
    let v = e.cross(u);
    let centre = DVec3::splat(0.5);
    for p in &mut plates.points {
        let (x, y, z) = (p[0] / 0.2 - 0.5, p[1] / 0.2 - 0.5, p[2]);
        *p = (centre + u * (3.0 * x) + v * (3.0 * y) + e * (1.0 + z)).to_array();
    }
    let base = mesh.points.len() as u32;
    mesh.points.extend(&plates.points);
    let cells = mesh.source_cell.iter().max().map_or(0, |c| c + 1);
    mesh.tets
        .extend(plates.tets.iter().map(|t| t.map(|i| i + base)));
    mesh.source_cell
        .extend(plates.source_cell.iter().map(|c| c + cells));
    for (a, b) in mesh.point_arrays.iter_mut().zip(&plates.point_arrays) {
        a.values.extend(&b.values);
    }
    mesh.cell_arrays.clear();
    prepared_of(&mesh)
}

#[test]
fn a_grazing_re_entry_past_the_eighth_entry_is_followed() {
    let h = headless(Backend::Egl);
    let volume = slotted_volume(Sort::Mpvonc);
    let p = scene(Mode::Volume, volume, Vec::new());
    // A view found by a sweep of 40 random rotations and two zooms: with the search for
    // re-entries in the first pass only (before), this view's grazing pixel was off by
    // 1.5e-3. (The sweep's other views off by more were off at a plate's corner, a pixel
    // its entry face's rasterization took though the exact ray misses the plate; the
    // search does not touch that, docs/cellproj.md.)
    let rotation = [-0.335, 0.52, 0.423, 0.662];
    let prepared = slotted_behind_plates(rotation);
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let cam = Camera {
            projection,
            rotation,
            zoom: 1.6,
            ..Camera::default()
        };
        let want = reference_image(&p, &prepared, cam);
        let (image, entries) =
            draw_counting_entries(&h, &p, &prepared, Fidelity::Precise, ProgramKind::Glsl, cam);
        let (most, over) = worst(&image, &want);
        eprintln!(
            "behind plates {projection:?}: {entries} entries, worst {most:.2e}, {over} over 1e-3"
        );
        assert!(entries > 10, "{projection:?}: {entries} entries");
        // As above: f32 arithmetic and the 2^-12 termination.
        assert!(
            most < 1e-3,
            "{projection:?}: worst {most}, {over} pixels over 1e-3"
        );
    }
}
