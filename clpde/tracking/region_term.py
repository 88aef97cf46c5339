"""The adaptive discrepancy's region term on a level set's grid: the speed of
`adaptive.region_field` (the foreground's and background's local statistics near the
contour), uploaded into one buffer that the morphing step reads and kept up to date while
the contour moves."""

from __future__ import annotations

import numpy as np

from ..fields import Field
from .adaptive import region_field
from .levelset import LevelSet

# The region term's settings, chosen on the calibration half of benchmarks/track_corpus.py
# (benchmarks/tracking_generalise.py --calibrate).
REGION_SIGMA = 6.0  # px: the windows of the region term's local statistics
REGION_SEPARATION = 0.5  # Bhattacharyya distance at which the region term has half weight
REGION_REFRESH = 10  # iterations between updates of the region term's statistics


class RegionTerm:
    """The region speed, weight times `region_field`, in a field of the level set's grid.

    Parameters
    ----------
    ls : LevelSet
        The tracker's level set (its grid and storage).
    weight : float
        The region term's largest speed; 0 leaves the field at 0.
    """

    def __init__(self, ls: LevelSet, weight: float):
        self.weight = float(weight)
        self.field = Field.empty(ls.grid)
        self._features: np.ndarray | None = None
        self._noise2 = 0.0

    @property
    def follows(self) -> bool:
        """Whether the field changes with the contour (a region term of weight 0 does not)."""
        return self.weight > 0

    def start(self, ls: LevelSet, features: np.ndarray, noise2: float) -> None:
        """A new frame: its (C, H, W) features and noise variance, and the field for the
        contour where the frame's morphing starts."""
        self._features, self._noise2 = features, noise2
        self.update(ls)

    def update(self, ls: LevelSet) -> None:
        """The field for the current contour (u < 0 inside)."""
        speed = np.zeros(self._features.shape[-2:])
        if self.weight > 0:
            speed = self.weight * region_field(
                self._features, ls.values() < 0, REGION_SIGMA, REGION_SEPARATION, self._noise2
            )
        # Into the same buffer each time; band cells never read its ghosts.
        padded = np.zeros(ls.grid.padded_shape, ls.grid.dtype)
        ls.grid.interior(padded)[...] = ls.pad(speed)[np.newaxis]
        self.field.data.set(padded)
