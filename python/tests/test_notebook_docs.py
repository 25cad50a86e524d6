"""The docs notebook (`docs/notebooks/f3-in-one-view.ipynb`, issue 56 item 3) runs from
top to bottom in a kernel (nbclient, from its own folder as a user opens it) and shows what
it says: its view of three layers (F3 from its MDIO dataset through xarray, the horizon
from numpy, picks from laspy) and the still picture of the same scene, 640x480, with the
survey's greys and the horizon's colours by its time (viridis: green over red and blue)."""

import base64
from pathlib import Path

import numpy as np

import arbvis

NOTEBOOK = Path(__file__).resolve().parents[2] / "docs" / "notebooks" / "f3-in-one-view.ipynb"


def test_the_docs_notebook_runs_and_shows_its_three_layers(tmp_path):
    import nbclient
    import nbformat

    notebook = nbformat.read(NOTEBOOK, as_version=4)
    nbclient.NotebookClient(
        notebook,
        timeout=300,
        kernel_name="python3",
        resources={"metadata": {"path": str(NOTEBOOK.parent)}},
    ).execute()
    code = [c for c in notebook.cells if c.cell_type == "code"]
    errors = [o for c in code for o in c.outputs if o.output_type == "error"]
    assert not errors, errors
    # The view: a widget (its picture lives in the page; the kernel's side is
    # test_notebook.py), with a text fallback.
    view = [o for o in code[-2].outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})]
    assert len(view) == 1, code[-2].outputs
    # The still picture.
    pngs = [o.data["image/png"] for o in code[-1].outputs if "image/png" in o.get("data", {})]
    assert len(pngs) == 1, code[-1].outputs
    path = tmp_path / "still.png"
    path.write_bytes(base64.b64decode(pngs[0]))
    still = arbvis.read_png(path).astype(int)
    assert still.shape == (480, 640, 4)
    r, g, b = still[..., 0], still[..., 1], still[..., 2]
    # The horizon through viridis (its greens), the survey drawn faint in greys.
    horizon = (g > r + 30) & (g > b - 10) & (g > 60)
    grey = (np.abs(r - g) < 12) & (np.abs(g - b) < 12) & (r > 60)
    assert horizon.sum() > 3000, horizon.sum()
    assert grey.sum() > 3000, grey.sum()
