"""motion='image' (the default): each frame's contour starts where the image says the
object went, and an appearance term keeps it on the object (appearance.py).

Per frame: the object's motion from the previous frame (`appearance.object_motion`, with a
light-blind match on local contrast beside the frames' own) carries the object's whole
shape, hidden parts included, as a level set (its contour's sub-pixel place kept) to its
predicted place, where the morphing starts (a part whose own motion, a turn included,
clearly explains it better carried by it, turns.py); the prediction grows by the pieces next to it
that clearly look like the object (parts.py: a swinging leg the motion did not carry); the
appearance model's log ratio there, with the grown prediction's prior, becomes the
morphing's region speed, believed as far as it classified the last result (unless the
background around the object moves otherwise than it, where the image term cannot hold the
contour either), and not at all on a still frame; after the morphing, small pieces that
split off a larger one are dropped (a piece caught on an occluder) and the models learn
the frame. The whole shape is the result, unless the evidence says that the part it lost
is hidden by something still (occlusion.py): then the prediction, laid on the visible
outline, is kept as the whole shape, the motion is searched near the velocity, and the
result is the whole shape's visible part (the pieces that look like the object), so that
the contour grows back where the object reappears and leaves nothing on the occluder.
Pixels of the prediction that the frames show still while the object moved, and that
its motion does not explain (occlusion.seen_still), are an occluder even where they look
like the object: carved from the result where the appearance left them, remembered while
they stay still, and kept out of the next frame's match. A moving object's match far off
its velocity is taken only where it is clearly better than the best near it (a bar over
part of the object lowers the true match).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from . import turns
from .adaptive import noise_variance
from .appearance import (
    MATCH_FLOOR,
    AppearanceModel,
    AppearanceTerm,
    bilinear,
    box,
    dilate,
    erode,
    gradients,
    match_shift,
    object_motion,
)
from .levelset import LevelSet, signed_distance
from .local_trust import believed, trust_map
from .motion_filter import local_contrast
from .occlusion import (
    LOST,
    SEEN_REACH,
    STILL,
    align,
    hidden_by_still,
    lost_part,
    seen_still,
    still_share,
    visible_pieces,
)
from .parts import grow_parts
from .velocity import corrected

# The correlation's peak that overrides the velocity while the object is hidden in part.
HIDDEN_FLOOR = MATCH_FLOOR  # chosen on the calibration half: 0.6 lost more than it kept
# The largest change of velocity (px a frame) searched while the object is hidden in part.
HIDDEN_CHANGE = 3.0  # chosen on the calibration half: occlusion 0.565 with it, 0.533 without
# A hidden object's fitted motion farther than this (px a frame) from its velocity is not
# taken (the fit on a sliver runs off; a still bar drags it): the velocity is kept.
# Chosen on the calibration half's occlusions: 2 and 4 the same with the noise over the
# frame, 4 lost occlude-2 (0.933 -> 0.165) with the noise over the box.
HIDDEN_RUNOFF = 2.0
# A moving object's (JUMP_MOVING px a frame or more) match more than JUMP px off its
# velocity is taken only where its correlation beats the best within JUMP px of the
# velocity by JUMP_MARGIN (`_clearly_better`).
JUMP_MOVING, JUMP, JUMP_MARGIN = 1.0, 3.0, 0.15
# ... and does not land where the frame looks unlike the object (the appearance's mean
# log odds of the surroundings there above LOOKS_AWAY; `_looks_away`).
LOOKS_AWAY = 0.0
# Pieces smaller than this share of the largest (or than MIN_PIECE px) are dropped.
PIECE_SHARE, MIN_PIECE = 0.08, 10
# The result stays within this many px of the predicted whole shape.
GROW = 6
# The prediction's prior: log odds of the surroundings = signed distance / PRIOR_SCALE,
# within +-PRIOR_CAP.
PRIOR_SCALE, PRIOR_CAP = 2.0, 3.0
# The appearance's evidence is scaled by 1 - e / RELIABLE_ERROR (local_trust.believed); 0: not.
# RELIABLE_ERROR and RING_LO, RING_HI: chosen on the calibration half of
# benchmarks/track_photo_corpus.py among the settings with which every promise of
# tests/tracking holds (docs/tracking.md, "One default").
RELIABLE_ERROR = 0.1
# ... unless the image cannot hold the contour either: the previous frame carried by the
# object's motion misses the current one in the ring 3-8 px around the object by more
# than RING_LO times its miss over the object (the background moves otherwise); the doubt
# fades out between RING_LO and RING_HI (`_ring_miss`). RING_HI 0: always doubted.
RING_LO, RING_HI = 1.6, 2.0
# (Tried, issue 35's grey class, trackgrey2, not taken. Believing the appearance less where
# the ring misses (1 - e / 0.3, 0.5 or 1 instead of 1) or its carving only (sided): grey-0
# and grey-8 stop shrinking (grey-0 0.874 -> 0.964) but grey-2 and grey-12 leak and are
# lost (0.922 -> 0.654, 0.888 -> 0.615; the appearance off: 0.438, 0.465): photo
# calibration 0.911 -> 0.858-0.903 mean of sequences. Believing its carving only as far as
# it earned on the pixels the object's motion explains and standing still does not (3x3
# means of |frame t - frame t-1 carried by the motion| below, of |frame t - frame t-1| at
# least, 2 sigma of the noise; moved >= 3 px): photo calibration grey 0.855 -> 0.868,
# no class lower, carphone bit for bit, but synthetic calibration 0.7060 -> 0.7056 mean of
# class means (stop-and-go -0.003), and on the test half the grey class unchanged (0.471)
# and occlude-3 0.727 -> 0.685: commit ab36175.)
# The object's model learns the result's pixels whose log ratio is below this (a strip of
# an occluder taken in by mistake is not learned).
LEARN_BELOW = 1.0
# The start keeps the appearance's visible part of the prediction unless less than this
# share of it remains.
VISIBLE = 0.3
# The motion is also matched on local-contrast-normalised frames over boxes of this
# half-width (a shadow or a flicker does not move that match; object_motion's `light`);
# 0: on the frames themselves only.
MATCH_CONTRAST = 4
# Occluders seen by the frames, not the appearance (occlusion.seen_still; in grey footage
# a bar can look like the object): looked for where the object moved at least SEEN_MOVED
# px (a bar drags the measured motion of a 3-6 px a frame object below 3 px); pixels whose
# appearance's log odds of the surroundings is below -SEEN_LOOKS (clearly the object) are
# not taken for one; the motion is matched on the object's pixels farther than SEEN_NEAR
# px from those seen still the frame before (an occluder's edge held the match still).
# Chosen on the calibration half's occlusions (docs/tracking.md, "Occluders seen still").
SEEN_MOVED, SEEN_LOOKS, SEEN_NEAR = 1.5, 1.0, 2
# While hidden, the prediction's prior is 0 outside it within BESIDE px of the occluder
# seen (calibration occlusions: occlude-2 0.933 without, 0.945 / 0.954 / 0.935 at 3 / 6 /
# 9 px).
BESIDE = 6
# A frame pair whose difference near the unmoved object is below this many times the
# noise's is still (`_change`).
STILL_CHANGE = 2.0


def _at(image: np.ndarray, a: np.ndarray, where: np.ndarray) -> np.ndarray:
    """image read at A x for the pixels x of `where` (the affine map of object_motion):
    the warp at the pixels needed only."""
    return _at_channels(np.asarray(image, np.float64)[np.newaxis], a, where)[0]


def _at_channels(stack: np.ndarray, a: np.ndarray, where: np.ndarray) -> np.ndarray:
    """(C, n): `_at` of every image of the (C, H, W) stack (the points and weights found
    once: the same values as `_at` of each)."""
    pts = np.array(np.nonzero(where), np.float64)
    coords = np.tensordot(a[:, :2], pts, 1) + a[:, 2:]
    return bilinear(np.asarray(stack, np.float64), coords)


def _warp_values(u: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The level set u carried by the motion `a` (object_motion's map): u read at A x."""
    return ndimage.affine_transform(u, a[:, :2], a[:, 2], order=1, mode="nearest")


