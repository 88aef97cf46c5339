"""Harmonic, biharmonic and Poisson fills by conjugate gradients on the device
(clpde.inpainting.poisson) against the sparse solves of the same equations and against
scikit-image's inpaint_biharmonic."""

import numpy as np
import pytest

from clpde.inpainting import poisson
from tests.reference import inpainting_methods as ref


def _case(seed=0, shape=(37, 45), nc=2):
    rng = np.random.default_rng(seed)
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx]
    data = np.stack([0.5 + 0.3 * np.sin(0.3 * x + 0.2 * y), rng.random(shape)][:nc])
    omega = np.zeros(shape, bool)
    omega[8:20, 10:25] = True
    omega[25:, 30:40] = True  # touches the bottom border: the Neumann form of L
    omega[3, 3:30] = True  # a thin scratch
    return data, omega


@pytest.mark.parametrize("kind", ["harmonic", "biharmonic"])
def test_fill_matches_sparse_solve(runtime, kind):
    data, omega = _case()
    got = poisson.fill(data, omega, runtime, kind, tol=1e-7, clip=False)
    want = ref.poisson_fill(data, omega, kind)
    np.testing.assert_allclose(got, want, atol=2e-5)
    assert np.array_equal(got[:, ~omega], data[:, ~omega])
    # the discrete equation holds in the hole
    L = ref.graph_laplacian
    op = (lambda u: L(u)) if kind == "harmonic" else (lambda u: L(L(u)))
    residual = max(np.abs(op(got[c])[omega]).max() for c in range(2))
    assert residual < 1e-4


def test_poisson_with_right_hand_side(runtime):
    data, omega = _case(seed=1, nc=1)
    rng = np.random.default_rng(3)
    f = 0.01 * rng.standard_normal(data.shape)
    solver = poisson.PoissonSolver(runtime, poisson.ring_mean_start(data, omega), omega, "harmonic")
    solver.f.set(f.astype(np.float32))
    solver.solve(tol=1e-7)
    got = solver.result()
    want = ref.poisson_fill(data, omega, "harmonic", f=f)
    np.testing.assert_allclose(got, want, atol=2e-5)
    assert np.abs(ref.graph_laplacian(got[0]) - f[0])[omega].max() < 1e-4


@pytest.mark.parametrize("kind", ["harmonic", "biharmonic"])
def test_linear_ramp_is_reproduced(runtime, kind):
    ny, nx = 40, 50
    y, x = np.mgrid[0:ny, 0:nx]
    ramp = (0.1 + 0.013 * x + 0.007 * y)[None]
    omega = np.zeros((ny, nx), bool)
    omega[5:30, 8:20] = True
    omega[20:24, 25:45] = True
    got = poisson.fill(ramp, omega, runtime, kind, tol=1e-7)
    assert np.abs(got - ramp).max() < 2e-6


def test_biharmonic_matches_scikit_image(runtime):
    from skimage import data as skdata
    from skimage.restoration import inpaint_biharmonic

    image = skdata.camera()[100:228, 150:278].astype(np.float64) / 255
    yy, xx = np.mgrid[0:128, 0:128]
    omega = np.hypot(yy - 40, xx - 50) < 9
    omega[90:93, 10:110] = True  # a scratch
    omega[60:75, 100:104] = True
    omega[20:40, 60:66] = True  # two holes one pixel apart
    omega[41:44, 58:70] = True
    got = poisson.fill(image[None], omega, runtime, "biharmonic", tol=1e-6)[0]
    want = inpaint_biharmonic(image, omega)
    assert np.abs(got - want)[omega].max() < 1e-4


def test_biharmonic_is_clipped_to_the_known_range(runtime):
    # like scikit-image's: unclipped, the fill overshoots across a sharp step
    step = np.zeros((1, 30, 30))
    step[0, :, 15:] = 1.0
    omega = np.zeros((30, 30), bool)
    omega[10:20, 8:22] = True
    raw = poisson.fill(step, omega, runtime, tol=1e-6, clip=False)
    assert raw.max() > 1.0005 and raw.min() < -0.0005
    clipped = poisson.fill(step, omega, runtime, tol=1e-6)
    assert clipped.min() == 0.0 and clipped.max() == 1.0
    np.testing.assert_allclose(clipped, np.clip(raw, 0, 1), atol=1e-6)


def test_solve_contract(runtime):
    data, omega = _case(seed=2, nc=3)
    data32 = data.astype(np.float32)
    before = data32.copy()
    out = poisson.solve(data32, omega, runtime, kind="harmonic")
    assert out.shape == data32.shape and out.dtype == np.float32
    assert np.array_equal(data32, before)
    assert np.array_equal(out[:, ~omega], data32[:, ~omega])
    assert not np.allclose(out[:, omega], data32[:, omega])
    assert np.array_equal(poisson.solve(data32, np.zeros_like(omega), runtime), data32)


@pytest.mark.parametrize("kind", ["harmonic", "biharmonic"])
def test_multigrid_preconditioned_cg(runtime, kind):
    # measured: harmonic 20 against 110 iterations, biharmonic 90 against 1060, both within
    # 7e-6 of the sparse solve
    data, omega = _case(seed=5, shape=(70, 80), nc=1)
    omega[25:65, 20:60] = True
    start = poisson.ring_mean_start(data, omega)
    iterations = {}
    for pre in (False, True):
        solver = poisson.PoissonSolver(runtime, start, omega, kind, precondition=pre)
        iterations[pre] = solver.solve(tol=1e-6, max_iter=20000)
        np.testing.assert_allclose(solver.result(), ref.poisson_fill(data, omega, kind), atol=2e-5)
    assert solver.mg.levels >= 4
    assert iterations[True] * 3 < iterations[False]
    assert poisson.thick(omega) and not poisson.thick(omega[:20])


@pytest.mark.parametrize("kind", ["harmonic", "biharmonic"])
def test_double_precision_equals_sparse_solve(runtime, kind):
    if not runtime.fp64:
        pytest.skip("the device has no double precision")
    # measured: 8e-14 (harmonic), 5e-12 (biharmonic); with the V-cycle 7e-16, 1e-13
    data, omega = _case(seed=6)
    want = ref.poisson_fill(data, omega, kind)
    for pre in (False, True):
        solver = poisson.PoissonSolver(
            runtime, poisson.ring_mean_start(data, omega), omega, kind, np.float64, precondition=pre
        )
        solver.solve(tol=1e-11, max_iter=20000)
        np.testing.assert_allclose(solver.result(), want, atol=1e-10)
