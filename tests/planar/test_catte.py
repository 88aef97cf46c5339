"""Regularised Perona-Malik (Catte et al.): kernels against their numpy references, and the
flow against its maths."""

import numpy as np
import pytest

import clpde
from clpde.fields import Field, Grid
from clpde.planar.flows import PlanarFlow, gaussian_weights
from tests.reference import planar as ref


@pytest.mark.parametrize("presmooth,ny,nx", [(1.0, 9, 14), (2.5, 20, 6), (0.0, 5, 5)])
def test_gaussian_passes_match_reference(runtime, rng, presmooth, ny, nx):
    nc = 2
    grid = Grid(runtime, nx, ny, nc)
    u = rng.random((nc, ny, nx))
    w = gaussian_weights(presmooth)
    import pyopencl.array as cla

    wd = cla.to_device(runtime.queue, w.astype(np.float32))
    src, tmp, out = Field.from_host(grid, u), Field.empty(grid), Field.empty(grid)
    grid.launch(
        grid.kernel("planar/catte.cl", "catte_gauss_rows"),
        src.data.data,
        tmp.data.data,
        wd.data,
        np.int32(len(w) - 1),
    )
    grid.launch(
        grid.kernel("planar/catte.cl", "catte_gauss_cols"),
        tmp.data.data,
        out.data.data,
        wd.data,
        np.int32(len(w) - 1),
    )
    np.testing.assert_allclose(out.to_host(), ref.gauss_smooth(u, w), atol=2e-6)
    # the ghosts the step reads are the mirrored interior
    padded = out.data.get()
    np.testing.assert_allclose(padded[:, 1:-1, 0], padded[:, 1:-1, 1])


@pytest.mark.parametrize("edge", ["exp", "rational"])
def test_catte_step_matches_reference(runtime, rng, edge):
    nc, ny, nx = 2, 11, 13
    grid = Grid(runtime, nx, ny, nc)
    u = rng.random((nc, ny, nx))
    us = ref.gauss_smooth(u, gaussian_weights(1.2))
    cur, smooth, nxt = Field.from_host(grid, u), Field.from_host(grid, us), Field.empty(grid)
    kappa, dt = 0.1, 0.2
    k = grid.kernel("planar/catte.cl", "catte_perona_malik_step", EDGE_STOP=int(edge == "rational"))
    grid.launch(
        k, cur.data.data, smooth.data.data, nxt.data.data, np.float32(dt), np.float32(1 / kappa**2)
    )
    want = ref.perona_malik_catte_step(ref.pad_neumann(u), ref.pad_neumann(us), dt, kappa, edge)
    np.testing.assert_allclose(nxt.to_host(), want, atol=3e-6)


def test_gaussian_weights_sum_to_one_and_vanishing_scale_is_identity():
    for s in (0.3, 1.0, 4.0):
        w = gaussian_weights(s)
        assert abs(w[0] + 2 * w[1:].sum() - 1) < 1e-12 and len(w) == int(np.ceil(3 * s)) + 1
    assert list(gaussian_weights(0.0)) == [1.0]
    with pytest.raises(clpde.InputError, match="presmooth"):
        gaussian_weights(-1.0)


@pytest.mark.parametrize("edge", ["exp", "rational"])
def test_vanishing_presmooth_is_plain_perona_malik(rng, edge):
    image = rng.random((24, 30))
    plain = clpde.diffuse(image, "perona-malik", steps=25, kappa=0.1, edge=edge)
    catte = clpde.diffuse(image, "perona-malik", steps=25, kappa=0.1, edge=edge, presmooth=0)
    np.testing.assert_array_equal(catte, plain)
    # and a small scale is close to it (the smoothed copy tends to u)
    near = clpde.diffuse(image, "perona-malik", steps=25, kappa=0.1, edge=edge, presmooth=0.2)
    assert np.abs(near - plain).max() < 0.02


def test_whole_run_matches_reference_iteration(rng):
    image = rng.random((16, 19))
    image.flat[0], image.flat[1] = 0.0, 1.0
    flow = PlanarFlow(image, "perona-malik", kappa=0.08, presmooth=1.5, dtype=np.float64)
    flow.run(12)
    u = image[None].copy()
    w = gaussian_weights(1.5)
    for _ in range(12):
        us = ref.gauss_smooth(u, w)
        u = ref.perona_malik_catte_step(ref.pad_neumann(u), ref.pad_neumann(us), flow.dt, 0.08)
    np.testing.assert_allclose(flow.result(), u[0], atol=1e-10)


def test_regularised_flow_removes_an_isolated_spike():
    """A single bright pixel's differences exceed kappa, so plain Perona-Malik barely
    diffuses it; with presmooth the smoothed gradient is small and it spreads."""
    image = np.full((31, 31), 0.2)
    image[15, 15] = 1.0
    plain = clpde.diffuse(image, "perona-malik", steps=100, kappa=0.1)
    catte = clpde.diffuse(image, "perona-malik", steps=100, kappa=0.1, presmooth=2.0)
    assert plain[15, 15] > 0.9 and catte[15, 15] < 0.5


def test_presmooth_belongs_to_perona_malik():
    with pytest.raises(clpde.InputError, match="presmooth applies to the perona-malik"):
        clpde.diffuse(np.zeros((8, 8)), "heat", steps=1, presmooth=1.0)


def test_diffuse_return_info():
    out, info = clpde.diffuse(np.zeros((8, 9), np.uint8), "tv", steps=7, return_info=True)
    assert out.dtype == np.uint8 and info.steps == 7 and info.flow == "tv"
    assert info.dt == pytest.approx(0.8 * info.stability_limit)
    assert info.time == pytest.approx(7 * info.dt)
