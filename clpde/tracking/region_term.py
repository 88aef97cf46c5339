"""The adaptive discrepancy's region term, on the device: a Chan-Vese-like speed from the
foreground's and background's local statistics near the contour, kept in one buffer of the
level set's grid that the morphing step reads, and updated from the level set on the device
while the contour moves (kernels/tracking/region.cl; nothing is read back).

The frame's features (`adaptive.region_features`: each channel's grey level and a local
standard deviation, a texture measure) are summarised inside (u < 0) and outside the
contour by Gaussian-weighted local means and variances, computed at half resolution (2x2
means, sigma / 2; the statistics are smooth on the scale of sigma, and this costs an eighth
of the full-resolution blur). Each pixel gets Chan and Vese's comparison of its distances
to the two sides' means, normalised by their spread and summed over the features,
L = sum_k ((f - mean_in)^2 - (f - mean_out)^2) / (var_in + var_out), pooled over `pool` px
(neighbouring pixels share the side); the speed is weight w tanh(L / 2), positive where the
pixel looks like the outside (the contour shrinks there), with w = B / (B + separation), B
the summed Bhattacharyya distance of the two sides' Gaussians, times a factor that fades
where one side has (almost) no pixels. Where the inside and outside look alike the term
fades and the frame-to-frame discrepancy decides.
"""

from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from ..fields import Field
from .adaptive import region_features
from .levelset import MARGIN, LevelSet

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("tracking/region.cl",)

# The region term's settings, chosen on the calibration half of benchmarks/track_corpus.py
# (benchmarks/tracking_generalise.py --calibrate).
REGION_SIGMA = 6.0  # px: the windows of the region term's local statistics
REGION_SEPARATION = 0.5  # Bhattacharyya distance at which the region term has half weight
REGION_REFRESH = 10  # iterations between updates of the region term's statistics
POOL = 1.5  # px: the Gaussian that pools the log-likelihood ratios of neighbouring pixels


def gaussian_weights(sigma: float, truncate: float) -> np.ndarray:
    """The normalised weights of a discrete Gaussian of `sigma` cut at `truncate` sigmas,
    as scipy.ndimage.gaussian_filter uses them (radius int(truncate sigma + 0.5))."""
    radius = int(truncate * sigma + 0.5)
    x = np.arange(-radius, radius + 1)
    w = np.exp(-0.5 / (sigma * sigma) * x**2)
    return w / w.sum()


