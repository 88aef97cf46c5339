"""Gradient-domain stitching of an exemplar fill (host side, proportional to the hole).

A patch-based fill copies pixels from several places of the image. Where two copied regions
meet, inside the hole or at its border, their values need not agree: the seam is a jump in
tone, even when each side's texture is right. Stitching keeps the copied gradients and lets
the values follow: the fill u solves, over the hole's pixels p, the discrete Poisson equation

    sum over the 4 neighbours q of p of (u_p - u_q) = sum over q of g_pq,

with u_q the known value where q is known (Dirichlet data) and neighbours outside the box
left out (Neumann). The guidance g_pq is the difference p - q as the copied sources see it:
p's source s(p) is a known pixel, and its neighbour s(p) + (q - p), where known, gives the
view I(s(p)) - I(s(p) + q - p); when q is in the hole too, its source gives the view
I(s(q) - (q - p)) - I(s(q)), and g_pq is the mean of the views there are (antisymmetric, so
the system is the Dirichlet graph Laplacian: symmetric positive definite). Where the sources
of p and q are neighbours in the image (no seam), both views are the copied difference and
the fill is kept up to a smooth correction; across a seam the two real gradients are averaged
and the tone jump is spread over the hole, as in Perez, Gangnet and Blake's seamless cloning.

s(p) is the source pixel that the exemplar's last vote (``sharpen``) took for p: the value,
at p's offset, of the source patch of the covering target q of smallest
dist(q) / (2 sigma^2) + pen(q), the first such in the kernel's loop order. A view is used
only where the neighbour lies inside that matched patch too: just outside it the source
need not resemble the target (a flat patch matches anywhere in a flat region, and the pixel
next to it may belong to another tile of a periodic pattern).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import linalg as splinalg


def vote_sources(
    nnf: np.ndarray, dist: np.ndarray, pen: np.ndarray, hole: np.ndarray, r: int, sigma2: float
) -> np.ndarray:
    """(src, oy, ox): the flat index of the source pixel of each hole pixel (in
    np.flatnonzero(hole) order), as patchmatch_vote's best_only picks it (-1 where no covering
    patch has a finite distance), and the pixel's offset in the chosen patch.

    nnf: (H, W, 2) source centres (x, y); dist, pen: (H, W)."""
    H, W = hole.shape
    py, px = np.nonzero(hole)
    inv = 1.0 / (2 * max(float(sigma2), 1e-10))
    side = 2 * r + 1
    # each target's score once, padded by r with inf (no covering patch beyond the box);
    # NaN never wins either (a strict comparison)
    e = dist * inv + pen
    e = np.pad(np.where(np.isnan(e), np.inf, e), r, constant_values=np.inf)
    # every offset's score at once, in the kernel's loop order: argmin keeps the first of
    # equal scores, as a loop taking only strictly better ones does (one gather, not 49
    # rounds of where; 3 ms of a periodic call's 45, stop 51)
    oy, ox = (o - r for o in np.divmod(np.arange(side * side), side))
    scores = e[py[None] - oy[:, None] + r, px[None] - ox[:, None] + r]
    k = np.argmin(scores, axis=0)
    found = np.isfinite(scores[k, np.arange(py.size)])
    offy, offx = np.where(found, oy[k], 0), np.where(found, ox[k], 0)
    qy, qx = np.clip(py - offy, 0, H - 1), np.clip(px - offx, 0, W - 1)
    s = nnf[qy, qx].astype(np.int64)
    src = np.where(found, (s[:, 1] + offy) * W + s[:, 0] + offx, -1)
    return src, offy, offx


def stitch(img: np.ndarray, hole: np.ndarray, sources, r: int) -> np.ndarray:
    """The hole's values of ``img`` ((channels, H, W): known values outside the hole, the
    fill inside) re-solved from the sources' gradients (module docstring); ``sources`` is
    vote_sources' (src, oy, ox), r the patch radius. Returns a new array; only the hole
    changes."""
    src, offy, offx = sources
    nc, H, W = img.shape
    flat = img.reshape(nc, -1).astype(np.float64)
    holes = np.flatnonzero(hole)
    n = holes.size
    if n == 0:
        return img.copy()
    hole_flat = hole.ravel()
    index = np.full(H * W, -1, np.int64)
    index[holes] = np.arange(n)
    py, px = holes // W, holes % W
    has_src = src >= 0
    sy, sx = np.where(has_src, src // W, 0), np.where(has_src, src % W, 0)

    def known_at(y, x):
        inside = (y >= 0) & (y < H) & (x >= 0) & (x < W)
        f = np.where(inside, y, 0) * W + np.where(inside, x, 0)
        return inside & ~hole_flat[f], f

    rows, cols = [], []
    diag = np.zeros(n)
    rhs = np.zeros((nc, n))
    for dy, dx in ((0, -1), (0, 1), (-1, 0), (1, 0)):
        qy, qx = py + dy, px + dx
        inside = (qy >= 0) & (qy < H) & (qx >= 0) & (qx < W)
        q = np.where(inside, qy * W + qx, 0)
        q_hole = inside & hole_flat[q]
        diag += inside
        # Views of u_p - u_q: from p's source, and (q in the hole) from q's. Views inside
        # the matched patch come first: just outside it the source need not look like the
        # target (a flat patch matches anywhere in a flat region).
        ok_a, ta = known_at(sy + dy, sx + dx)
        ok_a &= has_src
        in_a = ok_a & (np.abs(offy + dy) <= r) & (np.abs(offx + dx) <= r)
        view_a = flat[:, src.clip(0)] - flat[:, ta]
        k = index[q]
        kq = k.clip(0)
        q_src = np.where(q_hole, src[kq], -1)
        q_has = q_src >= 0
        qsy, qsx = np.where(q_has, q_src // W, 0), np.where(q_has, q_src % W, 0)
        ok_b, tb = known_at(qsy - dy, qsx - dx)
        ok_b &= q_hole & q_has
        in_b = ok_b & (np.abs(offy[kq] - dy) <= r) & (np.abs(offx[kq] - dx) <= r)
        view_b = flat[:, tb] - flat[:, q_src.clip(0)]
        plain = flat[:, holes] - flat[:, q]  # no view: keep the fill's own difference
        g = plain
        for use_a, use_b in ((ok_a, ok_b), (in_a, in_b)):  # the later tier wins
            count = use_a.astype(np.float64) + use_b
            mean = (np.where(use_a, view_a, 0) + np.where(use_b, view_b, 0)) / np.maximum(count, 1)
            g = np.where(count > 0, mean, g)
        rhs += np.where(inside, g, 0)
        known_q = inside & ~q_hole
        rhs += np.where(known_q, flat[:, q], 0)
        rows.append(np.flatnonzero(q_hole))
        cols.append(k[q_hole])
    r_, c_ = np.concatenate(rows), np.concatenate(cols)
    ids = np.arange(n)
    A = sparse.csc_matrix(
        (
            np.concatenate([diag, -np.ones(r_.size)]),
            (np.concatenate([ids, r_]), np.concatenate([ids, c_])),
        ),
        shape=(n, n),
    )
    try:
        solve = splinalg.factorized(A)
    except RuntimeError:  # a component with no known neighbour in the box: keep the fill
        return img.copy()
    out = flat.copy()
    for c in range(nc):
        out[c, holes] = solve(rhs[c])
    return out.reshape(img.shape)
