"""Type stubs of the extension module (its functions are re-exported by `vcm_rs`)."""

import os
from typing import Callable, Literal, Optional, Union

from typing_extensions import TypedDict, Unpack

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]
_Image = npt.NDArray[np.float32]

class VcmError(Exception):
    """What vcm-rs could not do, with the reason."""

class Scene:
    """A scene loaded from a glTF or OBJ file, rendered from one of its cameras."""

    @property
    def path(self) -> str: ...
    def info(self) -> dict:
        """What the scene contains: triangles, materials, lights by kind, cameras, bounds…"""

class RenderState:
    """A render's film and the global samples it holds; merges exactly, pickles."""

    @property
    def samples(self) -> list[range]: ...
    @property
    def spp(self) -> int: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def scene_path(self) -> str: ...
    def settings(self) -> dict[str, str]: ...
    def merge(self, other: RenderState) -> RenderState: ...
    def image(self) -> _Image: ...
    def save(self, path: _Path) -> None: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> RenderState: ...

def load_scene(
    path: _Path,
    camera: Optional[str] = None,
    max_triangles: int = ...,
    max_texels: int = ...,
    allow_outside_files: bool = False,
) -> Scene: ...
class RenderOptions(TypedDict, total=False):
    """The keyword arguments of `render` and `render_state` (see `help(vcm_rs.render)`)."""

    algo: Literal["auto", "pt", "lt", "bpt", "ppm", "bpm", "vcm"]
    spp: int
    time: float
    width: int
    height: Optional[int]
    seed: int
    sampler: Literal["sobol", "independent"]
    max_depth: Optional[int]
    connections: int
    radius: Union[float, str]
    alpha: float
    no_prune: bool
    backend: Literal["cpu", "gpu"]
    spp_per_frame: Optional[int]
    scheduler: Optional[Literal["none", "tile", "queue"]]
    tile_size: Optional[int]
    progress: Callable[[float, float], object]

def render(scene: Scene, **options: Unpack[RenderOptions]) -> _Image: ...
def render_state(
    scene: Scene, samples: Optional[range] = None, **options: Unpack[RenderOptions]
) -> RenderState: ...
def load_state(path: _Path) -> RenderState: ...
def write_exr(path: _Path, image: npt.NDArray[np.floating]) -> None: ...
def read_exr(path: _Path) -> _Image: ...
def rmse(image: npt.NDArray[np.floating], reference: npt.NDArray[np.floating]) -> float: ...
def relmse(image: npt.NDArray[np.floating], reference: npt.NDArray[np.floating]) -> float: ...
