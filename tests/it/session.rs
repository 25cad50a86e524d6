//! The one interactive session below every front end (`arbvis::session`): a session
//! turned through views draws each as a fresh render of it does, with streamed data (a
//! COPC cloud's cut, a store's bricks) following the camera; a reduced frame keeps to the
//! frame budget.

use std::path::Path;

use arbvis::camera::Camera;
use arbvis::gl::{Backend, Headless};
use arbvis::image::Image;
use arbvis::scene::Scene;
use arbvis::session::{FrameBudget, Mode, Offscreen, Pending, Session};
use glam::DQuat;

use crate::common::{headless, temp_dir};

/// `count` rotations around the vertical axis, seen from 35 degrees above (as
/// `arbvis.dask.orbit`).
fn orbit(count: usize) -> Vec<[f64; 4]> {
    let tilt = DQuat::from_rotation_x(35f64.to_radians());
    (0..count)
        .map(|k| {
            let turn = DQuat::from_rotation_y(std::f64::consts::TAU * k as f64 / count as f64);
            (tilt * turn).to_array()
        })
        .collect()
}

/// `tests/fixtures/session-copc.toml` (the autzen cloud close up, at a budget that makes
/// the views want other cuts) beside its cloud, converted into `dir`.
fn copc_scene(dir: &Path) -> Scene {
    crate::remote::copc_fixture(dir);
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/session-copc.toml");
    let path = dir.join("session-copc.toml");
    std::fs::copy(fixture, &path).unwrap();
    Scene::load(&path).unwrap()
}

/// A session on the demo `name` (edited by `edit`) drawn with the context of `h`.
fn demo_session(h: &Headless, name: &str, edit: impl FnOnce(&mut Scene)) -> (Scene, Session) {
    let gpu = h.gpu();
    let mut scene = Scene::demo(name).unwrap();
    edit(&mut scene);
    let kind = scene.programs.resolve(gpu);
    let session = Session::build(gpu, &scene, kind, true).unwrap();
    (scene, session)
}

/// Pictures of `scene` turned through an orbit by one session, each beside a fresh
/// render of the same view.
pub fn turned_and_fresh(mut scene: Scene) -> Vec<(Image, Image)> {
    let mut session = Offscreen::new(&scene, Backend::Egl).unwrap();
    orbit(5)
        .into_iter()
        .map(|rotation| {
            scene.camera.rotation = rotation;
            let turned = session.render(&scene).unwrap();
            (turned, fresh_render(&scene))
        })
        .collect()
}

/// A fresh render of `scene` on a thread of its own (a GL context is current on one
/// thread: the session's stays current on this one).
fn fresh_render(scene: &Scene) -> Image {
    let scene = scene.clone();
    std::thread::spawn(move || arbvis::render::render(&scene, Backend::Egl).unwrap().image)
        .join()
        .unwrap()
}

/// Exact: the same cut, the same bricks, the same sort and programs draw the same bytes.
pub fn assert_each_view_equal(pairs: &[(Image, Image)], what: &str) {
    for (k, (turned, fresh)) in pairs.iter().enumerate() {
        assert!(
            turned.data == fresh.data,
            "{what}: view {k} differs from a fresh render"
        );
    }
    // The views differ, so the check above is not of one picture five times.
    assert!(
        pairs[0].0.data != pairs[2].0.data,
        "{what}: the orbit drew one picture"
    );
}

#[test]
fn a_copc_cloud_turned_by_one_session_draws_each_view_as_a_fresh_render() {
    let dir = temp_dir("session-copc");
    let pairs = turned_and_fresh(copc_scene(&dir));
    assert_each_view_equal(&pairs, "COPC");
}

#[test]
fn a_store_turned_by_one_session_draws_each_view_as_a_fresh_render() {
    let (dir, _) = crate::store::fixture("session-store", [37, 29, 45], 16);
    let volume = format!("{{ store = \"{}\" }}", dir.join("s.zarr").display());
    let text = crate::store::store_scene_text(&volume, "", 48);
    let pairs = turned_and_fresh(Scene::parse(&text, "test").unwrap());
    assert_each_view_equal(&pairs, "store");
}

