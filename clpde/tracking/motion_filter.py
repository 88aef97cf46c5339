"""Helpers of clpde.track for real video: the motion model that starts each frame's
evolution at the predicted place (the MP4 overlay is clpde.io.frames.overlay).

MotionFilter predicts the object's displacement from one frame to the next:

- 'velocity': the displacement of the previous result's centroid, damped (half of it),
  a constant-velocity guess from the masks alone;
- 'kalman': a constant-velocity Kalman filter per axis (state: the displacement per frame,
  a random walk) whose measurement is the displacement that best matches the object's
  features between the two frames: the mean absolute difference over the previous mask
  (dilated by 3 pixels, so the boundary's context counts), searched within `radius`
  pixels of the prediction. An innovation beyond three standard deviations is a jump: its
  measurement noise is raised so the filter moves only part of the way (damping).

With motion='checked' (clpde.tracking.prediction.checked_shift) a wide search of the image
can overrule the filter; `MotionFilter.jump` then restarts it at the displacement found.
"""

from __future__ import annotations

import numpy as np


def shift_image(image: np.ndarray, shift) -> np.ndarray:
    """image moved by (dy, dx) pixels (bilinear; the edge repeats)."""
    from scipy import ndimage

    return ndimage.shift(np.asarray(image, np.float64), shift, order=1, mode="nearest")


def local_contrast(
    image: np.ndarray, radius: int = 4, eps: float = 0.02, scale: float = 0.25
) -> np.ndarray:
    """scale (I - mean) / sqrt(var + eps^2) over (2 radius + 1)^2 boxes, per channel of
    (C, H, W) data, the edge repeated: kernels/tracking/features.cl's local_contrast on the
    host (separable box sums), used to match frames for the motion model."""
    from scipy import ndimage

    size = 2 * int(radius) + 1
    out = np.empty(np.shape(image), np.float64)
    for c, x in enumerate(np.asarray(image, np.float64)):
        mean = ndimage.uniform_filter(x, size, mode="nearest")
        var = np.maximum(ndimage.uniform_filter(x * x, size, mode="nearest") - mean**2, 0)
        out[c] = scale * (x - mean) / np.sqrt(var + eps**2)
    return out


def _search(prev, cur, weight, centre, radius):
    """Mean absolute differences of cur(x + d) and prev(x) over the weight's pixels, for
    the integer d within `radius` of `centre` (inf where cur has no pixels)."""
    ys, xs = np.nonzero(weight)
    costs = np.full((2 * radius + 1, 2 * radius + 1), np.inf)
    if ys.size == 0:  # the contour has vanished: nothing to match
        return costs
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    h, w = weight.shape
    cy, cx = centre
    template = prev[:, y0:y1, x0:x1]
    wt = weight[y0:y1, x0:x1]
    total = wt.sum()
    for dy in range(cy - radius, cy + radius + 1):
        if y0 + dy < 0 or y1 + dy > h:
            continue
        for dx in range(cx - radius, cx + radius + 1):
            if x0 + dx < 0 or x1 + dx > w:
                continue
            window = cur[:, y0 + dy : y1 + dy, x0 + dx : x1 + dx]
            costs[dy - cy + radius, dx - cx + radius] = (
                np.abs(window - template).sum(axis=0)[wt].sum() / total
            )
    return costs


def _halve(a):
    """2x2 mean pooling of (C, H, W) (an odd last row or column dropped)."""
    h, w = a.shape[-2] // 2 * 2, a.shape[-1] // 2 * 2
    a = a[..., :h, :w]
    return 0.25 * (a[..., ::2, ::2] + a[..., 1::2, ::2] + a[..., ::2, 1::2] + a[..., 1::2, 1::2])


