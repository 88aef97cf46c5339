"""Every launch names its work-group size, and a kernel keeps one size whatever the input.

PoCL compiles a kernel anew for each work-group size it meets, and when the host leaves the
size to the driver it picks one from the global size: every new image size or band length
then cost a build (0.75 s for the ghost fills of a new image size, measured). This runs the
public flows on two input sizes each and records every launch."""

from collections import defaultdict

import numpy as np
import pyopencl as cl
import pytest

import clpde
from clpde import runtime as runtime_module
from clpde.surface import ImplicitSurface


@pytest.fixture()
def launches(monkeypatch):
    seen = defaultdict(set)  # (program, kernel name) -> local sizes
    call = runtime_module.Kernel.__call__
    enqueue = cl.enqueue_nd_range_kernel

    def key(kernel):
        return kernel.program.int_ptr, kernel.function_name

    def recorded_call(self, queue, global_size, local_size, *args, **kwargs):
        seen[key(self.cl_kernel)].add(None if local_size is None else tuple(local_size))
        return call(self, queue, global_size, local_size, *args, **kwargs)

    def recorded_enqueue(queue, kernel, global_size, local_size, *args, **kwargs):
        seen[key(kernel)].add(None if local_size is None else tuple(local_size))
        return enqueue(queue, kernel, global_size, local_size, *args, **kwargs)

    monkeypatch.setattr(runtime_module.Kernel, "__call__", recorded_call)
    monkeypatch.setattr(cl, "enqueue_nd_range_kernel", recorded_enqueue)
    return seen


def _check(seen):
    assert seen, "no launch was recorded"
    named = {name: sizes for (_, name), sizes in seen.items()}
    left_to_driver = sorted(name for name, sizes in named.items() if None in sizes)
    assert not left_to_driver, f"launches without a work-group size: {left_to_driver}"
    varying = {name: sizes for (_, name), sizes in seen.items() if len(sizes) > 1}
    assert not varying, f"kernels launched with several work-group sizes: {varying}"


def _photo(n, rng):
    y, x = np.mgrid[:n, :n] / n
    return (0.5 + 0.3 * np.sin(9 * x) * np.cos(7 * y) + 0.05 * rng.random((n, n))).astype(
        np.float32
    )


def test_planar_and_inpainting(launches, rng):
    for n in (61, 80):
        image = _photo(n, rng)
        clpde.diffuse(image, "perona-malik", steps=3)
        clpde.denoise_tv(image)
        mask = np.zeros((n, n), bool)
        mask[n // 2, 5:-5] = True  # a scratch: the structure method
        mask[10:26, 10:26] = True  # a blob: the exemplar
        clpde.inpaint(image, mask)
        clpde.inpaint(image, mask, method="navier-stokes")
    _check(launches)


def test_surfaces_and_tracking(launches):
    for spacing in (0.2, 0.17):
        for storage in ("lists", "bricks"):
            surf = ImplicitSurface.sphere(spacing=spacing, storage=storage)
            x, y, z = surf.coordinates()
            u = np.broadcast_to(x + 0 * y + 0 * z, surf.shape)
            surf.heat(u, 0.01)
            surf.denoise_tv(u, sigma=0.1, t=0.002)
            surf.reaction_diffusion(2)
    for n in (40, 52):
        yy, xx = np.mgrid[:n, :n]
        frames = [
            ((xx - n / 2 - k) ** 2 + (yy - n / 2) ** 2 < (n / 5) ** 2).astype(np.float32)
            for k in range(2)
        ]
        for layout in ("lists", "bricks8x8"):
            clpde.track(frames, frames[0] > 0.5, max_iterations=5, storage=layout)
    for n in (32, 40):
        h = 2.0 / n
        ax = (np.arange(n) - n / 2 + 0.5) * h
        z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
        phi = np.sqrt(x**2 + y**2 + z**2) - 0.4
        for storage in ("lists", "bricks"):
            clpde.track_region(phi, z - 0.1, beta=0.5, t=0.01, spacing=h, saves=1, storage=storage)
    _check(launches)
