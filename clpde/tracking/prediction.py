"""Where each frame's morphing starts: the motion model's predicted displacement applied to
the level set and to the previous frame's features together, so that the morphing only
has to explain what the displacement does not.

motion='velocity' or 'kalman' moves the whole contour by one displacement
(`features.MotionFilter`); motion='components' moves each connected piece by its own
(`adaptive.ComponentMotion`). Both match local-contrast-normalised frames, whatever the
morphing compares: a shadow or a flicker does not move the measured displacement.
"""

from __future__ import annotations

import numpy as np

from .adaptive import ComponentMotion, noise_variance
from .features import MotionFilter, local_contrast, shift_image
from .levelset import LevelSet
from .options import TrackOptions


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
        if self.pieces:
            self.model = ComponentMotion(options.search_radius)
        else:
            self.model = MotionFilter(options.motion, options.search_radius)
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
