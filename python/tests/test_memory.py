"""arbvis.Volume: a survey handed over in memory draws as the same survey read from a
SEG-Y file does. The SEG-Y is written here from a random cube of odd sizes on a rotated
grid (CDP coordinates with scalar -100, 4 ms samples); the same samples as an xarray
DataArray with the SEG-Y's coordinates, as numpy arrays of several dtypes and orders, and
through a scene's TOML all draw the same picture. Bad arrays are refused naming the
argument; a volume lives as long as a scene holds it."""

import gc
import math
import struct

import numpy as np
import pytest

import arbvis
import arbvis.dask

# The grid: 25 m between inlines and 12.5 m between crosslines, turned 0.3 rad on the map.
BINS = (25.0, 12.5)
ANGLE = 0.3
DT_MS = 4
ORIGIN = (612345.0, 6123456.0)


def random_cube(shape=(9, 13, 31), seed=7):
    """A cube [inline, crossline, sample] of noise over a dipping layer: nothing smooth
    or symmetric for a defect to hide in."""
    rng = np.random.default_rng(seed)
    ni, nx, ns = shape
    k, j, s = np.meshgrid(np.arange(ni), np.arange(nx), np.arange(ns), indexing="ij")
    layer = np.sin(0.4 * s - 0.3 * k + 0.2 * j)
    return (layer + 0.6 * rng.standard_normal(shape)).astype(np.float32)


def trace_xy(k, j):
    """The map position of inline index k, crossline index j, in centimetres (as the
    SEG-Y holds it)."""
    c, s = math.cos(ANGLE), math.sin(ANGLE)
    x = ORIGIN[0] + k * BINS[0] * c - j * BINS[1] * s
    y = ORIGIN[1] + k * BINS[0] * s + j * BINS[1] * c
    return round(x * 100), round(y * 100)


def write_segy(path, cube):
    """`cube` as a big-endian IEEE-float SEG-Y rev 1: inline at byte 189, crossline at
    193, CDP x/y at 181/185 with coordinate scalar -100 (centimetres)."""
    ni, nx, ns = cube.shape
    binary = bytearray(400)
    struct.pack_into(">hhh", binary, 16, DT_MS * 1000, 0, ns)  # bytes 3217-3222
    struct.pack_into(">h", binary, 24, 5)  # 3225: IEEE float
    struct.pack_into(">hh", binary, 300, 0x0100, 1)  # 3501: rev 1, fixed length
    parts = [b" " * 3200, bytes(binary)]
    for k in range(ni):
        for j in range(nx):
            h = bytearray(240)
            struct.pack_into(">h", h, 70, -100)
            struct.pack_into(">ii", h, 180, *trace_xy(k, j))
            struct.pack_into(">ii", h, 188, 100 + k, 200 + j)
            struct.pack_into(">hh", h, 114, ns, DT_MS * 1000)
            parts += [bytes(h), cube[k, j].astype(">f4").tobytes()]
    path.write_bytes(b"".join(parts))


SCENE = """
size = [88, 70]
[camera]
rotation = [0.31, -0.12, -0.64, 0.69]
zoom = 1.1
[technique.opacity3d.primary]
volume = { segy = "cube.sgy" }
attribute = "amplitude"
table = { builtin = "seismic" }
"""


def segy_scene(tmp_path, cube):
    write_segy(tmp_path / "cube.sgy", cube)
    return arbvis.Scene.from_toml(SCENE, base=tmp_path)


def render(scene):
    with arbvis.Renderer(scene) as r:
        return r.render()


def with_volume(scene, volume):
    scene = arbvis.Scene.from_toml(scene.to_toml(), base=scene.base)
    scene["technique.opacity3d.primary.volume"] = volume
    return scene


def survey_xy(cube):
    """The traces' map coordinates in metres, [inline, crossline, (x, y)]."""
    ni, nx, _ = cube.shape
    return np.array([[trace_xy(k, j) for j in range(nx)] for k in range(ni)]) / 100.0


def survey_dataarray(xr, cube):
    """`cube` as mdio names it: dimensions inline, crossline, time; the map coordinates
    beside."""
    ni, nx, ns = cube.shape
    xy = survey_xy(cube)
    return xr.DataArray(
        cube,
        dims=("inline", "crossline", "time"),
        coords={
            "inline": 100 + np.arange(ni),
            "crossline": 200 + np.arange(nx),
            "time": DT_MS * np.arange(ns, dtype=np.float64),
            "cdp_x": (("inline", "crossline"), xy[..., 0]),
            "cdp_y": (("inline", "crossline"), xy[..., 1]),
        },
    )


