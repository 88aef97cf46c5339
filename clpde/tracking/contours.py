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
model (motion='velocity' or 'kalman', clpde.tracking.features.MotionFilter) shifts the level
set and F1 by the predicted displacement before each frame's evolution; shape_weight pulls
the contour towards that predicted start where the features say nothing; and each frame
reports its final discrepancy in the band (TrackState.discrepancy), a confidence measure.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pyopencl.array as cla
from numpy.typing import ArrayLike, DTypeLike

from .._progress import State, progress_bar
from ..errors import InputError
from ..fields import Field, PingPong, check_fits
from ..imagedata import value_range
from ..planar.flows import diffuse
from ..runtime import DeviceLike, get_runtime
from .adaptive import ComponentMotion, noise_variance, region_field
from .confidence import track_confidence
from .features import MotionFilter, local_contrast, shift_image
from .levelset import GHOST, MARGIN, STORAGES, LevelSet, signed_distance

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("tracking/levelset.cl", "tracking/features.cl", "tracking/adaptive.cl")

FEATURES = ("intensity", "edges", "contrast")
DISCREPANCIES = {"difference": 0, "ncc": 1, "huber": 2, "adaptive": 3}
MOTIONS = (None, "velocity", "kalman", "components")
CFL = 0.5  # largest distance in pixels a level set moves in one step
# Rebuild when the front comes this close to the band's outer ring. Between two checks
# (check_every steps) the front moves at most check_every * CFL pixels, so it cannot leave
# the band unnoticed while NEAR_EDGE >= check_every * CFL.
NEAR_EDGE = 1.0
# The adaptive discrepancy's weights, chosen on the calibration half of
# benchmarks/track_corpus.py (benchmarks/tracking_generalise.py --calibrate).
REGION_WEIGHT = 1.0  # the region term's largest speed, px per unit time
CURVATURE = 0.3  # the curvature term's weight
ADAPTIVE_ITERATIONS = 20  # the cap of iterations per frame with the adaptive discrepancy
REGION_SIGMA = 6.0  # px: the windows of the region term's local statistics
REGION_SEPARATION = 0.5  # Bhattacharyya distance at which the region term has half weight
DISCREPANCY_WEIGHT = 1.0  # the frame-to-frame discrepancy's share of the contour's speed
CONTRAST_NOISE = 4.0  # the correlation takes over where a window's variance passes this x noise
REGION_REFRESH = 10  # iterations between updates of the region term's statistics


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


def _check_frames(frames) -> list[np.ndarray]:
    if isinstance(frames, np.ndarray):
        if frames.ndim not in (3, 4) or (frames.ndim == 4 and frames.shape[-1] not in (3, 4)):
            raise InputError(
                f"frames must be a (T, H, W) grey or (T, H, W, 3) colour array, or a sequence "
                f"of frames, got an array of shape {frames.shape}"
            )
        items = list(frames)
    else:
        try:
            items = [np.asarray(f) for f in frames]
        except TypeError:
            raise InputError(
                "frames must be a (T, H, W) array or a sequence of 2-D arrays"
            ) from None
    if not items:
        raise InputError("frames is empty: give at least one frame")
    for k, f in enumerate(items):
        if not (f.ndim == 2 or (f.ndim == 3 and f.shape[-1] in (3, 4))):
            raise InputError(
                f"frame {k} has shape {f.shape}; every frame must be 2-D (grey) or (H, W, 3) colour"
            )
        if f.shape != items[0].shape:
            raise InputError(
                f"frame {k} is {f.shape[1]}x{f.shape[0]} but frame 0 is "
                f"{items[0].shape[1]}x{items[0].shape[0]}; all frames must have one size"
                + ("" if f.shape[:2] != items[0].shape[:2] else " and kind (grey or colour)")
            )
        if f.dtype == bool or not (
            np.issubdtype(f.dtype, np.integer) or np.issubdtype(f.dtype, np.floating)
        ):
            raise InputError(f"frame {k} has dtype {f.dtype}; expected integers or floats")
        if np.issubdtype(f.dtype, np.floating) and not np.isfinite(f).all():
            raise InputError(f"frame {k} contains NaN or infinite values")
    return items


