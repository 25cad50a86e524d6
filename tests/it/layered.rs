//! Scenes of layers (`[[layer]]`, issue 55): the text read and written, each technique's
//! place in one world frame, the surface layer against its f64 reference, and opaque
//! layers composited with translucent ones by depth.

use crate::common;

use arbvis::gl::{Backend, ProgramChoice, TargetFormat};
use arbvis::render::render_on;
use arbvis::scene::{Fidelity, Scene, SceneError};
use arbvis::techniques::surface::{prepare, reference, SurfaceScene};
use common::{headless, LEVEL};

/// A quad (two triangles) at height `z` spanning `[x0, x1] x [y0, y1]`, as OBJ text.
fn plane_obj(x: [f64; 2], y: [f64; 2], z: f64) -> String {
    format!(
        "v {x0} {y0} {z}\nv {x1} {y0} {z}\nv {x1} {y1} {z}\nv {x0} {y1} {z}\nf 1 2 3\nf 1 3 4\n",
        x0 = x[0],
        x1 = x[1],
        y0 = y[0],
        y1 = y[1]
    )
}

/// An uneven height field of `n` x `m` cells (a horizon-like sheet with a fold and a
/// step), as OBJ text: not smooth, not symmetric.
fn horizon_obj(n: usize, m: usize) -> String {
    let mut text = String::new();
    for j in 0..=m {
        for i in 0..=n {
            let (x, y) = (i as f64 * 13.0 + 635_000.0, j as f64 * 17.0 + 848_000.0);
            let z = -400.0
                + 30.0 * ((i as f64) * 0.7).sin() * ((j as f64) * 0.45).cos()
                + if i > n / 2 { 12.0 } else { 0.0 }
                + 0.37 * (i * j % 7) as f64;
            text += &format!("v {x} {y} {z}\n");
        }
    }
    for j in 0..m {
        for i in 0..n {
            let v = |i: usize, j: usize| j * (n + 1) + i + 1;
            text += &format!("f {} {} {}\n", v(i, j), v(i + 1, j), v(i + 1, j + 1));
            text += &format!("f {} {} {}\n", v(i, j), v(i + 1, j + 1), v(i, j + 1));
        }
    }
    text
}

/// Layer `index` of `scene` prepared on the CPU, and where it lies in the world.
fn prepared_in_world(
    scene: &Scene,
    index: usize,
) -> (
    arbvis::catalog::PreparedData,
    arbvis::techniques::world::World,
) {
    let technique = scene.layers().nth(index).unwrap().1;
    let limits = arbvis::volume::Limits::for_max_side(2048);
    let data = arbvis::catalog::prepare(technique, &scene.settings(), &limits).unwrap();
    let world = arbvis::catalog::world(technique, &data).unwrap();
    (data, world)
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, "layered.toml")
}

#[test]
fn a_layered_scene_reads_and_writes_its_layers() {
    let text = r#"
size = [64, 48]
[[layer]]
name = "the cube"
[layer.opacity3d.primary]
volume = { synthetic = { size = [9, 7, 11], seed = 3 } }
attribute = "amplitude"
[[layer]]
name = "horizon"
visible = false
offset = [1.0, -2.0, 3.5]
scale = 0.25
[layer.surface]
file = "top.obj"
colour = [0.9, 0.75, 0.2]
lighting = "none"
"#;
    let scene = parse(text).unwrap();
    assert!(scene.is_layered());
    let layers: Vec<_> = scene.layers().collect();
    assert_eq!(layers.len(), 2);
    assert_eq!(layers[0].0.name, "the cube");
    assert_eq!(layers[0].1.name(), "opacity3d");
    assert_eq!(layers[1].1.name(), "surface");
    assert!(!layers[1].0.visible);
    assert_eq!(layers[1].0.offset, [1.0, -2.0, 3.5]);
    // Written back as layers and read again: the same scene.
    let again = parse(&scene.to_toml()).unwrap();
    assert_eq!(again, scene);
    assert!(scene.to_toml().contains("[[layer]]"));
    // Data files are named by their layer's key.
    let keys: Vec<_> = scene.data_files().into_iter().map(|f| f.key).collect();
    assert_eq!(keys, ["layer.1.surface.file"]);
    // A one-technique scene stays one: written as [technique.NAME].
    let one = Scene::demo("v3o2-sum").unwrap();
    assert!(!one.is_layered() && one.to_toml().contains("[technique.opacity3d]"));
}

