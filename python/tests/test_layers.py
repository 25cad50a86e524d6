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


def test_a_surface_from_arrays_and_from_a_grid_draws_as_its_file(tmp_path):
    """An uneven height field as an OBJ file, as vertices and triangles, and as a grid:
    one picture; a NaN node leaves its cells out; bad arrays are refused by name."""
    rng = np.random.default_rng(4)
    x, y = 635000.0 + 25.0 * np.arange(9), 848000.0 + 12.5 * np.arange(7)
    z = -400 + 30 * rng.standard_normal((9, 7))
    grid = arbvis.Surface.grid(z, x, y)
    assert len(grid) == 2 * 8 * 6
    gx, gy = np.meshgrid(x, y, indexing="ij")
    vertices = np.stack([gx.ravel(), gy.ravel(), z.ravel()], axis=1)
    node = np.arange(63).reshape(9, 7)
    a, b, c, d = node[:-1, :-1].ravel(), node[1:, :-1].ravel(), node[1:, 1:].ravel(), node[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    obj = "".join(f"v {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}\n" for p in vertices)
    obj += "".join(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n" for t in triangles)
    (tmp_path / "h.obj").write_text(obj)
    text = "size = [57, 43]\n[technique.surface]\nfile = \"h.obj\"\ncolour_by = \"elevation\"\n"
    scene = arbvis.Scene.from_toml(text, base=tmp_path)
    want, _ = render(scene)
    for surface in (arbvis.Surface(vertices, triangles), grid):
        scene["technique.surface.file"] = surface
        assert scene["technique.surface.file"] == {"memory": surface.name}
        got, _ = render(scene)
        assert np.array_equal(got, want)
    holed = z.copy()
    holed[4, 3] = np.nan
    assert len(arbvis.Surface.grid(holed, x, y)) == 2 * 8 * 6 - 6, "the node's six triangles"
    with pytest.raises(arbvis.InputError, match="surface: triangle 1 is"):
        arbvis.Surface(vertices, np.array([[0, 1, 2], [0, 1, 99]]))
    with pytest.raises(arbvis.InputError, match="surface: vertex 2 has a non-finite"):
        bad = vertices.copy()
        bad[2, 1] = np.inf
        arbvis.Surface(bad, triangles)
    with pytest.raises(arbvis.SceneError):
        scene["technique.surface.file"] = 5


def test_a_surface_with_a_property_draws_as_its_tsurf(tmp_path):
    """Values per vertex handed over with the arrays (`properties=`) or the grid colour a
    surface as the same values in a TSurf's PVRTX lines do (`colour_by = { property }`);
    a NaN is a vertex without a value; values of the wrong shape are refused by name."""
    rng = np.random.default_rng(8)
    x, y = 620000.0 + 25.0 * np.arange(7), 6074000.0 + 25.0 * np.arange(5)
    z = -130.0 + 6.0 * rng.standard_normal((7, 5))
    throw = 18.0 * rng.random((7, 5))
    throw[2, 3] = np.nan
    grid = arbvis.Surface.grid(z, x, y, properties={"throw": throw})
    assert grid.properties == ["throw"]
    gx, gy = np.meshgrid(x, y, indexing="ij")
    vertices = np.stack([gx.ravel(), gy.ravel(), z.ravel()], axis=1)
    node = np.arange(35).reshape(7, 5)
    a, b, c, d = node[:-1, :-1].ravel(), node[1:, :-1].ravel(), node[1:, 1:].ravel(), node[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    ts = "GOCAD TSurf 1\nPROPERTIES throw\nNO_DATA_VALUES -99999\nTFACE\n"
    for k, (p, t) in enumerate(zip(vertices, throw.ravel())):
        t = -99999.0 if np.isnan(t) else float(t)
        ts += f"PVRTX {k + 1} {float(p[0])!r} {float(p[1])!r} {float(p[2])!r} {t!r}\n"
    ts += "".join(f"TRGL {t[0] + 1} {t[1] + 1} {t[2] + 1}\n" for t in triangles) + "END\n"
    (tmp_path / "f.ts").write_text(ts)
    text = (
        "size = [53, 41]\nfidelity = \"precise\"\n[technique.surface]\nfile = \"f.ts\"\n"
        "colour_by = { property = \"throw\" }\ntable = { builtin = \"plasma\" }\n"
    )
    scene = arbvis.Scene.from_toml(text, base=tmp_path)
    want, _ = render(scene)
    assert np.abs(want[..., :3] - want[20, 26, :3]).max() > 0.2, "the colours vary"
    arrays = arbvis.Surface(vertices, triangles, properties={"throw": throw.ravel()})
    for surface in (arrays, grid):
        scene["technique.surface.file"] = surface
        got, _ = render(scene)
        assert np.array_equal(got, want)
    with pytest.raises(arbvis.InputError, match="property 'throw' is an array of \\(35,\\)"):
        arbvis.Surface(vertices, triangles, properties={"throw": throw})
    with pytest.raises(arbvis.InputError, match="property 'p' is an array of \\(7, 5\\)"):
        arbvis.Surface.grid(z, x, y, properties={"p": throw[:3]})
    scene["technique.surface.colour_by"] = {"property": "dip"}
    with pytest.raises(arbvis.SceneError, match='colour_by.property: "dip".*it has "throw"'):
        render(scene)


def test_a_section_moves_by_key_for_the_cost_of_a_frame(tmp_path):
    """A layered scene's section moved from Python (`scene["layer.1.section.inline"]`) is
    drawn by the renderer it has, which reads no file for it (the survey's file is gone by
    then): the same picture as a fresh renderer's of the moved scene."""
    rng = np.random.default_rng(5)
    dims = [19, 13, 11]  # samples fastest, as a raw volume's dims
    values = rng.standard_normal(dims[::-1]).astype("<f4")
    values.tofile(tmp_path / "survey.raw")
    volume = {"raw": {"path": str(tmp_path / "survey.raw"), "dims": dims, "type": "f32"}}
    scene = arbvis.Scene.from_dict(
        {
            "size": [57, 43],
            "fidelity": "precise",
            "technique": {"section": {"volume": volume, "inline": 2}},
        }
    )
    scene.add_layer("section", {"volume": volume, "time": 7.5}, name="time 7.5")
    with arbvis.Renderer(scene) as r:
        before = r.render()
        (tmp_path / "survey.raw").rename(tmp_path / "moved.raw")
        scene["layer.1.section.time"] = 3.25
        scene["layer.0.section.inline"] = 8
        kept = r.render()
        (tmp_path / "moved.raw").rename(tmp_path / "survey.raw")
    with arbvis.Renderer(scene) as r:
        fresh = r.render()
    assert np.array_equal(kept, fresh)
    assert np.abs(kept.astype(float) - before.astype(float)).max() > 0.1, "the sections moved"


def test_a_section_of_a_survey_in_memory_draws_as_its_file(tmp_path):
    """A section layer takes an `arbvis.Volume` as it takes a file: a C-order cube indexed
    [inline, crossline, sample] in memory and the same bytes as a raw file (sample fastest)
    draw the same inline section, given the same spacing (a survey in memory without one
    takes a seismic survey's default, the raw file 1 m)."""
    rng = np.random.default_rng(11)
    cube = rng.standard_normal((9, 13, 21)).astype(np.float32)
    cube.tofile(tmp_path / "cube.raw")
    raw = {"raw": {"path": str(tmp_path / "cube.raw"), "dims": [21, 13, 9], "type": "f32"}}
    camera = {"projection": "orthographic", "rotation": [0.3265, -0.0923, -0.701, 0.6272]}
    pictures = []
    for volume in (arbvis.Volume(cube, spacing=(1.0, 1.0, 1.0)), raw):
        scene = arbvis.Scene.from_dict(
            {
                "size": [48, 40],
                "fidelity": "precise",
                "camera": camera,
                "technique": {
                    "section": {"volume": volume, "inline": 5, "quantize": "min-max"}
                },
            }
        )
        with arbvis.Renderer(scene) as r:
            pictures.append(r.render())
    assert np.array_equal(pictures[0], pictures[1])
    assert (pictures[0][..., 3] > 0).sum() > 200, "the section is in view"


def test_lines_and_a_well_log_from_arrays_draw_as_their_files(tmp_path):
    """Polylines handed over as numpy arrays (`polylines=[array, ...]`, (N, 3) or (N, 4)
    with a value) and a well's log as an (N, 2) array (`log_rows`) draw exactly what
    their CSV files draw, a NaN value (none: the constant colour) included; bad points are
    refused by key."""
    rng = np.random.default_rng(21)
    lines = [np.column_stack([rng.random((n, 3)) * 80.0, rng.random(n)]) for n in (4, 7)]
    lines[1][2, 3] = np.nan
    text = "\n".join("".join(f"{p[0]!r},{p[1]!r},{p[2]!r},{p[3]!r}\n" for p in l.tolist()) for l in lines)
    (tmp_path / "l.csv").write_text(text)
    base = {"size": [64, 48], "fidelity": "precise", "camera": {"rotation": [0.31, -0.22, 0.12, 0.917]}}

    def draw(lines_table):
        scene = arbvis.Scene.from_dict({**base, "technique": {"lines": lines_table}}, base=tmp_path)
        return render(scene)[0]

    want = draw({"file": "l.csv", "radius": 3.0})
    assert int((want[..., :3].sum(axis=2) > 0.05).sum()) > 100, "the lines are in view"
    got = draw({"polylines": lines, "radius": 3.0})
    assert np.array_equal(got, want)
    # A ribbon 3 pixels wide (shaped for the view) from the arrays, as from the file.
    ribbon = {"style": "ribbon", "width": {"pixels": 3.0}}
    want = draw({"file": "l.csv", **ribbon})
    assert int((want[..., :3].sum(axis=2) > 0.05).sum()) > 60, "the ribbons are in view"
    assert np.array_equal(draw({"polylines": lines, **ribbon}), want)
    md = np.arange(0.0, 100.5, 0.5)
    log = np.column_stack([md, 50.0 + 40.0 * np.sin(md / 7.0)])
    log[30:41, 1] = np.nan  # a gap in the log, as lasio reads -999.25
    (tmp_path / "gr.csv").write_text("MD,GR\n" + "".join(f"{m!r},{v!r}\n" for m, v in log.tolist()))
    well = {"head": [10.0, 20.0], "stations": [[0.0, 0.0, 0.0], [50.0, 20.0, 45.0], [100.0, 30.0, 60.0]]}
    want = draw({"well": {**well, "log": "gr.csv"}, "radius": 5.0})
    got = draw({"well": {**well, "log_rows": log}, "radius": 5.0})
    assert np.array_equal(got, want)
    with pytest.raises(arbvis.SceneError, match=r"polylines\.1\.0"):
        draw({"polylines": [lines[0], np.zeros((3, 2))]})
