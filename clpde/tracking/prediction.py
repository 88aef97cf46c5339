"""Where each frame's morphing starts: the motion model's predicted displacement applied to
the level set and to the previous frame's features together, so that the morphing only
has to explain what the displacement does not.

motion='velocity' or 'kalman' moves the whole contour by one displacement
(`features.MotionFilter`); motion='components' moves each connected piece by its own
(`adaptive.ComponentMotion`). Both match local-contrast-normalised frames, whatever the
morphing compares: a shadow or a flicker does not move the measured displacement.

motion='checked' is 'kalman' checked against the image (`checked_shift`): the filter only
searches `search_radius` px around its last velocity and damps jumps, so an object that
starts at, or speeds up to, more than that is lost at once; a wide search (a masked
normalised cross-correlation over every shift within CHECK_REACH px) proposes a second
displacement, and the one whose features match better wins. When the wide one wins, the
filter restarts there (`MotionFilter.jump`).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .adaptive import ComponentMotion, noise_variance
from .appearance import MATCH_FLOOR, match_shift
from .levelset import LevelSet
from .motion_filter import MotionFilter, local_contrast, match_displacement, shift_image
from .options import TrackOptions

# motion='checked''s settings, chosen on the calibration half of
# benchmarks/track_photo_corpus.py (benchmarks/track_image_search.py, mean IoU over its 13
# sequences: gain 0.6 / 0.7 / 0.8 / 0.9 gave 0.586 / 0.613 / 0.606 / 0.576; 1.0 gave 0.572
# on the 12 composites alone; a reach of 24 or 40 px changed nothing at gain 0.8).
CHECK_REACH = 32  # px: the wide search's largest displacement per frame
# the wide search's displacement replaces the filter's when its matching cost (mean
# absolute difference of the features over the object) is below this share of the filter's
CHECK_GAIN = 0.7


def _cost(prev: np.ndarray, cur: np.ndarray, weight: np.ndarray, shift) -> float:
    """Mean absolute difference of cur(x + shift) (bilinear, the edge repeated) and prev(x)
    over the pixels x of `weight`, summed over the channels of (C, H, W) features."""
    pts = np.array(np.nonzero(weight), np.float64)
    moved = pts + np.asarray(shift, np.float64)[:, None]
    total = 0.0
    for p, c in zip(prev, cur, strict=True):
        at = ndimage.map_coordinates(c, moved, order=1, mode="nearest")
        total += float(np.abs(at - p[weight]).mean())
    return total


def checked_shift(
    prev: np.ndarray,
    cur: np.ndarray,
    mask: np.ndarray,
    shift,
    reach: int = CHECK_REACH,
    gain: float = CHECK_GAIN,
) -> tuple[tuple[float, float], bool]:
    """The filter's displacement `shift` (dy, dx) of the object `mask` from features `prev`
    to `cur` (C, H, W), checked against a wide search of the image.

    The wide search is the masked normalised cross-correlation over every whole-pixel
    shift within `reach` px (`appearance.match_shift`, on the mask dilated by 3 px so that
    the boundary's context counts), refined to sub-pixel within 2 px
    (`features.match_displacement`). It replaces `shift` when its matching cost is below
    `gain` times that of `shift`, and its correlation peak is a match at all (MATCH_FLOOR).

    Returns the displacement and whether the wide search's replaced the filter's."""
    if mask.sum() < 4 or mask.all():
        return tuple(shift), False
    weight = ndimage.binary_dilation(mask, iterations=3)
    wide = match_shift(prev, cur, weight.astype(np.float64), reach, prior=shift)
    if match_shift.peak < MATCH_FLOOR or np.abs(wide - np.round(shift)).max() <= 1:
        return tuple(shift), False  # no match, or the filter's answer
    wide, _ = match_displacement(prev, cur, mask, wide, 2)
    if _cost(prev, cur, weight, wide) < gain * _cost(prev, cur, weight, shift):
        return (float(wide[0]), float(wide[1])), True
    return tuple(shift), False


class MotionPrediction:
    """The motion model of a track (options.motion, not None) and the features it matched
    last.

    Parameters
    ----------
    options : TrackOptions
        The tracker's options: motion, search_radius, contrast_radius, contrast_eps and
        band_width.
    """

    def __init__(self, options: TrackOptions):
        self.options = options
        self.pieces = options.motion == "components"
        self.checked = options.motion == "checked"
        if self.pieces:
            self.model = ComponentMotion(options.search_radius)
        else:
            kind = "kalman" if self.checked else options.motion
            self.model = MotionFilter(kind, options.search_radius)
        self._previous: np.ndarray | None = None  # the last frame's matching features

    def move(
        self,
        ls: LevelSet,
        prepared_prev: np.ndarray,
        prepared: np.ndarray,
        mask: np.ndarray,
        noise2: float | None = None,
    ) -> tuple[np.ndarray, tuple[float, float], bool]:
        """Predict the displacement from the previous frame to `prepared` (both (C, H, W))
        of the previous result `mask`, and move the level set there. `noise2`: the noise
        variance of `prepared`, if known (motion='components' needs it).

        Returns the previous frame's features moved with it, the displacement (dy, dx) (of
        the largest piece, with motion='components') and whether anything moved."""
        if self.pieces:
            if noise2 is None:
                noise2 = noise_variance(prepared)
            return self._move_pieces(ls, prepared_prev, prepared, mask, noise2)
        cr = self.options.contrast_radius
        features = local_contrast(prepared, cr)
        if self._previous is None:
            self._previous = local_contrast(prepared_prev, cr)
        shift = self.model.predict(self._previous, features, mask)
        if self.checked:
            shift, jumped = checked_shift(
                self._previous, features, mask, shift, CHECK_REACH, CHECK_GAIN
            )
            if jumped:
                self.model.jump(shift)
        self._previous = features
        if max(abs(shift[0]), abs(shift[1])) < 0.25:
            # Below the matching's precision; shifting would only blur F1.
            return prepared_prev, (0.0, 0.0), False
        ls.assign(shift_image(ls.values(), shift))
        return np.stack([shift_image(c, shift) for c in prepared_prev]), shift, True

    def _move_pieces(self, ls, prepared_prev, prepared, mask, noise2):
        # eps raised to twice the noise, so that a flat, noisy patch is not blown up into
        # texture.
        cr = self.options.contrast_radius
        eps = max(self.options.contrast_eps, 2 * float(np.sqrt(noise2)))
        features = local_contrast(prepared, cr, eps)
        if self._previous is None:
            self._previous = local_contrast(prepared_prev, cr, eps)
        pieces = self.model.predict(self._previous, features, mask)
        self._previous = features
        u_moved, prev_moved, moved = ComponentMotion.apply(
            ls.values(), prepared_prev, pieces, self.options.band_width
        )
        if moved and (u_moved < 0).any() and not (u_moved < 0).all():
            ls.assign(u_moved)
            largest = max(pieces, key=lambda p: p[0].sum())
            return prev_moved, largest[1], True
        return prepared_prev, (0.0, 0.0), False

    def observe(self, before: np.ndarray, after: np.ndarray) -> None:
        """After a frame: the velocity model learns the result's displacement."""
        if not self.pieces:
            self.model.observe(before, after)