/// While interacting, a frame over the budget is drawn smaller the next time, and a
/// still frame is the full picture, equal to the offscreen render.
#[test]
fn interactive_frames_shrink_to_the_budget_and_a_still_frame_is_the_full_picture() {
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let (mut scene, mut session) = demo_session(&h, "v3o2-sum", |s| s.size = [96, 80]);
    // A budget no frame can meet: the scale doubles each frame up to a tenth of a side.
    session.set_budget(FrameBudget {
        interactive: std::time::Duration::from_nanos(1),
        ..FrameBudget::default()
    });
    let mut scales = Vec::new();
    for k in 0..5 {
        scene.camera = Camera {
            zoom: 1.0 + 0.01 * k as f64,
            ..scene.camera
        };
        let pending = session.frame(gpu, &scene, Mode::Interacting).unwrap();
        assert_eq!(pending, Pending::Refine);
        scales.push(session.picture().scale);
    }
    assert_eq!(scales, [4.0, 8.0, 10.0, 10.0, 10.0]);
    let shown = session.shown().unwrap();
    // The last interactive picture was drawn at a tenth of each side (9.6 rounds to 10).
    assert_eq!([shown.width(), shown.height()], [10, 8]);
    assert_eq!(
        session.frame(gpu, &scene, Mode::Now).unwrap(),
        Pending::Done
    );
    let image = session.read(gpu, &scene).unwrap();
    let fresh = fresh_render(&scene);
    assert!(
        image.data == fresh.data,
        "the still picture differs from a render"
    );
}

/// Each technique's cheaper parameters at an image scale: splats keep their size relative
/// to the picture, 3D opacity draws a scale-th of its slices, a cell-projection volume's
/// pre-integrated table shrinks; at scale 1 nothing changes.
#[test]
fn the_cheaper_parameters_follow_the_scale() {
    use arbvis::techniques::cellproj::CellprojScene;
    use arbvis::techniques::opacity3d::Opacity3dScene;
    use arbvis::techniques::splats::SplatsScene;
    let splats = Scene::demo("splats-section").unwrap().technique;
    let size = |t: &arbvis::catalog::TechniqueScene| t.get::<SplatsScene>().unwrap().point_size;
    for scale in [1.0, 1.4, 2.5, 10.0] {
        let reduced = splats.for_interaction(scale);
        // The demo's 9-pixel splats, a scale-th of it (never under a pixel).
        assert!(
            (size(&reduced) - (9.0 / scale).max(1.0)).abs() < 1e-12,
            "{scale}"
        );
        // And every floor(scale)-th point.
        let stride = reduced.get::<SplatsScene>().unwrap().stride;
        assert_eq!(stride, scale.floor() as usize, "{scale}");
    }
    let v3o2 = Scene::demo("v3o2-sum").unwrap().technique;
    let slices = |t: &arbvis::catalog::TechniqueScene| t.get::<Opacity3dScene>().unwrap().slices;
    let full = slices(&v3o2);
    assert_eq!(slices(&v3o2.for_interaction(1.0)), full);
    assert_eq!(
        slices(&v3o2.for_interaction(2.5)),
        (full as f64 / 2.5) as usize
    );
    assert_eq!(slices(&v3o2.for_interaction(10.0)), full / 10);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data/bracket-volume.toml");
    let cells = Scene::parse(&std::fs::read_to_string(path).unwrap(), "test")
        .unwrap()
        .technique;
    let params = cells.get::<CellprojScene>().unwrap();
    let table = |t: &arbvis::catalog::TechniqueScene| {
        let p = t.get::<CellprojScene>().unwrap();
        p.volume
            .as_ref()
            .map_or(p.volume_spec().table_size, |v| v.table_size)
    };
    let whole = params.volume_spec().table_size;
    assert_eq!(table(&cells.for_interaction(1.0)), whole);
    // A table an eighth of each side (at least 8) at a quarter, as the viewer's quarter
    // quality had.
    assert_eq!(
        table(&cells.for_interaction(4.0)),
        whole.map(|s| (s / 8).max(8).min(s))
    );
}

