"""The arbvis_image fixture, run in pytest's own pytester: a missing reference fails,
is added on request, then holds; a changed coefficient fails with a diff image; a reset
rewrites."""

import arbvis

TEST_FILE = """
import arbvis

def test_sum(arbvis_image):
    scene = arbvis.Scene.demo("v3o2-sum")
    scene.size = (64, 48)
    scene["technique.opacity3d.primary.coefficients"] = COEFFICIENTS
    with arbvis.Renderer(scene) as r:
        arbvis_image(r.render())
"""


def write_test(pytester, coefficients):
    pytester.makepyfile(
        test_images=TEST_FILE.replace("COEFFICIENTS", repr(coefficients))
    )


def test_references_are_added_kept_and_a_changed_coefficient_fails(pytester):
    cache = pytester.path / "cache"
    failed = pytester.path / "failed"
    options = [
        f"--arbvis-image-cache-dir={cache}",
        f"--arbvis-failed-image-dir={failed}",
    ]
    write_test(pytester, [0.4, 0.3, 0.2, 0.8])
    # No reference yet: a failure that says how to add it.
    result = pytester.runpytest(*options)
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*no reference picture*--arbvis-add-missing-images*"])
    # Added on request, then the same picture passes.
    pytester.runpytest(*options, "--arbvis-add-missing-images").assert_outcomes(passed=1)
    assert (cache / "test_sum.png").exists()
    pytester.runpytest(*options).assert_outcomes(passed=1)
    # A changed coefficient must fail, with the picture and its diff image kept.
    write_test(pytester, [0.9, 0.3, 0.2, 0.8])
    result = pytester.runpytest(*options)
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*largest difference*levels*over the tolerance*"])
    assert (failed / "test_sum.png").exists() and (failed / "test_sum.diff.png").exists()
    diff = arbvis._arbvis.read_png(str(failed / "test_sum.diff.png"))
    # Red where the picture moved by more than the tolerance.
    red = (diff[..., 0] == 255) & (diff[..., 1] == 0) & (diff[..., 2] == 0)
    assert red.any()
    # A reset makes the new picture the reference.
    pytester.runpytest(*options, "--arbvis-reset-image-cache").assert_outcomes(passed=1)
    pytester.runpytest(*options).assert_outcomes(passed=1)


def test_the_plugin_is_registered_by_its_entry_point(pytester):
    pytester.makepyfile(
        test_fixture="def test_fixture(arbvis_image):\n    assert callable(arbvis_image)\n"
    )
    # No -p: the package's pytest11 entry point loads it.
    pytester.runpytest().assert_outcomes(passed=1)
