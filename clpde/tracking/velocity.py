"""The velocity corrected by the result where the match was wrong (issue 35, trackwide).

A frame's match can lock a few px off the object (a smooth, turning object over a busy
ground: the photo corpus' deform-40, calibration half, matched 3.6 px off at a peak of
0.46) while the appearance term still carries the contour onto the object: the result is
right, but the velocity, read from the match, is not. The velocity is the next frame's
prior and the yardstick of its jump check (`follow._jumped`), so the error grows: the
wrong place is searched, the true one is refused as a jump, and the object is lost a few
frames on. Where the result, whole (its area within RESULT_AREA of the prediction's) and
in sight (not hidden), lies more than RESULT_OFF px from the prediction, the velocity takes
that difference in.

(Tried first, not taken, docs/tracking.md "A mislocked match"): the forward-backward
consistency of a jump (the landed pixels matched back into the previous frame) instead
of, or besides, the jump's margin: a smooth object's weak true match comes back
inconsistent, and a look-alike over a patterned wall consistent.)
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

# The result's centre farther than this from the prediction's (px, either axis) corrects
# the velocity: chosen on the widened calibration half (1.5 and 2 the same tracks).
RESULT_OFF = 2.0
# ... where the result's area is within this share of the prediction's (a leak or a loss
# moves the centre without any motion).
RESULT_AREA = 0.15


def corrected(velocity, predicted: np.ndarray, result: np.ndarray, hidden: bool) -> np.ndarray:
    """The velocity (dy, dx) after a frame whose predicted whole shape was `predicted` and
    whose result is `result`: plus the result's offset from the prediction where it is
    whole, in sight and more than RESULT_OFF px off; else as it was."""
    velocity = np.asarray(velocity, np.float64)
    if hidden or not result.any() or not predicted.any():
        return velocity
    if abs(result.sum() / predicted.sum() - 1) > RESULT_AREA:
        return velocity
    off = np.subtract(ndimage.center_of_mass(result), ndimage.center_of_mass(predicted))
    return velocity + off if np.abs(off).max() > RESULT_OFF else velocity
