"""motion='image''s occlusion (issue 35): the object's whole shape kept apart from its
visible part while something still hides it.

The evidence that a lost part is hidden, not gone (`hidden_by_still`): the result lost part
of the predicted shape, that part looks like the surroundings, not like the object, and the
contour's cut through the object stays where it was in the last frame while the object
moved (an occluder's edge does not move with the object; a shrinking or deforming
object's outline does). While hidden, the whole shape is carried by the motion fitted on
the visible part and only its visible part is the result (`visible_pieces`): pieces that
look like the object within the whole shape, none on the occluder.

Where the appearance cannot tell the occluder from the object (grey footage: a bar of the
object's grey level), the frames can (`seen_still`): an occluder's pixels stay the same
from one frame to the next while the object's motion does not explain them.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .appearance import box, dilate, erode

# A result missing at least this share of the predicted shape has lost part of it.
LOST = 0.04
# The share of the cut (the result's pixels next to the lost part) that must lie within
# 1 px of the last frame's outline: the cut stays where it was.
STILL_CUT = 0.4
# A hidden object stays hidden while at least STILL of its lost part is still (its pixels
# change by less than STILL_NOISE times the noise): the occluder is still there.
STILL, STILL_NOISE = 0.8, 3.0
# The whole shape is laid on the visible outline by a shift of at most this many px.
ALIGN = 3
# The object must have moved at least this many px for a still cut to tell anything
# (chosen on the calibration halves: 1.5 took a synthetic textured object's loss for an
# occlusion, textured class 0.731 -> 0.690; photo occlusion 0.935 either way).
MOVED = 3.0
# A pixel of the prediction shows something still, not the moving object (`seen_still`),
# where over its 3x3 patch the two frames differ by less than SEEN_STILL times what the
# noise alone gives, while the previous frame carried by the object's motion misses it by
# more than SEEN_MISS times that: a still occluder in front of the object, or the ground
# it moved off. It needs no appearance (in grey footage a bar can look like the object).
SEEN_STILL, SEEN_MISS, SEEN_REACH = 2.0, 4.0, 2


def lost_part(predicted: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The predicted shape's pixels more than 1 px from the result: what it lost."""
    return predicted & ~dilate(mask, 1)


def hidden_by_still(
    lost: np.ndarray,
    mask: np.ndarray,
    previous: np.ndarray,
    ratio: np.ndarray | None,
    shift: np.ndarray,
) -> bool:
    """Whether the lost part of the prediction (`lost`) is hidden by something still:
    it is at least LOST of the prediction, looks like the surroundings (`ratio`, the
    appearance's log odds, positive there on average; None: no appearance, not asked), the
    object moved at least MOVED px (`shift`), and at least STILL_CUT of the cut (`mask`'s
    pixels next to `lost`) lies within 1 px of the `previous` result's outline."""
    if np.hypot(*shift) < MOVED or not lost.any() or not previous.any():
        return False
    if ratio is not None and not ratio[lost].mean() > 0:
        return False
    cut = mask & dilate(lost, 2)
    if cut.sum() < 3:
        return False
    outline = previous & ~erode(previous)
    return float((cut & dilate(outline, 1)).sum()) >= STILL_CUT * float(cut.sum())


def seen_still(
    before: np.ndarray,
    after: np.ndarray,
    carried: np.ndarray,
    noise: float,
    hidden: np.ndarray | None = None,
) -> np.ndarray:
    """Where frame `after` shows something still, not the moving object: the 3x3 patches
    that differ from frame `before` by less than SEEN_STILL times what noise of standard
    deviation `noise` gives, and by more than SEEN_MISS times that from `carried` (`before`
    carried by the object's motion, over the same box grown by SEEN_REACH px) at every
    shift within SEEN_REACH px (the motion fitted on a sliver can be off by a px or two; a
    smooth patch of the object then matches nearby). Also the still patches of what was
    seen still before (`hidden`, (h, w)): an occluder stays where it was, and the
    object behind it has not come out there. (C, h, w) arrays."""
    expected = 2.0 * noise / np.sqrt(np.pi) * after.shape[0]
    still = ndimage.uniform_filter(np.abs(after - before).sum(axis=0), 3)
    still = still < SEEN_STILL * expected
    seen = still.copy()
    if not seen.any():
        return seen
    r = SEEN_REACH
    h, w = after.shape[1:]
    shifts = [(dy, dx) for dy in range(-r, r + 1) for dx in range(-r, r + 1)]
    misses = np.stack(
        [
            np.abs(after - carried[:, r + dy : r + dy + h, r + dx : r + dx + w]).sum(axis=0)
            for dy, dx in shifts
        ]
    )
    miss = ndimage.uniform_filter(misses, (1, 3, 3)).min(axis=0)
    seen &= miss > SEEN_MISS * expected
    return seen | (still & hidden) if hidden is not None else seen


def still_share(before: np.ndarray, after: np.ndarray, where: np.ndarray, noise: float) -> float:
    """The share of `where`'s pixels that did not change between the frames `before` and
    `after` ((C, H, W)) by more than STILL_NOISE times the noise's standard deviation
    `noise`, summed over the channels: an occluder stays still; where the object was, or
    moved on, the pixels change."""
    if not where.any():
        return 0.0
    change = np.abs(after[:, where] - before[:, where]).sum(axis=0)
    return float((change < STILL_NOISE * noise * after.shape[0]).mean())


def align(whole: np.ndarray, mask: np.ndarray, lost: np.ndarray) -> np.ndarray:
    """The whole-pixel shift (dy, dx), within ALIGN px, that best lays the predicted
    `whole` shape's outline on the result `mask`'s own outline (away from the cut next to
    the `lost` part): the chamfer distance's least mean. The motion fitted on a small or
    plain visible part can miss; the visible outline still tells where the whole is."""
    own = mask & ~erode(mask) & ~dilate(lost, 2)
    if own.sum() < 8:
        return np.zeros(2)
    edge = whole & ~erode(whole)
    dist = ndimage.distance_transform_edt(~edge)
    h, w = mask.shape
    ys, xs = np.nonzero(own)
    best, shift = np.inf, np.zeros(2)
    for dy in range(-ALIGN, ALIGN + 1):
        for dx in range(-ALIGN, ALIGN + 1):
            y, x = np.clip(ys - dy, 0, h - 1), np.clip(xs - dx, 0, w - 1)
            # a faint preference for small shifts among equals
            cost = dist[y, x].mean() + 0.01 * (abs(dy) + abs(dx))
            if cost < best:
                best, shift = cost, np.array([dy, dx], np.float64)
    return shift


def visible_pieces(mask: np.ndarray, whole: np.ndarray, ratio: np.ndarray | None) -> np.ndarray:
    """The result's visible part while the object is hidden in part: given the
    appearance's log odds `ratio`, its pixels that look like the object (the log odds
    smoothed over 1 px negative; holes filled: a dark spot of the object is not an
    occluder), in pieces overlapping the `whole` shape. The occluder looks like itself,
    not like the object: nothing stays on it."""
    if ratio is not None and mask.any():
        where = box(mask, 4)
        looks = ndimage.gaussian_filter(ratio[where], 1.0) < 0
        part = np.zeros(mask.shape, bool)
        part[where] = ndimage.binary_fill_holes(mask[where] & looks)
        mask = part
    labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
    if n == 0:
        return mask
    keep = ndimage.maximum(whole, labels, np.arange(1, n + 1)) > 0
    return keep[labels - 1] & (labels > 0)