def _check_mask(mask, shape) -> np.ndarray:
    mask = np.asarray(mask)
    if mask.ndim == 3 and mask.shape[-1] in (3, 4):  # a colour mask image: any nonzero colour
        mask = mask[..., :3].any(axis=-1)
    if mask.shape != shape:
        raise InputError(
            f"the first mask is {mask.shape[-1]}x{mask.shape[0]} (shape {mask.shape}) but the "
            f"frames are {shape[1]}x{shape[0]}; draw the mask on the first frame at its size"
        )
    mask = mask > 0 if mask.dtype != bool else mask
    if not mask.any():
        raise InputError("the first mask is empty: mark the object to follow in the first frame")
    if mask.all():
        raise InputError("the first mask covers the whole frame: leave the background unmarked")
    return mask


def _user_features(features, frames: list[np.ndarray]) -> np.ndarray:
    """The user's feature maps as a (T, C, H, W) float64 array scaled to [0, 1] over the
    whole sequence (one scale for all frames keeps F2 - F1 meaningful)."""
    shape = frames[0].shape[:2]
    if callable(features):
        try:
            maps = [np.asarray(features(f), np.float64) for f in frames]
        except InputError:
            raise
        except Exception as exc:
            raise InputError(f"the features callable failed on a frame: {exc}") from exc
    else:
        maps = features
    try:
        stack = np.stack([np.asarray(m, np.float64) for m in maps])
    except ValueError:
        raise InputError("the feature maps must all have one shape") from None
    if len(stack) != len(frames):
        raise InputError(f"{len(stack)} feature maps for {len(frames)} frames: give one per frame")
    if stack.shape[1:3] == shape:
        stack = stack[:, np.newaxis] if stack.ndim == 3 else np.moveaxis(stack, -1, 1)
    if stack.ndim != 4 or stack.shape[2:] != shape:
        raise InputError(
            f"feature maps of shape {stack.shape[1:]} do not fit frames of {shape[1]}x{shape[0]}: "
            "give (H, W) or (H, W, C) per frame"
        )
    if not np.isfinite(stack).all():
        raise InputError("the feature maps contain NaN or infinite values")
    lo, hi = float(stack.min()), float(stack.max())
    return (stack - lo) / (hi - lo) if hi > lo else np.zeros_like(stack)


