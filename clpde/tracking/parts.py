"""Parts of an object that move otherwise than the whole (issue 35, trackfoot): a walker's
swinging leg lies off where the object's overall motion carries the body, and the
prediction's prior would hold the contour back from it although the appearance says object
there. `grow_parts` grows the prediction by such pieces (follow.py: for the prior and the
result's bound)."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .appearance import box, dilate

# Where the appearance clearly says object (its believed log odds, smoothed over 1 px,
# below -PART_LOOKS) on a piece next to the prediction, thicker than 2 px (an opening) and
# reaching at least PART_FAR px out of it, within PART_REACH px, the prediction grows by
# that piece: its prior and the result's bound (follow.GROW) start from the grown shape. (A
# 1-2 px rim of a blurred edge would otherwise grow the contour a little every frame.)
# Chosen on the calibration half of the photo corpus (docs/tracking.md, "Parts that move
# otherwise").
PART_REACH, PART_LOOKS, PART_FAR = 12, 1.0, 3


def grow_parts(predicted: np.ndarray, evidence: np.ndarray) -> np.ndarray:
    """The predicted shape with the pieces next to it that clearly look like the object
    (`evidence`: log odds of the surroundings, the appearance's as far as it is believed):
    what the object's overall motion did not carry there (a limb that swings). A piece is
    taken where, smoothed over 1 px and opened by 1 px, it lies below -PART_LOOKS, touches
    the prediction and reaches PART_FAR px or more out of it, within PART_REACH px."""
    if not PART_REACH or not predicted.any():
        return predicted
    where = box(predicted, PART_REACH + 4)
    part = predicted[where]
    looks = ndimage.gaussian_filter(evidence[where], 1.0) < -PART_LOOKS
    clear = ndimage.binary_opening(looks & dilate(part, PART_REACH) & ~part)
    labels, n = ndimage.label(clear, structure=np.ones((3, 3)))
    if not n:
        return predicted
    touch = np.unique(labels[dilate(part, 1)])
    far = np.unique(labels[~dilate(part, PART_FAR - 1)])
    keep = np.intersect1d(touch, far)
    grown = predicted.copy()
    grown[where] |= np.isin(labels, keep[keep > 0])
    return grown
