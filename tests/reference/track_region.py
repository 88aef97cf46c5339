"""NumPy reference of kernels/tracking/region.cl, the adaptive discrepancy's region term: the
same discrete scheme, step by step, in float64 (written with explicit edge padding, not
scipy's filters, which tests/tracking/test_track_region.py checks them against)."""

import numpy as np


def gaussian_weights(sigma, truncate):
    radius = int(truncate * sigma + 0.5)
    x = np.arange(-radius, radius + 1)
    w = np.exp(-0.5 * x**2 / sigma**2)
    return w / w.sum()


def moments(inside, feats):
    """region_moments: (2 + 4K, ceil(H/2), ceil(W/2)) 2x2 means, the last row and column
    repeated for odd sizes, of m, 1 - m and per feature m f, (1 - m) f, m f^2, (1 - m) f^2."""
    m = np.asarray(inside, np.float64)
    out = 1.0 - m
    planes = [m, out]
    for f in feats:
        planes += [m * f, out * f, m * f * f, out * f * f]
    h, w = m.shape
    padded = np.pad(np.array(planes), ((0, 0), (0, h % 2), (0, w % 2)), mode="edge")
    return 0.25 * (
        padded[:, ::2, ::2] + padded[:, 1::2, ::2] + padded[:, ::2, 1::2] + padded[:, 1::2, 1::2]
    )


def blur(planes, weights, axis):
    """blur_cols (axis -2) or blur_rows (axis -1): correlation with the weights, the index
    clamped at the edges."""
    r = (len(weights) - 1) // 2
    n = planes.shape[axis]
    out = np.zeros(planes.shape)
    for k, wk in enumerate(weights):
        idx = np.clip(np.arange(n) + k - r, 0, n - 1)
        out += wk * np.take(planes, idx, axis=axis)
    return out


def blur2d(planes, weights):
    return blur(blur(planes, weights, -2), weights, -1)


def llr(stats, feats, noise2, separation):
    """region_llr: (L, weight) per pixel, each reading its 2x2 block's statistics."""
    h, w = feats.shape[1:]
    s = np.repeat(np.repeat(stats, 2, axis=1), 2, axis=2)[:, :h, :w]
    cover = np.clip(np.minimum(s[0], s[1]) / 0.05, 0, 1)
    a_in, a_out = np.maximum(s[0], 1e-6), np.maximum(s[1], 1e-6)
    total, bhat = np.zeros((h, w)), np.zeros((h, w))
    for k, f in enumerate(feats):
        floor = (0.25 * noise2 if k == len(feats) - 1 else noise2) + 1e-4
        mi, mo = s[2 + 4 * k] / a_in, s[3 + 4 * k] / a_out
        vi = np.maximum(s[4 + 4 * k] / a_in - mi**2, 0) + floor
        vo = np.maximum(s[5 + 4 * k] / a_out - mo**2, 0) + floor
        total += ((f - mi) ** 2 - (f - mo) ** 2) / (vi + vo)
        bhat += 0.25 * (mi - mo) ** 2 / (vi + vo) + 0.5 * np.log((vi + vo) / (2 * np.sqrt(vi * vo)))
    return total, cover * bhat / (bhat + separation)


def speed(total, weight, scale):
    """region_speed on the frame: scale weight tanh(L / 2), L clipped to [-20, 20]."""
    return scale * weight * np.tanh(0.5 * np.clip(total, -20, 20))


def region_speed(inside, feats, noise2, scale=1.0, sigma=6.0, separation=0.5, pool=1.5):
    """The whole term on the frame: the kernels in turn, as RegionTerm.update runs them."""
    stats = blur2d(moments(inside, feats), gaussian_weights(sigma / 2, 3.0))
    total, weight = llr(stats, feats, noise2, separation)
    if pool > 0:
        total = blur2d(total[np.newaxis], gaussian_weights(pool, 4.0))[0]
    return speed(total, weight, scale)