def test_an_xarray_survey_draws_as_its_segy(tmp_path):
    xr = pytest.importorskip("xarray")
    cube = random_cube()
    scene = segy_scene(tmp_path, cube)
    want = render(scene)
    da = survey_dataarray(xr, cube)
    volume = arbvis.Volume(da)
    # The proportions measured as the SEG-Y's are: 25 m, 12.5 m and 4 ms as 4 m
    # (the centimetres of the coordinates round the bins by far less than 1e-6 m).
    assert np.allclose(volume.spacing, (BINS[0], BINS[1], DT_MS), atol=1e-6), volume.spacing
    assert volume.shape == cube.shape
    assert np.array_equal(render(with_volume(scene, volume)), want)
    # The same DataArray in another dimension order, as segysak names it: the same survey.
    other = da.rename(inline="iline", crossline="xline", time="twt").transpose("twt", "iline", "xline")
    assert np.array_equal(render(with_volume(scene, arbvis.Volume(other))), want)
    # A numpy array given the spacing the DataArray measured: the same picture.
    plain = arbvis.Volume(cube, spacing=volume.spacing)
    assert np.array_equal(render(with_volume(scene, plain)), want)


def test_every_dtype_and_order_of_one_survey_draws_one_picture(tmp_path):
    cube = np.round(random_cube(shape=(7, 11, 23), seed=3) * 1000).astype(np.int16)
    spacing = (25.0, 12.5, 4.0)
    scene = segy_scene(tmp_path, cube.astype(np.float32))
    want = render(with_volume(scene, arbvis.Volume(cube.astype(np.float32), spacing)))
    for variant in [
        cube,
        np.asfortranarray(cube),
        cube.astype(np.float64),
        cube.astype(np.int32),
        cube[:, ::-1, :][:, ::-1, :],  # a strided view
    ]:
        got = render(with_volume(scene, arbvis.Volume(variant, spacing)))
        assert np.array_equal(got, want), (variant.dtype, variant.flags["C_CONTIGUOUS"])


def test_a_bad_array_is_refused_naming_the_argument():
    cases = [
        (np.zeros((4, 5), np.float32), None, "a 3D array indexed [inline, crossline, sample]"),
        (np.zeros((2, 3, 4), np.complex64), None, "samples of float32"),
        (np.zeros((2, 0, 4), np.float32), None, "holds no samples"),
        (np.zeros((2, 3, 4), np.float32), (1.0, -1.0, 1.0), "spacing is three positive"),
        (np.zeros((2, 3, 4), np.float32), (1.0, float("nan"), 1.0), "spacing is three positive"),
        (np.zeros((2, 3, 4), np.float32), "25", "spacing is three positive"),
        ([[1, 2], [3, 4]], None, "a 3D array"),
    ]
    for data, spacing, says in cases:
        with pytest.raises(arbvis.InputError) as e:
            arbvis.Volume(data, spacing)
        assert str(e.value).startswith("volume: ") and says in str(e.value), str(e.value)


def test_a_dataarray_without_survey_dimensions_is_refused_by_name():
    xr = pytest.importorskip("xarray")
    da = xr.DataArray(np.zeros((2, 3, 4), np.float32), dims=("a", "b", "c"))
    with pytest.raises(arbvis.InputError) as e:
        arbvis.Volume(da)
    assert "volume: a DataArray with one inline dimension" in str(e.value)
    assert "('a', 'b', 'c')" in str(e.value)


def test_a_volume_lives_while_a_scene_holds_it(tmp_path):
    cube = random_cube(shape=(5, 6, 9), seed=11)
    scene = segy_scene(tmp_path, cube)
    volume = arbvis.Volume(cube, spacing=(25.0, 12.5, 4.0))
    name = volume.name
    scene["technique.opacity3d.primary.volume"] = volume
    assert scene["technique.opacity3d.primary.volume"] == {"memory": name}
    assert f'memory = "{name}"' in scene.to_toml()
    want = render(scene)
    # The Python object gone: the scene still holds the samples.
    del volume
    gc.collect()
    assert np.array_equal(render(scene), want)
    # Another scene may name it by its TOML while the first holds it ...
    again = arbvis.Scene.from_toml(scene.to_toml(), base=tmp_path)
    assert np.array_equal(render(again), want)
    # ... and once no scene that was given it lives, the name finds nothing.
    del scene
    gc.collect()
    with pytest.raises(arbvis.ArbvisError) as e:
        render(again)
    assert "no such volume in this process" in str(e.value)
    # In a dict too, at any depth.
    volume = arbvis.Volume(cube, spacing=(25.0, 12.5, 4.0))
    d = arbvis.Scene.from_toml(SCENE, base=tmp_path).to_dict()
    d["technique"]["opacity3d"]["primary"]["volume"] = volume
    from_dict = arbvis.Scene.from_dict(d, base=tmp_path)
    del volume, d
    gc.collect()
    assert np.array_equal(render(from_dict), want)


