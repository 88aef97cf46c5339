"""The 2D band in bricks (LevelSet layouts 'bricks8x8' and 'bricks16x4', kernels/bricks/bricks2d.h)
against the list layout and the numpy references (tests/reference/levelset.py).

Every band cell runs the same inline arithmetic (morph_cell, reinit_update_2d) in every
layout and launch geometry, so the stepped values are the list's bit for bit; only the
per-work-item statistics are grouped differently (maxima exact, sums to rounding). The one
exception is morph_track_tiled, the NCC step of bricks on CPUs, which slides the window
sums over each brick: equal to rounding."""

from dataclasses import replace

import numpy as np
import pyopencl.array as cla
import pytest

from clpde.fields import Field, PingPong
from clpde.runtime import Runtime
from clpde.tracking.levelset import LevelSet
from clpde.tracking.morph import morph_kernel_name
from clpde.tracking.tracker import MorphingTracker
from tests.reference import levelset as ref

BRICKS = [("bricks8x8", False), ("bricks16x4", False), ("bricks8x8", True), ("bricks16x4", True)]


def _level_set(runtime, layout, group=None, shape=(45, 61)):
    ny, nx = shape
    y, x = np.mgrid[:ny, :nx]
    # Two blobs, one near the frame's corner: bricks cut short at the movable region's edge.
    u = np.minimum(np.hypot(x - 20.3, y - 19.6) - 9, np.hypot(x - 54, y - 40) - 5)
    return LevelSet(runtime, u, 3.0, np.float32, storage=layout, group_per_brick=group)


def _features(ls, rng, channels):
    grid = ls.grid
    cgrid = replace(grid, nc=channels)
    shape = (channels, grid.ny, grid.nx)
    f1 = Field.from_host(cgrid, rng.random(shape))
    f2 = Field.from_host(cgrid, 0.5 * grid.interior(f1.data.get()) + 0.3 * rng.random(shape))
    u = grid.interior(ls.u.cur.data.get())
    prior = Field.from_host(grid, u + rng.normal(size=u.shape))
    return f1, f2, prior


def _step(ls, f1, f2, prior, channels, disc, lam, name=None):
    g = ls.grid
    name = name or ls.store.KERNELS["morph"]
    kernel = ls.band_kernel("tracking/features.cl", name, NCH=channels, DISC=disc, WIN=3)
    parts = ls.band_parts()
    stats = cla.zeros(ls.runtime.queue, 5 * parts + 1, g.dtype)
    pair = PingPong(f1)
    ls.launch_band(
        kernel,
        ls.band,
        ls.u.cur.data.data,
        pair.cur.data.data,
        f2.data.data,
        ls.band_mask.data,
        prior.data.data,
        ls.u.nxt.data.data,
        pair.nxt.data.data,
        stats.data,
        g.scalar(0.3),
        g.scalar(0.02**2),
        g.scalar(1e-3**2),
        g.scalar(1.0),
        g.scalar(lam),
        g.scalar(0.05),
        np.int32(g.sx),
        np.int32(g.plane),
    )
    s = stats.get()
    summary = (
        [s[k * parts : (k + 1) * parts].max() for k in range(3)]
        + [s[k * parts : (k + 1) * parts].sum() for k in (3, 4)]
        + [s[5 * parts]]
    )
    return ls.u.nxt.data.get(), pair.nxt.data.get(), np.array(summary)


