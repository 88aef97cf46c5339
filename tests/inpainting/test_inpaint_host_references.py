"""The exemplar route's host-side measures against plain references (stop 51 made them
faster; these say they still compute the same thing): the autocorrelation by FFTs against
sums over each lag, the lattice's lags against the mean squared differences lag by lag, the
last vote's sources against a loop over the patch's offsets, and the square dilation
against scipy's binary dilation."""

import numpy as np
import pytest
from scipy import ndimage

from clpde.inpainting import choose, stitch
from clpde.inpainting.patchmatch import square_dilation


def _shifted(a, dy, dx):
    """a(p + lag) beside a(p), over the pixels where both lie in the image."""
    H, W = a.shape
    ys, xs = slice(max(0, -dy), min(H, H - dy)), slice(max(0, -dx), min(W, W - dx))
    yt, xt = slice(max(0, dy), min(H, H + dy)), slice(max(0, dx), min(W, W + dx))
    return a[yt, xt], a[ys, xs]


def test_the_autocorrelation_is_the_direct_sums_at_each_lag():
    rng = np.random.default_rng(3)
    detail = rng.normal(size=(40, 47)).astype(np.float32)
    ok = rng.random((40, 47)) > 0.3
    ok[12:25, 15:30] = False  # a hole
    lags, a = choose._autocorrelation(detail, ok)
    d = np.where(ok, detail, 0).astype(np.float64)
    k = ok.astype(np.float64)
    want = {}
    for dy in range(-choose.LAGS[1], choose.LAGS[1] + 1):
        for dx in range(-choose.LAGS[1], choose.LAGS[1] + 1):
            if max(abs(dy), abs(dx)) < choose.LAGS[0]:
                continue
            d1, d0 = _shifted(d, dy, dx)
            k1, k0 = _shifted(k, dy, dx)
            count, e1, e2 = (k1 * k0).sum(), (d1 * d1 * k0).sum(), (k1 * d0 * d0).sum()
            if count > 0.25 * k.sum() and min(e1, e2) > 1e-12 * max(count, 1):
                want[(dy, dx)] = (d1 * d0).sum() / np.sqrt(e1 * e2)
    got = {(int(y), int(x)): v for (y, x), v in zip(lags, a, strict=True)}
    assert got.keys() == want.keys()
    assert max(abs(got[key] - want[key]) for key in want) < 1e-4


def test_the_lattice_s_lags_are_where_the_known_pixels_repeat():
    rng = np.random.default_rng(5)
    tile = rng.random((2, 5, 7))
    data = np.tile(tile, (1, 8, 6))  # periods 5 rows, 7 columns
    omega = np.zeros(data.shape[1:], bool)
    omega[14:22, 10:19] = True
    max_lag = 12
    lags = choose.lattice_offsets(data, omega, max_lag=max_lag)
    known = ~omega
    x = np.where(known, data, 0)
    msd = {}
    for dy in range(-max_lag, max_lag + 1):
        for dx in range(-max_lag, max_lag + 1):
            k1, k0 = _shifted(known.astype(float), dy, dx)
            both = k1 * k0
            if (dy, dx) == (0, 0) or both.sum() <= 0.25 * known.sum():
                continue
            sq = sum(((a - b) ** 2 * both).sum() for a, b in (_shifted(c, dy, dx) for c in x))
            msd[(dx, dy)] = sq / both.sum()
    exact = {key for key, v in msd.items() if v < 1e-9}
    assert exact and {(int(a), int(b)) for a, b in lags} == exact
    assert {(7, 0), (0, 5), (7, 5)} <= exact


def _sources_by_loop(nnf, dist, pen, hole, r, sigma2):
    """The last vote's source of each hole pixel, the covering patch of lowest score, the
    first of equal ones in the kernel's loop order (the loop stop 50 had)."""
    H, W = hole.shape
    py, px = np.nonzero(hole)
    inv = 1.0 / (2 * max(float(sigma2), 1e-10))
    best, src = np.full(py.size, np.inf), np.full(py.size, -1, np.int64)
    offy, offx = np.zeros(py.size, np.int64), np.zeros(py.size, np.int64)
    for oy in range(-r, r + 1):
        for ox in range(-r, r + 1):
            qy, qx = py - oy, px - ox
            ok = (qy >= 0) & (qy < H) & (qx >= 0) & (qx < W)
            qy_, qx_ = np.where(ok, qy, 0), np.where(ok, qx, 0)
            e = np.where(ok, dist[qy_, qx_] * inv + pen[qy_, qx_], np.inf)
            better = e < best
            best = np.where(better, e, best)
            s = nnf[qy_, qx_]
            src = np.where(better, (s[:, 1] + oy) * W + s[:, 0] + ox, src)
            offy, offx = np.where(better, oy, offy), np.where(better, ox, offx)
    return src, offy, offx


@pytest.mark.parametrize("seed", range(6))
def test_the_last_vote_s_sources_are_the_loop_s(seed):
    rng = np.random.default_rng(seed)
    H, W = (int(v) for v in rng.integers(9, 30, 2))
    r = int(rng.integers(1, 4))
    hole = rng.random((H, W)) < 0.3
    nnf = rng.integers(0, min(H, W), (H, W, 2)).astype(np.int32)
    dist = rng.integers(0, 4, (H, W)).astype(np.float32)  # many equal scores
    dist[rng.random((H, W)) < 0.3] = np.inf
    dist[rng.random((H, W)) < 0.05] = np.nan
    dist[: 2 * r + 2, : 2 * r + 2] = np.inf  # no covering patch scored
    hole[r, r] = True
    pen = (rng.integers(0, 3, (H, W)) * 0.5).astype(np.float32)
    got = stitch.vote_sources(nnf, dist, pen, hole, r, 0.7)
    want = _sources_by_loop(nnf, dist, pen, hole, r, 0.7)
    assert (want[0] == -1).any() and (want[0] >= 0).any()
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize("r", [0, 1, 3])
def test_the_square_dilation_is_scipy_s(r):
    rng = np.random.default_rng(r)
    mask = rng.random((23, 31)) < 0.05
    mask[0, 5] = mask[-1, -1] = True  # at the edges
    want = ndimage.binary_dilation(mask, structure=np.ones((2 * r + 1,) * 2, bool))
    np.testing.assert_array_equal(square_dilation(mask, r), want)
