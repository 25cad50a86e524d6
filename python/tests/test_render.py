"""arbvis.Renderer: numpy arrays, frames after edits equal to fresh renderers', goldens,
errors, two threads."""

import copy
import shutil
import threading

import numpy as np
import pytest

import arbvis
import arbvis.dask


def quad(size=128, programs="arb"):
    scene = arbvis.Scene.demo("quad")
    scene.size = (size, size)
    scene.programs = programs
    return scene


def test_the_quad_equals_the_rust_tests_golden(root):
    # The golden of tests/it/quad.rs (llvmpipe, ARB, 128x128); one 8-bit level as there.
    with arbvis.Renderer(quad()) as r:
        image = r.render()
        assert r.program_kind == "arb"
    assert image.shape == (128, 128, 4) and image.dtype == np.uint8
    golden = arbvis._arbvis.read_png(str(root / "tests/snapshots/quad/quad_arb_128.png"))
    d = arbvis._arbvis.compare(image, golden, 1.0 / 255.0)
    assert d["max_abs"] <= 1.0 / 255.0 + 1e-6, d


def test_a_precise_picture_is_float32_handed_over_without_a_copy():
    scene = arbvis.Scene.demo("quad")
    scene.size = (40, 30)
    scene.fidelity = "precise"
    with arbvis.Renderer(scene) as r:
        image = r.render()
    assert image.shape == (30, 40, 4) and image.dtype == np.float32
    # Handed over, not copied: numpy does not own the buffer (Rust's Vec does).
    assert not image.flags["OWNDATA"]
    assert image.flags["C_CONTIGUOUS"]


@pytest.mark.parametrize("demo", ["v3o2-sum", "quad"])
def test_frames_after_edits_equal_a_fresh_renderers(demo):
    scene = arbvis.Scene.demo(demo)
    scene.size = (72, 56)
    edits = [
        ("zoom", 1.3),
        ("rotation", (0.2, 0.3, 0.1, 0.927)),
        ("size", (50, 64)),
    ]
    if demo == "v3o2-sum":
        edits.append(("technique.opacity3d.primary.coefficients", [0.7, 0.1, 0.3, 0.2]))
        edits.append(("technique.opacity3d.slices", 61))
    else:
        edits.append(("technique.quad.left", [0.3, 0.9, 0.1, 1.0]))
    with arbvis.Renderer(scene) as r:
        first = r.render()
        for key, value in edits:
            if key in ("zoom", "rotation", "size"):
                setattr(scene, key, value)
            else:
                scene[key] = value
            edited = r.render()
            with arbvis.Renderer(scene) as fresh:
                expected = fresh.render()
            assert edited.shape == expected.shape, key
            assert np.array_equal(edited, expected), key
        assert not np.array_equal(first.shape, edited.shape) or not np.array_equal(
            first, edited
        )


def test_a_scene_given_to_render_becomes_the_renderers():
    with arbvis.Renderer(quad(32)) as r:
        first = r.render()
        other = quad(32)
        other["technique.quad.right"] = [1.0, 1.0, 0.0, 1.0]
        image = r.render(other)
        assert r.scene == other
    with arbvis.Renderer(other) as fresh:
        assert np.array_equal(image, fresh.render())
    # The right edge took the new colour (yellow for blue): more green, less blue.
    assert (image[:, -1, 1] >= first[:, -1, 1]).all() and image[:, -1, 1].sum() > first[:, -1, 1].sum()
    assert image[:, -1, 2].sum() < first[:, -1, 2].sum()


def test_render_errors_are_arbvis_exceptions():
    scene = arbvis.Scene.demo("quad")
    scene.programs = "glsl"
    with arbvis.Renderer(scene) as r:
        r.render()
        r.close()
        with pytest.raises(RuntimeError):
            r.render()
    with pytest.raises(ValueError):
        arbvis.Renderer(scene, backend="vulkan")


