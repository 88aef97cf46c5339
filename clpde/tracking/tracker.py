"""Morphing active contours (thesis section 2.1): carry contours through frames or slices.

For each pair of consecutive frames (I1, I2) the features F1 = L(I1) and F2 = L(I2) (the
frames themselves, or their edge maps, used inside a band around the contour) drive the
coupled system (2.3)-(2.6):

    F1_t = beta |grad F1|,   u_t = beta (N_F1 . N_u) |grad u|,   beta = F2 - F1,

so the contour, the zero level set of u, moves with the projection of F1's morphing velocity
on its own normal. u starts as the signed distance to the first mask's boundary; the band
follows the zero level set and is rebuilt, with u reinitialised on the device, whenever the
front nears its edge. Each frame stops when the contour has stopped moving or after a cap;
its result starts the next frame. Topology changes need no special handling.

For real video the features may be contrast-invariant (features='contrast':
local contrast normalisation), colour (colour=True: every channel enters the discrepancy)
or the user's own maps (an array per frame or a callable); the discrepancy may be a local
normalised cross-correlation ('ncc') or a Huber difference instead of F2 - F1; a motion
model (motion='velocity' or 'kalman', clpde.tracking.motion_filter.MotionFilter) shifts the level
set and F1 by the predicted displacement before each frame's evolution; shape_weight pulls
the contour towards that predicted start where the features say nothing; and each frame
reports its final discrepancy in the band (TrackState.discrepancy), a confidence measure.

This module holds the tracker and `track`; the steps live beside it: inputs.py checks the
frames and masks, options.py the options, preprocessing.py prepares the frames and their
features, prediction.py moves each frame's start by the motion model, morph.py runs the
coupled system on one frame pair and region_term.py keeps the adaptive discrepancy's
region term.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, DTypeLike
from scipy import ndimage

from .._progress import State, progress_bar
from ..errors import InputError
from ..fields import Field, check_fits
from ..runtime import DeviceLike, get_runtime
from .adaptive import LIGHT_CHANGE, QUIET_FACTOR, background_change, noise_variance
from .confidence import track_confidence
from .follow import ObjectFollower
from .inputs import check_frames, check_mask, scaled_frames, user_features
from .levelset import GHOST, MARGIN, LevelSet, signed_distance
from .morph import morph_pair
from .options import TrackOptions, track_options
from .prediction import MotionPrediction
from .preprocessing import feature_field, prepare_frame
from .region_term import RegionTerm


@dataclass
class TrackState(State):
    """One frame's result: its boolean mask, the level set u (negative inside) and how the
    morphing went (iterations, whether it stopped on its own, band rebuilds)."""

    index: int
    mask: np.ndarray
    level_set: np.ndarray
    iterations: int = 0
    converged: bool = True
    rebuilds: int = 0
    info: dict = field(default_factory=dict)
    discrepancy: float = 0.0  # final mean |beta| in the band (lower: the frames agree)
    displacement: tuple = (0.0, 0.0)  # (dy, dx) the motion model shifted the start by

    @property
    def step(self) -> int:
        """The frame's index: how far along the sequence the run is."""
        return self.index

    @property
    def time(self) -> None:
        """None: frames have indices, not times."""
        return None


