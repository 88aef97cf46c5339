"""Numpy twins of kernels/motion/flow.cl, the same discrete scheme step by step."""

from __future__ import annotations

import numpy as np


def sample_clamped(img, x, y):
    """Bilinear sample of a (ny, nx) plane at float coordinates, clamped to the image."""
    ny, nx = img.shape
    x = np.clip(x, 0.0, nx - 1.0)
    y = np.clip(y, 0.0, ny - 1.0)
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    x1 = np.minimum(x0 + 1, nx - 1)
    y1 = np.minimum(y0 + 1, ny - 1)
    fx, fy = x - x0, y - y0
    top = img[y0, x0] + fx * (img[y0, x1] - img[y0, x0])
    bot = img[y1, x0] + fx * (img[y1, x1] - img[y1, x0])
    return top + fy * (bot - top)


def keys_weights(t):
    return [
        ((-0.5 * t + 1.0) * t - 0.5) * t,
        (1.5 * t - 2.5) * t * t + 1.0,
        ((-1.5 * t + 2.0) * t + 0.5) * t,
        (0.5 * t - 0.5) * t * t,
    ]


def sample_cubic(img, x, y):
    """Keys bicubic sample (a = -0.5), coordinates and taps clamped to the image."""
    ny, nx = img.shape
    x = np.clip(x, 0.0, nx - 1.0)
    y = np.clip(y, 0.0, ny - 1.0)
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    wx, wy = keys_weights(x - x0), keys_weights(y - y0)
    acc = 0.0
    for a in range(4):
        yy = np.clip(y0 - 1 + a, 0, ny - 1)
        row = sum(wx[b] * img[yy, np.clip(x0 - 1 + b, 0, nx - 1)] for b in range(4))
        acc = acc + wy[a] * row
    return acc


def down(src, w):
    ny, nx = src.shape
    ny2, nx2 = (ny + 1) // 2, (nx + 1) // 2
    k = np.array([1.0, 3.0, 3.0, 1.0])
    dst = np.empty((ny2, nx2))
    wdst = np.empty((ny2, nx2))
    for y in range(ny2):
        rows = np.clip(2 * y - 1 + np.arange(4), 0, ny - 1)
        for x in range(nx2):
            cols = np.clip(2 * x - 1 + np.arange(4), 0, nx - 1)
            kk = np.outer(k, k)
            val = src[np.ix_(rows, cols)]
            wt = w[np.ix_(rows, cols)]
            sk, sw = kk.sum(), (kk * wt).sum()
            dst[y, x] = (kk * wt * val).sum() / sw if sw > 1e-6 * sk else (kk * val).sum() / sk
            wdst[y, x] = sw / sk
    return dst, wdst


def up(u2, v2, ny, nx):
    ny2, nx2 = u2.shape
    rx, ry = nx / nx2, ny / ny2
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    xc = (xx + 0.5) / rx - 0.5
    yc = (yy + 0.5) / ry - 0.5
    return rx * sample_clamped(u2, xc, yc), ry * sample_clamped(v2, xc, yc)


def linearise(I0, I1, w0, w1, u, v):
    ny, nx = I0.shape
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    xs, ys = xx + u, yy + v
    xm, xp = np.maximum(xx - 1, 0), np.minimum(xx + 1, nx - 1)
    ym, yp = np.maximum(yy - 1, 0), np.minimum(yy + 1, ny - 1)
    g0x = (sample_clamped(I0, xp, yy) - sample_clamped(I0, xm, yy)) / np.maximum(xp - xm, 1)
    g0y = (sample_clamped(I0, xx, yp) - sample_clamped(I0, xx, ym)) / np.maximum(yp - ym, 1)
    g1x = 0.5 * (sample_cubic(I1, xs + 1, ys) - sample_cubic(I1, xs - 1, ys))
    g1y = 0.5 * (sample_cubic(I1, xs, ys + 1) - sample_cubic(I1, xs, ys - 1))
    It = sample_cubic(I1, xs, ys) - I0
    inside = (xs >= 0) & (xs <= nx - 1) & (ys >= 0) & (ys <= ny - 1)
    xi, yi, xmi, xpi, ymi, ypi = (a.astype(int) for a in (xx, yy, xm, xp, ym, yp))
    c0 = np.minimum.reduce([w0, w0[yi, xmi], w0[yi, xpi], w0[ymi, xi], w0[ypi, xi]])
    c1 = np.minimum.reduce(
        [sample_clamped(w1, xs + a, ys + b) for a, b in ((0, 0), (-1, 0), (1, 0), (0, -1), (0, 1))]
    )
    wd = np.where(inside, c0 * c1, 0.0)
    return 0.5 * (g0x + g1x), 0.5 * (g0y + g1y), It, wd


