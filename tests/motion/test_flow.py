"""Optical-flow kernels against their numpy references, and the flow's mathematics."""

import numpy as np
import pyopencl.array as cla
import pytest
from scipy.ndimage import gaussian_filter, shift

from clpde import InputError
from clpde.motion import FlowParams, FlowSolver, optical_flow, warp
from tests.reference import motion as ref


def _dev(q, a):
    return cla.to_device(q, np.ascontiguousarray(a, np.float32))


@pytest.fixture
def solver(runtime):
    return FlowSolver(runtime)


def _launch(solver, ny, nx):
    return solver.rt.items(nx, ny)


def test_down_and_up_match_reference(solver, rng):
    q = solver.rt.queue
    ny, nx = 23, 17
    src, w = rng.random((ny, nx)), (rng.random((ny, nx)) > 0.3).astype(float)
    w[:6, :6] = 0  # a whole footprint damaged: the plain average stands in
    ny2, nx2 = 12, 9
    d, dw = cla.empty(q, (ny2, nx2), np.float32), cla.empty(q, (ny2, nx2), np.float32)
    g, loc = _launch(solver, ny2, nx2)
    solver.k_down(
        q,
        g,
        loc,
        _dev(q, src).data,
        _dev(q, w).data,
        d.data,
        dw.data,
        np.int32(nx),
        np.int32(ny),
        np.int32(nx2),
        np.int32(ny2),
    )
    rd, rw = ref.down(src, w)
    np.testing.assert_allclose(d.get(), rd, atol=1e-5)
    np.testing.assert_allclose(dw.get(), rw, atol=1e-6)
    u2, v2 = rng.normal(size=(ny2, nx2)), rng.normal(size=(ny2, nx2))
    u, v = cla.empty(q, (ny, nx), np.float32), cla.empty(q, (ny, nx), np.float32)
    g, loc = _launch(solver, ny, nx)
    solver.k_up(
        q,
        g,
        loc,
        _dev(q, u2).data,
        _dev(q, v2).data,
        u.data,
        v.data,
        np.int32(nx2),
        np.int32(ny2),
        np.int32(nx),
        np.int32(ny),
    )
    ru, rv = ref.up(u2, v2, ny, nx)
    np.testing.assert_allclose(u.get(), ru, atol=1e-5)
    np.testing.assert_allclose(v.get(), rv, atol=1e-5)


def test_linearise_sor_median_warp_match_reference(solver, rng):
    q = solver.rt.queue
    ny, nx = 19, 26
    I0, I1 = gaussian_filter(rng.random((ny, nx)), 1), gaussian_filter(rng.random((ny, nx)), 1)
    w0, w1 = rng.random((ny, nx)), rng.random((ny, nx))
    u, v = 3 * rng.normal(size=(ny, nx)), 3 * rng.normal(size=(ny, nx))
    size = (np.int32(nx), np.int32(ny))
    g, loc = _launch(solver, ny, nx)
    bufs = [cla.empty(q, (ny, nx), np.float32) for _ in range(4)]
    solver.k_lin(
        q,
        g,
        loc,
        *(_dev(q, a).data for a in (I0, I1, w0, w1, u, v)),
        *(b.data for b in bufs),
        *size,
    )
    want = ref.linearise(I0, I1, w0, w1, u, v)
    for got, exp in zip(bufs, want, strict=True):
        np.testing.assert_allclose(got.get(), exp, atol=2e-5)
    Ix, Iy, It, wd = want
    du0, dv0 = 0.1 * rng.normal(size=(ny, nx)), 0.1 * rng.normal(size=(ny, nx))
    du, dv = _dev(q, du0), _dev(q, dv0)
    dIx, dIy, dIt, dwd, du_, dv_ = (_dev(q, a) for a in (Ix, Iy, It, wd, u, v))
    rdu, rdv = du0, dv0
    for parity in (0, 1, 0, 1):
        solver.k_sor(
            q,
            g,
            loc,
            dIx.data,
            dIy.data,
            dIt.data,
            dwd.data,
            du_.data,
            dv_.data,
            du.data,
            dv.data,
            np.float32(0.03**2),
            np.float32(0.01),
            np.float32(1.8),
            np.int32(parity),
            *size,
        )
        rdu, rdv = ref.sor_half(Ix, Iy, It, wd, u, v, rdu, rdv, 0.03**2, 0.01, 1.8, parity)
    np.testing.assert_allclose(du.get(), rdu, atol=1e-4)
    np.testing.assert_allclose(dv.get(), rdv, atol=1e-4)
    out = cla.empty(q, (ny, nx), np.float32)
    solver.k_median(q, g, loc, du_.data, out.data, *size)
    np.testing.assert_allclose(out.get(), ref.median3(u), atol=1e-6)
    src = rng.random((3, ny, nx))
    np.testing.assert_allclose(
        solver.warp(_dev(q, src), du_, dv_).get(), ref.warp(src, u, v), atol=1e-5
    )


