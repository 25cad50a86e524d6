//! Which COPC nodes a view draws (issue 28, item 3): Potree's policy on laspy's
//! `simple_with_page.copc.laz` (65 nodes over four levels). Never more points than the
//! budget (a stride of the root's when the root alone is over it); every node taken has
//! its parent taken; nodes under the pixel size are left; a node called outside the view
//! has all eight corners outside one plane of the clip volume (checked here by projecting
//! them, not by the selector's spheres); a zoomed-in, rotated perspective view culls and
//! draws the nodes in front deeper; `render` draws the cut and `--stats` says so.

use std::process::Command;

use arbvis::camera::{Camera, Projection};
use arbvis::points::copc::Copc;
use arbvis::points::copc_lod::{frame, select, Cut, View};
use glam::DVec4;

use crate::common::splats::camera_turned as camera;
use crate::common::splats::{errors, quantile};
use crate::common::{data_file, stdout_of, temp_dir};

fn copc() -> Copc {
    Copc::open(&data_file("points/simple_with_page.copc.laz")).unwrap()
}

/// A scene file over `simple_with_page.copc.laz`: `head` (size, fidelity, camera lines)
/// then `[technique.splats]` with its cloud and `keys`.
fn copc_scene_file(name: &str, head: &str, keys: &str) -> std::path::PathBuf {
    let path = temp_dir(name).join("copc.toml");
    std::fs::write(
        &path,
        format!(
            "{head}[technique.splats]\ncloud = {{ copc = {{ path = \"{}\" }} }}\ncolour = \"rgb\"\n{keys}",
            data_file("points/simple_with_page.copc.laz").display()
        ),
    )
    .unwrap();
    path
}

/// The eight corners of a node's cube in the cloud's frame, in clip coordinates.
fn corners(c: &Copc, view: &View, key: [i32; 4]) -> Vec<DVec4> {
    let (origin, scale) = frame(c);
    let i = c.info;
    let side = 2.0 * i.halfsize / f64::from(1 << key[0]);
    let lo = [
        i.center_x - i.halfsize + side * key[1] as f64,
        i.center_y - i.halfsize + side * key[2] as f64,
        i.center_z - i.halfsize + side * key[3] as f64,
    ];
    (0..8)
        .map(|k| {
            let p: [f64; 3] =
                std::array::from_fn(|a| (lo[a] + side * ((k >> a) & 1) as f64 - origin[a]) / scale);
            view.view_projection * DVec4::new(p[0], p[1], p[2], 1.0)
        })
        .collect()
}

/// Whether every corner lies outside the same clip plane.
fn outside(corners: &[DVec4]) -> bool {
    let planes: [fn(&DVec4) -> bool; 6] = [
        |p| p.x < -p.w,
        |p| p.x > p.w,
        |p| p.y < -p.w,
        |p| p.y > p.w,
        |p| p.z < -p.w,
        |p| p.z > p.w,
    ];
    planes.iter().any(|f| corners.iter().all(f))
}

/// The cut's invariants: within the budget, parents before children.
fn check(c: &Copc, cut: &Cut, budget: u64) {
    assert!(cut.points / cut.root_stride <= budget.max(1), "{cut:?}");
    if cut.root_stride > 1 {
        assert_eq!(cut.nodes.len(), 1);
    }
    let keys: Vec<[i32; 4]> = cut.nodes.iter().map(|n| n.key).collect();
    for k in &keys[1..] {
        let parent = [k[0] - 1, k[1] >> 1, k[2] >> 1, k[3] >> 1];
        assert!(keys.contains(&parent), "{k:?} without its parent");
    }
    assert_eq!(keys[0], [0, 0, 0, 0]);
    let _ = c;
}

