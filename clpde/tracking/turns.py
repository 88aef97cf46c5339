"""Parts that turn (issue 35, trackturn): the object's motion carries its whole shape, so a
part that moves otherwise (a walker's leg turning about the knee) is predicted where the
body's motion puts it, and the prediction's prior holds the contour there. Here the shape
is split into a few parts along its principal axis; each part gets its own affine motion
(a whole-pixel search near where the whole motion takes it, then appearance._refine's
Lucas-Kanade steps on the part and a rim, so that it can turn), and a part is carried by
it only where that explains the part's pixels clearly better than the whole motion does
(`part_maps`) and the frame looks more like the object where it lands (`look_better`).
Elsewhere, and whenever the object may be hidden (follow.py's caller), the whole motion
carries it, so that the occlusion rule still reads the lost part.

(Branch tracklimb, docs/tracking.md "A motion per part", tried a shift per part: a leg that
turns at the knee matched no shift there.)
"""

from __future__ import annotations

import numpy as np

from .appearance import MATCH_FLOOR, _refine, bilinear, box, dilate, inverse, match_shift
from .levelset import signed_distance
from .occlusion import LOST
from .rigid import rigid_fit

# The shape's parts: BANDS bands of equal area along its principal axis, each split in COLS
# across it (a walker: head, body, hips, legs; left and right). Each part is matched with a
# RIM px ring of its surroundings (a leg's inside is often plain, its outline is not); its
# whole-pixel search reaches RADIUS px from where the whole motion takes it.
BANDS, COLS, RIM, RADIUS = 4, 2, 2, 8
# A part's own map is taken where its correlation (part and rim, the maps read with
# sub-pixel accuracy) beats the whole motion's for it by MARGIN, where it moves some pixel
# of the part MOVED px or more off the whole motion, and where the part's own pixels (no
# rim) prefer it too. (tracklimb's settings; around them, on the calibration half's
# footage: margin 0.05-0.2, rim 1-3, radius 6-8 and 3-5 bands all kept footage-0 at 0.83 or
# more, against 0.80 without parts; radius 12 0.80.)
MARGIN = 0.1
MOVED = 2.0
# ... and at least the whole object's correlation or FLOOR, whichever is lower: a leg with its
# rim of lawn matches less well than a body of 5000 px (footage-2, calibration: the leg
# turning at frame 2, 0.74 against the whole's 0.90). Chosen on the calibration half of the
# photo corpus (docs/tracking.md, "Parts that turn"): 0.6-0.7 the same, 0.5 and 0.75 lower.
FLOOR = 0.6
# Parts of fewer pixels (the rim left out) are not fitted: six parameters on a part of a
# small, faintly textured object fit its rim of busy ground (tests/tracking/
# test_track_inside_match.py's 14 px disc, parts of 70-80 px: min IoU 0.847 -> 0.788 with
# 40, tracklimb's). Chosen on the calibration half of the photo corpus: 100 lost deform-10
# (0.968 -> 0.955), 120-150 change only the walkers, 175 / 200 gave back footage-0's gain
# (0.831 / 0.800 against 0.871).
MIN_PART = 120
# Lucas-Kanade steps per part
STEPS = 6
# The part's map: appearance._refine's affine fit ("affine"), rigid.rigid_fit's turn and
# shift ("rigid"), or both from each start, the better correlation kept ("both"). Chosen
# on the widened calibration half (docs/tracking.md, "The appearance believed where it
# earned it"): "rigid" alone footage-0 0.871 / 0.906 -> 0.888 / 0.919 but footage-2
# 0.836 / 0.907 -> 0.835 / 0.890; "both" 0.889 / 0.919 and 0.836 / 0.906, the other 106
# sequences within 0.001.
FIT = "both"


