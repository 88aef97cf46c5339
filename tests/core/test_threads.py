"""Every public function gives, from 4 threads at once, bitwise the result of serial calls.

pyopencl's Kernel.__call__ sets the arguments and then enqueues; two threads sharing a
kernel object used to interleave the two and run a step with the other thread's buffers
(11 of 24 heat results differed before the runtime locked each launch).
"""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import clpde
from clpde.surface import ImplicitSurface

THREADS = 4


def _images(n, shape=(64, 64), seed=0):
    rng = np.random.default_rng(seed)
    return [rng.random(shape).astype(np.float32) for _ in range(n)]


def _same_in_threads(fn, inputs, repeats=1):
    """Number of thread results that differ bitwise from the serial ones."""
    serial = [fn(x) for x in inputs]
    bad = 0
    for _ in range(repeats):
        with ThreadPoolExecutor(THREADS) as pool:
            threaded = list(pool.map(fn, inputs))
        for a, b in zip(serial, threaded, strict=False):
            a, b = (a if isinstance(a, tuple) else (a,)), (b if isinstance(b, tuple) else (b,))
            bad += not all(np.array_equal(x, y, equal_nan=True) for x, y in zip(a, b, strict=False))
    return bad


@pytest.mark.parametrize("flow", clpde.FLOWS)
def test_diffuse_each_flow(flow):
    params = {"curvature": {"weight": np.ones((64, 64))}}.get(flow, {})
    assert (
        _same_in_threads(
            lambda im: clpde.diffuse(im, flow, steps=60, **params), _images(8), repeats=2
        )
        == 0
    )


def test_denoise_tv():
    assert (
        _same_in_threads(lambda im: clpde.denoise_tv(im, 0.1, max_steps=30), _images(8), repeats=2)
        == 0
    )


def test_inpaint():
    mask = np.zeros((40, 40), bool)
    mask[15:25, 12:28] = True
    assert (
        _same_in_threads(lambda im: clpde.inpaint(im, mask, max_steps=60), _images(6, (40, 40)))
        == 0
    )


def test_track():
    yy, xx = np.mgrid[:40, :40]

    def sequence(shift):
        return np.stack(
            [
                ((yy - 20) ** 2 + (xx - 14 - shift - 2 * k) ** 2 < 64).astype(np.float32)
                for k in range(3)
            ]
        )

    first = (yy - 20) ** 2 + (xx - 14) ** 2 < 64
    assert (
        _same_in_threads(
            lambda s: clpde.track(sequence(s), first, max_iterations=10), [0, 1, 0, 1, 0, 1]
        )
        == 0
    )


def test_surface_flows_share_one_surface():
    surf = ImplicitSurface.sphere(1.0, 0.2)
    x, y, z = surf.closest_points_host()
    data = [np.broadcast_to(np.cos(k * x) + y * z, surf.shape).copy() for k in range(4)]
    t = 4 * surf.stability_limit("heat")
    calls = [
        lambda u: surf.heat(u, t),
        lambda u: surf.tv(u, t),
        lambda u: surf.extend(u),
        lambda u: surf.heat(u, t, weighted=True),
    ]
    jobs = [(c, u) for c in calls for u in data[:2]]
    assert _same_in_threads(lambda job: job[0](job[1]), jobs) == 0


def test_track_region():
    h, n = 0.1, 36
    ax = (np.arange(n) - (n - 1) / 2) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = np.sqrt(x**2 + y**2 + z**2) - 0.7

    def run(beta):
        frame = clpde.track_region(
            phi, 0.35 - z, beta=beta, t=0.1, spacing=h, origin=(ax[0],) * 3, keep_volumes=True
        )[-1]
        return frame.phi, frame.phihat, np.asarray(frame.mesh.vertices)

    assert _same_in_threads(run, [0.5, 0.2, 0.5, 0.2]) == 0


def test_concurrent_first_use_builds_one_runtime_and_program():
    from clpde import runtime as rt

    runtime = rt.get_runtime()
    with ThreadPoolExecutor(THREADS) as pool:
        got = list(pool.map(lambda _: rt.get_runtime(), range(8)))
        kernels = list(
            pool.map(
                lambda _: runtime.kernel("planar/planar.cl", "planar_heat_step", HALO_TEST=3),
                range(8),
            )
        )
    assert all(r is runtime for r in got)
    assert all(k is kernels[0] for k in kernels)
