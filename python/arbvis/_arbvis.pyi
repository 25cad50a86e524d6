"""Type stubs of the extension module (crates/arbvis-python)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class ArbvisError(Exception):
    """Every error arbvis raises."""

class SceneError(ArbvisError):
    """A scene that does not parse or validate."""

    path: Optional[str]
    line: Optional[int]
    column: Optional[int]
    key: Optional[str]

class InputError(ArbvisError):
    """A data file that cannot be read or used (the message names file and position)."""

class GLError(ArbvisError):
    """The GL refused: no context, a program that does not compile, out of memory."""

class RenderError(ArbvisError):
    """Something else went wrong preparing or drawing a picture."""

class Cancelled(ArbvisError):
    """Work stopped on request (a progress callback returned False)."""

_Path = Union[str, PathLike]

class Volume:
    """A survey in memory, indexed [inline, crossline, sample]: a numpy array with
    `spacing` (inline, crossline, sample) in metres, or an xarray DataArray whose
    coordinates give it. Stands wherever a scene names a volume file."""

    def __init__(self, data: Any, spacing: Optional[Tuple[float, float, float]] = None) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def shape(self) -> Tuple[int, int, int]: ...
    @property
    def spacing(self) -> Tuple[float, float, float]: ...

class Cloud:
    """A point cloud in memory: an (N, 3) array of positions, a dict of N values per
    attribute, (N, 3) colours; or a laspy.LasData. Stands wherever a scene names a
    cloud file."""

    def __init__(
        self, positions: Any, attributes: Optional[Dict[str, Any]] = None, rgb: Any = None
    ) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def attributes(self) -> List[str]: ...
    def __len__(self) -> int: ...

class Surface:
    """A triangle surface in memory: (N, 3) vertices and (M, 3) triangles; or
    Surface.grid(z, x, y), a 2D grid of heights (NaN: undefined). Stands wherever a scene
    names a surface file."""

    def __init__(self, vertices: Any, triangles: Any) -> None: ...
    @staticmethod
    def grid(z: Any, x: Any = None, y: Any = None) -> "Surface": ...
    @property
    def name(self) -> str: ...
    def __len__(self) -> int: ...

class Mesh:
    """An unstructured mesh in memory: (N, 3) points, an (M, 4) array of tetrahedra or a
    dict of meshio cell names to cells, point_data / cell_data dicts; or a meshio.Mesh.
    Stands wherever a scene names a mesh file."""

    def __init__(
        self,
        points: Any,
        cells: Any = None,
        point_data: Optional[Dict[str, Any]] = None,
        cell_data: Optional[Dict[str, Any]] = None,
    ) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def tetrahedra(self) -> int: ...

class Scene:
    """A scene: the technique and its parameters, size, fidelity, programs, camera."""

    @staticmethod
    def load(path: _Path) -> "Scene": ...
    @staticmethod
    def from_toml(text: str, base: Optional[_Path] = None) -> "Scene": ...
    @staticmethod
    def from_dict(d: Dict[str, Any], base: Optional[_Path] = None) -> "Scene": ...
    @staticmethod
    def demo(name: str) -> "Scene": ...
    def to_toml(self) -> str: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def __getitem__(self, key: str) -> Any: ...
    def __setitem__(self, key: str, value: Any) -> None: ...
    def __contains__(self, key: str) -> bool: ...
    @property
    def layers(self) -> List[Dict[str, Any]]: ...
    def add_layer(
        self,
        technique: str,
        params: Optional[Dict[str, Any]] = None,
        *,
        name: Optional[str] = None,
        visible: bool = True,
        offset: Optional[Tuple[float, float, float]] = None,
        scale: Optional[float] = None,
        index: Optional[int] = None,
    ) -> None: ...
    def remove_layer(self, index: int) -> None: ...
    def move_layer(self, from_index: int, to_index: int) -> None: ...
    def _repr_png_(self) -> bytes: ...
    def azimuth(self, degrees: float) -> None: ...
    def elevation(self, degrees: float) -> None: ...
    def reset_camera(self) -> None: ...
    def view_matrix(self) -> npt.NDArray[np.float64]: ...
    def projection_matrix(self) -> npt.NDArray[np.float64]: ...
    def to_pixels(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    @property
    def technique(self) -> str: ...
    params: Dict[str, Any]
    size: Tuple[int, int]
    fidelity: str
    programs: str
    rotation: Tuple[float, float, float, float]
    zoom: float
    projection: str
    base: str

class Renderer:
    """A scene kept ready to draw: context, data and programs kept between frames."""

    def __init__(self, scene: Scene, backend: str = "egl") -> None: ...
    def render(
        self, scene: Optional[Scene] = None, interactive: bool = False
    ) -> Union[npt.NDArray[np.uint8], npt.NDArray[np.float32]]: ...
    budget_ms: float
    def reference(self) -> Optional[npt.NDArray[np.float32]]: ...
    def stats(self) -> Dict[str, Any]: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def program_kind(self) -> str: ...
    @property
    def backend(self) -> str: ...
    @property
    def driver(self) -> str: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Renderer": ...
    def __exit__(self, *exc: Any) -> None: ...

def info(backend: str = "egl") -> Dict[str, Any]: ...
def inspect(path: _Path) -> Dict[str, Any]: ...
def fetch_stats() -> Dict[str, Any]: ...
def convert(
    src: _Path,
    dst: _Path,
    brick: int = 64,
    attributes: List[str] = ["envelope"],
    compression: str = "lz4",
    progress: Optional[Callable[[int, int], Optional[bool]]] = None,
    node_points: int = 100_000,
) -> Dict[str, Any]: ...

_Image = Union[npt.NDArray[np.uint8], npt.NDArray[np.float32]]

def read_png(path: _Path) -> npt.NDArray[np.uint8]: ...
def write_png(path: _Path, array: _Image) -> None: ...
def compare(
    actual: _Image, expected: _Image, tolerance: float = 1.0 / 255.0
) -> Dict[str, Any]: ...
def diff_image(
    actual: _Image, expected: _Image, tolerance: float = 1.0 / 255.0, gain: float = 16.0
) -> npt.NDArray[np.uint8]: ...
