"""The film detector's last step on a frame's blotches (clpde.film.detect): the ring of
pixels around each blotch, taken where the ring as a whole carries the blotch's sign.

A soft rim changes its pixels by 6-15 grey levels under grain of 2-5: per pixel it cannot
be told from the grain (clpde.film._grow takes only the rim pixels in the frame's top 5%
of residuals). A ring as a whole can: its mean residual, on its region's side, is compared
with the deviation of a mean over its n pixels, level * sqrt(area / n) (the residual's
level and the grain's correlation area measured on the frame, as for faint regions in
clpde.film._grow._regions_found). Where the ring passes, its pixels whose own residual
leans the region's way by PIXEL_SHARE of the grain join the region. One ring only: past the
rim the ring of a clean surround passes by chance alone, and a second ring added false
pixels for no true ones (benchmarks/film_missed.py's calibration half).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

# deviations of the ring's mean a ring must reach on its region's side (one-sided, about
# 2% of clean rings by chance); chosen on the calibration half: 1.5 took more false pixels
# for no better repair, 2.5 and 3 found less of the rims (docs/film.md, "Blotch rims")
RING_Z = 2.0
# a ring pixel joins where its own residual leans the region's way by this share of sigma
PIXEL_SHARE = 0.5

_CROSS = ndimage.generate_binary_structure(2, 1)


def ring_rims(
    blotch: np.ndarray,
    taken: np.ndarray,
    res: np.ndarray,
    has_nb: np.ndarray,
    sigma: float,
    region_noise: tuple[float, float],
) -> np.ndarray:
    """blotch (H, W) with the ring 1 px around each region taken where it passes (see the
    module text). taken: pixels never to take (scratches); res: the frame minus its trusted
    neighbours' median; has_nb: where res is defined; sigma: the grain's level;
    region_noise: the residual's level and the grain's correlation area (film_scores)."""
    if not blotch.any():
        return blotch
    level, area = region_noise
    labels, n = ndimage.label(blotch)
    # each region's side: the sign most of its pixels' residuals take
    votes = np.bincount(labels.ravel(), weights=np.sign(res).ravel(), minlength=n + 1)
    sign = np.sign(votes)
    sign[0] = 0.0
    # the ring: pixels next to a region (a pixel between two takes the higher label's)
    near = ndimage.grey_dilation(labels, footprint=_CROSS)
    ring = np.where((near > 0) & ~blotch & has_nb & ~taken, near, 0)
    lean = sign[ring] * res  # the residual on the region's side
    count = np.bincount(ring.ravel(), minlength=n + 1).astype(np.float64)
    total = np.bincount(ring.ravel(), weights=lean.ravel(), minlength=n + 1)
    count = np.maximum(count, 1.0)
    z = total / count / (level * np.sqrt(area / count))
    passed = z >= RING_Z
    passed[0] = False
    return blotch | (passed[ring] & (lean > PIXEL_SHARE * sigma))
