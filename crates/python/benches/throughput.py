"""Throughput of the Python package against the `vcm` command line, in interleaved (ABBA)
rounds on one machine:

- a render through Dask (a LocalCluster of worker processes) against `vcm render` alone,
  the same samples of the same image, with the overheads of a distributed render (scene
  load on the workers, state transfer, merges);
- `vcm_rs.render` against `vcm render`, the same render in the same process.

Usage (after tools/test or `maturin develop --release` in crates/python):

    .venv/bin/python crates/python/benches/throughput.py [--spp 80] [--rounds 2]

Prints a Markdown table; docs/python.md holds the figures and the machine they came from.
"""

import argparse
import os
import pathlib
import re
import subprocess
import tempfile
import time

import numpy as np
from distributed import Client, LocalCluster

import vcm_rs
import vcm_rs.distributed as vd

ROOT = pathlib.Path(__file__).resolve().parents[3]
RENDERED = re.compile(r"rendered (\d+) spp at (\d+)×(\d+) in ([\d.]+) s")


def cli_render(vcm, scene, spp, width, algo, out):
    """Seconds of `vcm render`'s own render loop and of the whole process."""
    start = time.perf_counter()
    done = subprocess.run(
        [vcm, "render", scene, "--algo", algo, "--spp", str(spp), "--width", str(width),
         "-o", out],
        check=True, capture_output=True, text=True,
    )
    wall = time.perf_counter() - start
    loop = float(RENDERED.search(done.stderr + done.stdout).group(4))
    return loop, wall


def dask_render(client, scene, spp, width, algo, tasks):
    """Seconds from submitting to holding the image, and the merged state."""
    start = time.perf_counter()
    state = vd.render_state(client, scene, spp=spp, tasks=tasks, algo=algo, width=width)
    image = state.image()
    return time.perf_counter() - start, state, image


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default=str(ROOT / "scenes" / "cornell-water.gltf"))
    parser.add_argument("--algo", default="vcm")
    parser.add_argument("--width", type=int, default=512)
    parser.add_argument("--spp", type=int, default=80, help="about 60 s of VCM at 512² on 2 cores")
    parser.add_argument("--tasks", type=int, default=8)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=1, help="ABBA rounds")
    parser.add_argument("--python-spp", type=int, default=16)
    parser.add_argument("--python-only", action="store_true",
                        help="only vcm_rs.render against vcm render")
    args = parser.parse_args()
    vcm = os.environ.get("VCM_BIN", str(ROOT / "target" / "release" / "vcm"))
    scene = args.scene
    pixels = args.width * vcm_rs.render(vcm_rs.load_scene(scene), spp=1, width=args.width,
                                        algo="pt").shape[0]
    out = pathlib.Path(tempfile.mkdtemp()) / "cli.exr"
    print(f"machine: {os.cpu_count()} cores; scene {scene}, {args.algo}, {args.width} wide")

    if not args.python_only:
        dask_against_cli(args, vcm, scene, pixels, out)
    python_against_cli(args, vcm, scene, out)


def dask_against_cli(args, vcm, scene, pixels, out):
    """Renders through Dask and with `vcm render` in ABBA rounds; prints the table."""
    threads = max(1, (os.cpu_count() or 1) // args.workers)
    cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0", env={"RAYON_NUM_THREADS": str(threads)})
    client = Client(cluster)
    cli_seconds, dask_seconds = [], []
    for _ in range(args.rounds):
        for kind in ("cli", "dask", "dask", "cli"):
            if kind == "cli":
                loop, wall = cli_render(vcm, scene, args.spp, args.width, args.algo, out)
                cli_seconds.append((loop, wall))
                print(f"  vcm render: {loop:.2f} s rendering, {wall:.2f} s in all", flush=True)
            else:
                wall, state, image = dask_render(client, scene, args.spp, args.width,
                                                 args.algo, args.tasks)
                dask_seconds.append(wall)
                print(f"  dask: {wall:.2f} s", flush=True)
    same = np.array_equal(image, vcm_rs.read_exr(out))
    start = time.perf_counter()
    state_bytes = len(state.to_bytes())
    encode_seconds = time.perf_counter() - start
    extra = vcm_rs.render_state(vcm_rs.load_scene(scene), samples=range(args.spp, args.spp + 1),
                                algo=args.algo, width=args.width)
    start = time.perf_counter()
    state.merge(extra)
    merge_seconds = time.perf_counter() - start
    loads = client.run(lambda: __import__("vcm_rs.distributed").distributed.scene_loads)
    client.close()
    cluster.close()
    start = time.perf_counter()
    vcm_rs.load_scene(scene)
    load_seconds = time.perf_counter() - start

    cli_loop = float(np.median([s[0] for s in cli_seconds]))
    cli_wall = float(np.median([s[1] for s in cli_seconds]))
    dask_wall = float(np.median(dask_seconds))
    samples = args.spp * pixels
    print()
    print(f"| what | seconds (median of {len(cli_seconds)}) | M samples/s | ratio |")
    print("| --- | --- | --- | --- |")
    print(f"| `vcm render` (render loop) | {cli_loop:.2f} | {samples / cli_loop / 1e6:.3f} | 1 |")
    print(f"| `vcm render` (whole process) | {cli_wall:.2f} | {samples / cli_wall / 1e6:.3f} | "
          f"{cli_loop / cli_wall:.3f} |")
    print(f"| Dask, {args.workers} workers, {args.tasks} tasks (submit to image) | "
          f"{dask_wall:.2f} | {samples / dask_wall / 1e6:.3f} | {cli_loop / dask_wall:.3f} |")
    print()
    print(f"image equal to the command line's: {same}")
    print(f"scene loads per worker: {sorted(loads.values())}; one load here: {load_seconds:.3f} s")
    print(f"state: {state_bytes / 2**20:.1f} MiB, encoded in {encode_seconds:.3f} s; "
          f"one merge: {merge_seconds:.3f} s")
    print(f"overhead per task: {(dask_wall - cli_loop) / args.tasks:.3f} s")



def python_against_cli(args, vcm, scene, out):
    """The same render, from the scene file to the EXR, with vcm_rs (load_scene, render,
    write_exr in a running interpreter) and with `vcm render` (the whole process, which
    also writes a PNG), in ABBA rounds; prints the medians and their ratio."""
    python_seconds, cli_seconds = [], []
    for _ in range(args.rounds):
        for kind in ("cli", "python", "python", "cli"):
            if kind == "cli":
                cli_seconds.append(cli_render(vcm, scene, args.python_spp, args.width,
                                              args.algo, out)[1])
            else:
                start = time.perf_counter()
                image = vcm_rs.render(vcm_rs.load_scene(scene), spp=args.python_spp,
                                      width=args.width, algo=args.algo)
                vcm_rs.write_exr(out.with_name("python.exr"), image)
                python_seconds.append(time.perf_counter() - start)
    python, cli = float(np.median(python_seconds)), float(np.median(cli_seconds))
    print()
    print(f"scene file to EXR, {args.python_spp} spp: vcm_rs {python:.2f} s, vcm render "
          f"{cli:.2f} s (medians of {len(cli_seconds)}): {100 * (python / cli - 1):+.1f}%")


if __name__ == "__main__":
    main()
