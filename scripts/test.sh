#!/usr/bin/env bash
# The tests on a fresh Debian/Ubuntu machine: install the libraries they need where missing
# (scripts/install-deps.sh), then `cargo test --workspace` (every crate of the workspace)
# with any arguments given; without arguments, then the Python package's tests too
# (scripts/python-tests.sh: the package built into a virtual environment, pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cargo test --workspace "$@"
if [ "$#" -eq 0 ]; then
  bash scripts/python-tests.sh
fi
