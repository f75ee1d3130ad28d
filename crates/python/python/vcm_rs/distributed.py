"""One render spread over a Dask cluster, equal bit for bit to a single-process render.

The global samples (iterations, for the VCM family) ``0..spp`` are split into ``tasks``
contiguous ranges; each task renders its range on a worker into a `RenderState` (the
worker loads the scene once and keeps it for later tasks), and the states are merged by a
tree of merge tasks on the workers. A sample is the same whatever process renders it and
the film's sums are exact, so the image equals ``vcm_rs.render`` with the same settings
and seed, bit for bit, however the tasks were spread, retried or merged. A worker that dies
mid-task costs only that task, which Dask runs again elsewhere.

Every worker must see the scene file (and its buffers and textures) at the same path::

    from dask.distributed import Client
    import vcm_rs.distributed

    client = Client("tcp://scheduler:8786")     # or Client() for a local cluster
    image = vcm_rs.distributed.render(client, "/shared/scenes/water.gltf",
                                      spp=1024, tasks=64, algo="vcm", width=1024)

Each worker process renders on all the cores it sees (set ``RAYON_NUM_THREADS`` in the
worker's environment to use fewer); run one worker process per machine with one Dask
thread (``--nworkers 1 --nthreads 1``).
"""

import os

from distributed import get_worker

from . import VcmError, load_scene, render_state as _render_state

__all__ = ["render", "render_state", "submit", "split"]

# The scenes this worker process has loaded: (path, camera, load options) → ((mtime, size),
# Scene). A scene file changed on disk is loaded again.
_scenes = {}

# How many times this worker process has loaded a scene (for tests and reports).
scene_loads = 0


def split(spp, tasks):
    """The ranges of global samples ``tasks`` tasks render: ``0..spp`` cut into
    contiguous pieces whose sizes differ by at most one."""
    if spp < 1:
        raise ValueError(f"spp: must be at least 1, not {spp}")
    if tasks < 1:
        raise ValueError(f"tasks: must be at least 1, not {tasks}")
    tasks = min(tasks, spp)
    bounds = [spp * i // tasks for i in range(tasks + 1)]
    return [range(a, b) for a, b in zip(bounds, bounds[1:])]


def _worker_name():
    try:
        return get_worker().address
    except ValueError:
        return "the local process"


def _cached_scene(path, camera, load_options):
    """The scene at ``path``, loaded once per worker process (again if the file changed)."""
    global scene_loads
    key = (path, camera, tuple(sorted(load_options.items())))
    try:
        status = os.stat(path)
    except OSError as error:
        raise VcmError(
            f"worker {_worker_name()}: cannot read the scene {path}: {error.strerror}"
        ) from None
    signature = (status.st_mtime_ns, status.st_size)
    cached = _scenes.get(key)
    if cached is not None and cached[0] == signature:
        return cached[1]
    try:
        scene = load_scene(path, camera=camera, **load_options)
    except VcmError as error:
        raise VcmError(f"worker {_worker_name()}: {error}") from None
    scene_loads += 1
    _scenes[key] = (signature, scene)
    return scene


def _render_shard(path, camera, load_options, samples, options):
    """A task: the state of global samples ``samples`` of the scene at ``path``."""
    scene = _cached_scene(path, camera, load_options)
    return _render_state(scene, samples=samples, **options)


def _merge(a, b):
    """A task: the state holding the samples of both."""
    return a.merge(b)


def submit(client, scene_path, spp=16, tasks=None, camera=None, load_options=None, **options):
    """Submits the render and returns a Dask future of the merged `RenderState`.

    Args:
        client: a ``distributed.Client``.
        scene_path: the scene file, at a path every worker can read.
        spp: samples per pixel (iterations for the VCM family) in all.
        tasks: how many tasks to split them into (default: four per worker thread, at
            most ``spp``).
        camera: the scene's camera to render from (as ``vcm_rs.load_scene``).
        load_options: further keyword arguments of ``vcm_rs.load_scene`` (limits).
        **options: the keyword arguments of ``vcm_rs.render`` (algo, width, seed, …), but
            not ``time``, ``spp`` or ``progress``.
    """
    for key in ("time", "progress", "samples"):
        if key in options:
            raise ValueError(f"{key}: a distributed render takes spp and tasks only")
    if tasks is None:
        threads = sum(w["nthreads"] for w in client.scheduler_info()["workers"].values())
        tasks = 4 * max(threads, 1)
    path = os.path.abspath(os.fspath(scene_path))
    load_options = dict(load_options or {})
    states = [
        client.submit(
            _render_shard, path, camera, load_options, samples, options, pure=False
        )
        for samples in split(spp, tasks)
    ]
    while len(states) > 1:
        pairs = [states[i : i + 2] for i in range(0, len(states), 2)]
        states = [
            client.submit(_merge, *pair, pure=False) if len(pair) == 2 else pair[0]
            for pair in pairs
        ]
    return states[0]


def render_state(client, scene_path, spp=16, tasks=None, **options):
    """Renders on the cluster and returns the merged `RenderState` (arguments as `submit`)."""
    return submit(client, scene_path, spp=spp, tasks=tasks, **options).result()


def render(client, scene_path, spp=16, tasks=None, **options):
    """Renders on the cluster and returns the image, a float32 array of shape (height,
    width, 3), equal bit for bit to ``vcm_rs.render`` with the same settings (arguments as
    `submit`)."""
    return render_state(client, scene_path, spp=spp, tasks=tasks, **options).image()