def _drop_strays(mask: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """The mask without its small pieces (below PIECE_SHARE of the largest, or MIN_PIECE
    px) that split off a larger one: a small piece is kept only where it is all there is
    of a piece of the predicted shape (a speck the object had all along), and dropped where
    that piece also holds a larger one (a strip caught on an occluder)."""
    labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
    if n < 2:
        return mask
    sizes = np.bincount(labels.ravel())[1:]
    small = sizes < max(MIN_PIECE, PIECE_SHARE * sizes.max())
    if not small.any():
        return mask
    whole, _ = ndimage.label(predicted | mask, structure=np.ones((3, 3)))
    # each piece's part of the whole (pieces lie within one part: the part holds them)
    part = ndimage.maximum(whole, labels, np.arange(1, n + 1)).astype(np.int64)
    big = np.zeros(part.max() + 1, bool)
    big[part[~small]] = True
    drop = small & big[part]
    return mask & ~(drop[labels - 1] & (labels > 0))


def _ring_miss(prev, cur, a, predicted) -> float:
    """How badly the previous frame's features `prev` carried by the object's motion `a`
    explain `cur` ((C, H, W), light-blind) in the ring 3-8 px around the predicted object,
    against how well over the object (2 px in): the median absolute residuals' ratio. About
    1 where the background moves with the object or is flat; large where it moves
    otherwise, and the image term drags the contour off."""
    inner = erode(predicted, 2)
    near = dilate(predicted, 3)
    ring = dilate(near, 5) & ~near
    if inner.sum() < 8 or not ring.any():
        return 1.0
    where = inner | ring
    res = np.zeros(where.shape)
    res[where] = np.mean(
        [np.abs(c[where] - _at(p, a, where)) for p, c in zip(prev, cur, strict=True)], axis=0
    )
    return float(np.median(res[ring]) / max(float(np.median(res[inner])), 1e-6))


def _change(before: np.ndarray, after: np.ndarray, where: np.ndarray) -> float:
    """The mean |after - before| over `where`, against what the noise alone gives there
    (2 sigma / sqrt(pi) for two frames of noise variance sigma^2): about 1 where only noise
    changed. (C, H, W) frames."""
    expected = 2.0 * np.sqrt(noise_variance(after)) / np.sqrt(np.pi)
    return float(np.abs(after - before).sum(axis=0)[where].mean() / max(expected, 1e-6))


def _prior(predicted: np.ndarray) -> np.ndarray:
    """The prediction's log prior odds of the surroundings: the signed distance to the
    predicted shape over PRIOR_SCALE px, within +-PRIOR_CAP. The distances are found over
    the shape's box grown by `reach` px only: a pixel outside it is farther than that from
    the shape (the cap), and one inside it is no nearer to a pixel outside the box than to
    the box's rim, which is outside the shape too (the same values as over the frame)."""
    reach = int(np.ceil(PRIOR_SCALE * PRIOR_CAP)) + 1
    prior = np.full(predicted.shape, float(PRIOR_CAP))
    where = box(predicted, reach)
    prior[where] = np.clip(signed_distance(predicted[where]) / PRIOR_SCALE, -PRIOR_CAP, PRIOR_CAP)
    return prior


def _jumped(a: np.ndarray, shape: np.ndarray, velocity: np.ndarray) -> bool:
    """Whether the motion `a` takes the object's centre more than JUMP px off where its
    velocity (at least JUMP_MOVING px a frame) would."""
    if np.hypot(*velocity) < JUMP_MOVING:
        return False
    centre = _centroid(shape)
    shift = np.linalg.solve(a[:, :2], centre - a[:, 2]) - centre
    return bool(np.abs(shift - velocity).max() > JUMP)


def _clearly_better(prev, cur, pixels, velocity) -> bool:
    """Whether the object's best match beats its best within JUMP px of its velocity by
    JUMP_MARGIN of correlation: a moving object's jump must be clear (a bar over part of
    it lowers the true match, and a look-alike elsewhere can score as high)."""
    weight = pixels.astype(np.float64)
    match_shift(prev, cur, weight, prior=velocity)
    best = match_shift.peak
    match_shift(prev, cur, weight, prior=velocity, within=JUMP)
    return best >= match_shift.peak + JUMP_MARGIN


def _centroid(mask: np.ndarray) -> np.ndarray:
    return np.array(ndimage.center_of_mass(mask)) if mask.any() else np.zeros(2)


class ObjectFollower:
    """The state of motion='image' over a track: the object's whole shape, its last
    displacement, the appearance model and its term.

    Parameters
    ----------
    tracker : MorphingTracker
        The tracker (its options, its colour frames and its first mask).
    ls : LevelSet
        The tracker's level set.
    """

    def __init__(self, tracker, ls: LevelSet):
        self.ls = ls
        self.band = tracker.options.band_width
        self.looks = tracker._looks
        self.shape = tracker.first_mask.copy()
        # its level set (negative inside), carried with it: the contour's sub-pixel place
        self.shape_u = signed_distance(self.shape)
        self.predicted = self.shape
        self._grown = self.shape  # the prediction with the parts that moved otherwise
        self._predicted_u = self.shape_u
        self.velocity = np.zeros(2)
        # hidden in part by something still (occlusion.py): the shape is then the whole
        # shape, the result its visible part
        self.hidden = False
        self.visible = self.shape
        # the whole shape if the loss of the last frame turns out to be hidden (the first
        # frame behind an occluder: its cut was not there the frame before)
        self._whole_u = None
        self._predicted_whole_u = None
        weight = tracker.options.appearance_weight
        self.model = AppearanceModel(colour=self.looks is not None and self.looks.shape[1] >= 3)
        self.term = AppearanceTerm(ls, weight) if weight else None
        self.reliability, self._errors = 1.0, None  # the share believed (and local_trust's)
        if self.term is not None:
            bins = self.model.bins(self.looks[0])
            self.model.learn(bins, self.shape)
            ratio = self.model.log_ratio(bins, self.shape)
            self.reliability, self._errors = believed(ratio, self.shape, RELIABLE_ERROR)
        self._bins, self._bins_t = None, None  # frame _bins_t's bins
        self._match_cache = {}
        self._grey_t = {}  # frames' appearance.gradients, the pair in use
        self._ratio = None  # the last frame's log odds (surroundings over object)
        self._looks_ratio = None  # the same from the looks alone
        self._seen = None  # the prediction's pixels seen still (occlusion.seen_still)
        # what was seen still near the object, and stayed still since (an occluder)
        self._occluder = None

    def move(self, t, prepared_prev, prepared, mask):
        """Predict frame t: move the level set to the whole shape's predicted place and set
        the appearance term. Returns the previous frame's features moved with the object
        (near it) and the displacement (dy, dx) of the object's centre."""
        # matched in colour where the footage has it: a red object on a blue sky can have
        # the sky's grey level
        # The object's pixels that look like it: a piece of an occluder or of the
        # background the contour took in would pull the match to its own (lack of) motion.
        pixels = mask & (self._looks_ratio < 0) if self._looks_ratio is not None else mask
        if self._seen is not None:  # nor the pixels next to what was seen still
            pixels = pixels & ~dilate(self._seen, SEEN_NEAR)
        if pixels.sum() < 0.3 * mask.sum():
            pixels = mask
        # Much of the object out of sight: what is left must match clearly to override
        # the velocity (a sliver matches anywhere; a hidden object does not turn at once).
        hidden = self.hidden
        floor = HIDDEN_FLOOR if hidden else MATCH_FLOOR
        within = HIDDEN_CHANGE if hidden else None
        if pixels.sum() >= MIN_PIECE:
            light = (self._light(t - 1), self._light(t)) if MATCH_CONTRAST else None
            before, now = self.looks[t - 1], self.looks[t]
            grey = (self._gradients(t - 1), self._gradients(t)[0])
            # An object that the appearance tells from its surroundings and whose inside
            # matches nothing is hidden: it keeps its velocity. One it does not tell apart
            # at all (a faint flat object, a region over the same texture) has nothing
            # inside to match: its outline finds it (on the calibration halves, with the
            # outline whatever the appearance, the photo corpus' occlusion 0.947 -> 0.293:
            # the occluder's still edge holds the outline).
            outline = self.term is not None and self.reliability == 0

            def match(bound):
                return object_motion(
                    before,
                    now,
                    pixels,
                    self.velocity,
                    floor=floor,
                    within=bound,
                    light=light,
                    grey=grey,
                    outline=outline,
                )

            a = match(within)
            if within is None and _jumped(a, self.shape, self.velocity):
                if self._looks_away(t, a) or not _clearly_better(
                    before, now, object_motion.pixels, self.velocity
                ):
                    a = match(JUMP)
        else:  # nothing in sight: the object keeps its velocity
            a = np.array([[1.0, 0.0, -self.velocity[0]], [0.0, 1.0, -self.velocity[1]]])
        # the velocity: where the motion takes the whole shape's centre
        centre = _centroid(self.shape)
        shift = np.linalg.solve(a[:, :2], centre - a[:, 2]) - centre
        if hidden and np.abs(shift - self.velocity).max() > HIDDEN_RUNOFF:
            # the fit on what is left in sight ran off: a hidden object keeps its velocity
            shift = self.velocity.copy()
            a = np.array([[1.0, 0.0, -shift[0]], [0.0, 1.0, -shift[1]]])
        self.velocity = shift
        predicted_u = _warp_values(self.shape_u, a)
        predicted = predicted_u < 0
        if not predicted.any() or predicted.all():  # carried out of the frame: it stays
            predicted, predicted_u = self.shape, self.shape_u
        self._seen = None
        if np.hypot(*shift) >= SEEN_MOVED:
            self._seen = self._seen_still(t, a, predicted)
        else:
            self._occluder = None
        if not hidden and pixels.sum() >= MIN_PIECE and self.term is not None:
            predicted_u, predicted = self._parts(t, a, pixels, predicted_u, predicted)
        self.predicted, self._predicted_u = predicted, predicted_u
        self._grown = predicted
        self._predicted_whole_u = None if self._whole_u is None else _warp_values(self._whole_u, a)
        # F1: the previous frame carried with the object near its predicted place
        near = dilate(predicted, int(np.ceil(self.band)) + 4)
        out = np.array(prepared_prev, np.float64, copy=True)
        out[:, near] = _at_channels(out, a, near)
        start = predicted
        if self.term is not None:
            # a still object in a still scene (no motion, and the frames differ near it by
            # no more than the noise explains): nothing new for the appearance to say, and
            # its evidence on a blurred edge's pixels would move the contour
            moved = np.abs(a - [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).max() > 0.02
            still = not moved and _change(out, prepared, near) < STILL_CHANGE
            start = self._appearance(t, a, predicted, still)
        self.ls.assign(predicted_u if start is predicted else signed_distance(start))
        return out, (float(shift[0]), float(shift[1]))

    def _parts(self, t, a, pixels, predicted_u, predicted):
        """The prediction with the parts that move otherwise (turns.predict), if believed."""
        u = (
            None
            if self.reliability <= 0
            else turns.predict(self, t, a, pixels, predicted, _warp_values)
        )
        if u is None:
            return predicted_u, predicted
        self._seen = None if self._seen is None else self._seen & (u < 0)
        return u, u < 0

    def _seen_still(self, t, a, predicted) -> np.ndarray:
        """The predicted shape's pixels that show something still in frame t, not the
        object that moved by `a` (occlusion.seen_still), over the prediction's box; the
        occluders seen there are remembered."""
        where = box(predicted, 1)
        r = SEEN_REACH
        # the previous frame carried by the motion over the box grown by r px (edge
        # values beyond the frame)
        rows = np.clip(np.arange(where[0].start - r, where[0].stop + r), 0, predicted.shape[0] - 1)
        cols = np.clip(np.arange(where[1].start - r, where[1].stop + r), 0, predicted.shape[1] - 1)
        pts = np.array([np.repeat(rows, len(cols)), np.tile(cols, len(rows))], np.float64)
        coords = np.tensordot(a[:, :2], pts, 1) + a[:, 2:]
        before, after = self.looks[t - 1], self.looks[t]
        carried = bilinear(np.asarray(before, np.float64), coords).reshape(
            (len(before), len(rows), len(cols))
        )
        # (the noise over the box: over the frame it would cost more than the rest; on the
        # calibration occlusions the same but for grey-4, 0.943 over the frame, 0.951)
        noise = float(np.sqrt(noise_variance(after[:, where[0], where[1]])))
        known = None if self._occluder is None else self._occluder[where]
        seen = np.zeros(predicted.shape, bool)
        seen[where] = seen_still(
            before[:, where[0], where[1]], after[:, where[0], where[1]], carried, noise, known
        )
        self._occluder = seen
        return seen & predicted

    def _seen_counts(self, mask) -> bool:
        """Whether the pixels seen still say what the appearance did not: at least LOST of
        the prediction is seen still and left in the morphing's result `mask` (in colour
        the appearance carves an occluder by itself, and the still evidence stays out)."""
        return (self._seen & mask).sum() >= max(LOST * self.predicted.sum(), 1)

    def _looks_away(self, t, a) -> bool:
        """Whether the shape carried by the motion `a` lands where frame t does not look
        like the object (the appearance's mean log odds there above LOOKS_AWAY): a jump
        onto the background, not the object's."""
        if self.term is None:
            return False
        landed = _warp_values(self.shape_u, a) < 0
        if not landed.any():
            return False
        self._bins, self._bins_t = self.model.bins(self.looks[t]), t
        return float(self.model.log_ratio(self._bins, landed)[landed].mean()) > LOOKS_AWAY

    def _appearance(self, t, a, predicted, still):
        """Set the appearance term of frame t around the predicted whole shape; returns the
        morphing's start."""
        if self._bins_t != t:  # (`_looks_away` may have binned the frame)
            self._bins, self._bins_t = self.model.bins(self.looks[t]), t
        # the appearance's evidence and the prediction's: the log prior odds of the
        # surroundings, the signed distance to the predicted shape over PRIOR_SCALE px
        # (capped at PRIOR_CAP), so that ambiguous looks leave the predicted shape as it is
        # and only clear evidence carves it or grows it
        self._looks_ratio = self.model.log_ratio(self._bins, predicted)
        # believed where the last result's neighbourhood earned it (not while hidden)
        errors = None if self.hidden else self._errors
        trust = trust_map(self._trust(t, a, predicted), errors, RELIABLE_ERROR)
        if still or self.hidden or np.max(trust) <= 0:  # (hidden: the occluder's rules hold)
            self._grown = predicted
        else:
            self._grown = grow_parts(predicted, trust * self._looks_ratio)
        prior = _prior(self._grown)
        if self.hidden and self._occluder is not None and self._occluder.any():
            # next to an occluder the object's extent is not known (it comes out from
            # behind it): the prediction does not hold the contour back there
            beside = dilate(self._occluder, BESIDE) & ~self._occluder & (prior > 0)
            prior[beside] = 0.0
        # (no evidence from the motion-compensated residual: a talking mouth or a turning
        # face does not move with the object either, and on the calibration half, 0.827 ->
        # 0.851 mean IoU without it, carphone J 0.824 -> 0.850)
        self._ratio = prior if still else trust * self._looks_ratio + prior
        # doubted, the whole term yields to the image's (the prior alone would hold the
        # contour at the predicted place against the frames' evidence)
        self.term.set(self._ratio, trust)
        return predicted if still else self._visible(predicted)

    def _trust(self, t, a, predicted) -> float:
        """The share of the appearance believed in frame t: its reliability on the last
        result, unless the image term cannot hold the contour either (`_ring_miss`)."""
        if self.reliability >= 1 or not RING_HI:
            return self.reliability
        miss = _ring_miss(self._light(t - 1), self._light(t), a, predicted)
        doubt = float(np.clip((RING_HI - miss) / (RING_HI - RING_LO), 0, 1))
        return 1 - doubt * (1 - self.reliability)

    def _light(self, t):
        """Frame t's light-blind features (local contrast) that the motion also matches."""
        cached = self._match_cache.get(t)
        if cached is None:
            # of the grey levels: one correlation channel (the colour's is the frames' own
            # match)
            cached = local_contrast(self.looks[t].mean(axis=0, keepdims=True), MATCH_CONTRAST)
            # the frame pair in use: this frame and the one before
            self._match_cache = {k: v for k, v in self._match_cache.items() if k >= t - 1}
            self._match_cache[t] = cached
        return cached

    def _gradients(self, t):
        """Frame t's grey level and gradients (appearance.gradients), found once: the
        frame is the motion's second frame, then its first."""
        if self._grey_t.get(t) is None:
            self._grey_t = {k: v for k, v in self._grey_t.items() if k >= t - 1}
            self._grey_t[t] = gradients(self.looks[t])
        return self._grey_t[t]

    def _visible(self, predicted: np.ndarray) -> np.ndarray:
        """The morphing's start: the predicted whole shape less what looks like the
        surroundings there (an occluder, the background it moved off), so that the contour
        need not carve a hidden strip out from the edge; the whole prediction where the
        appearance tells too little (less than VISIBLE of it would remain)."""
        # over the prediction's box grown by the filter's radius (4 px) and the opening's
        # (1 px): the same values there as over the frame, at the object's cost
        where = box(predicted, 5)
        looks = ndimage.gaussian_filter(self._ratio[where], 1.0) < 0
        start = np.zeros(predicted.shape, bool)
        start[where] = ndimage.binary_opening(predicted[where] & looks)
        labels, n = ndimage.label(start, structure=np.ones((3, 3)))
        if n > 1 and not self.hidden:  # hidden, every piece that looks like the object
            sizes = np.bincount(labels.ravel())[1:]
            start = (sizes >= max(MIN_PIECE, PIECE_SHARE * sizes.max()))[labels - 1] & (labels > 0)
        return start if start.sum() >= max(VISIBLE * predicted.sum(), 1) else predicted

    def observe(self, t, mask: np.ndarray, u: np.ndarray) -> np.ndarray:
        """After frame t's morphing (its mask and level set u): the mask cleaned of stray
        pieces; the models learn."""
        # no farther than GROW px from the prediction: the motion is accounted for, and a
        # frame's deformation is small; a leak along a look-alike stops there
        mask = mask & dilate(self._grown, GROW)
        if self._seen is not None and self._looks_ratio is not None:
            # what clearly looks like the object is not an occluder: a smooth part of it
            # coming out from behind one is still, and the frame before showed the
            # occluder where it came from
            clear = self._looks_ratio < -SEEN_LOOKS
            self._seen &= ~clear
            self._occluder &= ~clear
        if self._seen is not None and not self._seen_counts(mask):
            self._seen = None
        if self._seen is not None:  # what shows something still is not the object
            mask = mask & ~self._seen
        if self.hidden:
            mask = visible_pieces(mask, self.predicted, self._looks_ratio)
        else:
            mask = _drop_strays(mask, self.predicted)
        if self.term is not None and mask.any():
            self.reliability, self._errors = believed(self._looks_ratio, mask, RELIABLE_ERROR)
            # the object's model learns the pixels that did not look clearly like the
            # surroundings: a strip of an occluder taken in by mistake is not learned
            self.model.learn(self._bins, mask & (self._looks_ratio < LEARN_BELOW))
        if mask.any() and (mask == (u < 0)).all():
            shape_u = np.asarray(u, np.float64)
        else:
            shape_u = signed_distance(mask) if mask.any() else np.abs(u) + 1.0
        shape_u = self._whole(t, mask, shape_u)
        self.velocity = corrected(self.velocity, self.predicted, mask, self.hidden)  # a mislock
        if self.hidden and self._occluder is not None:
            # the whole shape's part out of sight stays so where it stays still
            self._occluder = self._occluder | ((shape_u < 0) & ~mask)
        self.visible = mask
        self.shape_u = shape_u
        self.shape = shape_u < 0
        return mask

    def _whole(self, t, mask: np.ndarray, shape_u: np.ndarray) -> np.ndarray:
        """The shape to carry on from frame t's result `mask` (its level set `shape_u`):
        the result itself, or the whole shape where the evidence says the part lost is
        hidden by something still (occlusion.py); `hidden` updated."""
        least = LOST * self.predicted.sum()
        # (the lost part lies within the prediction less the result: most frames stop here)
        lost = None if (self.predicted & ~mask).sum() < least else lost_part(self.predicted, mask)
        if lost is None or lost.sum() < least:
            self.hidden, self._whole_u = False, None
            return shape_u
        if not mask.any():  # nothing in sight: the whole shape goes on with its velocity
            still = True
        elif self.hidden:  # stays hidden while what hides it stays still
            noise = float(np.sqrt(noise_variance(self.looks[t])))
            still = still_share(self.looks[t - 1], self.looks[t], lost, noise) >= STILL
        else:
            ratio = self._looks_ratio if self.term is not None else None
            still = hidden_by_still(lost, mask, self.visible, ratio, self.velocity)
        # the whole shape: the prediction with the result (and the loss of the frame
        # before, where this frame tells it was hidden too)
        predicted_u = self._predicted_u
        if self.hidden:  # laid on the visible outline: the fitted motion can miss
            # (away from the cut, and from the occluder seen by the frames: its still edge
            # is no outline of the object's)
            cut = lost if self._occluder is None else lost | self._occluder
            d = align(self.predicted, mask, cut)
            if d.any():
                predicted_u = ndimage.shift(predicted_u, d, order=0, mode="nearest")
                self.velocity = self.velocity + d
        whole_u = np.minimum(shape_u, predicted_u)
        if still and not self.hidden and self._predicted_whole_u is not None:
            whole_u = np.minimum(whole_u, self._predicted_whole_u)
        self.hidden = still
        # not (yet) hidden: kept a frame, in case the next one tells it was
        self._whole_u = None if still else whole_u
        return whole_u if still else shape_u
