"""Process pools and pickling: a forked child never hangs, spawn works, objects pickle by value.

OpenCL drivers do not survive fork() (PoCL's worker threads stay in the parent: a forked
child that enqueued anything waited forever). A child forked after its parent used OpenCL
gets a ClpdeError naming the 'spawn' start method; a child forked before starts afresh.
"""

import multiprocessing as mp
import operator
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import clpde
from clpde.regions.tracker import RegionTracker
from clpde.surface import ImplicitSurface

TIMEOUT = 120  # seconds: a hang fails the test instead of blocking the suite


def _script(body: str) -> subprocess.CompletedProcess:
    code = textwrap.dedent(body)
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=TIMEOUT
    )


def test_fork_never_hangs():
    """One script (interpreter start-up is most of the time): a fork pool made before the
    first clpde call gives the serial results; after it, workers and inherited objects
    raise the error naming 'spawn'; the parent itself is unaffected."""
    done = _script("""
    import multiprocessing as mp
    import os
    import numpy as np
    import clpde

    def work(seed):
        image = np.random.default_rng(seed).random((24, 24)).astype(np.float32)
        return clpde.diffuse(image, "heat", steps=5)

    if __name__ == "__main__":
        with mp.get_context("fork").Pool(2) as pool:  # before any OpenCL use
            forked = pool.map(work, range(3))
        print("BEFORE", all(np.array_equal(a, work(i)) for i, a in enumerate(forked)))
        with mp.get_context("fork").Pool(2) as pool:
            try:
                pool.map(work, range(2))
            except clpde.ClpdeError as exc:
                print("AFTER", exc)
        flow = clpde.PlanarFlow(np.eye(16, dtype=np.float32), "heat").run(2)
        pid = os.fork()
        if pid == 0:
            code = 3
            for action in (lambda: flow.run(1), flow.result, lambda: work(0)):
                try:
                    action()
                except clpde.ClpdeError as exc:
                    code -= "'spawn'" in str(exc)
            os._exit(code)
        _, status = os.waitpid(pid, 0)
        print("CHILD", os.waitstatus_to_exitcode(status))
        print("PARENT", np.array_equal(work(1), work(1)))
    """)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "BEFORE True" in out
    assert "AFTER this process was forked" in out and "'spawn'" in out
    assert "CHILD 0" in out and "PARENT True" in out


def _images(n):
    rng = np.random.default_rng(3)
    return [rng.random((20, 28)).astype(np.float32) for _ in range(n)]


def test_spawn_pool_gives_the_serial_results_and_carries_objects_by_value():
    images = _images(3)
    flow = clpde.PlanarFlow(images[0], "tv").run(4)
    ctx = mp.get_context("spawn")
    with ctx.Pool(2) as pool:
        spawned = pool.starmap(clpde.diffuse, [(im, "perona-malik", 6) for im in images])
        # the flow goes to a worker by value, takes 4 more steps there and comes back
        returned = pool.apply(operator.methodcaller("run", 4), (flow,))
    assert all(
        np.array_equal(a, clpde.diffuse(im, "perona-malik", 6))
        for a, im in zip(spawned, images, strict=False)
    )
    assert returned.steps_done == 8
    assert np.array_equal(returned.result(), flow.run(4).result())


def _round_trip(obj):
    return pickle.loads(pickle.dumps(obj))


def test_planar_flow_pickles_by_value_mid_run_for_each_flow():
    image = _images(1)[0]
    for name in clpde.FLOWS:
        params = (
            {"weight": np.linspace(0, 1, 28)[None].repeat(20, 0)} if name == "curvature" else {}
        )
        flow = clpde.PlanarFlow(image, name, **params).run(3)
        copy = _round_trip(flow)
        assert copy.runtime is flow.runtime  # same process: the same runtime
        assert np.array_equal(copy.result(), flow.result())
        assert np.array_equal(copy.run(3).result(), flow.run(3).result()), name
        assert copy.steps_done == flow.steps_done == 6


def test_surface_tracker_inpainting_and_region_tracker_pickle_by_value():
    surf = ImplicitSurface.sphere(1.0, 0.2)
    x, y, z = surf.closest_points_host()
    u = np.broadcast_to(x + y * z, surf.shape).copy()
    t = 3 * surf.stability_limit("heat")
    assert np.array_equal(_round_trip(surf).heat(u, t), surf.heat(u, t))

    yy, xx = np.mgrid[:32, :32]
    frames = np.stack(
        [((yy - 16) ** 2 + (xx - 12 - 2 * k) ** 2 < 36).astype(np.float32) for k in range(3)]
    )
    tracker = clpde.MorphingTracker(frames, frames[0] > 0, max_iterations=8)
    masks = [s.mask for s in _round_trip(tracker).iterate()]
    assert all(np.array_equal(a, s.mask) for a, s in zip(masks, tracker.iterate(), strict=False))

    image = _images(1)[0]
    mask = np.zeros(image.shape, bool)
    mask[6:14, 8:18] = True
    job = clpde.Inpainting(image, mask, max_steps=30)
    assert np.array_equal(_round_trip(job).run(), job.run())
    assert np.array_equal(_round_trip(job).result, job.result)

    h, n = 0.1, 36
    ax = (np.arange(n) - (n - 1) / 2) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = np.sqrt(x**2 + y**2 + z**2) - 0.7
    regions = RegionTracker(phi, (0.35 - z)[None], h, speed="constant", scale=-0.5 / h)
    regions.advance(0.05)
    copy = _round_trip(regions)
    regions.advance(0.1)
    copy.advance(0.1)
    assert copy.steps == regions.steps
    assert all(
        np.array_equal(a, b) for a, b in zip(copy.volumes(), regions.volumes(), strict=False)
    )


def test_device_objects_of_other_contexts_refuse_to_pickle():
    import pyopencl as cl

    ctx = cl.Context([clpde.get_runtime().device])
    with pytest.raises(pickle.PicklingError, match="clpde did not make"):
        pickle.dumps(cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 16))