def test_dask_refuses_a_volume_in_memory_before_sending_anything(tmp_path):
    cube = random_cube(shape=(3, 4, 5))
    scene = with_volume(segy_scene(tmp_path, cube), arbvis.Volume(cube, (1.0, 1.0, 1.0)))
    with pytest.raises(arbvis.InputError) as e:
        arbvis.dask.render_views(None, scene, arbvis.dask.orbit(2))
    assert "lives in this process only" in str(e.value)


CLOUD_SCENE = """
size = [90, 70]
[camera]
rotation = [0.28, -0.1, -0.05, 0.95]
[technique.splats]
cloud = { las = "c.las" }
point_size = 3.0
"""


def lidar_las(n=3001, seed=5):
    """A laspy LasData of `n` points of format 3 (GPS time, colours) over a rough surface,
    with an extra dimension: written to and read back from a LAS file by laspy itself."""
    laspy = pytest.importorskip("laspy")
    rng = np.random.default_rng(seed)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales = [0.001, 0.001, 0.001]
    header.offsets = [500000.0, 4000000.0, 100.0]
    header.add_extra_dim(laspy.ExtraBytesParams(name="moisture", type=np.float32))
    las = laspy.LasData(header)
    x = 500000.0 + rng.uniform(0, 80, n)
    y = 4000000.0 + rng.uniform(0, 50, n)
    las.x, las.y = x, y
    las.z = 100.0 + 3 * np.sin(x / 7.0) + rng.normal(0, 0.4, n)
    las.intensity = rng.integers(0, 65535, n, dtype=np.uint16)
    las.classification = rng.integers(1, 7, n, dtype=np.uint8)
    las.gps_time = 3e8 + np.sort(rng.uniform(0, 100, n))
    las.red, las.green, las.blue = (rng.integers(0, 65535, n, dtype=np.uint16) for _ in range(3))
    las.moisture = rng.uniform(0, 1, n).astype(np.float32)
    return las


@pytest.mark.parametrize("colour", [None, "rgb", "intensity", "classification"])
def test_a_laspy_cloud_draws_as_its_las_file(tmp_path, colour):
    laspy = pytest.importorskip("laspy")
    lidar_las().write(str(tmp_path / "c.las"))
    las = laspy.read(str(tmp_path / "c.las"))
    scene = arbvis.Scene.from_toml(CLOUD_SCENE, base=tmp_path)
    if colour:
        scene["technique.splats.colour"] = colour
    want = render(scene)
    assert want[..., :3].any(), "the cloud is drawn"
    cloud = arbvis.Cloud(las)
    assert len(cloud) == len(las.points)
    assert cloud.attributes == [
        "intensity", "classification", "return_number", "number_of_returns", "gps_time", "moisture"
    ]
    scene["technique.splats.cloud"] = cloud
    assert np.array_equal(render(scene), want)
    # The same points as plain arrays.
    xyz = np.column_stack([las.x, las.y, las.z])
    rgb = np.column_stack([las.red, las.green, las.blue])
    attributes = {
        "intensity": np.asarray(las.intensity),
        "classification": np.asarray(las.classification),
    }
    scene["technique.splats.cloud"] = arbvis.Cloud(xyz, attributes, rgb)
    assert np.array_equal(render(scene), want)


def test_a_bad_cloud_is_refused_naming_the_argument():
    xyz = np.zeros((4, 3))
    cases = [
        (np.zeros((4, 2)), None, None, "cloud: positions are an (N, 3) array"),
        (xyz, {"a": np.zeros(3)}, None, "cloud: attribute 'a' has shape (3,), not (4,)"),
        (xyz, {"a": np.array(["x"] * 4)}, None, "cloud: attribute 'a' holds"),
        (xyz, [1, 2], None, "cloud: attributes are a dict"),
        (xyz, None, np.zeros((4, 3), np.float32), "cloud: rgb is an (4, 3) array"),
        (np.array([[0, 0, 0], [np.nan, 0, 0]]), None, None, "cloud: point 1 has a non-finite coordinate"),
    ]
    for positions, attributes, rgb, says in cases:
        with pytest.raises(arbvis.InputError) as e:
            arbvis.Cloud(positions, attributes, rgb)
        assert says in str(e.value), str(e.value)


