//! Horizon files as interpretation tools export them (issue 57 item 1): the tracked F3
//! horizon as GOCAD TSurf and as an x y z grid (OpendTect's columns) is one surface, in
//! one place; an x y z grid without inline and crossline columns is triangulated by
//! Delaunay over the nodes that are there.

use crate::common;

use arbvis::gl::Backend;
use arbvis::render::render_on;
use arbvis::scene::Scene;
use common::headless;

/// The two files of `scripts/track_horizon.py` hold the same nodes and triangles: the
/// x y z grid's time positive down, which `z_down` turns as the TSurf's `ZPOSITIVE Depth`.
#[test]
fn the_tracked_horizon_as_xyz_is_the_tsurf_surface() {
    let ts = arbvis::surface::read(&common::data_file("seismic/f3-horizon.ts")).unwrap();
    let xyz = arbvis::surface::read(&common::data_file("seismic/f3-horizon.xyz")).unwrap();
    assert_eq!(xyz.triangles, ts.triangles);
    assert_eq!(xyz.vertices.len(), 414);
    for (a, b) in xyz.vertices.iter().zip(&ts.vertices) {
        // Both written with the same decimals: equal, z of opposite sign.
        assert_eq!([a[0], a[1], -a[2]], *b);
    }
    let said = common::inspect(&common::data_file("seismic/f3-horizon.xyz"));
    common::assert_says(
        &said,
        &[
            "nodes: 414 defined, 0 undefined",
            "grid of 23 inlines x 18 crosslines",
            "triangles: 748",
        ],
    );
}

/// As layers of one scene, the two files draw the same picture (the x y z one with
/// `z_down`), coloured by the survey where they lie.
#[test]
fn the_xyz_horizon_draws_as_the_tsurf_horizon_in_a_layered_scene() {
    let h = headless(Backend::Egl);
    let scene = |file: &str, z_down: bool| {
        let text = format!(
            "size = [64, 48]\n[[layer]]\nname = \"F3\"\nvisible = false\n[layer.opacity3d.primary]\nvolume = {{ segy = \"{}\" }}\n[[layer]]\nname = \"horizon\"\n[layer.surface]\nfile = \"{}\"\nz_down = {z_down}\ncolour_from = {{ layer = \"F3\" }}\n",
            common::data_file("seismic/f3.sgy").display(),
            common::data_file(file).display()
        );
        Scene::parse(&text, "h.toml").unwrap()
    };
    let a = render_on(&h, &scene("seismic/f3-horizon.ts", false))
        .unwrap()
        .image;
    let b = render_on(&h, &scene("seismic/f3-horizon.xyz", true))
        .unwrap()
        .image;
    assert_eq!(a.compare(&b, 0.0).unwrap().pixels_over, 0);
    let lit = common::lit_pixels(&a, 0.05);
    // A sheet seen from 30 degrees above, framed with the whole survey: 210 of 3,072.
    assert!(lit > 150, "the horizon is in view: {lit}");
}

/// Nodes without inline and crossline columns, one undefined (OpendTect's 1e30) and one
/// left out, in comma-separated UTM: every node with a z is a vertex, and no triangle
/// bridges the gaps (none has an edge over 1.5 of the 25 m spacing's diagonal).
#[test]
fn an_xyz_grid_without_inline_numbers_is_triangulated_over_its_nodes() {
    let dir = common::temp_dir("horizons-xyz");
    let mut text = String::from("# X, Y, TWT\n");
    for i in 0..7 {
        for j in 0..5 {
            if (i, j) == (3, 2) {
                continue;
            }
            let z = if (i, j) == (5, 1) {
                1e30
            } else {
                900.0 + (i * j % 4) as f64
            };
            text += &format!(
                "{}, {}, {z}\n",
                635_000.0 + i as f64 * 25.0,
                848_000.0 + j as f64 * 25.0
            );
        }
    }
    std::fs::write(dir.join("h.xyz"), &text).unwrap();
    let mesh = arbvis::surface::read(&dir.join("h.xyz")).unwrap();
    assert_eq!(mesh.vertices.len(), 35 - 2);
    for t in &mesh.triangles {
        for k in 0..3 {
            let (p, q) = (
                mesh.vertices[t[k] as usize],
                mesh.vertices[t[(k + 1) % 3] as usize],
            );
            let edge = (p[0] - q[0]).hypot(p[1] - q[1]);
            assert!(edge < 1.5 * 25.0 * 2f64.sqrt(), "{edge}");
        }
    }
    // 6 x 4 cells of two triangles, less the eight around each of the two gaps, plus the
    // triangle of three corners left in each such cell: 48 - 16 + 8.
    assert_eq!(mesh.triangles.len(), 40);
    let said = common::inspect(&dir.join("h.xyz"));
    common::assert_says(&said, &["nodes: 33 defined, 1 undefined", "by Delaunay"]);
}
