"""NumPy references of kernels/levelset.cl: the same discrete formulas on padded arrays.

2D arrays are (ny + 4, nx + 4) with a two-cell ghost layer; each function returns values on
the interior (ny, nx). `pad` fills ghosts as Field.fill_ghosts('neumann') does.
"""

import numpy as np

G = 2


def pad(u):
    return np.pad(np.asarray(u, np.float64), G, mode="symmetric")


def _view(p, dy, dx):
    ny, nx = p.shape[0] - 2 * G, p.shape[1] - 2 * G
    return p[G + dy : G + dy + ny, G + dx : G + dx + nx]


def minmod(a, b):
    return np.where(a * b > 0, np.sign(a) * np.minimum(np.abs(a), np.abs(b)), 0.0)


def one_sided(p, axis):
    """Slope-limited backward and forward differences along axis 1 (x) or 0 (y)."""
    step = (lambda k: _view(p, 0, k)) if axis == 1 else (lambda k: _view(p, k, 0))
    m2, m1, c, p1, p2 = (step(k) for k in (-2, -1, 0, 1, 2))
    q_m, q_c, q_p = m2 - 2 * m1 + c, m1 - 2 * c + p1, c - 2 * p1 + p2
    dm = (c - m1) + 0.5 * minmod(q_m, q_c)
    dp = (p1 - c) - 0.5 * minmod(q_c, q_p)
    return dm, dp


def godunov_axis(dm, dp, v):
    down = np.maximum(np.maximum(dm, 0) ** 2, np.minimum(dp, 0) ** 2)
    up = np.maximum(np.minimum(dm, 0) ** 2, np.maximum(dp, 0) ** 2)
    return np.where(v > 0, up, down)


def upwind_norm(p, v):
    """Godunov |grad u| for u_t = v |grad u| (v: interior array or scalar)."""
    dmx, dpx = one_sided(p, 1)
    dmy, dpy = one_sided(p, 0)
    return np.sqrt(godunov_axis(dmx, dpx, v) + godunov_axis(dmy, dpy, v))


def mark_band(u, w, margin=0):
    a = np.abs(u)
    band = np.where(a < w, np.where(a < w - 1, 1, 2), 0).astype(np.uint8)
    if margin:
        frozen = np.ones(u.shape, bool)
        frozen[margin:-margin, margin:-margin] = False
        band[frozen] = 0
    return band


def dilate_band(band, reach, margin):
    """Movable cells with a band cell within Chebyshev distance `reach`."""
    from scipy import ndimage

    near = ndimage.maximum_filter(band > 0, size=2 * reach + 1, mode="constant")
    frozen = np.ones(band.shape, bool)
    frozen[margin:-margin, margin:-margin] = False
    return (near & ~frozen).astype(np.uint8)


def reinit_step(p, p0, dt, subcell_fix=True):
    c0 = _view(p0, 0, 0)
    e0, w0, n0, s0 = _view(p0, 0, 1), _view(p0, 0, -1), _view(p0, 1, 0), _view(p0, -1, 0)
    sgn = np.sign(c0)
    interface = (c0 * e0 < 0) | (c0 * w0 < 0) | (c0 * n0 < 0) | (c0 * s0 < 0)
    g = 0.5 * np.sqrt((e0 - w0) ** 2 + (n0 - s0) ** 2)
    g = np.maximum.reduce([g, np.abs(e0 - c0), np.abs(c0 - w0), np.abs(n0 - c0), np.abs(c0 - s0)])
    d = c0 / np.maximum(g, 1e-12)
    c = _view(p, 0, 0)
    subcell = c - dt * (sgn * np.abs(c) - d)
    godunov = c - dt * sgn * (upwind_norm(p, -sgn) - 1)
    return np.where(interface & subcell_fix, subcell, godunov)


def gradient_magnitude(p):
    return 0.5 * np.sqrt((_view(p, 0, 1) - _view(p, 0, -1)) ** 2
                         + (_view(p, 1, 0) - _view(p, -1, 0)) ** 2)


def morph_step(pu, pf1, f2, band, dt, eps_f, eps_u, near):
    """One coupled step; returns (u_new, f1_new, (max |du/dt|, max |beta|, max |grad F1|),
    hit) over the band cells.

    Cells outside the band keep their values, as the kernel leaves them untouched.
    """
    u, f1 = _view(pu, 0, 0), _view(pf1, 0, 0)
    beta = f2 - f1
    grad_f = upwind_norm(pf1, beta)
    f1_new = f1 + dt * beta * grad_f
    fx = 0.5 * (_view(pf1, 0, 1) - _view(pf1, 0, -1))
    fy = 0.5 * (_view(pf1, 1, 0) - _view(pf1, -1, 0))
    ux = 0.5 * (_view(pu, 0, 1) - _view(pu, 0, -1))
    uy = 0.5 * (_view(pu, 1, 0) - _view(pu, -1, 0))
    dot = (fx * ux + fy * uy) / np.sqrt((fx**2 + fy**2 + eps_f**2) * (ux**2 + uy**2 + eps_u**2))
    bhat = beta * dot
    rate = bhat * upwind_norm(pu, bhat)
    u_new = u + dt * rate
    inside = band > 0
    hit = bool(np.any((band == 2) & (np.abs(u_new) < near)))
    maxima = tuple(float(np.abs(a[inside]).max()) if inside.any() else 0.0
                   for a in (rate, beta, grad_f))
    return np.where(inside, u_new, u), np.where(inside, f1_new, f1), maxima, hit


def signed_distance(mask):
    """Reference signed distance: negative inside, zero level halfway between pixels."""
    from scipy import ndimage

    mask = np.asarray(mask, bool)
    inside = ndimage.distance_transform_edt(mask)
    outside = ndimage.distance_transform_edt(~mask)
    return np.where(mask, 0.5 - inside, outside - 0.5)
