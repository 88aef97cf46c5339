"""clpde batch on a real 2-worker distributed.LocalCluster (started once for the module):
outputs bitwise equal to serial runs, a killed worker, reruns, failures, and tiling."""

import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")

import clpde  # noqa: E402
from clpde.cli import main  # noqa: E402
from clpde.io.images import read_image, write_image  # noqa: E402
from clpde.scale.batch import batch  # noqa: E402
from clpde.scale.cluster import plan_workers, start_cluster  # noqa: E402
from clpde.scale.manifest import MANIFEST  # noqa: E402


@pytest.fixture(scope="module")
def client():
    """The layout of a GPU machine (one worker per device, pinned by CLPDE_DEVICE, with the
    resource GPU=1 that every task then asks for), the CPU device standing in for two
    GPUs. (The plain LocalCluster runs in test_video.py and the Ctrl-C test.)"""
    from distributed import Client

    index = clpde.get_runtime().index
    cluster, workers, threads = start_cluster(gpus=[index, index])
    assert (workers, threads) == (2, None)
    with Client(cluster, set_as_default=False) as c:
        c.wait_for_workers(2, timeout=60)
        assert set(c.run(lambda: os.environ["CLPDE_DEVICE"]).values()) == {str(index)}
        assert all(w["resources"] == {"GPU": 1} for w in c.scheduler_info()["workers"].values())
        yield c
    cluster.close()


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """Six small photos (grey and RGB, two sizes) and a scratch mask for the 64x80 ones."""
    folder = tmp_path_factory.mktemp("photos")
    rng = np.random.default_rng(7)
    yy, xx = np.mgrid[0:64, 0:80]
    paths = []
    for k in range(6):
        smooth = 120 + 60 * np.sin(xx / (6 + k)) * np.cos(yy / 9)
        image = np.clip(smooth + rng.normal(0, 12, smooth.shape), 0, 255).astype(np.uint8)
        if k % 2:
            image = np.stack([image, image[::-1], np.roll(image, 5, axis=1)], axis=-1)
        paths.append(folder / f"photo{k}.png")
        write_image(paths[-1], image)
    mask = np.zeros((64, 80), np.uint8)
    mask[30:33, 5:70] = 255
    mask[10:40, 50:52] = 255
    write_image(folder / "scratch.png", mask)
    return paths, folder / "scratch.png"


@pytest.fixture(scope="module")
def serial_inpainted(photos):
    """clpde.inpaint on each photo, called directly (max_steps=300)."""
    paths, scratch = photos
    mask = read_image(scratch) > 0
    return {
        p.name: clpde.inpaint(
            read_image(p), mask, max_steps=300, channel_axis=-1 if read_image(p).ndim == 3 else None
        )
        for p in paths
    }


def _serial_cli(argv):
    assert main(argv) == 0


