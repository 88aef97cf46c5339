"""The adaptive option of clpde.track (discrepancy='adaptive', motion='components'): motion
per connected component and a region term.

- `ComponentMotion` (motion='components'): each connected piece of the previous result is
  matched between the two frames on its own (`match_displacement`, coarse to fine), its
  search centred on the piece's previous displacement and wide enough to take in a stop.
  The prediction only places the search; the measurement decides, and a measured shift
  that does not explain the frames clearly better than no shift at all is dropped, so an
  object that stops is not carried on and a still slice stack is not shifted.
- `region_features`: what the region term (region_term.py, on the device) compares inside
  and outside the contour: the grey levels per channel and a local standard deviation, a
  texture measure.
- `noise_variance`: the frame's noise level (median absolute deviation of the diagonal
  second difference), against which kernels/tracking/adaptive.cl decides where a patch has
  contrast enough for the correlation to mean something.
- `background_change`: how much a frame pair changed away from the object, against the
  noise: the default's gate between comparing grey levels and the light-blind correlation.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .levelset import signed_distance
from .motion_filter import match_displacement, shift_image

# The pieces are matched over themselves and this many pixels around: enough for the
# boundary's contrast, little enough that a still background does not pull the match to 0.
DILATION = 1

# The default's light gate (discrepancy='adaptive' without the region and curvature terms),
# chosen on the calibration half of benchmarks/track_corpus.py
# (benchmarks/track_default_search.py): on a frame whose background changed by less than
# LIGHT_CHANGE times what the noise explains (`background_change`), the light did not
# change, so the grey levels compare as they are and the noise variance in the adaptive
# weight is raised QUIET_FACTOR times, handing low-contrast windows to F2 - F1. Otherwise
# the correlation keeps every window with contrast, blind to the light.
LIGHT_CHANGE = 6.0
QUIET_FACTOR = 32.0


def noise_variance(image: np.ndarray) -> float:
    """Noise variance of (C, H, W) or (H, W) data: the squared MAD estimate of sigma from
    the diagonal second difference (x[i,j] - x[i+1,j] - x[i,j+1] + x[i+1,j+1]) / 2, whose
    variance is sigma^2 for white noise and which a smooth image barely feeds."""
    a = np.asarray(image, np.float64)
    a = a.reshape((-1,) + a.shape[-2:])
    if min(a.shape[1:]) < 2:  # one row or column: no 2x2 neighbourhood to estimate the noise
        return 0.0
    # in place, in the order of 0.5 * (x00 - x10 - x01 + x11), and the medians partitioning
    # d itself (a median is the same whatever the order): the same value as with copies, a
    # colour frame's in two thirds of the time
    d = a[:, :-1, :-1] - a[:, 1:, :-1]
    d -= a[:, :-1, 1:]
    d += a[:, 1:, 1:]
    d *= 0.5
    d -= np.median(d, overwrite_input=True)
    sigma = 1.4826 * float(np.median(np.abs(d, out=d), overwrite_input=True))
    return sigma * sigma


def background_change(
    before: np.ndarray, after: np.ndarray, mask: np.ndarray, noise2: float, reach: int = 8
) -> float:
    """How much the frames changed away from the object, against the noise: the mean
    |after - before| over the pixels farther than `reach` px from `mask`, over the mean
    |difference| that the noise alone gives there (2 sigma / sqrt(pi) for two frames with
    noise of variance `noise2`). About 1 where only noise changed; a change of light (a
    flicker, a shadow) raises it. (C, H, W) or (H, W) frames; the channels' mean."""
    a = np.asarray(before, np.float64).reshape((-1,) + mask.shape).mean(axis=0)
    b = np.asarray(after, np.float64).reshape((-1,) + mask.shape).mean(axis=0)
    away = ~ndimage.binary_dilation(mask, iterations=reach) if mask.any() else np.ones_like(mask)
    if not away.any():
        return 0.0
    expected = 2.0 * np.sqrt(max(noise2, 0.0)) / np.sqrt(np.pi)
    return float(np.abs(b - a)[away].mean() / max(expected, 1e-6))


def _local_std(x: np.ndarray, size: int = 5) -> np.ndarray:
    mean = ndimage.uniform_filter(x, size, mode="nearest")
    return np.sqrt(np.maximum(ndimage.uniform_filter(x * x, size, mode="nearest") - mean**2, 0))


def region_features(image: np.ndarray) -> np.ndarray:
    """(K, H, W): each channel's grey level and the local (3x3) standard deviation of their
    mean, the texture measure that tells a smooth look-alike from a rough object."""
    img = np.asarray(image, np.float64)
    grey = img.mean(axis=0)
    return np.concatenate([img, _local_std(grey, 3)[np.newaxis]])