/// Settle `r` at `camera` until the cut it loads has arrived whole (a stage of it may
/// arrive first on a slow machine) or failed; panics after 30 s.
fn settle_until_loaded(
    r: &mut Box<dyn arbvis::techniques::Renderer>,
    gpu: &arbvis::gl::Gpu,
    camera: &Camera,
    size: [u32; 2],
    what: &str,
) {
    let start = std::time::Instant::now();
    let mut arrived = false;
    loop {
        arrived |= r.settle(gpu, camera, size).unwrap();
        if arrived && !r.pending() {
            return;
        }
        assert!(
            start.elapsed().as_secs() < 30,
            "{what}: the cut never arrived"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

#[test]
fn budgets_are_never_passed_and_parents_come_first() {
    let c = copc();
    let rotated = [0.3, -0.5, 0.1, 0.8];
    for projection in [Projection::Orthographic, Projection::Perspective] {
        let view = View::of(&camera(projection, 1.3, rotated), [1600, 900]);
        for budget in [1, 10, 23, 24, 25, 90, 100, 287, 500, 1065, 10_000] {
            let cut = select(&c, &view, budget, 0.0).unwrap();
            check(&c, &cut, budget);
            if budget >= 1065 {
                assert_eq!(cut.nodes.len(), 65, "{projection:?}: every node fits");
            }
        }
        // The root's 24 points over a budget of 10: every third.
        assert_eq!(select(&c, &view, 10, 0.0).unwrap().root_stride, 3);
    }
}

#[test]
fn the_pixel_size_decides_the_depth() {
    let c = copc();
    let cam = camera(Projection::Orthographic, 1.0, [0.0, 0.0, 0.0, 1.0]);
    // A thumbnail: every child's sphere projects under 150 px; only the root.
    let small = select(&c, &View::of(&cam, [64, 48]), 1_000_000, 150.0).unwrap();
    assert_eq!(small.nodes.len(), 1);
    assert_eq!(small.too_small, 4);
    // 1600 x 900: the root's sphere is about 780 px in radius, halving each level:
    // levels 0-2 are over 150 px, level 3 (about 97 px) is not.
    let large = select(&c, &View::of(&cam, [1600, 900]), 1_000_000, 150.0).unwrap();
    assert_eq!(large.deepest, 2, "{large:?}");
    assert_eq!(large.nodes.len(), 1 + 4 + 12);
    assert_eq!(large.too_small, 48);
    // Without a pixel size, the budget alone.
    assert_eq!(
        select(&c, &View::of(&cam, [64, 48]), 1_000_000, 0.0)
            .unwrap()
            .nodes
            .len(),
        65
    );
}

#[test]
fn a_zoomed_rotated_perspective_culls_what_it_cannot_see() {
    let c = copc();
    let cam = camera(Projection::Perspective, 4.0, [0.2, 0.6, -0.1, 0.75]);
    let view = View::of(&cam, [800, 600]);
    let cut = select(&c, &view, 1_000_000, 0.0).unwrap();
    check(&c, &cut, 1_000_000);
    assert!(cut.culled > 0, "{cut:?}");
    let taken: Vec<[i32; 4]> = cut.nodes.iter().map(|n| n.key).collect();
    let mut outside_count = 0;
    for n in &c.all_nodes().unwrap() {
        let out = outside(&corners(&c, &view, n.key));
        outside_count += usize::from(out);
        // A node entirely outside one plane is never drawn; one whose parent is drawn
        // and that is not outside is drawn (no pixel size, budget to spare). The
        // selector's sphere test is looser than the cube, so only these two hold.
        if out {
            assert!(!taken.contains(&n.key), "{:?} is outside but drawn", n.key);
        }
    }
    assert!(
        outside_count >= cut.culled,
        "{outside_count} {}",
        cut.culled
    );
    // Seen whole, nothing is culled.
    let whole = View::of(
        &camera(Projection::Perspective, 0.8, [0.2, 0.6, -0.1, 0.75]),
        [800, 600],
    );
    assert_eq!(select(&c, &whole, 1_000_000, 0.0).unwrap().culled, 0);
}

#[test]
fn render_draws_the_cut_and_stats_say_what_it_holds() {
    let scene = copc_scene_file(
        "copc-lod-render",
        "size = [320, 180]\n[camera]\nrotation = [0.2, 0.6, -0.1, 0.75]\nprojection = \"perspective\"\n",
        "",
    );
    let dir = scene.parent().unwrap().to_path_buf();
    let out = dir.join("copc.png");
    let said = stdout_of(
        Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["--stats", "--point-budget", "100"]),
    );
    assert!(said.contains("COPC: "), "{said}");
    // The root page's 60 nodes known; the child page under (2, 0, 0, 0) left unread.
    assert!(
        said.contains("of the 60 nodes of the 1 hierarchy page read (1 not read)"),
        "{said}"
    );
    let drawn: u64 = said
        .split(" points drawn")
        .next()
        .and_then(|s| s.rsplit('\n').next())
        .and_then(|s| s.split(" of ").next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("{said}"));
    assert!((24..=100).contains(&drawn), "{said}");
    assert!(out.is_file());
}

/// Splat sizes follow the spacing: a point of a drawn node counts the spacing of the
/// deepest level drawn in its child octant, over the deepest level's: 1, 2 or 4 here
/// (levels 0-2 drawn), 1 for the level-2 nodes' own points (their children are not).
#[test]
fn coarse_points_stand_in_for_their_missing_children() {
    use arbvis::points::PointSource;
    let cam = camera(Projection::Orthographic, 1.0, [0.0, 0.0, 0.0, 1.0]);
    let view = View::of(&cam, [1600, 900]);
    let (cloud, loaded) =
        PointSource::copc(data_file("points/simple_with_page.copc.laz"), 1_000_000)
            .load_for(std::path::Path::new("."), Some(&view))
            .unwrap();
    let loaded = loaded.unwrap();
    assert_eq!(cloud.len(), 24 + 66 + 197);
    let scales = &loaded.size_scales;
    assert_eq!(scales.len(), cloud.len());
    assert!(
        scales.iter().all(|s| [1.0, 2.0, 4.0].contains(s)),
        "{scales:?}"
    );
    // Nodes come largest first: the last 197 points are the level-2 nodes'.
    assert!(scales[24 + 66..].iter().all(|s| *s == 1.0));
    // The root's points: some stand in for a level drawn only to 1 or 2 below.
    assert!(scales[..24].iter().any(|s| *s < 4.0), "{:?}", &scales[..24]);
    assert!(
        loaded.describe.contains("17 of 65 nodes"),
        "{}",
        loaded.describe
    );
}

/// The splats-lod study on the small file: every budget's points within it, the whole
/// cloud's picture its own reference (RMSE 0), a coarser cut further from it than the
/// finest but one.
#[test]
fn the_lod_study_measures_each_budget_against_every_point() {
    let scene_path = copc_scene_file(
        "copc-lod-study",
        "size = [160, 90]\nfidelity = \"precise\"\n[camera]\nrotation = [0.2, 0.6, -0.1, 0.75]\n",
        "draw = \"tiles\"\n",
    );
    let scene = arbvis::scene::Scene::load(&scene_path).unwrap();
    let h = crate::common::headless(arbvis::gl::Backend::Egl);
    let rows = arbvis::techniques::splats::study::lod::lod(&h, &scene, &[24, 300, 1065], 1, |_| {})
        .unwrap();
    assert_eq!(rows.len(), 3);
    for r in &rows {
        assert!(
            r.points <= r.budget && r.ms.is_finite() && r.ms > 0.0,
            "{r:?}"
        );
    }
    assert_eq!(rows[2].points, 1065);
    assert_eq!(rows[2].rmse, 0.0);
    assert!(rows[0].rmse > 0.0, "{rows:?}");
    let csv = arbvis::techniques::splats::study::lod::to_csv(&rows);
    assert!(
        csv.starts_with("budget,points,nodes,deepest_level,ms_turning,rmse\n24,24,1,0,"),
        "{csv}"
    );
}

/// The viewer's hook once the camera stops: a COPC renderer loads the nodes of the new
/// view on a thread, keeps drawing the old cut until they arrive (pending), then says
/// so; nothing when the view is the one it has.
#[test]
fn a_still_camera_loads_the_nodes_of_its_view() {
    let scene_path = copc_scene_file("copc-lod-settle", "size = [800, 450]\n", "");
    let scene = arbvis::scene::Scene::load(&scene_path).unwrap();
    let h = crate::common::headless(arbvis::gl::Backend::Egl);
    let gpu = h.gpu();
    let kind = scene.programs.resolve(gpu);
    let mut r = arbvis::catalog::build(gpu, &scene.technique, &scene.settings(), kind).unwrap();
    let before = r.status().unwrap();
    assert!(!r.settle(gpu, &scene.camera, scene.size).unwrap());
    let closer = camera(Projection::Perspective, 5.0, [0.2, 0.6, -0.1, 0.75]);
    // The cut is loaded on a thread: the drawn one stays (pending) until it arrives.
    assert!(!r.settle(gpu, &closer, scene.size).unwrap());
    assert!(r.pending());
    assert_eq!(r.status().unwrap(), before);
    settle_until_loaded(&mut r, gpu, &closer, scene.size, "the closer view");
    assert!(!r.pending());
    let after = r.status().unwrap();
    assert_ne!(
        before.lines().next(),
        after.lines().next(),
        "{before}\n{after}"
    );
    assert!(after.contains("outside the view"), "{after}");
    assert!(!r.settle(gpu, &closer, scene.size).unwrap());
}

/// A damaged node met when the camera stops: the drawn cut stays and the status line says
/// which node could not be read.
#[test]
fn a_damaged_node_keeps_the_drawn_cut_and_says_so() {
    let dir = temp_dir("copc-lod-damaged");
    let good = data_file("points/simple_with_page.copc.laz");
    let copc = Copc::open(&good).unwrap();
    let mut b = std::fs::read(&good).unwrap();
    for n in copc.all_nodes().unwrap().iter().filter(|n| n.key[0] == 3) {
        for k in 0..n.bytes as usize {
            let at = n.offset as usize + k;
            b[at] = b[at].wrapping_mul(31).wrapping_add(7);
        }
    }
    let damaged = dir.join("damaged.copc.laz");
    std::fs::write(&damaged, &b).unwrap();
    let text = format!(
        "size = [800, 450]\n[technique.splats]\ncloud = {{ copc = {{ path = \"{}\" }} }}\ncolour = \"rgb\"\n",
        damaged.display()
    );
    let scene = arbvis::scene::Scene::parse(&text, "damaged.toml").unwrap();
    let h = crate::common::headless(arbvis::gl::Backend::Egl);
    let gpu = h.gpu();
    let kind = scene.programs.resolve(gpu);
    // The first view reaches level 2 only (level 3 is under 150 px): it draws.
    let mut r = arbvis::catalog::build(gpu, &scene.technique, &scene.settings(), kind).unwrap();
    let closer = camera(Projection::Perspective, 5.0, [0.2, 0.6, -0.1, 0.75]);
    assert!(!r.settle(gpu, &closer, scene.size).unwrap());
    settle_until_loaded(&mut r, gpu, &closer, scene.size, "the damaged view");
    let status = r.status().unwrap();
    assert!(
        status.contains("not refined: ") && status.contains("node [3,"),
        "{status}"
    );
    // A stage drawn before the error no longer says it is loading.
    assert!(!status.contains("loading: "), "{status}");
    // And it still draws.
    let target = arbvis::gl::Target::new(gpu, 80, 45, arbvis::gl::TargetFormat::Rgba8).unwrap();
    let frame = arbvis::techniques::Frame {
        camera: closer,
        width: 80,
        height: 45,
    };
    r.draw(gpu, arbvis::gl::Surface::Target(&target), &frame)
        .unwrap();
}

/// Decoded nodes are kept between cuts: a second load of the same view reads no node
/// again, and its points are the same.
#[test]
fn a_second_cut_takes_its_nodes_from_memory() {
    use arbvis::points::copc::CopcSpec;
    use arbvis::points::PointSource;
    let view = View::of(
        &camera(Projection::Orthographic, 1.0, [0.1, 0.2, 0.0, 0.97]),
        [640, 360],
    );
    let source = PointSource::Copc(CopcSpec {
        path: data_file("points/simple_with_page.copc.laz"),
        points: 1_000_000,
        min_node_pixels: 0.0,
    });
    let (first, _) = source
        .load_for(std::path::Path::new("."), Some(&view))
        .unwrap();
    let (second, loaded) = source
        .load_for(std::path::Path::new("."), Some(&view))
        .unwrap();
    let said = loaded.unwrap().describe;
    assert!(said.contains("65 of its 65 nodes from memory"), "{said}");
    assert_eq!(first, second);
    assert!(arbvis::points::copc_cache::held() > 0);
}

/// The GPU node cache: when the camera stops and a new cut arrives, only the nodes the
/// vertex buffer lacks are uploaded, and the picture is the one a renderer built afresh
/// for that view draws, bit for bit. A budget of 100 points (room for 150 in the buffer),
/// every node eligible, and six views zoomed in turn make nodes leave, come back and be
/// evicted.
#[test]
fn a_refined_cut_uploads_only_what_the_buffer_lacks_and_draws_as_a_fresh_one() {
    let text = format!(
        "size = [160, 90]\nfidelity = \"precise\"\n[technique.splats]\ncloud = {{ copc = {{ path = \"{}\", points = 100, min_node_pixels = 0.0 }} }}\ncolour = \"rgb\"\n",
        data_file("points/simple_with_page.copc.laz").display()
    );
    let scene = arbvis::scene::Scene::parse(&text, "cache.toml").unwrap();
    let h = crate::common::headless(arbvis::gl::Backend::Egl);
    let gpu = h.gpu();
    let kind = scene.programs.resolve(gpu);
    let draw = |r: &mut Box<dyn arbvis::techniques::Renderer>, camera: &Camera| {
        crate::common::splats::draw_renderer(gpu, &mut **r, camera, [160, 90])
    };
    let mut r = arbvis::catalog::build(gpu, &scene.technique, &scene.settings(), kind).unwrap();
    let views = [
        camera(Projection::Perspective, 5.0, [0.2, 0.6, -0.1, 0.75]),
        camera(Projection::Perspective, 8.0, [-0.3, 0.1, 0.4, 0.85]),
        camera(Projection::Orthographic, 6.0, [0.05, -0.2, 0.1, 0.97]),
        camera(Projection::Perspective, 9.0, [0.7, -0.3, 0.2, 0.6]),
        camera(Projection::Orthographic, 7.0, [-0.5, 0.5, 0.5, 0.5]),
        camera(Projection::Perspective, 5.0, [0.2, 0.6, -0.1, 0.75]),
    ];
    let (mut kept, mut evicted) = (0, 0);
    for (k, c) in views.iter().enumerate() {
        settle_until_loaded(&mut r, gpu, c, scene.size, &format!("view {k}"));
        let status = r.status().unwrap();
        let line = status
            .lines()
            .find(|l| l.starts_with("node cache: "))
            .unwrap_or_else(|| panic!("view {k}: no node cache line in\n{status}"));
        let words: Vec<&str> = line.split_whitespace().collect();
        let (uploaded, nodes): (usize, usize) =
            (words[2].parse().unwrap(), words[6].parse().unwrap());
        assert!(uploaded <= nodes, "{line}");
        kept += nodes - uploaded;
        evicted += words[9].parse::<usize>().unwrap();
        // The same view built afresh draws the same picture.
        let mut settings = scene.settings();
        settings.view = View::of(c, scene.size);
        let mut fresh = arbvis::catalog::build(gpu, &scene.technique, &settings, kind).unwrap();
        let (a, b) = (draw(&mut r, c), draw(&mut fresh, c));
        assert_eq!(a.data, b.data, "view {k}: {line}");
        assert!(
            a.data.chunks(4).any(|p| p[3] > 0.0),
            "view {k} drew nothing"
        );
    }
    // Nodes were kept from cut to cut, and some evicted for others.
    assert!(kept > 0 && evicted > 0, "kept {kept}, evicted {evicted}");
}

/// Precise points take each point's size scale as the tiles do: a cut of 192 points over
/// levels 0-2 (a budget of 200, every node eligible) in which 41 coarse points stand in
/// at twice the size for the level-2 nodes not drawn, drawn as GL points (GLSL and ARB)
/// and as tiles, agrees within the f32 rounding the splat tests measure between the two
/// (99.9 % of channels within 1e-4).
#[test]
fn precise_points_size_each_point_as_the_tiles_do() {
    let text = |draw: &str, programs: &str| {
        format!(
            "size = [1600, 900]\nfidelity = \"precise\"\nprograms = \"{programs}\"\nbackground = [0.0, 0.0, 0.0, 1.0]\n[camera]\nprojection = \"orthographic\"\n[technique.splats]\ncloud = {{ copc = {{ path = \"{}\", points = 200, min_node_pixels = 0.0 }} }}\ncolour = \"rgb\"\npoint_size = 10.0\ndraw = \"{draw}\"\n",
            data_file("points/simple_with_page.copc.laz").display()
        )
    };
    let h = crate::common::headless(arbvis::gl::Backend::Egl);
    let render = |text: String| {
        let scene = arbvis::scene::Scene::parse(&text, "scales.toml").unwrap();
        arbvis::render::render_on(&h, &scene).unwrap().image
    };
    let tiles = render(text("tiles", "glsl"));
    for programs in ["glsl", "arb"] {
        let points = render(text("points", programs));
        let p999 = quantile(&errors(&tiles, &points), 0.999);
        // Measured 3e-8 (1.2e-7 at most); points drawn at their unscaled size put 38,208
        // channels more than 1e-3 off.
        assert!(p999 < 1e-4, "{programs}: 99.9 % within {p999:e}");
        let lit = crate::common::lit_pixels(&points, 0.0);
        assert!(lit > 1000, "{programs}: {lit} pixels drawn");
    }
}
