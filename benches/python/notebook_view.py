"""The notebook view while the user drags, measured in the page: a JupyterLab server and
Debian's headless Chromium (the browser test's harness, python/tests/test_notebook_browser.py)
open a view of a scene, the mouse drags across it for SECONDS, and the page records when each
frame arrives. Prints frames per second during the drag, the median and 90th percentile of
the time between frames (browser to kernel to picture and back: the page sends its next drag
when a frame arrives), the dragging frames' size, and the time from the release to the full
picture. Usage: python benches/python/notebook_view.py [DEMO] [WIDTHxHEIGHT] [SECONDS]
(default v3o2-sum 800x600 4)."""

import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python" / "tests"))
from test_notebook_browser import (  # noqa: E402
    CHROMIUM,
    CHROMIUM_ARGS,
    notebook,
    open_notebook,
    run_cell,
    serve_lab,
)

# Records each frame's arrival (performance.now(), ms) and the picture's pixel size.
WATCH = """() => {
  window.arrivals = [];
  const img = document.querySelector('img.arbvis-view');
  new MutationObserver(() => {
    window.arrivals.push([performance.now(), Number(img.dataset.frames)]);
  }).observe(img, { attributes: true, attributeFilter: ['data-frames'] });
  img.addEventListener('load', () => { window.lastSize = [img.naturalWidth, img.naturalHeight]; });
}"""


def main():
    from playwright.sync_api import sync_playwright

    demo = sys.argv[1] if len(sys.argv) > 1 else "v3o2-sum"
    w, h = (int(v) for v in (sys.argv[2] if len(sys.argv) > 2 else "800x600").split("x"))
    seconds = float(sys.argv[3]) if len(sys.argv) > 3 else 4.0
    cell = (
        "import arbvis\nfrom arbvis.notebook import View\n"
        f"scene = arbvis.Scene.demo({demo!r})\nscene.size = ({w}, {h})\nview = View(scene)\nview"
    )
    with tempfile.TemporaryDirectory() as d, serve_lab(d) as (url, token):
        (Path(d) / "bench.ipynb").write_text(json.dumps(notebook([cell])))
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": w + 400, "height": h + 300})
            open_notebook(page, url, token, "bench.ipynb")
            run_cell(page, 0)
            page.wait_for_function(
                "(() => { const i = document.querySelector('img.arbvis-view');"
                " return i && i.complete && i.naturalWidth > 0; })()",
                timeout=120_000,
            )
            time.sleep(1.0)
            page.evaluate(WATCH)
            box = page.locator("img.arbvis-view").bounding_box()
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down()
            start = page.evaluate("performance.now()")
            t0 = time.monotonic()
            k = 0
            while time.monotonic() - t0 < seconds:
                k += 1
                page.mouse.move(x + 120 * ((k % 40) / 40 - 0.5), y + 10 * ((k % 7) / 7 - 0.5))
                time.sleep(1 / 60)
            dragging_size = page.evaluate("window.lastSize")
            end = page.evaluate("performance.now()")
            page.mouse.up()
            released = page.evaluate("performance.now()")
            time.sleep(3.0)
            arrivals = page.evaluate("window.arrivals")
            browser.close()
    during = [t for t, _ in arrivals if start <= t <= end]
    gaps = [b - a for a, b in zip(during, during[1:])]
    after = [t for t, _ in arrivals if t > released]
    print(f"scene: demo {demo} at {w}x{h}; drag {seconds:.1f} s (the mouse moved every 1/60 s)")
    print(f"frames while dragging: {len(during)}, {len(during) / ((end - start) / 1000):.1f} per second")
    if gaps:
        gaps.sort()
        p90 = gaps[min(len(gaps) - 1, int(0.9 * len(gaps)))]
        print(f"between frames: median {statistics.median(gaps):.0f} ms, 90th percentile {p90:.0f} ms")
    print(f"dragging frame: {dragging_size[0]}x{dragging_size[1]} pixels")
    if after:
        print(f"release to the full picture: {after[-1] - released:.0f} ms")


if __name__ == "__main__":
    main()
