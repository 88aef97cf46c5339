"""Decoy holes: copies of a cluster of damage's own shape, placed on known pixels nearby,
on which `method="auto"` scores its candidates (clpde/inpainting/auto.py).

A ring of known pixels hidden around a hole tests a fill at the ring's depth, not at the
hole's: a thin ring rewards the fills that are good next to the border, a wide one makes
the hole thicker than it is. A copy of the hole's own shape, moved onto known pixels
nearby, has the hole's thickness at every pixel, so every candidate's error on it is a
sample of its error in the hole itself, whatever the shape.

Each copy is the cluster's hole pixels translated on a grid of steps one cluster size plus
GAP apart (nearest first, within WINDOW cluster sizes but at least MIN_WINDOW px), kept
where at least KEEP of its pixels land on known pixels more than GAP px from the damage,
from the box's edge and from every decoy placed before (the pixels that do not are
dropped: a long scratch or a crack network cannot be copied whole, but its thickness can).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

# Decoys per cluster; the spread of the candidates' errors across them is what tells a
# real difference from chance (auto.py).
COUNT = 8
# Known pixels between a decoy and the damage, the box's edge or another decoy.
GAP = 3
# How far decoys may lie from their cluster, in cluster sizes (its bounding box's longer
# side), and at least MIN_WINDOW px: near enough to share its surroundings.
WINDOW = 4
MIN_WINDOW = 32
# The surround whose detail a decoy's should match: RING px around the shape (less the
# first, whose differences read the damage); FLOOR: detail added before the ratio (an
# 8-bit step's square), so that flat surroundings match each other.
RING = 4
FLOOR = (1 / 255) ** 2
# The least share of a cluster's pixels a decoy keeps (the rest land on damage or off
# the box).
KEEP = 0.5
# A cluster that no decoy can copy KEEP of (a crack network across the image) takes
# copies that keep at least LAST of it: its thickness, at least, is the hole's.
LAST = 0.1


def _offsets(h, w, reach):
    """Grid translations (dy, dx) of a (h, w) shape, steps h + GAP + 1 and w + GAP + 1 (so
    that copies on the grid never touch), within `reach` px, nearest first, (0, 0) out."""
    sy, sx = h + GAP + 1, w + GAP + 1
    ky, kx = reach // sy, reach // sx
    iy, ix = np.mgrid[-ky : ky + 1, -kx : kx + 1]
    dy, dx = (iy * sy).ravel(), (ix * sx).ravel()
    order = np.argsort(np.hypot(dy, dx), kind="stable")[1:]  # the first is (0, 0)
    return dy[order], dx[order]


def detail(data, omega):
    """Each pixel's detail: its squared gradient (central differences), summed over the
    channels; NaN where a difference reads the damage."""
    g = sum(sum(d**2 for d in np.gradient(c)) for c in np.asarray(data, np.float64))
    return np.where(ndimage.binary_dilation(omega), np.nan, g)


def _surround(ys, xs, shape):
    """The pixels within RING px of (ys, xs) but not within 1 px, as coordinates."""
    near = _grown(ys, xs, shape, 1)
    return np.nonzero(_grown(ys, xs, shape, RING) & ~near)


def _mean(values, y, x):
    """The mean of `values` at (y, x) inside it, NaN where none (or all NaN)."""
    ny, nx = values.shape
    inside = (y >= 0) & (y < ny) & (x >= 0) & (x < nx)
    v = values[y[inside], x[inside]]
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else np.nan


def place(omega, labels, order, count=COUNT, texture=None):
    """Decoys of the clusters `order` (labels of the hole's pixels in `labels`, an int
    image), tried in that order: a label image (0: no decoy), each decoy pixel labelled
    with its cluster, and the decoys' own index per pixel (1, 2, ... within its cluster).
    With `texture` (`detail`'s map), the places whose surround's mean detail is nearest
    the cluster's (in ratio) come first, else the nearest places.

    Decoys never touch the damage, the edge of the image or each other: every decoy pixel
    lies more than GAP px from each (module docstring)."""
    ny, nx = omega.shape
    free = ndimage.distance_transform_edt(~omega) > GAP
    free[: GAP + 1], free[ny - GAP - 1 :] = False, False
    free[:, : GAP + 1], free[:, nx - GAP - 1 :] = False, False
    owner = np.zeros(omega.shape, np.int64)
    index = np.zeros(omega.shape, np.int64)
    objects = ndimage.find_objects(np.where(omega, labels, 0))
    for lab in order:
        if lab > len(objects) or objects[lab - 1] is None:
            continue
        sl = objects[lab - 1]
        ly, lx = np.nonzero((labels[sl] == lab) & omega[sl])
        ys, xs = ly + sl[0].start, lx + sl[1].start
        h, w = int(ly.max()) + 1, int(lx.max()) + 1
        reach = max(WINDOW * max(h, w), MIN_WINDOW)
        placed = 0
        dys, dxs = _offsets(h, w, reach)
        if texture is not None:  # surroundings like the cluster's first
            ry, rx = _surround(ys, xs, omega.shape)
            own = _mean(texture, ry, rx)
            cost = np.array([_mean(texture, ry + a, rx + b) for a, b in zip(dys, dxs, strict=True)])
            cost = np.abs(np.log((cost + FLOOR) / (own + FLOOR)))
            rank = np.argsort(np.where(np.isfinite(cost), cost, np.inf), kind="stable")
            dys, dxs = dys[rank], dxs[rank]
        for keep in (KEEP, LAST):  # LAST: only where no decoy kept KEEP
            for dy, dx in zip(dys, dxs, strict=True):
                if placed == count:
                    break
                y, x = ys + dy, xs + dx
                inside = (y >= 0) & (y < ny) & (x >= 0) & (x < nx)
                ok = inside.copy()
                ok[inside] = free[y[inside], x[inside]]
                if ok.sum() < max(keep * ys.size, 1):
                    continue
                y, x = y[ok], x[ok]
                placed += 1
                owner[y, x], index[y, x] = lab, placed
                # no later decoy within GAP px of this one
                free[_grown(y, x, omega.shape, GAP)] = False
            if placed:
                break
    return owner, index


def _grown(ys, xs, shape, by):
    """The pixels (ys, xs) grown by `by` px (Euclidean), as a mask of `shape`: a distance
    transform over their bounding box only."""
    y0, x0 = max(int(ys.min()) - by, 0), max(int(xs.min()) - by, 0)
    y1 = min(int(ys.max()) + by + 1, shape[0])
    x1 = min(int(xs.max()) + by + 1, shape[1])
    local = np.ones((y1 - y0, x1 - x0), bool)
    local[ys - y0, xs - x0] = False
    out = np.zeros(shape, bool)
    out[y0:y1, x0:x1] = ndimage.distance_transform_edt(local) <= by
    return out
