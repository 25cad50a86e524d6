"""What a PyVista user reaches for first (issue 56 item 4): numpy numbers anywhere a scene
takes numbers, a picture in a notebook (`_repr_png_`), and clear refusals where a call
cannot mean anything (a zoom of 0, pictures of two sizes, a JPEG name for a PNG, a SEG-Y
given as a scene, two techniques in one scene, a closed renderer's reference)."""

import re

import numpy as np
import pytest

import arbvis


def test_numpy_numbers_and_arrays_stand_for_python_ones():
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.zoom = np.float32(1.5)
    scene.rotation = np.array([0.1, 0.2, 0.0, 0.97])
    scene.size = np.array([64, 48], dtype=np.int64)
    scene["technique.opacity3d.primary.coefficients"] = np.array([0.2, 0.3, 0.1, 0.9], np.float32)
    scene["technique.opacity3d.slices"] = np.int16(40)
    assert scene.zoom == pytest.approx(1.5)
    assert scene.size == (64, 48)
    assert scene["technique.opacity3d.slices"] == 40
    assert scene["technique.opacity3d.primary.coefficients"] == pytest.approx([0.2, 0.3, 0.1, 0.9])
    # NaN is no number a scene holds, from numpy either.
    with pytest.raises(ValueError):
        scene.zoom = np.float64("nan")
    with pytest.raises(TypeError):
        scene.zoom = object()


@pytest.mark.parametrize("zoom", [0, -1.0, 1e9])
def test_a_zoom_that_shows_nothing_is_refused_by_key(zoom):
    scene = arbvis.Scene.demo("quad")
    with pytest.raises(arbvis.SceneError) as e:
        scene.zoom = zoom
    assert e.value.key == "camera.zoom" and "above 0" in str(e.value)
    assert scene.zoom == 1.0, "the scene keeps its last good state"


def test_a_scene_shows_itself_as_a_png_in_a_notebook(tmp_path):
    scene = arbvis.Scene.demo("quad")
    scene.size = (48, 32)
    png = scene._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "scene.png").write_bytes(png)
    with arbvis.Renderer(scene) as r:
        want = r.render()
    assert np.array_equal(arbvis.read_png(str(tmp_path / "scene.png")), want)


def test_compare_and_write_png_refuse_what_means_nothing(tmp_path):
    a = np.zeros((4, 5, 4), np.uint8)
    with pytest.raises(ValueError, match="sizes differ: 5x4 and 5x3"):
        arbvis.compare(a, np.zeros((3, 5, 4), np.uint8))
    for tolerance in (-0.1, float("nan")):
        with pytest.raises(ValueError, match="tolerance"):
            arbvis.compare(a, a, tolerance)
    assert arbvis.compare(a, a, 0.0)["max_abs"] == 0.0
    with pytest.raises(ValueError, match="name it .png"):
        arbvis.write_png(str(tmp_path / "x.jpg"), a)
    assert not (tmp_path / "x.jpg").exists()


def test_a_data_file_given_as_a_scene_says_what_it_is(root):
    with pytest.raises(arbvis.SceneError) as e:
        arbvis.Scene.load(str(root / "data/seismic/f3.sgy"))
    assert "SEG-Y" in str(e.value) and "not a scene" in str(e.value)


def test_two_techniques_in_one_scene_are_told_apart():
    with pytest.raises(arbvis.SceneError) as e:
        arbvis.Scene.from_dict({"technique": {"quad": {}, "splats": {}}})
    assert "a scene draws one technique" in str(e.value)


def test_a_closed_renderer_draws_no_reference():
    r = arbvis.Renderer(arbvis.Scene.demo("quad"))
    r.close()
    with pytest.raises(RuntimeError, match="closed"):
        r.reference()


def test_a_renderer_says_what_its_last_frame_drew(f3_store_scene):
    with arbvis.Renderer(f3_store_scene) as r:
        assert r.stats()["frame_ms"] == 0.0, "no frame yet"
        r.render()
        stats = r.stats()
        assert stats["frame_ms"] > 0.0
        # A store's renderer says which bricks and levels it drew, as --stats prints it.
        assert stats["status"] and "brick" in stats["status"], stats
        assert isinstance(stats["facts"], dict)
    with arbvis.Renderer(arbvis.Scene.demo("quad")) as r:
        r.render()
        assert r.stats()["status"] is None and r.stats()["frame_ms"] > 0.0
    with pytest.raises(RuntimeError, match="closed"):
        r.stats()


class FakeColormap:
    """What matplotlib's colormaps are to arbvis.table: called with positions in 0..1,
    they give RGBA rows."""

    N = 256

    def __call__(self, t):
        t = np.asarray(t)
        return np.column_stack([t, 1 - t, 0.5 + 0.5 * np.sin(9 * t), 0.2 + 0.8 * t])