def _neighbour_mean(t):
    ny, nx = t.shape
    s = np.zeros_like(t)
    n = np.zeros_like(t)
    s[:, 1:] += t[:, :-1]
    n[:, 1:] += 1
    s[:, :-1] += t[:, 1:]
    n[:, :-1] += 1
    s[1:, :] += t[:-1, :]
    n[1:, :] += 1
    s[:-1, :] += t[1:, :]
    n[:-1, :] += 1
    return np.where(n > 0, s / np.maximum(n, 1), t)


def sor_half(Ix, Iy, It, wd, u, v, du, dv, alpha2, eps, omega, parity):
    """One red-black half sweep; returns new (du, dv)."""
    ny, nx = u.shape
    yy, xx = np.mgrid[0:ny, 0:nx]
    sel = ((xx + yy) & 1) == parity
    bu = _neighbour_mean(u + du) - u
    bv = _neighbour_mean(v + dv) - v
    r = Ix * du + Iy * dv + It
    w = wd * eps / np.sqrt(r * r + eps * eps)
    q = w * (Ix * bu + Iy * bv + It) / (alpha2 + w * (Ix * Ix + Iy * Iy))
    du = np.where(sel, du + omega * (bu - Ix * q - du), du)
    dv = np.where(sel, dv + omega * (bv - Iy * q - dv), dv)
    return du, dv


def median3(a):
    p = np.pad(a, 1, mode="edge")
    ny, nx = a.shape
    stack = [p[dy : dy + ny, dx : dx + nx] for dy in range(3) for dx in range(3)]
    return np.median(np.stack(stack), axis=0)


def warp(src, u, v):
    """(nc, ny, nx) backward warp."""
    ny, nx = u.shape
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    return np.stack([sample_cubic(c, xx + u, yy + v) for c in src])


def optical_flow(
    I0, I1, w0, w1, levels, alpha=0.03, eps=0.01, warps=4, iterations=30, omega=1.8, median=True
):
    """The whole coarse-to-fine solver of clpde.motion.FlowSolver.flow."""
    P0, W0, P1, W1 = [I0], [w0], [I1], [w1]
    for _ in range(levels - 1):
        a, b = down(P0[-1], W0[-1])
        P0.append(a)
        W0.append(b)
        a, b = down(P1[-1], W1[-1])
        P1.append(a)
        W1.append(b)
    u = v = None
    for lev in range(levels - 1, -1, -1):
        ny, nx = P0[lev].shape
        if u is None:
            u, v = np.zeros((ny, nx)), np.zeros((ny, nx))
        else:
            u, v = up(u, v, ny, nx)
        du, dv = np.zeros_like(u), np.zeros_like(v)
        for _ in range(warps):
            Ix, Iy, It, wd = linearise(P0[lev], P1[lev], W0[lev], W1[lev], u, v)
            for _ in range(iterations):
                for parity in (0, 1):
                    du, dv = sor_half(Ix, Iy, It, wd, u, v, du, dv, alpha**2, eps, omega, parity)
            u, v = u + du, v + dv
            du, dv = np.zeros_like(u), np.zeros_like(v)
            if median:
                u, v = median3(u), median3(v)
    return u, v
