"""Thick clusters of damage in piecewise-smooth surrounds (depth and disparity maps).

A depth or disparity map is flat or planar over each surface and jumps at each surface's
outline: nearly every known pixel's 4-neighbour Laplacian is zero (a plane's disparity is
linear in the image's coordinates), and the few that are not sit on the jumps. The smooth
route (pick.py) measures such a surround's fine detail as small beside its standard
deviation (the jumps make that large) and gave the cluster to the biharmonic fill, which
bends the surfaces on either side of a jump into each other and overshoots it. The spectral
fill continues the jumps as edges: on the rendered disparity maps of
tests/cases/inpaint_depth.py (calibration only) it led the biharmonic fill on the clusters
the smooth route took (docs/inpainting.md, "Depth maps"). So a cluster whose window is
piecewise smooth stays with the spectral fill.

"Piecewise smooth": at least FLAT_SHARE of the window's known pixels whose 4 neighbours are
known have a Laplacian within FLAT_TOL times the window's standard deviation (of the grey
known pixels), and the largest difference between known 4-neighbours is a jump, at least
JUMP times that deviation. Calibration: the rendered maps' thick clusters' shares 0.80-1.00;
the photos', microscopy's, binned 16-bit data's and the fractal and ridged fields' 0.01-0.85,
and the few photo windows above 0.6 (flat sky, synthetic edges) were not on the smooth route.
The jump keeps a smooth field without edges on the smooth route: a Gaussian-filtered noise
field of sigma 20 px is as "flat" (0.99) as a depth map, but its largest step is 0.13 of its
deviation (sigma 6: 0.37), against 1.5-2.4 for 90% of the rendered maps' windows.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .smooth import grown_box

FLAT_TOL = 0.01  # |Laplacian| within this share of the window's std: a flat or planar pixel
FLAT_SHARE = 0.8  # share of such pixels for a piecewise-smooth window
JUMP = 1.0  # its largest known neighbours' difference, over its std: a jump (an outline)
MIN_PIXELS = 64  # known pixels with known neighbours needed for the share to count


def jump(grey, ok) -> float:
    """The largest difference between known 4-neighbours of `grey` (a window) over the
    known pixels' standard deviation (0 where they do not vary)."""
    a = np.abs(grey[:, 1:] - grey[:, :-1])[ok[:, 1:] & ok[:, :-1]]
    b = np.abs(grey[1:, :] - grey[:-1, :])[ok[1:, :] & ok[:-1, :]]
    spread = float(grey[ok].std())
    if spread <= 0 or not (a.size or b.size):
        return 0.0
    return max(a.max(initial=0.0), b.max(initial=0.0)) / spread


def flat_share(grey, ok) -> float:
    """The share of the known pixels of `grey` (a window) with 4 known neighbours whose
    Laplacian is within FLAT_TOL times the known pixels' standard deviation (NaN where fewer
    than MIN_PIXELS have 4 known neighbours)."""
    c = grey[1:-1, 1:-1]
    lap = 4 * c - grey[:-2, 1:-1] - grey[2:, 1:-1] - grey[1:-1, :-2] - grey[1:-1, 2:]
    inner = ok[1:-1, 1:-1] & ok[:-2, 1:-1] & ok[2:, 1:-1] & ok[1:-1, :-2] & ok[1:-1, 2:]
    if inner.sum() < MIN_PIXELS:
        return float("nan")
    spread = float(grey[ok].std())
    return float((np.abs(lap[inner]) <= FLAT_TOL * spread).mean())


def piecewise_smooth(data, omega, clusters, labels, window):
    """The labels among `labels` (of the image `clusters`) whose window (their box grown by
    `window` px) is piecewise smooth (module docstring)."""
    known = ~np.asarray(omega, bool)
    grey = np.asarray(data, np.float64).mean(axis=0)
    grey = np.where(known, grey, 0.0)  # (the hole's values may be NaN)
    slices = ndimage.find_objects(clusters)
    out = []
    for lab in labels:
        w = grown_box(slices[lab - 1], window, known.shape)
        if flat_share(grey[w], known[w]) >= FLAT_SHARE and jump(grey[w], known[w]) >= JUMP:
            out.append(int(lab))
    return np.asarray(out, int)