class ComponentMotion:
    """Displacement per connected component of the previous mask (motion='components').

    Parameters
    ----------
    radius : int
        Search radius in pixels around the piece's previous displacement (widened to take
        in zero displacement, so a stop is always within reach).
    gate : float
        A measured shift is kept only if its matching cost is below (1 - gate) times the
        cost of no shift.
    min_size : int
        Pieces smaller than this many pixels are not matched (they keep still).
    max_pieces : int
        With more pieces of min_size pixels than this, the mask is matched as one object.
    """

    def __init__(
        self, radius: int = 6, gate: float = 0.05, min_size: int = 12, max_pieces: int = 4
    ):
        self.radius, self.gate, self.min_size = int(radius), float(gate), int(min_size)
        self.max_pieces = int(max_pieces)
        self._labels = None
        self._velocities: dict[int, np.ndarray] = {}

    def _prior(self, piece: np.ndarray) -> np.ndarray:
        if self._labels is None:
            return np.zeros(2)
        hits = np.bincount(self._labels[piece], minlength=1)
        hits[0] = 0
        if hits.max() == 0:
            return np.zeros(2)
        return self._velocities.get(int(np.argmax(hits)), np.zeros(2))

    def predict(
        self, prev_features: np.ndarray, features: np.ndarray, mask: np.ndarray
    ) -> list[tuple[np.ndarray, tuple[float, float]]]:
        """[(piece mask, (dy, dx))] for each piece of `mask` (the previous frame's result),
        matched from prev_features to features ((C, H, W) each)."""
        labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
        sizes = np.bincount(labels.ravel())[1:]
        if (sizes >= self.min_size).sum() > self.max_pieces:
            # Many pieces (a tissue in a slice, say): one match for all of them, as one
            # object; matching each would cost a search per piece for little.
            labels, n = mask.astype(np.int32), 1
        pieces = []
        velocities = {}
        for k in range(1, n + 1):
            piece = labels == k
            d = np.zeros(2)
            if piece.sum() >= self.min_size:
                prior = self._prior(piece)
                reach = int(np.ceil(np.abs(prior).max())) + 3
                radius = max(self.radius, reach)
                (dy, dx), _ = match_displacement(
                    prev_features, features, piece, prior, radius, dilation=DILATION
                )
                d = _refine(prev_features, features, piece, np.array([dy, dx]))
                if np.abs(d).max() < 0.25 or not _explains(
                    prev_features, features, piece, d, self.gate
                ):
                    d = np.zeros(2)  # the frames do not show the motion: drop it
            velocities[k] = d
            pieces.append((piece, (float(d[0]), float(d[1]))))
        self._labels, self._velocities = labels, velocities
        return pieces

    @staticmethod
    def apply(u: np.ndarray, image: np.ndarray, pieces, band: float = 3.0):
        """The level set and the (C, H, W) previous features moved piece by piece: u is the
        minimum of the pieces' shifted signed distances; the features near each moved piece
        (within band + 4 px) are read from the features shifted by its displacement.
        Returns (u, image, moved)."""
        moved = [(p, d) for p, d in pieces if d != (0.0, 0.0)]
        if not moved:
            return u, image, False
        parts = []
        for piece, d in pieces:
            part = signed_distance(piece)
            parts.append(shift_image(part, d) if d != (0.0, 0.0) else part)
        u_new = np.min(parts, axis=0)
        out = np.array(image, np.float64, copy=True)
        reach = int(np.ceil(band)) + 4
        for piece, d in moved:
            near = ndimage.binary_dilation(shift_image(piece * 1.0, d) > 0.5, iterations=reach)
            for c in range(out.shape[0]):
                out[c][near] = shift_image(image[c], d)[near]
        return u_new, out, True


def _refine(prev, cur, piece, d, steps: int = 3) -> np.ndarray:
    """Gauss-Newton steps on the sum of squared differences of cur(x + d) and prev(x) over
    the piece dilated by DILATION px (Lucas-Kanade): the block match's sub-pixel part,
    which a parabola through the absolute differences biases towards whole pixels."""
    weight = ndimage.binary_dilation(piece, iterations=DILATION)
    d = np.asarray(d, np.float64).copy()
    for _ in range(steps):
        moved = np.stack([shift_image(c, (-d[0], -d[1])) for c in cur])
        gy = np.gradient(moved, axis=1)[:, weight].ravel()
        gx = np.gradient(moved, axis=2)[:, weight].ravel()
        r = (moved - prev)[:, weight].ravel()
        jtj = np.array([[gy @ gy, gy @ gx], [gx @ gy, gx @ gx]])
        if np.linalg.det(jtj) <= 1e-12 * max(np.trace(jtj) ** 2, 1e-30):
            break
        step = -np.linalg.solve(jtj, np.array([gy @ r, gx @ r]))
        d += np.clip(step, -1.0, 1.0)
        if np.abs(step).max() < 0.02:
            break
    return d


def _explains(prev, cur, piece, d, gate: float) -> bool:
    """Whether cur(x + d) matches prev(x) clearly better than cur(x) does, over the piece
    dilated by DILATION px: by at least `gate` of the still cost, and by more than two
    standard errors of the per-pixel gains (counting one independent pixel per 2x2, as the
    frames are smoothed), so that noise searched over many shifts does not pass."""
    weight = ndimage.binary_dilation(piece, iterations=DILATION)
    moved = np.stack([shift_image(c, (-d[0], -d[1])) for c in cur])
    cost = np.abs(moved - prev).sum(axis=0)[weight]
    still = np.abs(cur - prev).sum(axis=0)[weight]
    gain = still - cost
    n_eff = max(weight.sum() / 4.0, 1.0)
    return bool(gain.mean() > gate * still.mean() and gain.mean() > 2 * gain.std() / np.sqrt(n_eff))
