"""arbvis.dask on a LocalCluster of two worker processes on loopback: an orbit of a survey
store's views equals a single-process render of each, each worker keeps one renderer
between tasks."""

import numpy as np
import pytest

import arbvis
import arbvis.dask

distributed = pytest.importorskip("dask.distributed")


def test_an_orbit_of_a_store_on_two_workers_equals_one_process(f3_store_scene, tmp_path):
    scene = f3_store_scene
    views = arbvis.dask.orbit(6)
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster, distributed.Client(cluster) as client:
        images = arbvis.dask.render_views(client, scene, views)
        pngs = arbvis.dask.render_views(client, scene, views[:2], out_dir=str(tmp_path / "views"))
        # Every worker that rendered keeps one renderer (the scene's), not one per task.
        kept = client.run(lambda: len(arbvis.dask._RENDERERS))
    assert len(images) == 6
    # The survey is drawn (not a blank picture that would equal any other).
    assert all(image[..., :3].any() for image in images)
    assert not np.array_equal(images[0], images[3])
    assert set(kept.values()) <= {0, 1} and sum(kept.values()) >= 1
    with arbvis.Renderer(scene) as r:
        for rotation, image in zip(views, images):
            scene.rotation = rotation
            assert np.array_equal(r.render(), image)
    for png, image in zip(pngs, images):
        assert np.array_equal(arbvis._arbvis.read_png(png), image)
