"""kernels/tracking/features.cl against its numpy references (tests/reference/levelset.py),
and the helpers of clpde.tracking.motion_filter."""

import itertools

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.fields import Field, Grid, compact
from clpde.tracking.motion_filter import MotionFilter, local_contrast, match_displacement
from tests.reference import levelset as ref


@pytest.mark.parametrize("radius", [1, 4])
def test_local_contrast_kernel_matches_reference_and_host_version(runtime, rng, radius):
    ny, nx = 19, 23
    img = rng.random((2, ny, nx))
    grid = Grid(runtime, nx, ny, 2, 2, np.dtype(np.float32))
    f, out = Field.from_host(grid, img), Field.empty(grid)
    grid.launch(
        grid.kernel("tracking/features.cl", "features_local_contrast"),
        f.data.data,
        out.data.data,
        np.int32(radius),
        grid.scalar(0.02**2),
        grid.scalar(0.25),
    )
    want = np.array([ref.local_contrast(c, radius, 0.02, 0.25) for c in img])
    np.testing.assert_allclose(out.to_host(), want, atol=2e-5, rtol=1e-4)
    np.testing.assert_allclose(local_contrast(img, radius), want, atol=1e-10)
    # Invariance: a positive affine change of the grey levels leaves it (nearly) unchanged.
    np.testing.assert_allclose(
        local_contrast(3 * img + 0.5, radius, eps=1e-6),
        local_contrast(img, radius, eps=1e-6),
        atol=1e-6,
    )


def _inputs(kind, rng, channels, ny=22, nx=27):
    y, x = np.mgrid[:ny, :nx]
    if kind == "random":
        u = rng.normal(size=(ny, nx)) * 2
        f1, f2 = rng.random((channels, ny, nx)), rng.random((channels, ny, nx))
    else:  # a distance-like level set, an edge that moved and changed its light
        r = np.hypot(x - 12.3, y - 9.6)
        u = r - 6
        f1 = np.array([1 / (1 + np.exp((r - 6) / 1.5)) * (1 + 0.2 * c) for c in range(channels)])
        r2 = np.hypot(x - 13.5, y - 10.1)
        f2 = np.array([0.6 / (1 + np.exp((r2 - 6.5) / 1.5)) + 0.1 * c for c in range(channels)])
    return u, f1, f2


def _run_morph_track(
    runtime, grid, band, fu, ff1, ff2, fprior, dt, eps_f, eps_u, near, lam, delta, channels, disc
):
    """One launch of morph_track over the cells where band > 0; returns (u_out, f1_out,
    stats, the launch's work-item count)."""
    padded_band = np.zeros(grid.padded_shape[1:], np.uint8)
    padded_band[2:-2, 2:-2] = band
    band_dev = cla.to_device(runtime.queue, padded_band)
    cells = compact(runtime, band_dev)
    assert cells.n == int((band > 0).sum()) > 0
    u_out, f1_out = fu.copy(), ff1.copy()
    (gsize,), _, _ = runtime.list_launch(cells.n)
    stats = cla.zeros(runtime.queue, 5 * gsize + 1, np.float32)
    kernel = grid.kernel(
        "tracking/features.cl",
        "features_morph_track",
        NCH=channels,
        DISC={"difference": 0, "ncc": 1, "huber": 2}[disc],
        WIN=3,
    )
    grid.launch_list(
        kernel,
        cells,
        fu.data.data,
        ff1.data.data,
        ff2.data.data,
        band_dev.data,
        fprior.data.data,
        u_out.data.data,
        f1_out.data.data,
        stats.data,
        grid.scalar(dt),
        grid.scalar(eps_f**2),
        grid.scalar(eps_u**2),
        grid.scalar(near),
        grid.scalar(lam),
        grid.scalar(delta),
        np.int32(grid.sx),
        np.int32(grid.plane),
    )
    return u_out, f1_out, stats.get(), gsize


@pytest.mark.parametrize("kind", ["random", "structured"])
@pytest.mark.parametrize(
    "disc,channels,lam",
    [
        ("difference", 1, 0.0),
        ("ncc", 1, 0.0),
        ("huber", 3, 0.0),
        ("ncc", 3, 0.1),
        ("difference", 2, 0.2),
    ],
)
def test_morph_track_matches_reference(runtime, rng, kind, disc, channels, lam):
    u, f1, f2 = _inputs(kind, rng, channels)
    ny, nx = u.shape
    grid = Grid(runtime, nx, ny, 1, 2, np.dtype(np.float32))
    cgrid = Grid(runtime, nx, ny, channels, 2, np.dtype(np.float32))
    fu = Field.from_host(grid, u[np.newaxis])
    prior_values = u + rng.normal(size=u.shape)
    fprior = Field.from_host(grid, prior_values[np.newaxis])
    ff1, ff2 = Field.from_host(cgrid, f1), Field.from_host(cgrid, f2)
    # Band cells 2 cells inside the interior, as in a LevelSet (its frozen margin), so an
    # NCC window of radius 3 stays inside the buffer.
    band = ref.mark_band(u, 3.0, margin=2)
    dt, eps_f, eps_u, near, delta = 0.3, 0.02, 1e-3, 1.0, 0.05
    u_out, f1_out, got, gsize = _run_morph_track(
        runtime,
        grid,
        band,
        fu,
        ff1,
        ff2,
        fprior,
        dt,
        eps_f,
        eps_u,
        near,
        lam,
        delta,
        channels,
        disc,
    )
    host = ff1.data.get().astype(np.float64), ff2.data.get().astype(np.float64)
    want_u, want_f1, want_maxima, want_mean, want_hit = ref.morph_track(
        fu.data.get()[0].astype(np.float64),
        *host,
        band,
        fprior.data.get()[0].astype(np.float64),
        dt,
        eps_f,
        eps_u,
        near,
        lam,
        delta,
        disc,
    )
    inside = band > 0
    np.testing.assert_allclose(u_out.to_host()[0][inside], want_u[inside], atol=3e-5, rtol=1e-4)
    np.testing.assert_allclose(
        f1_out.to_host()[:, inside], want_f1[:, inside], atol=3e-5, rtol=1e-4
    )
    maxima = [got[k * gsize : (k + 1) * gsize].max() for k in range(3)]
    np.testing.assert_allclose(maxima, want_maxima, rtol=2e-4, atol=1e-6)
    mean = got[3 * gsize : 4 * gsize].sum() / got[4 * gsize : 5 * gsize].sum()
    np.testing.assert_allclose(mean, want_mean, rtol=2e-4)
    assert bool(got[5 * gsize]) == want_hit


