"""The Python API: shapes and values (equal to the command line's), states, errors, the
interpreter released while rendering, Ctrl-C and progress."""

import os
import pickle
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import vcm_rs


@pytest.fixture(scope="module")
def box(scenes):
    return vcm_rs.load_scene(scenes / "cornell-box.gltf")


@pytest.fixture(scope="module")
def water(scenes):
    return vcm_rs.load_scene(scenes / "cornell-water.gltf")


def test_render_returns_an_owned_float32_image_sized_by_the_camera(box):
    image = vcm_rs.render(box, algo="pt", spp=2, width=40, height=30)
    assert image.shape == (30, 40, 3)
    assert image.dtype == np.float32
    assert image.flags["C_CONTIGUOUS"]
    assert np.isfinite(image).all() and image.min() >= 0 and image.mean() > 0
    # The box's camera gives no aspect ratio: the image is square.
    assert vcm_rs.render(box, algo="pt", spp=1, width=24).shape == (24, 24, 3)


def test_scene_info_describes_the_scene(box, water):
    info = box.info()
    assert info["triangles"] == 36
    assert info["lights"]["area"] == 2
    assert info["material_classes"]["diffuse"] and not info["material_classes"]["specular"]
    assert water.info()["material_classes"]["transmission"]
    assert info["cameras"] and info["camera"] is None and info["warnings"] == []
    assert info["features"] == dict.fromkeys(
        ["textures", "alpha_masks", "normal_maps", "vertex_colors", "absorbing_volumes"], False
    )
    assert str(box.path).endswith("cornell-box.gltf")


@pytest.mark.parametrize("algo", ["pt", "vcm", "bpt"])
def test_images_equal_the_command_lines_exr(box, vcm_cli, tmp_path, algo):
    exr = tmp_path / "cli.exr"
    subprocess.run(
        [vcm_cli, "render", box.path, "--algo", algo, "--spp", "3", "--width", "32",
         "--seed", "5", "-o", exr],
        check=True,
        capture_output=True,
    )
    image = vcm_rs.render(box, algo=algo, spp=3, width=32, seed=5)
    assert np.array_equal(image, vcm_rs.read_exr(exr))


def test_auto_chooses_as_the_command_line_and_the_state_records_the_choice(
    water, vcm_cli, tmp_path
):
    exr = tmp_path / "cli.exr"
    cli = subprocess.run(
        [vcm_cli, "render", water.path, "--spp", "2", "--width", "64", "--seed", "2", "-o", exr],
        check=True,
        capture_output=True,
        text=True,
    )
    chosen = next(line for line in cli.stderr.splitlines() if line.startswith("algorithm: "))
    chosen = chosen.split()[1]
    assert np.array_equal(vcm_rs.render(water, spp=2, width=64, seed=2), vcm_rs.read_exr(exr))
    state = vcm_rs.render_state(water, samples=range(0, 2), width=64, seed=2)
    assert state.settings()["algorithm"] == chosen
    assert np.array_equal(state.image(), vcm_rs.read_exr(exr))


@pytest.mark.parametrize(
    "flag, value, keyword",
    [("--radius", "3px", dict(radius="3px")), ("--light-paths", "2.5", dict(light_paths=2.5))],
)
def test_integrator_options_are_the_command_lines(water, vcm_cli, tmp_path, flag, value, keyword):
    exr = tmp_path / "cli.exr"
    subprocess.run(
        [vcm_cli, "render", water.path, "--algo", "vcm", "--spp", "2", "--width", "32",
         flag, value, "-o", exr],
        check=True,
        capture_output=True,
    )
    image = vcm_rs.render(water, algo="vcm", spp=2, width=32, **keyword)
    assert np.array_equal(image, vcm_rs.read_exr(exr))
    assert not np.array_equal(image, vcm_rs.render(water, algo="vcm", spp=2, width=32))
    state = vcm_rs.render_state(water, samples=range(0, 2), algo="vcm", width=32, **keyword)
    assert state.settings()[flag[2:].replace("-", "_")] == value


def test_shards_merge_into_the_whole_render_bit_for_bit(water):
    options = dict(algo="vcm", width=32, seed=3)
    whole = vcm_rs.render(water, spp=6, **options)
    a = vcm_rs.render_state(water, samples=range(0, 2), **options)
    b = vcm_rs.render_state(water, samples=range(2, 5), **options)
    c = vcm_rs.render_state(water, samples=range(5, 6), **options)
    merged = c.merge(a).merge(b)
    assert merged.samples == [range(0, 6)] and merged.spp == 6
    assert np.array_equal(merged.image(), whole)
    assert np.array_equal(a.merge(b.merge(c)).image(), whole)
    # States travel between processes as their file's bytes.
    assert np.array_equal(pickle.loads(pickle.dumps(merged)).image(), whole)


