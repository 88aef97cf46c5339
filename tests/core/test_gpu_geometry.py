"""The GPU launch geometry, run on the CPU: every public flow gives the same result when the
runtime launches one work-item per cell (and per list entry, and per band cell as a run of
its own), as it does on GPUs, instead of a work-item per row or per chunk. CI has no GPU;
this keeps the GPU code paths (padded global sizes, bounds checks, single-cell runs) tested."""

import numpy as np
import pytest

import clpde
from clpde.runtime import Runtime
from clpde.surface import ImplicitSurface


@pytest.fixture(scope="module")
def gpu_like(runtime):
    rt = Runtime(runtime.index, runtime.platform, runtime.device)
    rt.is_cpu = False  # launch geometry only: the kernels and the device are the same
    return rt


def _pair(runtime, gpu_like, run):
    return run(runtime), run(gpu_like)


def test_launch_geometry_differs(runtime, gpu_like):
    assert runtime.grid_launch(100, 30)[2] == 100 and gpu_like.grid_launch(100, 30)[2] == 1
    assert runtime.list_launch(5000)[2] > 1 and gpu_like.list_launch(5000)[2] == 1


def test_planar_flows_and_denoising(runtime, gpu_like, rng):
    image = rng.random((37, 53)).astype(np.float32)
    for flow in ("heat", "perona-malik", "tv", "curvature"):
        cpu, gpu = _pair(
            runtime, gpu_like, lambda d, f=flow: clpde.diffuse(image, flow=f, steps=7, device=d)
        )
        np.testing.assert_allclose(gpu, cpu, atol=2e-6)
    cpu, gpu = _pair(runtime, gpu_like, lambda d: clpde.denoise_tv(image, sigma=0.1, device=d))
    np.testing.assert_allclose(gpu, cpu, atol=1e-4)


def test_inpainting(runtime, gpu_like, rng):
    y, x = np.mgrid[:48, :48]
    image = (0.5 + 0.4 * np.sin(x / 3.0)).astype(np.float32)
    mask = (np.abs(y - 24) < 3) & (np.abs(x - 20) < 12)
    cpu, gpu = _pair(
        runtime, gpu_like, lambda d: clpde.inpaint(image, mask, max_steps=60, device=d)
    )
    np.testing.assert_allclose(gpu, cpu, atol=1e-4)


def test_morphing_tracker(runtime, gpu_like):
    y, x = np.mgrid[:40, :40]
    frames = np.stack(
        [((x - 14 - 2 * t) ** 2 + (y - 20) ** 2 < 64).astype(np.float32) for t in range(3)]
    )
    cpu, gpu = _pair(runtime, gpu_like, lambda d: clpde.track(frames, frames[0] > 0.5, device=d))
    assert np.mean(cpu != gpu) < 0.002


def test_surface_flows(runtime, gpu_like):
    def run(device):
        s = ImplicitSurface.sphere(1.0, 0.2, device=device)
        u = s.field(lambda x, y, z: x * y + z)
        v = np.stack(
            [
                s.field(lambda x, y, z: x + 0.2),
                s.field(lambda x, y, z: y),
                s.field(lambda x, y, z: z),
            ]
        )
        v /= np.sqrt((v**2).sum(axis=0))
        return s.heat(u, 0.02), s.harmonic_map(v, 0.01), s.denoise_tv(u, sigma=0.05, t=0.01)

    for cpu, gpu in zip(*_pair(runtime, gpu_like, run), strict=False):
        np.testing.assert_allclose(gpu, cpu, atol=2e-5)


def test_surface_heat_on_bricks(runtime, gpu_like):
    """The band in dense bricks: a work-item walking whole bricks from a private tile (CPUs)
    against a work-group per brick sharing a local tile (GPUs)."""

    def run(device):
        s = ImplicitSurface.sphere(1.0, 0.2, device=device)
        s.storage = "bricks"
        u = s.field(lambda x, y, z: x * y + z)
        return s.heat(u, 0.02), s.heat(u, 0.02, weighted=True)

    for cpu, gpu in zip(*_pair(runtime, gpu_like, run), strict=False):
        np.testing.assert_allclose(gpu, cpu, atol=2e-6)


def test_mesh_to_signed_distance_with_a_hole(runtime, gpu_like):
    """Nearest-triangle refinement and the winding numbers (one point per work-item on GPUs)
    that close a hole several cells wide."""
    import trimesh

    ball = trimesh.creation.icosphere(2)
    ball.update_faces(np.arange(len(ball.faces)) != 7)
    with pytest.warns(UserWarning, match="watertight"):
        cpu, gpu = _pair(
            runtime, gpu_like, lambda d: ImplicitSurface.from_mesh(ball, resolution=40, device=d)
        )
    # the inside survived the hole: about the ball's volume
    assert (cpu.psi < 0).sum() * cpu.spacing**3 == pytest.approx(4 / 3 * np.pi, rel=0.05)
    np.testing.assert_allclose(gpu.psi, cpu.psi, atol=1e-6)


def test_region_tracking(runtime, gpu_like):
    h = 0.1
    ax = np.arange(-2.1, 2.1 + h / 2, h)
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = np.sqrt(x**2 + y**2 + z**2) - 0.9
    cap = 0.45 - z
    cpu, gpu = _pair(runtime, gpu_like, lambda d: track_cap(phi, cap, h, ax[0], d))
    assert gpu == pytest.approx(cpu, rel=1e-4)


def track_cap(phi, cap, h, origin, device):
    frames = clpde.track_region(
        phi, cap, beta="mean-curvature", t=0.02, spacing=h, origin=(origin,) * 3, device=device
    )
    return frames[-1].area(0), frames[-1].area()