MESH_SCENE = """
size = [80, 64]
fidelity = "precise"
[camera]
rotation = [0.21, 0.37, 0.1, 0.9]
[technique.cellproj]
mesh = { file = "m.vtk" }
mode = "volume"
"""


def mixed_mesh(seed=9):
    """Points of a 3 x 2 x 2 block of hexahedra with jittered corners, its first row as
    hexahedra and the rest split by hand into tetrahedra, and a rough point scalar."""
    rng = np.random.default_rng(seed)
    g = np.stack(np.meshgrid(np.arange(4), np.arange(3), np.arange(3), indexing="ij"), -1)
    points = (g.reshape(-1, 3) + rng.uniform(-0.15, 0.15, (36, 3))).astype(np.float64)
    index = np.arange(36).reshape(4, 3, 3)
    hexes, tets = [], []
    for i in range(3):
        for j in range(2):
            for k in range(2):
                v = [index[i, j, k], index[i + 1, j, k], index[i + 1, j + 1, k], index[i, j + 1, k],
                     index[i, j, k + 1], index[i + 1, j, k + 1], index[i + 1, j + 1, k + 1], index[i, j + 1, k + 1]]
                if i == 0:
                    hexes.append(v)
                else:
                    for t in ([0, 1, 3, 4], [1, 2, 3, 6], [1, 4, 5, 6], [3, 4, 6, 7], [1, 3, 4, 6]):
                        tets.append([v[a] for a in t])
    scalar = np.sin(points[:, 0] * 1.3) + points[:, 2] * 0.4 + rng.normal(0, 0.1, 36)
    return points, np.array(tets), np.array(hexes), scalar


def write_vtk(path, points, tets, hexes, scalar):
    """A VTK legacy ASCII unstructured grid: the tetrahedra (10), then the hexahedra (12)."""
    lines = ["# vtk DataFile Version 3.0", "mixed", "ASCII", "DATASET UNSTRUCTURED_GRID"]
    lines.append(f"POINTS {len(points)} double")
    lines += [" ".join(repr(float(c)) for c in p) for p in points]
    cells = [[4, *t] for t in tets] + [[8, *h] for h in hexes]
    lines.append(f"CELLS {len(cells)} {sum(len(c) for c in cells)}")
    lines += [" ".join(str(int(v)) for v in c) for c in cells]
    lines.append(f"CELL_TYPES {len(cells)}")
    lines += ["10"] * len(tets) + ["12"] * len(hexes)
    lines += [f"POINT_DATA {len(points)}", "SCALARS s double 1", "LOOKUP_TABLE default"]
    lines += [repr(float(v)) for v in scalar]
    path.write_text("\n".join(lines) + "\n")


def test_a_mesh_from_arrays_and_from_meshio_draws_as_its_file(tmp_path):
    points, tets, hexes, scalar = mixed_mesh()
    write_vtk(tmp_path / "m.vtk", points, tets, hexes, scalar)
    scene = arbvis.Scene.from_toml(MESH_SCENE, base=tmp_path)
    want = render(scene)
    assert want[..., :3].any(), "the volume is drawn"
    mesh = arbvis.Mesh(points, {"tetra": tets, "hexahedron": hexes}, {"s": scalar})
    # 24 tetrahedra given, 4 hexahedra split in 6 each (as arbvis splits a file's).
    assert mesh.tetrahedra == len(tets) + 6 * len(hexes)
    scene["technique.cellproj.mesh"] = mesh
    assert np.array_equal(render(scene), want)
    meshio = pytest.importorskip("meshio")
    m = meshio.Mesh(points, [("tetra", tets), ("hexahedron", hexes)], point_data={"s": scalar})
    scene["technique.cellproj.mesh"] = arbvis.Mesh(m)
    assert np.array_equal(render(scene), want)
    # What meshio writes (VTU), read by arbvis from the file and by meshio into memory.
    m.write(str(tmp_path / "m.vtu"))
    scene["technique.cellproj.mesh"] = {"file": "m.vtu"}
    assert np.array_equal(render(scene), want)
    scene["technique.cellproj.mesh"] = arbvis.Mesh(meshio.read(str(tmp_path / "m.vtu")))
    assert np.array_equal(render(scene), want)


