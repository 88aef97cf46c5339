"""The tracker's options: TrackOptions, one frozen object holding their defaults and
checks, which `clpde.track`, `MorphingTracker`, `clpde track` and batch all build
(track_options applies a call's keywords); the tracker, the pre-processing and the
morphing read it."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

from ..errors import InputError
from .appearance import APPEARANCE_WEIGHT
from .levelset import CFL, NEAR_EDGE
from .storage import STORAGES

FEATURES = ("intensity", "edges", "contrast")
# discrepancy -> the DISC define of kernels/tracking/features.cl (adaptive: its own kernel)
DISCREPANCIES = {"difference": 0, "ncc": 1, "huber": 2, "adaptive": 3}
MOTIONS = (None, "velocity", "kalman", "checked", "components", "image")
# The adaptive option's weights (motion='components', discrepancy='adaptive' with these),
# chosen on the calibration half of benchmarks/track_corpus.py
# (benchmarks/tracking_generalise.py --calibrate). The default leaves both terms off: they
# win the synthetic corpus but lose the real video and slices (docs/tracking.md).
REGION_WEIGHT = 1.0  # the region term's largest speed, px per unit time
CURVATURE = 0.3  # the curvature term's weight
ADAPTIVE_ITERATIONS = 20  # the cap of iterations per frame with the region or curvature term
ITERATIONS = 40  # the cap of iterations per frame otherwise


@dataclass(frozen=True)
class TrackOptions:
    """The tracker's options (`clpde.track`, `MorphingTracker`, `clpde track` and batch
    build this one object), their defaults, checked on construction (one InputError line).

    Parameters
    ----------
    features : {'intensity', 'edges', 'contrast'}
        What the frames are compared by: the frames themselves (after pre-processing),
        gradient-magnitude edge maps, or local contrast normalisation over a
        (2 contrast_radius + 1)^2 box (invariant to local changes of light). The user's own
        maps (an array or a callable) are given to `track` as `features=` and stand here
        as 'user'.
    colour : bool
        Put every channel of colour frames in the discrepancy (default: grey, Rec. 601
        luma).
    discrepancy : {'adaptive', 'ncc', 'difference', 'huber'}
        How F2 and F1 are compared: 'adaptive' (the default) blends the two below, the
        correlation where a window has contrast well above the frame's noise and F2 - F1
        where it is flat or noisy; 'ncc', the steepest ascent of the local normalised
        cross-correlation over a (2 ncc_radius + 1)^2 window; F2 - F1 (the thesis); or F2 -
        F1 clipped at huber_delta.
    motion : {'image', 'checked', 'kalman', 'components', 'velocity', None}
        Each frame's start: 'image' (the default) moves it by the object's motion found in
        the image (a masked correlation over every shift up to 32 px, of the frames and of
        their light-blind local contrast, then a sub-pixel shift and, where it explains
        the object clearly better, an affine fit; clpde.tracking.appearance), its whole
        shape kept through occlusions, with the appearance term on, its evidence tempered
        by how well the object's colours separate from its surroundings' and believed as
        far as it classified the last result, unless the background moves otherwise than
        the object (clpde.tracking.follow); 'checked': a constant-velocity Kalman filter
        fed by matching the object's features (within search_radius pixels of the
        prediction), its shift checked against a wide search of the image (any shift up to
        32 px; clpde.tracking.prediction.checked_shift); 'kalman': the filter alone; each
        connected piece by its own match; by the previous displacement; or not at all.
    shape_weight : float
        (>= 0, e.g. 0.05) pulls the contour towards the start where the features say
        nothing.
    equalize : bool or {'match', 'global'}
        Grey-level equalisation across frames: 'match' (or True) gives every frame the
        first frame's histogram, 'global' equalises each flat (costs accuracy on large
        uniform backgrounds, docs/tracking.md), False skips it.
    smooth : bool
        Perona-Malik pre-smoothing of the frames.
    smooth_steps : int
        Its number of steps.
    smooth_kappa : float
        Its edge threshold.
    band_width : float
        Half-width of the narrow band in pixels.
    max_iterations : int, optional
        Cap of morphing iterations per frame (None: 40, or 20 with the region, curvature or
        appearance term; `iterations` is the cap in use).
    tol : float
        Each frame runs until the contour's top speed falls below `tol` pixels per unit
        time (or the cap of iterations).
    check_every : int
        Iterations between the speed checks.
    dt : float
        The morphing's time step (bounded by the CFL condition).
    max_dt : float
        The largest time step the adaptive step may take (at least dt).
    reinit_iterations : int
        Reinitialisation iterations of the level set.
    min_size : int
        When > 0, components and holes smaller than this many pixels are removed from each
        result, and the next frame starts from the cleaned mask.
    contrast_radius : int
        Half-width of the box of features='contrast'.
    contrast_eps : float
        Regularisation of features='contrast' (intensities in [0, 1]).
    ncc_radius : int
        Half-width of the NCC's window.
    huber_delta : float
        The clipping of discrepancy='huber'.
    search_radius : int
        The motion filter's search radius in pixels.
    storage : {'lists', 'bricks8x8', 'bricks16x4'}
        The band as a list of cells or of bricks (the same results, bit for bit except the
        NCC's window sums, equal to rounding; docs/tracking.md).
    region_weight : float, optional
        discrepancy='adaptive': the weight of the region term (the foreground's and
        background's local statistics near the contour); None or 0: off. The adaptive
        option's calibrated weight is REGION_WEIGHT.
    curvature : float, optional
        discrepancy='adaptive': the weight of the curvature term; None or 0: off (the
        adaptive option's: CURVATURE).
    appearance : float, optional
        With motion='image' (and the adaptive discrepancy): the largest speed of the
        appearance term, the colour (grey without colour) and texture histograms of the
        object against its surroundings (None: APPEARANCE_WEIGHT with motion='image' and
        the adaptive discrepancy without a region term, else 0; 0: off;
        `appearance_weight` is the weight in use).
    """

    features: str = "intensity"
    colour: bool = False
    discrepancy: str = "adaptive"
    motion: str | None = "image"
    shape_weight: float = 0.0
    equalize: bool | str = False
    smooth: bool = True
    smooth_steps: int = 5
    smooth_kappa: float = 0.08
    band_width: float = 3.0
    max_iterations: int | None = None
    tol: float = 0.02
    check_every: int = 2
    dt: float = 0.5
    max_dt: float = 4.0
    reinit_iterations: int = 5
    min_size: int = 0
    contrast_radius: int = 4
    contrast_eps: float = 0.02
    ncc_radius: int = 3
    huber_delta: float = 0.05
    search_radius: int = 6
    storage: str = "lists"
    region_weight: float | None = None
    curvature: float | None = None
    appearance: float | None = None

    def __post_init__(self) -> None:
        self._check_choices()
        self._check_adaptive()
        self._check_steps()
        self._check_sizes()
        self._normalise()

    @property
    def appearance_weight(self) -> float:
        """The appearance term's weight in use (`appearance`, or its default)."""
        if self.appearance is not None:
            return float(self.appearance)
        image = self.motion == "image" and self.discrepancy == "adaptive"
        return APPEARANCE_WEIGHT if image and not self.region_weight else 0.0

    @property
    def iterations(self) -> int:
        """The cap of iterations per frame in use (`max_iterations`, or its default)."""
        if self.max_iterations is not None:
            return int(self.max_iterations)
        terms = self.region_weight or self.curvature or self.appearance_weight > 0
        return ADAPTIVE_ITERATIONS if terms else ITERATIONS

    def _set(self, name, value) -> None:
        """A field normalised on construction (idempotent, so that dataclasses.replace
        of a checked object gives the same object as building it anew)."""
        object.__setattr__(self, name, value)

    def _check_choices(self) -> None:
        if self.features not in FEATURES + ("user",):
            raise InputError(
                f"features must be one of {', '.join(FEATURES)}, an array of maps "
                f"per frame or a callable, not {self.features!r}"
            )
        if self.discrepancy not in DISCREPANCIES:
            raise InputError(
                f"discrepancy must be one of {', '.join(DISCREPANCIES)}, not {self.discrepancy!r}"
            )
        if self.motion not in MOTIONS:
            raise InputError(
                f"motion must be None, 'checked', 'image', 'velocity', 'kalman' or 'components', "
                f"not {self.motion!r}"
            )

    def _check_steps(self) -> None:
        if not 0 < self.dt <= 0.5:
            raise InputError(
                f"dt={self.dt} is outside (0, 0.5], the stable range of the upwind scheme"
            )
        if self.iterations < 1 or self.check_every < 1:
            raise InputError("max_iterations and check_every must be at least 1")
        if self.check_every * CFL > NEAR_EDGE:
            raise InputError(
                f"check_every={self.check_every} lets the front move "
                f"{self.check_every * CFL:g} pixels between checks, more than the band's "
                f"{NEAR_EDGE:g}-pixel safety margin; use check_every <= {int(NEAR_EDGE / CFL)}"
            )

    def _check_sizes(self) -> None:
        if not 1 <= int(self.ncc_radius) <= 4:
            raise InputError(f"ncc_radius must be 1 to 4 pixels, not {self.ncc_radius}")
        if not 1 <= int(self.contrast_radius) <= 16:
            raise InputError(f"contrast_radius must be 1 to 16 pixels, not {self.contrast_radius}")
        if (
            self.shape_weight < 0
            or self.huber_delta <= 0
            or self.search_radius < 0
            or self.contrast_eps <= 0
        ):
            raise InputError(
                "shape_weight and search_radius must be >= 0, huber_delta and contrast_eps > 0"
            )

    def _check_adaptive(self) -> None:
        adaptive = self.discrepancy == "adaptive"
        self._set("region_weight", float(self.region_weight or 0.0))
        self._set("curvature", float(self.curvature or 0.0))
        if self.region_weight < 0 or self.curvature < 0:
            raise InputError("region_weight and curvature must be at least 0")
        # the appearance term (appearance.py): by default with motion='image' and the
        # adaptive discrepancy, unless the region term takes its place (appearance_weight)
        if self.appearance_weight < 0:
            raise InputError("appearance must be at least 0")
        if self.appearance_weight and (not adaptive or self.region_weight):
            raise InputError(
                "appearance works with discrepancy='adaptive' and no region_weight: "
                "drop one of them"
            )
        if not adaptive and (self.region_weight or self.curvature):
            raise InputError(
                "region_weight and curvature work with discrepancy='adaptive' "
                "only: drop them or use the adaptive discrepancy"
            )

    def _normalise(self) -> None:
        for name in ("shape_weight", "contrast_eps", "huber_delta", "smooth_kappa"):
            self._set(name, float(getattr(self, name)))
        for name in ("band_width", "tol", "dt", "max_dt"):
            self._set(name, float(getattr(self, name)))
        for name in ("contrast_radius", "ncc_radius", "search_radius", "smooth_steps"):
            self._set(name, int(getattr(self, name)))
        for name in ("check_every", "min_size", "reinit_iterations"):
            self._set(name, int(getattr(self, name)))
        if self.max_iterations is not None:
            self._set("max_iterations", int(self.max_iterations))
        if self.equalize is True:
            self._set("equalize", "match")
        if self.equalize not in (False, None, "match", "global"):
            raise InputError(f"equalize must be 'match', 'global' or False, not {self.equalize!r}")
        self._set("equalize", self.equalize or False)
        self._set("smooth", bool(self.smooth))
        STORAGES.choose(self.storage)


def track_options(options: TrackOptions | None = None, **overrides) -> TrackOptions:
    """`options` (default: TrackOptions()) with `overrides` replacing its fields, checked
    once; a name TrackOptions lacks is one InputError naming its fields."""
    if options is not None and not isinstance(options, TrackOptions):
        raise InputError(f"options must be a TrackOptions, not {type(options).__name__}")
    names = [f.name for f in fields(TrackOptions)]
    unknown = sorted(set(overrides) - set(names))
    if unknown:
        raise InputError(
            f"unknown tracking option(s) {', '.join(unknown)}; the options are {', '.join(names)}"
        )
    if options is None:
        return TrackOptions(**overrides)
    return replace(options, **overrides) if overrides else options