#[test]
fn a_wrong_layer_is_named_by_its_key_and_line() {
    let head = "size = [32, 32]\n[[layer]]\n[layer.surface]\nfile = \"a.obj\"\n";
    // A bad value: its dotted key with the layer's index, at its line.
    let bad =
        format!("{head}[[layer]]\nname = \"b\"\nscale = -2.0\n[layer.surface]\nfile = \"b.obj\"\n");
    let e = parse(&bad).unwrap_err();
    let SceneError::Invalid { key, line, .. } = &e else {
        panic!("{e}");
    };
    assert_eq!((key.as_str(), *line), ("layer.1.scale", 7), "{e}");
    let bad = format!("{head}[[layer]]\n[layer.surface]\nfile = \"b.obj\"\nopacity = 1.5\n");
    let e = parse(&bad).unwrap_err();
    let SceneError::Invalid { key, line, .. } = &e else {
        panic!("{e}");
    };
    assert_eq!((key.as_str(), *line), ("layer.1.surface.opacity", 8), "{e}");
    // A layer of two techniques, of none, and a scene of both forms.
    let two = format!("{head}[layer.quad]\n");
    assert!(parse(&two)
        .unwrap_err()
        .to_string()
        .contains("layer 0 (unnamed) must name exactly one technique's table"));
    let none = format!("{head}[[layer]]\nname = \"empty\"\n");
    assert!(parse(&none)
        .unwrap_err()
        .to_string()
        .contains("layer 1 (empty)"));
    let both = format!("{head}[technique.quad]\n");
    assert!(parse(&both).unwrap_err().to_string().contains("not both"));
    assert!(parse("size = [8, 8]\n")
        .unwrap_err()
        .to_string()
        .contains("[[layer]]"));
}

#[test]
fn a_missing_layer_file_names_the_layer_and_a_broken_hidden_layer_is_still_an_error() {
    let dir = common::temp_dir("layered-missing");
    std::fs::write(dir.join("a.obj"), plane_obj([0.0, 1.0], [0.0, 1.0], 0.0)).unwrap();
    let text = "[[layer]]\n[layer.surface]\nfile = \"a.obj\"\n[[layer]]\nname = \"gone\"\n[layer.surface]\nfile = \"gone.obj\"\n";
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    let e = Scene::load_checked(&dir.join("scene.toml")).unwrap_err();
    assert!(e.to_string().contains("layer.1.surface.file"), "{e}");
    // Hidden, with a broken file: it still has a place in the frame, so it is read.
    let broken = "[[layer]]\n[layer.surface]\nfile = \"a.obj\"\n[[layer]]\nname = \"broken\"\nvisible = false\n[layer.surface]\nfile = \"bad.obj\"\n";
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    std::fs::write(dir.join("broken.toml"), broken).unwrap();
    let scene = Scene::load(&dir.join("broken.toml")).unwrap();
    let h = headless(Backend::Egl);
    let e = render_on(&h, &scene)
        .err()
        .expect("a broken hidden layer fails");
    assert!(e.to_string().starts_with("layer 1 (broken): "), "{e}");
}

/// A technique's picture alone and as the one named layer of a layered scene: the same
/// pixels, so each technique's place in the world frame matches how it frames itself.
#[test]
fn one_named_layer_draws_what_its_technique_draws_alone() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("layered-one");
    std::fs::write(dir.join("h.obj"), horizon_obj(9, 6)).unwrap();
    let surface = format!(
        "size = [61, 47]\n[camera]\nrotation = [0.31, -0.22, 0.12, 0.917]\nzoom = 0.8\n[technique.surface]\nfile = \"{}\"\ncolour_by = \"elevation\"\n",
        dir.join("h.obj").display()
    );
    let mut scenes = vec![("surface", parse(&surface).unwrap())];
    for demo in [
        "v3o2-sum",
        "cellproj-spherical",
        "splats-section",
        "splats-section-precise",
    ] {
        let mut scene = Scene::demo(demo).unwrap();
        scene.size = [53, 41];
        scenes.push((demo, scene));
    }
    for (name, alone) in scenes {
        let mut layered = alone.clone();
        layered.layer.name = "it".into();
        assert!(layered.is_layered());
        let a = render_on(&h, &alone).unwrap().image;
        let b = render_on(&h, &layered).unwrap().image;
        let d = a.compare(&b, 0.0).unwrap();
        assert_eq!(d.pixels_over, 0, "{name}: {d:?}");
        assert!(common::lit_pixels(&a, 0.05) > 100, "{name} draws something");
    }
}

/// A surface scene of `params` drawn on the GPU (RGBA32F) and by its reference.
fn gpu_and_reference(
    h: &arbvis::gl::Headless,
    params: &SurfaceScene,
    prepared: &prepare::Prepared,
    fidelity: Fidelity,
    programs: ProgramChoice,
    camera: arbvis::camera::Camera,
    size: [u32; 2],
) -> (arbvis::image::Image, arbvis::image::Image) {
    let mut scene = parse("[technique.surface]\nfile = \"x.obj\"\n").unwrap();
    scene.technique = params.clone().into();
    (scene.fidelity, scene.programs, scene.camera, scene.size) = (fidelity, programs, camera, size);
    scene.target = Some(TargetFormat::Rgba32f);
    let gpu = render_on(h, &scene).unwrap().image;
    let cpu = reference::reference(prepared, params, fidelity, &camera, size, [0.0; 4]);
    (gpu, cpu)
}