class MorphingTracker:
    """The object form of `track`: iterate to get each frame's mask and level set in turn.

    Parameters
    ----------
    frames : array_like
        As for `track`.
    first_mask : array_like
        As for `track`.
    features : {'intensity', 'edges', 'contrast'} or array_like or callable, optional
        As for `track`.
    colour : bool, optional
        Put every channel of colour frames in the discrepancy (default: grey, Rec. 601
        luma).
    discrepancy : {'ncc', 'difference', 'huber'}, optional
        How F2 and F1 are compared: steepest ascent of the local normalised
        cross-correlation over a (2 ncc_radius + 1)^2 window, F2 - F1 (the thesis), or F2 -
        F1 clipped at huber_delta.
    motion : {'kalman', 'velocity', None}, optional
        Each frame's start: shifted by a constant-velocity Kalman filter fed by matching the
        object's features (within search_radius pixels of the prediction), by the previous
        displacement, or not at all.
    shape_weight : float, optional
        (>= 0, e.g. 0.05) pulls the contour towards the start where the features say
        nothing.
    equalize : bool or {'match', 'global'}, optional
        As for `track`.
    smooth : bool, optional
        As for `track`.
    smooth_steps : int, optional
        As for `track`.
    smooth_kappa : float, optional
        Perona-Malik's edge threshold of the pre-smoothing.
    band_width : float, optional
        As for `track`.
    max_iterations : int, optional
        As for `track`.
    tol : float, optional
        As for `track`.
    check_every : int, optional
        Iterations between the speed checks.
    dt : float, optional
        The morphing's time step (bounded by the CFL condition).
    max_dt : float, optional
        The largest time step the adaptive step may take.
    reinit_iterations : int, optional
        Reinitialisation iterations of the level set.
    min_size : int, optional
        As for `track`.
    contrast_radius : int, optional
        Half-width of the box of features='contrast'.
    contrast_eps : float, optional
        Regularisation of features='contrast' (intensities in [0, 1]).
    ncc_radius : int, optional
        Half-width of the NCC's window.
    huber_delta : float, optional
        The clipping of discrepancy='huber'.
    search_radius : int, optional
        The motion filter's search radius in pixels.
    region_weight : float, optional
        discrepancy='adaptive': the weight of the region term (the foreground's and
        background's local statistics near the contour); None: the calibrated default.
    curvature : float, optional
        discrepancy='adaptive': the weight of the curvature term; None: the calibrated
        default.
    storage : {'lists', 'bricks8x8', 'bricks16x4'}, optional
        The band as a list of cells or of bricks (the same results, bit for bit except the
        NCC's window sums, equal to rounding; docs/tracking.md).
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    dtype : {float32, float64}, optional
        The device's arithmetic.

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
        features: str | ArrayLike | Callable = "intensity",
        colour: bool = False,
        discrepancy: str = "ncc",
        motion: str | None = "kalman",
        shape_weight: float = 0.0,
        equalize: bool | str = False,
        smooth: bool = True,
        smooth_steps: int = 5,
        smooth_kappa: float = 0.08,
        band_width: float = 3.0,
        max_iterations: int | None = None,
        tol: float = 0.02,
        check_every: int = 2,
        dt: float = 0.5,
        max_dt: float = 4.0,
        reinit_iterations: int = 5,
        min_size: int = 0,
        contrast_radius: int = 4,
        contrast_eps: float = 0.02,
        ncc_radius: int = 3,
        huber_delta: float = 0.05,
        search_radius: int = 6,
        storage: str = "lists",
        region_weight: float | None = None,
        curvature: float | None = None,
        device: DeviceLike = None,
        dtype: DTypeLike | None = None,
    ):
        self.frames = _check_frames(frames)
        self.first_mask = _check_mask(first_mask, self.frames[0].shape[:2])
        self._user = None
        if callable(features) or not isinstance(features, str):
            self._user = _user_features(features, self.frames)
            features = "user"
        elif features not in FEATURES:
            raise InputError(
                f"features must be one of {', '.join(FEATURES)}, an array of maps "
                f"per frame or a callable, not {features!r}"
            )
        if discrepancy not in DISCREPANCIES:
            raise InputError(
                f"discrepancy must be one of {', '.join(DISCREPANCIES)}, not {discrepancy!r}"
            )
        if motion not in MOTIONS:
            raise InputError(
                f"motion must be None, 'velocity', 'kalman' or 'components', not {motion!r}"
            )
        if not 0 < dt <= 0.5:
            raise InputError(f"dt={dt} is outside (0, 0.5], the stable range of the upwind scheme")
        if max_iterations is None:
            max_iterations = ADAPTIVE_ITERATIONS if discrepancy == "adaptive" else 40
        if max_iterations < 1 or check_every < 1:
            raise InputError("max_iterations and check_every must be at least 1")
        if check_every * CFL > NEAR_EDGE:
            raise InputError(
                f"check_every={check_every} lets the front move {check_every * CFL:g} pixels "
                f"between checks, more than the band's {NEAR_EDGE:g}-pixel safety margin; "
                f"use check_every <= {int(NEAR_EDGE / CFL)}"
            )
        if not 1 <= int(ncc_radius) <= 4:
            raise InputError(f"ncc_radius must be 1 to 4 pixels, not {ncc_radius}")
        if not 1 <= int(contrast_radius) <= 16:
            raise InputError(f"contrast_radius must be 1 to 16 pixels, not {contrast_radius}")
        if shape_weight < 0 or huber_delta <= 0 or search_radius < 0 or contrast_eps <= 0:
            raise InputError(
                "shape_weight and search_radius must be >= 0, huber_delta and contrast_eps > 0"
            )
        adaptive = discrepancy == "adaptive"
        region_weight = (
            (REGION_WEIGHT if adaptive else 0.0) if region_weight is None else float(region_weight)
        )
        curvature = (CURVATURE if adaptive else 0.0) if curvature is None else float(curvature)
        if region_weight < 0 or curvature < 0:
            raise InputError("region_weight and curvature must be at least 0")
        if not adaptive and (region_weight or curvature):
            raise InputError(
                "region_weight and curvature work with discrepancy='adaptive' "
                "only: drop them or use the adaptive discrepancy"
            )
        self.region_weight, self.curvature = region_weight, curvature
        self.features, self.discrepancy, self.motion = features, discrepancy, motion
        self.shape_weight = float(shape_weight)
        self.contrast_radius, self.ncc_radius = int(contrast_radius), int(ncc_radius)
        self.contrast_eps = float(contrast_eps)
        self.huber_delta, self.search_radius = float(huber_delta), int(search_radius)
        if equalize is True:
            equalize = "match"
        if equalize not in (False, None, "match", "global"):
            raise InputError(f"equalize must be 'match', 'global' or False, not {equalize!r}")
        self.equalize, self.smooth = equalize or False, bool(smooth)
        self.smooth_steps, self.smooth_kappa = int(smooth_steps), float(smooth_kappa)
        self.band_width = float(band_width)
        self.max_iterations, self.tol = int(max_iterations), float(tol)
        self.check_every, self.dt, self.min_size = int(check_every), float(dt), int(min_size)
        self.max_dt = max(float(max_dt), self.dt)
        self.reinit_iterations = int(reinit_iterations)
        if storage not in STORAGES:
            raise InputError(f"storage must be one of {', '.join(STORAGES)}, not {storage!r}")
        self.storage = storage
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
        stack = np.stack([f.astype(np.float64) for f in self.frames])
        if stack.ndim == 4:  # colour: all channels, or grey (Rec. 601 luma)
            stack = (
                np.moveaxis(stack[..., :3], -1, 1)
                if colour
                else (stack[..., :3] @ np.array([0.299, 0.587, 0.114]))[:, np.newaxis]
            )
        else:
            stack = stack[:, np.newaxis]
        lo, hi = float(stack.min()), float(stack.max())
        value_range(lo, hi, "frames")  # refuses a span that overflows float64
        self._scaled = (stack - lo) / (hi - lo) if hi > lo else np.zeros_like(stack)
        self.channels = (self._user if self._user is not None else self._scaled).shape[1]

    def __len__(self) -> int:
        return len(self.frames)

    # ---- pre-processing and features ---------------------------------------------------
    def prepared(self, index: int) -> np.ndarray:
        """Frame `index` after pre-processing (histogram equalisation, anisotropic
        smoothing), in [0, 1], as (C, H, W); the user's feature maps as given (scaled)."""
        if self._user is not None:
            return self._user[index]
        img = self._scaled[index]
        if self.equalize == "match" and index > 0:
            # Equalise the grey levels across the sequence: each frame gets the first
            # frame's histogram, as beta = F2 - F1 compares grey values directly.
            img = np.stack(
                [match_histogram(c, r) for c, r in zip(img, self._scaled[0], strict=False)]
            )
        elif self.equalize == "global":
            from skimage.exposure import equalize_hist

            img = np.stack([equalize_hist(c) for c in img])
        if self.smooth and self.smooth_steps > 0:
            # The rational edge-stopping function: as anisotropic as the exponential one
            # and about 3x faster on PoCL, where exp() does not vectorise.
            img = np.stack(
                [
                    diffuse(
                        c,
                        "perona-malik",
                        steps=self.smooth_steps,
                        kappa=self.smooth_kappa,
                        edge="rational",
                        device=self.runtime,
                        progress=False,
                    )
                    for c in img
                ]
            )
        return np.asarray(img, np.float64)

    def _feature_field(self, image: np.ndarray, ls: LevelSet) -> Field:
        grid = replace(ls.grid, nc=self.channels)
        f = Field.from_host(grid, np.stack([ls.pad(c) for c in image]))
        if self.features in ("edges", "contrast"):
            out = Field.empty(grid)
            if self.features == "edges":
                grid.launch(
                    grid.kernel("tracking/levelset.cl", "gradient_magnitude"),
                    f.data.data,
                    out.data.data,
                )
            else:
                # Scaled by 1/4: normalised values of about +-2 become F2 - F1 of the
                # order of the [0, 1] grey levels, for which tol and dt are set.
                grid.launch(
                    grid.kernel("tracking/features.cl", "local_contrast"),
                    f.data.data,
                    out.data.data,
                    np.int32(self.contrast_radius),
                    grid.scalar(self.contrast_eps**2),
                    grid.scalar(0.25),
                )
            out.fill_ghosts()
            f = out
        return f

    def _match_features(self, image: np.ndarray) -> np.ndarray:
        """(C, H, W) local contrast normalisation of a prepared frame, for matching."""

        return local_contrast(image, self.contrast_radius)

    # ---- the morphing of one frame pair ------------------------------------------------
    def _morph(
        self,
        ls: LevelSet,
        f1: Field,
        f2: Field,
        prior: Field,
        discrepancy=None,
        region: Field | None = None,
        noise2: float = 0.0,
        refresh=None,
    ):
        """Run the coupled system on one frame pair; returns (iterations, converged,
        final mean |beta| in the band).

        The time step adapts at each check to the largest stable one: the level sets move
        at most CFL pixels per step (dt (|beta| + lam w) <= CFL), F1's relaxation towards
        F2 does not overshoot (dt |grad F1| <= 1) nor does u's towards the prior
        (dt lam <= 1/2). It restarts from `dt` whenever the band changes.
        """
        g = ls.grid
        q = self.runtime.queue
        discrepancy = discrepancy or self.discrepancy
        extra = ()
        if discrepancy == "adaptive":
            kernel = ls.band_kernel(
                "tracking/adaptive.cl",
                "morph_adaptive" if ls.brick is None else "morph_adaptive_bricks",
                NCH=self.channels,
                WIN=self.ncc_radius,
            )
            extra = (
                (region if region is not None else ls.u.cur).data.data,
                g.scalar(CONTRAST_NOISE * noise2 + 1e-6),
                g.scalar(self.curvature),
                g.scalar(DISCREPANCY_WEIGHT),
            )
        else:
            kernel = ls.band_kernel(
                "tracking/features.cl",
                morph_kernel_name(ls, discrepancy),
                NCH=self.channels,
                DISC=DISCREPANCIES[discrepancy],
                WIN=self.ncc_radius,
            )
        pair = PingPong(f1)
        lam = self.shape_weight
        delta = self.huber_delta if discrepancy == "huber" else 0.02
        consts = (
            g.scalar(0.02**2),
            g.scalar(1e-3**2),
            g.scalar(NEAR_EDGE),
            g.scalar(lam),
            g.scalar(delta),
            np.int32(g.sx),
            np.int32(g.plane),
        )
        dt_cap = self.max_dt if lam == 0 else min(self.max_dt, 0.5 / lam)
        if discrepancy == "adaptive" and self.curvature > 0:
            dt_cap = min(dt_cap, 0.2 / self.curvature)  # the explicit curvature term's limit
        first_dt = min(self.dt, dt_cap)
        stats = None
        dt = first_dt
        converged = False
        iterations = 0
        residual = 0.0
        while iterations < self.max_iterations:
            if ls.band.n == 0:  # the contour vanished from the frame
                converged = True
                break
            if refresh is not None and iterations and iterations % REGION_REFRESH == 0:
                # The region term's statistics follow the contour (as Chan-Vese's do).
                region = refresh()
                extra = (region.data.data,) + extra[1:]
            if stats is None:
                parts = ls.band_parts()
                stats = cla.zeros(q, 5 * parts + 1, g.dtype)
            ls.launch_band(
                kernel,
                ls.band,
                ls.u.cur.data.data,
                pair.cur.data.data,
                f2.data.data,
                ls.band_mask.data,
                prior.data.data,
                ls.u.nxt.data.data,
                pair.nxt.data.data,
                stats.data,
                g.scalar(dt),
                *consts,
                *extra,
            )
            ls.u.swap()
            pair.swap()
            iterations += 1
            if iterations % self.check_every == 0 or iterations == self.max_iterations:
                # One small read every few steps: speed, stability maxima and edge flag.
                values = stats.get()
                fastest, beta_max, grad_max = (
                    values[k * parts : (k + 1) * parts].max() for k in range(3)
                )
                residual = float(
                    values[3 * parts : 4 * parts].sum()
                    / max(values[4 * parts : 5 * parts].sum(), 1)
                )
                if fastest < self.tol:
                    converged = True
                    break
                if values[5 * parts]:
                    ls.rebuild(self.reinit_iterations)
                    pair.nxt.assign(pair.cur)  # the band moved: both copies agree outside it
                    stats = None
                    dt = first_dt
                else:
                    speed = beta_max + lam * self.band_width
                    dt = float(min(dt_cap, CFL / max(speed, 1e-6), 1.0 / max(grad_max, 1e-6)))
        return iterations, converged, residual

    # ---- iteration ---------------------------------------------------------------------
    def iterate(self) -> Iterator[TrackState]:
        """Track frame after frame, yielding each one's TrackState (frame 0's first)."""

        mask = self.first_mask
        u = signed_distance(mask)
        yield TrackState(0, mask.copy(), u.astype(np.float32))
        if len(self.frames) == 1:
            return
        ls = LevelSet(self.runtime, u, self.band_width, self.dtype, storage=self.storage)
        # The shape pull's target; without it the kernel multiplies it by 0, so any finite
        # buffer of the grid will do.
        prior = Field.empty(ls.grid) if self.shape_weight else ls.u.cur
        prepared_prev = self.prepared(0)
        pieces_motion = None
        if self.motion == "components":
            pieces_motion, motion = ComponentMotion(self.search_radius), None
        else:
            motion = MotionFilter(self.motion, self.search_radius) if self.motion else None
        adaptive = self.discrepancy == "adaptive"
        region = None
        feats_prev = None
        fresh = True  # u is a signed distance with a band around its zero set
        for t in range(1, len(self.frames)):
            prepared = self.prepared(t)
            f2 = self._feature_field(prepared, ls)
            shift = (0.0, 0.0)
            if motion is not None:
                # Matched on contrast-normalised frames, whatever the morphing compares:
                # a shadow or a flicker does not move the measured displacement.
                feats = self._match_features(prepared)
                if feats_prev is None:
                    feats_prev = self._match_features(prepared_prev)
                shift = motion.predict(feats_prev, feats, mask)
                feats_prev = feats
                if max(abs(shift[0]), abs(shift[1])) < 0.25:
                    # Below the matching's precision; shifting would only blur F1.
                    shift = (0.0, 0.0)
                else:
                    # Start from the predicted place: u and F1 move together, so the
                    # morphing only has to explain what the displacement does not.
                    u = shift_image(ls.values(), shift)
                    ls.assign(u)
                    prepared_prev = np.stack([shift_image(c, shift) for c in prepared_prev])
                    fresh = False
            if pieces_motion is not None:
                # Contrast-normalised as for the Kalman model, with eps raised to twice the
                # noise so that a flat, noisy patch is not blown up into texture.

                eps = max(self.contrast_eps, 2 * float(np.sqrt(noise_variance(prepared))))
                feats = local_contrast(prepared, self.contrast_radius, eps)
                if feats_prev is None:
                    feats_prev = local_contrast(prepared_prev, self.contrast_radius, eps)
                pieces = pieces_motion.predict(feats_prev, feats, mask)
                feats_prev = feats
                u_moved, prev_moved, moved = ComponentMotion.apply(
                    ls.values(), prepared_prev, pieces, self.band_width
                )
                if moved and (u_moved < 0).any() and not (u_moved < 0).all():
                    ls.assign(u_moved)
                    prepared_prev = prev_moved
                    fresh = False
                    big = max(pieces, key=lambda p: p[0].sum())
                    shift = big[1]
            f1 = self._feature_field(prepared_prev, ls)
            noise2, refresh = 0.0, None
            if adaptive:
                features = prepared if self._user is None else self._user[t]
                noise2 = noise_variance(features)

                region = region if region is not None else Field.empty(ls.grid)

                def refresh(features=features, noise2=noise2, region=region):
                    speed = np.zeros(features.shape[-2:])
                    if self.region_weight > 0:
                        speed = self.region_weight * region_field(
                            features, ls.values() < 0, REGION_SIGMA, REGION_SEPARATION, noise2
                        )
                    # Into the same buffer each time; band cells never read its ghosts.
                    padded = np.zeros(ls.grid.padded_shape, ls.grid.dtype)
                    ls.grid.interior(padded)[...] = ls.pad(speed)[np.newaxis]
                    region.data.set(padded)
                    return region

                region = refresh()
                if self.region_weight == 0:
                    refresh = None
            if not fresh:  # a frame without rebuilds may have bent u away from a distance
                ls.rebuild(self.reinit_iterations)
            if self.shape_weight:
                prior.assign(ls.u.cur)
            rebuilds0 = ls.rebuilds
            iterations, converged, residual = self._morph(
                ls, f1, f2, prior, region=region, noise2=noise2, refresh=refresh
            )
            fresh = ls.rebuilds > rebuilds0
            u = ls.values()
            new_mask = u < 0

            if self.min_size > 0:
                cleaned = self._clean(new_mask)
                if (cleaned != new_mask).any() and cleaned.any() and not cleaned.all():
                    new_mask = cleaned
                    u = signed_distance(new_mask)
                    ls.assign(u)
                    fresh = True
            if motion is not None:
                motion.observe(mask, new_mask)
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
        return _drop_small(~_drop_small(~mask, self.min_size), self.min_size)


