"""A confidence per frame for a track: the probability that the contour still holds its
object, from what a lost track shows.

Per frame t >= 1, from the frames and the masks alone (so any tracker's masks can be
scored, which is how the model was calibrated: on clpde's tracks, scikit-image's and tracks
made to jump away, of the calibration half of benchmarks/track_corpus.py):

- ``area_jump``: |log| of the area's ratio to the previous frame's;
- ``area_drift``: |log| of the area's ratio to the first frame's;
- ``separation``: log of the Bhattacharyya distance between the features (grey level,
  local standard deviation) inside and outside the contour within 6 px of it: a contour
  that has lost its object no longer separates two populations;
- ``appearance``: log of the Bhattacharyya distance between the inside's features now and
  in the first frame (each frame's grey levels standardised, so a flicker does not count);
- ``fragments``: how many pieces of 10 px or more the mask gained or lost since the
  previous frame;
- ``edge``: log of the mean gradient magnitude on the contour over that of the ring
  around it: a held contour lies on an edge;
- ``discrepancy``: log of the mean |F_t - F_(t-1)| in the ring around the contour
  (standardised grey levels) over its median in the frames before.

The score is a logistic model of these features, its weights fitted on frames known good
(IoU > 0.9) and lost (IoU < 0.5); `LOW_CONFIDENCE` is the threshold chosen on the same
calibration half. Frame 0 (the given mask) has confidence 1.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

FEATURES = (
    "area_jump",
    "area_drift",
    "separation",
    "appearance",
    "fragments",
    "edge",
    "discrepancy",
)
# Logistic weights (intercept first, then FEATURES' order) and the flagging threshold,
# fitted by benchmarks/tracking_generalise.py --calibrate-confidence.
WEIGHTS = (1.772, -3.339, -4.371, 2.418, -0.7796, -1.428, -0.6542, 1.76)
LOW_CONFIDENCE = 0.453


def _standardised(frame: np.ndarray) -> np.ndarray:
    f = np.asarray(frame, np.float64)
    if f.ndim == 3:  # colour (H, W, C) or prepared (C, H, W): the mean channel
        f = f.mean(axis=-1) if f.shape[-1] in (3, 4) else f.mean(axis=0)
    f = ndimage.gaussian_filter(f, 1.0)
    return (f - f.mean()) / max(f.std(), 1e-9)


def _stats(feats, where):
    if where.sum() < 4:
        return None
    v = feats[:, where]
    return v.mean(axis=1), v.var(axis=1) + 1e-3


def _bhattacharyya(a, b) -> float:
    if a is None or b is None:
        return 0.0
    (ma, va), (mb, vb) = a, b
    return float(
        np.sum(0.25 * (ma - mb) ** 2 / (va + vb) + 0.5 * np.log((va + vb) / (2 * np.sqrt(va * vb))))
    )


def _pieces(mask) -> int:
    labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
    return int((np.bincount(labels.ravel())[1:] >= 10).sum()) if n else 0


def separation(image, mask, ring: int = 6) -> float:
    """Bhattacharyya distance between the features (grey level, local standard deviation)
    inside and outside `mask` within `ring` px of its boundary; image (H, W) or (C, H, W)."""
    std = _standardised(image)
    feats = np.stack(
        [
            std,
            np.sqrt(
                np.maximum(
                    ndimage.uniform_filter(std * std, 5) - ndimage.uniform_filter(std, 5) ** 2, 0
                )
            ),
        ]
    )
    mask = np.asarray(mask, bool)
    if not mask.any() or mask.all():
        return 0.0
    inside = ndimage.distance_transform_edt(mask)
    outside = ndimage.distance_transform_edt(~mask)
    return _bhattacharyya(
        _stats(feats, mask & (inside <= ring)), _stats(feats, ~mask & (outside <= ring))
    )


def frame_features(frames, masks) -> np.ndarray:
    """(T, len(FEATURES)) of a track: frames (T, H, W[, C]) and boolean masks (T, H, W);
    row 0 is zeros (the given mask)."""
    masks = np.asarray(masks, bool)
    std = [_standardised(f) for f in frames]
    feats = [
        np.stack(
            [
                s,
                np.sqrt(
                    np.maximum(
                        ndimage.uniform_filter(s * s, 5) - ndimage.uniform_filter(s, 5) ** 2, 0
                    )
                ),
            ]
        )
        for s in std
    ]
    area0 = masks[0].sum() + 1.0
    ref = _stats(feats[0], masks[0])
    out = np.zeros((len(masks), len(FEATURES)))
    history = []
    for t in range(1, len(masks)):
        m, prev = masks[t], masks[t - 1]
        area, area_prev = m.sum() + 1.0, prev.sum() + 1.0
        if m.any() and not m.all():
            inside = ndimage.distance_transform_edt(m)
            outside = ndimage.distance_transform_edt(~m)
            ring_in, ring_out = m & (inside <= 6), ~m & (outside <= 6)
            contour = (m & (inside <= 1)) | (~m & (outside <= 1))
            near = ring_in | ring_out
        else:
            ring_in = ring_out = contour = near = np.zeros_like(m)
        sep = _bhattacharyya(_stats(feats[t], ring_in), _stats(feats[t], ring_out))
        app = _bhattacharyya(_stats(feats[t], m), ref)
        grad = ndimage.gaussian_gradient_magnitude(std[t], 1.0)
        edge = (grad[contour].mean() + 1e-3) / (grad[near].mean() + 1e-3) if contour.any() else 1.0
        disc = float(np.abs(std[t] - std[t - 1])[near].mean()) if near.any() else 0.0
        base = np.median(history) if history else disc
        history.append(disc)
        out[t] = (
            abs(np.log(area / area_prev)),
            abs(np.log(area / area0)),
            np.log(sep + 1e-3),
            np.log(app + 1e-3),
            abs(_pieces(m) - _pieces(prev)),
            np.log(edge),
            np.log((disc + 1e-3) / (base + 1e-3)),
        )
    return out


def score(features: np.ndarray, weights=WEIGHTS) -> np.ndarray:
    """The logistic model's probability of a good frame, per row of frame_features."""
    w = np.asarray(weights, np.float64)
    z = w[0] + np.asarray(features) @ w[1:]
    return 1.0 / (1.0 + np.exp(-np.clip(z, -50, 50)))