class MorphingTracker:
    """The object form of `track`: iterate to get each frame's mask and level set in turn.

    Parameters
    ----------
    frames : array_like
        As for `track`.
    first_mask : array_like
        As for `track`.
    options : TrackOptions, optional
        As for `track`.
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    dtype : {float32, float64}, optional
        The device's arithmetic.
    **overrides
        As for `track`: fields of TrackOptions, and `features` as the user's own maps.

    Raises
    ------
    InputError
        For frames, a mask or options that cannot be used.

    Examples
    --------
    >>> import numpy as np
    >>> yy, xx = np.mgrid[:48, :48]
    >>> frames = np.stack([((yy - 24) ** 2 + (xx - 16 - 3 * t) ** 2 < 64).astype(np.float32)
    ...                    for t in range(3)])
    >>> tracker = MorphingTracker(frames, frames[0] > 0.5)
    >>> [state.mask.shape for state in tracker.iterate()]     # show(state.mask, ...)
    [(48, 48), (48, 48), (48, 48)]
    """

    def __init__(
        self,
        frames: ArrayLike,
        first_mask: ArrayLike,
        *,
        options: TrackOptions | None = None,
        device: DeviceLike = None,
        dtype: DTypeLike | None = None,
        **overrides: Any,
    ):
        self.frames = check_frames(frames)
        self.first_mask = check_mask(first_mask, self.frames[0].shape[:2])
        self._user = None
        features = overrides.get("features")
        if features is not None and (callable(features) or not isinstance(features, str)):
            self._user = user_features(features, self.frames)
            overrides["features"] = "user"
        self.options = track_options(options, **overrides)
        colour = self.options.colour
        self.runtime = get_runtime(device)
        self.dtype = np.dtype(dtype or np.float32)
        # a frame's level set (three fields, three masks, index lists) and its features
        check_fits(
            self.runtime,
            (1,) + self.frames[0].shape,
            "tracking",
            10,
            ghost=GHOST + MARGIN,
            dtype=self.dtype,
        )
        self._scaled = scaled_frames(self.frames, colour)
        self.channels = (self._user if self._user is not None else self._scaled).shape[1]
        # the appearance model's frames: colour where the footage has it (the same array
        # where the discrepancy's frames are in colour too, or the footage is grey)
        image = self.options.motion == "image"
        same = colour or self.frames[0].ndim == 2
        self._looks = (
            (self._scaled if same else scaled_frames(self.frames, True)) if image else None
        )

    def __len__(self) -> int:
        return len(self.frames)

    def prepared(self, index: int) -> np.ndarray:
        """Frame `index` after pre-processing (histogram equalisation, anisotropic
        smoothing), in [0, 1], as (C, H, W); the user's feature maps as given (scaled)."""
        if self._user is not None:
            return self._user[index]
        return prepare_frame(self._scaled, index, self.options, self.runtime)

    def iterate(self) -> Iterator[TrackState]:
        """Track frame after frame, yielding each one's TrackState (frame 0's first)."""
        options = self.options
        mask = self.first_mask
        u = signed_distance(mask)
        yield TrackState(0, mask.copy(), u.astype(np.float32))
        if len(self.frames) == 1:
            return
        ls = LevelSet(self.runtime, u, options.band_width, self.dtype, storage=options.storage)
        # The shape pull's target; without it the kernel multiplies it by 0, so any finite
        # buffer of the grid will do.
        prior = Field.empty(ls.grid) if options.shape_weight else ls.u.cur
        image = options.motion == "image"
        prediction = MotionPrediction(options) if options.motion and not image else None
        adaptive = options.discrepancy == "adaptive"
        region = RegionTerm(ls, options.region_weight) if adaptive else None
        follow = ObjectFollower(self, ls) if image else None
        prepared_prev = self.prepared(0)
        fresh = True  # u is a signed distance with a band around its zero set
        for t in range(1, len(self.frames)):
            prepared = self.prepared(t)
            f2 = feature_field(prepared, ls, options)
            # the frame's noise, for the adaptive discrepancy and the pieces' matching
            noise2 = noise_variance(prepared) if adaptive or options.motion == "components" else 0.0
            # the adaptive weight's noise: raised on frames whose background changed no more
            # than the noise explains, where the grey levels can be compared as they are
            noise2_weight = noise2
            if adaptive and not (options.region_weight or options.curvature):
                change = background_change(prepared_prev, prepared, mask, noise2)
                noise2_weight = noise2 * (QUIET_FACTOR if change < LIGHT_CHANGE else 1.0)
            shift = (0.0, 0.0)
            if follow is not None:
                prepared_prev, shift = follow.move(t, prepared_prev, prepared, mask)
                region = follow.term or region
                fresh = False
            if prediction is not None:
                prepared_prev, shift, moved = prediction.move(
                    ls, prepared_prev, prepared, mask, noise2
                )
                fresh = fresh and not moved
            f1 = feature_field(prepared_prev, ls, options)
            if region is not None:
                region.start(ls, prepared, noise2)
            if not fresh:  # a frame without rebuilds may have bent u away from a distance
                ls.rebuild(options.reinit_iterations)
            if options.shape_weight:
                prior.assign(ls.u.cur)
            rebuilds0 = ls.rebuilds
            iterations, converged, residual = morph_pair(
                ls, f1, f2, prior, options, self.channels, region, noise2_weight
            )
            fresh = ls.rebuilds > rebuilds0
            u = ls.values()
            new_mask = u < 0
            if options.min_size > 0:
                cleaned = self._clean(new_mask)
                if (cleaned != new_mask).any() and cleaned.any() and not cleaned.all():
                    new_mask = cleaned
                    u = signed_distance(new_mask)
                    ls.assign(u)
                    fresh = True
            if prediction is not None:
                prediction.observe(mask, new_mask)
            if follow is not None:
                cleaned = follow.observe(t, new_mask, u)
                if (cleaned != new_mask).any():
                    # all hidden: an empty mask, u positive everywhere
                    u = signed_distance(cleaned) if cleaned.any() else np.abs(u) + 1
                    new_mask = cleaned
            mask = new_mask
            yield TrackState(
                t,
                mask,
                u.astype(np.float32),
                iterations,
                converged,
                ls.rebuilds - rebuilds0,
                discrepancy=residual,
                displacement=tuple(float(s) for s in shift),
            )
            prepared_prev = prepared

    def confidence(self, masks: ArrayLike) -> np.ndarray:
        """The confidence per frame of a track of these frames (clpde.tracking.confidence).

        Parameters
        ----------
        masks : array_like
            (T, H, W) boolean masks, one per frame (e.g. the states' masks in turn).

        Returns
        -------
        numpy.ndarray
            (T,) float64 in [0, 1]: the calibrated probability that each frame's contour
            still holds its object (frame 0: 1). Below `LOW_CONFIDENCE`: flag it.

        Raises
        ------
        InputError
            If the masks do not match the frames' count and size.

        Examples
        --------
        >>> import numpy as np
        >>> yy, xx = np.mgrid[:40, :40]
        >>> frames = np.stack([np.hypot(yy - 20, xx - 14 - 2 * t) < 8 for t in range(3)]) * 0.6
        >>> tracker = MorphingTracker(frames, frames[0] > 0.3)
        >>> tracker.confidence([s.mask for s in tracker.iterate()]).shape
        (3,)
        """

        masks = np.asarray(masks, bool)
        if masks.shape != (len(self.frames),) + self.first_mask.shape:
            raise InputError(
                f"confidence needs one ({self.first_mask.shape[0]}, "
                f"{self.first_mask.shape[1]}) mask per frame, got {masks.shape}"
            )
        return track_confidence(self._scaled.mean(axis=1), masks)

    def _clean(self, mask: np.ndarray) -> np.ndarray:
        """Post-processing: drop components and fill holes smaller than min_size pixels."""
        return _drop_small(~_drop_small(~mask, self.options.min_size), self.options.min_size)