def morph_kernel_name(ls: LevelSet, discrepancy: str) -> str:
    """The morphing step's kernel for the band's storage: with bricks walked by one
    work-item, the NCC slides its window sums over each brick (morph_track_tiled: 1.0-1.45x
    the cell-by-cell sums, measured in docs/tracking.md; equal to rounding)."""
    if ls.brick is None:
        return "morph_track"
    if discrepancy == "ncc" and not ls.group_per_brick:
        return "morph_track_tiled"
    return "morph_track_bricks"


def match_histogram(image: np.ndarray, reference: np.ndarray, levels: int = 4096) -> np.ndarray:
    """Histogram specification of data in [0, 1]: the grey-level map that gives `image` the
    grey-level distribution of `reference`, on `levels` quantisation levels (equal values
    stay equal)."""

    def quantise(a):
        return np.minimum((np.asarray(a) * levels).astype(np.int64), levels - 1)

    q = quantise(image)
    src = np.bincount(q.ravel(), minlength=levels).astype(np.float64)
    ref = np.bincount(quantise(reference).ravel(), minlength=levels).astype(np.float64)
    src_cdf = (np.cumsum(src) - 0.5 * src) / src.sum()  # each level at its mid-rank
    ref_cdf = (np.cumsum(ref) - 0.5 * ref) / ref.sum()
    present = ref > 0
    centres = (np.arange(levels) + 0.5) / levels
    mapping = np.interp(src_cdf, ref_cdf[present], centres[present])
    return mapping[q]