@pytest.mark.parametrize("kind", ["random", "structured"])
def test_morph_track_with_one_channel_is_the_thesis_step(runtime, rng, kind):
    # NCH 1, DISC 0 and lam = 0: the coupled step of thesis eqs. (2.3)-(2.6), against its
    # own reference (ref.morph_step, written from the equations, not from morph_track's
    # generalisation). Band cells reach the interior's edge: DISC 0 reads 2 cells out.
    u, f1, f2 = _inputs(kind, rng, 1, ny=21, nx=26)
    ny, nx = u.shape
    grid = Grid(runtime, nx, ny, 1, 2, np.dtype(np.float32))
    fu, ff1, ff2 = (Field.from_host(grid, a.reshape(1, ny, nx)) for a in (u, f1, f2))
    band = ref.mark_band(u, 3.0)
    dt, eps_f, eps_u, near = 0.4, 0.02, 1e-3, 1.0
    u_out, f1_out, got, gsize = _run_morph_track(
        runtime, grid, band, fu, ff1, ff2, fu, dt, eps_f, eps_u, near, 0.0, 0.0, 1, "difference"
    )
    padded = [a.data.get()[0].astype(np.float64) for a in (fu, ff1, ff2)]
    want_u, want_f1, want_maxima, want_hit = ref.morph_step(
        padded[0], padded[1], padded[2][2:-2, 2:-2], band, dt, eps_f, eps_u, near
    )
    np.testing.assert_allclose(u_out.to_host()[0], want_u, atol=2e-5, rtol=1e-5)
    np.testing.assert_allclose(f1_out.to_host()[0], want_f1, atol=2e-5, rtol=1e-5)
    maxima = [got[k * gsize : (k + 1) * gsize].max() for k in range(3)]
    np.testing.assert_allclose(maxima, want_maxima, rtol=1e-4, atol=1e-6)
    assert bool(got[5 * gsize]) == want_hit


def test_ncc_discrepancy_ignores_a_change_of_light_that_the_difference_sees(rng):
    # F2 = 0.5 F1 + 0.3 (a shadow over a still scene): F2 - F1 is large, the NCC's
    # steepest ascent vanishes (up to the variance regularisation).
    f1 = ref.pad(rng.random((20, 20)))
    f2 = 0.5 * f1 + 0.3
    plain = ref.discrepancy(f1, f2, "difference", 0.0)
    ncc = ref.discrepancy(f1, f2, "ncc", 1e-4)
    assert np.abs(plain).mean() > 0.1 and np.abs(ncc).max() < 1e-3


def test_match_displacement_finds_a_subpixel_shift(rng):
    from scipy import ndimage

    scene = ndimage.gaussian_filter(rng.random((60, 70)), 1.5)
    mask = np.zeros((60, 70), bool)
    mask[20:40, 25:45] = True
    for true in ((1.5, -2.0), (-3.0, 4.5), (0.0, 0.0)):
        moved = ndimage.shift(scene, true, order=3, mode="nearest")
        (dy, dx), _ = match_displacement(
            local_contrast(scene[None]), local_contrast(moved[None]), mask, (0, 0), 6
        )
        assert abs(dy - true[0]) < 0.3 and abs(dx - true[1]) < 0.3, (true, dy, dx)


def test_kalman_filter_damps_a_jump():
    from scipy import ndimage

    rng = np.random.default_rng(3)
    scene = ndimage.gaussian_filter(rng.random((60, 60)), 1.5)
    mask = np.zeros((60, 60), bool)
    mask[22:38, 22:38] = True
    f = MotionFilter("kalman", radius=6)
    frames = [ndimage.shift(scene, (0, 1.0 * t), order=3, mode="nearest") for t in range(6)]
    shifts = [
        f.predict(local_contrast(a[None]), local_contrast(b[None]), mask)[1]
        for a, b in itertools.pairwise(frames)
    ]
    assert abs(shifts[-1] - 1.0) < 0.25  # it learns the constant velocity
    jump = ndimage.shift(frames[-1], (0, 5.0), order=3, mode="nearest")
    step = f.predict(local_contrast(frames[-1][None]), local_contrast(jump[None]), mask)[1]
    assert 1.0 < step < 4.0  # a 5-pixel jump moves it only part of the way