def test_a_colour_table_from_an_array_or_a_colormap_draws_as_its_table_file(tmp_path):
    rng = np.random.default_rng(4)
    levels = rng.integers(0, 256, (256, 4), dtype=np.uint8)  # a rough table, not a ramp
    np.savetxt(tmp_path / "rough.table", levels, fmt="%d")
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.size = (64, 48)
    scene.base = str(tmp_path)
    scene["technique.opacity3d.primary.table"] = {"file": "rough.table"}
    with arbvis.Renderer(scene) as r:
        want = r.render()
        scene["technique.opacity3d.primary.table"] = arbvis.table(levels)
        assert np.array_equal(r.render(), want)
        # 256 float colours land on the entries as the file's levels do.
        scene["technique.opacity3d.primary.table"] = arbvis.table(levels / 255.0)
        assert np.array_equal(r.render(), want)
        # A colormap: sampled at 256 positions; three columns are opaque unless an alpha
        # curve says otherwise.
        spec = arbvis.table(FakeColormap())
        assert len(spec["colors"]) == 256 and spec["colors"][255][3] == pytest.approx(1.0)
        scene["technique.opacity3d.primary.table"] = spec
        assert not np.array_equal(r.render(), want)
        three = arbvis.table(levels[:, :3], alpha=[[0.0, 0.0], [1.0, 0.5]])
        assert three["alpha"] == [[0.0, 0.0], [1.0, 0.5]] and three["colors"][0][3] == 1.0
    for bad, says in [
        (np.zeros((1, 3)), "2 <= N <= 4096"),
        (np.zeros((4, 5)), "(N, 3) or (N, 4)"),
        (np.full((4, 3), 2.0), "in 0..1"),
        (np.zeros((4, 3), np.int32), "floats in 0..1 or uint8"),
    ]:
        with pytest.raises(arbvis.InputError, match=re.escape(says)):
            arbvis.table(bad)
    # Colours given in a scene that make no table: the scene's error, with the key.
    with pytest.raises(arbvis.SceneError) as e:
        scene["technique.opacity3d.primary.table"] = {"colors": [[0.0, 0.0, 0.0, 2.0]] * 3}
    assert e.value.key.endswith("table.colors")


def test_the_camera_turns_resets_and_maps_points_to_pixels(root):
    scene = arbvis.Scene.demo("quad")
    scene.size = (200, 100)
    scene.rotation = (0.0, 0.0, 0.0, 1.0)
    # The centre of the frame is the centre of the picture.
    assert np.allclose(scene.to_pixels(np.zeros((1, 3))), [[100.0, 50.0]])
    # Identity: +x is right, +y is up (pixels count down), at zoom 1 the frame's side
    # fills the shorter side (100 pixels for 2 units).
    px = scene.to_pixels(np.array([[1.0, 0, 0], [0, 1.0, 0]]))
    assert np.allclose(px, [[150.0, 50.0], [100.0, 0.0]])
    # The eye moved right around the data: the point that faced it goes left.
    scene.azimuth(90)
    assert scene.to_pixels(np.array([[0, 0, 1.0]]))[0, 0] == pytest.approx(50.0)
    for _ in range(3):
        scene.azimuth(90)
    assert np.allclose(np.abs(scene.rotation), (0, 0, 0, 1), atol=1e-12)
    # The eye moved up over the data: the point that faced it goes down.
    scene.elevation(90)
    assert scene.to_pixels(np.array([[0, 0, 1.0]]))[0, 1] == pytest.approx(100.0)
    scene.elevation(-90)
    assert np.allclose(np.abs(scene.rotation), (0, 0, 0, 1), atol=1e-12)
    # The matrices: clip = projection @ view @ point.
    m = scene.projection_matrix() @ scene.view_matrix()
    assert m.shape == (4, 4) and np.allclose(m @ [1, 0, 0, 1], [0.5, 0, 0, 1])
    with pytest.raises(ValueError):
        scene.azimuth(float("inf"))
    # A survey's scene (no [camera] in its file) resets to its three-quarter view.
    survey = arbvis.Scene.load(str(root / "scenes/data/f3-minimal.toml"))
    first = (survey.rotation, survey.zoom)
    assert first[0] != pytest.approx((0.0, 0.0, 0.0, 1.0))
    survey.azimuth(40)
    survey.zoom = 3.0
    assert survey.rotation != pytest.approx(first[0])
    survey.reset_camera()
    assert survey.rotation == pytest.approx(first[0]) and survey.zoom == pytest.approx(first[1])


def test_a_wrong_shaped_value_in_a_whole_scene_names_its_key():
    # As the setters do (scene[key] = value): the dotted key of the value of the wrong shape.
    with pytest.raises(arbvis.SceneError) as e:
        arbvis.Scene.from_dict({"technique": {"quad": {"left": 5}}})
    assert e.value.key == "technique.quad.left" and "technique.quad.left" in str(e.value)
    with pytest.raises(arbvis.SceneError) as e:
        arbvis.Scene.from_toml("[camera]\nrotation = [\n  0.1,\n  \"x\", 0.0, 1.0]\n[technique.quad]\n")
    assert e.value.key == "camera.rotation" and e.value.line == 4
