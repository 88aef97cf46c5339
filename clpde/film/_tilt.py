"""Lines that are not scratches: long thin detections leaning off the vertical, and lines
along the frame's left or right border.

A line scratch is vertical: the film slides down through the gate, so what scratches it
runs along the film (a slow drift from frame to frame, never a slant within one). Compact
dirt is not long and thin. What is a long thin straight line leaning off the vertical
within one frame is scene structure the motion did not follow: a pole or a wire seen
through a car's window, passing in a frame or two (carphone, the widened calibration half
of benchmarks/film_corpus.py: pathological motion, which the neighbours' agreement cannot
tell from dirt). Such a component of either kind is dropped (do no harm).

Measured by a component's second moments: its long axis's length over its width (ASPECT)
and the axis's lean, columns per row (TILT). Chosen on the calibration half (docs/film.md,
"Leaning lines"): the false alarms there lean 0.17-0.28 with aspect 6.2 and more; true
scratches lean 0.05 at most, true blotches with aspect 5.5 or less.

A line within BORDER columns of the frame's left or right border has one flank only (the
line response reads 3-4 columns either side): it cannot be told from the frame's own edge.
A dark column fixed to the frame (carphone's first column, a codec's or scanner's border)
against a moving scene reads in the temporal residual as a line fixed to the film, a
scratch; the fill then pastes the scene over the border (0.57% of a frame's pixels changed,
the widened calibration half). Such a scratch component is dropped.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

TILT = 0.1  # columns per row (about 6 degrees): a scratch leans less
ASPECT = 6.0  # long axis over short: compact dirt is shorter
SMALLEST = 12  # px: fewer pixels give no reliable axis
BORDER = 5  # columns: a line nearer the border has its flank outside the frame


def leaning(mask: np.ndarray) -> np.ndarray:
    """The 8-connected components of a bool (H, W) mask that are long thin lines leaning
    off the vertical (spanning 2 ASPECT rows or more: a lean is read along rows): bool
    (H, W).

    Examples
    --------
    >>> m = np.zeros((60, 60), bool)
    >>> for y in range(10, 50):
    ...     m[y, 10 + y // 4 : 12 + y // 4] = True  # leans 0.25 columns a row
    ...     m[y, 45:47] = True  # upright
    >>> lean = leaning(m)
    >>> bool(lean[30, 17]), bool(lean[30, 45])
    (True, False)
    """
    labels, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
    out = np.zeros(mask.shape, bool)
    for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
        own = labels[sl] == idx
        ys, xs = np.nonzero(own)
        if len(ys) < SMALLEST or ys.max() - ys.min() < 2 * ASPECT:
            continue
        cov = np.cov(np.stack([ys, xs]).astype(np.float64))
        w, v = np.linalg.eigh(cov)  # ascending: v[:, 1] the long axis (y, x)
        if w[1] < ASPECT**2 * max(w[0], 1 / 12):  # a pixel's own spread: 1/12
            continue
        ay, ax = v[:, 1]
        if abs(ax) > TILT * abs(ay):
            out[sl] |= own
    return out


def at_border(mask: np.ndarray) -> np.ndarray:
    """The 8-connected components of a bool (H, W) mask whose mean column lies within
    BORDER columns of the frame's left or right border: bool (H, W).

    Examples
    --------
    >>> m = np.zeros((40, 30), bool)
    >>> m[5:35, 1] = m[5:35, 15] = m[5:35, 27] = True
    >>> np.nonzero(at_border(m)[20])[0].tolist()
    [1, 27]
    """
    labels, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
    if n == 0:
        return np.zeros(mask.shape, bool)
    nx = mask.shape[1]
    cols = np.broadcast_to(np.arange(nx, dtype=np.float64), mask.shape)
    mean = np.asarray(ndimage.mean(cols, labels, np.arange(1, n + 1)))
    edge = (mean < BORDER) | (mean > nx - 1 - BORDER)
    return np.concatenate([[False], edge])[labels]
