"""The film detector's hysteresis (clpde.film.detect): the candidate regions that reach the
blotch threshold (_regions_found), and, once confirmed, their growth into their own pixels
that the first pass left out: hysteresis from confident seeds.

A blotch that passed every check (clpde.film._regions) is damage; what the first pass
misses of it is its rim and its inside where the neighbours disagree among themselves:

- the inside: a blotch in frame t disturbs the flows from t, so its neighbours'
  compensated values spread over its area, and the blotch score's scale, which grows with
  that spread (pathological motion), hides the blotch's own pixels. Connected to a
  confirmed region, a pixel outside the range of all its trusted neighbours by the low
  hysteresis level, on the region's side, is the same damage (the spread is the region's
  doing, not the scene's);
- the rim: a soft edge changes its pixels by less than the grain's level. A pixel next to
  the region whose residual, on the region's side, lies in the frame's own top GROW_SHARE
  of residuals (measured outside the candidates, so the level adapts to the frame's
  grain, codec and flow errors) joins it.

Both are bounded (INSIDE_REACH, RIM_REACH px), so a region never spreads along a moving
edge that the same test happens to pass.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ._morph import dilate

HYSTERESIS_LOW = 0.5  # share of the blotch threshold a region grows into
# share of the blotch threshold the owned region evidence (clpde.film.detect.blotch_evidence)
# joins a region at: 3 noise units at the default 7 (chosen on the calibration half:
# benchmarks/film_missed.py; 3.5, the pixels' low level, found 1.7% less of its blotches)
REGION_LOW = 3.0 / 7.0
# one-sided share of the frame's residuals a rim pixel must stand in (the level is the
# 1 - 2 * GROW_SHARE quantile of |residual|): chosen on the calibration half
GROW_SHARE = 0.05
RIM_REACH = 1  # px of rim a region may gain
INSIDE_REACH = 8  # px a region may grow into pixels outside all its neighbours' range


def _geodesic(seed: np.ndarray, allowed: np.ndarray, reach: int) -> np.ndarray:
    """seed grown by up to `reach` steps of 4-connected dilation within seed | allowed
    (one call: each step sets only pixels inside seed | allowed, as binary_dilation's mask does)."""
    return dilate(seed, reach, within=seed | allowed)


def grow_blotches(
    blotch: np.ndarray,
    taken: np.ndarray,
    d: np.ndarray,
    res: np.ndarray,
    has_nb: np.ndarray,
    sigma: float,
    low: float,
) -> np.ndarray:
    """blotch (H, W) grown into its own inside and rim (see the module text).

    taken: pixels never to take (scratches); d: the signed distance outside the range of
    the trusted neighbours (0 where a side is untrusted); res: the frame minus its trusted
    neighbours' median; has_nb: where res is defined; sigma: the grain's level; low: the
    hysteresis low level in noise units."""
    if not blotch.any():
        return blotch
    # each region's side: the sign most of its pixels' residuals take
    labels, n = ndimage.label(blotch)
    votes = np.bincount(labels.ravel(), weights=np.sign(res).ravel(), minlength=n + 1)
    sign = np.sign(votes)
    sign[0] = 0.0
    sign = sign[labels]
    clean = has_nb & ~taken & ~dilate(blotch, 2)
    r = np.abs(res[clean])
    level = float(np.quantile(r, 1.0 - 2.0 * GROW_SHARE)) if r.size else np.inf
    grown = blotch.copy()
    for s in (-1.0, 1.0):
        seed = blotch & (sign == s)
        if not seed.any():
            continue
        seed = _geodesic(seed, (s * d >= low * sigma) & ~taken, INSIDE_REACH)
        seed = _geodesic(seed, (s * res >= level) & has_nb & ~taken, RIM_REACH)
        grown |= seed
    return grown


def _regions_found(
    a: np.ndarray,
    zr: np.ndarray,
    res: np.ndarray,
    region_noise: tuple[float, float],
    threshold: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The blotch candidates and their evidence: the connected regions of a > the low level
    (HYSTERESIS_LOW of the threshold), or of the owned region evidence zr > REGION_LOW of
    it (a faint blotch's pixels, each within the grain, in a square whose mean stands out),
    that reach the threshold somewhere (hysteresis), or,
    a faint blotch, whose mean residual does as a whole: in noise units of a mean over the
    region's n pixels, level * sqrt(area / n), with the residual's level and the grain's
    correlation area measured on the frame (film_scores). The evidence returned is the
    larger of the pixel's own and its region's."""
    labels, n = ndimage.label((a > HYSTERESIS_LOW * threshold) | (zr > REGION_LOW * threshold))
    if n == 0:
        return labels > 0, a
    idx = np.arange(1, n + 1)
    level, area = region_noise
    size = ndimage.sum_labels(np.ones_like(a), labels, idx)
    z = np.abs(ndimage.mean(res, labels, idx)) / (level * np.sqrt(area / size))
    region = np.concatenate([[0.0], z]).astype(np.float32)[labels]
    strong = np.zeros(n + 1, bool)
    strong[np.unique(labels[a > threshold])] = True
    strong[1:] |= z >= threshold
    strong[0] = False
    return strong[labels], np.maximum(a, region)
