"""NumPy references of kernels/inpainting/patchmatch.cl: the patch distance and the patch vote."""

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


def cohere(img, weights, nnf, dist, valid, targets, r, factor, sweeps):
    """pm_coherence's ICM sweeps: per sweep, the targets of parity 0 then 1 ((x + y) % 2)
    each take, among their own offset and their 8 neighbours' (read before the half-sweep),
    the one of least dist * factor^-agree (agree: neighbours with that offset); the first in
    row-major neighbour order wins a tie, the own offset before all. Returns (nnf, dist)."""
    H, W = targets.shape
    nnf, dist = nnf.copy(), dist.astype(np.float64).copy()
    ys, xs = np.nonzero(targets)
    for _ in range(sweeps):
        for parity in (0, 1):
            before = nnf.copy()
            for py, px in zip(ys, xs, strict=False):
                if (px + py) % 2 != parity:
                    continue
                offs = []
                for oy in (-1, 0, 1):
                    for ox in (-1, 0, 1):
                        qy, qx = py + oy, px + ox
                        if (oy or ox) and 0 <= qy < H and 0 <= qx < W:
                            offs.append(tuple(before[qy, qx] - (qx, qy)))
                own = tuple(before[py, px] - (px, py))
                best_e = dist[py, px] / factor ** offs.count(own)
                for o in dict.fromkeys(offs):
                    sx, sy = px + o[0], py + o[1]
                    if o == own or not (0 <= sx < W and 0 <= sy < H) or not valid[sy, sx]:
                        continue
                    d = patch_distance(img, weights, px, py, sx, sy, r)
                    if d / factor ** offs.count(o) < best_e:
                        best_e = d / factor ** offs.count(o)
                        nnf[py, px], dist[py, px] = (sx, sy), d
    return nnf, dist


def try_offsets(img, weights, colour_weights, nnf, dist, targets, valid, lags, r, use=None):
    """pm_offsets: each target tries its pixel plus each lag (dx, dy) with a legal source
    and keeps it when its colour distance (colour_weights) is at most the best so far, the
    current source's first (ties go to the later lag); a target that moved gets the full
    distance (weights) of its new source. Returns the new (nnf, dist)."""
    H, W = targets.shape
    nnf, dist = nnf.copy(), dist.copy()
    for py, px in zip(*np.nonzero(targets), strict=False):
        best = tuple(nnf[py, px])
        bd = patch_distance(img, colour_weights, px, py, *best, r, use)
        moved = False
        for dx, dy in lags:
            sx, sy = px + dx, py + dy
            if not (0 <= sx < W and 0 <= sy < H) or not valid[sy, sx]:
                continue
            d = patch_distance(img, colour_weights, px, py, sx, sy, r, use)
            if d <= bd:
                bd, best, moved = d, (sx, sy), True
        if moved:
            nnf[py, px] = best
            dist[py, px] = patch_distance(img, weights, px, py, *best, r, use)
    return nnf, dist