def _drop_small(mask: np.ndarray, min_size: int) -> np.ndarray:
    """The mask without its 8-connected components of fewer than min_size pixels."""
    from scipy import ndimage

    labels, _ = ndimage.label(mask, structure=np.ones((3, 3)))
    sizes = np.bincount(labels.ravel())
    keep = sizes >= min_size
    keep[0] = False
    return keep[labels]


def track(
    frames: ArrayLike,
    first_mask: ArrayLike,
    *,
    features: str | ArrayLike | Callable = "intensity",
    equalize: bool | str = False,
    smooth: bool = True,
    smooth_steps: int = 5,
    band_width: float = 3.0,
    max_iterations: int | None = None,
    tol: float = 0.02,
    min_size: int = 0,
    device: DeviceLike = None,
    progress: bool | None = None,
    return_level_sets: bool = False,
    return_discrepancy: bool = False,
    return_confidence: bool = False,
    **options: Any,
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
    features : {'intensity', 'edges', 'contrast'} or array_like or callable, optional
        What the frames are compared by: the frames themselves (after pre-processing),
        gradient-magnitude edge maps, local contrast normalisation over a
        (2 contrast_radius + 1)^2 box (invariant to local changes of light), or the user's
        own maps: a (T, H, W[, C]) array, a list of T maps, or a callable taking a frame
        and returning its map (scaled to [0, 1] over the sequence; no pre-processing).
    equalize : bool or {'match', 'global'}, optional
        Grey-level equalisation across frames: 'match' (or True) gives every frame the
        first frame's histogram, 'global' equalises each flat (costs accuracy on large
        uniform backgrounds, docs/tracking.md), False skips it.
    smooth : bool, optional
        Perona-Malik pre-smoothing of the frames (True by default).
    smooth_steps : int, optional
        Its number of steps.
    band_width : float, optional
        Half-width of the narrow band in pixels.
    max_iterations : int, optional
        Cap of morphing iterations per frame.
    tol : float, optional
        Each frame runs until the contour's top speed falls below `tol` pixels per unit
        time (or `max_iterations`).
    min_size : int, optional
        When > 0, components and holes smaller than this many pixels are removed from each
        result, and the next frame starts from the cleaned mask.
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    progress : bool, optional
        Draw a progress bar; by default only for long runs on a terminal.
    return_level_sets : bool, optional
        Also return the (T, H, W) float32 level sets (negative inside).
    return_discrepancy : bool, optional
        Also return the (T,) final mean |beta| in each frame's band (0 for frame 0), whose
        high values mark frames of low confidence.
    return_confidence : bool, optional
        Also return the (T,) confidence per frame in [0, 1] (see Returns).
    **options
        MorphingTracker's other options: colour (every channel in the discrepancy),
        discrepancy ('ncc', the default; 'difference', the thesis; 'huber'; 'adaptive':
        NCC where a window has contrast above the noise, F2 - F1 where it is flat, plus a
        region term of weight region_weight and a curvature term of weight curvature,
        better on the synthetic corpus and worse on real video and slices,
        docs/tracking.md), motion ('kalman', the default; None; 'velocity'; 'components':
        each connected piece matched on its own), shape_weight, storage ('lists',
        'bricks8x8' or 'bricks16x4': the same results), contrast_radius, ncc_radius,
        huber_delta, search_radius, region_weight, curvature, dtype.

    Returns
    -------
    masks : ndarray of bool
        (T, H, W); frame 0 is the given mask.
    level_sets : ndarray of float32
        Only with `return_level_sets`.
    discrepancy : ndarray
        Only with `return_discrepancy`.

    Raises
    ------
    InputError
        For frames, a mask or options that cannot be used; the message names the fix.
    confidence : ndarray
        Only with `return_confidence`: (T,) in [0, 1] (clpde.tracking.confidence: a model
        calibrated on good and lost tracks of the calibration half of
        benchmarks/track_corpus.py); frames below LOW_CONFIDENCE are likely lost.

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
        frames,
        first_mask,
        features=features,
        equalize=equalize,
        smooth=smooth,
        smooth_steps=smooth_steps,
        band_width=band_width,
        max_iterations=max_iterations,
        tol=tol,
        min_size=min_size,
        device=device,
        **options,
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
