"""NumPy references of kernels/tracking/levelset.cl and tracking/features.cl: the same discrete
formulas on padded arrays.

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
    return 0.5 * np.sqrt(
        (_view(p, 0, 1) - _view(p, 0, -1)) ** 2 + (_view(p, 1, 0) - _view(p, -1, 0)) ** 2
    )


def morph_step(pu, pf1, f2, band, dt, eps_f, eps_u, near):
    """One coupled step of thesis eqs. (2.3)-(2.6), written from the equations (the kernel
    is tracking/features.cl's morph_track with one channel, DISC 0 and lam = 0); returns
    (u_new, f1_new, (max |du/dt|, max |beta|, max |grad F1|), hit) over the band cells.

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
    maxima = tuple(
        float(np.abs(a[inside]).max()) if inside.any() else 0.0 for a in (rate, beta, grad_f)
    )
    return np.where(inside, u_new, u), np.where(inside, f1_new, f1), maxima, hit


def signed_distance(mask):
    """Reference signed distance: negative inside, zero level halfway between pixels."""
    from scipy import ndimage

    mask = np.asarray(mask, bool)
    inside = ndimage.distance_transform_edt(mask)
    outside = ndimage.distance_transform_edt(~mask)
    return np.where(mask, 0.5 - inside, outside - 0.5)


# ---- kernels/tracking/features.cl ---------------------------------------------------------


def local_contrast(img, r, eps, scale):
    """(ny, nx) -> scale (I - mean) / sqrt(var + eps^2) over (2r+1)^2 boxes, edge repeated."""
    img = np.asarray(img, np.float64)
    p = np.pad(img, r, mode="edge")
    ny, nx = img.shape
    s = np.zeros_like(img)
    s2 = np.zeros_like(img)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            v = p[dy : dy + ny, dx : dx + nx]
            s += v
            s2 += v * v
    n = (2 * r + 1) ** 2
    mean = s / n
    var = np.maximum(s2 / n - mean**2, 0)
    return scale * (img - mean) / np.sqrt(var + eps**2)


def discrepancy(pf1, pf2, kind, delta, win=3):
    """beta on the interior of padded (ny+4, nx+4) channel arrays: 'difference', 'huber'
    or 'ncc' (window reads may reach `win` cells out, so the caller pads enough)."""
    f1, f2 = _view(pf1, 0, 0), _view(pf2, 0, 0)
    if kind == "difference":
        return f2 - f1
    if kind == "huber":
        return np.clip(f2 - f1, -delta, delta)
    # Padded `win` more (values beyond the ghosts only reach cells the caller ignores).
    q1, q2 = (np.pad(p, win, mode="edge") for p in (pf1, pf2))
    ny, nx = f1.shape
    o = G + win

    def view(q, dy, dx):
        return q[o + dy : o + dy + ny, o + dx : o + dx + nx]

    sums = np.zeros((5,) + f1.shape)
    for dy in range(-win, win + 1):
        for dx in range(-win, win + 1):
            a, b = view(q1, dy, dx), view(q2, dy, dx)
            sums += np.array([a, b, a * a, b * b, a * b])
    n = (2 * win + 1) ** 2
    m1, m2 = sums[0] / n, sums[1] / n
    v1 = np.maximum(sums[2] / n - m1**2, 0) + delta**2
    v2 = np.maximum(sums[3] / n - m2**2, 0) + delta**2
    rho = (sums[4] / n - m1 * m2) / np.sqrt(v1 * v2)
    return np.sqrt(v1 / v2) * (f2 - m2) - rho * (f1 - m1)


def morph_track(pu, pf1, pf2, band, prior, dt, eps_f, eps_u, near, lam, delta, kind, win=3):
    """The generalised step over C channels: pf1, pf2 (C, ny+4, nx+4); returns (u_new,
    f1_new (C, ny, nx), (max |du/dt|, max |beta|, max |grad F1|), mean over band cells of
    the channels' mean |beta|, hit)."""
    u = _view(pu, 0, 0)
    ux = 0.5 * (_view(pu, 0, 1) - _view(pu, 0, -1))
    uy = 0.5 * (_view(pu, 1, 0) - _view(pu, -1, 0))
    proj = np.zeros_like(u)
    gsum = np.zeros_like(u)
    babs = np.zeros_like(u)
    f1_new, betas, grads = [], [], []
    for p1, p2 in zip(pf1, pf2, strict=False):
        beta = discrepancy(p1, p2, kind, delta, win)
        grad_f = upwind_norm(p1, beta)
        f1_new.append(_view(p1, 0, 0) + dt * beta * grad_f)
        fx = 0.5 * (_view(p1, 0, 1) - _view(p1, 0, -1))
        fy = 0.5 * (_view(p1, 1, 0) - _view(p1, -1, 0))
        proj += beta * (fx * ux + fy * uy)
        gsum += fx**2 + fy**2
        babs += np.abs(beta)
        betas.append(np.abs(beta))
        grads.append(grad_f)
    bhat = proj / np.sqrt((gsum + eps_f**2) * (ux**2 + uy**2 + eps_u**2))
    rate = bhat * upwind_norm(pu, bhat) + lam * (_view(prior, 0, 0) - u)
    u_new = u + dt * rate
    inside = band > 0
    hit = bool(np.any((band == 2) & (np.abs(u_new) < near)))
    maxima = (
        float(np.abs(rate[inside]).max()),
        float(np.max([b[inside] for b in betas])),
        float(np.max([g[inside] for g in grads])),
    )
    mean_beta = float((babs / len(pf1))[inside].mean())
    f1_new = np.array(
        [np.where(inside, f, _view(p1, 0, 0)) for f, p1 in zip(f1_new, pf1, strict=False)]
    )
    return np.where(inside, u_new, u), f1_new, maxima, mean_beta, hit