def test_whole_solver_matches_reference(solver, rng):
    ny, nx = 22, 27
    I0 = gaussian_filter(rng.random((ny, nx)), 1.5)
    I1 = shift(I0, (0.6, -0.8), mode="nearest")
    w0 = np.ones((ny, nx))
    w1 = np.ones((ny, nx))
    w1[5:9, 5:12] = 0
    q = solver.rt.queue
    params = FlowParams(warps=2, iterations=5)
    s = FlowSolver(solver.rt, params)
    u, v = s.flow(*(_dev(q, a) for a in (I0, I1, w0, w1)), levels=2)
    ru, rv = ref.optical_flow(I0, I1, w0, w1, 2, warps=2, iterations=5)
    np.testing.assert_allclose(u.get(), ru, atol=2e-3)
    np.testing.assert_allclose(v.get(), rv, atol=2e-3)


@pytest.mark.parametrize("d", [(1.3, -2.6), (-4.4, 3.7)])
def test_translation_recovered_to_subpixel(runtime, rng, d):
    """A textured image shifted by d: frame1[y + dy, x + dx] = frame0[y, x]."""
    a = gaussian_filter(rng.random((96, 96)), 1.5)
    b = shift(a, d, mode="nearest", order=3)
    flow = optical_flow(a, b, device=runtime)
    inner = flow[20:-20, 20:-20]
    err = np.hypot(inner[..., 0] - d[1], inner[..., 1] - d[0])
    assert np.median(err) < 0.05
    assert np.percentile(err, 95) < 0.25


def test_masked_damage_does_not_drag_the_flow(runtime, rng):
    a = gaussian_filter(rng.random((96, 96)), 1.5)
    b = shift(a, (2.0, 1.0), mode="nearest", order=3)
    b_dirty = b.copy()
    b_dirty[40:56, 30:50] = 0.0  # a dark blotch in frame1 only
    m1 = np.zeros(b.shape, bool)
    m1[40:56, 30:50] = True
    flow = optical_flow(a, b_dirty, mask1=m1, device=runtime)
    inner = flow[30:66, 20:60]  # around and over the blotch (in frame0's coordinates)
    assert np.abs(inner[..., 0] - 1.0).max() < 0.3
    assert np.abs(inner[..., 1] - 2.0).max() < 0.3


def test_warp_aligns_and_keeps_channels(runtime, rng):
    a = gaussian_filter(rng.random((64, 64, 3)), (1.5, 1.5, 0))
    b = shift(a, (1.0, -2.0, 0), mode="nearest", order=1)
    flow = np.zeros((64, 64, 2), np.float32)
    flow[..., 0], flow[..., 1] = -2.0, 1.0
    back = warp(b, flow, channel_axis=-1, device=runtime)
    assert back.shape == a.shape
    np.testing.assert_allclose(back[8:-8, 8:-8], a[8:-8, 8:-8], atol=1e-5)


def test_bad_input(runtime):
    a = np.zeros((16, 16))
    with pytest.raises(InputError, match="same size"):
        optical_flow(a, np.zeros((16, 17)))
    with pytest.raises(InputError, match="mask1"):
        optical_flow(a, a, mask1=np.zeros((8, 8), bool))
    with pytest.raises(InputError, match="flow has shape"):
        warp(a, np.zeros((16, 16, 3)))