def test_states_saved_from_python_are_the_command_lines(water, vcm_cli, tmp_path):
    options = dict(algo="vcm", width=24, seed=1)
    first = vcm_rs.render_state(water, samples=range(0, 2), **options)
    second = vcm_rs.render_state(water, samples=range(2, 4), **options)
    first.save(tmp_path / "a.state")
    second.save(tmp_path / "b.state")
    assert vcm_rs.load_state(tmp_path / "a.state").samples == [range(0, 2)]
    exr = tmp_path / "merged.exr"
    subprocess.run(
        [vcm_cli, "merge", tmp_path / "a.state", tmp_path / "b.state", "-o", exr],
        check=True,
        capture_output=True,
    )
    assert np.array_equal(vcm_rs.read_exr(exr), vcm_rs.render(water, spp=4, **options))


def test_merging_refuses_shared_samples_and_other_settings(water):
    a = vcm_rs.render_state(water, samples=range(0, 2), algo="pt", width=16)
    overlapping = vcm_rs.render_state(water, samples=range(1, 3), algo="pt", width=16)
    with pytest.raises(vcm_rs.VcmError, match="both hold samples 1..2"):
        a.merge(overlapping)
    other_seed = vcm_rs.render_state(water, samples=range(2, 3), algo="pt", width=16, seed=9)
    with pytest.raises(vcm_rs.VcmError, match="seed 9 instead of 0"):
        a.merge(other_seed)


@pytest.mark.parametrize(
    "options, error, words",
    [
        (dict(spp=0), ValueError, "spp"),
        (dict(spp="many"), TypeError, "spp"),
        (dict(width=-4), ValueError, "width"),
        (dict(time=-1.0), ValueError, "time"),
        (dict(time=float("nan")), ValueError, "time"),
        (dict(spp=4, time=1.0), ValueError, "not both"),
        (dict(algo="mlt"), ValueError, "one of auto, pt, lt, bpt, ppm, bpm, vcm"),
        (dict(sampler="halton"), ValueError, "sampler"),
        (dict(backend="tpu"), ValueError, "backend"),
        (dict(shading="gpu"), ValueError, 'give backend="gpu" too'),
        (dict(progress=3), TypeError, "progress"),
        (dict(colour="red"), TypeError, "unexpected keyword argument 'colour'"),
        (dict(connections=0, algo="bpt"), ValueError, "connections"),
        (
            dict(light_paths=17, algo="vcm"),
            ValueError,
            "light_paths: expected a number of light paths per pixel from 1/16 to 16, not 17",
        ),
        (dict(light_paths="many", algo="vcm"), TypeError, "light_paths"),
        (dict(radius=0.0, algo="ppm"), ValueError, "radius"),
        (dict(radius="2 pixels", algo="ppm"), ValueError, "radius: '2 pixels'"),
        (dict(radius=[2], algo="ppm"), TypeError, "radius"),
    ],
)
def test_bad_arguments_raise_python_errors_naming_them(box, options, error, words):
    with pytest.raises(error, match=words):
        vcm_rs.render(box, **{"width": 8, **options})


def test_gpu_shading_renders_the_command_lines_image(water, vcm_cli, tmp_path):
    """shading="gpu" is `vcm render --backend gpu --shading gpu`, bit for bit (the same
    kernel on the same adapter), and the CPU path tracer's image up to rounding. Skipped
    without a graphics adapter unless VCM_REQUIRE_GPU=1 (lavapipe is one)."""
    try:
        image = vcm_rs.render(water, backend="gpu", shading="gpu", spp=4, width=32, seed=3)
    except vcm_rs.VcmError as error:
        if os.environ.get("VCM_REQUIRE_GPU") == "1" or "adapter" not in str(error):
            raise
        pytest.skip(f"no GPU adapter: {error}")
    exr = tmp_path / "cli.exr"
    subprocess.run(
        [vcm_cli, "render", water.path, "--backend", "gpu", "--shading", "gpu",
         "--spp", "4", "--width", "32", "--seed", "3", "-o", exr],
        check=True,
        capture_output=True,
    )
    assert np.array_equal(image, vcm_rs.read_exr(exr))
    cpu = vcm_rs.render(water, algo="pt", spp=4, width=32, seed=3)
    close = np.abs(image - cpu).max(axis=2) <= 1e-4 * np.maximum(cpu.max(axis=2), 1e-2)
    assert close.mean() >= 0.99


