"""Shared pieces of the Python tests: the repository's root (goldens, scenes, data)."""

from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def root():
    """The repository's root."""
    return ROOT


@pytest.fixture
def range_server():
    """Start the Rust tests' Range server (tests/servers/range_server.py) on a folder:
    `range_server(folder)` gives its port on 127.0.0.1; every server started is stopped
    with the test."""
    import subprocess
    import sys

    started = []

    def start(folder):
        server = subprocess.Popen(
            [sys.executable, str(ROOT / "tests/servers/range_server.py"), str(folder)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
        )
        started.append(server)
        return int(server.stdout.readline())

    yield start
    for server in started:
        server.stdin.close()
        server.kill()
        server.wait()


@pytest.fixture
def f3_store_scene(tmp_path):
    """The F3 crop converted to a store of 16³ bricks in `tmp_path`, and a 48 x 40 scene of
    its amplitude in the seismic table (the store's fixed range)."""
    import arbvis

    store = tmp_path / "f3.zarr"
    arbvis.convert(ROOT / "data/seismic/f3.sgy", store, brick=16)
    return arbvis.Scene.from_toml(
        f"""
size = [48, 40]
[technique.opacity3d]
slices = 64
[technique.opacity3d.primary]
volume = {{ store = "{store}" }}
quantize = {{ range = [-6000.0, 6000.0] }}
table = {{ builtin = "seismic" }}
"""
    )