/// A stride draws every k-th point of the order; back at 1, the picture is the full one
/// again (the same view ordered anew, not the strided order kept).
#[test]
fn a_stride_thins_the_splats_and_one_restores_them() {
    use arbvis::techniques::splats::SplatsScene;
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    // A smaller section than the demo's, for a test's time.
    let (scene, mut session) = demo_session(&h, "splats-section", |scene| {
        scene.size = [64, 48];
        if let Some(s) = scene.technique.get_mut::<SplatsScene>() {
            if let arbvis::points::PointSource::Section(spec) = &mut s.cloud {
                spec.points = 20_000;
            }
        }
    });
    let draw = |scene: &Scene, session: &mut Session| {
        session.params_changed(gpu, scene).unwrap();
        session.frame(gpu, scene, Mode::Now).unwrap();
        session.read(gpu, scene).unwrap()
    };
    let full = draw(&scene, &mut session);
    let mut thin = scene.clone();
    thin.technique.get_mut::<SplatsScene>().unwrap().stride = 7;
    let thinned = draw(&thin, &mut session);
    let again = draw(&scene, &mut session);
    assert!(full.data != thinned.data, "a stride of 7 drew every point");
    assert!(
        full.data == again.data,
        "stride 1 after 7 is not the full picture"
    );
    // A stride that no cloud could use is refused by name.
    let mut bad = scene.clone();
    bad.technique.get_mut::<SplatsScene>().unwrap().stride = 0;
    let e = session.params_changed(gpu, &bad).unwrap_err().to_string();
    assert!(e.contains("stride"), "{e}");
}

/// A layered scene's reduced frames reduce every layer, not only the first (issue 53 item
/// 2): at a quarter, two 3D-opacity layers each draw a quarter of their slices into a
/// picture a quarter of each side, exactly as a fresh render of that scene draws it.
#[test]
fn a_layered_scenes_reduced_frame_reduces_every_layer() {
    use arbvis::session::InteractiveQuality;
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let layer = |name: &str, seed: u32, offset: f64| {
        format!("[[layer]]\nname = \"{name}\"\noffset = [{offset}, 0.0, 0.0]\n[layer.opacity3d]\nslices = 96\n[layer.opacity3d.primary]\nvolume = {{ synthetic = {{ size = [19, 13, 17], seed = {seed} }} }}\nattribute = \"amplitude\"\n")
    };
    let text = format!(
        "size = [96, 72]\n[camera]\nrotation = [0.2, -0.3, 0.1, 0.926]\n{}{}",
        layer("a", 4, 0.0),
        layer("b", 5, 14.0)
    );
    let scene = Scene::parse(&text, "layers.toml").unwrap();
    let kind = scene.programs.resolve(gpu);
    let mut session = Session::build(gpu, &scene, kind, true).unwrap();
    session.quality = InteractiveQuality::Quarter;
    let pending = session.frame(gpu, &scene, Mode::Interacting).unwrap();
    assert_eq!(pending, Pending::Refine);
    let reduced = session.shown().unwrap().read(gpu).unwrap();
    assert_eq!([reduced.width, reduced.height], [24, 18]);
    // The scene as the reduced frame should draw it: every layer's cheaper parameters,
    // a quarter of each side; and as it was drawn when only the first layer was reduced.
    let reduced_scene = |layers: usize| {
        let mut s = scene.clone();
        s.size = [24, 18];
        for (_, t) in s.layers_mut().take(layers) {
            *t = t.for_interaction(4.0);
        }
        s
    };
    let want = fresh_render(&reduced_scene(2));
    assert!(
        reduced.data == want.data,
        "the reduced frame differs from its scene's render"
    );
    let first_only = fresh_render(&reduced_scene(1));
    assert!(
        first_only.data != want.data,
        "the second layer's slices change its picture"
    );
}
