"""The inpainting kernels agree with their NumPy references (tests/reference/inpaint.py)."""

import numpy as np
import pytest

from clpde.inpainting.transport import LevelSolver
from clpde.inpainting.transport_params import InpaintParams
from clpde.runtime import get_runtime
from tests.reference import inpaint as ref
from tests.reference.planar import pad_neumann


def _inputs(kind, shape=(23, 31), nc=2, seed=0):
    rng = np.random.default_rng(seed)
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx]
    if kind == "random":
        data = rng.random((nc, ny, nx))
    else:  # smooth structure: a ramp, a disc edge and a sinusoid
        data = np.stack(
            [
                0.5 + 0.4 * np.tanh((np.hypot(x - 12.3, y - 9.1) - 6) / 1.5),
                0.5 + 0.3 * np.sin(0.4 * x + 0.25 * y) + 0.01 * x,
            ][:nc]
        )
    omega = np.zeros(shape, bool)
    omega[5:12, 7:20] = True
    omega[15:, 25:] = True  # touches two borders: exercises the ghost refills
    omega[0, 3] = True
    return data, omega


def _solver(data, omega, **params):
    p = InpaintParams(**params)
    return LevelSolver(get_runtime(), data, omega, p, np.float32)


@pytest.mark.parametrize("kind", ["random", "structured"])
@pytest.mark.parametrize(
    "scaling,rotation,stencil",
    [
        ("none", "ccw", "central"),
        ("quartic-root", "cw", "central"),
        ("none", "ccw", "isotropic"),
        ("quartic-root", "cw", "isotropic"),
    ],
)
def test_transport_step_matches_reference(kind, scaling, rotation, stencil):
    data, omega = _inputs(kind)
    solver = _solver(data, omega, scaling=scaling, rotation=rotation, dt=0.1, stencil=stencil)
    solver.transport_step()
    got = solver.result()
    rot = 1.0 if rotation == "ccw" else -1.0
    want = ref.transport_step(
        pad_neumann(data.astype(np.float32).astype(float)),
        omega,
        0.1,
        rot=rot,
        scaling=scaling,
        stencil=stencil,
    )
    np.testing.assert_allclose(got, want, atol=2e-5)
    assert np.array_equal(got[:, ~omega], data.astype(np.float32)[:, ~omega])
    assert np.abs(got - data).max() > 1e-3  # the step did something


@pytest.mark.parametrize("kind", ["random", "structured"])
def test_diffusion_step_matches_reference(kind):
    data, omega = _inputs(kind, seed=1)
    solver = _solver(data, omega, diffusion_dt=0.2, epsilon=3.0)
    solver.diffusion_step()
    got = solver.result()
    g = solver.weight.to_host()[0].astype(float)
    assert g[omega].min() == 1 and g.max() == 1 and (g == 0).any()
    want = ref.diffusion_step(pad_neumann(data.astype(np.float32).astype(float)), g, 0.2)
    np.testing.assert_allclose(got, want, atol=5e-5)
    assert np.array_equal(got[:, g == 0], data.astype(np.float32)[:, g == 0])


def test_fill_step_and_pair_consistency():
    data, omega = _inputs("structured", seed=2)
    solver = _solver(data, omega)
    solver.harmonic_fill(1)
    want = ref.fill_step(pad_neumann(data.astype(np.float32).astype(float)), omega)
    np.testing.assert_allclose(solver.result(), want, atol=1e-6)
    # After a full cycle both buffers of the pair agree everywhere off Omega.
    solver.cycle()
    a = solver.pair.cur.to_host()
    b = solver.pair.nxt.to_host()
    band = solver.weight.to_host()[0] > 0
    assert np.array_equal(a[:, ~omega & ~band], b[:, ~omega & ~band])
    assert np.array_equal(a[:, band], b[:, band])


def test_max_change_reduction():
    data, omega = _inputs("random", seed=3)
    solver = _solver(data, omega)
    solver.prev.assign(solver.pair.cur)
    solver.transport_step()
    diff = np.abs(solver.result() - solver.prev.to_host())
    assert solver.max_change() == pytest.approx(diff[:, omega].max(), rel=1e-6)


def test_mean_change_reduction():
    data, omega = _inputs("random", seed=4)
    solver = _solver(data, omega)
    solver.prev.assign(solver.pair.cur)
    solver.transport_step()
    diff = np.abs(solver.result() - solver.prev.to_host())
    assert solver.mean_change() == pytest.approx(diff[:, omega].mean(), rel=1e-4)
    assert solver.mean_change() < solver.max_change()
