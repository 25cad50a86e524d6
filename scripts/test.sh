#!/usr/bin/env bash
# The tests on a fresh Debian/Ubuntu machine: install the libraries they need where missing
# (scripts/install-deps.sh), then `cargo test --workspace` (every crate of the workspace)
# with any arguments given.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
exec cargo test --workspace "$@"
