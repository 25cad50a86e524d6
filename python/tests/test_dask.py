"""arbvis.dask on a LocalCluster of two worker processes on loopback: an orbit of a survey
store's views equals a single-process render of each, each worker keeps one renderer
between tasks."""

import numpy as np
import pytest

import arbvis
import arbvis.dask

distributed = pytest.importorskip("dask.distributed")


def local_cluster(workers):
    """A LocalCluster of `workers` single-threaded worker processes on loopback."""
    return distributed.LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    )


def peak_rss():
    """This process's peak resident memory in bytes (Linux reports KiB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def test_an_orbit_of_a_store_on_two_workers_equals_one_process(f3_store_scene, tmp_path):
    scene = f3_store_scene
    views = arbvis.dask.orbit(6)
    with local_cluster(2) as cluster, distributed.Client(cluster) as client:
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


def test_four_workers_on_a_remote_store_with_one_shared_cache_equal_one_process(
    f3_store_scene, tmp_path, monkeypatch, range_server
):
    """Under load: the same store over HTTP (the tests' Range server on 127.0.0.1), four
    worker processes sharing one disk cache: every view equals the single-process render
    of the local store, and the shared cache holds whole entries only."""
    cache = tmp_path / "cache"
    # Worker processes start from this environment: one cache folder for all four, and a
    # memory budget of 256 MiB each.
    monkeypatch.setenv("ARBVIS_CACHE_DIR", str(cache))
    monkeypatch.setenv("ARBVIS_MEMORY_BUDGET", "256M")
    port = range_server(tmp_path)
    local = f3_store_scene
    remote = arbvis.Scene.from_toml(
        local.to_toml().replace(str(tmp_path / "f3.zarr"), f"http://127.0.0.1:{port}/f3.zarr")
    )
    assert "http://" in remote.to_toml()
    views = arbvis.dask.orbit(8)
    with local_cluster(4) as cluster, distributed.Client(cluster) as client:
        before = client.run(peak_rss)
        images = arbvis.dask.render_views(client, remote, views)
        after = client.run(peak_rss)
    # Each worker's peak grew by less than its budget: the budget bounds one allocation,
    # and a render's allocations together (the GL context, the store's chunk cache, the
    # picture) stay under it here.
    grown = {w: after[w] - before[w] for w in after}
    print("peak RSS growth per worker (MiB):", {w: g >> 20 for w, g in grown.items()})
    assert max(grown.values()) < 256 << 20, grown
    with arbvis.Renderer(local) as r:
        for rotation, image in zip(views, images):
            local.rotation = rotation
            assert np.array_equal(r.render(), image)
    entries = [p for p in cache.rglob("*") if p.is_file()]
    assert entries, "the workers shared the cache"
    assert not [p for p in entries if p.name.startswith(".tmp-")], "a temporary was left"
