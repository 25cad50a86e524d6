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

/// Three squares of one TSurf coloured by their vertices' own property (`colour_by =
/// { property = "throw" }`) over `range = [0, 10]`, unlit, seen from above: throw 5 takes
/// the table's middle, a square without the property the constant colour, throw 20 the
/// table's top (clamped); in both fidelities. A property the file lacks is refused by its
/// key, naming those it has; `inspect` lists them with their ranges.
#[test]
fn a_surface_is_coloured_by_its_own_vertex_property() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("surface-property");
    let square = |first: u32, x: f64, throw: Option<f64>| -> String {
        let corners = [[x, 0.0], [x + 1.0, 0.0], [x + 1.0, 1.0], [x, 1.0]];
        let mut text = String::from("TFACE\n");
        for (k, [cx, cy]) in corners.into_iter().enumerate() {
            let id = first + k as u32;
            text += &match throw {
                // The dip column is there to be skipped.
                Some(t) => format!("PVRTX {id} {cx} {cy} 0 {t} 33\n"),
                None => format!("VRTX {id} {cx} {cy} 0\n"),
            };
        }
        let [a, b, c, d] = [0, 1, 2, 3].map(|k| first + k);
        text + &format!("TRGL {a} {b} {c}\nTRGL {a} {c} {d}\n")
    };
    let ts = format!(
        "GOCAD TSurf 1\nPROPERTIES throw dip\nNO_DATA_VALUES -99999 -99999\n{}{}{}END\n",
        square(1, 0.0, Some(5.0)),
        square(5, 2.0, None),
        square(9, 4.0, Some(20.0)),
    );
    std::fs::write(dir.join("f.ts"), ts).unwrap();
    let scene = |fidelity: &str, property: &str| {
        let text = format!(
            "size = [90, 30]\nfidelity = \"{fidelity}\"\n[camera]\nprojection = \"orthographic\"\nzoom = 2.5\n[technique.surface]\nfile = \"{}\"\ncolour = [0.9, 0.1, 0.6]\ncolour_by = {{ property = \"{property}\" }}\nrange = [0.0, 10.0]\nlighting = \"none\"\ntable = {{ builtin = \"viridis\" }}\n",
            dir.join("f.ts").display()
        );
        Scene::parse(&text, "f.toml").unwrap()
    };
    let table = arbvis::colortable::ColorTable::builtin("viridis").unwrap();
    let colour = |s: f64| arbvis::techniques::surface::prepare::table_colour(&table, s);
    let wanted = [colour(0.5), glam::DVec3::new(0.9, 0.1, 0.6), colour(1.0)];
    for fidelity in ["faithful", "precise"] {
        let image = render_on(&h, &scene(fidelity, "throw")).unwrap().image;
        for (k, want) in wanted.iter().enumerate() {
            // A colour constant over each square: the 8-bit target's rounding (half a
            // level) and the float interpolation of three equal corners, within 1 level.
            let hits = (0..image.height)
                .flat_map(|y| (0..image.width).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let p = image.pixel(x, y);
                    (0..3).all(|c| (p[c] as f64 - want[c]).abs() <= 1.0 / 255.0)
                })
                .count();
            // The 5-unit row spans 75 of the 90 pixels at zoom 2.5: each square 15 x 15
            // pixels (225), less its rasterized edges.
            assert!(hits > 180, "{fidelity}: square {k} ({want}): {hits} pixels");
        }
    }
    let e = render_on(&h, &scene("precise", "porosity"))
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("colour_by.property") && e.contains("\"throw\", \"dip\""),
        "{e}"
    );
    let said = common::inspect(&dir.join("f.ts"));
    common::assert_says(
        &said,
        &[
            "property \"throw\": 8 of 12 vertices, 5 to 20",
            "property \"dip\": 8 of 12 vertices, 33 to 33",
        ],
    );
}

/// The synthetic fault of `scripts/make_fault.py` (`data/seismic/f3-fault.ts`) carries its
/// throw at every vertex but the ten tips left unpicked (`NO_DATA_VALUES`), 0 at the
/// edges to 18 ms in the middle, and lies inside F3's map area and time range.
#[test]
fn the_f3_fault_carries_its_throw_inside_the_survey() {
    let fault = arbvis::surface::read(&common::data_file("seismic/f3-fault.ts")).unwrap();
    let throw = fault.property("throw").expect("its throw");
    assert_eq!(throw.range(), Some([0.0, 18.0]));
    assert_eq!(throw.values.iter().filter(|v| v.is_nan()).count(), 10);
    let (lo, hi) = fault.bounds();
    // F3's crop: its corner traces' CDP coordinates (inspect's map line) and 0..296 ms,
    // time turned to z = -t by ZPOSITIVE Depth.
    let (x, y) = ([620_197.0, 620_623.0], [6_074_232.0, 6_074_784.0]);
    assert!(lo[0] > x[0] && hi[0] < x[1], "{lo:?} {hi:?}");
    assert!(lo[1] > y[0] && hi[1] < y[1], "{lo:?} {hi:?}");
    assert!(lo[2] >= -296.0 && hi[2] <= 0.0, "{lo:?} {hi:?}");
    // inspect names its coordinate system and that z was turned.
    let said = common::inspect(&common::data_file("seismic/f3-fault.ts"));
    common::assert_says(
        &said,
        &[
            "objects: 1; z positive downwards (depth, turned up)",
            "coordinate system (as the file names it; not applied): NAME Default; AXIS_NAME \"X\" \"Y\" \"Z\"; AXIS_UNIT \"m\" \"m\" \"ms\"",
            "property \"throw\": 263 of 273 vertices, 0 to 18",
        ],
    );
}

/// A choice given two keys (`colour_by = { property = ..., bogus = 1 }`) is told as such
/// at its line, not as a second technique; two techniques are told with every technique's
/// table, from the catalog (the list had fallen behind it).
#[test]
fn a_choice_of_two_keys_is_not_told_as_two_techniques() {
    let e = Scene::parse(
        "[technique.surface]\nfile = \"f.ts\"\ncolour_by = { property = \"throw\", bogus = 1 }\n",
        "cb.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("cb.toml:3:") && e.contains("more than one key") && !e.contains("technique"),
        "{e}"
    );
    let e = Scene::parse("[technique.quad]\n[technique.lines]\n", "two.toml")
        .unwrap_err()
        .to_string();
    for t in arbvis::catalog::TECHNIQUES {
        assert!(e.contains(&format!("[technique.{}]", t.name)), "{e}");
    }
}
