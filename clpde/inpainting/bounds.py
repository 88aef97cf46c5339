"""Fills kept within what surrounds them, for every method alike (api.py applies it to each
box's fill before writing it).

No inpainting method here promises a maximum principle: the spectral fill's Fourier sums,
the exemplar's blended patches, the biharmonic start and the Navier-Stokes Poisson solve
can all leave the range of the pixels around a hole (the spectral default returned -0.078
to 1.06 for a float image in [0, 1]; Navier-Stokes, whose vorticity on a textured border
is integrated into the hole, painted saturated false colours). A value the surroundings do
not hold is rarely right, and a colour outside their gamut is seen at once. So, per
cluster of damage (a connected component of the hole, 8-connected):

- the ring: the known pixels within RING pixels of the cluster (each known pixel belongs
  to the ring of its nearest cluster);
- every channel of the fill is clipped to the ring's range in that channel;
- with `hull` (navier-stokes asks for it), for 2 to 4 colour channels, a colour outside
  the convex hull of the ring's colours is moved towards the ring's mean colour (inside the
  hull) until it reaches the hull, along the line joining them: its hue drifts towards the
  surroundings' instead of saturating.

A partly damaged pixel of a soft mask also keeps its own observed value in its range (the
fill is blended with it) and is not moved by the hull. RING was chosen on the calibration
half of benchmarks/inpaint_corpus.py's corpus (benchmarks/inpaint_bounds_calibrate.py; the
mean PSNR over the classes of the default, navier-stokes and exemplar, widths 2 to 32;
docs/inpainting.md has the table).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from scipy.spatial import ConvexHull, QhullError

RING = 4  # px: the width of the ring of known pixels that bounds a cluster's fill


def limit(fill, data, omega, damage=None, ring: int | None = None, hull: bool = False):
    """`fill` ((channels, rows, cols), a box's solution) with its hole pixels held within
    their cluster's ring (module docstring); `data` holds the known values (the hole's
    values are not read), `damage` a soft mask's degree of damage or None. Returns a new
    array; the known pixels are `fill`'s."""
    ring = RING if ring is None else ring
    omega = np.asarray(omega, bool)
    out = np.array(fill, np.float64, copy=True)
    if not omega.any() or omega.all():
        return out
    labels, count = ndimage.label(omega, np.ones((3, 3), bool))
    dist, (iy, ix) = ndimage.distance_transform_edt(omega == 0, return_indices=True)
    # each known pixel within the ring goes to the cluster of its nearest hole pixel
    near = ~omega & (dist <= ring)
    owner = np.where(near, labels[iy, ix], 0)
    known = np.asarray(data, np.float64)
    nc = known.shape[0]
    hole = labels[omega]  # each hole pixel's cluster
    values = out[:, omega]  # (nc, n)
    partly = None
    if damage is not None:
        partly = np.asarray(damage, np.float64)[omega] < 1
    # per channel: the ring's range per cluster; a cluster without ring pixels of its own
    # (every one nearer another cluster) takes the box's known range
    whole = ~omega
    # the ring's pixels grouped by cluster, by one sort, for every channel's range
    flat = owner.ravel()
    ring_at = np.flatnonzero(flat)
    order = ring_at[np.argsort(flat[ring_at], kind="stable")]
    sizes = np.bincount(flat[ring_at], minlength=count + 1)[1:]
    empty = sizes == 0
    starts = (np.cumsum(sizes) - sizes)[~empty]
    for c in range(nc):
        ring_values = known[c].ravel()[order]
        lo, hi = np.empty(count), np.empty(count)
        if starts.size:
            lo[~empty] = np.minimum.reduceat(ring_values, starts)
            hi[~empty] = np.maximum.reduceat(ring_values, starts)
        lo[empty], hi[empty] = known[c][whole].min(), known[c][whole].max()
        lo_p, hi_p = lo[hole - 1], hi[hole - 1]
        if partly is not None:  # the blend with the observed value stays possible
            seen = known[c][omega]
            lo_p = np.where(partly, np.minimum(lo_p, seen), lo_p)
            hi_p = np.where(partly, np.maximum(hi_p, seen), hi_p)
        np.clip(values[c], lo_p, hi_p, out=values[c])
    if hull and 2 <= nc <= 4:
        _hull(values, known, owner, hole, count, partly)
    out[:, omega] = values
    return out


def _hull(values, known, owner, hole, count, partly):
    """Moves each fill colour outside its cluster's ring hull towards the ring's mean, in
    place (values: (nc, n), hole: each value's cluster)."""
    ring_of = _groups(owner[owner > 0], count)
    ring_colours = known[:, owner > 0].T  # (m, nc)
    pixels_of = _groups(hole, count)
    for lab in range(1, count + 1):
        pts = ring_colours[ring_of[lab]]
        sel = pixels_of[lab]
        if partly is not None:
            sel = sel[~partly[sel]]
        if sel.size == 0 or len(pts) <= pts.shape[1]:
            continue
        centre = pts.mean(axis=0)
        try:
            eq = ConvexHull(pts).equations  # a . x + b <= 0 inside
        except (QhullError, ValueError):  # flat (e.g. grey stored as colour): ranges only
            continue
        x = values[:, sel].T - centre  # (k, nc)
        a, b = eq[:, :-1], eq[:, -1]
        slack = -(a @ centre + b)  # >= 0: the centre's distance inside each facet
        reach = x @ a.T  # (k, facets): how far each colour heads out through each facet
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(reach > 1e-15, np.maximum(slack, 0) / reach, np.inf).min(axis=1)
        t = np.minimum(t, 1.0)
        if (t < 1).any():
            values[:, sel] = (centre + t[:, None] * x).T


def _groups(labels, count):
    """[indices of `labels` equal to each label 0..count], by one sort."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(count + 2))
    return [order[bounds[k] : bounds[k + 1]] for k in range(count + 1)]
