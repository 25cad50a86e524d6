"""Image regression for arbvis pictures in pytest, in the style of pytest-pyvista.

The ``arbvis_image`` fixture compares a rendered array with a reference PNG in the image
cache (``--arbvis-image-cache-dir``, default ``tests/arbvis_images`` under the rootdir),
named after the test (or the name given)::

    def test_sum(arbvis_image):
        with arbvis.Renderer(arbvis.Scene.demo("v3o2-sum")) as r:
            arbvis_image(r.render())

The metric is the Rust tests' (``Image::compare``): on 8-bit levels (what a PNG holds),
the largest channel difference must be at most the tolerance, by default
``ONE_LEVEL`` = 1/255: llvmpipe and OSMesa draw the same picture bit for bit run after
run, and a PNG holds 8-bit levels, so one level is the rounding of a float target into the
PNG and anything more is a changed picture. A driver that rounds otherwise (another GPU)
needs its own cache.

Options: ``--arbvis-reset-image-cache`` writes every reference anew;
``--arbvis-add-missing-images`` writes the references that are missing instead of
failing; ``--arbvis-failed-image-dir DIR`` receives, for each failure, the picture and
its diff image (each pixel's largest difference x16 as grey, pixels over the tolerance in
red).
"""

import os
import re
from pathlib import Path

import pytest

from . import _arbvis

#: One 8-bit level: the resolution of a PNG; what a llvmpipe picture may differ by when a
#: float target is rounded into the PNG.
ONE_LEVEL = 1.0 / 255.0


def pytest_addoption(parser):
    group = parser.getgroup("arbvis", "arbvis image regression")
    group.addoption(
        "--arbvis-image-cache-dir",
        default=None,
        help="folder of the reference PNGs (default: tests/arbvis_images under the rootdir)",
    )
    group.addoption(
        "--arbvis-reset-image-cache",
        action="store_true",
        help="write every reference picture anew instead of comparing",
    )
    group.addoption(
        "--arbvis-add-missing-images",
        action="store_true",
        help="write the reference pictures that are missing instead of failing",
    )
    group.addoption(
        "--arbvis-failed-image-dir",
        default=None,
        help="write each failed picture and its diff image to this folder",
    )
    parser.addini(
        "arbvis_image_cache_dir",
        "folder of the reference PNGs, relative to the rootdir",
        default="tests/arbvis_images",
    )


class ImageMismatch(AssertionError):
    """A picture that differs from its reference by more than the tolerance."""


class ImageChecker:
    """Compares pictures with the references in the cache (the ``arbvis_image`` fixture)."""

    def __init__(self, cache, test_name, reset, add_missing, failed_dir):
        self.cache = Path(cache)
        self.test_name = re.sub(r"[^A-Za-z0-9_.-]", "_", test_name)
        self.reset = reset
        self.add_missing = add_missing
        self.failed_dir = Path(failed_dir) if failed_dir else None
        self.calls = 0

    def __call__(self, image, name=None, tolerance=ONE_LEVEL):
        """Compare ``image`` (an ``(h, w, 4)`` array) with the reference ``name`` (by
        default the test's name, numbered from the second call)."""
        if name is None:
            name = self.test_name if self.calls == 0 else f"{self.test_name}_{self.calls}"
        self.calls += 1
        reference = self.cache / f"{name}.png"
        if self.reset or (self.add_missing and not reference.exists()):
            reference.parent.mkdir(parents=True, exist_ok=True)
            _arbvis.write_png(str(reference), image)
            return
        if not reference.exists():
            self._keep_failed(name, image, None, tolerance)
            raise ImageMismatch(
                f"{name}: no reference picture {reference}; "
                "run with --arbvis-add-missing-images to write it"
            )
        expected = _arbvis.read_png(str(reference))
        if image.shape != expected.shape:
            self._keep_failed(name, image, None, tolerance)
            raise ImageMismatch(
                f"{name}: size {image.shape[1]}x{image.shape[0]} differs from the "
                f"reference's {expected.shape[1]}x{expected.shape[0]}"
            )
        d = _arbvis.compare(image, expected, tolerance)
        if d["max_abs"] > tolerance + 1e-6:
            kept = self._keep_failed(name, image, expected, tolerance)
            raise ImageMismatch(
                f"{name}: largest difference {d['max_abs']:.4f} "
                f"({d['max_abs'] * 255:.1f} levels) at {d['worst']} over the tolerance "
                f"{tolerance:.4f}; {d['pixels_over']} pixels over; RMSE {d['rmse']:.5f}, "
                f"PSNR {d['psnr']:.1f} dB" + (f"; wrote {kept}" if kept else "")
            )

    def _keep_failed(self, name, image, expected, tolerance):
        if self.failed_dir is None:
            return None
        self.failed_dir.mkdir(parents=True, exist_ok=True)
        picture = self.failed_dir / f"{name}.png"
        _arbvis.write_png(str(picture), image)
        if expected is None or expected.shape != image.shape:
            return str(picture)
        diff = self.failed_dir / f"{name}.diff.png"
        _arbvis.write_png(str(diff), _arbvis.diff_image(image, expected, tolerance))
        return f"{picture} and {diff}"


@pytest.fixture
def arbvis_image(request):
    """Compare a rendered picture with its reference PNG (see the module's doc)."""
    config = request.config
    cache = config.getoption("arbvis_image_cache_dir") or os.path.join(
        str(config.rootpath), config.getini("arbvis_image_cache_dir")
    )
    return ImageChecker(
        cache,
        request.node.name,
        config.getoption("arbvis_reset_image_cache"),
        config.getoption("arbvis_add_missing_images"),
        config.getoption("arbvis_failed_image_dir"),
    )