/// A surface against its f64 reference (nearest hit per pixel centre, the headlight
/// per vertex or per pixel), ARB and GLSL, faithful and precise, on an uneven horizon in
/// UTM coordinates at an odd size and a rotated perspective camera.
#[test]
fn a_surface_matches_its_reference_in_both_fidelities_and_program_kinds() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("layered-surface");
    std::fs::write(dir.join("h.obj"), horizon_obj(11, 8)).unwrap();
    let params = SurfaceScene {
        colour_by: Some(arbvis::techniques::surface::ColourBy::Elevation),
        ..SurfaceScene::of(dir.join("h.obj"))
    };
    let mesh = arbvis::surface::read(&dir.join("h.obj")).unwrap();
    let table = params.table.build(&dir).unwrap();
    let prepared = prepare::of_mesh(&mesh, &params, Some(&table));
    for fidelity in [Fidelity::Faithful, Fidelity::Precise] {
        for programs in [ProgramChoice::Arb, ProgramChoice::Glsl] {
            let camera = arbvis::camera::Camera {
                projection: arbvis::camera::Projection::Perspective,
                rotation: [-0.21, 0.09, 0.13, 0.965],
                ..Default::default()
            };
            let (gpu, cpu) =
                gpu_and_reference(&h, &params, &prepared, fidelity, programs, camera, [73, 58]);
            let scene_size = [73u32, 58];
            // Inside triangles the GPU's f32 interpolation and lighting agree with f64
            // to ~1e-5; a pixel whose centre lies within f32 rounding of an edge may take
            // the other triangle (or the background at the silhouette), so the count of
            // pixels over one 8-bit level is bounded by the edge pixels (under 2 %).
            let d = gpu.compare(&cpu, LEVEL).unwrap();
            let pixels = (scene_size[0] * scene_size[1]) as usize;
            assert!(
                d.pixels_over * 50 < pixels,
                "{fidelity:?} {programs:?}: {d:?}"
            );
            assert!(d.rmse < 0.01, "{fidelity:?} {programs:?}: {d:?}");
            let lit = common::lit_pixels(&gpu, 0.05);
            // Perspective frames the unit sphere: the sheet covers about a quarter.
            assert!(
                lit > pixels / 6,
                "the horizon is in view: {lit} of {pixels}"
            );
        }
    }
}

/// An unlit plane behind a translucent volume: exactly the volume drawn over the plane's
/// colour (a background of that colour); in front: the plane's colour wherever it lies.
#[test]
fn an_opaque_surface_hides_a_volume_behind_it_and_shows_through_one_in_front() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("layered-occlusion");
    // The cube's world box: [0, 17] x [0, 13] x [0, 15] (synthetic, spacing 1). A square
    // plane centred on it, wider than it, below it (seen from above: behind) and above
    // it (in front); the frame's longest side is the plane's 37.
    let (x, y) = ([-10.0, 27.0], [-12.0, 25.0]);
    std::fs::write(dir.join("below.obj"), plane_obj(x, y, -4.0)).unwrap();
    std::fs::write(dir.join("above.obj"), plane_obj(x, y, 19.0)).unwrap();
    let colour = [0.25, 0.5, 0.75];
    let cube = r#"[layer.opacity3d]
combine = "sum"
slices = 96
[layer.opacity3d.primary]
volume = { synthetic = { size = [17, 13, 15], seed = 5 } }
attribute = "amplitude"
table = { builtin = "seismic", alpha = [[0.0, 0.7], [0.4, 0.0], [0.6, 0.0], [1.0, 0.7]] }
"#;
    let plane = |file: &str| {
        format!(
            "[[layer]]\nname = \"plane\"\n[layer.surface]\nfile = \"{}\"\ncolour = {colour:?}\nlighting = \"none\"\n",
            dir.join(file).display()
        )
    };
    // Seen from straight above (identity rotation: z toward the viewer), orthographic.
    // Zoom 1.15: the view spans +-0.87 of the frame, inside the plane's +-1.
    let head = "size = [61, 61]\nbackground = [0.0, 0.0, 0.0, 1.0]\n[camera]\nzoom = 1.15\n";
    let behind = parse(&format!(
        "{head}[[layer]]\nname = \"cube\"\n{cube}{}",
        plane("below.obj")
    ))
    .unwrap();
    let front = parse(&format!(
        "{head}{}[[layer]]\nname = \"cube\"\n{cube}",
        plane("above.obj")
    ))
    .unwrap();
    let behind_image = render_on(&h, &behind).unwrap().image;
    let front_image = render_on(&h, &front).unwrap().image;
    // The frame of the two planes and the cube is the planes' box: place the cube alone
    // there by drawing it with an invisible plane (hidden layers keep their place).
    let mut alone = behind.clone();
    alone.more_layers[0].0.visible = false;
    alone.background = [colour[0] as f32, colour[1] as f32, colour[2] as f32, 1.0];
    let over_colour = render_on(&h, &alone).unwrap().image;
    // Faithful, RGBA8: the same blends from the same bytes: identical.
    let d = behind_image.compare(&over_colour, 0.0).unwrap();
    assert_eq!(d.pixels_over, 0, "the volume over the plane: {d:?}");
    assert!(
        behind_image
            .compare(&front_image, LEVEL)
            .unwrap()
            .pixels_over
            > 100,
        "the cube shows over the plane behind it"
    );
    // In front: every pixel is the plane's colour (it covers the view).
    let want = [colour[0] as f32, colour[1] as f32, colour[2] as f32, 1.0];
    for (x, y) in [(0, 0), (30, 30), (60, 60), (20, 40)] {
        common::assert_close(front_image.pixel(x, y), want, LEVEL, "the plane in front");
    }
    let flat = arbvis::image::Image::filled(61, 61, TargetFormat::Rgba8, want);
    assert!(front_image.compare(&flat, LEVEL).unwrap().pixels_over == 0);
    // Precise with the ray caster (a pass over the whole box): drawn on precise slices
    // beside the opaque plane, so the plane in front still hides it (f32 target: exact).
    let mut precise = front.clone();
    precise.fidelity = Fidelity::Precise;
    let raycast = "[layer.opacity3d.raycast]\nsteps_per_voxel = 1.0\n";
    let text = precise.to_toml().replacen(
        "[layer.opacity3d.primary]",
        &format!("{raycast}[layer.opacity3d.primary]"),
        1,
    );
    let precise = parse(&text).unwrap();
    assert!(precise.to_toml().contains("[layer.opacity3d.raycast]"));
    let image = render_on(&h, &precise).unwrap().image;
    let flat = arbvis::image::Image::filled(61, 61, TargetFormat::Rgba32f, want);
    assert_eq!(
        image.compare(&flat, 1e-6).unwrap().pixels_over,
        0,
        "the ray caster hidden"
    );
}

