"""Parts that move off the object's motion, carried by dense flow (issue 35, trackflow).

The object's motion (appearance.object_motion) carries the whole shape by one affine map, so
where a walker's legs cross the prediction keeps the last frame's legs. Dense flow loses
small fast objects as the object's own motion (docs/tracking.md, "How the object's motion
is found"), but once that motion is taken out, what is left on a part is a few pixels, where
DIS is good: the previous frame carried by the motion is matched to the new frame by DIS
over the object's box, and the carried level set is carried again by that residual flow
where it is trusted (forward-backward consistent, within REACH px); elsewhere the rigid
prediction stands.
"""

from __future__ import annotations

import numpy as np

from scipy import ndimage

from .adaptive import noise_variance
from .appearance import bilinear, box
from .levelset import signed_distance

# The residual flow's bound (parts.py's reach), the forward-backward check's tolerance
# (px), and the margin of the box DIS sees beyond the prediction's (px).
REACH, CONSISTENT, MARGIN = 12, 1.0, 16
# Residual flows below this (px) are the flow's own jitter on a rigid object: left at 0.
MIN_FLOW = 1.0
import os  # EXPLORE

REACH = int(os.environ.get("RF_REACH", REACH))  # EXPLORE
CONSISTENT = float(os.environ.get("RF_CONS", CONSISTENT))  # EXPLORE
MIN_FLOW = float(os.environ.get("RF_MIN", MIN_FLOW))  # EXPLORE
PRESET = os.environ.get("RF_PRESET", "medium")  # EXPLORE
MODE = os.environ.get("RF_MODE", "splat")  # EXPLORE
MISS = float(os.environ.get("RF_MISS", 3.0))  # EXPLORE
MIN_PART = int(os.environ.get("RF_PART", 20))  # EXPLORE

_dis = {}


def _flow():
    """One DIS instance (medium preset) for the tracker's pairs; None without OpenCV."""
    if "flow" not in _dis:
        try:
            from ..motion.dis import DisFlow

            _dis["flow"] = DisFlow(PRESET)
        except Exception:  # OpenCV absent: the rigid prediction stands
            _dis["flow"] = None
    return _dis["flow"]


def _u8(grey: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.rint(np.clip(grey, 0.0, 1.0) * 255.0).astype(np.uint8))


def residual_carry(
    before: np.ndarray,
    after: np.ndarray,
    a: np.ndarray,
    predicted_u: np.ndarray,
    visible: np.ndarray = None,
) -> np.ndarray:
    """The level set `predicted_u` (the shape carried by the motion `a`: u read at A x)
    carried further by the residual flow between frame `before` carried by `a` and frame
    `after` ((C, H, W) looks, averaged to grey), over the prediction's box grown by
    REACH + MARGIN px. Returns predicted_u itself where nothing is carried."""
    flow = _flow()
    predicted = predicted_u < 0
    if flow is None or not predicted.any():
        return predicted_u
    where = box(predicted, REACH + MARGIN)
    rows = np.arange(where[0].start, where[0].stop)
    cols = np.arange(where[1].start, where[1].stop)
    if len(rows) < 16 or len(cols) < 16:
        return predicted_u
    pts = np.array([np.repeat(rows, len(cols)), np.tile(cols, len(rows))], np.float64)
    coords = np.tensordot(a[:, :2], pts, 1) + a[:, 2:]
    grey_before = np.asarray(before, np.float64).mean(axis=0)[np.newaxis]
    carried = bilinear(grey_before, coords).reshape(len(rows), len(cols))
    now = np.asarray(after, np.float64).mean(axis=0)[where]
    c8, n8 = _u8(carried), _u8(now)
    # f: now(x) ~ carried(x + f(x)); g the other way; a trusted f comes back by g
    f = flow.flow(n8, c8).astype(np.float32)
    g = flow.flow(c8, n8).astype(np.float32)
    back = flow.warp(g, f, "linear")
    trusted = np.hypot(*(f + back).transpose(2, 0, 1)) <= CONSISTENT
    size = np.hypot(f[..., 0], f[..., 1])
    trusted &= (size <= REACH) & (size >= MIN_FLOW)
    if not trusted.any():
        return predicted_u
    if MODE == "splat":
        return _splat(predicted_u, where, carried, now, g, f, flow)
    bg = float(os.environ.get("RF_BG", 0))  # EXPLORE
    if bg:
        from .appearance import dilate

        part = predicted_u[where] < 0
        ring = dilate(part, 16) & ~dilate(part, 6) & trusted
        if ring.sum() < 20:
            return predicted_u
        ground = np.median(f[ring], axis=0)
        trusted &= np.hypot(*(f - ground).transpose(2, 0, 1)) > bg
    if os.environ.get("RF_STILL"):  # EXPLORE
        from .appearance import dilate

        part = predicted_u[where] < 0
        ring = dilate(part, 16) & ~dilate(part, 6) & trusted
        if ring.sum() < 20:
            return predicted_u
        ground = np.median(f[ring], axis=0)
        if np.hypot(ground[0] - a[1, 2], ground[1] - a[0, 2]) > float(os.environ["RF_STILL"]):
            return predicted_u
    if MODE in ("backmiss", "vismiss"):
        noise = max(float(np.sqrt(noise_variance(now[np.newaxis]))), 1e-3)
        trusted &= np.abs(ndimage.gaussian_filter(carried - now, 1.0)) > MISS * noise
        if os.environ.get("RF_EXPL"):  # EXPLORE
            moved = flow.warp(np.ascontiguousarray(carried, np.float32), f, "linear")
            trusted &= np.abs(ndimage.gaussian_filter(moved - now, 1.0)) <= MISS * noise
        labels, n = ndimage.label(trusted)
        if n:
            sizes = ndimage.sum(trusted, labels, np.arange(1, n + 1))
            trusted = np.isin(labels, 1 + np.flatnonzero(sizes >= MIN_PART))
    f[~trusted] = 0.0
    if MODE.startswith("vis") and visible is not None:
        u = np.ascontiguousarray(predicted_u[where], np.float32)
        vis = np.ascontiguousarray(visible[where], np.float32)
        whole = flow.warp(u, f, "linear") < 0
        seen = flow.warp(vis, f, "linear") > 0.5
        part = predicted_u[where] < 0
        new = part.copy()
        new[trusted & seen] = True
        new[trusted & ~whole] = False
        if (new == part).all():
            return predicted_u
        full = predicted_u < 0
        full[where] = new
        return signed_distance(full)
    u = np.ascontiguousarray(predicted_u[where], np.float32)
    out = predicted_u.copy()
    out[where] = flow.warp(u, f, "linear")
    return out


