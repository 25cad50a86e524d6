"""The Python examples of README.md and docs/python.md run as written (each file's
```python blocks in order, in one namespace, in a folder that links the repository's
scenes/ and data/); the Dask example is test_dask.py's, at a test's size."""

import os
import re

import pytest

FENCE = re.compile(r"```python\n(.*?)```", re.S)


@pytest.mark.parametrize("document", ["README.md", "docs/python.md"])
def test_the_examples_run(document, root, tmp_path, monkeypatch):
    text = (root / document).read_text()
    blocks = [b for b in FENCE.findall(text) if "LocalCluster" not in b]
    assert blocks, f"{document} has no Python example"
    for name in ("scenes", "data"):
        os.symlink(root / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "docs_example"}
    for block in blocks:
        exec(compile(block, document, "exec"), namespace)
