"""Scenes of layers from Python: layers added, read, changed by dotted key, moved and
removed, each checked as a scene file is; data in memory in a layer; a layered picture
drawn and its layers hidden."""

import numpy as np
import pytest

import arbvis


def horizon_and_cube():
    """A generated horizon first, then a cube from memory (an odd, noisy volume)."""
    scene = arbvis.Scene.from_dict(
        {
            "size": [61, 47],
            "technique": {"surface": {"synthetic": {"size": [17, 11], "seed": 2}}},
        }
    )
    rng = np.random.default_rng(3)
    cube = rng.standard_normal((9, 13, 21)).astype(np.float32)
    scene.add_layer(
        "opacity3d",
        {"primary": {"volume": arbvis.Volume(cube), "attribute": "amplitude"}},
        name="cube",
        offset=(0.0, 0.0, -900.0),
    )
    return scene


def render(scene):
    with arbvis.Renderer(scene) as r:
        return r.render(), r.reference()


def test_layers_are_added_read_and_changed_by_key():
    scene = horizon_and_cube()
    layers = scene.layers
    assert len(layers) == 2
    assert "surface" in layers[0] and layers[1]["name"] == "cube"
    assert layers[1]["offset"] == [0.0, 0.0, -900.0]
    scene["layer.0.surface.opacity"] = 0.5
    assert scene["layer.0.surface.opacity"] == 0.5
    assert "[[layer]]" in scene.to_toml()
    with pytest.raises(arbvis.SceneError) as e:
        scene["layer.0.surface.opacity"] = 2.0
    assert e.value.key == "layer.0.surface.opacity"
    assert scene["layer.0.surface.opacity"] == 0.5, "the scene keeps its last good state"
    with pytest.raises(arbvis.SceneError) as e:
        scene.add_layer("surface", {"colour": [0.5, 0.5]}, name="bad")
    assert "layer.2" in str(e.value)
    with pytest.raises(KeyError):
        scene["layer.7.surface.opacity"] = 0.5


def test_layers_move_and_go_and_one_stays():
    scene = horizon_and_cube()
    scene.move_layer(1, 0)
    assert scene.layers[0]["name"] == "cube"
    scene.remove_layer(0)
    assert len(scene.layers) == 1 and "surface" in scene.layers[0]
    with pytest.raises(IndexError):
        scene.remove_layer(0)


def test_a_layered_picture_draws_each_visible_layer():
    scene = horizon_and_cube()
    both, reference = render(scene)
    assert reference is None, "a layered scene's exact composite is not built yet"
    scene["layer.1.visible"] = False
    horizon_only, _ = render(scene)
    scene["layer.1.visible"] = True
    scene["layer.0.visible"] = False
    cube_only, _ = render(scene)
    assert both.shape == (47, 61, 4)
    lit = lambda image: int((image[..., :3].sum(axis=2) > 0.05).sum())
    # Each layer draws something, and the picture of both differs from either alone.
    assert lit(horizon_only) > 100 and lit(cube_only) > 100
    assert np.abs(both - horizon_only).max() > 0.1
    assert np.abs(both - cube_only).max() > 0.1