def test_two_renderers_in_two_threads_draw_what_one_draws_alone():
    scenes = [arbvis.Scene.demo("v3o2-sum"), arbvis.Scene.demo("quad")]
    for s in scenes:
        s.size = (64, 64)
    alone = []
    for s in scenes:
        with arbvis.Renderer(s) as r:
            alone.append(r.render())
    together = [None, None]

    def draw(i):
        with arbvis.Renderer(scenes[i]) as r:
            for _ in range(3):
                together[i] = r.render()

    threads = [threading.Thread(target=draw, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(alone, together):
        assert np.array_equal(a, b)


def test_one_renderer_shared_by_threads_editing_and_drawing_never_panics():
    # One thread edits the scene in a tight loop (each edit holds the scene a moment)
    # while two others draw through one renderer: every frame is a picture of one of the
    # scene's states, no call fails, and close() waits for the frames asked before it.
    scene = quad(size=32)
    colours = [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]]
    with arbvis.Renderer(scene) as r:
        states = []
        for c in colours:
            scene["technique.quad.left"] = c
            states.append(r.render())
        stop = threading.Event()
        errors, frames = [], []

        def edit():
            i = 0
            while not stop.is_set():
                scene["technique.quad.left"] = colours[i % 2]
                i += 1

        def draw():
            try:
                for _ in range(15):
                    frames.append(r.render())
            except BaseException as e:  # a PanicException is a BaseException
                errors.append(e)

        editor = threading.Thread(target=edit)
        drawers = [threading.Thread(target=draw) for _ in range(2)]
        editor.start()
        for t in drawers:
            t.start()
        for t in drawers:
            t.join()
        stop.set()
        editor.join()
    assert not errors, errors
    assert len(frames) == 30
    for f in frames:
        assert any(np.array_equal(f, s) for s in states)
    # Closed while another thread draws: that frame is drawn or refused by name.
    r = arbvis.Renderer(quad(size=32))
    outcome = []

    def late():
        try:
            for _ in range(20):
                r.render()
            outcome.append("drawn")
        except RuntimeError as e:
            outcome.append(str(e))

    t = threading.Thread(target=late)
    t.start()
    r.close()
    t.join()
    assert outcome == ["drawn"] or outcome == ["the renderer is closed"], outcome


def test_ten_renderers_in_ten_threads_each_draw_the_single_picture():
    # Under load: ten renderers of one scene at once in one process, each turned through
    # the same three views; every frame equals the one renderer's frame of that view.
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.size = (48, 40)
    views = [(0.0, 0.0, 0.0, 1.0), (0.0, 0.6, 0.0, 0.8), (0.5, 0.5, -0.5, 0.5)]

    def frames(s):
        with arbvis.Renderer(s) as r:
            out = []
            for q in views:
                s.rotation = q
                out.append(r.render())
            return out

    alone = frames(copy.copy(scene))
    results = [None] * 10

    def work(i):
        results[i] = frames(copy.copy(scene))

    threads = [threading.Thread(target=work, args=(i,)) for i in range(10)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i, got in enumerate(results):
        assert got is not None, f"renderer {i} drew nothing"
        for v, (a, b) in enumerate(zip(alone, got)):
            assert np.array_equal(a, b), f"renderer {i}, view {v}"


def test_osmesa_draws_what_egl_draws():
    scene = quad(64)
    with arbvis.Renderer(scene) as egl, arbvis.Renderer(scene, backend="osmesa") as osmesa:
        assert osmesa.backend == "osmesa"
        assert np.array_equal(egl.render(), osmesa.render())


def test_info_reports_the_driver():
    report = arbvis.info()
    assert report["backend"] == "egl"
    assert report["renderer"]
    assert report["linear_filter_error"] >= 0


def test_the_reference_is_what_a_precise_quad_draws():
    scene = quad(48, "glsl")
    scene.fidelity = "precise"
    with arbvis.Renderer(scene) as r:
        image, reference = r.render(), r.reference()
    assert reference.dtype == np.float32 and reference.shape == image.shape
    # RGBA32F: interpolation and arithmetic in f32, relative ~1e-6 on values <= 1; 1e-5
    # leaves margin for the rasterizer's barycentrics (as tests/it/quad.rs).
    assert np.abs(image - reference).max() <= 1e-5


def test_more_slices_come_closer_to_the_3d_opacity_reference():
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.size = (64, 64)
    scene.fidelity = "precise"
    errors = []
    with arbvis.Renderer(scene) as r:
        reference = r.reference()
        for slices in (16, 64, 256):
            scene["technique.opacity3d.slices"] = slices
            rgb = r.render()[..., :3] - reference[..., :3]
            errors.append(float(np.sqrt((rgb**2).mean())))
    assert errors[0] > errors[1] > errors[2], errors


def test_a_technique_without_a_reference_says_none():
    scene = arbvis.Scene.demo("splats-section")
    scene.size = (32, 32)
    with arbvis.Renderer(scene) as r:
        assert r.reference() is None


def test_a_turned_copc_cloud_and_store_equal_a_fresh_renderers_views(
    root, tmp_path, f3_store_scene
):
    # One renderer turned through an orbit draws each view as a renderer made for that
    # view does: a COPC cloud's cut and a store's bricks follow the camera (a renderer
    # that kept its first cut differed by up to 0.84 on 44 % of the pixels).
    # The Rust session test's scene (tests/fixtures/session-copc.toml), beside its cloud.
    written = arbvis.convert(
        root / "data/points/autzen_trim.laz", tmp_path / "c.copc.laz", node_points=2000
    )
    assert written["nodes"] > 10 and written["levels"] > 2, written
    shutil.copy(root / "tests/fixtures/session-copc.toml", tmp_path)
    cloud = arbvis.Scene.load(tmp_path / "session-copc.toml")
    for scene in (cloud, f3_store_scene):
        pictures = []
        with arbvis.Renderer(scene) as turned:
            for rotation in arbvis.dask.orbit(5, elevation_deg=35.0):
                scene.rotation = rotation
                picture = turned.render()
                with arbvis.Renderer(scene) as fresh:
                    expected = fresh.render()
                # Exact: the same cut, the same sort, the same programs.
                assert np.array_equal(picture, expected), rotation
                pictures.append(picture)
        assert not np.array_equal(pictures[0], pictures[2])


def test_interactive_frames_shrink_within_the_budget_and_a_full_render_follows():
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.size = (120, 90)
    with arbvis.Renderer(scene) as r:
        assert r.budget_ms == 66.0
        with pytest.raises(ValueError):
            r.budget_ms = 0.0
        # A budget no frame meets: each frame's scale doubles, to a tenth of each side.
        r.budget_ms = 1e-6
        shapes = []
        for k in range(5):
            scene.zoom = 1.0 + 0.01 * k
            shapes.append(r.render(interactive=True).shape)
        # 1/2, 1/4, 1/8, then 1/10 of 120 x 90 (sides rounded).
        assert shapes == [(45, 60, 4), (23, 30, 4), (11, 15, 4), (9, 12, 4), (9, 12, 4)]
        full = r.render()
        with arbvis.Renderer(scene) as fresh:
            assert np.array_equal(full, fresh.render())