/// A translucent closed surface (the cow, every sheet blended back to front) against the
/// reference that composites every hit of each pixel's ray in depth order.
#[test]
fn a_translucent_surface_composites_every_sheet_as_the_reference_does() {
    let h = headless(Backend::Egl);
    let file = common::data_file("surfaces/cow.obj");
    let params = SurfaceScene {
        opacity: 0.35,
        colour: [0.9, 0.6, 0.3],
        ..SurfaceScene::of(&file)
    };
    let mesh = arbvis::surface::read(&file).unwrap();
    let prepared = prepare::of_mesh(&mesh, &params, None);
    for (fidelity, programs) in [
        (Fidelity::Faithful, ProgramChoice::Arb),
        (Fidelity::Precise, ProgramChoice::Glsl),
    ] {
        let camera = arbvis::camera::Camera {
            rotation: [0.35, -0.41, 0.12, 0.83],
            ..Default::default()
        };
        let (gpu, cpu) =
            gpu_and_reference(&h, &params, &prepared, fidelity, programs, camera, [71, 53]);
        let scene_size = [71u32, 53];
        // The renderer orders triangles by their centroids, the reference each pixel's
        // hits exactly: they differ where two triangles overlap out of centroid order,
        // and at edges as for an opaque surface; both are a few pixels of the picture.
        let d = gpu.compare(&cpu, 2.0 * LEVEL).unwrap();
        let pixels = (scene_size[0] * scene_size[1]) as usize;
        assert!(d.pixels_over * 25 < pixels, "{fidelity:?}: {d:?}");
        assert!(d.rmse < 0.01, "{fidelity:?}: {d:?}");
        // Several sheets: the densest pixel holds more than one layer's opacity.
        let densest = gpu.data.chunks(4).map(|p| p[3]).fold(0.0f32, f32::max);
        assert!(densest > 0.35 + 0.1, "sheets accumulate: {densest}");
    }
}

/// Many layers of one surface placed apart share its data (read and uploaded once) and
/// draw in bounded time; past the limit a scene is refused by key.
#[test]
fn many_layers_of_one_file_are_read_once_and_too_many_are_refused() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("layered-many");
    std::fs::write(dir.join("p.obj"), plane_obj([0.0, 1.0], [0.0, 1.0], 0.0)).unwrap();
    let layer = |i: usize| {
        format!(
            "[[layer]]\noffset = [{}.0, {}.0, 0.0]\n[layer.surface]\nfile = \"p.obj\"\nlighting = \"none\"\n",
            (i % 40) * 2,
            (i / 40) * 2
        )
    };
    let text: String = (0..1600).map(layer).collect();
    std::fs::write(
        dir.join("many.toml"),
        format!("size = [80, 80]\n[camera]\nzoom = 1.4\n{text}"),
    )
    .unwrap();
    let scene = Scene::load(&dir.join("many.toml")).unwrap();
    let rendered = render_on(&h, &scene).unwrap();
    // 1600 unit squares on a 40 x 40 grid, 2 apart: a quarter of the grid's area.
    let lit = common::lit_pixels(&rendered.image, 0.5);
    assert!(lit > 80 * 80 / 8 && lit < 80 * 80 / 2, "{lit}");
    // One renderer for the 1600 layers: one vertex buffer holds the surface.
    let buffers = rendered
        .resources
        .iter()
        .filter(|r| r.label == "vertices surface")
        .count();
    assert_eq!(buffers, 1, "{:?}", rendered.resources);
    let text: String = (0..4097).map(layer).collect();
    let e = parse(&text).unwrap_err();
    assert!(
        e.to_string()
            .contains("layer: 4097 layers: a scene holds at most 4096"),
        "{e}"
    );
}