def test_plan_workers_fills_the_cores():
    n = os.cpu_count()
    workers, threads = plan_workers()
    assert workers * threads <= n and workers * threads >= n - workers + 1
    assert plan_workers(workers=1) == (1, max(1, n // 1))
    assert plan_workers(threads=1)[0] == n
    with pytest.raises(clpde.InputError, match="--workers"):
        plan_workers(workers=0)


def _page_faults_of_temporaries() -> int:
    """Minor page faults while 20 float32 512x512 RGB images (3 MiB) are made and dropped
    after one warm-up: a few when malloc reuses its heap, about 15 000 when each is mmapped
    anew. (Under 4 MiB, where NumPy would ask for huge pages, which fault once per 2 MiB.)"""
    import resource

    import numpy as np

    np.ones((512, 512, 3), np.float32).sum()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(20):
        np.ones((512, 512, 3), np.float32).sum()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


def test_workers_reuse_memory_and_run_no_profiler(client):
    """Dask's nanny sets MALLOC_TRIM_THRESHOLD_, which made every image-sized temporary a
    fresh mmap (13 000 page faults per 512x512 inpainting, docs/batch.md); clpde's workers
    go without it and without the dashboard's profiler."""
    assert set(client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_")).values()) == {None}
    assert all(n < 2000 for n in client.run(_page_faults_of_temporaries).values())
    profiling = client.run(lambda dask_worker: "profile" in dask_worker.periodic_callbacks)
    assert not any(profiling.values())


def test_the_preload_fixes_malloc_under_dasks_environment():
    """A worker of a cluster started by hand has the nanny's MALLOC_TRIM_THRESHOLD_; the
    preload's malloc settings (clpde.scale.cluster._malloc_for_arrays) undo its effect."""
    import inspect
    import subprocess
    import sys

    measure = inspect.getsource(_page_faults_of_temporaries)
    env = {**os.environ, "MALLOC_TRIM_THRESHOLD_": "65536"}
    faults = {}
    for fix in ("", "from clpde.scale.cluster import _malloc_for_arrays\n_malloc_for_arrays()\n"):
        code = measure + fix + "print(_page_faults_of_temporaries())\n"
        run = subprocess.run(
            [sys.executable, "-c", code],
            env=env,
            capture_output=True,
            text=True,
            check=True,
            timeout=120,
        )
        faults[bool(fix)] = int(run.stdout.split()[-1])
    assert faults[False] > 8000 and faults[True] < 2000, faults


def test_batch_equals_serial_calls(client, photos, serial_inpainted, tmp_path):
    paths, scratch = photos
    out = tmp_path / "diffuse"
    result = batch("diffuse", paths, out, client=client, flow="tv", steps=30)
    assert [r.status for r in result] == ["done"] * 6 and result.ok
    for p in paths:
        image = read_image(p)
        axis = -1 if image.ndim == 3 else None
        serial = clpde.diffuse(image, "tv", steps=30, channel_axis=axis)
        assert np.array_equal(read_image(out / p.name), serial), p.name
    # The work was spread over both workers.
    assert len({r.worker for r in result}) == 2

    out = tmp_path / "inpaint"
    result = batch("inpaint", paths, out, mask=scratch, client=client, max_steps=300)
    assert result.ok, result.failed
    for p in paths:
        assert np.array_equal(read_image(out / p.name), serial_inpainted[p.name]), p.name

    out = tmp_path / "denoise"
    result = batch("denoise", paths[:2], out, client=client, weight=0.1)
    assert result.ok
    for p in paths[:2]:
        image = read_image(p)
        axis = -1 if image.ndim == 3 else None
        assert np.array_equal(
            read_image(out / p.name), clpde.denoise_tv(image, weight=0.1, channel_axis=axis)
        )


def test_track_and_surface_batches_equal_serial_runs(client, tmp_path):
    sequences = []
    yy, xx = np.mgrid[0:40, 0:48]
    for s in range(2):
        folder = tmp_path / f"seq{s}"
        folder.mkdir()
        for t in range(4):
            disc = (yy - 20) ** 2 + (xx - 15 - 3 * t - 2 * s) ** 2 < 64
            write_image(folder / f"f{t}.png", np.where(disc, 200, 40).astype(np.uint8))
        sequences.append(folder)
    init = tmp_path / "init.png"
    write_image(init, (((yy - 20) ** 2 + (xx - 15) ** 2 < 64) * 255).astype(np.uint8))
    result = batch(
        "track",
        sequences,
        tmp_path / "tracks",
        mask=init,
        client=client,
        gif=False,
        max_iterations=10,
    )
    assert result.ok, result.failed
    _serial_cli(
        [
            "track",
            str(sequences[1]),
            "--init",
            str(init),
            "-o",
            str(tmp_path / "one"),
            "--no-gif",
            "--max-iterations",
            "10",
        ]
    )
    for name in ("mask_0003.png", "contours.json"):
        assert (tmp_path / "tracks" / "seq1" / name).read_bytes() == (
            tmp_path / "one" / name
        ).read_bytes()

    result = batch(
        "surface",
        ["sphere"],
        tmp_path / "surfaces",
        flow="heat",
        client=client,
        resolution=16,
        size=32,
    )
    assert result.ok, result.failed
    _serial_cli(
        [
            "surface",
            "heat",
            "sphere",
            "-o",
            str(tmp_path / "alone"),
            "--resolution",
            "16",
            "--size",
            "32",
        ]
    )
    for name in ("after.png", "result.ply"):
        assert (tmp_path / "surfaces" / "sphere" / name).read_bytes() == (
            tmp_path / "alone" / name
        ).read_bytes()
    assert not list((tmp_path / "surfaces").glob(".*.part"))


def test_rerun_skips_complete_outputs_and_redoes_changed_ones(client, photos, tmp_path):
    paths, _ = photos
    inputs = tmp_path / "in"
    inputs.mkdir()
    copies = []
    for p in paths[:3]:
        copies.append(inputs / p.name)
        copies[-1].write_bytes(p.read_bytes())
    out = tmp_path / "out"
    first = batch("diffuse", copies, out, client=client, steps=20)
    assert len(first.done) == 3 and (out / MANIFEST).is_file()
    stamps = {p.name: (out / p.name).stat().st_mtime_ns for p in copies}
    again = batch("diffuse", copies, out, client=client, steps=20)
    assert [r.status for r in again] == ["skipped"] * 3
    assert all(r.worker is None for r in again)  # nothing was sent to a worker
    assert {p.name: (out / p.name).stat().st_mtime_ns for p in copies} == stamps
    # A changed input, a damaged output and other options are redone; the rest is kept.
    write_image(copies[0], np.zeros((64, 80), np.uint8))
    (out / copies[1].name).write_bytes(b"truncated")
    third = batch("diffuse", copies, out, client=client, steps=20)
    assert [r.status for r in third] == ["done", "done", "skipped"]
    assert np.array_equal(
        read_image(out / copies[1].name),
        clpde.diffuse(
            read_image(copies[1]),
            steps=20,
            channel_axis=-1 if read_image(copies[1]).ndim == 3 else None,
        ),
    )
    assert [r.status for r in batch("diffuse", copies, out, client=client, steps=21)] == [
        "done"
    ] * 3


def test_failures_are_reported_by_name_and_do_not_stop_the_others(client, photos, tmp_path):
    paths, scratch = photos
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not a png")
    small = tmp_path / "small.png"
    write_image(small, np.zeros((20, 20), np.uint8))
    masks = tmp_path / "masks"
    masks.mkdir()
    for p in (paths[0], small):
        (masks / p.name).write_bytes(scratch.read_bytes())  # 64x80: wrong for small.png
    out = tmp_path / "out"
    result = batch(
        "inpaint", [paths[0], bad, small, paths[2]], out, masks=masks, client=client, max_steps=50
    )
    status = {Path(r.input).name: r for r in result}
    assert status[paths[0].name].status == "done"
    assert status["broken.png"].status == "failed" and "broken.png" in status["broken.png"].error
    assert status["small.png"].status == "failed" and "same size" in status["small.png"].error
    assert status[paths[2].name].status == "failed" and "no mask" in status[paths[2].name].error
    assert sorted(p.name for p in out.iterdir()) == sorted([MANIFEST, paths[0].name])


def test_cli_exit_status_and_report(client, photos, tmp_path, capsys):
    paths, scratch = photos
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not a png")
    out = tmp_path / "out"
    address = client.scheduler.address
    status = main(
        [
            "batch",
            "diffuse",
            str(paths[0]),
            str(bad),
            "-o",
            str(out),
            "--scheduler",
            address,
            "--steps",
            "5",
            "--flow",
            "heat",
        ]
    )
    err = capsys.readouterr().err
    assert status == 1 and "broken.png" in err and "1 done" in err and "1 failed" in err
    assert (out / paths[0].name).is_file()
    # Options of the command are checked before any work, by the command's own parser.
    assert main(["batch", "diffuse", str(paths[0]), "-o", str(out), "--stepz", "5"]) == 2
    assert "--stepz" in capsys.readouterr().err
    assert main(["batch", "inpaint", str(paths[0]), "-o", str(out), "--scheduler", address]) == 2
    assert "--mask" in capsys.readouterr().err


def test_a_killed_worker_does_not_lose_the_batch(client, photos, serial_inpainted, tmp_path):
    paths, scratch = photos
    out = tmp_path / "out"
    # Stray temporaries of an earlier, killed run are cleared first.
    out.mkdir()
    (out / f".{paths[0].name}.abc123.part").write_bytes(b"half")
    pids = client.run(os.getpid)
    run = batch("inpaint", paths, out, mask=scratch, client=client, futures=True, max_steps=300)
    assert not list(out.glob(".*.part"))
    victim = None
    deadline = time.monotonic() + 60
    while victim is None and time.monotonic() < deadline:
        busy = [w for w, keys in client.processing().items() if keys]
        if busy and any(f.status == "finished" for _, f in run.futures):
            victim = busy[0]
        time.sleep(0.02)
    assert victim is not None
    os.kill(pids[victim], signal.SIGKILL)
    result = run.results()
    assert result.ok, result.failed
    assert len(result.done) == 6
    assert set(client.run(os.getpid).values()) != set(pids.values())  # the nanny restarted it
    for p in paths:
        assert np.array_equal(read_image(out / p.name), serial_inpainted[p.name]), p.name
    assert not list(out.glob(".*.part"))
    client.wait_for_workers(2, timeout=60)


def test_tiled_diffuse_is_bitwise_equal_to_untiled(tmp_path):
    from clpde.planar import tiled

    image = np.random.default_rng(3).integers(0, 256, (3000, 3000), dtype=np.uint8)
    whole = clpde.diffuse(image, "heat", steps=8)
    tiles = tiled.diffuse(image, "heat", steps=8, chunks=256)  # 12 x 12 tiles
    assert np.array_equal(whole, tiles)
    assert not np.array_equal(whole, image)


@pytest.mark.parametrize("flow", ["perona-malik", "tv", "curvature"])
def test_tiled_flows_on_float_colour_images_are_bitwise_equal(flow):
    from clpde.planar import tiled

    image = np.random.default_rng(4).random((150, 130, 3)).astype(np.float32) * 5 - 1
    whole = clpde.diffuse(image, flow, steps=9, channel_axis=-1)
    assert np.array_equal(whole, tiled.diffuse(image, flow, steps=9, channel_axis=-1, chunks=40))


def test_tiled_denoise_with_fixed_iterations_is_bitwise_equal():
    from clpde.planar import tiled

    image = (np.random.default_rng(5).random((140, 150)) * 65535).astype(np.uint16)
    whole = clpde.denoise_tv(image, weight=0.2, max_steps=11, tol=1e-300)
    assert np.array_equal(whole, tiled.denoise_tv(image, 0.2, 11, chunks=48))


def test_batch_tile_option_gives_the_untiled_result(client, photos, tmp_path):
    paths, _ = photos
    out = tmp_path / "tiled"
    result = batch("diffuse", paths[:2], out, client=client, tile=True, steps=8)
    assert result.ok, result.failed
    for p in paths[:2]:
        image = read_image(p)
        axis = -1 if image.ndim == 3 else None
        assert np.array_equal(
            read_image(out / p.name), clpde.diffuse(image, steps=8, channel_axis=axis)
        )
    with pytest.raises(clpde.InputError, match="--tile"):
        batch("inpaint", paths[:1], out, client=client, mask=paths[0], tile=True)


def test_ctrl_c_leaves_complete_outputs_only(client, tmp_path):
    import subprocess
    import sys

    yy, xx = np.mgrid[0:96, 0:96]
    inputs = []
    for k in range(8):
        inputs.append(tmp_path / f"b{k}.png")
        write_image(inputs[-1], (120 + 60 * np.sin(xx / (4 + k)) * np.cos(yy / 7)).astype(np.uint8))
    mask = tmp_path / "mask.png"
    write_image(mask, ((np.abs(yy - 48) < 3) * 255).astype(np.uint8))
    out = tmp_path / "out"
    slow = ["--max-steps", "4000", "--tol", "0", "--mean-tol", "0"]
    command = [
        sys.executable,
        "-m",
        "clpde",
        "batch",
        "inpaint",
        *map(str, inputs),
        "-o",
        str(out),
        "--mask",
        str(mask),
        "--workers",
        "1",
        "--threads",
        "1",
        *slow,
    ]
    # A terminal's Ctrl-C: SIGINT to the whole process group, client and workers alike.
    proc = subprocess.Popen(
        command,
        start_new_session=True,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 90
    while not (out / MANIFEST).exists() and time.monotonic() < deadline:  # one recorded
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "complete outputs only" in err
    written = sorted(p.name for p in out.iterdir())
    assert not [n for n in written if n.startswith(".")]  # no temporary files
    images = [n for n in written if n.endswith(".png")]
    assert 1 <= len(images) < 8
    for name in images:
        read_image(out / name)  # complete files
    # The rerun keeps what was recorded complete and does the rest (an output written but
    # not yet recorded when the batch stopped is redone).
    rerun = batch(
        "inpaint", inputs, out, mask=mask, client=client, max_steps=4000, tol=0, mean_tol=0
    )
    assert rerun.ok and len(rerun.done) + len(rerun.skipped) == 8 and rerun.skipped


def test_time_is_the_calls_wall_time_and_a_complete_rerun_starts_no_cluster(photos, tmp_path):
    import json

    paths, _ = photos
    out = tmp_path / "out"
    start = time.perf_counter()
    first = batch("denoise", paths[:2], out, workers=1, threads=1, max_steps=20)
    wall = time.perf_counter() - start
    assert first.ok and first.workers == 1
    assert first.seconds >= 0.9 * wall  # the cluster's start and stop included
    options = json.loads((out / MANIFEST).read_text())["outputs"][paths[0].name]["options"]
    assert options["method"] == "primal-dual" and options["max_steps"] == 20.0
    assert options["sigma"] is None  # JSON values, not Python's text ('primal-dual', None)
    again = batch("denoise", paths[:2], out, workers=1, threads=1, max_steps=20)
    assert [r.status for r in again] == ["skipped"] * 2
    assert again.workers == 0  # every output was checked before any cluster was started


def test_an_interrupted_batch_leaves_no_empty_folder(client, photos, tmp_path, monkeypatch):
    from clpde.scale import batch as batch_module

    def interrupted(self, progress=None):  # Ctrl-C before any output is complete
        raise KeyboardInterrupt

    monkeypatch.setattr(batch_module.BatchFutures, "results", interrupted)
    paths, _ = photos
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        batch("diffuse", paths[:2], out, client=client, steps=5)
    assert not out.exists()
    out.mkdir()  # a folder that was there before stays
    with pytest.raises(KeyboardInterrupt):
        batch("diffuse", paths[:2], out, client=client, steps=5)
    assert out.is_dir()


def test_the_command_reports_the_time_the_user_waited(client, photos, tmp_path):
    """The summary's time is the command's own, from the process's start (Python's start
    and imports included), not the batch call's."""
    import re
    import subprocess
    import sys

    paths, _ = photos
    out = tmp_path / "out"
    assert batch("diffuse", paths[:2], out, client=client, steps=5, flow="heat").ok
    start = time.perf_counter()
    run = subprocess.run(
        [sys.executable, "-m", "clpde", "batch", "diffuse", *map(str, paths[:2]), "-o", str(out)]
        + ["--steps", "5", "--flow", "heat"],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    wall = time.perf_counter() - start
    assert "0 done, 2 skipped" in run.stderr and "no worker needed" in run.stderr
    reported = float(re.search(r"in ([\d.]+) s", run.stderr).group(1))
    # the report covers the whole command, not a part of it (it once said 17.5 s of 47 s);
    # loose bounds, since the interpreter's start is outside it and CI machines are loaded
    assert 0.5 * wall - 0.5 <= reported <= wall + 0.2
