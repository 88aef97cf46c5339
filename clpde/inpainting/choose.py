"""Measures of a hole's surroundings, on the host, in proportion to the box:

- ``radius``: the hole's half-thickness, the largest distance of a hole pixel to the known
  ones (Euclidean).
- ``texture``: how much fine texture surrounds the hole. On the ring of known pixels within
  RING pixels of the hole, the grey image minus its local mean (a normalised Gaussian of
  the known pixels, sigma SMOOTH, so that the hole's values never count) leaves the detail
  that a smooth fill cannot make; ``texture`` is its root mean square, in [0, 1] units.
- ``periodicity``: how well the surroundings repeat themselves. The same detail image, on
  the known pixels of the box, is correlated with itself shifted by every lag of LAGS
  pixels (normalised over the pixels both copies know, by FFTs); ``periodicity`` is the
  largest correlation, 1 for a pattern that repeats exactly (a periodic texture, stripes,
  a straight edge), near 0 for stochastic texture and most photos.
- ``lattice_offsets``: the lags at which the known pixels repeat exactly.

The exemplar uses the periodicity and the lattice (inpainting/exemplar.py). What
`method="auto"` fills each cluster of damage with is no longer a rule on these measures but
measured on the damage itself: inpainting/auto.py.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy import fft as sfft
from scipy import ndimage

RING = 8  # width of the ring of known pixels around the hole that is measured, in pixels
SMOOTH = 2.0  # sigma of the local mean removed before measuring the texture, in pixels
LAGS = (6, 32)  # the lags (chessboard distance, pixels) over which periodicity is sought
# surroundings that repeat this well are copied by the exemplar without a structure guide
# (docs/inpainting_texture.md: a plateau from 0.85 to 0.9)
MIN_PERIODICITY = 0.85


def _detail(data: np.ndarray, known: np.ndarray):
    """The grey image minus its local mean over the known pixels (0 where unknown), and the
    pixels where that mean is reliable (half its Gaussian weight known)."""
    grey = np.where(known, np.asarray(data, np.float32).mean(axis=0), 0).astype(np.float32)
    w = ndimage.gaussian_filter(known.astype(np.float32), SMOOTH, mode="constant", truncate=3)
    mean = ndimage.gaussian_filter(grey, SMOOTH, mode="constant", truncate=3) / np.maximum(w, 1e-6)
    return np.where(known, grey - mean, 0.0), known & (w > 0.5)


def periodicity(data: np.ndarray, omega: np.ndarray) -> float:
    """Largest normalised autocorrelation of the detail of the known pixels over the lags
    LAGS (module docstring); 0 when too little is known."""
    return _periodicity(*_detail(data, ~np.asarray(omega, bool)))


def _periodicity(detail, ok) -> float:
    lags, a = _autocorrelation(detail, ok)
    return float(a.max()) if a.size else 0.0


def _autocorrelation(detail, ok):
    """The normalised autocorrelation of the detail over the known pixels: the lags (dy,
    dx) of chessboard length within LAGS whose overlap holds at least a quarter of the known
    pixels and some detail ((m, 2) ints), and the correlation at each ((m,))."""
    d = np.where(ok, detail, 0).astype(np.float32)
    k = ok.astype(np.float32)
    H, W = d.shape
    hi = LAGS[1]
    # zero padding by the largest lag: no wrap-around within the lags looked at
    shape = (sfft.next_fast_len(H + hi + 1, True), sfft.next_fast_len(W + hi + 1, True))
    # the transforms in one call each way (a batch: the same values as one by one)
    fd, fd2, fk = sfft.rfft2(np.stack([d, d * d, k]), shape)
    # corr(a, b): sum over p of a(p + lag) b(p)
    num, e1, count = sfft.irfft2(
        np.stack([fd * np.conj(fd), fd2 * np.conj(fk), fk * np.conj(fk)]), shape
    )
    # only the lags looked at (the corners of the transform, in its row-major order: the
    # same lags in the same order as masking the whole of it, a third of the work); corr(k,
    # d^2) at a lag is corr(d^2, k) at the opposite lag: one inverse transform fewer
    idx, opposite, ly, lx = _lags(shape)
    e2 = e1.ravel()[opposite]
    num, e1, count = (a.ravel()[idx] for a in (num, e1, count))
    # lags whose overlap holds at least a quarter of the known pixels, and some detail
    use = (count > 0.25 * k.sum()) & (np.minimum(e1, e2) > 1e-12 * np.maximum(count, 1))
    return np.stack([ly[use], lx[use]], -1), num[use] / np.sqrt(e1[use] * e2[use])


@functools.lru_cache(maxsize=64)
def _lags(shape):
    """(idx, opposite, ly, lx) over a transform of `shape`: the flat indices, in row-major
    order, of the entries whose lag's chessboard length is within LAGS, those of the
    opposite lags (mod the shape), and the lags (rows, columns; int64) (read-only: shared
    by every call of that shape)."""
    ty = sfft.fftfreq(shape[0], 1 / shape[0])[:, None]
    tx = sfft.fftfreq(shape[1], 1 / shape[1])[None, :]
    ly, lx = (np.array(a) for a in np.broadcast_arrays(ty, tx))
    lag = np.maximum(np.abs(ly), np.abs(lx))
    idx = np.flatnonzero((lag >= LAGS[0]) & (lag <= LAGS[1]))
    ly, lx = (a.ravel()[idx].astype(np.int64) for a in (ly, lx))
    opposite = (-ly % shape[0]) * shape[1] + (-lx % shape[1])
    out = (idx, opposite, ly, lx)
    for a in out:
        a.flags.writeable = False
    return out


def repeat(detail, ok) -> float:
    """How well the detail repeats along two directions: the autocorrelation's best lag's
    value, or, if lower, the best value at a lag at least LAGS[0] px off the line through
    the origin along that lag; 0 when too little is known.

    A straight edge correlates with itself at every shift along it, as well as a periodic
    pattern at its period (periodicity ~1 for both), but only along that one line: across
    it the correlation falls and stays low. A periodic pattern repeats off that line too:
    a lattice along its second vector, stripes along themselves or across at their period."""
    lags, a = _autocorrelation(detail, ok)
    if not a.size:
        return 0.0
    best = int(np.argmax(a))
    ly, lx = lags[best]
    # distance of each lag from the line through the origin along the best one
    off = np.abs(lags[:, 0] * lx - lags[:, 1] * ly) / np.hypot(ly, lx)
    away = off >= LAGS[0]
    return float(min(a[best], a[away].max())) if away.any() else 0.0


def lattice_offsets(
    data: np.ndarray, omega: np.ndarray, max_lag: int = 96, tol: float = 1e-3, limit: int = 96
) -> np.ndarray:
    """The lags (dx, dy), up to ``max_lag`` px, at which the known pixels of ``data``
    ((channels, rows, cols)) repeat exactly, up to ``tol``: the local minima of the mean
    squared difference between the known pixels and their shifts (over the pairs both
    known, a quarter of the known pixels at least) of at most ``tol`` times the known
    pixels' variance; the ``limit`` shortest. Empty when nothing repeats that well.

    For a periodic pattern these are the lattice's vectors and their sums: a patch copied
    from any of them is exact, whatever the phase a flat patch alone would allow. The
    autocorrelation's peaks (periodicity) are not enough: at 0.97 they let in a rotated
    stripe pattern's near repeats, which differ on the stripes' edges."""
    known = ~np.asarray(omega, bool)
    x = np.where(known, np.asarray(data, np.float64), 0)
    k = known.astype(np.float64)
    H, W = k.shape
    shape = (sfft.next_fast_len(H + max_lag + 1, True), sfft.next_fast_len(W + max_lag + 1, True))
    # corr(a, b), the sum over p of a(p + lag) b(p), is linear in a and b: the squared
    # differences summed over the channels, sum_c corr(x_c^2, k) + corr(k, x_c^2) - 2
    # corr(x_c, x_c), are one inverse transform of a sum of products (with the overlap's
    # count, two in one call, and the forward ones batched): 2 + channels transforms, not
    # 4 + 5 per channel (3.3 ms of the exemplar's 6 on the periodic cases, stop 51)
    f = sfft.rfft2(np.concatenate([k[None], (x * x).sum(axis=0)[None], x]), shape)
    fk, fx2, fx = f[0], f[1], f[2:]
    cross = fx2 * np.conj(fk)
    spec = cross + np.conj(cross) - 2 * (fx * np.conj(fx)).sum(axis=0)
    sq, count = sfft.irfft2(np.stack([spec, fk * np.conj(fk)]), shape)
    ty = sfft.fftfreq(shape[0], 1 / shape[0])[:, None]
    tx = sfft.fftfreq(shape[1], 1 / shape[1])[None, :]
    ly, lx = np.broadcast_arrays(ty, tx)
    use = (np.maximum(np.abs(ly), np.abs(lx)) <= max_lag) & (count > 0.25 * k.sum())
    use &= (ly != 0) | (lx != 0)
    msd = np.where(use, sq / np.maximum(count, 1), np.inf)
    var = float(sum(np.var(xc[known]) for xc in x)) if known.any() else 0.0
    low = msd <= ndimage.minimum_filter(msd, size=3, mode="wrap")
    keep = use & low & (msd <= tol * var)
    lags = np.stack([lx[keep], ly[keep]], -1).astype(np.int32)
    order = np.lexsort((lags[:, 1], lags[:, 0], np.abs(lags).sum(axis=1)))
    return lags[order][:limit]


def hole_depth(omega: np.ndarray) -> np.ndarray:
    """Each hole pixel's Euclidean distance to the nearest known pixel (0 where known); the
    pixels beyond the box's edge count as known."""
    return ndimage.distance_transform_edt(np.pad(omega, 1))[1:-1, 1:-1]


def features(data: np.ndarray, omega: np.ndarray, depth: np.ndarray | None = None) -> dict:
    """{"radius", "texture", "periodicity"} of the hole ``omega`` in ``data`` ((channels,
    rows, cols) in [0, 1]; values inside omega are not read). ``depth``: hole_depth(omega),
    if the caller has it already."""
    omega = np.asarray(omega, bool)
    if not omega.any():
        return {"radius": 0.0, "texture": 0.0, "periodicity": 0.0}
    known = ~omega
    depth = hole_depth(omega) if depth is None else depth
    detail, ok = _detail(data, known)
    ring = known & (ndimage.distance_transform_edt(known) <= RING)
    texture = float(np.sqrt(np.mean(detail[ring].astype(np.float64) ** 2))) if ring.any() else 0.0
    return {
        "radius": float(depth.max()),
        "texture": texture,
        "periodicity": _periodicity(detail, ok),
    }