def track_confidence(frames, masks, weights=WEIGHTS) -> np.ndarray:
    """(T,) confidence in [0, 1] per frame of a track (frame 0: 1).

    Parameters
    ----------
    frames : array_like
        (T, H, W) grey or (T, H, W, C) colour frames.
    masks : array_like
        (T, H, W) boolean masks of the track.
    weights : sequence of float
        The logistic model's intercept and weights (default: the calibrated ones).

    Returns
    -------
    numpy.ndarray
        float64 (T,), high where the track looks held.

    Examples
    --------
    >>> import numpy as np
    >>> yy, xx = np.mgrid[:40, :40]
    >>> masks = np.stack([np.hypot(yy - 20, xx - 12 - 2 * t) < 7 for t in range(4)])
    >>> frames = 0.2 + 0.6 * masks
    >>> conf = track_confidence(frames, masks)
    >>> conf.shape, bool(conf[0] == 1.0)
    ((4,), True)
    """
    conf = score(frame_features(frames, masks), weights)
    conf[0] = 1.0
    return conf


def fit_logistic(x: np.ndarray, y: np.ndarray, l2: float = 1e-2, iterations: int = 50):
    """Weights (intercept first) of a logistic regression of y in {0, 1} on x, by Newton's
    method with an L2 penalty (not on the intercept); classes weighed equally."""
    x = np.column_stack([np.ones(len(x)), x])
    y = np.asarray(y, np.float64)
    cw = np.where(y > 0.5, 0.5 / max(y.mean(), 1e-9), 0.5 / max(1 - y.mean(), 1e-9))
    w = np.zeros(x.shape[1])
    pen = np.full(x.shape[1], l2)
    pen[0] = 0
    for _ in range(iterations):
        p = 1 / (1 + np.exp(-np.clip(x @ w, -50, 50)))
        grad = x.T @ (cw * (p - y)) + pen * w
        hess = (x * (cw * p * (1 - p))[:, None]).T @ x + np.diag(pen + 1e-9)
        step = np.linalg.solve(hess, grad)
        w -= step
        if np.abs(step).max() < 1e-8:
            break
    return w