def split_parts(shape: np.ndarray, bands: int = BANDS, cols: int = COLS) -> np.ndarray:
    """(H, W) int labels (0 outside the shape, 1.. the parts): the shape's pixels in `bands`
    bands of equal area along its principal axis, each split in `cols` of equal area across
    it."""
    pts = np.array(np.nonzero(shape), np.float64)
    q = pts - pts.mean(axis=1, keepdims=True)
    _, v = np.linalg.eigh(q @ q.T)
    major, minor = v[:, 1] @ q, v[:, 0] @ q
    band = np.minimum((np.argsort(np.argsort(major)) * bands) // len(major), bands - 1)
    part = np.zeros(len(major), np.int64)
    for b in range(bands):
        sel = np.flatnonzero(band == b)
        rank = np.argsort(np.argsort(minor[sel]))
        part[sel] = b * cols + np.minimum((rank * cols) // max(len(sel), 1), cols - 1)
    labels = np.zeros(shape.shape, np.int64)
    labels[shape] = part + 1
    return labels


def _crop(image, rows, cols):
    """image (C, H, W) at the rows and columns given, the edge repeated beyond the frame."""
    h, w = image.shape[-2:]
    return image[:, np.clip(rows, 0, h - 1)[:, None], np.clip(cols, 0, w - 1)[None, :]]


def _centre_shift(a, c):
    """Where the motion `a` (cur -> prev coordinates) takes the point c of prev: the shift."""
    return np.linalg.solve(a[:, :2], c - a[:, 2]) - c


def _mean(mask):
    return np.array(np.nonzero(mask), np.float64).mean(axis=1)


def ncc_by(prev, cur, mask, a) -> float:
    """The normalised correlation of prev's pixels under `mask` with cur read (bilinear)
    where the motion `a` (cur -> prev coordinates) takes them, the channels pooled."""
    pts = np.array(np.nonzero(mask), np.float64)
    ahead = inverse(a)
    p = np.asarray(prev)[:, mask]
    c = bilinear(np.asarray(cur, np.float64), np.tensordot(ahead[:, :2], pts, 1) + ahead[:, 2:])
    p = p - p.mean(axis=1, keepdims=True)
    c = c - c.mean(axis=1, keepdims=True)
    return float((p * c).sum() / np.sqrt(max((p * p).sum() * (c * c).sum(), 1e-12)))


def _search(prev, cur, use, base):
    """The whole-pixel shift of prev's pixels `use` within RADIUS of `base` that matches
    cur best (match_shift over the part's box)."""
    r = RADIUS
    where = box(use, r + 1)
    rows = np.arange(where[0].start, where[0].stop)
    cols = np.arange(where[1].start, where[1].stop)
    d = match_shift(
        _crop(prev, rows, cols),
        _crop(cur, rows + base[0], cols + base[1]),
        use[where].astype(np.float64),
        reach=r,
        within=r,
    )
    return base + d


def part_maps(prev, cur, shape, pixels, a, grey=None):
    """[(part mask, map)]: the parts of `shape` (prev's) whose own affine map (cur -> prev
    coordinates) explains them clearly better than the whole motion `a` (MARGIN), and as
    clearly as the whole object matches (or FLOOR); a part that its map moves less than MOVED px off
    `a` is left out, as is one that its map leaves standing still (a still occluder in front
    of it: the occlusion rule's), or one whose own pixels, without the rim, do not prefer
    the map. `pixels`: the object's pixels the whole motion was matched on; `grey`: prev's
    appearance.gradients and cur's grey level, or None. Empty where the whole object matches
    nothing (below MATCH_FLOOR)."""
    prev, cur = np.asarray(prev), np.asarray(cur)
    whole = ncc_by(prev, cur, pixels, a)
    if whole < MATCH_FLOOR:
        return []
    labels = split_parts(shape)
    out = []
    for k in range(1, labels.max() + 1):
        part = labels == k
        own = part & pixels
        if own.sum() < MIN_PART:
            continue
        # with its rim, but not the other parts
        use = dilate(own, RIM) & ~(shape & ~part)
        base = np.rint(_centre_shift(a, _mean(own))).astype(np.int64)
        at_whole = ncc_by(prev, cur, use, a)
        best, score = None, -np.inf
        # Lucas-Kanade from the whole motion's shift and from the part's own best shift: a
        # turn of a few degrees is found from the first, a leg 10 px off from the second
        # (FIT: six parameters, or three, a turn and a shift, that cannot shear a small part
        # onto its rim)
        for d in {tuple(base), tuple(_search(prev, cur, use, base))}:
            fits = []
            if FIT in ("affine", "both"):
                fits.append(_refine(prev, cur, use, np.asarray(d, np.float64), STEPS, grey))
            if FIT in ("rigid", "both"):
                fits.append(rigid_fit(prev, cur, use, np.asarray(d, np.float64), STEPS, grey))
            for b in fits:
                s = ncc_by(prev, cur, use, b)
                if s > score:
                    best, score = b, s
        if not score >= max(at_whole + MARGIN, min(whole, FLOOR)):
            continue
        pts = np.array(np.nonzero(part), np.float64)
        mine = np.tensordot(inverse(best)[:, :2], pts, 1) + inverse(best)[:, 2:]
        theirs = np.tensordot(inverse(a)[:, :2], pts, 1) + inverse(a)[:, 2:]
        if np.abs(mine - theirs).max() < MOVED or np.abs(mine - pts).max() <= 1:
            continue
        if ncc_by(prev, cur, own, best) < ncc_by(prev, cur, own, a):
            continue
        out.append((part, best))
    return out


def look_better(parts, a, ratio, warp):
    """The parts (part mask, map) that land where the frame looks more like the object by
    their own map than by the whole motion `a`: the appearance's mean log odds of the
    surroundings, `ratio`, lower there. (A second, independent cue: a correlation of a few
    hundred pixels can beat the whole's at a wrong place, on a look-alike or a pan.)"""
    kept = []
    for part, b in parts:
        u = signed_distance(part)
        rigid = warp(u, a) < 0
        own = warp(u, b) < 0
        if own.any() and rigid.any() and ratio[own].mean() < ratio[rigid].mean():
            kept.append((part, b))
    return kept


def carry(shape_u, a, parts, warp):
    """The level set `shape_u` carried by the motion `a`, each of `parts` (part mask, map)
    by its own map: the union of the pieces' carried level sets."""
    rest = shape_u
    pieces = []
    for part, b in parts:
        u_part = signed_distance(part)
        rest = np.maximum(rest, -u_part)
        pieces.append(warp(np.maximum(shape_u, u_part), b))
    out = warp(rest, a)
    for u in pieces:
        out = np.minimum(out, u)
    return out


def predict(follower, t, a, pixels, predicted, warp):
    """follow.ObjectFollower's whole shape carried by `a` (cur -> prev coordinates) into
    frame t, its parts that move otherwise by their own maps (`part_maps`, then
    `look_better` on the frame's log odds): its level set; None where no part moves
    otherwise, where the result would be empty or everything, or where at least
    occlusion.LOST of the shape carried by `a` (`predicted`) was seen still
    (occlusion.seen_still: the first frame behind an occluder, whose lost part must stay in
    the prediction for the occlusion rule)."""
    f, seen = follower, follower._seen
    if seen is not None and seen.sum() >= max(LOST * predicted.sum(), 1):
        return None
    grey = (f._gradients(t - 1), f._gradients(t)[0])
    parts = part_maps(f.looks[t - 1], f.looks[t], f.shape, pixels, a, grey)
    if parts:
        # the frame's log odds (the ring is learned by the follower's own call after)
        f._bins, f._bins_t, back = f.model.bins(f.looks[t]), t, f.model.back
        ratio, f.model.back = f.model.log_ratio(f._bins, predicted), back
        parts = look_better(parts, a, ratio, warp)
    if not parts:
        return None
    u = carry(f.shape_u, a, parts, warp)
    inside = u < 0
    return u if inside.any() and not inside.all() else None
