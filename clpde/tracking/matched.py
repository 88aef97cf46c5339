"""motion='image''s choice of the object's pixels that its motion is matched on (issue 35).

A piece of an occluder or of the background that the contour took in would pull the match
to its own (lack of) motion: the pixels that look like the surroundings are left out. But
where the appearance classified none of the last result right, its mild preferences say
nothing, and a choice by grey level biases the fit (on a graded object, grey-14's, the
affine fit took a stretch for the shift, and the contour leaked into the ground): only
the pixels that clearly look like the surroundings are left out there.
"""

from __future__ import annotations

import numpy as np

# The log odds of the surroundings above which a pixel is left out where the appearance's
# reliability is 0 (else above 0). Chosen on the photo corpus' calibration half
# (docs/tracking.md, "A look-alike ground"): 0.5 grey-14 0.638, 1.0 0.655.
UNRELIABLE_CLEAR = 1.0


def matched_pixels(
    mask: np.ndarray, looks_ratio: np.ndarray | None, reliability: float
) -> np.ndarray:
    """The pixels of the result `mask` that the object's motion is matched on: those whose
    appearance log odds of the surroundings (`looks_ratio`; None: all of them) are below 0,
    or below UNRELIABLE_CLEAR where the appearance's `reliability` is 0."""
    if looks_ratio is None:
        return mask
    return mask & (looks_ratio < (0.0 if reliability > 0 else UNRELIABLE_CLEAR))
