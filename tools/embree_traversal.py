#!/usr/bin/env python3
"""Traces ray sets written by `cargo bench --bench embree` through Embree 4 (the `embreex`
package from PyPI, single-ray API) and reports its rays/s, so that vcm-rs's CPU traversal and
Embree are timed on the same triangles and the same rays.

The folder holds `triangles.f32` (n × 9 little-endian floats: the corners of triangle i),
`sets.txt` (one line per ray set: its name and `closest` or `occluded`) and, per set,
`NAME.rays.f32` (m × 8 floats: origin, direction, tmin, tmax). Every set is traced
`--repeats` times on `--threads` threads pulling chunks of rays from one queue; the script
prints one line per set, `NAME SECONDS…` (the wall time of each pass), and writes
`NAME.embree.f32` (m × 2 floats: the hit's t, +inf for a miss, and its triangle index, -1
for a miss; for occlusion 1 or 0 and -1).

It also prints `overhead SECONDS…`: passes of a million rays that start outside the scene's
bounds and point away from it, which Embree rejects at the root. That is what the binding's
per-ray loop (filling Embree's ray structure, calling it, storing the answer) costs, which a
renderer calling Embree from C would not pay.

Embree's rays here start at t = 0: the sets must have tmin = 0.
"""

import argparse
import pathlib
import sys
import threading
import time

import numpy as np

try:
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh
except ImportError as error:
    sys.exit(f"embree_traversal.py: the embreex package is missing ({error}); pip install embreex")

CHUNK = 4096


def load(path, columns):
    values = np.fromfile(path, dtype="<f4")
    if values.size % columns:
        sys.exit(f"{path}: {values.size} floats is not a multiple of {columns}")
    return values.reshape(-1, columns)


def trace(scene, rays, query, threads):
    """Traces `rays` on `threads` threads; returns Embree's per-ray result array."""
    origins = np.ascontiguousarray(rays[:, 0:3])
    directions = np.ascontiguousarray(rays[:, 3:6])
    tmax = np.ascontiguousarray(rays[:, 7])
    result = np.empty(len(rays), dtype=np.int32)
    starts = iter(range(0, len(rays), CHUNK))
    lock = threading.Lock()

    def work():
        while True:
            with lock:
                start = next(starts, None)
            if start is None:
                return
            end = min(start + CHUNK, len(rays))
            ids = scene.run(
                origins[start:end], directions[start:end], dists=tmax[start:end], query=query
            )
            result[start:end] = ids

    pool = [threading.Thread(target=work) for _ in range(threads)]
    for thread in pool:
        thread.start()
    for thread in pool:
        thread.join()
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    triangles = load(args.folder / "triangles.f32", 9).reshape(-1, 3, 3)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, triangles)
    sets = [line.split() for line in (args.folder / "sets.txt").read_text().splitlines()]
    for name, kind in sets:
        rays = load(args.folder / f"{name}.rays.f32", 8)
        if np.any(rays[:, 6] != 0.0):
            sys.exit(f"{name}: Embree's rays start at t = 0, but some of these do not")
        query = {"closest": "INTERSECT", "occluded": "OCCLUDED"}[kind]
        # The first pass commits the scene (builds Embree's BVH) and is not timed.
        trace(scene, rays[:1], query, 1)
        seconds = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            ids = trace(scene, rays, query, args.threads)
            seconds.append(time.perf_counter() - start)
        out = np.empty((len(rays), 2), dtype="<f4")
        if kind == "closest":
            hits = scene.run(
                np.ascontiguousarray(rays[:, 0:3]),
                np.ascontiguousarray(rays[:, 3:6]),
                dists=np.ascontiguousarray(rays[:, 7]),
                output=1,
            )
            out[:, 0] = np.where(hits["geomID"] >= 0, hits["tfar"], np.inf)
            out[:, 1] = np.where(hits["geomID"] >= 0, hits["primID"], -1)
        else:
            # embreex reports an occluded ray as 0 (the geometry) and a clear one as -1.
            out[:, 0] = (ids >= 0).astype(np.float32)
            out[:, 1] = -1
        out.tofile(args.folder / f"{name}.embree.f32")
        print(name, " ".join(f"{s:.6f}" for s in seconds), flush=True)
    print("overhead", " ".join(f"{s:.6f}" for s in overhead(scene, triangles, args)), flush=True)


def overhead(scene, triangles, args):
    """Wall times of passes over a million rays that miss the scene's bounds at once."""
    corner = triangles.reshape(-1, 3).max(axis=0) + 1.0
    rays = np.zeros((1_000_000, 8), dtype=np.float32)
    rays[:, 0:3] = corner
    rays[:, 3:6] = 1.0
    rays[:, 7] = np.inf
    seconds = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        trace(scene, rays, "INTERSECT", args.threads)
        seconds.append(time.perf_counter() - start)
    return seconds


if __name__ == "__main__":
    main()
