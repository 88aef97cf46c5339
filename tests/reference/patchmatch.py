"""NumPy references of kernels/patchmatch.cl: the patch distance and the patch vote."""

from __future__ import annotations

import numpy as np


def patch_distance(img, weights, px, py, sx, sy, r, use=None):
    """Mean over the target patch's in-box pixels (or its `use` pixels) of the weighted
    squared colour differences between the patches centred at (px, py) and (sx, sy)."""
    nch, H, W = img.shape
    total, n = 0.0, 0
    for oy in range(-r, r + 1):
        for ox in range(-r, r + 1):
            ty, tx = py + oy, px + ox
            if not (0 <= ty < H and 0 <= tx < W):
                continue
            if use is not None and not use[ty, tx]:
                continue
            d = img[:, ty, tx].astype(np.float64) - img[:, sy + oy, sx + ox]
            total += float(np.sum(np.asarray(weights) * d * d))
            n += 1
    return total / n if n else np.inf


def distances(img, weights, nnf, targets, r, use=None):
    """dist[y, x] for every target (inf elsewhere); nnf[y, x] = (source x, source y)."""
    H, W = targets.shape
    out = np.full((H, W), np.inf)
    for py, px in zip(*np.nonzero(targets)):
        sx, sy = nnf[py, px]
        out[py, px] = patch_distance(img, weights, px, py, sx, sy, r, use)
    return out


def vote(img, nnf, dist, hole, r, sigma2, best_only=False, nout=None):
    """New hole values: each covering patch q proposes its source's value at the same
    offset, weighted by exp(-(d_q - d_min) / (2 sigma2)); best_only keeps the closest's.
    Only the first `nout` planes change (the others are guides)."""
    nch, H, W = img.shape
    nout = nch if nout is None else nout
    out = img.astype(np.float64).copy()
    for py, px in zip(*np.nonzero(hole)):
        props = []
        for oy in range(-r, r + 1):
            for ox in range(-r, r + 1):
                qy, qx = py - oy, px - ox
                if not (0 <= qy < H and 0 <= qx < W) or not np.isfinite(dist[qy, qx]):
                    continue
                sx, sy = nnf[qy, qx]
                props.append((dist[qy, qx], img[:nout, sy + oy, sx + ox]))
        if not props:
            continue
        dmin = min(d for d, _ in props)
        if best_only:
            out[:nout, py, px] = next(v for d, v in props if d == dmin)
            continue
        w = np.array([np.exp(-(d - dmin) / (2 * sigma2)) for d, _ in props])
        out[:nout, py, px] = np.sum(w[:, None] * np.array([v for _, v in props]), 0) / w.sum()
    return out
