"""Type stubs of the extension module (its functions are re-exported by `vcm_rs`)."""

import os
from typing import Callable, Literal, Optional, Union

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
def render(
    scene: Scene,
    *,
    algo: Literal["pt", "lt", "bpt", "ppm", "bpm", "vcm"] = "vcm",
    spp: Optional[int] = None,
    time: Optional[float] = None,
    width: int = 512,
    height: Optional[int] = None,
    seed: int = 0,
    sampler: Literal["sobol", "independent"] = "sobol",
    max_depth: Optional[int] = None,
    connections: int = 1,
    radius: float = ...,
    alpha: float = ...,
    no_prune: bool = False,
    backend: Literal["cpu", "gpu"] = "cpu",
    spp_per_frame: Optional[int] = None,
    scheduler: Optional[Literal["none", "tile", "queue"]] = None,
    tile_size: Optional[int] = None,
    progress: Optional[Callable[[float, float], object]] = None,
) -> _Image: ...
def render_state(
    scene: Scene,
    samples: Optional[range] = None,
    *,
    algo: Literal["pt", "lt", "bpt", "ppm", "bpm", "vcm"] = "vcm",
    spp: Optional[int] = None,
    time: Optional[float] = None,
    width: int = 512,
    height: Optional[int] = None,
    seed: int = 0,
    sampler: Literal["sobol", "independent"] = "sobol",
    max_depth: Optional[int] = None,
    connections: int = 1,
    radius: float = ...,
    alpha: float = ...,
    no_prune: bool = False,
    backend: Literal["cpu", "gpu"] = "cpu",
    spp_per_frame: Optional[int] = None,
    scheduler: Optional[Literal["none", "tile", "queue"]] = None,
    tile_size: Optional[int] = None,
    progress: Optional[Callable[[float, float], object]] = None,
) -> RenderState: ...
def load_state(path: _Path) -> RenderState: ...
def write_exr(path: _Path, image: npt.NDArray[np.floating]) -> None: ...
def read_exr(path: _Path) -> _Image: ...
def rmse(image: npt.NDArray[np.floating], reference: npt.NDArray[np.floating]) -> float: ...
def relmse(image: npt.NDArray[np.floating], reference: npt.NDArray[np.floating]) -> float: ...
