"""arbvis.inspect as a dict, arbvis.convert with progress, cancellation and resumption,
and a store drawn from Python."""

import numpy as np
import pytest

import arbvis


def test_inspect_gives_the_lines_as_a_dict(root):
    facts = arbvis.inspect(root / "data/seismic/small.sgy")
    assert facts["format"].startswith("SEG-Y")
    assert facts["traces"] == "25"
    assert "grid: 5 inlines x 5 crosslines" in facts["text"]
    cloud = arbvis.inspect(root / "data/points/autzen_trim.laz")
    assert cloud["points"] == "110000"


def test_inspect_of_a_missing_file_names_it(tmp_path):
    with pytest.raises(arbvis.InputError) as e:
        arbvis.inspect(tmp_path / "nowhere.sgy")
    assert "nowhere.sgy" in str(e.value)


def test_convert_reports_progress_stops_on_request_and_resumes(root, tmp_path):
    src = root / "data/seismic/f3.sgy"
    store = tmp_path / "f3.zarr"
    calls = []

    def stop_after_three(done, total):
        calls.append((done, total))
        return len(calls) < 3

    with pytest.raises(arbvis.Cancelled) as e:
        arbvis.convert(src, store, brick=16, progress=stop_after_three)
    assert "resume" in str(e.value)
    assert len(calls) == 3
    total = calls[0][1]
    seen = []
    report = arbvis.convert(src, store, brick=16, progress=lambda d, t: seen.append((d, t)))
    assert report["resumed"] >= 3
    assert report["written"] + report["resumed"] == total
    assert seen[-1] == (total, total)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    # A callback that raises: its exception, and the store is left as it was (whole).
    def fail(done, total):
        raise ValueError("no more")

    with pytest.raises(ValueError):
        arbvis.convert(src, tmp_path / "again.zarr", brick=16, progress=fail)
    # The store draws from Python as from the command line.
    scene = arbvis.Scene.from_toml(
        f"""
size = [64, 48]
[technique.opacity3d]
[technique.opacity3d.primary]
volume = {{ store = "{store}" }}
"""
    )
    with arbvis.Renderer(scene) as r:
        image = r.render()
    assert image.shape == (48, 64, 4) and image[..., :3].any()


def test_convert_refuses_an_unknown_attribute(root, tmp_path):
    with pytest.raises(ValueError):
        arbvis.convert(root / "data/seismic/small.sgy", tmp_path / "s.zarr", attributes=["colour"])


def test_convert_reads_a_url_as_a_url_and_writes_only_locally(tmp_path, monkeypatch):
    """A URL handed to convert is fetched (here from a port nothing listens on: the error
    says so), not looked for as a local path; a URL to write to is refused."""
    import socket

    monkeypatch.setenv("ARBVIS_REMOTE_TIMEOUT", "1")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    url = f"http://127.0.0.1:{port}/survey.zarr"
    with pytest.raises(arbvis.InputError) as e:
        arbvis.convert(url, tmp_path / "out.zarr")
    assert url in str(e.value) and "could not be reached" in str(e.value), e.value
    assert "looked for" not in str(e.value)
    with pytest.raises(arbvis.InputError) as e:
        arbvis.convert(tmp_path / "in.sgy", url)
    assert "local folder" in str(e.value), e.value


def test_a_remote_cloud_is_inspected_and_its_requests_counted(
    root, tmp_path, monkeypatch, range_server
):
    """A COPC file over HTTP (the Rust tests' Range server on 127.0.0.1, stopped with the
    test): inspected as the local file is, its requests in fetch_stats."""
    monkeypatch.setenv("ARBVIS_CACHE_DIR", str(tmp_path / "cache"))
    port = range_server(root / "data/points")
    before = arbvis.fetch_stats()["requests"]
    url = f"http://127.0.0.1:{port}/simple.copc.laz"
    remote = arbvis.inspect(url)
    local = arbvis.inspect(root / "data/points/simple.copc.laz")
    assert remote["text"].split("\n", 1)[1] == local["text"].split("\n", 1)[1]
    stats = arbvis.fetch_stats()
    # The 33 KB file in one request: its first 64 KiB block is all of it.
    assert stats["requests"] - before == 1
    assert stats["in_flight"] == 0 and stats["loading"] is None
    with pytest.raises(arbvis.InputError) as e:
        arbvis.inspect(f"http://127.0.0.1:{port}/none.copc.laz")
    assert "none.copc.laz" in str(e.value) and "404" in str(e.value)