def _drop_small(mask: np.ndarray, min_size: int) -> np.ndarray:
    """The mask without its 8-connected components of fewer than min_size pixels."""
    labels, _ = ndimage.label(mask, structure=np.ones((3, 3)))
    sizes = np.bincount(labels.ravel())
    keep = sizes >= min_size
    keep[0] = False
    return keep[labels]


def track(
    frames: ArrayLike,
    first_mask: ArrayLike,
    *,
    options: TrackOptions | None = None,
    device: DeviceLike = None,
    dtype: DTypeLike | None = None,
    progress: bool | None = None,
    return_level_sets: bool = False,
    return_discrepancy: bool = False,
    return_confidence: bool = False,
    **overrides: Any,
) -> np.ndarray | tuple[np.ndarray, ...]:
    """Follow the object marked in the first frame through a sequence (thesis section 2.1).

    Parameters
    ----------
    frames : array_like
        A (T, H, W) grey or (T, H, W, 3) colour array, or a sequence of T such frames (any
        int or float dtype).
    first_mask : array_like
        (H, W) boolean (or nonzero) mask of the object in frame 0; it may hold several
        pieces, and pieces may split or merge on the way.
    options : TrackOptions, optional
        The tracker's options, one frozen object that holds their defaults and checks
        (clpde.tracking.options.TrackOptions documents each: features, discrepancy, motion,
        equalize, smooth, band_width, max_iterations, tol, min_size, storage, ...). None:
        the defaults.
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    dtype : {float32, float64}, optional
        The device's arithmetic.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    return_level_sets : bool, optional
        Also return the (T, H, W) float32 level sets (negative inside).
    return_discrepancy : bool, optional
        Also return the (T,) final mean |beta| in each frame's band (0 for frame 0), whose
        high values mark frames of low confidence.
    return_confidence : bool, optional
        Also return the (T,) confidence per frame in [0, 1] (see Returns).
    **overrides
        Fields of TrackOptions that replace those of `options` (features='edges',
        tol=0.01, motion='image', ...), checked once with them; a name TrackOptions lacks
        is an InputError that lists its fields. `features` may also be the user's own
        maps: a (T, H, W[, C]) array, a list of T maps, or a callable taking a frame and
        returning its map (scaled to [0, 1] over the sequence; no pre-processing). With
        motion='components', discrepancy='adaptive' and the weights REGION_WEIGHT and
        CURVATURE of clpde.tracking.options, region_weight and curvature make the adaptive
        option, better on the synthetic corpus and worse on real video and slices
        (docs/tracking.md).

    Returns
    -------
    masks : ndarray of bool
        (T, H, W); frame 0 is the given mask.
    level_sets : ndarray of float32
        Only with `return_level_sets`.
    discrepancy : ndarray
        Only with `return_discrepancy`.
    confidence : ndarray
        Only with `return_confidence`: (T,) in [0, 1] (clpde.tracking.confidence: a model
        calibrated on good and lost tracks of the calibration half of
        benchmarks/track_corpus.py); frames below LOW_CONFIDENCE are likely lost.

    Raises
    ------
    InputError
        For frames, a mask or options that cannot be used; the message names the fix.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> yy, xx = np.mgrid[:48, :48]
    >>> frames = np.stack([((yy - 24) ** 2 + (xx - 16 - 3 * t) ** 2 < 64).astype(np.float32)
    ...                    for t in range(4)])                 # a disc moving right
    >>> masks = clpde.track(frames, frames[0] > 0.5)
    >>> masks.shape, masks.dtype
    ((4, 48, 48), dtype('bool'))
    >>> bool((masks[-1] == (frames[-1] > 0.5)).mean() > 0.99)   # found in the last frame
    True
    """
    tracker = MorphingTracker(
        frames, first_mask, options=options, device=device, dtype=dtype, **overrides
    )
    n = len(tracker)
    height, width = tracker.first_mask.shape
    masks = np.zeros((n, height, width), bool)
    levels = np.zeros((n, height, width), np.float32) if return_level_sets else None
    residuals = np.zeros(n)
    for state in progress_bar(
        progress, n, "clpde track", iterable=tracker.iterate(), unit="frame", long_run=n >= 20
    ):
        masks[state.index] = state.mask
        residuals[state.index] = state.discrepancy
        if levels is not None:
            levels[state.index] = state.level_set
    out = (
        (masks,)
        + ((levels,) if return_level_sets else ())
        + ((residuals,) if return_discrepancy else ())
        + ((tracker.confidence(masks),) if return_confidence else ())
    )
    return out[0] if len(out) == 1 else out
