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
    for py, px in zip(*np.nonzero(targets), strict=False):
        sx, sy = nnf[py, px]
        out[py, px] = patch_distance(img, weights, px, py, sx, sy, r, use)
    return out


def vote(img, nnf, dist, hole, r, sigma2, best_only=False, nout=None, pen=None):
    """New hole values: each covering patch q proposes its source's value at the same
    offset, weighted by exp(-d_q / (2 sigma2) - pen_q) (pen: the confidence penalty, 0 when
    None); best_only keeps the proposal of the largest weight. Only the first `nout` planes
    change (the others are guides)."""
    nch, H, W = img.shape
    nout = nch if nout is None else nout
    pen = np.zeros((H, W)) if pen is None else pen
    out = img.astype(np.float64).copy()
    for py, px in zip(*np.nonzero(hole), strict=False):
        props = []
        for oy in range(-r, r + 1):
            for ox in range(-r, r + 1):
                qy, qx = py - oy, px - ox
                if not (0 <= qy < H and 0 <= qx < W) or not np.isfinite(dist[qy, qx]):
                    continue
                sx, sy = nnf[qy, qx]
                e = dist[qy, qx] / (2 * sigma2) + pen[qy, qx]
                props.append((e, img[:nout, sy + oy, sx + ox]))
        if not props:
            continue
        emin = min(e for e, _ in props)
        if best_only:
            out[:nout, py, px] = next(v for e, v in props if e == emin)
            continue
        w = np.array([np.exp(-(e - emin)) for e, _ in props])
        out[:nout, py, px] = np.sum(w[:, None] * np.array([v for _, v in props]), 0) / w.sum()
    return out
