"""vcm-rs: a physically based renderer built around Vertex Connection and Merging.

Render a scene to a NumPy array::

    import vcm_rs
    scene = vcm_rs.load_scene("scenes/cornell-water.gltf")
    image = vcm_rs.render(scene, algo="vcm", spp=64, width=256)   # (height, width, 3) float32
    vcm_rs.write_exr("water.exr", image)

Render in pieces and merge them, exactly (bit for bit the image of one render)::

    a = vcm_rs.render_state(scene, samples=range(0, 32), width=256)
    b = vcm_rs.render_state(scene, samples=range(32, 64), width=256)
    image = a.merge(b).image()

Spread one render over a Dask cluster: see `vcm_rs.distributed`.
"""

import copyreg as _copyreg

from ._native import (
    RenderState,
    Scene,
    VcmError,
    load_scene,
    load_state,
    read_exr,
    relmse,
    render,
    render_state,
    rmse,
    write_exr,
)

__all__ = [
    "RenderState",
    "Scene",
    "VcmError",
    "load_scene",
    "load_state",
    "read_exr",
    "relmse",
    "render",
    "render_state",
    "rmse",
    "write_exr",
]


def _state_from_bytes(data):
    """A RenderState from the bytes pickling made of it."""
    return RenderState.from_bytes(data)


def _pickle_state(state):
    return _state_from_bytes, (state.to_bytes(),)


# States pickle as the bytes of their file, so that they travel between processes (Dask).
_copyreg.pickle(RenderState, _pickle_state)
