"""NumPy references of the inpainting kernels (kernels/inpainting/transport.cl): the same
discrete formulas.

Arrays are padded (nc, ny + 2, nx + 2) with Neumann ghosts (tests.reference.planar.pad_neumann);
masks are (ny, nx). Each step returns the new interior (nc, ny, nx); cells off the kernel's
list keep their old values.
"""

import numpy as np

from .planar import _shifts, curvature_speed, pad_neumann


def laplacian(p):
    c, e, w, n, s, *_ = _shifts(p)
    return e + w + n + s - 4 * c


def scharr(p):
    """Scharr's derivatives (x, y) of the interior of a padded array."""
    c, e, w, n, s, ne, nw, se, sw = _shifts(p)
    gx = (3 * (ne - nw + se - sw) + 10 * (e - w)) / 32
    gy = (3 * (ne - se + nw - sw) + 10 * (n - s)) / 32
    return gx, gy


def transport_rate(p, rot=1.0, grad_eps2=1e-10, scaling="none", stencil="central"):
    """I_t of eqs. (3.6)-(3.11) at every interior cell (L's ghosts mirrored like I's).
    stencil 'central': appendix A's central differences; 'isotropic': Scharr's derivatives
    for grad I (in N) and for delta L (twice the derivative: eq. 3.7 spans two cells)."""
    lap = pad_neumann(laplacian(p))
    c, e, w, n, s, *_ = _shifts(p)
    if stencil == "central":
        _, le, lw, ln, ls, *_ = _shifts(lap)
        ix, iy = 0.5 * (e - w), 0.5 * (n - s)
        dlx, dly = le - lw, ln - ls
    else:
        ix, iy = scharr(p)
        dlx, dly = (2 * d for d in scharr(lap))
    beta = rot * (dly * ix - dlx * iy) / np.sqrt(ix * ix + iy * iy + grad_eps2)
    xb, xf, yb, yf = c - w, e - c, c - s, n - c
    lo, hi = np.minimum, np.maximum
    up = lo(xb, 0) ** 2 + hi(xf, 0) ** 2 + lo(yb, 0) ** 2 + hi(yf, 0) ** 2
    down = hi(xb, 0) ** 2 + lo(xf, 0) ** 2 + hi(yb, 0) ** 2 + lo(yf, 0) ** 2
    rate = beta * np.sqrt(np.where(beta > 0, up, down))
    if scaling == "quartic-root":
        rate = np.sign(rate) * np.abs(rate) ** 0.25 / np.sqrt(255.0)  # appendix A's 8-bit scale
    return rate


def transport_step(p, omega, dt, rot=1.0, grad_eps2=1e-10, scaling="none", stencil="central"):
    c = p[:, 1:-1, 1:-1]
    rate = transport_rate(p, rot, grad_eps2, scaling, stencil)
    return np.where(omega[None], c + dt * rate, c)


def diffusion_step(p, g, dt, eps=1e-10):
    """Anisotropic diffusion (3.4) weighted by g (zero off the band: those cells keep)."""
    c = p[:, 1:-1, 1:-1]
    return np.where(g[None] > 0, c + dt * g[None] * curvature_speed(p, eps), c)


def fill_step(p, omega):
    c, e, w, n, s, *_ = _shifts(p)
    return np.where(omega[None], 0.25 * (e + w + n + s), c)
