"""Whole blotches the film detector's first pass leaves out (clpde.film.detect).

A faint blotch on a textured, moving scene (foliage, a pan) changes each of its pixels by
one to three grain deviations: its pixels reach the hysteresis's low level in fragments
of 10-30 px, none reaches the threshold, and the fragment's surroundings (the rest of the
blotch, the scene's flow errors) explain it to the tail check. On the calibration half of
benchmarks/film_corpus.py, 115 blotches were missed whole, most of them so.

Damage lies on the film, over the scene: dirt and dust hide the scene's fine detail and
the grain beneath them, while a flow or warp error only misplaces the detail (the frame
keeps about as much of it as its compensated neighbours). So a second chance, in the
middle frames where both sides are trusted: each low-level fragment away from what was
found is grown into the pixels beside it whose residual leans its way by WHOLE_GROW grain
units (WHOLE_REACH px at most), and is a blotch where its mean residual reaches WHOLE_Z
noise units of a mean of its size (level * sqrt(area / n), as for faint regions), the
frame's fine detail over it (3x3 high-pass energy, on its core) is under HIDDEN of its
compensated neighbours' (their median), and it passes the region checks of
clpde.film._regions (ring, local noise on that mean, tail, motion). On the calibration
half the regions that pass the checks but are not damage keep 0.45-3 times their
neighbours' detail; the blotches found this way 0.1-0.4. A blotch over a scene without
detail (a clipped, flat area) hides nothing and is not found this way.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ._morph import dilate
from ._regions import _kept, _local_noise_check, _motion_check, _ring_check, _tail_check

# chosen on the calibration half (docs/film.md, "Whole blotches")
WHOLE_Z = 4.0  # noise units of the grown fragment's mean residual
WHOLE_GROW = 1.0  # grain units a pixel's residual leans the fragment's way to join it
WHOLE_REACH = 4  # px a fragment may grow
HIDDEN = 0.4  # share of its neighbours' fine detail a blotch's region may keep
CORE_LEAST = 4  # px of a region's core its detail is read on (else the whole region)
_SQUARE = np.ones((3, 3), bool)


def _detail(x: np.ndarray) -> np.ndarray:
    """The fine detail: x minus its 3x3 mean."""
    x = x.astype(np.float32)
    return x - ndimage.uniform_filter(x, 3, mode="nearest")


def hides_detail(frame: np.ndarray, neighbours: list, mask: np.ndarray) -> np.ndarray:
    """The components of mask over which the frame keeps less than HIDDEN of its compensated
    neighbours' fine detail (neighbours: (grey, inside, gain) triples, the neighbour's
    warped grey, where its match is inside, and its flicker gain, which scales its detail;
    the median of their energies, each over the component's pixels whose match is inside).
    Read on each component's window (2 px past it: the 3x3 mean of its pixels lies inside)."""

    def hidden(win, own, labels_win) -> bool:
        # the core, whose 3x3 windows lie inside: at the edge the step to the scene is
        # detail of the frame's own (unless the core is too small to read)
        core = ndimage.binary_erosion(own, _SQUARE)
        if core.sum() >= CORE_LEAST:
            own = core
        energies = [
            gain**2 * float((_detail(g[win])[own & ok[win]] ** 2).mean())
            for g, ok, gain in neighbours
            if ok[win][own].any()
        ]
        if not energies:
            return False
        # strictly less: a region as flat as neighbours without detail hides nothing
        return float((_detail(frame[win])[own] ** 2).mean()) < HIDDEN * float(np.median(energies))

    return _kept(mask, 2, hidden)


def whole_blotches(
    G: np.ndarray,
    scores: dict,
    t: int,
    low: np.ndarray,
    found: np.ndarray,
    smallest: float,
    threshold: float,
    search: int,
    neighbours,
) -> np.ndarray:
    """Frame t's blotches among the low-level fragments `low` (H, W) that lie 3 px or more
    from `found` (blotches and scratches so far), as the module text says; smallest: the
    fewest pixels a fragment has; neighbours(): the compensated neighbours as
    hides_detail reads them, asked for only where a region's mean passed."""
    both, res, sigma = scores["both"][t], scores["res"][t], scores["sigma"][t]
    level, area = scores["region_noise"][t]
    away = both & ~dilate(found, 2)
    labels, n = ndimage.label(low & away)
    if n == 0:
        return np.zeros_like(low)
    idx = np.arange(1, n + 1)
    size = ndimage.sum_labels(np.ones(low.shape, np.float32), labels, idx)
    keep = np.concatenate([[False], size >= smallest])
    # each fragment's side: the sign most of its pixels' residuals take
    votes = np.bincount(labels.ravel(), weights=np.sign(res).ravel(), minlength=n + 1)
    side = np.where(keep, np.sign(votes), 0.0)[labels]
    grown = np.zeros_like(low)
    for s in (-1.0, 1.0):
        seed = side == s
        if seed.any():
            lean = (s * res >= WHOLE_GROW * sigma) & away
            grown |= dilate(seed, WHOLE_REACH, within=seed | lean)
    labels, n = ndimage.label(grown)
    if n == 0:
        return grown
    idx = np.arange(1, n + 1)
    size = ndimage.sum_labels(np.ones(low.shape, np.float32), labels, idx)
    z = np.abs(ndimage.mean(res, labels, idx)) / (level * np.sqrt(area / size))
    z = np.concatenate([[0.0], z]).astype(np.float32)
    cand = (z >= WHOLE_Z)[labels] & (labels > 0)
    if not cand.any():
        return cand
    # the detail test first: it is cheap on windows and takes most flow errors
    cand = hides_detail(G[t], neighbours(), cand)
    if not cand.any():
        return cand
    cand = _ring_check(cand, both, res, sigma, scores["flows"][t], scores["bridge"][t])
    # the local-noise check on the region's mean, scaled to the threshold it reads
    cand = _local_noise_check(cand, z[labels] * (threshold / WHOLE_Z), res, sigma, threshold)
    cand = _tail_check(cand, dilate(cand | found, 2), res, area, both)
    return _motion_check(cand, G, t, res, search, sigma, threshold)