def _splat(predicted_u, where, carried, now, g, f, flow):
    """The prediction's pixels that the motion did not carry (the carried frame misses the
    new one by more than MISS noise levels), moved by their trusted residual flow g (carried
    to now); the rest stays."""
    part = predicted_u[where] < 0
    noise = max(float(np.sqrt(noise_variance(now[np.newaxis]))), 1e-3)
    miss = np.abs(ndimage.gaussian_filter(carried - now, 1.0)) > MISS * noise
    back = flow.warp(f, g, "linear")
    size = np.hypot(g[..., 0], g[..., 1])
    trusted = (np.hypot(*(g + back).transpose(2, 0, 1)) <= CONSISTENT) & (size <= REACH)
    moving = part & miss & trusted & (size >= max(MIN_FLOW, 1.0))
    labels, n = ndimage.label(moving)
    if n:
        sizes = ndimage.sum(moving, labels, np.arange(1, n + 1))
        moving = np.isin(labels, 1 + np.flatnonzero(sizes >= MIN_PART))
    if not moving.any():
        return predicted_u
    ys, xs = np.nonzero(moving)
    ty = np.rint(ys + g[ys, xs, 1]).astype(int)
    tx = np.rint(xs + g[ys, xs, 0]).astype(int)
    inside = (ty >= 0) & (ty < part.shape[0]) & (tx >= 0) & (tx < part.shape[1])
    landed = np.zeros_like(part)
    landed[ty[inside], tx[inside]] = True
    landed = ndimage.binary_closing(landed, iterations=1)
    new = (part & ~moving) | landed
    new = ndimage.binary_closing(new, iterations=1) | (part & ~moving)
    out = predicted_u.copy()
    full = predicted_u < 0
    full[where] = new
    return signed_distance(full)


def raw_carry(before, after, a, predicted_u, prev_mask, prev_u):
    """EXPLORE: DIS between the frames themselves (the ground still on a still camera, so
    measured), the residual being the flow less the object's motion: where it differs from
    it by more than RF_BG px, within REACH px, and is trusted, a pixel is the object's if
    its source was in the previous visible mask, the surroundings' if outside the whole
    shape; elsewhere the rigid prediction stands."""
    flow = _flow()
    predicted = predicted_u < 0
    if flow is None or not predicted.any():
        return predicted_u
    where = box(predicted | prev_mask, MARGIN)
    now = np.asarray(after, np.float64).mean(axis=0)[where]
    was = np.asarray(before, np.float64).mean(axis=0)[where]
    if min(now.shape) < 16:
        return predicted_u
    n8, p8 = _u8(now), _u8(was)
    f = flow.flow(n8, p8).astype(np.float32)  # now(x) ~ was(x + f)
    g = flow.flow(p8, n8).astype(np.float32)
    trusted = np.hypot(*(f + flow.warp(g, f, "linear")).transpose(2, 0, 1)) <= CONSISTENT
    ys, xs = np.mgrid[where[0], where[1]].astype(np.float64)
    # the object's motion as a flow: x -> A x
    rx = a[1, 0] * ys + a[1, 1] * xs + a[1, 2] - xs
    ry = a[0, 0] * ys + a[0, 1] * xs + a[0, 2] - ys
    off = np.hypot(f[..., 0] - rx, f[..., 1] - ry)
    trusted &= (off > float(os.environ.get("RF_BG", 2.0))) & (off <= REACH)
    if MIN_PART > 1:
        labels, n = ndimage.label(trusted)
        if n:
            sizes = ndimage.sum(trusted, labels, np.arange(1, n + 1))
            trusted = np.isin(labels, 1 + np.flatnonzero(sizes >= MIN_PART))
    if not trusted.any():
        return predicted_u
    seen = flow.warp(np.ascontiguousarray(prev_mask[where], np.float32), f, "linear") > 0.5
    whole = flow.warp(np.ascontiguousarray(prev_u[where], np.float32), f, "linear") < 0
    part = predicted[where]
    new = part.copy()
    new[trusted & seen] = True
    if not os.environ.get("RF_NOREMOVE"):
        new[trusted & ~whole] = False
    if (new == part).all():
        return predicted_u
    full = predicted.copy()
    full[where] = new
    if full.sum() < 0.5 * predicted.sum():  # EXPLORE: the flow took the object away
        return predicted_u
    return signed_distance(full)