class RegionTerm:
    """The region speed, `weight` times the region term, in a field of the level set's grid.

    Parameters
    ----------
    ls : LevelSet
        The tracker's level set (its grid, and u, which the term follows).
    weight : float
        The region term's largest speed; 0 leaves the field at 0.
    sigma : float
        The windows of the local statistics, in pixels.
    separation : float
        The Bhattacharyya distance at which the term has half its weight.
    pool : float
        The Gaussian (pixels) pooling neighbouring pixels' evidence; 0: none.
    """

    def __init__(
        self,
        ls: LevelSet,
        weight: float,
        sigma: float = REGION_SIGMA,
        separation: float = REGION_SEPARATION,
        pool: float = POOL,
    ):
        g = ls.grid
        self.runtime = rt = g.runtime
        self.weight, self.separation = float(weight), float(separation)
        self.ny, self.nx = ls.shape
        self.ny2, self.nx2 = -(-self.ny // 2), -(-self.nx // 2)
        # Ghosts and the frozen margin too: band cells never read the ghosts, but they hold
        # finite values.
        self.field = Field(g, cla.zeros(rt.queue, g.padded_shape, g.dtype))
        self._feats = self._stats = self._work = None  # allocated with the first frame
        self._llr = self._llr_work = self._w = None
        self._noise2 = 0.0
        if not self.follows:  # a field of zeros: nothing to build or upload
            return
        coarse, pooling = gaussian_weights(sigma / 2, 3.0), gaussian_weights(max(pool, 1), 4.0)
        rc, rp = (len(coarse) - 1) // 2, (len(pooling) - 1) // 2
        self._coarse = cla.to_device(rt.queue, coarse.astype(g.dtype))
        self._pool = cla.to_device(rt.queue, pooling.astype(g.dtype)) if pool > 0 else None
        self._k = {
            "region_moments": rt.kernel("tracking/region.cl", "region_moments", g.dtype),
            # the blurs' radius is a define: one build per Gaussian, whatever the frame size
            "coarse_cols": rt.kernel("tracking/region.cl", "region_blur_cols", g.dtype, RADIUS=rc),
            "coarse_rows": rt.kernel("tracking/region.cl", "region_blur_rows", g.dtype, RADIUS=rc),
            "pool_cols": rt.kernel("tracking/region.cl", "region_blur_cols", g.dtype, RADIUS=rp),
            "pool_rows": rt.kernel("tracking/region.cl", "region_blur_rows", g.dtype, RADIUS=rp),
            "region_llr": rt.kernel("tracking/region.cl", "region_llr", g.dtype),
            "region_speed": rt.kernel("tracking/region.cl", "region_speed", g.dtype),
        }

    @property
    def follows(self) -> bool:
        """Whether the field changes with the contour (a region term of weight 0 does not)."""
        return self.weight > 0

    def start(self, ls: LevelSet, features: np.ndarray, noise2: float) -> None:
        """A new frame: its (C, H, W) features and noise variance, uploaded once, and the
        field for the contour where the frame's morphing starts."""
        if not self.follows:
            return
        feats = np.ascontiguousarray(region_features(features), ls.grid.dtype)
        if self._feats is None or self._feats.shape != feats.shape:
            q, dtype = self.runtime.queue, ls.grid.dtype
            planes = 2 + 4 * len(feats)
            self._feats = cla.empty(q, feats.shape, dtype)
            self._stats = cla.empty(q, (planes, self.ny2, self.nx2), dtype)
            self._work = cla.empty(q, (planes, self.ny2, self.nx2), dtype)
            self._llr = cla.empty(q, (self.ny, self.nx), dtype)
            self._llr_work = cla.empty(q, (self.ny, self.nx), dtype)
            self._w = cla.empty(q, (self.ny, self.nx), dtype)
        self._feats.set(feats)
        self._noise2 = float(noise2)
        self.update(ls)

    def _blur(self, which, src, work, weights, nx, ny, planes) -> None:
        """src blurred in place (through `work`) by the `which` Gaussian ('coarse' or
        'pool'): columns, then rows."""
        launch = self.runtime.items(nx, ny, planes)
        sizes = (np.int32(nx), np.int32(ny), np.int32(planes))
        q = self.runtime.queue
        self._k[which + "_cols"](q, *launch, src.data, work.data, weights.data, *sizes)
        self._k[which + "_rows"](q, *launch, work.data, src.data, weights.data, *sizes)

    def update(self, ls: LevelSet) -> None:
        """The field for the current contour (u < 0 inside), from u on the device."""
        if not self.follows:
            return
        g, q, k = ls.grid, self.runtime.queue, self._k
        nx, ny, nx2, ny2 = (np.int32(v) for v in (self.nx, self.ny, self.nx2, self.ny2))
        nfeat = np.int32(self._feats.shape[0])
        frame0 = (g.ghost + MARGIN) * g.sx + g.ghost + MARGIN  # the frame's (0, 0) in u
        k["region_moments"](
            q,
            *self.runtime.items(self.nx2, self.ny2),
            ls.u.cur.data.data,
            self._feats.data,
            self._stats.data,
            nx,
            ny,
            nx2,
            ny2,
            nfeat,
            np.int32(frame0),
            np.int32(g.sx),
        )
        planes = self._stats.shape[0]
        self._blur("coarse", self._stats, self._work, self._coarse, self.nx2, self.ny2, planes)
        k["region_llr"](
            q,
            *self.runtime.items(self.nx, self.ny),
            self._stats.data,
            self._feats.data,
            self._llr.data,
            self._w.data,
            nx,
            ny,
            nx2,
            ny2,
            nfeat,
            g.scalar(self._noise2),
            g.scalar(self.separation),
        )
        if self._pool is not None:
            self._blur("pool", self._llr, self._llr_work, self._pool, self.nx, self.ny, 1)
        k["region_speed"](
            q,
            *self.runtime.items(g.nx, g.ny),
            self._llr.data,
            self._w.data,
            self.field.data.data,
            nx,
            ny,
            np.int32(g.nx),
            np.int32(g.ny),
            np.int32(MARGIN),
            np.int32(g.ghost * g.sx + g.ghost),
            np.int32(g.sx),
            g.scalar(self.weight),
        )
