"""One render on a real Dask cluster (worker processes on this machine): bit for bit the
local render, scenes loaded once per worker, a worker killed mid-task, clear errors."""

import os
import signal
import time

import numpy as np
import pytest
from distributed import Client, LocalCluster

import vcm_rs
import vcm_rs.distributed as vd


def cluster():
    return LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    )


@pytest.fixture(scope="module")
def client():
    with cluster() as local, Client(local) as client:
        yield client


def scene_loads(client):
    return client.run(lambda: __import__("vcm_rs.distributed").distributed.scene_loads)


@pytest.mark.parametrize("algo, tasks", [("vcm", 3), ("pt", 5), ("bpt", 1)])
def test_the_cluster_renders_the_local_image_bit_for_bit(client, scenes, algo, tasks):
    path = scenes / "cornell-water.gltf"
    options = dict(algo=algo, width=48, seed=4)
    image = vd.render(client, path, spp=7, tasks=tasks, **options)
    assert np.array_equal(image, vcm_rs.render(vcm_rs.load_scene(path), spp=7, **options))
    state = vd.render_state(client, path, spp=7, tasks=tasks, **options)
    assert state.samples == [range(0, 7)]


def test_each_worker_loads_a_scene_once(client, scenes):
    path = scenes / "cornell-box.gltf"
    for seed in range(3):
        vd.render(client, path, spp=4, tasks=4, algo="pt", width=16, seed=seed)
    before = scene_loads(client)
    vd.render(client, path, spp=4, tasks=4, algo="pt", width=16)
    assert scene_loads(client) == before


def test_a_scene_missing_on_the_workers_is_named_with_the_worker(client, tmp_path):
    missing = tmp_path / "gone.gltf"
    with pytest.raises(vcm_rs.VcmError, match=r"worker tcp://[\d.:]+: .*gone\.gltf"):
        vd.render(client, missing, spp=2, tasks=2, width=8)


def test_bad_arguments_are_refused(client, scenes):
    path = scenes / "cornell-box.gltf"
    with pytest.raises(ValueError, match="tasks"):
        vd.render(client, path, spp=4, tasks=0)
    with pytest.raises(ValueError, match="spp"):
        vd.render(client, path, spp=0)
    with pytest.raises(ValueError, match="time"):
        vd.render(client, path, time=3.0)
    with pytest.raises(ValueError, match="algo"):
        vd.render(client, path, spp=2, width=8, algo="mlt")
    assert vd.split(10, 4) == [range(0, 2), range(2, 5), range(5, 7), range(7, 10)]
    assert vd.split(3, 8) == [range(0, 1), range(1, 2), range(2, 3)]


def suspicious_tasks(dask_scheduler):
    """How many tasks held by the scheduler were in the hands of a worker that died."""
    return sum(task.suspicious > 0 for task in dask_scheduler.tasks.values())


def test_a_worker_killed_mid_task_changes_nothing(scenes):
    path = scenes / "cornell-water.gltf"
    # Tasks of about a second each on two cores (four tasks of four samples at 256×256).
    options = dict(algo="vcm", width=256, seed=2)
    expected = vcm_rs.render(vcm_rs.load_scene(path), spp=16, **options)
    with cluster() as local, Client(local) as client:
        pids = client.run(os.getpid)
        future = vd.submit(client, path, spp=16, tasks=4, **options)
        victim = None
        deadline = time.monotonic() + 60
        while victim is None and time.monotonic() < deadline:
            for worker, keys in client.processing().items():
                if any("_render_shard" in str(key) for key in keys):
                    victim = worker
                    break
            time.sleep(0.02)
        assert victim is not None, "no task started"
        time.sleep(0.2)
        os.kill(pids[victim], signal.SIGKILL)
        # The scheduler saw a worker die with a task in hand, and runs that task again.
        deadline = time.monotonic() + 30
        while not client.run_on_scheduler(suspicious_tasks) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert client.run_on_scheduler(suspicious_tasks) >= 1
        image = future.result(timeout=300).image()
        # The nanny restarted the killed worker: a new process.
        assert pids[victim] not in client.run(os.getpid).values()
    assert np.array_equal(image, expected)
