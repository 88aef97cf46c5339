"""Numpy twins of kernels/film/detect.cl and kernels/film/fill.cl, pixel by pixel."""

from __future__ import annotations

import numpy as np


def _median(vals):
    v = sorted(vals)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def blotch_score(I, W, V, gain, offset, side, sigma, gamma):  # noqa: E741
    """(z, r, m, rp, rn) as kernels/film/detect.cl's blotch_score."""
    ny, nx = I.shape
    out = [np.zeros((ny, nx)) for _ in range(5)]
    z, r, m, rp, rn = out
    for y in range(ny):
        for x in range(nx):
            vals, pv, nv = [], [], []
            for k in range(W.shape[0]):
                if V[k, y, x] < 0.5:
                    continue
                w = gain[k] * W[k, y, x] + offset[k]
                vals.append(w)
                (pv if side[k] < 0 else nv).append(w)
            v = I[y, x]
            rp[y, x] = v - _median(pv) if pv else 0.0
            rn[y, x] = v - _median(nv) if nv else 0.0
            if not vals:
                continue
            diffs = [v - w for w in vals]
            order = sorted(range(len(diffs)), key=lambda j: (abs(diffs[j]), j))
            m[y, x] = diffs[order[1]] if len(diffs) >= 3 else diffs[order[0]]
            r[y, x] = v - _median(vals)
            if not pv or not nv:
                continue
            lo, hi = min(vals), max(vals)
            d = v - hi if v > hi else (v - lo if v < lo else 0.0)
            z[y, x] = d / (sigma + gamma * max(hi - lo - 2 * sigma, 0.0))
    return z, r, m, rp, rn


def column_mean(src, h, lim):
    ny, nx = src.shape
    c = np.clip(src, -lim, lim)
    out = np.empty_like(src, dtype=float)
    for y in range(ny):
        y0, y1 = max(y - h, 0), min(y + h, ny - 1)
        out[y] = c[y0 : y1 + 1].mean(axis=0)
    return out


def line_response(src, w):
    ny, nx = src.shape
    xs = np.arange(nx)
    left = 0.5 * (src[:, np.maximum(xs - w, 0)] + src[:, np.maximum(xs - w - 1, 0)])
    right = 0.5 * (src[:, np.minimum(xs + w, nx - 1)] + src[:, np.minimum(xs + w + 1, nx - 1)])
    d = src - 0.5 * (left + right)
    same = (src > 0) == (d > 0)
    return np.where(same, np.sign(d) * np.minimum(np.abs(d), np.abs(src)), 0.0)


def _drift(other, sgn):
    p = np.pad(other, ((0, 0), (1, 1)), mode="edge")
    return sgn * np.maximum.reduce([sgn * p[:, i : i + other.shape[1]] for i in range(3)])


def scratch_continuity(zprev, z, znext, has_prev, has_next):
    sgn = np.where(z >= 0, 1.0, -1.0)
    s, n = z.copy(), np.ones_like(z)
    if has_prev:
        s += _drift(zprev, sgn)
        n += 1
    if has_next:
        s += _drift(znext, sgn)
        n += 1
    joint = s / np.sqrt(n)
    return sgn * np.maximum(sgn * z, sgn * joint)


def box_mean(src, h):
    ny, nx = src.shape
    out = np.empty_like(src, dtype=float)
    for y in range(ny):
        for x in range(nx):
            out[y, x] = src[max(y - h, 0) : y + h + 1, max(x - h, 0) : x + h + 1].mean()
    return out


def temporal_fill(F, G, M, W, Wg, MW, V, gain, offset, dist, sigma, rad, clean):
    """(out (C, ny, nx), unfilled) as kernels/film/fill.cl's temporal_fill."""
    C, ny, nx = F.shape
    K = Wg.shape[0]
    out = F.astype(float).copy()
    unfilled = np.zeros((ny, nx))
    for y in range(ny):
        for x in range(nx):
            m = M[y, x]
            if m <= 0:
                continue
            cands = []
            for k in range(K):
                if V[k, y, x] < 0.5 or MW[k, y, x] > clean:
                    continue
                ys = slice(max(y - rad, 0), y + rad + 1)
                xs = slice(max(x - rad, 0), x + rad + 1)
                ok = (M[ys, xs] <= 0) & (MW[k][ys, xs] <= clean) & (V[k][ys, xs] >= 0.5)
                diff = np.abs(G[ys, xs] - (gain[k] * Wg[k][ys, xs] + offset[k]))[ok]
                e = diff.mean() if diff.size else -1.0
                cands.append((k, e, gain[k] * Wg[k, y, x] + offset[k]))
            if not cands:
                unfilled[y, x] = 1
                continue
            known = [e for _, e, _ in cands if e >= 0]
            emin = min(known) if known else np.inf
            keep = [c for c in cands if not (c[1] >= 0 and c[1] > 1.5 * emin + sigma)]
            costs = [sum(abs(a[2] - b[2]) for b in keep) + 1e-6 * dist[a[0]] for a in keep]
            k = keep[int(np.argmin(costs))][0]
            for c in range(C):
                out[c, y, x] = m * (gain[k] * W[k, c, y, x] + offset[k]) + (1 - m) * F[c, y, x]
    return out, unfilled