def match_displacement(
    prev: np.ndarray, cur: np.ndarray, mask: np.ndarray, centre, radius: int, dilation: int = 3
):
    """The (dy, dx) within about `radius` of `centre` minimising the mean absolute
    difference between cur(x + d) and prev(x) over the mask dilated by `dilation` px
    (features (C, H, W)); also returns the final cost map.

    Coarse to fine: the search runs at half resolution over radius / 2, then at full
    resolution within one pixel of the coarse answer, and the best integer shift is
    refined to sub-pixel by a parabola through its neighbours along each axis (an object
    moving 1.5 px per frame is not seen as 1 or 2)."""
    from scipy import ndimage

    weight = ndimage.binary_dilation(mask, iterations=dilation) if dilation > 0 else mask
    cy, cx = (round(c) for c in centre)
    coarse_w = _halve(weight[np.newaxis].astype(np.float64))[0] > 0.5
    if radius >= 2 and coarse_w.any() and min(mask.shape) >= 16:
        r2 = -(-radius // 2)
        costs = _search(_halve(prev), _halve(cur), coarse_w, (cy // 2, cx // 2), r2)
        if np.isfinite(costs).any():
            k = np.unravel_index(np.argmin(costs), costs.shape)
            cy, cx = 2 * (cy // 2 + k[0] - r2), 2 * (cx // 2 + k[1] - r2)
        costs = _search(prev, cur, weight, (cy, cx), 2)
        r = 2
    else:
        costs = _search(prev, cur, weight, (cy, cx), radius)
        r = radius
    if not np.isfinite(costs).any():  # the object fills the frame: no room to search
        return (float(cy), float(cx)), costs
    k = np.unravel_index(np.argmin(costs), costs.shape)
    best = [float(cy + k[0] - r), float(cx + k[1] - r)]
    for axis in (0, 1):
        j = k[axis]
        if 0 < j < costs.shape[axis] - 1:
            lo, mid, hi = (costs[(j + d, k[1]) if axis == 0 else (k[0], j + d)] for d in (-1, 0, 1))
            curvature = lo - 2 * mid + hi
            if np.isfinite(curvature) and curvature > 0:
                best[axis] += float(np.clip(0.5 * (lo - hi) / curvature, -0.5, 0.5))
    return (best[0], best[1]), costs


class MotionFilter:
    """The displacement model of clpde.track (motion='velocity' or 'kalman')."""

    def __init__(
        self,
        kind: str,
        radius: int = 6,
        process: float = 1.0,
        measurement: float = 1.0,
        gate: float = 3.0,
    ):
        self.kind, self.radius = kind, int(radius)
        self.q, self.r, self.gate = float(process), float(measurement), float(gate)
        self.v = np.zeros(2)  # displacement per frame (dy, dx)
        self.p = np.full(2, 4.0)  # its variance
        self.measured = None

    def predict(self, prev_features, features, mask) -> tuple[float, float]:
        """The displacement to start the next frame with (after its features are known)."""
        if self.kind == "velocity":
            return tuple(float(v) for v in 0.5 * self.v)
        prior_v, prior_p = self.v, self.p + self.q
        z, _ = match_displacement(prev_features, features, mask, prior_v, self.radius)
        z = np.array(z)
        innovation = z - prior_v
        r = np.where(
            np.abs(innovation) > self.gate * np.sqrt(prior_p + self.r),
            (innovation / self.gate) ** 2,
            self.r,
        )  # a jump: trust it less
        gain = prior_p / (prior_p + r)
        self.v = prior_v + gain * innovation
        self.p = (1 - gain) * prior_p
        self.measured = z
        return tuple(float(v) for v in self.v)

    def jump(self, displacement) -> None:
        """Restart the filter at `displacement` (dy, dx), found by a check against the
        image: its damping would otherwise take several frames to follow a fast object
        that the search radius around the old velocity cannot reach."""
        self.v = np.array(displacement, np.float64)
        self.p = np.full(2, 4.0)
        self.measured = self.v.copy()

    def observe(self, before, after) -> None:
        """After a frame: the velocity model learns the centroid's displacement."""
        if self.kind != "velocity" or not before.any() or not after.any():
            return
        c0 = np.array(np.nonzero(before)).mean(axis=1)
        c1 = np.array(np.nonzero(after)).mean(axis=1)
        # What the morphing moved plus the shift it started from.
        self.v = c1 - c0
