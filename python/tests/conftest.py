"""Shared pieces of the Python tests: the repository's root (goldens, scenes, data)."""

from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def root():
    """The repository's root."""
    return ROOT
