"""A shift that a part of the object moving otherwise does not decide (issue 35, trackgrey).

The masked correlation of `appearance.match_shift` sums over all the object's pixels, so a
part that moves otherwise (a swinging leg, ground or an occluder's edge the contour took
in, a part going behind a still bar) pulls its peak: the part's pixels match at their own
shift, the rest's correlation at the true one is lowered by the part's misfit, and a
wrong shift can win. Here the correlation map's few highest local maxima are scored again
by a trimmed correlation: at each shift, cur's pixels are fitted to prev's by a gain and
an offset, the TRIM share with the largest misfit is left out, and the correlation is
taken over the rest. The true shift explains the object but for the part; a wrong one,
which matches the part or nothing, keeps its misfit across most of the object. Another
maximum replaces the peak only where it is a clear match once its worst share is left out
(CLEAR) and better than the peak by the same score; the Lucas-Kanade fit that follows
(appearance._refine) finds the sub-pixel motion from it.

(Tried, on the calibration half of the photo corpus, and not taken: the chosen maximum's 8
neighbours scored too: occlude-2 0.954 -> 0.923, grey-8 0.872 -> 0.859, grey-14 0.577 ->
0.573; any better trimmed score, not a clear one: occlude-0 0.968 -> 0.964, footage-0
0.838 -> 0.836.)
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

# The share of the object's pixels left out of the trimmed correlation (the largest
# misfits): a part up to this share of the object may move otherwise.
TRIM = 0.25
# The correlation map's local maxima (over 5x5 shifts) scored again.
CANDIDATES = 4
# Another local maximum replaces the correlation's peak only where its trimmed correlation
# is at least this (a clear match of all but the part; appearance.LIGHT_CLEAR's level) and
# higher than the peak's.
CLEAR = 0.9
# At most this many of the object's pixels are scored (an even stride over them beyond).
MAX_PIXELS = 2000


def trimmed_scores(prev, cur, where: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """(S,): the trimmed correlation of prev (C, H, W) over the pixels of `where` with cur
    read at those pixels plus each of `shifts` (S, 2, whole pixels; cur's edge repeated
    beyond the frame), the channels pooled."""
    pts = np.array(np.nonzero(where))
    if pts.shape[1] > MAX_PIXELS:
        pts = pts[:, :: int(np.ceil(pts.shape[1] / MAX_PIXELS))]
    size = np.array(where.shape)[None, :, None]
    at = np.clip(pts[None] + np.asarray(shifts, np.int64)[:, :, None], 0, size - 1)
    p = np.asarray(prev)[:, pts[0], pts[1]]  # (C, n)
    c = np.asarray(cur)[:, at[:, 0], at[:, 1]]  # (C, S, n)
    p = p - p.mean(axis=1, keepdims=True)
    c = c - c.mean(axis=2, keepdims=True)
    # each channel's gain at each shift; the misfit pooled over the channels
    gain = (c * p[:, None]).sum(axis=2, keepdims=True) / max(float((p * p).sum()), 1e-12)
    misfit = ((c - gain * p[:, None]) ** 2).sum(axis=0)  # (S, n)
    keep = misfit <= np.quantile(misfit, 1 - TRIM, axis=1, keepdims=True)
    k = keep.sum(axis=1)  # (S,)
    pk = np.where(keep[None], p[:, None], 0.0)
    ck = np.where(keep[None], c, 0.0)
    pk = pk - (pk.sum(axis=2, keepdims=True) / k[None, :, None]) * keep[None]
    ck = ck - (ck.sum(axis=2, keepdims=True) / k[None, :, None]) * keep[None]
    num = (pk * ck).sum(axis=(0, 2))
    den = np.sqrt(np.maximum((pk * pk).sum(axis=(0, 2)) * (ck * ck).sum(axis=(0, 2)), 1e-12))
    return num / den


def robust_shift(prev, cur, where: np.ndarray, scores: np.ndarray, dy, dx) -> np.ndarray:
    """(dy, dx): among the CANDIDATES highest local maxima of the correlation map `scores`
    (indexed as match_shift's, -inf where not searched; dy, dx its shifts), the one whose
    trimmed correlation is highest where that is at least CLEAR, else the peak."""
    finite = np.isfinite(scores)
    peaks = finite & (ndimage.maximum_filter(scores, size=5, mode="wrap") == scores)
    idx = np.flatnonzero(peaks)
    idx = idx[np.argsort(scores.ravel()[idx])[::-1][:CANDIDATES]]
    ys, xs = np.unravel_index(idx, scores.shape)
    dy, dx = np.ravel(dy), np.ravel(dx)
    best = 0
    if len(idx) > 1:
        shifts = np.column_stack([dy[ys], dx[xs]])
        trimmed = trimmed_scores(prev, cur, where, shifts)
        best = int(np.argmax(trimmed))
        if trimmed[best] < CLEAR:
            best = 0
    return np.array([dy[ys[best]], dx[xs[best]]], np.float64)
