"""The appearance believed where it earned it, not only as a whole (issue 35, trackfoot).

follow.py scales the appearance's evidence by one number, 1 - e / RELIABLE_ERROR, e the
share of the last result that the appearance misclassified (its interior looking like the
surroundings, its ring looking like the object). A small object beside a look-alike (an
olive fruit half over blue sky, half against a beige wall: the photo corpus' deform-4,
calibration half) misclassifies 10-14% of its ring, all of it on the wall's side, and the
appearance is then believed nowhere: the contour, held by the prediction alone, lags the
deforming outline on the sky's side too. Here the same error is measured near each pixel
(Gaussian-weighted over SIGMA px of the last result's interior and ring), and the evidence
is believed there as far as the neighbourhood earned it: never less than the whole's
trust, and the whole's alone where too little of the last result was measured nearby.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .appearance import dilate, erode

# The neighbourhood's scale (px, the Gaussian's sigma).
SIGMA = 6.0
# The local error is read only where the measured pixels' Gaussian weight is at least this
# (a pixel on the ring of a straight contour has about 0.5): elsewhere the whole's trust.
MEASURED = 0.2
# Only where at most this share of the result's interior looks like the surroundings: the
# misclassified pixels are then the ground's (a look-alike beside the object), not the
# object's own (a shadow or a flicker over it, tests/tracking/test_track_image.py: 2-45%
# of the interior, whose mild wrong evidence, believed where the ring is clean, eroded
# the disc, min IoU 0.77).
INNER_CLEAN = 0.01


def believed(ratio: np.ndarray, mask: np.ndarray, scale: float):
    """How far the appearance's log ratio can be believed, from how it classified a
    frame's result: its error, the share of the mask's interior (2 px in) that looks like
    the surroundings plus the share of the ring 2-8 px out that looks like the object, e;
    1 - e / scale, within [0, 1] (0: always 1). (A look-alike beside the object, a shadow
    over it: its pixels look like something else, and the evidence would erode it.) With
    it, the same error near each pixel (`trust_map`'s: the misclassified share and the
    measured weight, each smoothed over SIGMA px), or None where the interior itself is
    misclassified by more than INNER_CLEAN, or where nothing is measured."""
    if not scale:
        return 1.0, None
    inner = erode(mask, 2)
    near = dilate(mask, 2)
    ring = dilate(near, 6) & ~near
    if not inner.any() or not ring.any():
        return 1.0, None
    inside, outside = float((ratio[inner] > 0).mean()), float((ratio[ring] < 0).mean())
    whole = float(np.clip(1 - (inside + outside) / scale, 0, 1))
    if not SIGMA or inside > INNER_CLEAN:
        return whole, None
    bad = (inner & (ratio > 0)) | (ring & (ratio < 0))
    weight = ndimage.gaussian_filter((inner | ring).astype(np.float64), SIGMA)
    bad = ndimage.gaussian_filter(bad.astype(np.float64), SIGMA)
    return whole, (bad, weight)


def trust_map(trust: float, errors, scale: float):
    """The appearance's trust per pixel: 1 - local error / scale where enough was measured
    (`errors`, believed's), never below the whole's `trust`; `trust` itself where errors
    is None or the whole is believed."""
    if errors is None or trust >= 1 or not scale:
        return trust
    bad, weight = errors
    local = np.clip(1 - bad / np.maximum(weight, 1e-9) / scale, 0, 1)
    return np.where(weight >= MEASURED, np.maximum(local, trust), trust)