def test_a_bad_mesh_is_refused_naming_the_argument_and_the_cell():
    points, tets, hexes, scalar = mixed_mesh()
    flat = tets.copy()
    flat[3] = [0, 1, 2, 2]  # a collapsed tetrahedron among good ones: dropped, not an error
    cases = [
        ((np.zeros((4, 2)), tets), "mesh: points are an (N, 3) array"),
        ((points, None), "mesh: cells are needed"),
        ((points, {"polyhedron": tets}), "mesh: cells of kind 'polyhedron'"),
        ((points, tets + 100), "mesh: tetra cells name point 135; the mesh has 36 points"),
        ((points, tets, {"s": scalar[:5]}), "mesh: point array 's' has shape (5,)"),
        ((points, tets, None, {"c": np.zeros(3)}), "mesh: cell array 'c' has shape (3,)"),
        ((points, {"triangle": tets[:, :3]}), "mesh: cell 0: no volume cells"),
        # Rows of the wrong length for their kind: named by the cell's index.
        ((points, {"tetra": hexes}), "mesh: cell 0: cell 0 is a VTK_TETRA and needs 4 points"),
    ]
    for args, says in cases:
        with pytest.raises(arbvis.InputError) as e:
            arbvis.Mesh(*args)
        assert says in str(e.value), str(e.value)
    assert arbvis.Mesh(points, flat).tetrahedra == len(tets) - 1


def test_arrays_whose_strides_declare_huge_shapes_are_refused_before_any_copy():
    """A few bytes seen through zero strides as trillions of values: refused by the memory
    budget at once, never copied (numpy would try to allocate them)."""
    from numpy.lib.stride_tricks import as_strided

    base = np.zeros(4, np.float32)
    huge = as_strided(base, shape=(1 << 20, 1 << 20, 1 << 12), strides=(0, 0, 0))
    points = as_strided(np.zeros(3), shape=(1 << 40, 3), strides=(0, 8))
    cells = as_strided(np.arange(4), shape=(1 << 40, 4), strides=(0, 8))
    for make in [
        lambda: arbvis.Volume(huge, spacing=(1.0, 1.0, 1.0)),
        lambda: arbvis.Cloud(points),
        lambda: arbvis.Mesh(points[:4], cells),
        lambda: arbvis.Mesh(points),
    ]:
        with pytest.raises(arbvis.InputError, match="memory budget"):
            make()


def test_an_array_changed_after_it_was_handed_over_changes_no_picture(tmp_path):
    cube = random_cube(shape=(5, 6, 9), seed=2)
    scene = segy_scene(tmp_path, cube)
    want = render(with_volume(scene, arbvis.Volume(cube.copy(), (25.0, 12.5, 4.0))))
    handed = arbvis.Volume(cube, (25.0, 12.5, 4.0))
    cube[...] = 0.0  # the user's array changed before the volume is read: it holds a copy
    assert np.array_equal(render(with_volume(scene, handed)), want)
    # A read-only view is read as any other.
    view = cube.copy()
    view.flags.writeable = False
    arbvis.Volume(view, (1.0, 1.0, 1.0))


def test_an_xarray_survey_lies_where_its_segy_does_in_a_layered_scene(tmp_path):
    """Placed by cdp_x/cdp_y as the SEG-Y by its trace headers: beside a plane in map
    coordinates through the survey's middle, the same picture from either."""
    xr = pytest.importorskip("xarray")
    cube = random_cube()
    write_segy(tmp_path / "cube.sgy", cube)
    xy = survey_xy(cube)
    x0, y0 = xy[..., 0].min() - 50, xy[..., 1].min() - 50
    x1, y1 = xy[..., 0].max() + 50, xy[..., 1].max() + 50
    # A plane 60 m down (the survey's 31 samples of 4 ms reach 120 m), a little tilted.
    (tmp_path / "plane.obj").write_text(
        f"v {x0} {y0} -60\nv {x1} {y0} -60\nv {x1} {y1} -55\nv {x0} {y1} -55\nf 1 2 3\nf 1 3 4\n"
    )
    layers = f"""size = [73, 61]
[[layer]]
name = "survey"
[layer.opacity3d.primary]
volume = {{ segy = "cube.sgy" }}
attribute = "amplitude"
[[layer]]
name = "plane"
[layer.surface]
file = "plane.obj"
colour = [0.9, 0.75, 0.2]
"""
    scene = arbvis.Scene.from_toml(layers, base=tmp_path)
    want = render(scene)
    da = survey_dataarray(xr, cube)
    scene["layer.0.opacity3d.primary.volume"] = arbvis.Volume(da)
    got = render(scene)
    assert np.array_equal(got, want)
    # The plane cuts the survey: hiding it changes the picture where the survey was hidden.
    scene["layer.1.visible"] = False
    assert np.abs(render(scene) - want).max() > 0.1
