"""arbvis.notebook.View, the kernel's side of the notebook view (issue 56 item 2): its
frames are the renderer's pictures as PNG; the page's drags turn the scene (smaller
frames within the budget while dragging, the full picture on release), its wheel zooms,
its resizes are clamped; what the page sends that is not a message is said and ignored;
edits made from Python show; two views live side by side. (The page in a browser:
test_notebook_browser.py.)"""

import numpy as np
import pytest

import arbvis
from arbvis.notebook import MAX_SIDE, MIN_SIDE, View


def picture_of(png, tmp_path, name="frame.png"):
    """A view's PNG frame as the (height, width, 4) uint8 array it holds."""
    path = tmp_path / name
    path.write_bytes(png)
    return arbvis.read_png(path)


def fresh(scene):
    """The scene drawn by a renderer of its own, in 8 bits as the view sends it."""
    with arbvis.Renderer(scene) as r:
        image = r.render()
    if image.dtype != np.uint8:
        image = np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)
    return image


def survey_scene():
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.size = (96, 80)
    return scene


def test_a_views_frame_is_its_scenes_picture(tmp_path):
    scene = survey_scene()
    view = View(scene)
    try:
        assert view.frames == 1 and view.size == [96, 80] and view.error == ""
        assert view.frame[:8] == b"\x89PNG\r\n\x1a\n"
        shown = picture_of(view.frame, tmp_path)
        assert shown.shape == (80, 96, 4)
        assert np.array_equal(shown, fresh(scene))
    finally:
        view.close()


def test_a_drag_turns_the_scene_and_a_release_draws_the_full_picture(tmp_path):
    scene = survey_scene()
    view = View(scene)
    try:
        first = picture_of(view.frame, tmp_path, "first.png")
        rotation = scene.rotation
        # A budget no frame meets: the dragging frame is drawn smaller.
        view.renderer.budget_ms = 0.001
        view._on_message(view, {"kind": "drag", "dx": 40, "dy": 0}, [])
        assert view.frames == 2 and view.error == ""
        assert scene.rotation != rotation, "the scene turned"
        dragging = picture_of(view.frame, tmp_path, "drag.png")
        assert dragging.shape[0] < 80 and dragging.shape[1] < 96, dragging.shape
        view._on_message(view, {"kind": "release", "dx": 0, "dy": 0}, [])
        turned = picture_of(view.frame, tmp_path, "turned.png")
        assert turned.shape == (80, 96, 4)
        assert np.array_equal(turned, fresh(scene)), "the full picture of the turned scene"
        assert not np.array_equal(turned, first), "the turn shows"
        # Dragging back turns it back: the first picture again.
        view._on_message(view, {"kind": "release", "dx": -40, "dy": 0}, [])
        assert np.allclose(scene.rotation, rotation, atol=1e-12)
        back = picture_of(view.frame, tmp_path, "back.png")
        assert np.array_equal(back, fresh(scene))
        assert np.abs(back.astype(int) - first.astype(int)).max() <= 1
    finally:
        view.close()


def test_the_wheel_zooms_and_a_resize_is_clamped(tmp_path):
    scene = survey_scene()
    view = View(scene)
    try:
        zoom = scene.zoom
        view._on_message(view, {"kind": "zoom", "factor": 1.5}, [])
        assert scene.zoom == pytest.approx(zoom * 1.5)
        assert np.array_equal(picture_of(view.frame, tmp_path), fresh(scene))
        for _ in range(40):
            view._on_message(view, {"kind": "zoom", "factor": 40.0}, [])
        assert scene.zoom == 1000.0, "held at the wheel's largest zoom"
    finally:
        view.close()
    quad = arbvis.Scene.demo("quad")
    view = View(quad)
    try:
        view._on_message(view, {"kind": "resize", "width": 10**6, "height": 3}, [])
        assert view.size == [MAX_SIDE, MIN_SIDE] and quad.size == (MAX_SIDE, MIN_SIDE)
        assert picture_of(view.frame, tmp_path).shape == (MIN_SIDE, MAX_SIDE, 4)
        view._on_message(view, {"kind": "resize", "width": 120.4, "height": 70}, [])
        assert view.size == [120, 70]
    finally:
        view.close()


@pytest.mark.parametrize(
    "message, says",
    [
        ("drag", "a message from the page is a dict"),
        ({"kind": "fly"}, "kind is drag, release, zoom or resize, got 'fly'"),
        ({"kind": "x" * 10**6}, "got 'xxxxxxxx"),
        ({"kind": "drag", "dx": "1"}, "drag: dx is a number, got '1'"),
        ({"kind": "drag", "dx": float("nan")}, "drag: dx nan is outside"),
        ({"kind": "drag", "dx": True}, "drag: dx is a number, got True"),
        ({"kind": "drag", "dy": 1e300}, "drag: dy 1e+300 is outside"),
        ({"kind": "zoom", "factor": 0}, "zoom: factor 0 is outside"),
        ({"kind": "zoom", "factor": -2.0}, "zoom: factor -2.0 is outside"),
        ({"kind": "resize", "width": -5, "height": 10}, "resize: width -5 is outside"),
        ({"kind": "resize", "width": [1], "height": 10}, "resize: width is a number"),
    ],
)
def test_what_the_page_sends_that_is_not_a_message_is_said_and_ignored(message, says):
    scene = survey_scene()
    view = View(scene)
    try:
        before = (scene.rotation, scene.zoom, scene.size, view.frame)
        view._on_message(view, message, [])
        assert says in view.error, view.error
        assert len(view.error) < 200, "the page's text is not echoed whole"
        assert (scene.rotation, scene.zoom, scene.size, view.frame) == before
        assert view.frames == 2, "the page hears back, so it sends its next drag"
        # The next good message clears the error.
        view._on_message(view, {"kind": "release"}, [])
        assert view.error == ""
    finally:
        view.close()


def test_an_edit_from_python_shows_and_two_views_live_side_by_side(tmp_path):
    one, two = survey_scene(), arbvis.Scene.demo("quad")
    a, b = View(one), View(two)
    try:
        one["technique.opacity3d.primary.coefficients"] = [0.2, 0.2, 0.2, 0.9]
        a.refresh()
        assert np.array_equal(picture_of(a.frame, tmp_path, "a.png"), fresh(one))
        two["technique.quad.left"] = [0.1, 0.9, 0.3, 1.0]
        b.refresh()
        assert np.array_equal(picture_of(b.frame, tmp_path, "b.png"), fresh(two))
        a._on_message(a, {"kind": "release", "dx": 25, "dy": -10}, [])
        assert np.array_equal(picture_of(a.frame, tmp_path, "a2.png"), fresh(one))
        assert np.array_equal(picture_of(b.frame, tmp_path, "b2.png"), fresh(two))
    finally:
        a.close()
        b.close()


def test_a_view_shows_a_scene_only():
    with pytest.raises(TypeError, match="View shows an arbvis.Scene, got dict"):
        View({"size": [4, 4]})
