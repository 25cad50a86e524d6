"""A scene in a notebook, turned with the mouse: `arbvis.notebook.View(scene)`.

>>> from arbvis.notebook import View
>>> view = View(arbvis.Scene.demo("v3o2-sum"))
>>> view                                    # the picture; drag to turn, wheel to zoom
>>> view.scene["technique.opacity3d.slices"] = 64
>>> view.refresh()                          # an edit made from Python, shown

The view is an anywidget (Jupyter, JupyterLab, VS Code): the page shows PNG frames drawn
by one `arbvis.Renderer` in the kernel, the one interactive session every front end uses.
While the user drags, each frame is drawn within the renderer's budget (`budget_ms`,
smaller and cheaper: the frame budget); on release the full picture. The page sends at
most one drag at a time, summing the motion while a frame is on its way. Every message
from the page is checked: one that is not a known kind with numbers in range is ignored
and said in `error` (shown under the picture), never raised into the kernel.
"""

import math

import anywidget
import traitlets

from . import _arbvis

# Degrees the scene turns per pixel dragged, as the desktop viewer's arcball turns near
# the centre of a 400-pixel view.
DEGREES_PER_PIXEL = 0.5
# The largest picture side a page may ask for (a resize to a million pixels is clamped).
MAX_SIDE = 2048
# The smallest.
MIN_SIDE = 16
# The farthest one drag message may move (pixels) and the most one wheel step may zoom.
MAX_DRAG = 10_000
ZOOM_STEP = (0.02, 50.0)
# The zoom a scene may reach through the wheel (a scene refuses 0 and 1e9).
ZOOM_RANGE = (0.01, 1000.0)

_ESM = """
function render({ model, el }) {
  const img = document.createElement("img");
  img.draggable = false;
  img.alt = "arbvis";
  img.className = "arbvis-view";
  img.style.cursor = "grab";
  img.style.touchAction = "none";
  img.style.maxWidth = "100%";
  const error = document.createElement("div");
  error.className = "arbvis-error";
  error.style.color = "#b00020";
  error.style.font = "12px sans-serif";
  el.append(img, error);
  let url = null, down = null, waiting = false, dx = 0, dy = 0;
  function send() {
    if (waiting || (dx === 0 && dy === 0)) return;
    waiting = true;
    model.send({ kind: "drag", dx, dy });
    dx = 0; dy = 0;
  }
  function show() {
    const frame = model.get("frame");
    waiting = false;
    if (frame && frame.byteLength > 0) {
      const next = URL.createObjectURL(new Blob([frame], { type: "image/png" }));
      const [w, h] = model.get("size");
      img.onload = () => { if (url) URL.revokeObjectURL(url); url = next; };
      img.src = next;
      // The picture's own size, also while a smaller interactive frame stands for it.
      img.width = w; img.height = h;
      img.dataset.frames = String(model.get("frames"));
    }
    send();
  }
  img.addEventListener("pointerdown", (e) => {
    down = [e.clientX, e.clientY];
    img.setPointerCapture(e.pointerId);
    img.style.cursor = "grabbing";
  });
  img.addEventListener("pointermove", (e) => {
    if (!down) return;
    dx += e.clientX - down[0]; dy += e.clientY - down[1];
    down = [e.clientX, e.clientY];
    send();
  });
  const up = () => {
    if (!down) return;
    down = null;
    img.style.cursor = "grab";
    model.send({ kind: "release", dx, dy });
    dx = 0; dy = 0;
  };
  img.addEventListener("pointerup", up);
  img.addEventListener("pointercancel", up);
  img.addEventListener("wheel", (e) => {
    e.preventDefault();
    model.send({ kind: "zoom", factor: Math.exp(-e.deltaY / 500) });
  }, { passive: false });
  model.on("change:frames", show);
  model.on("change:error", () => { error.textContent = model.get("error"); });
  show();
  error.textContent = model.get("error");
  return () => { if (url) URL.revokeObjectURL(url); };
}
export default { render };
"""