def test_bad_sample_ranges_are_refused(box):
    for samples in [range(3, 3), range(0, 8, 2), range(-1, 4)]:
        with pytest.raises(ValueError, match="samples"):
            vcm_rs.render_state(box, samples=samples, width=8)
    with pytest.raises(TypeError, match="samples"):
        vcm_rs.render_state(box, samples=[0, 1], width=8)
    with pytest.raises(ValueError, match="not both"):
        vcm_rs.render_state(box, samples=range(0, 2), spp=2, width=8)


def test_unreadable_files_raise_vcm_errors_naming_them(tmp_path):
    with pytest.raises(vcm_rs.VcmError, match="missing.gltf"):
        vcm_rs.load_scene(tmp_path / "missing.gltf")
    junk = tmp_path / "junk.state"
    junk.write_bytes(b"\x10\x00\x00\x00\x00\x00\x00\x00{}")
    with pytest.raises(vcm_rs.VcmError, match="junk.state"):
        vcm_rs.load_state(junk)
    with pytest.raises(vcm_rs.VcmError, match="the render state's bytes"):
        vcm_rs.RenderState.from_bytes(b"not a state")
    with pytest.raises(vcm_rs.VcmError, match="junk.state"):
        vcm_rs.read_exr(junk)


def test_other_threads_run_while_rendering(water):
    counter = [0]
    rendering = threading.Event()

    def count():
        rendering.wait()
        while rendering.is_set():
            counter[0] += 1

    thread = threading.Thread(target=count)
    thread.start()
    rendering.set()
    start = time.perf_counter()
    vcm_rs.render(water, algo="vcm", spp=4, width=96)
    seconds = time.perf_counter() - start
    counted = counter[0]
    rendering.clear()
    thread.join()
    # A thread that holds the interpreter starves the counter; released, it counts
    # millions of times a second (the bound is ten thousand per second, with room).
    assert counted > 10_000 * seconds, (counted, seconds)


def test_progress_is_reported_until_done_and_its_errors_stop_the_render(box):
    calls = []
    vcm_rs.render(box, algo="pt", spp=5, width=16, progress=lambda n, t: calls.append((n, t)))
    assert calls[-1] == (5, 5)
    assert [n for n, _ in calls] == sorted(n for n, _ in calls)

    def fail(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        vcm_rs.render(box, algo="pt", time=30.0, width=64, progress=fail)


def test_ctrl_c_interrupts_a_render_with_keyboard_interrupt(scenes):
    script = textwrap.dedent(
        f"""
        import signal, time, vcm_rs
        # Python raises KeyboardInterrupt on SIGINT unless it started with SIGINT ignored,
        # as every process started in the background by a non-interactive shell does.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        scene = vcm_rs.load_scene({str(scenes / "cornell-water.gltf")!r})
        print("rendering", flush=True)
        start = time.perf_counter()
        try:
            vcm_rs.render(scene, algo="vcm", time=60.0, width=128)
        except KeyboardInterrupt:
            print(f"interrupted after {{time.perf_counter() - start:.2f}} s", flush=True)
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert child.stdout.readline() == "rendering\n"
    time.sleep(1.0)
    sent = time.perf_counter()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=30)
    stopped = time.perf_counter() - sent
    assert child.returncode == 0, err
    assert out.startswith("interrupted after"), (out, err)
    assert stopped < 5.0, stopped


def test_exr_files_round_trip_and_metrics_match_their_formulas(tmp_path):
    rng = np.random.default_rng(7)
    image = rng.random((5, 7, 3), dtype=np.float32) * 4
    reference = rng.random((5, 7, 3), dtype=np.float32) * 4
    vcm_rs.write_exr(tmp_path / "a.exr", image)
    assert np.array_equal(vcm_rs.read_exr(tmp_path / "a.exr"), image)
    vcm_rs.write_exr(tmp_path / "b.exr", image.astype(np.float64))
    assert np.array_equal(vcm_rs.read_exr(tmp_path / "b.exr"), image)
    d = image.astype(np.float64) - reference
    assert vcm_rs.rmse(image, reference) == pytest.approx(np.sqrt(np.mean(d * d)), rel=1e-12)
    relmse = np.mean(d * d / (reference.astype(np.float64) ** 2 + 0.01))
    assert vcm_rs.relmse(image, reference) == pytest.approx(relmse, rel=1e-12)
    with pytest.raises(ValueError, match="7×5"):
        vcm_rs.rmse(image, reference[:4])
    poisoned = reference.copy()
    poisoned[2, 3, 1] = np.nan
    with pytest.raises(ValueError, match="reference: 1 pixels are not finite"):
        vcm_rs.relmse(image, poisoned)
    with pytest.raises(ValueError, match=r"\(height, width, 3\)"):
        vcm_rs.write_exr(tmp_path / "c.exr", image[:, :, :2])