/// A value of the wrong shape in a layer is named with the layer's index, as the text's
/// `[[layer]]` tables count.
#[test]
fn a_value_of_the_wrong_shape_names_its_layer() {
    let text = "[[layer]]\n[layer.surface]\nfile = \"a.obj\"\n[[layer]]\nname = \"b\"\n[layer.surface]\nfile = \"b.obj\"\ncolour = [0.5, 0.5]\n";
    let SceneError::Parse { key, line, .. } = parse(text).unwrap_err() else {
        panic!("a parse error");
    };
    assert_eq!((key.as_deref(), line), (Some("layer.1.surface.colour"), 8));
}

/// F3's SEG-Y in the world: its first trace's first sample at the trace's CDP
/// coordinates (read here from the file's bytes) at z = 0, its samples downwards.
#[test]
fn a_segy_survey_lies_at_its_cdp_coordinates() {
    let path = common::data_file("seismic/f3.sgy");
    let bytes = std::fs::read(&path).unwrap();
    let header = &bytes[3600..3600 + 240];
    let i32_at = |at: usize| i32::from_be_bytes(header[at..at + 4].try_into().unwrap());
    let scalar = i16::from_be_bytes([header[70], header[71]]) as f64;
    let scale = if scalar < 0.0 {
        -1.0 / scalar
    } else if scalar > 0.0 {
        scalar
    } else {
        1.0
    };
    assert_eq!(
        (i32_at(188), i32_at(192)),
        (111, 875),
        "the file's first trace is the grid's first"
    );
    let cdp = [i32_at(180) as f64 * scale, i32_at(184) as f64 * scale];
    let scene = Scene::load(std::path::Path::new("scenes/data/f3-minimal.toml")).unwrap();
    let (_, world) = prepared_in_world(&scene, 0);
    // The first voxel's centre: half a voxel in from the box's corner (75 x 18 x 23).
    let dims = glam::DVec3::new(75.0, 18.0, 23.0);
    let first = -world.half + world.half / dims;
    let at = world.to_world(first);
    // The CDP coordinates are whole metres or finer; f64 at 6e6: 1e-8.
    assert!(
        (at.x - cdp[0]).abs() < 1e-6 && (at.y - cdp[1]).abs() < 1e-6,
        "{at} vs {cdp:?}"
    );
    assert!(at.z.abs() < 1e-9, "{at}");
    // The last sample lies 74 samples of 4 m below.
    let last = world.to_world(first + glam::DVec3::X * (world.half.x * 2.0 * 74.0 / 75.0));
    assert!((last.z + 296.0).abs() < 1e-6, "{last}");
}

/// A survey store is a 3D-opacity layer (issue 55): F3 converted into a store lies where
/// the SEG-Y lies (the same world, to f64 rounding of the CDP corners read from the
/// store's coordinate arrays); a layered scene of the store alone draws exactly its
/// one-technique picture; beside a horizon it draws; a window of the store is refused by
/// its layer.
#[test]
fn a_survey_store_is_a_layer_where_its_segy_lies() {
    let h = headless(Backend::Egl);
    let (_dir, f3, store) = crate::mdio::f3_store("layered-store");
    let volume =
        |v: String| format!("[layer.opacity3d.primary]\nvolume = {v}\nattribute = \"amplitude\"\n");
    let segy = volume(format!("{{ segy = \"{}\" }}", f3.display()));
    let zarr = volume(format!("{{ store = \"{}\" }}", store.display()));
    let worlds: Vec<_> = [&segy, &zarr]
        .iter()
        .map(|layer| {
            let scene = parse(&format!("[[layer]]\nname = \"F3\"\n{layer}")).unwrap();
            prepared_in_world(&scene, 0).1
        })
        .collect();
    let (a, b) = (worlds[0], worlds[1]);
    // Metres at 6e6 in f64, through two sums: a micrometre.
    assert!(
        (a.centre - b.centre).abs().max_element() < 1e-6,
        "{a:?} {b:?}"
    );
    assert!((a.half - b.half).abs().max_element() < 1e-12, "{a:?} {b:?}");
    assert!((a.units - b.units).abs() < 1e-9 && a.rotation.abs_diff_eq(b.rotation, 1e-12));
    // The store's layer draws what the store alone draws under the layer's placement:
    // the same renderer, the same bricks, the same pixels.
    let head = "size = [72, 56]\nfidelity = \"precise\"\n[camera]\nrotation = [0.31, -0.22, 0.12, 0.917]\n";
    let layered = format!("{head}[[layer]]\nname = \"F3\"\n{zarr}");
    let mut alone = parse(&format!(
        "{head}{}",
        zarr.replace("[layer.opacity3d", "[technique.opacity3d")
    ))
    .unwrap();
    alone.camera.placement = arbvis::layered::placements(&[b])[0];
    let draw = |text: &str| render_on(&h, &parse(text).unwrap()).unwrap().image;
    let got = draw(&layered);
    let want = render_on(&h, &alone).unwrap().image;
    assert_eq!(got.compare(&want, 0.0).unwrap().pixels_over, 0);
    assert!(
        common::lit_pixels(&got, 0.05) > 500,
        "the survey is in view"
    );
    // Beside the tracked horizon (its own file's coordinates).
    let horizon = format!(
        "[[layer]]\nname = \"horizon\"\n[layer.surface]\nfile = \"{}\"\ncolour = [0.9, 0.75, 0.2]\n",
        common::data_file("seismic/f3-horizon.ts").display()
    );
    let both = draw(&format!("{layered}{horizon}"));
    assert!(
        both.compare(&got, 0.0).unwrap().pixels_over > 100,
        "the horizon shows"
    );
    let windowed =
        format!("{layered}[layer.opacity3d.store]\nwindow = [[0, 0, 0], [40, 18, 23]]\n");
    let e = render_on(&h, &parse(&windowed).unwrap())
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("F3") && e.contains("a window of a store"), "{e}");
}