class View(anywidget.AnyWidget):
    """A scene shown in a notebook and turned with the mouse (see the module's doc).

    `scene` is kept, not copied: edits made to it from Python show at the next frame
    (`refresh()`). `backend` is the renderer's (`"egl"` headless, `"osmesa"`)."""

    _esm = _ESM
    frame = traitlets.Bytes(b"").tag(sync=True)
    frames = traitlets.Int(0).tag(sync=True)
    size = traitlets.List(traitlets.Int(), default_value=[0, 0]).tag(sync=True)
    error = traitlets.Unicode("").tag(sync=True)

    def __init__(self, scene, backend="egl", **kwargs):
        super().__init__(**kwargs)
        if not isinstance(scene, _arbvis.Scene):
            raise TypeError(f"View shows an arbvis.Scene, got {type(scene).__name__}")
        self._scene = scene
        self._renderer = _arbvis.Renderer(scene, backend)
        self.on_msg(self._on_message)
        self.refresh()

    @property
    def scene(self):
        """The scene shown (edit it, then `refresh()`)."""
        return self._scene

    @property
    def renderer(self):
        """The renderer drawing the frames (its `budget_ms` is the dragging frames')."""
        return self._renderer

    def refresh(self):
        """Draw the full picture of the scene as it is now."""
        self._draw(interactive=False)

    def close(self):
        """Close the widget and its renderer."""
        self._renderer.close()
        super().close()

    def _draw(self, interactive):
        try:
            picture = self._renderer.render(interactive=interactive)
        except _arbvis.ArbvisError as e:
            self.error = str(e)
            return
        self.size = list(self._scene.size)
        self.frame = _arbvis.png_bytes(picture)
        self.frames += 1

    def _on_message(self, _widget, content, _buffers):
        """One message from the page: a drag, a release, a wheel step or a resize."""
        try:
            action = _checked(content)
        except ValueError as e:
            self.error = str(e)
            # The page waits for a frame before it sends the next drag.
            self.frames += 1
            return
        self.error = ""
        kind = action[0]
        if kind in ("drag", "release"):
            dx, dy = action[1], action[2]
            if dx or dy:
                self._scene.azimuth(-dx * DEGREES_PER_PIXEL)
                self._scene.elevation(-dy * DEGREES_PER_PIXEL)
            self._draw(interactive=kind == "drag")
        elif kind == "zoom":
            zoom = min(max(self._scene.zoom * action[1], ZOOM_RANGE[0]), ZOOM_RANGE[1])
            self._scene.zoom = zoom
            self._draw(interactive=False)
        elif kind == "resize":
            self._scene.size = (action[1], action[2])
            self._draw(interactive=False)


def _checked(content):
    """The action a page's message asks for, as a tuple of checked values; ValueError
    saying what is wrong otherwise."""

    def shown(value):
        text = repr(value)
        return text if len(text) <= 60 else text[:57] + "..."

    if not isinstance(content, dict):
        raise ValueError(f"a message from the page is a dict, got {shown(content)}")
    kind = content.get("kind")

    def number(key, low, high):
        value = content.get(key, 0)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{kind}: {key} is a number, got {shown(value)}")
        if not (math.isfinite(value) and low <= value <= high):
            raise ValueError(f"{kind}: {key} {shown(value)} is outside {low}..{high}")
        return float(value)

    if kind in ("drag", "release"):
        return (kind, number("dx", -MAX_DRAG, MAX_DRAG), number("dy", -MAX_DRAG, MAX_DRAG))
    if kind == "zoom":
        return (kind, number("factor", *ZOOM_STEP))
    if kind == "resize":
        # A page may ask for any size; the picture keeps to MIN_SIDE..MAX_SIDE.
        sides = [number(k, 0, 1e9) for k in ("width", "height")]
        return (kind, *(int(min(max(round(s), MIN_SIDE), MAX_SIDE)) for s in sides))
    raise ValueError(f"a message's kind is drag, release, zoom or resize, got {shown(kind)}")
