"""motion='image''s motion and appearance (issue 35): where the object went, measured from the
image, and what it looks like against its surroundings.

- `object_motion`: the previous mask's motion between two frames, an affine map found in
  two steps: a masked normalised cross-correlation over every shift within `reach` px
  (FFT, so a 25 px-a-frame object is found from the first frame, whatever its past; where
  its peak is not clear, another local maximum that a trimmed correlation finds a clear
  match, robust_match.py: a swinging leg lowers the true match),
  then Lucas-Kanade's Gauss-Newton steps on the six affine parameters over the object and
  a 2 px rim (turns, scaling). The object's own pixels decide, not the contour's past.
  Where nothing inside the object matches (a faint flat object, a region over a still
  texture), its outline on frames smoothed of the noise (`_outline_motion`).
  Measured against dense flow (benchmarks/track_motion_compare.py, docs/tracking.md): the
  median of clpde.motion.optical_flow or of OpenCV's DIS over the object misses the
  object's centre by more than 3 px on 8% and 12% of the frame pairs at 10-26 px a frame
  (up to 13 and 17 px); this, by 0.37 px at most, at 45 ms a pair against the flow's 370.
- `AppearanceModel`: GrabCut-like colour (grey where the footage has none) and texture
  histograms of the object (learned from each frame's result, a running mean) and of its
  surroundings (a ring around the predicted contour in the new frame), and their
  log-likelihood ratio per pixel, tempered by how well the two histograms separate in the
  frame (a head in a dim car separates little: untempered, each frame's mild preference
  moves the contour a little, and the moves add up to a leak); the surroundings'
  histogram a running mean too.
- `AppearanceTerm`: that ratio as the morphing's region speed (the field kernels/tracking/
  adaptive.cl adds to the contour's speed), uploaded once per frame: the contour shrinks
  where a pixel looks like the surroundings (a textured background it would leak into, an
  occluder in front of the object) and grows where it looks like the object.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla
from scipy import fft as sfft
from scipy import ndimage

from ..fields import Field
from .fft_rows import irfft2_rows, rfft2_rows
from .levelset import LevelSet
from .robust_match import robust_shift

# motion='image''s settings, chosen on the calibration half of benchmarks/track_photo_corpus.py
# (benchmarks/track_image_search.py).
# object_motion's whole-pixel shift, where the peak is below LIGHT_CLEAR: another local
# maximum of the correlation where a trimmed correlation finds it a clear match and better
# (robust_match.py: a part that moves otherwise lowered the true match); False: the peak
ROBUST = True
REACH = 32  # px: the widest shift per frame the correlation searches
MATCH_FLOOR = 0.3  # a correlation peak below this is no match: the velocity is kept
# the affine fit replaces the sub-pixel shift only where its cost is below this share of
# the shift's
AFFINE_GAIN = 0.95
# object_motion takes the light-blind features' shift where the frames' own correlation
# there is within this of their best
LIGHT_SLACK = 0.05
# ... unless the frames' own correlation peak is at least this: so clear a match leaves
# nothing for a change of light to have moved (and one correlation a frame is saved)
LIGHT_CLEAR = 0.9
# Below LIGHT_CLEAR, the object's interior (INSIDE px in from the mask's edge, where it
# keeps INSIDE_SHARE of the mask) is matched too, and its shift taken where its peak beats
# the whole mask's by INSIDE_MARGIN and the floor (object_motion); INSIDE 0: not. Chosen on
# the calibration halves (docs/tracking.md, "Smooth objects over a busy ground"): margin
# 0.1 lost grey-4 (0.950 -> 0.92), 0.15 the synthetic textured-2 (0.790 -> 0.731), 0.3
# fast-12 (0.52); 1 px in, deform-4 stayed lost.
INSIDE, INSIDE_SHARE, INSIDE_MARGIN = 2, 0.3, 0.2
# Where nothing inside the object matches (its peak below the floor), its outline is matched:
# the object dilated by OUTLINE_RIM px on frames smoothed by a Gaussian of OUTLINE_SMOOTH px
# (object_motion). Chosen on the calibration half of benchmarks/track_corpus.py among rims
# 2, 3, 4, 6 and smoothings 0, 0.7, 1, 1.5: mean of class means 0.706 -> 0.769 (flat 0.510
# -> 0.873, slices 0.529 -> 0.584, no class lower); unsmoothed, the noise drowns a faint
# step (flat 0.578).
OUTLINE_RIM, OUTLINE_SMOOTH = 3, 1.5
APPEARANCE_WEIGHT = 1.0  # the appearance speed's largest value, px per unit time
RING = (3, 16)  # px: the surroundings' ring around the predicted contour
MEMORY = 0.5  # the object model's running mean: this share of the new frame's histogram
BINS_COLOUR, BINS_GREY, BINS_TEXTURE = 8, 24, 4
# The appearance's evidence is tempered by B / (B + SEPARATION), B the Bhattacharyya
# distance of the object's and the surroundings' histograms in the frame. Chosen on the
# calibration half of benchmarks/track_photo_corpus.py (default options, mean IoU) with
# carphone (J): 0.5 / 1 / 1.5 / 2 gave 0.850 / 0.851 / 0.857 / 0.838 and 0.820 / 0.850 /
# 0.872 / 0.870; untempered, 0.847 and 0.6.
SEPARATION = 1.5
BRIGHT_TOP = 99
# The surroundings' histogram is a running mean too, keeping this share of the last one: a
# still occluder or a walker's street seen in earlier rings is still known when the ring
# around the object holds little of it. Chosen on the calibration half of
# benchmarks/track_photo_corpus.py (mean IoU of the sequences 0.839 -> 0.858 with 0.5,
# 0.857 with 0.8; the footage clip 0.692 -> 0.819, occlude-0 0.699 -> 0.951).
BACK_MEMORY = 0.5
# (The seen background, stop 44: where a 3 px patch of the predicted object showed, to the
# noise, the grey last seen there as background, up to 3 more units of log ratio. Photo
# calibration half 0.911 -> 0.915 mean IoU of the sequences, but the synthetic corpus'
# calibration half 0.706 -> 0.668 mean of class means (stop-and-go 0.770 -> 0.626, light
# 0.741 -> 0.616): not taken.)


def box(mask: np.ndarray, margin: int):
    """The slices of `mask`'s bounding box grown by `margin` px, within the frame; None for
    an empty mask."""
    rows = np.flatnonzero(mask.any(axis=1))
    if not len(rows):
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (
        slice(max(rows[0] - margin, 0), min(rows[-1] + 1 + margin, h)),
        slice(max(cols[0] - margin, 0), min(cols[-1] + 1 + margin, w)),
    )


def dilate(mask: np.ndarray, iterations: int) -> np.ndarray:
    """ndimage.binary_dilation(mask, iterations=iterations) (iterations >= 1), computed over
    the mask's box grown by `iterations` px only (the cross reaches no farther): the same
    result, at a cost that grows with the object, not the frame."""
    out = np.zeros(mask.shape, bool)
    where = box(mask, iterations)
    if where is not None:
        # (the cross iterated k times reaches the pixels within taxicab distance k: one
        # chamfer pass instead of k dilations)
        out[where] = ndimage.distance_transform_cdt(~mask[where], metric="taxicab") <= iterations
    return out


def erode(mask: np.ndarray, iterations: int = 1) -> np.ndarray:
    """ndimage.binary_erosion(mask, iterations=iterations) over the mask's box grown by 1
    px: the same result (outside the box, and on the frame's border, it is 0 either way)."""
    out = np.zeros(mask.shape, bool)
    where = box(mask, 1)
    if where is not None:
        out[where] = ndimage.binary_erosion(mask[where], iterations=iterations)
    return out


def match_shift(
    prev, cur, weight, reach: int = REACH, prior=(0.0, 0.0), within: float | None = None
) -> np.ndarray:
    """(dy, dx), whole pixels, that best carries `prev` (C, H, W) under `weight` (H, W,
    0/1) onto `cur`: the masked normalised cross-correlation, highest over |shift| <=
    reach, with a faint preference for shifts near `prior` (and, given `within`, no farther
    than that from it). `cur` is extended by its edge values, so that an object partly out
    of the frame is still matched."""
    r = int(reach)
    # the object's box in prev, and cur's pixels within reach of it (edge values beyond)
    ys, xs = np.nonzero(weight)
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    weight = weight[y0:y1, x0:x1]
    prev = np.asarray(prev)[:, y0:y1, x0:x1]
    # (the rows and columns of cur padded by r edge values, read at the box's: no padded
    # copy of the whole frame)
    cur = np.asarray(cur)
    rows = np.clip(np.arange(y0 - r, y1 + r), 0, cur.shape[1] - 1)
    cols = np.clip(np.arange(x0 - r, x1 + r), 0, cur.shape[2] - 1)
    cur = cur[:, rows[:, None], cols[None, :]]
    h, w = weight.shape
    # room for every shift within reach without wrapping, rounded up to a fast FFT length
    shape = tuple(sfft.next_fast_len(n + 3 * r, real=True) for n in (h, w))
    n = weight.sum()
    wp = np.zeros(shape)
    wp[r : r + h, r : r + w] = weight
    den_t = 0.0
    # (the transforms skip the rows that are zero, and the inverse ones find the rows of
    # the shifts within reach only: fft_rows.py, the same bits as rfft2 / irfft2)
    fw = np.conj(rfft2_rows(wp, slice(r, r + h)))
    # every channel's frame and its squares transformed in one call, the templates in
    # another (the same values as one call each, less the calls' overhead)
    k = len(prev)
    padded = np.zeros((3 * k,) + shape)
    padded[:k, : h + 2 * r, : w + 2 * r] = cur
    np.multiply(padded[:k], padded[:k], out=padded[k : 2 * k])
    for i, p in enumerate(prev):
        t = padded[2 * k + i]
        t[r : r + h, r : r + w] = (p - (p * weight).sum() / n) * weight
        den_t += (t * t).sum()
    fcs, fsq = np.split(rfft2_rows(padded[: 2 * k], slice(0, h + 2 * r)), 2)
    fts = rfft2_rows(padded[2 * k :], slice(r, r + h))
    # correlation index k is the shift k, negative shifts wrapped around: the rows of the
    # shifts within reach
    near = np.r_[0 : r + 1, shape[0] - r : shape[0]]
    s1s = irfft2_rows(fw * fcs, near, shape)
    var_c = np.zeros(s1s.shape[1:])
    # the cross-correlations and the sums of squares summed over the channels before the
    # inverse transforms (linear): 2 inverse transforms a frame, and one per channel
    fscore, fsquares = 0.0, 0.0
    for fc, squares, ft, s1 in zip(fcs, fsq, fts, s1s, strict=True):
        var_c -= s1 * s1 / n
        fsquares = fsquares + squares
        fscore = fscore + np.conj(ft) * fc
    var_c = np.maximum(var_c + irfft2_rows(fw * fsquares, near, shape), 0)
    score = irfft2_rows(fscore, near, shape)
    ncc = np.full(shape, -np.inf)  # (the rows beyond reach: not searched)
    ncc[near] = score / np.sqrt(np.maximum(var_c * den_t, 1e-12))
    flat = np.ones(shape, bool)  # where cur's window holds no variance
    flat[near] = var_c < 1e-9 * n
    dy = np.rint(np.fft.fftfreq(shape[0], 1 / shape[0]))[:, None]
    dx = np.rint(np.fft.fftfreq(shape[1], 1 / shape[1]))[None, :]
    ncc = ncc - 0.05 * ((dy - prior[0]) ** 2 + (dx - prior[1]) ** 2) / reach**2
    ncc[(np.abs(dy) > reach) | (np.abs(dx) > reach) | flat] = -np.inf
    if within is not None:
        ncc[(np.abs(dy - prior[0]) > within) | (np.abs(dx - prior[1]) > within)] = -np.inf
    k = np.unravel_index(int(np.argmax(ncc)), shape)
    match_shift.peak = float(ncc[k])  # the match's quality, read by object_motion
    match_shift.scores = (ncc, dy, dx)  # the whole map, for robust_match.robust_shift
    return np.array([float(dy[k[0], 0]), float(dx[0, k[1]])])


def _warp(image, a, order=1):
    """image (H, W) read at A x for every output pixel x: `a` (2, 3) maps output (y, x)
    coordinates to input ones."""
    return ndimage.affine_transform(image, a[:, :2], a[:, 2], order=order, mode="nearest")


def inverse(a: np.ndarray) -> np.ndarray:
    """The inverse of the affine map a (2, 3)."""
    m = np.linalg.inv(a[:, :2])
    return np.column_stack([m, -m @ a[:, 2]])


def _ncc_at(prev, cur, weight, d) -> float:
    """The masked normalised cross-correlation of `prev` under `weight` with `cur` shifted
    by the whole pixels d (dy, dx), the channels pooled as in match_shift (cur's edge
    repeated)."""
    pts = np.array(np.nonzero(weight))
    at = np.clip(pts + np.asarray(d, np.int64)[:, None], 0, np.array(weight.shape)[:, None] - 1)
    p = np.asarray(prev)[:, pts[0], pts[1]]
    c = np.asarray(cur)[:, at[0], at[1]]
    p = p - p.mean(axis=1, keepdims=True)
    c = c - c.mean(axis=1, keepdims=True)
    return float((p * c).sum() / np.sqrt(max((p * p).sum() * (c * c).sum(), 1e-12)))


def _flat(image, mask) -> bool:
    """Whether most of the object's pixels hold one value in every channel (their median
    absolute deviation is 0): no texture inside it, noise included."""
    values = np.asarray(image)[:, mask]
    med = np.median(values, axis=1, keepdims=True)
    return bool((np.median(np.abs(values - med), axis=1) == 0).all())


def object_motion(
    prev,
    cur,
    mask,
    prior=(0.0, 0.0),
    reach: int = REACH,
    steps: int = 6,
    floor=MATCH_FLOOR,
    within=None,
    light=None,
    grey=None,
    outline=True,
):
    """The affine map (2, 3) taking frame coordinates of `cur` to those of `prev` (cur(x)
    ~ prev(A x) on the object), from the object `mask` of `prev`; prev, cur (C, H, W).
    `prior`: the last displacement (prev -> cur), which the search prefers among equals
    and which stands when the correlation's peak is below `floor`; `within`: the largest
    change of velocity searched (None: any shift within `reach`). `light`: the two frames'
    light-blind features (local contrast), whose match is taken where the frames' own
    correlation there is within LIGHT_SLACK of their best (a shadow or a flicker moves the
    frames' own best, not this one), unless the frames' own peak is LIGHT_CLEAR or more.
    `grey`: prev's `gradients` and cur's grey level where the caller keeps them (else
    found here). `outline`: where nothing inside the object matches (the peak below
    `floor`), its outline is matched (`_outline_motion`) before the velocity is kept (False:
    a low peak means the object is hidden)."""
    # the object alone: a rim takes in more of an occluder's still edge. But an object most
    # of whose pixels hold one value (a flat graphic, a saturated highlight) has nothing
    # inside to correlate: it is found by its outline, with 2 px of its surroundings
    rim = dilate(mask, 2) if _flat(prev, mask) else mask
    weight = rim.astype(np.float64)
    d = match_shift(prev, cur, weight, reach, prior, within)
    peak = match_shift.peak
    object_motion.pixels = mask  # the pixels matched, read by the caller's checks
    if INSIDE and rim is mask and peak < LIGHT_CLEAR and within is None:
        # A smooth object over a busy ground: a strip of ground the mask took in at its
        # edge outweighs the object's own faint texture in the correlation, and its match
        # (or, below the floor, none) wins. The interior alone decides where it matches
        # clearly better. (Not while hidden, `within` given: a sliver's inside is small.)
        inner = erode(mask, INSIDE)
        scores = match_shift.scores
        if inner.sum() >= INSIDE_SHARE * mask.sum():
            d_in = match_shift(prev, cur, inner.astype(np.float64), reach, prior, within)
            if match_shift.peak >= max(peak + INSIDE_MARGIN, floor):
                rim, d, peak = inner, d_in, match_shift.peak
                weight, scores = rim.astype(np.float64), match_shift.scores
                object_motion.pixels = rim
        match_shift.peak, match_shift.scores = peak, scores
    if ROBUST and floor <= peak < LIGHT_CLEAR:
        # a part that moves otherwise does not decide (robust_match.py); a clear peak has
        # no such part to have lowered it
        d = robust_shift(prev, cur, rim, *match_shift.scores)
    if light is not None and floor <= peak < LIGHT_CLEAR:
        d_light = match_shift(light[0], light[1], weight, reach, prior, within)
        if match_shift.peak >= floor and np.abs(d_light - d).max() > 0:
            if _ncc_at(prev, cur, rim, d_light) >= peak - LIGHT_SLACK:
                d = d_light
    a = None
    if peak < floor and outline:
        a = _outline_motion(prev, cur, mask, prior, reach, steps, floor, within)
    if a is not None:
        return a
    if peak < floor:
        # nothing matches (the object went behind something): it keeps its velocity
        d = np.asarray(prior, np.float64)
        return np.array([[1.0, 0.0, -d[0]], [0.0, 1.0, -d[1]]])
    return _refine(prev, cur, rim, d, steps, grey)


def _outline_motion(prev, cur, mask, prior, reach, steps, floor, within):
    """object_motion by the object's outline (None where that does not match either): the
    mask dilated by OUTLINE_RIM px, on frames smoothed by OUTLINE_SMOOTH px. An object whose
    inside holds nothing the noise does not drown (a faint flat object) or a texture that
    stays where it is (a region moving over a still texture, a blob through a volume's
    slices) matches nothing inside; its edge, freed of the noise, still locates it."""
    sigma = (0, OUTLINE_SMOOTH, OUTLINE_SMOOTH)
    prev, cur = (ndimage.gaussian_filter(np.asarray(f, np.float64), sigma) for f in (prev, cur))
    rim = dilate(mask, OUTLINE_RIM)
    d = match_shift(prev, cur, rim.astype(np.float64), reach, prior, within)
    return _refine(prev, cur, rim, d, steps) if match_shift.peak >= floor else None


def gradients(frame: np.ndarray) -> np.ndarray:
    """(3, H, W): the grey level of `frame` (C, H, W), the channels' mean, and its
    gradient along y and x (np.gradient)."""
    g = frame.mean(axis=0)
    return np.stack([g, *np.gradient(g)])


def bilinear(stack: np.ndarray, coords: np.ndarray) -> np.ndarray:
    """(K, n): the images of `stack` (K, H, W) read at the points `coords` (2, n) by
    bilinear interpolation, the edge repeated beyond the frame (ndimage.map_coordinates'
    order=1, mode='nearest', the indices and weights found once for the K images)."""
    k, h, w = stack.shape
    y = np.clip(coords[0], 0, h - 1)
    x = np.clip(coords[1], 0, w - 1)
    y0 = np.minimum(np.floor(y).astype(np.int64), max(h - 2, 0))
    x0 = np.minimum(np.floor(x).astype(np.int64), max(w - 2, 0))
    fy, fx = y - y0, x - x0
    dy, dx = (w if h > 1 else 0), (1 if w > 1 else 0)
    flat = stack.reshape(k, -1)
    i = y0 * w + x0
    # (take: the same gather as flat[:, i], several times faster)
    gx = 1 - fx
    top = flat.take(i, axis=1) * gx + flat.take(i + dx, axis=1) * fx
    bottom = flat.take(i + dy, axis=1) * gx + flat.take(i + (dy + dx), axis=1) * fx
    return top * (1 - fy) + bottom * fy


def _refine(prev, cur, rim, d, steps, grey=None):
    """Lucas-Kanade from the whole-pixel shift d: first the sub-pixel shift, then the
    affine map where it explains the object clearly better (AFFINE_GAIN). `grey`: prev's
    `gradients` and cur's grey level (H, W), or None."""
    shifted = np.array([[1.0, 0.0, -d[0]], [0.0, 1.0, -d[1]]])
    # Lucas-Kanade on prev(A x) = cur(x) over the object's predicted place (inverse warp:
    # cur's coordinates), the grey levels averaged over the channels; the affine part
    # about the object's centre, so that turning and shifting are not confounded.
    # (a frame's grey levels and gradients found once where the caller keeps them: a frame
    # is the pair's second, then its first)
    stack, gc = grey if grey is not None else (gradients(prev), cur.mean(axis=0))
    centre = np.array(ndimage.center_of_mass(rim)) + d  # in cur's coordinates
    # one set of pixels for every step and for the costs compared: cur's pixels where the
    # shift puts the object (a whole-pixel shift, the edge repeated: an index shift)
    h, w = rim.shape
    if np.array_equal(d, np.round(d)):
        rows = np.clip(np.arange(h) - int(d[0]), 0, h - 1)
        cols = np.clip(np.arange(w) - int(d[1]), 0, w - 1)
        where = rim[np.ix_(rows, cols)]
    else:
        where = _warp(rim * 1.0, shifted, 1) > 0.5
    if where.sum() < 12:
        return shifted
    pts = np.array(np.nonzero(where), np.float64)
    y, x = pts[0] - centre[0], pts[1] - centre[1]

    def at(a, k=1):  # the first k of gp, gy, gx read at A x for the pixels x of `where`
        return bilinear(stack[:k], np.tensordot(a[:, :2], pts, 1) + a[:, 2:])

    # cur's grey levels mapped onto prev's by the gain and offset over the object at the
    # shift: a flicker's change of light is no motion
    target = gc[where]
    ref = at(shifted)[0]
    target = (target - target.mean()) * (ref.std() / max(target.std(), 1e-6)) + ref.mean()

    def cost(a, values=None):
        return float(np.mean(((at(a)[0] if values is None else values) - target) ** 2))

    def fit(a, columns, steps=steps):  # Gauss-Newton steps on the parameters `columns` of a
        for _ in range(steps):
            r, wy, wx = at(a, 3)
            r = r - target
            # (the shift's columns without the products; all six not selected: the same
            # Jacobian, with less work)
            if columns == [2, 5]:
                jac = np.column_stack([wy, wx])
            else:
                jac = np.column_stack([wy * y, wy * x, wy, wx * y, wx * x, wx])
                jac = jac if columns == [0, 1, 2, 3, 4, 5] else jac[:, columns]
            jtj = jac.T @ jac
            jtj += 1e-3 * np.trace(jtj) / len(columns) * np.eye(len(columns))  # a little damping
            step = np.zeros(6)
            step[columns] = np.linalg.solve(jtj, -jac.T @ r)
            step = step.reshape(2, 3)
            # a step in the centred parameters, back to frame coordinates
            step[:, 2] -= step[:, :2] @ centre
            a = a + step
            if np.abs(step[:, :2]).max() < 1e-3 and np.abs(step[:, 2]).max() < 0.02:
                break
        return a

    start = cost(shifted, ref)
    moved = fit(shifted, [2, 5], 3)  # the sub-pixel shift
    if not (np.all(np.isfinite(moved)) and np.abs(moved - shifted).max() < 1.5):
        moved = shifted
    moved_cost = cost(moved) if moved is not shifted else start
    if not moved_cost < start:
        moved, moved_cost = shifted, start
    a = fit(moved, list(range(6)))
    lin = a[:, :2]
    sane = np.all(np.isfinite(a)) and 0.8 < abs(np.linalg.det(lin)) < 1.25
    # the turn and scaling only where they explain the object clearly better than the
    # shift: fitted to noise, a slight shrink each frame adds up to a lost object
    if not sane or np.abs(lin - np.eye(2)).max() > 0.35 or not cost(a) < AFFINE_GAIN * moved_cost:
        a = moved
    return a


def move_mask(mask: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The mask carried by the motion `a` (object_motion's map, cur -> prev coordinates)."""
    return _warp(mask * 1.0, a, 1) > 0.5


def _texture(grey: np.ndarray) -> np.ndarray:
    mean = ndimage.uniform_filter(grey, 5)
    return np.sqrt(np.maximum(ndimage.uniform_filter(grey * grey, 5) - mean * mean, 0))


class AppearanceModel:
    """Histograms of the object's and its surroundings' colour (or grey level) and texture.

    Parameters
    ----------
    colour : bool
        Whether the frames have colour (then three channels are binned; else the grey).
    """

    def __init__(self, colour: bool):
        self.colour = colour
        self.object: np.ndarray | None = None
        self.back: np.ndarray | None = None

    def bins(self, frame: np.ndarray) -> np.ndarray:
        """(H, W) bin index of every pixel of `frame` (C, H, W) in [0, 1]: its colour, or
        grey level, and its local standard deviation (the texture), each frame's brightness
        divided out, so that a dimming light does not move the object's bins."""
        f = np.asarray(frame, np.float64)
        if BRIGHT_TOP:
            lo, hi = np.percentile(f.mean(axis=0), [100 - BRIGHT_TOP, BRIGHT_TOP])
            f = 0.05 + 0.9 * (f - lo) / max(float(hi - lo), 1e-3)
        else:
            f = 0.5 * f / max(float(f.mean()), 1e-3)
        grey = f.mean(axis=0)
        tex = np.clip((_texture(grey) / 0.12) ** 0.5 * BINS_TEXTURE, 0, BINS_TEXTURE - 1)
        if self.colour and f.shape[0] >= 3:
            q = np.clip(f[:3] * BINS_COLOUR, 0, BINS_COLOUR - 1).astype(np.int64)
            colour = (q[0] * BINS_COLOUR + q[1]) * BINS_COLOUR + q[2]
        else:
            colour = np.clip(grey * BINS_GREY, 0, BINS_GREY - 1).astype(np.int64)
        return colour * BINS_TEXTURE + tex.astype(np.int64)

    @property
    def size(self) -> int:
        colours = BINS_COLOUR**3 if self.colour else BINS_GREY
        return colours * BINS_TEXTURE

    def _histogram(self, bins: np.ndarray, where: np.ndarray) -> np.ndarray:
        h = np.bincount(bins[where], minlength=self.size).astype(np.float64)
        shape = (BINS_COLOUR,) * 3 + (BINS_TEXTURE,) if self.colour else (BINS_GREY, BINS_TEXTURE)
        # neighbouring bins share: a few hundred pixels do not fill a thousand bins
        h = ndimage.gaussian_filter(h.reshape(shape), 0.7, mode="constant").ravel()
        return (h + 0.5 / self.size) / (h.sum() + 0.5)

    def learn(self, bins: np.ndarray, mask: np.ndarray) -> None:
        """The object's histogram from its mask in a frame (`bins` of that frame), as a
        running mean over the frames."""
        inner = erode(mask) if mask.sum() > 60 else mask
        if inner.sum() < 4:
            return
        h = self._histogram(bins, inner)
        self.object = h if self.object is None else (1 - MEMORY) * self.object + MEMORY * h

    def log_ratio(self, bins: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """(H, W) log p(surroundings) / p(object) per pixel, the surroundings' histogram
        taken from the ring RING around `predicted` in this frame (a running mean,
        BACK_MEMORY)."""
        near = dilate(predicted, RING[0])
        far = dilate(near, RING[1] - RING[0])
        ring = far & ~near
        if ring.sum() < 16 or self.object is None:
            return np.zeros(bins.shape)
        back = self._histogram(bins, ring)
        if BACK_MEMORY and self.back is not None:
            back = (1 - BACK_MEMORY) * back + BACK_MEMORY * self.back
        self.back = back
        # the evidence tempered by how well the two histograms separate this frame (their
        # Bhattacharyya distance B, weight B / (B + SEPARATION)): where the object looks
        # like its surroundings (a head in a dim car), every frame's mild preference would
        # move the contour a little, and the moves add up to a leak
        b = -np.log(max(float(np.sqrt(back * self.object).sum()), 1e-12))
        return b / (b + SEPARATION) * np.clip(np.log(back / self.object), -6, 6)[bins]


class AppearanceTerm:
    """The appearance's speed, weight tanh(log ratio / 2), as the morphing's region field:
    the RegionTerm interface (field, follows, start, update) with a field fixed per frame.

    Parameters
    ----------
    ls : LevelSet
        The tracker's level set (its grid).
    weight : float
        The largest speed, px per unit time.
    """

    follows = False  # fixed for the frame: the morphing does not refresh it

    def __init__(self, ls: LevelSet, weight: float):
        g = ls.grid
        self.weight = float(weight)
        self.field = Field(g, cla.zeros(g.runtime.queue, g.padded_shape, g.dtype))
        self._ls = ls

    def set(self, log_ratio: np.ndarray, scale: float = 1.0) -> None:
        """Upload this frame's field from the log-likelihood ratio (H, W), its speed
        `scale` times the weight."""
        g = self._ls.grid
        padded = np.zeros(g.padded_shape, g.dtype)
        g.interior(padded)[0] = self._ls.pad(scale * self.weight * np.tanh(0.5 * log_ratio))
        self.field.data.set(padded)

    def start(self, ls, features, noise2) -> None:  # the RegionTerm interface: set() does it
        return None

    def update(self, ls) -> None:
        return None
