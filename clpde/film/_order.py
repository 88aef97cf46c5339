"""Order statistics over a frame's few compensated neighbours, per pixel, where trusted.

A frame has 2-4 neighbours: sorting K values per pixel along the stack's first (strided)
axis with np.sort costs more than a sorting network of K(K-1)/2 elementwise minima and
maxima over whole planes (5x less at 640x360, K = 4), and picking by index with
take_along_axis more than a masked copy per plane.
Both give exactly the sorted values, so the results are the same bit for bit.
"""

from __future__ import annotations

import numpy as np


def median_of(x: np.ndarray) -> np.floating:
    """np.median of a 1-D float array without NaNs, the same value and type (a scalar of
    x's dtype): one partition at the middle and the largest of the lower half (np.median
    partitions at two places, 5x the time on the ~80k values of a flicker fit)."""
    h = x.size // 2
    part = np.partition(x, h)
    if x.size % 2:
        return part[h]
    return (part[:h].max() + part[h]) / 2


def sorted_planes(vals: np.ndarray) -> list[np.ndarray]:
    """vals (K, H, W) sorted along K, as K planes (a sorting network: odd-even
    transposition, K rounds of compare-exchange)."""
    s = [v for v in vals]
    K = len(s)
    for r in range(K):
        for i in range(r % 2, K - 1, 2):
            s[i], s[i + 1] = np.minimum(s[i], s[i + 1]), np.maximum(s[i], s[i + 1])
    return s


def _pick(index: np.ndarray, planes: list[np.ndarray]) -> np.ndarray:
    """planes[index[y, x]][y, x] (np.choose's result, by masked copies: faster)."""
    out = planes[0].copy()
    for k in range(1, len(planes)):
        np.copyto(out, planes[k], where=index == k)
    return out


def _count(ok: np.ndarray) -> np.ndarray:
    """How many of ok's planes are True per pixel, as uint16 (a stack holds a few frames;
    numpy's default int64 sum costs 7x the time)."""
    return ok.sum(0, dtype=np.uint16)


def median(vals: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """The median over k of vals[k] where ok[k] (NaN where none): the values not trusted
    are pushed to the end as +inf, and the middle of the n trusted ones is taken (NaN
    everywhere for an empty stack)."""
    if len(vals) == 0:
        return np.full(vals.shape[1:], np.nan, np.float32)
    s = sorted_planes(np.where(ok, vals, np.inf))
    n = _count(ok)
    lo = _pick((np.maximum(n, 1) - 1) >> 1, s)  # (n - 1) // 2, 0 for none
    hi = _pick(n >> 1, s)
    out = 0.5 * (lo + hi)
    return np.where(n > 0, out, np.nan).astype(np.float32)


def second_least(v: np.ndarray, vals: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Of the differences v - vals[k] over trusted k, the second least in magnitude (the
    least with fewer than 3; 0 with none): the residual the scratch detector reads. A
    scratch fixed on the film differs from every neighbour but perhaps the nearest in a slow
    pan; beside it, where one neighbour's own scratch lands, the others agree: no ghost.
    Ties go to the earlier neighbour: each difference's place in a stable sort by magnitude
    is the count of those before it (K(K-1)/2 comparisons of planes), and the one at the
    place wanted is copied."""
    K = len(vals)
    d = [np.where(ok[k], v - vals[k], np.float32(np.inf)) for k in range(K)]
    mag = [np.abs(x) for x in d]
    place = [np.zeros(v.shape, np.uint8) for _ in range(K)]
    for j in range(K):
        for k in range(j + 1, K):
            first = mag[j] <= mag[k]  # j sorts before k (a tie: the earlier)
            place[k] += first
            place[j] += ~first
    n = _count(ok)
    want = (n >= 3).view(np.uint8)  # the second least with 3 or more, else the least
    out = np.zeros(v.shape, np.float32)
    for k in range(K):
        np.copyto(out, d[k], where=(place[k] == want) & (n > 0))
    return out
