#!/usr/bin/env bash
# The Python package's tests: a virtual environment in target/python-venv (numpy, pytest,
# dask[distributed], xarray, laspy and meshio (arbvis.Volume, Cloud and Mesh from their objects),
# anywidget, jupyterlab and playwright (the notebook view, opened in Debian's Chromium: no
# browser is downloaded) and
# maturin from PyPI), the package built from this checkout and
# installed into it (`pip install .`: a debug build that reuses the workspace's test build
# in target/), then pytest on python/tests. scripts/test.sh runs it after the Rust tests.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/python-venv
# maturin, the build backend, is found on the PATH.
export PATH="$PWD/$venv/bin:$PATH"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --disable-pip-version-check \
  "maturin>=1.5,<2" numpy pytest "dask[distributed]" xarray laspy meshio anywidget \
  jupyterlab playwright nbclient zarr
# Not pyproject.toml's release profile: the dev profile with the test profile's opt-level
# (Cargo.toml), so that the extension reuses `cargo test`'s crates instead of compiling them
# again (maturin's `--profile test` would build a test harness, not a library).
CARGO_PROFILE_DEV_OPT_LEVEL=1 MATURIN_PEP517_ARGS="--profile dev" \
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --no-build-isolation .
exec "$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests "$@"
