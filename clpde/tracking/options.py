"""MorphingTracker's options, checked and normalised into one parameter object (the public
signatures stay flat keyword arguments; the tracker, the pre-processing and the morphing
read this)."""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .appearance import APPEARANCE_WEIGHT
from .levelset import CFL, NEAR_EDGE, STORAGES

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


@dataclass
class TrackOptions:
    """MorphingTracker's keyword options (documented there), checked on construction:
    `features` is 'user' for the user's own maps, `region_weight` and `curvature` default
    to 0 (off), `max_iterations` gets its default for the terms used, `equalize` becomes 'match',
    'global' or False. Raises InputError for options that cannot be used."""

    features: str
    colour: bool
    discrepancy: str
    motion: str | None
    shape_weight: float
    equalize: bool | str
    smooth: bool
    smooth_steps: int
    smooth_kappa: float
    band_width: float
    max_iterations: int | None
    tol: float
    check_every: int
    dt: float
    max_dt: float
    reinit_iterations: int
    min_size: int
    contrast_radius: int
    contrast_eps: float
    ncc_radius: int
    huber_delta: float
    search_radius: int
    storage: str
    region_weight: float | None
    curvature: float | None
    appearance: float | None = None

    def __post_init__(self) -> None:
        self._check_choices()
        self._check_adaptive()
        self._check_steps()
        self._check_sizes()
        self._normalise()

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
        if self.max_iterations is None:
            terms = self.region_weight > 0 or self.curvature > 0 or self.appearance > 0
            self.max_iterations = ADAPTIVE_ITERATIONS if terms else ITERATIONS
        if self.max_iterations < 1 or self.check_every < 1:
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
        self.region_weight = float(self.region_weight or 0.0)
        self.curvature = float(self.curvature or 0.0)
        if self.region_weight < 0 or self.curvature < 0:
            raise InputError("region_weight and curvature must be at least 0")
        # the appearance term (appearance.py): by default with motion='image' and the
        # adaptive discrepancy, unless the region term takes its place
        if self.appearance is None:
            image = self.motion == "image" and adaptive and not self.region_weight
            self.appearance = APPEARANCE_WEIGHT if image else 0.0
        self.appearance = float(self.appearance)
        if self.appearance < 0:
            raise InputError("appearance must be at least 0")
        if self.appearance and (not adaptive or self.region_weight):
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
        self.shape_weight = float(self.shape_weight)
        self.contrast_radius, self.ncc_radius = int(self.contrast_radius), int(self.ncc_radius)
        self.contrast_eps = float(self.contrast_eps)
        self.huber_delta, self.search_radius = float(self.huber_delta), int(self.search_radius)
        if self.equalize is True:
            self.equalize = "match"
        if self.equalize not in (False, None, "match", "global"):
            raise InputError(f"equalize must be 'match', 'global' or False, not {self.equalize!r}")
        self.equalize, self.smooth = self.equalize or False, bool(self.smooth)
        self.smooth_steps, self.smooth_kappa = int(self.smooth_steps), float(self.smooth_kappa)
        self.band_width = float(self.band_width)
        self.max_iterations, self.tol = int(self.max_iterations), float(self.tol)
        self.check_every, self.dt = int(self.check_every), float(self.dt)
        self.min_size = int(self.min_size)
        self.max_dt = max(float(self.max_dt), self.dt)
        self.reinit_iterations = int(self.reinit_iterations)
        if self.storage not in STORAGES:
            raise InputError(f"storage must be one of {', '.join(STORAGES)}, not {self.storage!r}")