/// A layered scene's memory estimate says which layer makes each allocation.
#[test]
fn the_memory_estimate_names_each_layer() {
    let text = "[[layer]]\nname = \"cube\"\n[layer.opacity3d.primary]\nvolume = { synthetic = { size = [31, 17, 23], seed = 1 } }\nattribute = \"amplitude\"\n[[layer]]\n[layer.surface]\nsynthetic = { size = [9, 7] }\n";
    let scene = parse(text).unwrap();
    let estimates = scene.memory_estimate(false);
    assert!(
        estimates
            .iter()
            .any(|e| e.what.starts_with("layer 0 (cube): ")),
        "{estimates:?}"
    );
    let horizon = "layer 1: the 9x7 generated horizon's corners";
    let e = estimates
        .iter()
        .find(|e| e.what == horizon)
        .expect("the horizon's estimate");
    assert_eq!(e.bytes, 6 * 8 * 6 * 120);
}

/// A generated horizon past the memory budget is refused before anything is made, naming
/// its layer.
#[test]
fn a_horizon_past_the_memory_budget_is_refused_by_its_layer() {
    let dir = common::temp_dir("layered-budget");
    let scene = dir.join("big.toml");
    std::fs::write(
        &scene,
        "[[layer]]\nname = \"huge\"\n[layer.surface]\nsynthetic = { size = [2048, 2048] }\n[[layer]]\n[layer.surface]\nsynthetic = { size = [4, 4] }\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .args(["render", scene.to_str().unwrap(), "-o"])
        .arg(dir.join("big.png"))
        .args(["--memory-budget", "64M"])
        .output()
        .unwrap();
    common::refused(
        &out,
        "layer 0 (huge): the 2048x2048 generated horizon's corners",
    );
    assert!(!dir.join("big.png").exists());
}

/// A precise cloud drawn by tiles (one pass over the frame) beside an opaque plane: drawn
/// as points instead, which the plane's depth hides behind it and shows in front of it.
#[test]
fn an_opaque_plane_hides_a_precise_cloud_behind_it() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("layered-cloud");
    let cloud = "[layer.splats]\ncloud = { section = { points = 20000, seed = 3 } }\ncolour = \"facies\"\npoint_size = 6.0\nkernel = \"gaussian\"\ngauss_width = 0.35\nsort = \"radix\"\ndraw = \"tiles\"\n";
    // The cloud's world box, for planes that cover it.
    let probe = parse(&format!(
        "fidelity = \"precise\"\n[[layer]]\nname = \"c\"\n{cloud}"
    ))
    .unwrap();
    let [lo, hi] = prepared_in_world(&probe, 0).1.bounds();
    let margin = (hi - lo).max_element();
    let (x, y) = (
        [lo.x - margin, hi.x + margin],
        [lo.y - margin, hi.y + margin],
    );
    std::fs::write(dir.join("below.obj"), plane_obj(x, y, lo.z - 0.1 * margin)).unwrap();
    std::fs::write(dir.join("above.obj"), plane_obj(x, y, hi.z + 0.1 * margin)).unwrap();
    let colour = [0.25f32, 0.5, 0.75];
    let plane = |file: &str| {
        format!(
            "[[layer]]\nname = \"plane\"\n[layer.surface]\nfile = \"{}\"\ncolour = {colour:?}\nlighting = \"none\"\n",
            dir.join(file).display()
        )
    };
    // From straight above; the view inside the planes (zoom: the frame is 3x the cloud).
    let head = "size = [64, 48]\nfidelity = \"precise\"\nprograms = \"glsl\"\nbackground = [0.0, 0.0, 0.0, 1.0]\n[camera]\nzoom = 2.0\n";
    let layered = |plane_file: &str| {
        parse(&format!(
            "{head}[[layer]]\nname = \"cloud\"\n{cloud}{}",
            plane(plane_file)
        ))
        .unwrap()
    };
    let want = [colour[0], colour[1], colour[2], 1.0];
    let front = render_on(&h, &layered("above.obj")).unwrap().image;
    let flat = arbvis::image::Image::filled(64, 48, TargetFormat::Rgba32f, want);
    // An unlit plane's colour, exactly: f32 arithmetic on exact values.
    assert_eq!(
        front.compare(&flat, 1e-6).unwrap().pixels_over,
        0,
        "the plane hides the cloud"
    );
    // Behind: the cloud as points over the plane's colour, exactly.
    let behind = render_on(&h, &layered("below.obj")).unwrap().image;
    let mut alone = layered("below.obj");
    alone.more_layers[0].0.visible = false;
    alone.background = want;
    alone
        .technique
        .get_mut::<arbvis::techniques::splats::SplatsScene>()
        .unwrap()
        .draw = arbvis::techniques::splats::scene::DrawChoice::Points;
    let over_colour = render_on(&h, &alone).unwrap().image;
    let d = behind.compare(&over_colour, 0.0).unwrap();
    assert_eq!(d.pixels_over, 0, "{d:?}");
    assert!(common::lit_pixels(&behind, 0.05) > 0);
    assert!(
        behind.compare(&flat, LEVEL).unwrap().pixels_over > 50,
        "the cloud shows"
    );
}

