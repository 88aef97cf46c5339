"""The biharmonic fill of single clusters of damage, on the host, by a direct sparse solve.

method="pick" hands some thick clusters to a smooth fill (pick.py). The device's biharmonic
fill (poisson.py) iterates over the whole box, and on the corpus's voids it cost about as
much as the spectral fill it would replace; a cluster of a few hundred pixels is solved
exactly on the host in a few milliseconds instead. The fill: Laplacian squared of the image
zero at every hole pixel of the cluster, the Laplacian the grid graph's (4 neighbours;
at the image's edge only the neighbours inside it, so no values beyond the image are
invented). Its stencil reaches 2 px: a cluster of pick.clusters_of (the hole grown by 1 px)
is at least 3 known pixels from any other, so only known pixels and the cluster's own are
read.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import linalg as splinalg

MARGIN = 3  # px around a cluster's box: its stencil's reach (2) and its neighbours' degree


def _laplacian(shape, y0, x0, full):
    """The grid graph's Laplacian (a sparse (n, n) matrix, n = rows x cols of `shape`) of a
    window at (y0, x0) in an image of shape `full`: each pixel's degree counts its
    neighbours inside the image, the edges only those inside the window (rows of pixels on
    the window's edge are wrong where the image goes on, and never used)."""
    h, w = shape
    index = np.arange(h * w).reshape(h, w)
    right = (index[:, :-1].ravel(), index[:, 1:].ravel())
    down = (index[:-1, :].ravel(), index[1:, :].ravel())
    i = np.concatenate([right[0], down[0]])
    j = np.concatenate([right[1], down[1]])
    ones = np.ones(i.size)
    adjacency = sparse.coo_matrix((ones, (i, j)), shape=(h * w, h * w))
    adjacency = (adjacency + adjacency.T).tocsr()
    gy = np.arange(y0, y0 + h)[:, None]
    gx = np.arange(x0, x0 + w)[None, :]
    degree = 4 - (gy == 0) - (gy == full[0] - 1) - (gx == 0) - (gx == full[1] - 1)
    return adjacency - sparse.diags(degree.ravel().astype(np.float64))


def _solve(planes, origin, hole, full, order=2):
    """Fill `hole` (a bool mask of a window at `origin` (row, col) in an image of shape
    `full`) of `planes` (the window's (channels, rows, cols), written in place) by the
    biharmonic fill (order 2), or the harmonic one (order 1: Laplacian zero), every other
    pixel of the window known."""
    g = _laplacian(hole.shape, origin[0], origin[1], full)
    g2 = (g @ g).tocsr() if order == 2 else g.tocsr()
    flat = hole.ravel()
    unknown, known = np.flatnonzero(flat), np.flatnonzero(~flat)
    rows = g2[unknown]
    solve = splinalg.factorized(rows[:, unknown].tocsc())
    coupling = rows[:, known]
    for plane in planes:
        plane[hole] = solve(-(coupling @ plane.ravel()[known]))


def grown_box(s, grow, full):
    """The box `s` (a pair of slices) grown by `grow` px, within an image of shape `full`."""
    return (
        slice(max(s[0].start - grow, 0), min(s[0].stop + grow, full[0])),
        slice(max(s[1].start - grow, 0), min(s[1].stop + grow, full[1])),
    )


def fill(data, omega, clusters, labels, order=2):
    """`data` ((channels, rows, cols) floats) with the hole pixels of each cluster in
    `labels` (labels of the image `clusters`) filled by the biharmonic fill of that cluster
    alone (module docstring; order 1: the harmonic fill); every other pixel as given. A
    float64 copy."""
    out = np.array(data, np.float64, copy=True)
    slices = ndimage.find_objects(clusters)
    for lab in labels:
        window = grown_box(slices[lab - 1], MARGIN, omega.shape)
        hole = (clusters[window] == lab) & omega[window]
        if hole.any():
            origin = (window[0].start, window[1].start)
            _solve(out[:, window[0], window[1]], origin, hole, omega.shape, order)
    return out


def ring_errors(data, omega, clusters, labels, width, ring=None):
    """Per cluster in `labels`, the biharmonic fill's mean squared error (over the pixels
    and channels) on its ring: the known pixels within `width` px of the hole that are
    nearest to that cluster, hidden with every hole pixel around. ring: (dist, owner) of
    the known pixels (their distance to the hole and their nearest cluster's label), if
    known already. Returns (errors, the ring pixels' values' mean squared deviation from
    their mean per cluster)."""
    data = np.asarray(data, np.float64)
    if ring is None:
        dist, (iy, ix) = ndimage.distance_transform_edt(~omega, return_indices=True)
        owner = np.where(omega, 0, clusters[iy, ix])
    else:
        dist, owner = ring
    slices = ndimage.find_objects(clusters)
    errors, spread = np.zeros(len(labels)), np.zeros(len(labels))
    for k, lab in enumerate(labels):
        window = grown_box(slices[lab - 1], width + MARGIN, omega.shape)
        band = (owner[window] == lab) & (dist[window] <= width)
        if not band.any():
            continue
        truth = data[:, window[0], window[1]][:, band]
        out = data[:, window[0], window[1]].copy()
        origin = (window[0].start, window[1].start)
        _solve(out, origin, omega[window] | band, omega.shape)
        errors[k] = np.mean((out[:, band] - truth) ** 2)
        spread[k] = np.mean((truth - truth.mean(axis=1, keepdims=True)) ** 2)
    return errors, spread
