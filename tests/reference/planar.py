"""NumPy references of the planar kernels: the same discrete formulas, on padded arrays.

Arrays are (nc, ny + 2, nx + 2) with a one-cell ghost layer; each step returns the new
interior (nc, ny, nx). `pad_neumann` fills ghosts as Field.fill_ghosts does.
"""

import numpy as np


def pad_neumann(u):
    """(nc, ny, nx) -> padded with the border cells mirrored into the ghost layer."""
    return np.pad(u, ((0, 0), (1, 1), (1, 1)), mode="edge")


def _shifts(p):
    """Neighbour views of the interior of a padded array: c, e, w, n, s, ne, nw, se, sw.

    'n' is +y (the next row), matching the kernels' i + sx.
    """
    c = p[:, 1:-1, 1:-1]
    e, w = p[:, 1:-1, 2:], p[:, 1:-1, :-2]
    n, s = p[:, 2:, 1:-1], p[:, :-2, 1:-1]
    ne, nw = p[:, 2:, 2:], p[:, 2:, :-2]
    se, sw = p[:, :-2, 2:], p[:, :-2, :-2]
    return c, e, w, n, s, ne, nw, se, sw


def heat_step(p, dt):
    c, e, w, n, s, *_ = _shifts(p)
    return c + dt * (e + w + n + s - 4 * c)


def perona_malik_step(p, dt, kappa, edge="exp"):
    c, e, w, n, s, *_ = _shifts(p)

    def flux(d):
        if edge == "exp":
            return d * np.exp(-((d / kappa) ** 2))
        return d / (1 + (d / kappa) ** 2)

    return c + dt * (flux(e - c) + flux(w - c) + flux(n - c) + flux(s - c))


def _tv_fluxes(p, eps):
    c, e, w, n, s, ne, nw, se, sw = _shifts(p)

    def flux(d, t):
        return d / np.sqrt(d * d + t * t + eps * eps)

    fe = flux(e - c, 0.25 * (n + ne - s - se))
    fw = flux(c - w, 0.25 * (n + nw - s - sw))
    fn = flux(n - c, 0.25 * (e + ne - w - nw))
    fs = flux(c - s, 0.25 * (e + se - w - sw))
    return fe, fw, fn, fs


def tv_div(p, eps):
    fe, fw, fn, fs = _tv_fluxes(p, eps)
    return fe - fw + fn - fs


def tv_step(p, dt, eps):
    return p[:, 1:-1, 1:-1] + dt * tv_div(p, eps)


def rof_step(p, p0, lam, dt, eps):
    """lam: one value per channel."""
    c = p[:, 1:-1, 1:-1]
    lam = np.asarray(lam, float)[:, None, None]
    return c + dt * (tv_div(p, eps) - lam * (c - p0[:, 1:-1, 1:-1]))


def rof_lambda(p, p0, eps, sigma2):
    """Dynamic fidelity weight per channel: -sum_faces p . grad(u - u0) / (N sigma^2), >= 0."""
    fe, _, fn, _ = _tv_fluxes(p, eps)
    r = p - p0
    wx = r[:, 1:-1, 2:] - r[:, 1:-1, 1:-1]
    wy = r[:, 2:, 1:-1] - r[:, 1:-1, 1:-1]
    total = (fe * wx + fn * wy).sum(axis=(1, 2))
    n = p[0, 1:-1, 1:-1].size
    return np.maximum(0.0, -total / (n * np.asarray(sigma2, float)))


def curvature_speed(p, eps):
    c, e, w, n, s, ne, nw, se, sw = _shifts(p)
    ux, uy = 0.5 * (e - w), 0.5 * (n - s)
    uxx, uyy = e - 2 * c + w, n - 2 * c + s
    uxy = 0.25 * (ne - nw - se + sw)
    return (uxx * uy * uy - 2 * ux * uy * uxy + uyy * ux * ux) / (ux * ux + uy * uy + eps)


def curvature_step(p, dt, eps, weight=None):
    g = 1.0 if weight is None else weight[None]
    return p[:, 1:-1, 1:-1] + dt * g * curvature_speed(p, eps)


# ---- kernels/planar/catte.cl -----------------------------------------------------------
def gauss_smooth(u, w):
    """gauss_rows then gauss_cols on (nc, ny, nx): the separable convolution with one-sided
    weights w[0..r], mirrored at the border (index -1 reads 0)."""
    r = len(w) - 1

    def along(a, axis):
        n = a.shape[axis]
        idx = np.arange(n)
        out = w[0] * a
        for k in range(1, r + 1):

            def mirror(j):
                for _ in range(8):
                    j = np.where(j < 0, -j - 1, np.where(j >= n, 2 * n - j - 1, j))
                return np.clip(j, 0, n - 1)

            out = out + w[k] * (
                np.take(a, mirror(idx - k), axis=axis) + np.take(a, mirror(idx + k), axis=axis)
            )
        return out

    return along(along(u, 2), 1)


def perona_malik_catte_step(p, ps, dt, kappa, edge="exp"):
    """perona_malik_catte_step: p and ps padded (u and its smoothed copy)."""
    c, e, w, n, s, *_ = _shifts(p)
    cs, es, ws, ns, ss, *_ = _shifts(ps)

    def flux(d, ds):
        if edge == "exp":
            return d * np.exp(-((ds / kappa) ** 2))
        return d / (1 + (ds / kappa) ** 2)

    return c + dt * (
        flux(e - c, es - cs) + flux(w - c, ws - cs) + flux(n - c, ns - cs) + flux(s - c, ss - cs)
    )