/// A horizon exported as GOCAD TSurf (time positive downwards, UTM coordinates) lies in
/// the world where a survey in time hangs: z = -time; `inspect` describes it.
#[test]
fn a_tsurf_horizon_lies_at_minus_its_time() {
    let dir = common::temp_dir("layered-tsurf");
    let ts = "GOCAD TSurf 1\nHEADER {\nname:horizon\n}\nZPOSITIVE Depth\nTFACE\nVRTX 1 620200 6074300 140\nVRTX 2 620500 6074300 152\nVRTX 3 620200 6074700 148\nVRTX 4 620500 6074700 161\nTRGL 1 2 3\nTRGL 2 4 3\nEND\n";
    std::fs::write(dir.join("h.ts"), ts).unwrap();
    let scene = Scene::parse(
        &format!(
            "[[layer]]\nname = \"h\"\n[layer.surface]\nfile = \"{}\"\n",
            dir.join("h.ts").display()
        ),
        "h.toml",
    )
    .unwrap();
    let [lo, hi] = prepared_in_world(&scene, 0).1.bounds();
    // f64 through the object frame and back: 1e-9 of 6e6.
    assert!(
        lo.abs_diff_eq(glam::DVec3::new(620200.0, 6074300.0, -161.0), 1e-6),
        "{lo}"
    );
    assert!(
        hi.abs_diff_eq(glam::DVec3::new(620500.0, 6074700.0, -140.0), 1e-6),
        "{hi}"
    );
    let said = common::inspect(&dir.join("h.ts"));
    common::assert_says(&said, &["vertices: 4", "triangles: 2"]);
}

/// A horizontal sheet through a volume whose values change only with height takes, at
/// every corner, the volume's colour at that height: each of two sheets one colour, the
/// one the volume's table gives its slab ("seismic on the horizon", `colour_from`).
#[test]
fn a_surface_takes_the_colours_of_the_layer_it_lies_in() {
    let h = headless(Backend::Egl);
    let dir = common::temp_dir("layered-colour-from");
    // 8 x 6 x 5 voxels of 1 m, the value of slab k: 30 + 50 k (u8).
    let values: Vec<u8> = (0..5)
        .flat_map(|k| vec![30 + 50 * k as u8; 8 * 6])
        .collect();
    std::fs::write(dir.join("v.raw"), &values).unwrap();
    // A sheet of 12 x 12 nodes inside the footprint at height z (slab centres: k + 0.5).
    let sheet = |z: f64| {
        let mut text = String::new();
        for j in 0..12 {
            for i in 0..12 {
                text += &format!(
                    "v {} {} {z}\n",
                    0.6 + 6.8 * i as f64 / 11.0,
                    0.6 + 4.8 * j as f64 / 11.0
                );
            }
        }
        for j in 0..11 {
            for i in 0..11 {
                let v = |i: usize, j: usize| j * 12 + i + 1;
                text += &format!(
                    "f {} {} {}\nf {} {} {}\n",
                    v(i, j),
                    v(i + 1, j),
                    v(i + 1, j + 1),
                    v(i, j),
                    v(i + 1, j + 1),
                    v(i, j + 1)
                );
            }
        }
        text
    };
    std::fs::write(dir.join("low.obj"), sheet(1.5)).unwrap();
    std::fs::write(dir.join("high.obj"), sheet(3.5)).unwrap();
    let volume = "[[layer]]\nname = \"v\"\nvisible = false\n[layer.opacity3d.primary]\nvolume = { raw = { path = \"v.raw\", dims = [8, 6, 5], type = \"u8\" } }\nquantize = { range = [0.0, 255.0] }\ntable = { builtin = \"viridis\" }\n";
    let sheet_layer = |file: &str| {
        format!("[[layer]]\nname = \"{file}\"\n[layer.surface]\nfile = \"{file}\"\ncolour_from = {{ layer = \"v\" }}\nlighting = \"none\"\n")
    };
    let text = format!(
        "size = [40, 30]\nfidelity = \"precise\"\n{volume}{}{}",
        sheet_layer("low.obj"),
        sheet_layer("high.obj")
    );
    std::fs::write(dir.join("s.toml"), &text).unwrap();
    let scene = Scene::load(&dir.join("s.toml")).unwrap();
    let image = render_on(&h, &scene).unwrap().image;
    // Seen from above the high sheet hides the low one: one colour, slab 3's (180).
    let viridis = arbvis::colortable::ColorTable::builtin("viridis").unwrap();
    let colour = |level: usize| viridis.entries[level].map(|c| c as f32 / 255.0);
    let want = colour(180);
    let centre = image.pixel(20, 15);
    common::assert_close(
        centre,
        [want[0], want[1], want[2], 1.0],
        1e-5,
        "slab 3's colour",
    );
    // Without the high sheet: the low one, slab 1's (80).
    let mut low_only = scene.clone();
    low_only.more_layers[1].0.visible = false;
    let image = render_on(&h, &low_only).unwrap().image;
    let want = colour(80);
    common::assert_close(
        image.pixel(20, 15),
        [want[0], want[1], want[2], 1.0],
        1e-5,
        "slab 1's colour",
    );
    // A source that is not a layer of the scene is named.
    let bad = text.replace("layer = \"v\"", "layer = \"nope\"");
    std::fs::write(dir.join("bad.toml"), bad).unwrap();
    let e = render_on(&h, &Scene::load(&dir.join("bad.toml")).unwrap())
        .err()
        .unwrap();
    assert!(
        e.to_string().contains("colour_from names layer \"nope\""),
        "{e}"
    );
}