def test_bricks_cover_the_band_and_nothing_else(runtime):
    for layout, (bx, by) in (("bricks8x8", (8, 8)), ("bricks16x4", (16, 4))):
        ls = _level_set(runtime, layout)
        band = ls.band_cells()  # over the movable region, the caller's grid
        ny, nx = band.shape
        tiles = np.zeros((-(-ny // by) * by, -(-nx // bx) * bx), bool)
        tiles[:ny, :nx] = band
        want = np.flatnonzero(tiles.reshape(-(-ny // by), by, -1, bx).any(axis=(1, 3)))
        np.testing.assert_array_equal(ls.band.ids.get()[: ls.band.n], want)
        assert ls.store.brick == (bx, by)
        assert ls.stored_cells() == want.size * bx * by >= band.sum()


@pytest.mark.parametrize("layout,group", BRICKS)
@pytest.mark.parametrize("disc,channels,lam", [(0, 1, 0.0), (1, 3, 0.1), (2, 2, 0.2)])
def test_brick_step_is_bitwise_the_list_step_and_matches_reference(
    runtime, rng, layout, group, disc, channels, lam
):
    lists = _level_set(runtime, "lists")
    bricks = _level_set(runtime, layout, group)
    f1, f2, prior = _features(lists, rng, channels)
    want_u, want_f1, want_stats = _step(lists, f1, f2, prior, channels, disc, lam)
    got_u, got_f1, got_stats = _step(bricks, f1, f2, prior, channels, disc, lam)
    np.testing.assert_array_equal(got_u, want_u)
    np.testing.assert_array_equal(got_f1, want_f1)
    np.testing.assert_array_equal(got_stats[[0, 1, 2, 4, 5]], want_stats[[0, 1, 2, 4, 5]])
    np.testing.assert_allclose(got_stats[3], want_stats[3], rtol=1e-5)  # a sum, regrouped
    _check_reference(bricks, (got_u, got_f1, got_stats), f1, f2, prior, disc, lam)


def _check_reference(ls, got, f1, f2, prior, disc, lam):
    """A step's results against the numpy reference of the same discrete step."""
    got_u, got_f1, got_stats = got
    band = ls.grid.interior(ls.band_mask.get()[np.newaxis])[0]
    host = [a.data.get().astype(np.float64) for a in (f1, f2)]
    ref_u, ref_f1, maxima, mean, hit = ref.morph_track(
        ls.u.cur.data.get()[0].astype(np.float64),
        *host,
        band,
        prior.data.get()[0].astype(np.float64),
        0.3,
        0.02,
        1e-3,
        1.0,
        lam,
        0.05,
        {0: "difference", 1: "ncc", 2: "huber"}[disc],
    )
    inside = band > 0
    interior = ls.grid.interior
    np.testing.assert_allclose(interior(got_u)[0][inside], ref_u[inside], atol=3e-5, rtol=1e-4)
    np.testing.assert_allclose(interior(got_f1)[:, inside], ref_f1[:, inside], atol=3e-5, rtol=1e-4)
    np.testing.assert_allclose(got_stats[:3], maxima, rtol=2e-4, atol=1e-6)
    np.testing.assert_allclose(got_stats[3] / got_stats[4], mean, rtol=2e-4)
    assert bool(got_stats[5]) == hit


@pytest.mark.parametrize("layout", ["bricks8x8", "bricks16x4"])
@pytest.mark.parametrize("channels,lam", [(1, 0.0), (3, 0.1)])
def test_tiled_ncc_step_matches_the_list_step_to_rounding(runtime, rng, layout, channels, lam):
    # The NCC's window sums slid over each brick: the same sums, added in another order
    # (and with rows taken out again), so float32 rounding differs, by about 1e-6 here.
    lists, bricks = _level_set(runtime, "lists"), _level_set(runtime, layout)
    assert morph_kernel_name(bricks, "ncc") == "features_morph_track_tiled"
    f1, f2, prior = _features(lists, rng, channels)
    want_u, want_f1, want_stats = _step(lists, f1, f2, prior, channels, 1, lam)
    got_u, got_f1, got_stats = _step(
        bricks, f1, f2, prior, channels, 1, lam, "features_morph_track_tiled"
    )
    np.testing.assert_allclose(got_u, want_u, atol=2e-5, rtol=1e-5)
    np.testing.assert_allclose(got_f1, want_f1, atol=2e-5, rtol=1e-5)
    np.testing.assert_allclose(got_stats[:4], want_stats[:4], rtol=1e-4)
    np.testing.assert_array_equal(got_stats[4:], want_stats[4:])  # cell count, edge flag
    assert not np.array_equal(got_u, want_u)  # it did run the other sums
    _check_reference(bricks, (got_u, got_f1, got_stats), f1, f2, prior, 1, lam)
    # Cells outside the band keep their values exactly.
    outside = bricks.grid.interior(bricks.band_mask.get()[np.newaxis]) == 0
    np.testing.assert_array_equal(
        bricks.grid.interior(got_u)[outside], bricks.grid.interior(bricks.u.cur.data.get())[outside]
    )


@pytest.mark.parametrize("layout,group", BRICKS)
def test_brick_reinitialisation_is_bitwise_the_lists_and_matches_reference(runtime, layout, group):
    lists, bricks = _level_set(runtime, "lists"), _level_set(runtime, layout, group)
    for ls in (lists, bricks):  # far from a distance: u scaled by 2.5
        ls.u.cur.data.set(2.5 * ls.u.cur.data.get())
    start = bricks.u.cur.data.get()[0].astype(np.float64)
    for ls in (lists, bricks):
        ls.reinitialize(iterations=3)  # every movable cell
    np.testing.assert_array_equal(bricks.u.cur.data.get(), lists.u.cur.data.get())
    p, inner = start.copy(), np.zeros(start.shape, bool)
    inner[4:-4, 4:-4] = True  # ghost 2 + MARGIN 2
    for _ in range(3):
        step = np.pad(ref.reinit_step(p, start, 0.5), 2)
        p = np.where(inner, step, p)
    np.testing.assert_allclose(bricks.u.cur.data.get()[0], p, atol=2e-5, rtol=1e-5)
    for ls in (lists, bricks):  # the rebuild's band-limited reinitialisation
        ls.rebuild(4)
    np.testing.assert_array_equal(bricks.u.cur.data.get(), lists.u.cur.data.get())
    np.testing.assert_array_equal(bricks.band_cells(), lists.band_cells())


def _frames(n=6, size=72):
    y, x = np.mgrid[:size, :size]
    return np.stack(
        [((y - 36) ** 2 / 1.4 + (x - 22 - 4 * t) ** 2 < 150).astype(np.float32) for t in range(n)]
    )


@pytest.mark.parametrize("layout", ["bricks8x8", "bricks16x4"])
def test_tracker_with_bricks_is_the_tracker_with_lists(runtime, layout):
    frames = _frames()

    def run(band_layout, device=runtime, discrepancy="ncc"):
        return list(
            MorphingTracker(
                frames,
                frames[0] > 0.5,
                storage=band_layout,
                motion=None,
                discrepancy=discrepancy,
                device=device,
            ).iterate()
        )

    # Bit for bit where every cell sums its own window: F2 - F1 on the CPU geometry, and
    # the NCC in the GPU geometry (a work-group per brick), run on the CPU.
    lists, bricks = run("lists", discrepancy="difference"), run(layout, discrepancy="difference")
    assert sum(s.rebuilds for s in lists) > 0  # the band moved: upkeep is exercised
    for a, b in zip(lists, bricks, strict=True):
        np.testing.assert_array_equal(b.level_set, a.level_set)
        assert (b.iterations, b.rebuilds) == (a.iterations, a.rebuilds)
        assert b.discrepancy == pytest.approx(a.discrepancy, rel=1e-5)
    gpu_like = Runtime(runtime.index, runtime.platform, runtime.device)
    gpu_like.is_cpu = False
    lists = run("lists")
    for a, b in zip(lists, run(layout, gpu_like), strict=True):
        np.testing.assert_array_equal(b.level_set, a.level_set)
    # The tiled NCC sums: equal to rounding, which grows through the frames (1e-3 here).
    for a, b in zip(lists, run(layout), strict=True):
        np.testing.assert_allclose(b.level_set, a.level_set, atol=1e-2)
        assert np.mean(b.mask != a.mask) < 1e-3


def test_unknown_storage_is_refused():
    with pytest.raises(Exception, match="storage must be one of"):
        MorphingTracker(_frames(2), _frames(2)[0] > 0.5, storage="bricks4x4")