/// The horizon tracked on F3's peaks (data/seismic/f3-horizon.ts, UTM and ms) lies on
/// them in the world frame: sampled through F3's layer, nearly every vertex takes a
/// positive amplitude's colour (red in `seismic`); half a cycle below, few do; with time
/// up instead of down, none lies inside the survey.
#[test]
fn the_tracked_f3_horizon_lies_on_the_surveys_peaks() {
    let scene = Scene::load(std::path::Path::new("scenes/data/f3-horizon.toml")).unwrap();
    let layers: Vec<_> = scene.layers().collect();
    let (survey, survey_world) = prepared_in_world(&scene, 0);
    let (horizon, horizon_world) = prepared_in_world(&scene, 1);
    // The share of the horizon's corners on a positive amplitude, moved `down` metres (ms).
    let on_peaks = |down: f64| {
        let points: Vec<_> = arbvis::catalog::coloured_points(layers[1].1, &horizon)
            .into_iter()
            .map(|p| horizon_world.to_world(p) - glam::DVec3::Z * down)
            .map(|w| survey_world.to_object(w))
            .collect();
        let colours = arbvis::catalog::colours_at(layers[0].1, &survey, &points).unwrap();
        let inside: Vec<[f64; 3]> = colours.into_iter().flatten().collect();
        assert_eq!(
            inside.len(),
            points.len(),
            "every vertex lies inside the survey"
        );
        inside.iter().filter(|c| c[0] > c[2]).count() as f64 / inside.len() as f64
    };
    let share = on_peaks(0.0);
    // The tracker carries a time where the peak fades: 80 % of the corners lie on a
    // positive amplitude (measured: 0.806); half a cycle off (the trough 20 ms below),
    // 0.293 do. Fixed data, no randomness: the bounds sit between the two.
    let off = on_peaks(20.0);
    assert!(
        share > 0.75 && off < 0.35,
        "on the peak {share}, 20 ms below {off}"
    );
}

/// A ZMap+ grid of time (positive downwards, as it does not say) drawn with `z_down`:
/// its nodes at z = -time, the null node left out.
#[test]
fn a_zmap_time_grid_lies_at_minus_its_time() {
    let dir = common::temp_dir("layered-zmap");
    let grid = "@top, GRID, 3\n15, 1e30, , 4, 1\n2, 3, 620000.0, 620050.0, 6074000.0, 6074040.0\n0.0, 0.0, 0.0\n@\n120.0 122.5 121.0\n1e30 125.0 130.0\n";
    std::fs::write(dir.join("t.zmap"), grid).unwrap();
    let text = format!(
        "[[layer]]\n[layer.surface]\nfile = \"{}\"\nz_down = true\n",
        dir.join("t.zmap").display()
    );
    let scene = Scene::parse(&text, "t.toml").unwrap();
    let [lo, hi] = prepared_in_world(&scene, 0).1.bounds();
    // Column by column, north to south: the null is column 1's south node, which takes
    // five of the six triangles with it; the one left joins column 1's north node (121 ms)
    // to column 2's two (125, 130 ms).
    assert!(
        (lo.z + 130.0).abs() < 1e-9 && (hi.z + 121.0).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert!(
        (lo.x - 620025.0).abs() < 1e-6 && (hi.y - 6074040.0).abs() < 1e-6,
        "{lo} {hi}"
    );
    let said = common::inspect(&dir.join("t.zmap"));
    common::assert_says(&said, &["vertices: 5", "triangles: 1"]);
}
